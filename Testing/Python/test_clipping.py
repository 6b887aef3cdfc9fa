"""Clipping planes and crop boxes (Module/core/svdag/Clipping.h) in the GPU renderer, the CPU ray
caster, the VTK volume mapper, pyvista and the command line.

References are independent of the GPU: the CPU ray caster (vtkSegmentationSVDAGRayCaster, given
the same world planes) on the renderer's documented pixel-center rays generated here in double
precision, and numpy (a plane on voxel faces must show exactly what a volume with the removed
voxels deleted shows; a cut face shows the label of the voxel the cut point lies in).

Tolerances: labels agree on >= 99.5% of the pixels (rays within float rounding of a voxel edge may
see the neighbour, as in test_render_primary.py), depths to 1e-4 relative where both hit the same
label. Both casters move each plane into the kept side by a margin of 2.5e-4 voxel sides
(Clipping.h), so depths at cut faces may differ by that margin over the cosine of incidence.
"""
import json
import subprocess
import sys
import time

import nrrd
import numpy as np
import pytest
from conftest import (REPO, capture_errors, caster_pick, compress_zyx as build, mapper_pick,
                      mapper_scene, pixel_ray, primary_rays)
from test_render_primary import lod_boxes, rotation
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkPlane
from vtkmodules.vtkCommonMath import vtkMatrix4x4

from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGRayCaster
from vtksvdag.vtkSVDAGRendering import (vtkSegmentationSVDAGRenderer,
                                        vtkSegmentationSVDAGRenderSettings)

WIDTH, HEIGHT = 48, 36
S = vtkSegmentationSVDAGRenderSettings
LODS = {"block": S.LOD_BLOCK, "leaf": S.LOD_LEAF, "voxel": S.LOD_VOXEL}


# --- helpers ------------------------------------------------------------------------------------

def world_matrix(volume):
    """(M, origin): world = origin + M (p - 0.5) for index-space p."""
    direction, spacing, origin = [0.0] * 9, [0.0] * 3, [0.0] * 3
    volume.GetDirection(direction)
    volume.GetSpacing(spacing)
    volume.GetOrigin(origin)
    return np.reshape(direction, (3, 3)) @ np.diag(spacing), np.array(origin)


def world_point(volume, p):
    m, origin = world_matrix(volume)
    return origin + m @ (np.asarray(p, float) - 0.5)


def make_plane(origin, normal):
    plane = vtkPlane()
    plane.SetOrigin(*origin)
    plane.SetNormal(*normal)
    return plane


def make_renderer(volume, lod, planes=(), crop=None, camera=(30.0, 20.0, 1.2), backend="auto"):
    r = vtkSegmentationSVDAGRenderer()
    r.GetSettings().SetBackend(backend)
    r.SetInputData(volume)
    r.SetWidth(WIDTH)
    r.SetHeight(HEIGHT)
    r.GetSettings().SetLOD(lod)
    for origin, normal in planes:
        r.AddClippingPlane(make_plane(origin, normal))
    if crop is not None:
        r.SetCroppingRegionPlanes(*crop)
        r.CroppingOn()
    if callable(camera):
        camera(r)
    else:
        assert r.ResetCamera(*camera) == 1
    return r


def gpu_outputs(renderer):
    assert renderer.Render() == 1
    data = renderer.GetOutput().GetPointData()
    faces = data.GetArray("FaceNormal") or data.GetArray("Normal")
    return (vtk_to_numpy(data.GetArray("Label")).astype(np.int64),
            vtk_to_numpy(data.GetArray("Depth")).astype(np.float64),
            vtk_to_numpy(faces).astype(np.float64).reshape(-1, 3))


def make_caster(volume, lod, planes=(), crop=None):
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(volume)
    caster.SetLOD(lod)
    for origin, normal in planes:
        assert caster.AddClippingPlane(origin, normal) == 1
    if crop is not None:
        caster.SetCroppingRegionPlanes(*crop)
        caster.CroppingOn()
    return caster


def cpu_outputs(caster, renderer):
    """Per pixel: label index + 1 (0 miss), depth, world normal, cut plane (-1: none)."""
    origin, dirs = primary_rays(renderer)
    n = len(dirs)
    label, depth, normal, plane = np.zeros(n, np.int64), np.full(n, np.inf), np.zeros((n, 3)), np.full(n, -1)
    for i, d in enumerate(dirs):
        if caster.CastRay(origin, d):
            label[i] = caster.GetHitLabelIndex() + 1
            depth[i] = caster.GetHitDistance()
            normal[i] = caster.GetHitNormal()
            plane[i] = caster.GetHitClippingPlane()
    return label, depth, normal, plane


