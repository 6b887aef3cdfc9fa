"""The stiff and extreme cases: the ONE definition, run by test_extreme.py (pytest) and by
bench/stability.py (which times them and writes docs/stability.md).

Each case is a function returning a result dict:
    name       short unique name
    group      geometry | rays | shading | scale
    checked    what was checked, one line
    error      the measured error against the reference (the CPU ray caster, a brute force
               written here in numpy, or an analytic answer): a float, 0 for exact, inf where an
               answer was plainly wrong (a miss for a hit, a wrong label, a wrong dtype)
    tolerance  the largest error that passes
    passed     bool
    detail     (optional) what was observed, for a failure message

CASES are the cases pytest runs; LARGE_CASES (a DAG buffer over 128 MiB, about 1024^3 random
voxels) only `bench/stability.py --large` runs.

Conventions (vtkSegmentationSVDAG, README): voxel (i, j, k) is the box [i, i+1)^3 of index space
p, world = origin + D diag(spacing) (p - 0.5); so the voxel's center is origin + D s (i, j, k)
and its faces lie at origin + D s (index -/+ 0.5). Arrays here are indexed [x, y, z].
"""
import functools
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import textwrap

import numpy as np
from conftest import REPO, caster_pick, mapper_pick, mapper_scene, pixel_ray, primary_rays
from vtkmodules.util.numpy_support import vtk_to_numpy

import vtksvdag
from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGRayCaster
from vtksvdag.vtkSVDAGRendering import (vtkSegmentationSVDAGRenderer,
                                        vtkSegmentationSVDAGRenderSettings)

INF = float("inf")
CASES = []
LARGE_CASES = []


def case(group, large=False):
    """Registers a case function of `group`; its name is the function's name."""
    def register(function):
        function.group = group
        function.case_name = function.__name__
        (LARGE_CASES if large else CASES).append(function)
        return function
    return register


def result(name, group, checked, error, tolerance, passed=None, detail=""):
    error = float(error)
    if passed is None:
        passed = math.isfinite(error) and error <= tolerance  # nan never passes
    return {"name": name, "group": group, "checked": checked, "error": error,
            "tolerance": float(tolerance), "passed": bool(passed), "detail": str(detail)}


# ----------------------------------------------------------------------------------- geometry


class Geometry:
    """Index <-> world of a volume: world = origin + D diag(spacing) (p - 0.5)."""

    def __init__(self, shape, spacing=(1, 1, 1), origin=(0, 0, 0), direction=None):
        self.shape = np.array(shape)
        self.spacing = np.array(spacing, float)
        self.origin = np.array(origin, float)
        self.direction = np.eye(3) if direction is None else np.array(direction, float)
        self.matrix = self.direction @ np.diag(self.spacing)

    def world(self, p):
        return self.origin + self.matrix @ (np.asarray(p, float) - 0.5)

    def index(self, w):
        return np.linalg.solve(self.matrix, np.asarray(w, float) - self.origin) + 0.5

    def kwargs(self):
        return {"spacing": tuple(self.spacing), "origin": tuple(self.origin),
                "direction": self.direction}


def rotation(seed):
    """A proper rotation matrix, none of whose columns is close to an axis."""
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def round_trip_error(array, volume):
    """0 when to_numpy() gives back the same dtype and bits; else the fraction of voxels that
    differ (inf for another dtype or shape)."""
    out = volume.to_numpy()
    if out.dtype != array.dtype or out.shape != array.shape:
        return INF, f"got {out.dtype} {out.shape}, expected {array.dtype} {array.shape}"
    wrong = np.count_nonzero(out != array)
    return wrong / array.size, f"{wrong} of {array.size} voxels differ"


def caster_of(volume, lod=None):
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(volume.dataobject if hasattr(volume, "dataobject") else volume)
    if lod is not None:
        caster.SetLOD(lod)
    return caster


def hit_value(caster):
    return vtk_to_numpy(caster.GetHitLabelValue())[0]


def axis_rays_error(array, volume, geometry, rays):
    """Rays along index axes from outside the volume through voxel centers: the analytic answer
    is the first labelled voxel on the line, hit on its entry face. `rays` holds
    (i, j, k, axis, sign): the line through voxel (i, j, k)'s center along +/- axis. Returns
    the largest hit-position error in units of the voxel side along the axis (inf for a wrong
    hit, miss or label) and a description of the worst ray."""
    caster = caster_of(volume)
    worst, detail, hits = 0.0, "", 0
    for i, j, k, axis, sign in rays:
        line = [i, j, k]
        line[axis] = slice(None)
        values = array[tuple(line)]
        nonzero = np.flatnonzero(values)
        start = np.array([i, j, k], float) + 0.5
        start[axis] = -2.0 if sign > 0 else array.shape[axis] + 2.0
        direction = geometry.direction[:, axis] * sign
        hit = caster.CastRay(geometry.world(start), direction)
        hits += bool(hit)
        if len(nonzero) == 0:
            error = 0.0 if not hit else INF
            what = f"expected a miss, got {'a hit' if hit else 'a miss'}"
        else:
            first = nonzero[0] if sign > 0 else nonzero[-1]
            face = np.array([i, j, k], float) + 0.5
            face[axis] = first if sign > 0 else first + 1
            expected = geometry.world(face)
            if not hit:
                error, what = INF, f"expected label {values[first]} at {expected}, got a miss"
            elif hit_value(caster) != values[first]:
                error = INF
                what = f"expected label {values[first]}, got {hit_value(caster)}"
            else:
                error = (np.linalg.norm(np.array(caster.GetHitPosition()) - expected)
                         / geometry.spacing[axis])
                what = f"hit {caster.GetHitPosition()} expected {tuple(expected)}"
        if not error <= worst:
            worst, detail = error, f"ray ({i},{j},{k}) axis {axis} sign {sign}: {what}"
    return worst, f"{hits} of {len(rays)} rays hit; worst: {detail or 'exact'}"


def image_renderer(volume, width, height, spp=1):
    """The GPU image renderer of a SegmentationVolume at a size, `spp` samples per pass."""
    renderer = vtkSegmentationSVDAGRenderer()
    renderer.SetInputData(volume.dataobject)
    renderer.SetWidth(width)
    renderer.SetHeight(height)
    renderer.GetSettings().SetSamplesPerPixel(spp)
    return renderer


