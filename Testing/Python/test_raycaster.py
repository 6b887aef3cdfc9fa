"""vtkSegmentationSVDAGRayCaster: picking in world coordinates on a real segmentation.

The reference is a brute force in numpy on the original label array: the world ray is mapped to
index space independently (voxel (i, j, k) is the box [i, i+1)^3 around VTK point (i, j, k), so
world = origin + D diag(spacing) (p - 0.5)), then every labelled voxel's box is slab-tested.
"""
import math

import nrrd
import numpy as np
import pytest
from conftest import compress_zyx
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkCommand

from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGRayCaster

SPACING = (0.8, 1.1, 2.5)
ORIGIN = (-30.0, 12.0, 5.0)
# A rotation by 90 degrees about z followed by a flip of x: a non-trivial orthonormal direction.
DIRECTION = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])


@pytest.fixture(scope="module")
def segmentation(shared_data):
    labels, _ = nrrd.read(str(shared_data / "totalseg_ct.nrrd"), index_order="C")  # (z, y, x)
    return labels, compress_zyx(labels, SPACING, ORIGIN, DIRECTION)


def index_to_world_matrix():
    return DIRECTION @ np.diag(SPACING)


def brute_force(labels, origin, direction, tmax=np.inf):
    """Closed and strict minimum entry distance over all labelled voxels, and the voxels (x, y, z)
    reached at the closed minimum (zero-length contacts at faces/edges are ambiguous)."""
    m_inv = np.linalg.inv(index_to_world_matrix())
    unit = np.asarray(direction, float) / np.linalg.norm(direction)
    o = m_inv @ (np.asarray(origin, float) - ORIGIN) + 0.5
    d = m_inv @ unit  # parameter = world distance
    z, y, x = np.nonzero(labels)
    lo = np.stack([x, y, z], axis=1).astype(float)
    enter = np.zeros(len(lo))
    exit_ = np.full(len(lo), tmax)
    inside = np.ones(len(lo), bool)
    for a in range(3):
        if d[a] == 0.0:
            inside &= (o[a] >= lo[:, a]) & (o[a] < lo[:, a] + 1)
            continue
        t0 = (lo[:, a] - o[a]) / d[a]
        t1 = (lo[:, a] + 1 - o[a]) / d[a]
        enter = np.maximum(enter, np.minimum(t0, t1))
        exit_ = np.minimum(exit_, np.maximum(t0, t1))
    contact = exit_ - enter
    tol = 1e-4 * (1 + np.abs(enter))
    strict = inside & (contact > tol)
    closed = inside & (contact >= -tol)
    strict_min = enter[strict].min() if strict.any() else math.inf
    closed_min = enter[closed].min() if closed.any() else math.inf
    at_min = closed & (np.abs(enter - closed_min) <= 1e-4 * (1 + abs(closed_min)))
    return strict_min, closed_min, {tuple(v) for v in lo[at_min].astype(int)}


def random_rays(labels, rng, count):
    """Rays from outside the volume at labelled voxels, and rays from random inner points."""
    m = index_to_world_matrix()
    z, y, x = np.nonzero(labels)
    shape_xyz = np.array(labels.shape[::-1], float)
    rays = []
    for i in range(count):
        k = rng.integers(len(x))
        target = m @ (np.array([x[k], y[k], z[k]]) + rng.uniform(0, 1, 3) - 0.5) + ORIGIN
        if i % 3 == 2:
            origin = m @ (rng.uniform(0, 1, 3) * shape_xyz - 0.5) + ORIGIN
            direction = rng.normal(size=3)
        else:
            direction = rng.normal(size=3)
            origin = target - 400.0 * direction / np.linalg.norm(direction)
            direction = (target - origin) * rng.uniform(0.1, 5)  # any length
        rays.append((origin, direction))
    return rays