def coarse_box_labels(labels, volume, lod, points):
    """Per world point, the label values whose LOD box (lod_boxes) contains it (1e-3 voxels of
    slack): at block and leaf LOD a cut inside overlapping boxes of two labels ties, and then
    either label is right."""
    lo, hi, values = lod_boxes(labels, lod)
    m, origin = world_matrix(volume)
    p = (np.linalg.inv(m) @ (points - origin).T).T + 0.5
    inside = np.all((p[:, None, :] >= lo[None] - 1e-3) & (p[:, None, :] <= hi[None] + 1e-3), axis=2)
    return [set(values[row]) for row in inside]


def assert_matches_cpu(labels, volume, lod, planes=(), crop=None, camera=(30.0, 20.0, 1.2), what="",
                       backend="auto"):
    renderer = make_renderer(volume, lod, planes, crop, camera, backend)
    g_label, g_depth, g_normal = gpu_outputs(renderer)
    c_label, c_depth, c_normal, c_plane = cpu_outputs(make_caster(volume, lod, planes, crop), renderer)
    hit_same = (g_label > 0) == (c_label > 0)
    same = hit_same & (g_label == c_label)
    if lod != S.LOD_VOXEL:
        table = vtk_to_numpy(volume.NewLabelValues()).astype(np.int64)
        origin, dirs = primary_rays(renderer)
        both = hit_same & (c_label > 0)
        points = origin + np.where(both, c_depth, 0)[:, None] * dirs
        allowed = coarse_box_labels(labels, volume, lod, points)
        tie_ok = np.array([b and table[g - 1] in ok for b, g, ok in zip(both, g_label, allowed)])
        same = same | (both & tie_ok)
    agreement = same.mean()
    assert agreement >= 0.995, (f"{what}: labels agree on {agreement:.4%} "
                                f"(gpu {g_label[~same][:8]}, cpu {c_label[~same][:8]})")
    both = same & (c_label > 0)
    rel = np.abs(g_depth[both] - c_depth[both]) / np.maximum(c_depth[both], 1e-9)
    assert not both.any() or np.quantile(rel, 0.995) <= 1e-4, f"{what}: depth rel error {rel.max():.3g}"
    # Cut faces: the plane's (crop face's) outward normal on both, facing the ray.
    cut = both & (c_plane >= 0)
    if cut.any():
        np.testing.assert_allclose(g_normal[cut], c_normal[cut], atol=1e-5)
        _, dirs = primary_rays(renderer)
        assert np.all(np.einsum("ij,ij->i", c_normal[cut], dirs[cut]) < 0)
    return g_label, c_label, c_plane, renderer


def random_plane(rng, volume, shape_xyz):
    """A random plane that keeps the volume's center, 0 .. 8 world units from it."""
    normal = rng.normal(size=3)
    normal /= np.linalg.norm(normal)
    point = world_point(volume, shape_xyz / 2) - rng.uniform(0.0, 8.0) * normal
    return tuple(point), tuple(normal)


def random_crop(rng, volume, shape_xyz):
    corners = np.array([world_point(volume, c * shape_xyz) for c in np.ndindex(2, 2, 2)])
    lo, hi = corners.min(axis=0), corners.max(axis=0)
    a = lo + rng.uniform(0.05, 0.4, 3) * (hi - lo)
    b = hi - rng.uniform(0.05, 0.4, 3) * (hi - lo)
    return (a[0], b[0], a[1], b[1], a[2], b[2])


@pytest.fixture(scope="module")
def random_volume():
    """Sparse random labels plus one solid box, anisotropic spacing and a rotated direction."""
    rng = np.random.default_rng(77)
    shape = (21, 37, 29)  # z, y, x
    labels = rng.integers(1, 9, size=shape).astype(np.uint16)
    labels[rng.random(shape) < 0.75] = 0
    labels[3:15, 5:30, 2:20] = 7
    return labels, build(labels, spacing=(0.7, 1.0, 1.3), origin=(5.0, -3.0, 10.0),
                         direction=rotation(rng))


@pytest.fixture(scope="module")
def axis_volume():
    """Random labels on an axis-aligned grid (spacing 1, origin 0: voxel i spans [i-0.5, i+0.5])."""
    rng = np.random.default_rng(5)
    shape = (24, 30, 26)
    labels = rng.integers(1, 6, size=shape).astype(np.uint16)
    labels[rng.random(shape) < 0.5] = 0
    return labels, build(labels)


# --- GPU against the CPU ray caster ------------------------------------------------------------