def gpu_vs_cpu(volume, camera, width=32, height=24):
    """Label (index + 1) and Depth of the image renderer against the CPU caster on the same
    pixel-center rays (conftest.primary_rays); `camera(renderer)` sets the camera. Returns
    (fraction of pixels with another label, largest relative depth error where both hit,
    number of hits, detail)."""
    renderer = image_renderer(volume, width, height)
    renderer.GetSettings().SetLOD(vtkSegmentationSVDAGRenderSettings.LOD_VOXEL)
    camera(renderer)
    if renderer.Render() != 1:
        return INF, INF, 0, "the renderer reported an error"
    data = renderer.GetOutput().GetPointData()
    gpu_label = vtk_to_numpy(data.GetArray("Label")).astype(np.int64)
    gpu_depth = vtk_to_numpy(data.GetArray("Depth")).astype(np.float64)
    caster = caster_of(volume)
    origin, dirs = primary_rays(renderer)
    cpu_label = np.zeros(len(dirs), np.int64)
    cpu_depth = np.full(len(dirs), INF)
    for n, d in enumerate(dirs):
        if caster.CastRay(origin, d):
            cpu_label[n] = caster.GetHitLabelIndex() + 1
            cpu_depth[n] = caster.GetHitDistance()
    differ = gpu_label != cpu_label
    both = ~differ & (cpu_label > 0)
    depth_error = 0.0
    if both.any():
        depth_error = float(np.max(np.abs(gpu_depth[both] - cpu_depth[both])
                                   / np.maximum(cpu_depth[both], 1e-30)))
    detail = f"{differ.sum()} of {differ.size} labels differ, {both.sum()} hits compared"
    if differ.any():
        n = np.flatnonzero(differ)[0]
        detail += f"; first: pixel {n} gpu {gpu_label[n]} cpu {cpu_label[n]}"
    return differ.mean(), depth_error, int((cpu_label > 0).sum()), detail


def gpu_result(name, volume, camera, checked):
    mismatch, depth_error, hits, detail = gpu_vs_cpu(volume, camera)
    error = max(mismatch, depth_error)
    passed = error <= 1e-4 and hits > 50
    return result(name, "geometry", checked, error, 1e-4, passed,
                  f"{detail}; max relative depth error {depth_error:.3g}; {hits} CPU hits")