def test_voxel_hits_match_brute_force(segmentation, rng):
    labels, svdag = segmentation
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(svdag)
    assert caster.GetLOD() == vtkSegmentationSVDAGRayCaster.LOD_VOXEL
    m = index_to_world_matrix()
    hits = 0
    for origin, direction in random_rays(labels, rng, 150):
        strict_min, closed_min, reached = brute_force(labels, origin, direction)
        hit = caster.CastRay(origin, direction)
        assert hit == caster.GetHit()
        if math.isfinite(strict_min):
            assert hit == 1, (origin, direction)
        if not math.isfinite(closed_min):
            assert hit == 0, (origin, direction)
        if not hit:
            assert caster.GetHitLabelIndex() == -1
            assert caster.GetHitLabelValue() is None
            continue
        hits += 1
        t = caster.GetHitDistance()
        tol = 1e-4 * (1 + t)
        assert closed_min - tol <= t <= strict_min + tol
        voxel = caster.GetHitVoxel()
        assert voxel in reached
        # The label is the voxel's, as an index and as a value of the original dtype.
        value = vtk_to_numpy(caster.GetHitLabelValue())
        assert value.dtype == labels.dtype and value.shape == (1,)
        assert value[0] == labels[voxel[2], voxel[1], voxel[0]]
        table = vtk_to_numpy(svdag.NewLabelValues())
        assert table[caster.GetHitLabelIndex()] == value[0]
        # Position is on the ray at the distance; it lies on the voxel's box (in index space).
        unit = np.asarray(direction) / np.linalg.norm(direction)
        position = np.array(caster.GetHitPosition())
        np.testing.assert_allclose(position, origin + t * unit, atol=1e-9 * (1 + t))
        p = np.linalg.inv(m) @ (position - ORIGIN) + 0.5
        assert np.all(p >= np.array(voxel) - 1e-3) and np.all(p <= np.array(voxel) + 1 + 1e-3)
        # The normal is a unit world vector facing the ray, or zero when starting inside.
        normal = np.array(caster.GetHitNormal())
        if t > tol:
            assert abs(np.linalg.norm(normal) - 1) < 1e-9
            assert normal @ unit < 0
        else:
            assert np.all(normal == 0)
    assert hits > 50


def test_lods_and_maximum_distance(segmentation, rng):
    labels, svdag = segmentation
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(svdag)
    for origin, direction in random_rays(labels, rng, 60):
        distances = []
        for lod in ("Block", "Leaf", "Voxel"):
            getattr(caster, "SetLODTo" + lod)()
            distances.append(caster.GetHitDistance() if caster.CastRay(origin, direction) else math.inf)
        # Coarser boxes contain finer ones: the hit can only come earlier.
        assert distances[0] <= distances[1] + 1e-4 * (1 + distances[1])
        assert distances[1] <= distances[2] + 1e-4 * (1 + distances[2])
        if math.isfinite(distances[2]) and distances[2] > 1:
            caster.SetMaximumDistance(distances[2] * 0.999)
            assert caster.CastRay(origin, direction) == 0
            caster.SetMaximumDistance(distances[2] * 1.001)
            assert caster.CastRay(origin, direction) == 1
            caster.SetMaximumDistance(1e300)
    caster.SetLOD(7)
    assert caster.GetLOD() == vtkSegmentationSVDAGRayCaster.LOD_VOXEL


def test_misses_and_errors(segmentation):
    labels, svdag = segmentation
    caster = vtkSegmentationSVDAGRayCaster()
    errors = []
    caster.AddObserver(vtkCommand.ErrorEvent, lambda obj, event: errors.append(event))
    assert caster.CastRay((0, 0, 0), (1, 0, 0)) == 0  # no input
    assert len(errors) == 1
    caster.SetInputData(svdag)
    assert caster.CastRay((0, 0, 0), (0, 0, 0)) == 0  # zero direction
    assert caster.CastRay((0, 0, 0), (1, float("nan"), 0)) == 0
    assert len(errors) == 3
    # Pointing away from the volume: a plain miss, no error.
    center = index_to_world_matrix() @ (np.array(labels.shape[::-1]) / 2 - 0.5) + ORIGIN
    far = center + np.array([0, 0, -1000.0])
    assert caster.CastRay(far, (0, 0, -1)) == 0
    assert len(errors) == 3
    assert caster.GetHitLabelIndex() == -1 and caster.GetHitBlockIndex() == -1
    caster.SetLODToLeaf()
    caster.SetMaximumDistance(12.5)
    text = str(caster)
    assert "LOD: leaf" in text and "MaximumDistance: 12.5" in text and "Hit: 0" in text