@pytest.mark.parametrize("backend", ["rt", "compute"])
@pytest.mark.parametrize("lod", list(LODS), ids=list(LODS))
def test_random_planes_and_crop_match_cpu(random_volume, lod, backend):
    labels, volume = random_volume
    shape_xyz = np.array(labels.shape[::-1], float)
    rng = np.random.default_rng({"block": 1, "leaf": 2, "voxel": 3}[lod])
    cut_pixels = 0
    cases = [
        ("one plane", [random_plane(rng, volume, shape_xyz)], None),
        ("three planes", [random_plane(rng, volume, shape_xyz) for _ in range(3)], None),
        ("crop box", [], random_crop(rng, volume, shape_xyz)),
        ("plane and crop box", [random_plane(rng, volume, shape_xyz)], random_crop(rng, volume, shape_xyz)),
    ]
    for i, (what, planes, crop) in enumerate(cases):
        camera = (rng.uniform(-180, 180), rng.uniform(-60, 60), rng.uniform(1.0, 1.8))
        g_label, _, c_plane, _ = assert_matches_cpu(labels, volume, LODS[lod], planes, crop, camera,
                                                    f"{lod} {what} ({backend})", backend)
        assert (g_label > 0).sum() > 30, what
        cut_pixels += int((c_plane >= 0).sum())
    assert cut_pixels > 100  # the cases do show cut faces


def test_cut_through_solid_label(random_volume):
    """A plane through the middle of the solid box (label 7): the cut face is drawn with the
    plane's outward normal, and its label is that of the voxel (numpy) the cut point lies in."""
    labels, volume = random_volume
    center = world_point(volume, np.array([11.0, 17.5, 9.0]))  # index (x, y, z) in the box
    m, _ = world_matrix(volume)
    normal = m @ np.array([0.3, -0.2, -1.0])  # oblique, facing away from the camera below
    normal /= np.linalg.norm(normal)
    planes = [(tuple(center), tuple(normal))]
    eye = center - 60 * normal + 5 * np.cross(normal, [0, 0, 1])

    def camera(r):
        r.SetCameraPosition(*eye)
        r.SetCameraFocalPoint(*center)
        r.SetCameraViewUp(*np.cross(normal, [1, 0, 0]))
        r.SetCameraViewAngle(20.0)
        return 1

    for lod in LODS.values():
        g_label, c_label, c_plane, renderer = assert_matches_cpu(labels, volume, lod, planes, None,
                                                                 camera, f"solid cut lod {lod}")
    # Voxel LOD (the last): the cut face fills the middle of the image.
    _, g_depth, g_normal = gpu_outputs(renderer)
    origin, dirs = primary_rays(renderer)
    cut = (c_plane == 0) & (g_label > 0)
    assert cut.mean() > 0.3
    np.testing.assert_allclose(g_normal[cut], np.broadcast_to(-normal, g_normal[cut].shape), atol=1e-5)
    points = origin + g_depth[cut, None] * dirs[cut]
    # On the plane, within the margin and float rounding.
    assert np.max(np.abs((points - center) @ normal)) < 1e-3
    # The voxel just inside the kept side: its label from numpy.
    index = np.floor((np.linalg.inv(m) @ (points + 1e-3 * normal - world_point(volume, np.zeros(3))).T).T).astype(int)
    table = vtk_to_numpy(volume.NewLabelValues()).astype(np.int64)
    expected = labels[index[:, 2], index[:, 1], index[:, 0]]
    got = table[g_label[cut] - 1]
    assert np.mean(got == expected) >= 0.995
    assert np.all(expected[got == 7] == 7) and np.mean(got == 7) > 0.5  # mostly the box


def test_plane_removing_everything(random_volume):
    labels, volume = random_volume
    corners = np.array([world_point(volume, c * np.array(labels.shape[::-1])) for c in np.ndindex(2, 2, 2)])
    beyond = corners.max(axis=0) + 1.0
    planes = [(tuple(beyond), (1.0, 0.0, 0.0))]  # keeps x >= beyond: nothing of the volume
    for lod in LODS.values():
        renderer = make_renderer(volume, lod, planes)
        g_label, g_depth, _ = gpu_outputs(renderer)
        assert not g_label.any()
        assert np.all(g_depth == np.float32(3.402823466e38))
        c_label, _, _, _ = cpu_outputs(make_caster(volume, lod, planes), renderer)
        assert not c_label.any()
    # The two half-spaces of one plane together keep nothing either.
    planes = [((10.0, 0.0, 10.0), (0.0, 0.0, 1.0)), ((10.0, 0.0, 10.0), (0.0, 0.0, -1.0))]
    g_label, _, _ = gpu_outputs(make_renderer(volume, S.LOD_VOXEL, planes))
    assert not g_label.any()