def boxes_volume(shape, dtype=np.uint16, seed=0):
    """Random labels 1..6 on 25% of the voxels plus one solid box: faces, holes, full cells."""
    rng = np.random.default_rng(seed)
    array = rng.integers(1, 7, size=shape).astype(dtype)
    array[rng.random(shape) < 0.75] = 0
    sx, sy, sz = (max(1, s // 4) for s in shape)
    array[sx:3 * sx, sy:3 * sy, sz:3 * sz] = 6
    return array


def some_axis_rays(shape, rng, count=30):
    rays = []
    for n in range(count):
        i, j, k = (int(rng.integers(s)) for s in shape)
        rays.append((i, j, k, n % 3, 1 if (n // 3) % 2 == 0 else -1))
    return rays


GEOMETRIES = {
    "anisotropic 4x4x40": Geometry((24, 20, 18), spacing=(4, 4, 40), origin=(-10, 3, 7)),
    "spacing 1e-6": Geometry((24, 20, 18), spacing=(1e-6, 1e-6, 1e-6), origin=(1e-6, 0, -2e-5)),
    "spacing 1e6": Geometry((24, 20, 18), spacing=(1e6, 1e6, 1e6), origin=(0, 5e6, 0)),
    "origin 1e7": Geometry((24, 20, 18), spacing=(0.7, 1.0, 1.3), origin=(1e7, -1e7, 1e7)),
    "rotated direction": Geometry((24, 20, 18), spacing=(0.7, 1.0, 1.3), origin=(5, -3, 10),
                                  direction=rotation(2024)),
}


@functools.lru_cache(maxsize=None)
def geometry_volume(key):
    geometry = GEOMETRIES[key]
    array = boxes_volume(tuple(geometry.shape), seed=len(key))
    return array, vtksvdag.from_numpy(array, **geometry.kwargs()), geometry


def make_geometry_cases(key, gpu):
    slug = key.replace(" ", "_").replace(".", "")

    def round_trip():
        array, volume, _ = geometry_volume(key)
        error, detail = round_trip_error(array, volume)
        return result(f"{slug} round trip", "geometry",
                      f"{key}: to_numpy() bit-exact, dtype kept", error, 0, detail=detail)

    def rays():
        array, volume, geometry = geometry_volume(key)
        error, detail = axis_rays_error(array, volume, geometry,
                                        some_axis_rays(array.shape, np.random.default_rng(1)))
        return result(f"{slug} axis rays", "geometry",
                      f"{key}: CPU caster hit on the analytic face (error in voxels), 30 rays",
                      error, 1e-6, detail=detail)

    def render():
        _, volume, _ = geometry_volume(key)
        return gpu_result(f"{slug} GPU vs CPU", volume, lambda r: r.ResetCamera(35, 25, 1.2),
                          f"{key}: GPU Label/Depth at pixel centers = CPU caster (max of "
                          f"label-mismatch fraction, relative depth error)")

    functions = [round_trip, rays] + ([render] if gpu else [])
    for function in functions:
        function.__name__ = f"{slug}_{function.__name__}"
        case("geometry")(function)


for _key, _gpu in (("anisotropic 4x4x40", True), ("spacing 1e-6", False), ("spacing 1e6", True),
                   ("origin 1e7", True), ("rotated direction", True)):
    make_geometry_cases(_key, _gpu)


def round_trip_and_rays(name, array, rays, checked, geometry=None):
    geometry = geometry or Geometry(array.shape)
    volume = vtksvdag.from_numpy(array, **geometry.kwargs())
    rt_error, rt_detail = round_trip_error(array, volume)
    ray_error, ray_detail = axis_rays_error(array, volume, geometry, rays) if rays else (0.0, "")
    error = max(rt_error, ray_error)
    return result(name, "geometry", checked + " (round trip exact; ray error in voxels)", error,
                  1e-6, passed=rt_error == 0 and ray_error <= 1e-6,
                  detail=f"round trip: {rt_detail}; rays: {ray_detail}")


@case("geometry")
def dims_1x1x1():
    array = np.full((1, 1, 1), 7, np.uint8)
    rays = [(0, 0, 0, a, s) for a in range(3) for s in (1, -1)]
    return round_trip_and_rays("dims 1x1x1", array, rays,
                               "1x1x1: round trip, 6 axis rays hit its 6 faces")


@case("geometry")
def dims_1x1x65536():
    k = np.arange(65536)
    array = ((k * 2654435761 >> 7) % 5).astype(np.int16).reshape(1, 1, -1)
    array[0, 0, :40000] = 0  # a ray along z crosses 40000 empty voxels first
    array[0, 0, 40000] = 3
    rays = [(0, 0, 0, 2, 1), (0, 0, 0, 2, -1), (0, 0, 40000, 0, 1), (0, 0, 65535, 1, -1),
            (0, 0, 12345, 0, -1)]
    return round_trip_and_rays("dims 1x1x65536", array, rays,
                               "1x1x65536: round trip; rays along z (40000 empty voxels, then "
                               "label 3) and across")


@case("geometry")
def dims_4096x4096x1():
    rng = np.random.default_rng(3)
    array = np.zeros((4096, 4096, 1), np.uint8)
    array[rng.random(array.shape) < 0.01] = 200
    array[1000:3000, 2000:2100, 0] = 17
    rays = [(int(x), int(y), 0, 2, -1) for x, y in rng.integers(0, 4096, (12, 2))]
    rays += [(1500, 2050, 0, 2, 1), (0, 2050, 0, 0, 1), (4095, 2050, 0, 0, -1)]
    return round_trip_and_rays("dims 4096x4096x1", array, rays,
                               "4096x4096x1: round trip; rays into the sheet and along it")


@case("geometry")
def sheets_and_lines():
    array = np.zeros((48, 40, 36), np.uint32)
    array[20, :, :] = 3        # a one-voxel sheet x = 20
    array[:, 33, 30] = 5       # a one-voxel line along x
    array[7, :, 11] = 9        # a line along y
    array[40, 2, 5:] = 11      # a line along z, touching the border
    rays = [(0, 10, 10, 0, 1), (47, 10, 10, 0, -1), (3, 33, 30, 2, 1), (3, 33, 30, 0, 1),
            (7, 0, 11, 1, -1), (7, 17, 11, 2, -1), (40, 2, 20, 2, -1), (40, 2, 20, 1, 1),
            (20, 39, 35, 1, -1), (30, 33, 30, 2, -1)]
    return round_trip_and_rays("one-voxel sheets and lines", array, rays,
                               "sheet, lines along x, y, z: round trip, axis rays onto them")


@case("geometry")
def checkerboard_3d():
    x, y, z = np.indices((33, 31, 29))
    array = (1 + (x + y + z) % 2).astype(np.uint8)   # every voxel labelled, 1 and 2
    rays = some_axis_rays(array.shape, np.random.default_rng(4))
    return round_trip_and_rays("3D checkerboard", array, rays,
                               "checkerboard of labels 1/2: round trip, axis rays")


@case("geometry")
def all_background():
    array = np.zeros((40, 17, 33), np.int32)
    rays = some_axis_rays(array.shape, np.random.default_rng(5), 12)
    return round_trip_and_rays("all background", array, rays,
                               "all zeros: round trip, every axis ray misses")


@case("geometry")
def all_one_label():
    array = np.full((37, 16, 50), 42, np.uint16)
    rays = some_axis_rays(array.shape, np.random.default_rng(6), 12)
    return round_trip_and_rays("all one label", array, rays,
                               "every voxel label 42: round trip, axis rays hit the border faces")


@case("geometry")
def million_labels():
    rng = np.random.default_rng(7)
    array = (rng.permutation(1_000_000) + 1).astype(np.uint32).reshape(100, 100, 100)
    rays = some_axis_rays(array.shape, rng, 12)
    return round_trip_and_rays("1,000,000 labels", array, rays,
                               "100^3, a unique label per voxel: round trip, axis rays' labels")


def make_dtype_case(dtype):
    info = np.iinfo(dtype)

    def function():
        array = np.zeros((10, 9, 8), dtype)
        values = [info.min, info.max, info.min + 1, info.max - 1, 1]
        if info.min < 0:
            values.append(-1)
        for n, value in enumerate(values):
            array[n % 10, 2:7, n % 8] = value
        array[9, 8, 7] = info.max
        array[0, 0, 0] = info.min
        geometry = Geometry(array.shape)
        volume = vtksvdag.from_numpy(array)
        error, detail = round_trip_error(array, volume)
        # the caster's label value, in the original dtype, at the extremes
        caster = caster_of(volume)
        for (i, j, k) in ((9, 8, 7), (0, 0, 0), (1, 4, 1), (0, 4, 0)):
            want = array[i, j, k]
            if want == 0:
                continue
            ok = caster.CastRay(geometry.world((i + 0.5, j + 0.5, -3.0)), (0, 0, 1))
            got = vtk_to_numpy(caster.GetHitLabelValue()) if ok else None
            if not ok or got.dtype != dtype or got[0] != want:
                error = INF
                detail += f"; voxel ({i},{j},{k}) want {want!r} got {got!r}"
        return result(f"{np.dtype(dtype).name} limits", "geometry",
                      f"{np.dtype(dtype).name} min {info.min} and max {info.max} in one volume: "
                      "round trip, caster label value and dtype", error, 0, detail=detail)

    function.__name__ = f"limits_{np.dtype(dtype).name}"
    case("geometry")(function)


for _dtype in (np.int8, np.uint8, np.int16, np.uint16, np.int32, np.uint32, np.int64, np.uint64):
    make_dtype_case(_dtype)


# ---------------------------------------------------------------------------------------- rays
# Volumes of these cases have origin (0.5, 0.5, 0.5), spacing 1, no rotation: world = index
# space p exactly, so rays with dyadic coordinates are exact in floating point.

UNIT = Geometry((1, 1, 1), origin=(0.5, 0.5, 0.5))


def brute_force(array, o, d):
    """Reference for a ray o + t d (|d| = 1) in index space: the closed minimum entry distance
    over all labelled voxels (touching counts) and the strict one (the ray's interior must pass
    through the voxel's interior). Half-open voxel faces do not matter: both are reported."""
    x, y, z = np.nonzero(array)
    lo = np.stack([x, y, z], axis=1).astype(float)
    enter = np.zeros(len(lo))
    leave = np.full(len(lo), INF)
    closed = np.ones(len(lo), bool)
    strict = np.ones(len(lo), bool)
    for a in range(3):
        if d[a] == 0.0:
            closed &= (o[a] >= lo[:, a]) & (o[a] <= lo[:, a] + 1)
            strict &= (o[a] > lo[:, a]) & (o[a] < lo[:, a] + 1)
            continue
        t0 = (lo[:, a] - o[a]) / d[a]
        t1 = (lo[:, a] + 1 - o[a]) / d[a]
        enter = np.maximum(enter, np.minimum(t0, t1))
        leave = np.minimum(leave, np.maximum(t0, t1))
    tol = 1e-9 * (1 + np.abs(enter))
    closed &= leave >= enter - tol
    strict &= leave - enter > tol
    closed_min = enter[closed].min() if closed.any() else INF
    strict_min = enter[strict].min() if strict.any() else INF
    return closed_min, strict_min


def ray_error(array, caster, o, d, must_hit_closed=False):
    """How far the caster's answer is from the brute force (index units; inf: wrong hit, miss or
    label). Valid: a hit at t in [closed_min, strict_min] on a labelled voxel (GetHitVoxel)
    whose label is the hit's and whose closed box holds the hit point; a miss only where no
    voxel is entered strictly. must_hit_closed: the ray touches solid voxels only where every
    voxel it touches is solid (it lies on uniform faces): it must hit at closed_min."""
    o = np.asarray(o, float)
    d = np.asarray(d, float) / np.linalg.norm(d)
    closed_min, strict_min = brute_force(array, o, d)
    if must_hit_closed:
        strict_min = closed_min
    if not caster.CastRay(o, d):
        return (INF if math.isfinite(strict_min) else 0.0), f"miss; reference t in [{closed_min}, {strict_min}]"
    t = caster.GetHitDistance()
    voxel = caster.GetHitVoxel()
    what = f"hit t={t} voxel {voxel}; reference t in [{closed_min}, {strict_min}]"
    inside = all(0 <= v < s for v, s in zip(voxel, array.shape))
    if not inside or array[voxel] == 0 or hit_value(caster) != array[voxel]:
        return INF, what + " (wrong voxel or label)"
    p = o + t * d
    if np.any(p < np.array(voxel) - 1e-6) or np.any(p > np.array(voxel) + 1 + 1e-6):
        return INF, what + f" (hit point {p} not on the voxel)"
    # relative to the distance travelled: the traversal runs in float (Traversal.h, shared with
    # the GPU), so a hit distance carries float rounding
    return max(0.0, closed_min - t, t - strict_min) / max(1.0, t), what


def rays_result(name, checked, array, rays, must_hit_closed=False, tolerance=1e-6):
    volume = vtksvdag.from_numpy(array, **UNIT.kwargs())
    caster = caster_of(volume)
    worst, detail, hits = 0.0, "", 0
    for o, d in rays:
        error, what = ray_error(array, caster, o, d, must_hit_closed)
        hits += what.startswith("hit")
        if not error <= worst:
            worst, detail = error, f"o={tuple(o)} d={tuple(d)}: {what}"
    detail = f"{hits} of {len(rays)} rays hit; worst: {detail or 'exact'}"
    return result(name, "rays", checked + f" ({len(rays)} rays; relative distance error)", worst,
                  tolerance, detail=detail)


@functools.lru_cache(maxsize=None)
def coarse_volume():
    """48^3 labels constant on 2x2x2 groups of voxels (2c-1, 2c): every even plane is a face
    with equal voxels on both sides... of each group, so rays on even edges and corners (and all
    16-voxel cell boundaries) touch only uniform neighbourhoods."""
    rng = np.random.default_rng(8)
    coarse = rng.integers(1, 5, size=(25, 25, 25)).astype(np.uint16)
    coarse[rng.random(coarse.shape) < 0.7] = 0
    i = (np.arange(48) + 1) // 2
    return coarse[np.ix_(i, i, i)]


@case("rays")
def axis_aligned_rays():
    array = boxes_volume((40, 36, 44), seed=9)
    rng = np.random.default_rng(10)
    rays = []
    for n in range(150):
        axis, sign = n % 3, 1 if n % 2 else -1
        o = rng.integers(0, 40, 3) + 0.5
        o[axis] = -5.0 if sign > 0 else 50.0
        d = np.zeros(3)
        d[axis] = sign
        rays.append((o, d))
    return rays_result("axis-aligned rays", "exactly axis-aligned rays through voxel centers vs "
                       "brute force", array, rays)


def edge_rays(coordinates):
    rays = []
    for a in range(3):
        for u in coordinates:
            for v in coordinates:
                for sign in (1, -1):
                    o = np.zeros(3)
                    o[a] = -3.0 if sign > 0 else 51.0
                    o[(a + 1) % 3], o[(a + 2) % 3] = u, v
                    d = np.zeros(3)
                    d[a] = sign
                    rays.append((o, d))
    return rays


@case("rays")
def block_edge_rays():
    return rays_result("rays along block edges", "axis rays exactly on 16-voxel cell edges "
                       "inside the volume (uniform neighbourhoods: must hit at the first contact)",
                       coarse_volume(), edge_rays((16, 32, 10, 2)), must_hit_closed=True)


@case("rays")
def volume_border_rays():
    return rays_result("rays along the volume's border edges", "axis rays on the volume's outer "
                       "edges and faces (solid inside, empty outside) vs brute force",
                       coarse_volume(), edge_rays((0, 48, 16)))


@case("rays")
def block_corner_rays():
    array = coarse_volume()
    rays = []
    for d in ((1, 1, 1), (1, 1, 0), (1, 0, 1), (0, 1, 1), (1, -1, 1), (2, 1, 1), (1, 2, 0)):
        d = np.array(d, float)
        for start in ((0, 0, 0), (16, 16, 16), (0, 16, 32), (32, 0, 16), (16, 32, 0)):
            o = np.array(start, float) - 6 * d
            rays.append((o, d))
            rays.append((o + 60 * d, -d))
    return rays_result("rays through block corners", "diagonal rays through 16-voxel cell "
                       "corners and edges vs brute force", array, rays)


@case("rays")
def grazing_between_solids():
    array = np.zeros((40, 40, 40), np.uint8)
    array[4:36, 4:36, 8:16] = 1
    array[4:36, 4:36, 16:22] = 2      # a face at z = 16 (a cell boundary) between two labels
    array[4:36, 4:36, 22:30] = 3      # and one at z = 22 (inside a cell)
    volume = vtksvdag.from_numpy(array, **UNIT.kwargs())
    caster = caster_of(volume)
    worst, detail, count = 0.0, "", 0
    for z, allowed in ((16, (1, 2)), (22, (2, 3))):
        for y in (4.0, 10.5, 16.0, 20.25, 36.0):
            for d in ((1, 0, 0), (-1, 0, 0), (1, 1, 0), (0, -1, 0)):
                d = np.array(d, float) / np.linalg.norm(d)
                o = np.array([20.0, y if y < 36 else 35.5, z]) - 40 * d
                count += 1
                closed_min, _ = brute_force(array, o, d)
                if not caster.CastRay(o, d):
                    error, what = INF, "miss (fell through the face between two solids)"
                else:
                    t = caster.GetHitDistance()
                    error = abs(t - closed_min)
                    what = f"t={t} want {closed_min}, label {hit_value(caster)}"
                    if hit_value(caster) not in allowed:
                        error = INF
                if not error <= worst:
                    worst, detail = error, f"o={tuple(o)} d={tuple(d)}: {what}"
    return result("grazing between two solids", "rays", "rays lying in a face plane between two "
                  f"labels: hit at the volume entry, one of the two labels ({count} rays)",
                  worst, 1e-6, detail=detail)


@case("rays")
def grazing_solid_and_empty():
    array = np.zeros((40, 40, 40), np.uint8)
    array[4:36, 4:36, 8:16] = 5
    rays = []
    for z in (8.0, 16.0):       # the bottom and top faces of the slab: empty on the other side
        for d in ((1, 0, 0), (0, 1, 0), (1, 1, 0), (-1, 2, 0)):
            d = np.array(d, float)
            rays.append((np.array([20.0, 20.5, z]) - 40 * d / np.linalg.norm(d), d))
    for x in (4.0, 36.0):       # the side faces
        rays.append((np.array([x, -5.0, 12.5]), np.array([0.0, 1.0, 0.0])))
        rays.append((np.array([x, 20.5, -5.0]), np.array([0.0, 0.0, 1.0])))
    return rays_result("grazing solid/empty faces", "rays lying in a face with empty space on "
                       "the other side: a miss or a hit on the face, never another label",
                       array, rays)


@case("rays")
def start_inside_solid():
    array = boxes_volume((30, 30, 30), seed=11)
    volume = vtksvdag.from_numpy(array, **UNIT.kwargs())
    caster = caster_of(volume)
    rng = np.random.default_rng(12)
    solid = np.argwhere(array > 0)
    worst, detail = 0.0, ""
    for n in range(60):
        voxel = solid[rng.integers(len(solid))]
        o = voxel + rng.uniform(0.01, 0.99, 3)
        if n % 10 == 0:
            o = voxel + 0.5
        d = rng.normal(size=3)
        if not caster.CastRay(o, d):
            error, what = INF, "miss"
        else:
            normal = np.array(caster.GetHitNormal())
            error = caster.GetHitDistance() + np.abs(normal).sum()
            if hit_value(caster) != array[tuple(voxel)]:
                error = INF
            what = (f"t={caster.GetHitDistance()} normal {tuple(normal)} label "
                    f"{hit_value(caster)} want {array[tuple(voxel)]}")
        if not error <= worst:
            worst, detail = error, f"o={tuple(o)}: {what}"
    return result("start inside a solid voxel", "rays", "60 rays from inside labelled voxels: "
                  "t = 0, zero normal, the voxel's label", worst, 0, detail=detail)


@case("rays")
def gpu_camera_inside_solid():
    array = np.zeros((32, 32, 32), np.uint16)
    array[4:28, 4:28, 4:28] = 9
    array[10:12, 10:30, 10:12] = 4
    volume = vtksvdag.from_numpy(array, **UNIT.kwargs())
    renderer = image_renderer(volume, 24, 16)
    renderer.SetCameraPosition(20.3, 20.7, 20.1)
    renderer.SetCameraFocalPoint(0, 0, 0)
    renderer.SetCameraViewUp(0, 0, 1)
    ok = renderer.Render()
    data = renderer.GetOutput().GetPointData()
    label = vtk_to_numpy(data.GetArray("Label"))
    depth = vtk_to_numpy(data.GetArray("Depth"))
    normal = vtk_to_numpy(data.GetArray("Normal"))
    index9 = int(np.flatnonzero(volume.labels == 9)[0]) + 1
    error = float(np.abs(depth).max() + np.abs(normal).max())
    if not ok or np.any(label != index9):
        error = INF
    return result("GPU camera inside a solid", "rays", "image renderer with the camera inside a "
                  "labelled voxel: every pixel that label, Depth 0, Normal 0", error, 0,
                  detail=f"labels {np.unique(label)} want {index9}, max depth {depth.max()}")


@case("rays")
def camera_1e6_widths_away():
    array = boxes_volume((32, 32, 32), seed=13)
    volume = vtksvdag.from_numpy(array, spacing=(1.0, 1.0, 1.0), origin=(100.0, -50.0, 20.0))
    center = np.array([100.0, -50.0, 20.0]) + 15.5
    distance = 1e6 * 32
    direction = np.array([0.6, -0.48, 0.64])
    direction /= np.linalg.norm(direction)
    angle = math.degrees(2 * math.atan(0.5 * 32 * math.sqrt(3) / distance))

    def camera(r):
        r.SetCameraPosition(*(center + distance * direction))
        r.SetCameraFocalPoint(*center)
        r.SetCameraViewUp(0, 0, 1)
        r.SetCameraViewAngle(angle)

    mismatch, depth_error, hits, detail = gpu_vs_cpu(volume, camera)
    return result("camera 1e6 volume-widths away", "rays", "GPU primary labels = CPU caster's "
                  "with the camera 3.2e7 voxels away (label-mismatch fraction)", mismatch, 0.002,
                  passed=mismatch <= 0.002 and hits > 50,
                  detail=f"{detail}; relative depth error {depth_error:.3g}; view angle {angle:.3g} deg")


@case("rays")
def mapper_clipping_planes():
    array = np.zeros((40, 40, 40), np.uint16)
    array[5:35, 5:35, 5:35] = 3
    array[10:30, 10:30, 10:30] = 0      # a hollow: the near plane (z = 25) cuts through it
    array[12:20, 14:26, 10:20] = 7      # a box in it, between the planes
    volume = vtksvdag.from_numpy(array)  # behind the far plane (z = 15): the hollow's floor
    width, height = 64, 48
    eye, focal = np.array([19.5, 19.5, 120.0]), np.array([19.5, 19.5, 19.5])
    near, far = 95.0, 105.0                     # z = 25 .. 15: both planes inside the volume
    window, renderer, _, mapper = mapper_scene(volume.dataobject, camera_position=eye,
                                               focal=focal, up=(0, 1, 0), clipping=(near, far),
                                               size=(width, height))
    renderer.GetActiveCamera().SetViewAngle(30)
    window.Render()
    caster = caster_of(volume)
    view = (focal - eye) / np.linalg.norm(focal - eye)
    worst, detail, hits, at_near, clipped_far = 0.0, "", 0, 0, 0
    for y in range(1, height, 3):
        for x in range(1, width, 3):
            origin, direction = pixel_ray(renderer, x, y)
            caster.SetMaximumDistance(np.linalg.norm(direction))
            expected = caster_pick(caster, origin, direction)
            caster.SetMaximumDistance(1e300)
            unclipped = caster_pick(caster, origin, direction)
            got = mapper_pick(mapper, renderer, x + 0.5, y + 0.5)
            if expected is None and unclipped is not None:
                clipped_far += 1
            if (expected is None) != (got is None):
                error, what = INF, f"mapper {got} caster {expected}"
            elif got is None:
                continue
            else:
                hits += 1
                depth = float((got[1] - eye) @ view)
                at_near += abs(depth - near) < 1e-3
                error = float(np.linalg.norm(got[1] - expected[1]))
                what = f"mapper {got[:2]} caster {expected[:2]}, view depth {depth}"
                if got[0] != expected[0] or not near - 1e-3 <= depth <= far + 1e-3:
                    error = INF
            if not error <= worst:
                worst, detail = error, f"pixel ({x},{y}): {what}"
    window.Finalize()
    passed = worst <= 1e-3 and hits > 20 and at_near > 5 and clipped_far > 5
    return result("near/far clipping in the mapper", "rays", "vtkRenderWindow, clipping range "
                  "inside the volume: Pick positions between the planes = CPU caster on the "
                  "clipped segment (world distance)", worst, 1e-3, passed,
                  detail=f"{detail}; {hits} hits, {at_near} on the near plane, "
                  f"{clipped_far} cut by the far plane")


# ------------------------------------------------------------------------------------- shading

SHADE_W, SHADE_H = 32, 24
SHADE_VALUES = (1, 2, 3)


@functools.lru_cache(maxsize=None)
def shading_volume():
    array = np.zeros((24, 24, 24), np.uint8)
    array[2:22, 2:22, 2:4] = 1          # a floor
    array[6:13, 6:13, 4:12] = 2         # a box on it
    array[14:20, 13:19, 4:8] = 3        # and a smaller one
    array[15:17, 14:16, 6:8] = 0        # with a cavity opening on top
    return vtksvdag.from_numpy(array)


def shading_renderer(spp=64, bounces=64, environment=1.0, white=True):
    renderer = image_renderer(shading_volume(), SHADE_W, SHADE_H, spp)
    renderer.ResetCamera(30, 25, 1.3)
    settings = renderer.GetSettings()
    settings.SetSeed(1234)
    settings.SetMaximumBounces(bounces)
    settings.SetEnvironmentColor(environment, environment, environment)
    settings.SetBackground(environment, environment, environment, 1)
    if white:
        props = renderer.GetLabelProperties()
        for value in SHADE_VALUES:
            props.SetColor(value, 1, 1, 1)   # display 1 = linear 1
            props.SetSpecular(value, 0)
            props.SetMetallic(value, 0)
    return renderer


def outputs(renderer, passes=1):
    ok = all(renderer.Render() == 1 for _ in range(passes))
    data = renderer.GetOutput().GetPointData()
    hdr = vtk_to_numpy(data.GetArray("HDR")).astype(np.float64)
    label = vtk_to_numpy(data.GetArray("Label"))
    return ok, hdr, label


def bad_values(hdr):
    return int(np.count_nonzero(~np.isfinite(hdr)) + np.count_nonzero(hdr < 0))


def furnace_case(name, material, checked, exact=False, passes=4):
    """White furnace: constant environment 1, background 1, every label white with `material`.
    The error is (mean radiance of the hit pixels) - 1: above the tolerance energy was created
    (exact: |mean - 1|, the Lambertian furnace). NaN/Inf/negative anywhere: inf."""
    renderer = shading_renderer()
    for value in SHADE_VALUES:
        material(renderer.GetLabelProperties(), value)
    ok, hdr, label = outputs(renderer, passes)
    hit = label > 0
    mean = float(hdr[hit, :3].mean()) if hit.any() else math.nan
    error = abs(mean - 1) if exact else mean - 1
    bad = bad_values(hdr)
    if bad or not ok or hit.sum() < 100:
        error = INF
    return result(name, "shading", checked, error, 0.01,
                  detail=f"mean {mean:.5f} over {hit.sum()} hit pixels, {bad} NaN/Inf/negative, "
                  f"max {hdr[:, :3].max():.4g}, {renderer.GetAccumulatedSamples()} spp")


@case("shading")
def furnace_lambertian_64_bounces():
    return furnace_case("white furnace, Lambertian, 64 bounces", lambda p, v: None,
                        "white Lambertian, environment 1, 64 bounces, 256 spp: |mean - 1|",
                        exact=True)


@case("shading")
def furnace_roughness_0():
    return furnace_case("roughness 0", lambda p, v: (p.SetRoughness(v, 0), p.SetSpecular(v, 1)),
                        "white, roughness 0, specular 1 in the furnace: mean - 1 (no energy "
                        "created), no NaN/Inf")


@case("shading")
def furnace_roughness_1():
    return furnace_case("roughness 1", lambda p, v: (p.SetRoughness(v, 1), p.SetSpecular(v, 1)),
                        "white, roughness 1, specular 1 in the furnace: mean - 1, no NaN/Inf")


@case("shading")
def furnace_metallic_1():
    return furnace_case("metallic 1", lambda p, v: (p.SetMetallic(v, 1), p.SetRoughness(v, 0.3)),
                        "white metal, roughness 0.3 in the furnace: mean - 1, no NaN/Inf")


@case("shading")
def furnace_transmission_ior_1():
    return furnace_case("transmission 1, IOR 1.0",
                        lambda p, v: (p.SetTransmission(v, 1), p.SetIOR(v, 1.0)),
                        "white, transmission 1, IOR 1.0 in the furnace: mean - 1, no NaN/Inf")


@case("shading")
def furnace_transmission_ior_3():
    return furnace_case("transmission 1, IOR 3.0",
                        lambda p, v: (p.SetTransmission(v, 1), p.SetIOR(v, 3.0)),
                        "white, transmission 1, IOR 3.0 in the furnace: mean - 1, no NaN/Inf")


@case("shading")
def emission_1e4():
    renderer = shading_renderer(spp=16, environment=0.0)
    props = renderer.GetLabelProperties()
    for value in SHADE_VALUES:
        props.SetColor(value, 0, 0, 0)
    props.SetEmission(2, 1e4, 1e4, 1e4)
    ok, hdr, label = outputs(renderer)
    image = label.reshape(SHADE_H, SHADE_W)
    index2 = int(np.flatnonzero(shading_volume().labels == 2)[0]) + 1
    inner = np.zeros_like(image, bool)
    inner[1:-1, 1:-1] = True
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner &= np.roll(np.roll(image, dy, 0), dx, 1) == index2
    inner = inner.ravel()
    radiance = hdr[inner, :3]
    error = float(np.abs(radiance / 1e4 - 1).max()) if inner.any() else INF
    if bad_values(hdr) or not ok or inner.sum() < 5:
        error = INF
    return result("emission 1e4", "shading", "an emitter of 1e4 among black labels, black "
                  "environment: its inner pixels' radiance / 1e4 - 1, no NaN/Inf", error, 1e-3,
                  detail=f"{inner.sum()} inner pixels, radiance {radiance.min() if inner.any() else '-'}"
                  f"..{radiance.max() if inner.any() else '-'}, {bad_values(hdr)} bad values")


@case("shading")
def black_environment():
    renderer = shading_renderer(spp=16, environment=0.0, white=True)
    ok, hdr, _ = outputs(renderer)
    dark = float(np.abs(hdr[:, :3]).max()) if np.all(np.isfinite(hdr)) else INF
    # With an emitter: the pixels that see nothing stay exactly black; with the denoiser, whose
    # edge antialiasing blends a silhouette's miss pixels with the surface beside them, those
    # whose 8 neighbours see nothing either.
    renderer.GetLabelProperties().SetEmission(3, 50, 50, 50)
    ok2, hdr2, label2 = outputs(renderer)
    miss = label2.reshape(SHADE_H, SHADE_W) == 0
    padded = np.pad(miss, 1, constant_values=True)
    open_miss = miss.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            open_miss &= padded[1 + dy:1 + dy + SHADE_H, 1 + dx:1 + dx + SHADE_W]
    stray = float(np.abs(hdr2[open_miss.reshape(-1), :3]).max()) if open_miss.any() else INF
    renderer.GetSettings().SetDenoise(False)
    ok3, hdr3, label3 = outputs(renderer)
    stray_raw = float(np.abs(hdr3[label3 == 0, :3]).max()) if (label3 == 0).any() else INF
    error = max(dark, stray, stray_raw)
    if not (ok and ok2 and ok3) or bad_values(hdr2) or hdr2[:, :3].max() <= 0:
        error = INF
    return result("black environment", "shading", "environment 0, no sun, no emission: HDR "
                  "exactly 0 everywhere; with an emitter, exactly 0 where the camera misses (the "
                  "denoiser off; on, away from silhouettes)", error, 0,
                  detail=f"max without emission {dark}, on misses with emission {stray_raw} raw, "
                  f"{stray} denoised")


def write_exr(path, rgb):
    """A minimal scanline OpenEXR file (HALF R, G, B, no compression) of an (h, w, 3) array."""
    h, w, _ = rgb.shape

    def attribute(name, kind, value):
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value

    channels = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 1, 0, 1, 1) for c in "BGR") + b"\0"
    box = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = (struct.pack("<ii", 20000630, 2)
              + attribute("channels", "chlist", channels)
              + attribute("compression", "compression", b"\0")
              + attribute("dataWindow", "box2i", box)
              + attribute("displayWindow", "box2i", box)
              + attribute("lineOrder", "lineOrder", b"\0")
              + attribute("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + attribute("screenWindowCenter", "v2f", struct.pack("<ff", 0, 0))
              + attribute("screenWindowWidth", "float", struct.pack("<f", 1.0))
              + b"\0")
    half = rgb.astype("<f2")
    lines = [b"".join(half[y, :, c].tobytes() for c in (2, 1, 0)) for y in range(h)]
    offset = len(header) + 8 * h
    table = b""
    for line in lines:
        table += struct.pack("<Q", offset)
        offset += 8 + len(line)
    body = b"".join(struct.pack("<ii", y, len(line)) + line for y, line in enumerate(lines))
    with open(path, "wb") as f:
        f.write(header + table + body)


@case("shading")
def environment_hot_pixel():
    rgb = np.zeros((8, 16, 3), np.float32)
    rgb[2, 5] = 3e4           # one hot texel (half floats reach 65504)
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "hot.exr")
        write_exr(path, rgb)
        renderer = shading_renderer(spp=32, environment=1.0)  # the map's scale
        renderer.GetSettings().SetBackground(0, 0, 0, 1)
        renderer.GetSettings().SetEnvironmentMap(path)
        ok, hdr, label = outputs(renderer)
    bad = bad_values(hdr)
    lit = float(hdr[label > 0, :3].mean()) if (label > 0).any() else 0.0
    error = INF if not ok else float(bad)
    return result("environment map, one hot pixel", "shading", "equirectangular EXR, all zero "
                  "but one texel of 3e4: no NaN/Inf/negative in HDR, the scene is lit",
                  error, 0, passed=ok and bad == 0 and lit > 0,
                  detail=f"{bad} bad values, mean radiance of hits {lit:.4g}")


@case("shading")
def environment_map_furnace():
    with tempfile.TemporaryDirectory() as folder:
        path = os.path.join(folder, "one.exr")
        write_exr(path, np.ones((8, 16, 3), np.float32))
        renderer = shading_renderer(spp=64)
        renderer.GetSettings().SetEnvironmentMap(path)
        ok, hdr, label = outputs(renderer, 4)
    hit = label > 0
    mean = float(hdr[hit, :3].mean())
    error = abs(mean - 1) if ok and bad_values(hdr) == 0 else INF
    return result("environment map furnace", "shading", "an EXR map of constant 1 (importance "
                  "sampled) on white Lambertian labels, 256 spp: |mean - 1|", error, 0.01,
                  detail=f"mean {mean:.5f} over {hit.sum()} hit pixels")


@case("shading")
def error_estimate_decreases():
    renderer = shading_renderer(spp=4, environment=0.7)
    renderer.GetSettings().SunOn()
    renderer.GetSettings().SetSunIrradiance(3, 3, 3)
    outputs(renderer)
    few = renderer.GetErrorEstimate()
    renderer.GetSettings().SetSamplesPerPixel(60)
    ok, hdr, _ = outputs(renderer)
    many = renderer.GetErrorEstimate()
    samples = renderer.GetAccumulatedSamples()
    ratio = many / few if few > 0 else INF
    # 16x the samples: the standard error of a mean falls 4x (ratio 0.25)
    passed = ok and math.isfinite(few) and math.isfinite(many) and few > 0 and samples == 64 \
        and ratio <= 0.4 and bad_values(hdr) == 0
    return result("error estimate decreases", "shading", "GetErrorEstimate() finite, and after "
                  "16x the samples at most 0.4x (ideal 0.25): the ratio", ratio, 0.4, passed,
                  detail=f"4 spp {few:.4g}, {samples} spp {many:.4g}")


@case("shading")
def russian_roulette_bound():
    renderer = shading_renderer(spp=64, bounces=64)
    ok, hdr, _ = outputs(renderer, 2)
    worst = float(hdr[:, :3].max()) if bad_values(hdr) == 0 else INF
    return result("Russian roulette: no firefly", "shading", "white furnace, 64 bounces, 128 spp: "
                  "no pixel's mean radiance above 1.5 (roulette weights bounded)", worst, 1.5,
                  passed=ok and worst <= 1.5, detail=f"max pixel mean {worst:.4g}")


# --------------------------------------------------------------------------------------- scale


@case("scale")
def several_blas():
    array = boxes_volume((48, 40, 36), seed=14)
    volume = vtksvdag.from_numpy(array)
    images = []
    for limit in (0, 7):
        renderer = image_renderer(volume, 48, 32)
        renderer.GetSettings().SetBackend("rt")  # the BLAS split is the rt backend's
        renderer.GetSettings().SetMaximumBlocksPerBLAS(limit)
        renderer.ResetCamera(25, 30, 1.2)
        ok = renderer.Render()
        data = renderer.GetOutput().GetPointData()
        images.append((ok, renderer.GetNumberOfBLAS(),
                       vtk_to_numpy(data.GetArray("Label")).copy(),
                       vtk_to_numpy(data.GetArray("Depth")).copy()))
    (ok1, n1, label1, depth1), (ok2, n2, label2, depth2) = images
    error = float(np.mean(label1 != label2)) + float(np.mean(depth1 != depth2))
    passed = ok1 and ok2 and n1 == 1 and n2 > 1 and error == 0
    return result("several BLAS", "scale", "MaximumBlocksPerBLAS 7 (several BLAS) vs one BLAS: "
                  "Label and Depth images equal (fraction differing)", error, 0, passed,
                  detail=f"{n1} vs {n2} BLAS")


STREAM_SCRIPT = textwrap.dedent("""
    import json, sys
    import vtksvdag
    from vtksvdag import vtkSVDAGIO  # noqa: F401 (loaded before the baseline)

    def hwm():
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) * 1024

    base = hwm()
    volume = vtksvdag.read(sys.argv[1])
    peak = hwm()
    points = json.loads(sys.argv[2])
    values = [int(volume.label_at(*p)) for p in points]
    print(json.dumps({"growth": peak - base, "base": base, "values": values,
                      "dims": list(volume.dims), "dtype": str(volume.dtype)}))
""")


def stream_pattern(x, y, z):
    return 1 + (x // 64) + 8 * (y // 64) + 64 * (z // 64) + ((x + 2 * y + 3 * z) % 7 == 0) * 1000


@case("scale")
def streamed_nrrd_read():
    n = 512
    dense = n ** 3 * 2                       # 256 MiB of uint16
    y, x = np.mgrid[0:n, 0:n]
    rng = np.random.default_rng(15)
    points = [[int(v) for v in p] for p in rng.integers(0, n, (12, 3))] + [[0, 0, 0], [511, 511, 511]]
    with tempfile.TemporaryDirectory(dir=os.environ.get("VTKSVDAG_TMP")) as folder:
        path = os.path.join(folder, "big.nrrd")
        with open(path, "wb") as f:
            f.write(f"NRRD0004\ntype: uint16\ndimension: 3\nsizes: {n} {n} {n}\n"
                    "endian: little\nencoding: raw\n\n".encode())
            for z in range(n):                  # slab by slab: never the whole volume here
                f.write(stream_pattern(x, y, z).astype("<u2").tobytes())
        completed = subprocess.run([sys.executable, "-c", STREAM_SCRIPT, path, json.dumps(points)],
                                   capture_output=True, text=True, timeout=600, cwd=REPO)
    if completed.returncode != 0:
        return result("streamed 256 MiB NRRD", "scale", "read in a subprocess", INF, 0.5,
                      detail=completed.stderr[-500:])
    out = json.loads(completed.stdout.strip().splitlines()[-1])
    expected = [int(stream_pattern(*p)) for p in points]
    ratio = out["growth"] / dense
    passed = ratio < 0.5 and out["values"] == expected and out["dims"] == [n, n, n] \
        and out["dtype"] == "uint16"
    return result("streamed 256 MiB NRRD", "scale", "512^3 uint16 raw NRRD read by vtksvdag.read "
                  "in a subprocess: peak RSS growth / dense size (< 0.5), label_at = pattern",
                  ratio, 0.5, passed,
                  detail=f"growth {out['growth'] / 2**20:.1f} MiB of {dense / 2**20:.0f} MiB dense; "
                  f"values {'equal' if out['values'] == expected else out['values']} "
                  f"{'' if out['values'] == expected else expected}")


@case("scale", large=True)
def dag_over_128_mib():
    """About 1024^3 random binary voxels: random 4^3 leaves do not deduplicate, so the DAG
    buffer passes 128 MiB (lavapipe's descriptor range: reads past it would return zeros)."""
    n = 1024
    rng = np.random.default_rng(16)
    array = np.empty((n, n, n), np.uint8)
    for z in range(0, n, 64):
        array[:, :, z:z + 64] = rng.integers(0, 2, size=(n, n, 64), dtype=np.uint8)
    volume = vtksvdag.from_numpy(array)
    del array
    stats = volume.stats()
    dag_bytes = stats.get("bytes_dag", 0) if isinstance(stats, dict) else 0
    renderer = image_renderer(volume, 48, 48)
    renderer.ResetCamera(30, 20, 1.5)
    ok = renderer.Render()
    data = renderer.GetOutput().GetPointData()
    gpu_label = vtk_to_numpy(data.GetArray("Label")).astype(np.int64)
    caster = caster_of(volume)
    origin, dirs = primary_rays(renderer)
    pixels = np.random.default_rng(17).choice(len(dirs), 300, replace=False)
    wrong = 0
    for n_ in pixels:
        cpu = caster.GetHitLabelIndex() + 1 if caster.CastRay(origin, dirs[n_]) else 0
        wrong += cpu != gpu_label[n_]
    error = wrong / len(pixels)
    return result("DAG buffer over 128 MiB", "scale", "1024^3 random voxels (DAG > 128 MiB): GPU "
                  "labels at 300 sampled pixels = CPU caster (mismatch fraction)", error, 0.002,
                  passed=ok and error <= 0.002 and dag_bytes > 128 * 2**20,
                  detail=f"DAG {dag_bytes / 2**20:.1f} MiB, {wrong} of {len(pixels)} differ")


def run_case(function):
    """Runs one case; an exception is a failed result naming it."""
    try:
        return function()
    except Exception as error:  # noqa: BLE001 (reported as the case's failure)
        return result(function.case_name, function.group, "raised", INF, 0, False,
                      detail=f"{type(error).__name__}: {error}")