@pytest.mark.parametrize("case", ["plane_x", "plane_z_keep_below", "crop"])
def test_cut_on_voxel_faces_equals_deleted_voxels(axis_volume, case):
    """A plane exactly on voxel faces (or a crop box on voxel faces) must show exactly what the
    volume with the removed voxels set to 0 shows: same labels and normals, no speckle of the
    voxels just outside (the margin keeps the entry point inside; Clipping.h)."""
    labels, volume = axis_volume
    cut = labels.copy()
    if case == "plane_x":
        planes, crop = [((9.5, 0.0, 0.0), (1.0, 0.0, 0.0))], None  # keeps voxels x >= 10
        cut[:, :, :10] = 0
    elif case == "plane_z_keep_below":
        planes, crop = [((0.0, 0.0, 13.5), (0.0, 0.0, -2.0))], None  # keeps voxels z <= 13
        cut[14:] = 0
    else:
        planes, crop = [], (3.5, 20.5, -0.5, 16.5, 4.5, 30.0)  # voxels x 4..20, y 0..16, z 5..
        keep = np.zeros_like(labels, bool)
        keep[5:, 0:17, 4:21] = True
        cut[~keep] = 0
    reference = build(cut)
    total_mismatch = 0
    for azimuth, elevation in ((35, 25), (-120, -40), (200, 70)):
        clipped = make_renderer(volume, S.LOD_VOXEL, planes, crop, (azimuth, elevation, 1.3))
        # The same camera on the volume without those voxels (same world bounds: same framing).
        plain = make_renderer(reference, S.LOD_VOXEL, camera=lambda r, c=clipped: (
            r.SetCameraPosition(*c.GetCameraPosition()), r.SetCameraFocalPoint(*c.GetCameraFocalPoint()),
            r.SetCameraViewUp(*c.GetCameraViewUp()), r.SetCameraViewAngle(c.GetCameraViewAngle()), 1)[-1])
        a_label, a_depth, a_normal = gpu_outputs(clipped)
        b_label, b_depth, b_normal = gpu_outputs(plain)
        table_a = vtk_to_numpy(volume.NewLabelValues()).astype(np.int64)
        table_b = vtk_to_numpy(reference.NewLabelValues()).astype(np.int64)
        value_a = np.where(a_label > 0, table_a[np.maximum(a_label, 1) - 1], 0)
        value_b = np.where(b_label > 0, table_b[np.maximum(b_label, 1) - 1], 0)
        mismatch = value_a != value_b
        total_mismatch += int(mismatch.sum())
        both = ~mismatch & (value_a > 0)
        assert both.sum() > 100
        np.testing.assert_allclose(a_depth[both], b_depth[both], rtol=1e-4, atol=2e-3)
        normals_same = np.all(np.abs(a_normal[both] - b_normal[both]) < 1e-4, axis=1)
        assert normals_same.mean() >= 0.995
    # Pixels whose ray grazes an edge may see the neighbour voxel: at most 1 in 1000.
    print(f"{case}: {total_mismatch} of {3 * WIDTH * HEIGHT} pixels differ from the deleted voxels")
    assert total_mismatch <= 0.001 * 3 * WIDTH * HEIGHT, total_mismatch


def test_crop_equal_to_bounds_is_no_crop(axis_volume):
    labels, volume = axis_volume
    nz, ny, nx = labels.shape
    crop = (-0.5, nx - 0.5, -0.5, ny - 0.5, -0.5, nz - 0.5)  # the voxels' world bounds
    table = vtk_to_numpy(volume.NewLabelValues()).astype(np.int64)
    for lod in LODS.values():
        cropped = make_renderer(volume, lod, crop=crop)
        a_label, a_depth, a_normal = gpu_outputs(cropped)
        b_label, b_depth, b_normal = gpu_outputs(make_renderer(volume, lod))
        same = a_label == b_label
        if lod != S.LOD_VOXEL:
            # Overlapping boxes of one cell tie where the ray enters them together (every box of a
            # cell at the volume's face): then any label whose box holds the hit point is right.
            origin, dirs = primary_rays(cropped)
            hit = (a_label > 0) & (b_label > 0)
            allowed = coarse_box_labels(labels, volume, lod, origin + np.where(hit, b_depth, 0)[:, None] * dirs)
            same |= hit & np.array([h and table[g - 1] in ok for h, g, ok in zip(hit, a_label, allowed)])
        assert same.mean() >= 0.999
        both = same & (a_label > 0)
        np.testing.assert_allclose(a_depth[both], b_depth[both], rtol=1e-4, atol=1e-3)
        assert np.all(np.abs(a_normal[both] - b_normal[both]) < 1e-4, axis=1).mean() >= 0.999


# --- path tracing: secondary rays respect the cut ----------------------------------------------

def test_shadow_and_cut_face_lighting():
    """A floor (label 1) under a plate (label 2), a delta sun straight above, a black sky, one
    bounce. Without clipping the floor under the plate is in its shadow (black); a plane that
    keeps only z <= 10 removes the plate and with it the shadow. An oblique cut through the
    floor is lit by the sun with the cosine of its normal."""
    labels = np.zeros((32, 32, 32), np.uint16)  # z, y, x; world = index (voxel i: [i-0.5, i+0.5])
    labels[0:3] = 1
    labels[20:23, 6:26, 6:26] = 2
    volume = build(labels)

    def camera(r):
        r.SetCameraPosition(16.0, -40.0, 30.0)
        r.SetCameraFocalPoint(16.0, 14.0, 2.0)
        r.SetCameraViewUp(0.0, 0.0, 1.0)
        r.SetCameraViewAngle(40.0)
        return 1

    def trace(planes):
        r = make_renderer(volume, S.LOD_VOXEL, planes, camera=camera)
        r.SetWidth(64)
        r.SetHeight(48)
        s = r.GetSettings()
        s.SetEnvironmentColor(0.0, 0.0, 0.0)
        s.SunOn()
        s.SetSunDirection(0.0, 0.0, 1.0)
        s.SetSunAngularRadius(0.0)
        s.SetSunIrradiance(2.0, 2.0, 2.0)
        s.SetMaximumBounces(1)
        s.SetSamplesPerPixel(4)
        for _ in range(4):
            assert r.Render() == 1
        data = r.GetOutput().GetPointData()
        hdr = vtk_to_numpy(data.GetArray("HDR")).reshape(-1, 4)
        luminance = hdr[:, :3] @ np.array([0.2126, 0.7152, 0.0722])
        label = vtk_to_numpy(data.GetArray("Label")).astype(np.int64)
        depth = vtk_to_numpy(data.GetArray("Depth")).astype(np.float64)
        origin, dirs = primary_rays(r)
        points = origin + np.where(label > 0, depth, 0)[:, None] * dirs
        return luminance, label, points

    table = vtk_to_numpy(volume.NewLabelValues()).astype(np.int64)
    floor_index = int(np.nonzero(table == 1)[0][0]) + 1
    lum0, label0, points0 = trace([])
    lum1, label1, points1 = trace([((0.0, 0.0, 10.0), (0.0, 0.0, -1.0))])
    assert not np.any(label1 == int(np.nonzero(table == 2)[0][0]) + 1)  # the plate is cut away

    def region(label, points, shadowed):
        on_floor = (label == floor_index) & (np.abs(points[:, 2] - 2.5) < 1e-2)
        under = np.all((points[:, :2] > 7.0) & (points[:, :2] < 24.0), axis=1)
        away = np.any((points[:, :2] < 4.0) | (points[:, :2] > 27.0), axis=1)
        return on_floor & (under if shadowed else away)

    shadow0 = region(label0, points0, True)
    shadow1 = region(label1, points1, True)
    lit0 = region(label0, points0, False)
    assert shadow0.sum() > 20 and shadow1.sum() > 20 and lit0.sum() > 20
    lit = lum0[lit0].mean()
    assert lit > 0.05
    assert lum0[shadow0].mean() < 0.02 * lit            # the plate's shadow
    assert abs(lum1[shadow1].mean() / lit - 1) < 0.1    # gone with the plate

    # An oblique cut through the floor, keeping y - z >= 12: its face (outward normal
    # (0, -1, 1) / sqrt 2) faces the camera and the sun at 45 degrees.
    n = np.array([0.0, 1.0, -1.0]) / np.sqrt(2)
    lum2, label2, points2 = trace([((0.0, 13.0, 1.0), tuple(n)), ((0.0, 0.0, 10.0), (0.0, 0.0, -1.0))])
    on_cut = (label2 == floor_index) & (np.abs((points2 - [0.0, 13.0, 1.0]) @ n) < 1e-2) & (points2[:, 2] < 2.0)
    assert on_cut.sum() > 10
    ratio = lum2[on_cut].mean() / lit
    assert 0.4 < ratio < 1.0, ratio  # lit (a shadow ray from inside the solid would be black)


# --- the VTK volume mapper ---------------------------------------------------------------------

@pytest.fixture(scope="module")
def boxes():
    labels = np.zeros((40, 40, 40), np.uint16)
    labels[5:20, 8:30, 10:25] = 3
    labels[15:35, 12:25, 20:38] = 7
    return labels, build(labels)


def test_mapper_clipping_planes_and_cropping(boxes):
    """vtkAbstractMapper's clipping planes (VTK world, after the vtkVolume's matrix) and the
    mapper's cropping (data world) against the CPU caster given the planes in model coordinates,
    computed here; then a plane change: no BVH rebuild, the refinement restarts."""
    _, svdag = boxes
    window, renderer, volume, mapper = mapper_scene(svdag, camera_position=(90, -70, 100),
                                                    focal=(15, 25, 25), clipping=(10.0, 400.0))
    volume.SetPosition(5.0, -3.0, 2.0)
    volume.RotateZ(25.0)
    volume.SetScale(1.2, 0.9, 1.0)
    matrix = vtkMatrix4x4()
    volume.GetMatrix(matrix)
    to_world = np.array([[matrix.GetElement(i, j) for j in range(4)] for i in range(4)])
    plane = vtkPlane()
    world_origin, world_normal = np.array([20.0, 20.0, 30.0]), np.array([-0.3, 0.4, -1.0])
    plane.SetOrigin(*world_origin)
    plane.SetNormal(*world_normal)
    mapper.AddClippingPlane(plane)
    crop = (0.0, 35.0, 0.0, 40.0, 6.0, 40.0)
    mapper.SetCroppingRegionPlanes(*crop)
    mapper.CroppingOn()
    mapper.SetTargetSamplesPerPixel(2)
    window.Render()

    def caster_for(origin_w, normal_w):
        inverse = np.linalg.inv(to_world)
        caster = vtkSegmentationSVDAGRayCaster()
        caster.SetInputData(svdag)
        caster.AddClippingPlane((inverse @ np.append(origin_w, 1))[:3], to_world[:3, :3].T @ normal_w)
        caster.SetCroppingRegionPlanes(*crop)
        caster.CroppingOn()
        return caster

    def compare(caster):
        agree = total = cuts = 0
        for y in range(2, 150, 5):
            for x in range(2, 200, 5):
                origin, direction = pixel_ray(renderer, x, y)
                expected = caster_pick(caster, origin, direction, to_world)
                got = mapper_pick(mapper, renderer, x + 0.5, y + 0.5)
                total += 1
                if expected is None or got is None:
                    agree += expected is None and got is None
                    continue
                ok = got[0] == expected[0] and np.linalg.norm(got[1] - expected[1]) < 2e-2
                if ok and caster.GetHitClippingPlane() >= 0:
                    cuts += 1
                    ok = np.allclose(got[2], expected[2], atol=1e-4)
                agree += ok
        return agree / total, cuts

    fraction, cuts = compare(caster_for(world_origin, world_normal))
    assert fraction >= 0.99 and cuts > 20, (fraction, cuts)

    # A plane change: a uniform update, not a BVH rebuild; the refinement restarts.
    window.Render()
    builds = mapper.GetNumberOfBVHBuilds()
    assert mapper.GetAccumulatedSamples() == 2
    moved = world_origin + np.array([0.0, 0.0, -6.0])
    plane.SetOrigin(*moved)
    start = time.perf_counter()
    window.Render()
    seconds = time.perf_counter() - start
    assert mapper.GetAccumulatedSamples() == 1
    assert mapper.GetNumberOfBVHBuilds() == builds
    print(f"clip change to next frame: {seconds * 1000:.1f} ms (trace {mapper.GetLastTraceMilliseconds():.1f} ms)")
    fraction, cuts = compare(caster_for(moved, world_normal))
    assert fraction >= 0.99 and cuts > 20, (fraction, cuts)

    # RemoveAllClippingPlanes and CroppingOff: back to the whole volume, still no rebuild.
    mapper.RemoveAllClippingPlanes()
    mapper.CroppingOff()
    window.Render()
    assert mapper.GetNumberOfBVHBuilds() == builds
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(svdag)
    origin, direction = pixel_ray(renderer, 100, 75)
    expected = caster_pick(caster, origin, direction, to_world)
    got = mapper_pick(mapper, renderer, 100.5, 75.5)
    assert expected is not None and got is not None and got[0] == expected[0]


def test_mapper_bad_planes_report_errors(boxes):
    _, svdag = boxes
    window, renderer, volume, mapper = mapper_scene(svdag)
    errors = capture_errors(mapper)
    for i in range(7):
        p = vtkPlane()
        p.SetOrigin(0, 0, i)
        p.SetNormal(0, 0, 1)
        mapper.AddClippingPlane(p)
    window.Render()
    assert any("at most 6 clipping planes" in e for e in errors), errors
    mapper.RemoveAllClippingPlanes()
    errors.clear()
    p = vtkPlane()
    p.SetNormal(float("nan"), 0.0, 1.0)
    mapper.AddClippingPlane(p)
    window.Render()
    assert any("normal must be a finite, non-zero vector" in e for e in errors), errors
    mapper.RemoveAllClippingPlanes()
    errors.clear()
    mapper.SetCroppingRegionPlanes(10.0, 5.0, 0.0, 1.0, 0.0, 1.0)
    assert any("inverted along x" in e for e in errors), errors
    assert mapper.GetCroppingRegionPlanes()[:2] == (0.0, 1.0)  # the previous box stays
    errors.clear()
    window.Render()
    assert not errors
    assert mapper_pick(mapper, renderer, 100.5, 75.5) is not None


def test_renderer_and_caster_bad_input(boxes):
    """The image renderer owns its clipping planes and crop box (the settings hold none): bad
    planes fail the pass with the core's message, a bad box is refused where it is set."""
    labels, svdag = boxes
    assert not hasattr(vtkSegmentationSVDAGRenderSettings(), "AddClippingPlane")
    assert not hasattr(vtkSegmentationSVDAGRenderSettings(), "SetCroppingRegionPlanes")
    renderer = make_renderer(svdag, S.LOD_VOXEL)
    errors = capture_errors(renderer)
    assert renderer.GetMaximumNumberOfClippingPlanes() == 6
    for origin, normal, message in (((0, 0, 0), (float("nan"), 0, 1), "clipping plane 0: the normal"),
                                    ((0, 0, 0), (0, 0, 0), "clipping plane 0: the normal"),
                                    ((float("inf"), 0, 0), (0, 0, 1), "clipping plane 0: the origin")):
        plane = make_plane(origin, normal)
        renderer.AddClippingPlane(plane)
        assert renderer.Render() == 0 and message in errors[-1], errors
        renderer.RemoveClippingPlane(plane)
    assert renderer.GetClippingPlanes().GetNumberOfItems() == 0
    planes = [make_plane((0, 0, i), (0, 0, 1)) for i in range(7)]
    for plane in planes[:6]:
        renderer.AddClippingPlane(plane)
    errors.clear()
    assert renderer.Render() == 1 and not errors
    renderer.AddClippingPlane(planes[6])
    assert renderer.Render() == 0 and "at most 6 clipping planes" in errors[-1]
    renderer.RemoveAllClippingPlanes()
    assert renderer.GetClippingPlanes().GetNumberOfItems() == 0
    renderer.SetCroppingRegionPlanes(0, 1, 5, 2, 0, 1)
    assert "inverted along y" in errors[-1]
    renderer.SetCroppingRegionPlanes(0, 1, 0, float("nan"), 0, 1)
    assert "finite" in errors[-1]
    assert renderer.GetCroppingRegionPlanes() == (0, 1, 0, 1, 0, 1)  # unchanged
    errors.clear()
    assert renderer.Render() == 1 and not errors

    caster = vtkSegmentationSVDAGRayCaster()
    errors = capture_errors(caster)
    assert caster.AddClippingPlane((0, 0, 0), (0, float("nan"), 1)) == 0
    assert caster.AddClippingPlane((0, 0, 0), (0, 0, 0)) == 0
    for i in range(6):
        assert caster.AddClippingPlane((0, 0, i), (0, 0, 1)) == 1
    assert caster.AddClippingPlane((0, 0, 9), (0, 0, 1)) == 0
    assert "at most 6" in errors[-1]
    caster.SetCroppingRegionPlanes(3, 1, 0, 1, 0, 1)
    assert "min <= max" in errors[-1]


# --- pyvista and the command line --------------------------------------------------------------

def test_add_segmentation_clipping_and_pick(boxes):
    import pyvista as pv

    import vtksvdag

    labels, _ = boxes
    xyz = np.ascontiguousarray(np.transpose(labels, (2, 1, 0)))
    normal = np.array([0.0, 0.0, -1.0])
    plotter = pv.Plotter(off_screen=True, window_size=(200, 150))
    try:
        actor = vtksvdag.add_segmentation(plotter, xyz, clipping_planes=[((20, 20, 12.2), normal)],
                                          crop=(0, 39, 0, 39, 0, 39), spp=1, lod="voxel")
        mapper = actor.GetMapper()
        assert mapper.GetClippingPlanes().GetNumberOfItems() == 1
        assert mapper.GetCropping() and mapper.GetCroppingRegionPlanes() == (0, 39, 0, 39, 0, 39)
        plotter.camera_position = [(20, 20, 120), (20, 20, 10), (0, 1, 0)]
        plotter.camera.clipping_range = (10, 300)
        vtksvdag.refine(plotter)
        hit = vtksvdag.pick(plotter, 100, 75)  # looking down onto the cut through label 3
        assert hit is not None and hit["label"] == 3
        np.testing.assert_allclose(hit["normal"], -normal, atol=1e-5)
        assert abs(hit["position"][2] - 12.2) < 1e-2
    finally:
        plotter.close()
    plotter = pv.Plotter(off_screen=True)
    try:
        for options, message in [
            ({"clipping_planes": [((0, 0, 0), (0, 0, 0))]}, "non-zero"),
            ({"clipping_planes": [((0, 0, 0), (np.nan, 0, 1))]}, "finite"),
            ({"clipping_planes": [((0, 0, i), (0, 0, 1)) for i in range(7)]}, "at most 6"),
            ({"clipping_planes": [(0, 0, 1)]}, "(origin, normal)"),
            ({"crop": (0, 1, 5, 2, 0, 1)}, "inverted along y"),
            ({"crop": (0, 1, 2)}, "xmin, xmax"),
        ]:
            with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")):
                vtksvdag.add_segmentation(plotter, xyz, **options)
    finally:
        plotter.close()


def test_cli_clip_and_crop(tmp_path):
    labels = np.zeros((20, 20, 20), np.uint16)
    labels[4:16, 4:16, 4:16] = 5
    path = tmp_path / "box.nrrd"
    nrrd.write(str(path), labels, index_order="C")
    cli = [sys.executable, "-m", "vtksvdag", "render", str(path), "--width", "32", "--height", "32",
           "--spp", "1", "--json"]
    plain = subprocess.run(cli + ["-o", str(tmp_path / "a.exr")], capture_output=True, text=True, cwd=REPO)
    assert plain.returncode == 0, plain.stderr
    clipped = subprocess.run(cli + ["-o", str(tmp_path / "b.exr"), "--clip", "10,10,10,0,0,-1",
                                    "--clip", "10,10,10,1,0,0", "--crop", "0,19,0,19,0,19"],
                             capture_output=True, text=True, cwd=REPO)
    assert clipped.returncode == 0, clipped.stderr
    result = json.loads(clipped.stdout)
    assert result["clip"] == [[10, 10, 10, 0, 0, -1], [10, 10, 10, 1, 0, 0]]
    assert result["crop"] == [0, 19, 0, 19, 0, 19]
    for bad, message in [(["--clip", "1,2,3"], "6 finite numbers"), (["--clip", "0,0,0,0,0,0"], "normal"),
                         (["--crop", "5,1,0,1,0,1"], "inverted along x"),
                         (["--clip", "0,0,0,nan,0,1"], "finite")]:
        run = subprocess.run(cli + ["-o", str(tmp_path / "c.png")] + bad, capture_output=True, text=True, cwd=REPO)
        assert run.returncode != 0 and message in run.stderr, (bad, run.stderr)
    seven = [arg for i in range(7) for arg in ("--clip", f"0,0,{i},0,0,1")]
    run = subprocess.run(cli + ["-o", str(tmp_path / "c.png")] + seven, capture_output=True, text=True, cwd=REPO)
    assert run.returncode != 0 and "at most 6" in run.stderr, run.stderr


# --- image baseline (pytest-pyvista, Testing/Data/Baseline/pyvista), with value checks ---------

def test_clipped_scene(verify_image_cache):
    """The image tests' scene (slab 3, ball 7, rod 12) cut by an oblique plane through the ball's
    center (which also removes the rod) and cropped along x (the slab loses its first voxels),
    path-traced under a sun with a fixed seed. Values: the pixel at the ball's center is its cut
    face (label 7, the plane's outward normal, on the plane), and picks on a grid equal the CPU ray
    caster's with the same plane and box."""
    import vtksvdag
    from test_mapper_images import SIZE, new_plotter, scene_labels

    normal = np.array([-0.5, -0.4, -1.0])
    normal /= np.linalg.norm(normal)
    origin = np.array([26.0, 20.0, 22.0])
    plotter = new_plotter()
    try:
        actor = vtksvdag.add_segmentation(
            plotter, scene_labels(), colors={3: "steelblue", 7: "gold", 12: "white"},
            sun={"direction": (0.4, 0.8, 0.5), "irradiance": 3.0}, environment=(0.3, 0.32, 0.36),
            clipping_planes=[(origin, normal)], crop=(2, 40, -1, 40, -1, 40), spp=8, seed=3,
            lod="voxel")
        plotter.camera_position = [(50, 40, 110), (22, 20, 18), (0, 1, 0)]
        stats = vtksvdag.refine(plotter, timeout=60)
        assert all(s["converged"] for s in stats)
        renderer = plotter.renderer
        mapper = actor.GetMapper()
        # Where the view ray through the ball's center meets the plane: the cut face.
        camera = np.array(plotter.camera_position[0])
        direction = origin - camera
        renderer.SetWorldPoint(*origin, 1.0)
        renderer.WorldToDisplay()
        x, y, _ = renderer.GetDisplayPoint()
        hit = mapper_pick(mapper, renderer, x, y)
        assert hit is not None and hit[0] == 7
        np.testing.assert_allclose(hit[2], -normal, atol=1e-5)
        assert abs((hit[1] - origin) @ normal) < 1e-2
        assert direction @ hit[2] < 0  # facing the camera
        caster = vtkSegmentationSVDAGRayCaster()
        caster.SetInputData(mapper.GetInput())
        caster.AddClippingPlane(origin, normal)
        caster.SetCroppingRegionPlanes(2, 40, -1, 40, -1, 40)
        caster.CroppingOn()
        agree = total = cuts = 0
        seen = set()
        for py in range(4, SIZE[1], 11):
            for px in range(4, SIZE[0], 11):
                o, d = pixel_ray(renderer, px, py)
                expected = caster_pick(caster, o, d)
                got = mapper_pick(mapper, renderer, px + 0.5, py + 0.5)
                total += 1
                if expected is None or got is None:
                    agree += expected is None and got is None
                    continue
                seen.add(got[0])
                cuts += caster.GetHitClippingPlane() >= 0
                agree += got[0] == expected[0] and np.allclose(got[2], expected[2], atol=1e-4)
        assert agree >= total - max(1, total // 100), (agree, total)
        assert seen == {3, 7} and cuts > 20  # the rod is cut away
        plotter.show(auto_close=False)
    finally:
        plotter.close()
