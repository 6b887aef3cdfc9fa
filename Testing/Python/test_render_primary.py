"""vtkSegmentationSVDAGRenderer (Vulkan ray tracing, primary hits) against the CPU ray caster.

Runs on whatever ray-tracing device the machine has (lavapipe here). For several random camera
views of a random volume and of a real segmentation, at every LOD, the renderer's Label and Depth
outputs must equal those of vtkSegmentationSVDAGRayCaster for the same rays. The rays follow the
renderer's documented pixel-center convention (GpuLayout.h, vtkSegmentationSVDAGRenderer.h):
pixel (x, y), y = 0 the bottom row, at index x + width * y, with direction
normalize(F + u * tan(a/2) * aspect * R + v * tan(a/2) * U), u = 2 (x + 0.5) / width - 1,
v = 2 (y + 0.5) / height - 1. They are generated here in double precision, independently.

Pixels whose ray passes within float rounding of a voxel edge or corner may legitimately see
another label, so labels must agree on >= 99.9% of the pixels, and depths to 1e-4 (relative)
where both hit the same label.
"""
import gc
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import nrrd
import numpy as np
import pytest
from conftest import capture_errors, compress_zyx as build, primary_rays
from vtkmodules.util.numpy_support import vtk_to_numpy

from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGRayCaster
from vtksvdag.vtkSVDAGRendering import (vtkSegmentationSVDAGRenderer,
                                        vtkSegmentationSVDAGRenderSettings)

WIDTH, HEIGHT = 64, 48
LODS = (
    vtkSegmentationSVDAGRenderSettings.LOD_BLOCK,
    vtkSegmentationSVDAGRenderSettings.LOD_LEAF,
    vtkSegmentationSVDAGRenderSettings.LOD_VOXEL,
)
DEPTH_MISS = np.float32(3.402823466e38)


def rotation(rng):
    """A random proper rotation matrix."""
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


@pytest.fixture(scope="module")
def random_volume():
    rng = np.random.default_rng(2024)
    shape = (21, 37, 29)  # z, y, x: odd sizes, cells cut by the volume's border
    labels = rng.integers(1, 9, size=shape).astype(np.uint16)
    labels[rng.random(shape) < 0.8] = 0  # sparse: rays travel through the blocks
    labels[:, :, 20:] = 0
    labels[3:9, 5:30, 2:12] = 7  # one solid box: full octants and complemented leaves
    return labels, build(labels, spacing=(0.7, 1.0, 1.3), origin=(5.0, -3.0, 10.0),
                         direction=rotation(rng))


@pytest.fixture(scope="module")
def far_volume(random_volume):
    """The random labels far from the world origin: float precision on the GPU must not depend on
    where the volume is (the renderer shifts world coordinates to the volume in double)."""
    labels = random_volume[0]
    return labels, build(labels, spacing=(0.7, 1.0, 1.3), origin=(2.0e5, -3.5e5, 1.25e5))


@pytest.fixture(scope="module")
def real_labels(shared_data):
    labels, _ = nrrd.read(str(shared_data / "plantseg_1135_mini.nrrd"), index_order="C")
    return labels


@pytest.fixture(scope="module")
def real_volume(real_labels):
    return real_labels, build(real_labels, spacing=(1.0, 0.9, 1.2), origin=(-50.0, 0.0, 20.0))


def lod_boxes(labels, lod):
    """Index-space boxes (lo, hi exclusive, x y z) and label values of what a coarse LOD hits:
    per 16^3 cell and label, the tight box of the label's voxels (LOD_BLOCK), or each non-empty
    4^3 leaf of that block clipped to the box (LOD_LEAF). Built from the label array alone."""
    los, his, values = [], [], []
    for cz in range(0, labels.shape[0], 16):
        for cy in range(0, labels.shape[1], 16):
            for cx in range(0, labels.shape[2], 16):
                cell = labels[cz:cz + 16, cy:cy + 16, cx:cx + 16]
                corner = np.array([cx, cy, cz])
                for value in np.unique(cell[cell != 0]):
                    z, y, x = np.nonzero(cell == value)
                    xyz = np.stack([x, y, z], axis=1)
                    block_lo, block_hi = xyz.min(axis=0), xyz.max(axis=0) + 1
                    if lod == vtkSegmentationSVDAGRenderSettings.LOD_BLOCK:
                        boxes = [(block_lo, block_hi)]
                    else:
                        leaves = np.unique(xyz // 4, axis=0) * 4
                        boxes = [(np.maximum(leaf, block_lo), np.minimum(leaf + 4, block_hi))
                                 for leaf in leaves]
                    for lo, hi in boxes:
                        los.append(corner + lo)
                        his.append(corner + hi)
                        values.append(value)
    return np.array(los, float), np.array(his, float), np.array(values, np.int64)


def to_index_space(volume, origin, dirs):
    """World rays -> index space (world = origin + D diag(spacing) (p - 0.5)); t is unchanged."""
    direction, spacing, volume_origin = [0.0] * 9, [0.0] * 3, [0.0] * 3
    volume.GetDirection(direction)
    volume.GetSpacing(spacing)
    volume.GetOrigin(volume_origin)
    m_inv = np.linalg.inv(np.reshape(direction, (3, 3)) @ np.diag(spacing))
    return m_inv @ (origin - np.array(volume_origin)) + 0.5, dirs @ m_inv.T


def valid_coarse_labels(labels, volume, origin, dirs, lod):
    """Per ray, the label values whose box (lod_boxes) the ray enters first: overlapping boxes of
    different labels in one cell tie, and then any of them is a right answer."""
    lo, hi, values = lod_boxes(labels, lod)
    o, d = to_index_space(volume, origin, dirs)
    with np.errstate(divide="ignore", invalid="ignore"):
        t0 = (lo[None, :, :] - o[None, None, :]) / d[:, None, :]
        t1 = (hi[None, :, :] - o[None, None, :]) / d[:, None, :]
    enter = np.maximum(np.nanmax(np.minimum(t0, t1), axis=2), 0)
    leave = np.nanmin(np.maximum(t0, t1), axis=2)
    hit = enter <= leave
    enter = np.where(hit, enter, np.inf)
    nearest = enter.min(axis=1)
    tied = hit & (enter <= nearest[:, None] + 1e-4 * (1 + nearest[:, None]))
    return [set(values[row]) for row in tied]


def cpu_reference(volume, renderer, lod):
    """Label (index + 1, 0 = miss), depth and world normal per pixel from the CPU ray caster."""
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(volume)
    caster.SetLOD(lod)
    origin, dirs = primary_rays(renderer)
    labels = np.zeros(len(dirs), np.int64)
    depth = np.full(len(dirs), np.inf)
    normals = np.zeros((len(dirs), 3))
    for i, d in enumerate(dirs):
        if caster.CastRay(origin, d):
            labels[i] = caster.GetHitLabelIndex() + 1
            depth[i] = caster.GetHitDistance()
            normals[i] = caster.GetHitNormal()
    return labels, depth, normals


def outputs(renderer):
    data = renderer.GetOutput().GetPointData()
    return (vtk_to_numpy(data.GetArray("Label")).astype(np.int64),
            vtk_to_numpy(data.GetArray("Depth")).astype(np.float64))


# Both backends: the ray tracing pipeline and the compute cell-grid walk trace the same hits.
BACKENDS = ["rt", "compute"]


def make_renderer(volume, backend="auto"):
    renderer = vtkSegmentationSVDAGRenderer()
    renderer.GetSettings().SetBackend(backend)
    renderer.SetInputData(volume)
    renderer.SetWidth(WIDTH)
    renderer.SetHeight(HEIGHT)
    return renderer


def world_point(volume, p):
    """World position of index-space point p (world = origin + D diag(spacing) (p - 0.5))."""
    direction, spacing, origin = [0.0] * 9, [0.0] * 3, [0.0] * 3
    volume.GetDirection(direction)
    volume.GetSpacing(spacing)
    volume.GetOrigin(origin)
    return np.array(origin) + np.reshape(direction, (3, 3)) @ (np.array(spacing) * (p - 0.5))


def random_views(rng, labels, volume):
    """Camera setups (description, function that sets the renderer's camera): orbits around
    the volume; one zoomed in so far that the camera is inside the volume (in the real volume,
    inside a labelled voxel: every ray hits at distance 0); and one from the center of an empty voxel inside the volume, looking at a
    random point (rays start among the blocks, inside cells)."""
    views = []
    for _ in range(2):
        azimuth, elevation, zoom = rng.uniform(-180, 180), rng.uniform(-80, 80), rng.uniform(0.9, 2.5)
        views.append((f"orbit ({azimuth:.0f}, {elevation:.0f}, {zoom:.1f})",
                      lambda r, a=azimuth, e=elevation, z=zoom: r.ResetCamera(a, e, z)))
    views.append(("zoomed into the volume", lambda r: r.ResetCamera(-155, -44, 6.0)))
    inner = labels[2:-2, 2:-2, 2:-2]
    z, y, x = np.argwhere(inner == 0)[rng.integers(np.count_nonzero(inner == 0))] + 2
    eye = world_point(volume, np.array([x, y, z]) + 0.5)
    target = world_point(volume, rng.uniform(0, 1, 3) * labels.shape[::-1])

    def inside(renderer):
        renderer.SetCameraPosition(*eye)
        renderer.SetCameraFocalPoint(*target)
        renderer.SetCameraViewUp(0.0, 0.0, 1.0)
        renderer.SetCameraViewAngle(60.0)
        return 1
    views.append(("camera in an empty voxel inside the volume", inside))
    return views


def assert_matches_cpu(labels, volume, renderer, lod, what):
    """Voxel LOD: the labels must agree. Block and leaf LOD: boxes of different labels overlap
    inside a cell, so where several are entered at the same distance the label is any of them
    (checked against an independent brute force over the boxes); hit/miss and depth must agree."""
    renderer.GetSettings().SetLOD(lod)
    assert renderer.Render() == 1
    gpu_label, gpu_depth = outputs(renderer)
    gpu_normal = vtk_to_numpy(renderer.GetOutput().GetPointData().GetArray("Normal"))
    cpu_label, cpu_depth, cpu_normal = cpu_reference(volume, renderer, lod)
    if lod == vtkSegmentationSVDAGRenderSettings.LOD_VOXEL:
        same = gpu_label == cpu_label
    else:
        table = vtk_to_numpy(volume.NewLabelValues()).astype(np.int64)
        origin, dirs = primary_rays(renderer)
        allowed = valid_coarse_labels(labels, volume, origin, dirs, lod)
        same = np.array([
            (g == 0 and not ok) if c == 0 else (g > 0 and table[g - 1] in ok and c > 0)
            for g, c, ok in zip(gpu_label, cpu_label, allowed)]) & ((gpu_label > 0) == (cpu_label > 0))
    agreement = same.mean()
    assert agreement >= 0.999, (
        f"{what} LOD {lod}: labels agree on {agreement:.4%} of the pixels "
        f"(gpu {gpu_label[~same][:8]}, cpu {cpu_label[~same][:8]})")
    both = same & (cpu_label > 0)
    assert np.allclose(gpu_depth[both], cpu_depth[both], rtol=1e-4, atol=1e-5), (
        f"{what} LOD {lod}: depth differs, max relative error "
        f"{np.max(np.abs(gpu_depth[both] - cpu_depth[both]) / np.maximum(cpu_depth[both], 1e-9)):.3g}")
    # The entry face's world normal (zero where the ray starts inside); a ray through an edge
    # may enter by either face, so again 99.9% of the pixels.
    normal_agreement = np.all(np.abs(gpu_normal[both] - cpu_normal[both]) < 1e-4, axis=1).mean()
    assert not both.any() or normal_agreement >= 0.999, f"{what} LOD {lod}: normals agree on {normal_agreement:.4%}"
    # Misses carry the documented far value, never inf or NaN.
    assert np.all(gpu_depth[gpu_label == 0] == DEPTH_MISS)
    assert np.all(np.isfinite(gpu_depth))
    return gpu_label, cpu_label


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("which", ["random_volume", "real_volume", "far_volume"])
def test_primary_hits_match_cpu_ray_caster(which, backend, request):
    labels, volume = request.getfixturevalue(which)
    renderer = make_renderer(volume, backend)
    rng = np.random.default_rng({"random_volume": 7, "real_volume": 11, "far_volume": 13}[which])
    hits = 0
    views = random_views(rng, labels, volume)
    for description, set_camera in views:
        assert set_camera(renderer) == 1
        for lod in LODS:
            gpu_label, _ = assert_matches_cpu(labels, volume, renderer, lod,
                                              f"{which}, {backend}, {description}:")
            assert renderer.GetBackendInUse() == backend
            hits += np.count_nonzero(gpu_label)
    # The views must actually see the volume (a test of empty images would prove nothing).
    assert hits > 0.2 * len(views) * len(LODS) * WIDTH * HEIGHT


def test_outputs_are_consistent(real_volume):
    renderer = make_renderer(real_volume[1])
    renderer.ResetCamera(30, 20, 1.2)
    assert renderer.Render() == 1
    out = renderer.GetOutput()
    assert out.GetDimensions() == (WIDTH, HEIGHT, 1)
    data = out.GetPointData()
    label = vtk_to_numpy(data.GetArray("Label"))
    normal = vtk_to_numpy(data.GetArray("Normal"))
    hdr = vtk_to_numpy(data.GetArray("HDR"))
    color = vtk_to_numpy(data.GetArray("Color"))
    assert color.shape == (WIDTH * HEIGHT, 4) and hdr.shape == (WIDTH * HEIGHT, 4)
    hit = label > 0
    assert hit.any() and (~hit).any()
    # Unit normals on hits (the camera is outside), zero normals on misses.
    assert np.allclose(np.linalg.norm(normal[hit], axis=1), 1, atol=1e-5)
    assert np.all(normal[~hit] == 0)
    # Background where nothing is hit (path-traced samples are jittered inside the pixel, so only
    # misses whose neighbours' center rays also miss); the color output is the documented tone
    # curve x / (1 + x) of exposure * HDR, sRGB-encoded.
    grid = np.pad(hit.reshape(HEIGHT, WIDTH), 1)
    near_hit = np.zeros((HEIGHT, WIDTH), bool)
    for dy in range(3):
        for dx in range(3):
            near_hit |= grid[dy:dy + HEIGHT, dx:dx + WIDTH]
    far_miss = ~near_hit.ravel()
    assert far_miss.any()
    background = [0.0] * 4
    renderer.GetSettings().GetBackground(background)
    assert np.allclose(hdr[far_miss], background, atol=1e-6)
    x = hdr[:, :3] * renderer.GetSettings().GetExposure()
    mapped = x / (1 + x)
    srgb = np.where(mapped <= 0.0031308, 12.92 * mapped, 1.055 * mapped ** (1 / 2.4) - 0.055)
    assert np.max(np.abs(np.round(np.clip(srgb, 0, 1) * 255) - color[:, :3])) <= 1
    assert np.all(color[hit, 3] == 255)
    assert np.all(np.isfinite(hdr)) and np.all(np.isfinite(normal))
    # Deterministic: the same frame twice (a new accumulation, the same seed) gives the same bytes.
    first = {name: vtk_to_numpy(data.GetArray(name)).copy()
             for name in ("Color", "HDR", "Depth", "Label", "Normal")}
    renderer.ResetAccumulation()
    assert renderer.Render() == 1
    data = renderer.GetOutput().GetPointData()
    for name, values in first.items():
        assert np.array_equal(vtk_to_numpy(data.GetArray(name)), values), name
    # The backend's structure: a BVH (rt), or the cell grid and no BVH (compute).
    assert renderer.GetBackendInUse() in ("rt", "compute")
    if renderer.GetBackendInUse() == "rt":
        assert renderer.GetBLASBytes() > 0 and renderer.GetTLASBytes() > 0
    else:
        assert renderer.GetBLASBytes() == 0 and renderer.GetTLASBytes() == 0
    assert renderer.GetAccelerationBytes() > 0 and renderer.GetEncodingBytes() > 0
    assert renderer.GetDeviceBytes() >= (renderer.GetEncodingBytes() + renderer.GetAccelerationBytes()
                                         + renderer.GetMaterialBytes() + renderer.GetImageBytes())
    # 20 floats or words a pixel, and the denoiser's working images (on by default): two RGBA
    # and two guide records of 16 bytes, and the edge coverage record of 96.
    assert renderer.GetSettings().GetDenoise()
    assert renderer.GetImageBytes() == WIDTH * HEIGHT * (80 + 64 + 96)
    assert renderer.GetSetupSeconds() > 0 and renderer.GetLastFrameMilliseconds() > 0
    assert renderer.GetDeviceName() != ""


@pytest.mark.parametrize("backend", BACKENDS)
def test_auto_lod_chooses_per_ray(real_volume, backend):
    """AUTO with a huge pixel budget draws blocks everywhere, with a tiny one voxels everywhere,
    and in between each pixel shows what one of the fixed levels shows."""
    renderer = make_renderer(real_volume[1], backend)
    renderer.ResetCamera(-40, 25, 1.0)
    fixed = {}
    for lod in LODS:
        renderer.GetSettings().SetLOD(lod)
        assert renderer.Render() == 1
        fixed[lod] = outputs(renderer)
    renderer.GetSettings().SetLOD(vtkSegmentationSVDAGRenderSettings.LOD_AUTO)
    for pixels, expected in ((1e6, vtkSegmentationSVDAGRenderSettings.LOD_BLOCK),
                             (1e-6, vtkSegmentationSVDAGRenderSettings.LOD_VOXEL)):
        renderer.GetSettings().SetAutoLODPixels(pixels)
        assert renderer.Render() == 1
        label, depth = outputs(renderer)
        assert np.array_equal(label, fixed[expected][0])
        assert np.array_equal(depth, fixed[expected][1])
    renderer.GetSettings().SetAutoLODPixels(4.0)  # 64x48 pixels: leaves and blocks at some distances
    assert renderer.Render() == 1
    label, _ = outputs(renderer)
    some_level = np.zeros(len(label), bool)
    for lod in LODS:
        some_level |= label == fixed[lod][0]
    assert some_level.mean() >= 0.999


@pytest.mark.parametrize("backend", BACKENDS)
def test_hidden_labels_vanish(real_volume, backend):
    labels, volume = real_volume
    renderer = make_renderer(volume, backend)
    renderer.ResetCamera(10, 30, 1.3)
    assert renderer.Render() == 1
    label, _ = outputs(renderer)
    visible, counts = np.unique(label[label > 0], return_counts=True)
    hidden = visible[np.argsort(counts)[-3:]] - 1  # the three largest on screen
    values = vtk_to_numpy(volume.NewLabelValues()).astype(np.int64)  # index -> label value
    for index in hidden:
        renderer.GetLabelProperties().SetVisibility(int(values[index]), False)
    assert renderer.Render() == 1
    label_hidden, depth_hidden = outputs(renderer)
    assert not np.isin(label_hidden - 1, hidden).any()
    # The pixels they covered now show what lies behind them: exactly the image of a volume
    # built without those labels (compared by label value, the label tables differ).
    without = build(labels, spacing=(1.0, 0.9, 1.2), origin=(-50.0, 0.0, 20.0),
                    excluded=values[hidden])
    reference = make_renderer(without, backend)
    for name in ("CameraPosition", "CameraFocalPoint", "CameraViewUp"):
        getattr(reference, "Set" + name)(getattr(renderer, "Get" + name)())
    assert reference.Render() == 1
    ref_label, ref_depth = outputs(reference)
    ref_values = vtk_to_numpy(without.NewLabelValues()).astype(np.int64)
    as_value = lambda lab, table: np.where(lab > 0, table[np.maximum(lab - 1, 0)], -1)
    assert np.array_equal(as_value(label_hidden, values), as_value(ref_label, ref_values))
    assert np.array_equal(depth_hidden, ref_depth)
    renderer.GetLabelProperties().ShowAllLabels()
    assert renderer.Render() == 1
    assert np.array_equal(outputs(renderer)[0], label)


MISSING_DEVICE_SCRIPT = """
import json, sys
import numpy as np
from conftest import capture_errors, compress_zyx
from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGRenderer
labels = np.zeros((8, 8, 8), np.uint8)
labels[2:6, 2:6, 2:6] = 3
renderer = vtkSegmentationSVDAGRenderer()
renderer.SetInputData(compress_zyx(labels))
renderer.SetWidth(8)
renderer.SetHeight(8)
messages = capture_errors(renderer)
print(json.dumps({"status": renderer.Render(), "messages": messages}))
"""


def test_forced_missing_device_is_a_clear_error(real_volume):
    working = make_renderer(real_volume[1])
    assert working.Render() == 1
    device = working.GetDeviceName()
    # The process's one device is chosen when its first user comes, so the variable is forced in a
    # fresh process (this one may still hold the device for other tests' objects).
    env = dict(os.environ, SVDAG_VK_DEVICE="nonexistent")
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [str(Path(__file__).parent),
                                                      env.get("PYTHONPATH")]))
    child = subprocess.run([sys.executable, "-c", MISSING_DEVICE_SCRIPT], env=env,
                           capture_output=True, text=True, timeout=300)
    assert child.returncode == 0, child.stderr
    result = json.loads(child.stdout.strip().splitlines()[-1])
    assert result["status"] == 0
    assert len(result["messages"]) == 1, result["messages"]
    message = result["messages"][0]
    assert "SVDAG_VK_DEVICE='nonexistent'" in message
    # It names every device found, so also the one a normal run picks.
    assert "devices found" in message and device in message


def test_a_volume_over_the_device_memory_limit_is_a_clear_error(real_volume):
    svdag = real_volume[1]
    renderer = make_renderer(svdag)
    renderer.GetSettings().SetDeviceMemoryLimit(4096)
    messages = capture_errors(renderer)
    assert renderer.Render() == 0
    assert len(messages) == 1, messages
    match = re.search(r"needs (\d+) bytes of device memory, but (\d+) bytes are available", messages[0])
    assert match, messages[0]
    assert int(match.group(1)) > 4096 >= int(match.group(2))
    assert "a limit of 4096 bytes" in messages[0]
    # Lifting the limit renders.
    renderer.GetSettings().SetDeviceMemoryLimit(0)
    assert renderer.Render() == 1
    assert renderer.GetSettings().GetDeviceMemoryLimit() == 0


def test_render_without_input_is_an_error():
    renderer = vtkSegmentationSVDAGRenderer()
    messages = capture_errors(renderer)
    assert renderer.Render() == 0
    assert messages and "input" in messages[0]


def test_split_into_several_blas_gives_the_same_image(real_volume):
    """Volumes beyond the device's BLAS primitive limit are split into several BLAS (one TLAS
    instance each); capping the blocks per BLAS forces that path on a small volume."""
    renderer = make_renderer(real_volume[1])
    renderer.GetSettings().SetBackend("rt")
    renderer.ResetCamera(70, -20, 1.4)
    assert renderer.Render() == 1
    assert renderer.GetNumberOfBLAS() == 1
    single = outputs(renderer)
    renderer.GetSettings().SetMaximumBlocksPerBLAS(37)  # not a divisor of the block count: a short last BLAS
    assert renderer.Render() == 1
    blocks = real_volume[1].GetNumberOfBlocks()
    assert renderer.GetNumberOfBLAS() == -(-blocks // 37)
    split = outputs(renderer)
    assert np.array_equal(single[0], split[0])
    assert np.array_equal(single[1], split[1])


def test_all_labels_hidden_is_an_empty_image(random_volume):
    labels, volume = random_volume
    renderer = make_renderer(volume)
    renderer.ResetCamera(0, 0, 1)
    for value in vtk_to_numpy(volume.NewLabelValues()):
        renderer.GetLabelProperties().SetVisibility(int(value), False)
    assert renderer.Render() == 1
    label, depth = outputs(renderer)
    assert np.all(label == 0) and np.all(depth == DEPTH_MISS)
    assert renderer.GetNumberOfBLAS() == 0


def cli_path():
    import vtksvdag.vtkSVDAGRendering as module
    import pathlib
    # <build>/python/vtksvdag/vtkSVDAGRendering*.so -> <build>/bin/vtksvdag-render
    path = pathlib.Path(module.__file__).resolve().parents[2] / "bin" / "vtksvdag-render"
    assert path.is_file(), f"the command line renderer was not built: {path}"
    return path


def test_command_line_renders_a_file(real_volume, tmp_path):
    import json

    from PIL import Image
    from vtksvdag.vtkSVDAGIO import vtkSegmentationSVDAGWriter

    svdag_file = tmp_path / "plant.svdag"
    writer = vtkSegmentationSVDAGWriter()
    writer.SetInputData(real_volume[1])
    writer.SetFileName(str(svdag_file))
    assert writer.Write() == 1
    png, exr = tmp_path / "plant.png", tmp_path / "plant.exr"
    run = subprocess.run([str(cli_path()), str(svdag_file), str(png), "--width", "40",
                          "--height", "30", "--lod", "leaf", "--azimuth", "15"],
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    report = json.loads(run.stdout)
    assert report["width"] == 40 and report["height"] == 30 and report["lod"] == "leaf"
    assert report["backend"] in ("rt", "compute") and report["device"]
    assert (report["bytes_blas"] > 0) == (report["backend"] == "rt")
    parts = report["bytes_device"]
    assert parts["encoding"] > 0 and parts["acceleration"] > 0
    # with the denoiser's working images and edge coverage records
    assert parts["images"] == 40 * 30 * (80 + 64 + 96)
    assert parts["total"] == sum(v for k, v in parts.items() if k != "total")
    assert report["setup_seconds"] > 0 and report["ms_per_frame"] > 0
    image = np.asarray(Image.open(png))
    assert image.shape == (30, 40, 4)
    # The same view through the VTK class: the PNG holds the Color output, rows top first.
    renderer = vtkSegmentationSVDAGRenderer()
    renderer.SetInputData(real_volume[1])
    renderer.SetWidth(40)
    renderer.SetHeight(30)
    renderer.GetSettings().SetLOD(vtkSegmentationSVDAGRenderSettings.LOD_LEAF)
    renderer.ResetCamera(15, 20, 1)  # the command line's default elevation is 20
    assert renderer.Render() == 1
    color = vtk_to_numpy(renderer.GetOutput().GetPointData().GetArray("Color"))
    assert np.array_equal(image[::-1].reshape(-1, 4), color)

    run = subprocess.run([str(cli_path()), str(svdag_file), str(exr), "--width", "8",
                          "--height", "8"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert exr.read_bytes()[:4] == b"\x76\x2f\x31\x01"  # OpenEXR magic

    bad = subprocess.run([str(cli_path()), str(svdag_file), str(png), "--lod", "fine"],
                         capture_output=True, text=True, timeout=60)
    assert bad.returncode == 1 and "unknown LOD" in bad.stderr
    corrupt = tmp_path / "corrupt.svdag"
    corrupt.write_bytes(svdag_file.read_bytes()[:100])
    failed = subprocess.run([str(cli_path()), str(corrupt), str(png)],
                            capture_output=True, text=True, timeout=60)
    assert failed.returncode == 2 and "vtksvdag-render:" in failed.stderr


def test_command_line_shading_and_clipping_options(real_volume, tmp_path):
    """--shading and --clip (repeatable) of vtksvdag-render give the VTK class's frame with the
    same settings; a malformed plane is a usage error."""
    from PIL import Image
    from vtkmodules.vtkCommonDataModel import vtkPlane
    from vtksvdag.vtkSVDAGIO import vtkSegmentationSVDAGWriter

    volume = real_volume[1]
    svdag_file = tmp_path / "plant.svdag"
    writer = vtkSegmentationSVDAGWriter()
    writer.SetInputData(volume)
    writer.SetFileName(str(svdag_file))
    assert writer.Write() == 1
    # The fixture's grid: spacing (1.0, 0.9, 1.2), origin (-50, 0, 20), labels in (z, y, x).
    dims = real_volume[0].shape[::-1]
    center = [o + s * (n - 1) / 2 for o, s, n in zip((-50.0, 0.0, 20.0), (1.0, 0.9, 1.2), dims)]
    planes = [(center, (1.0, 0.2, 0.0)), (center, (0.0, -1.0, 0.5))]
    png = tmp_path / "clipped.png"
    command = [str(cli_path()), str(svdag_file), str(png), "--width", "40", "--height", "30",
               "--lod", "voxel", "--shading", "smooth"]
    for origin, normal in planes:
        command += ["--clip", ",".join(str(v) for v in (*origin, *normal))]
    run = subprocess.run(command, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    renderer = vtkSegmentationSVDAGRenderer()
    renderer.SetInputData(volume)
    renderer.SetWidth(40)
    renderer.SetHeight(30)
    settings = renderer.GetSettings()
    settings.SetLOD(vtkSegmentationSVDAGRenderSettings.LOD_VOXEL)
    settings.SetShading(vtkSegmentationSVDAGRenderSettings.SHADING_SMOOTH)
    for origin, normal in planes:
        plane = vtkPlane()
        plane.SetOrigin(*origin)
        plane.SetNormal(*normal)
        renderer.AddClippingPlane(plane)
    renderer.ResetCamera(30, 20, 1)  # the command line's default view
    assert renderer.Render() == 1
    color = vtk_to_numpy(renderer.GetOutput().GetPointData().GetArray("Color"))
    label = vtk_to_numpy(renderer.GetOutput().GetPointData().GetArray("Label")).copy()
    assert 0 < np.count_nonzero(label) < label.size
    image = np.asarray(Image.open(png))
    assert np.array_equal(image[::-1].reshape(-1, 4), color)
    renderer.RemoveAllClippingPlanes()
    assert renderer.Render() == 1
    unclipped = vtk_to_numpy(renderer.GetOutput().GetPointData().GetArray("Label"))
    assert np.count_nonzero(label) < np.count_nonzero(unclipped)  # the planes cut some away

    for bad, message in ((["--clip", "1,2,3"], "--clip needs OX,OY,OZ,NX,NY,NZ"),
                         (["--shading", "phong"], "phong")):
        failed = subprocess.run([str(cli_path()), str(svdag_file), str(png), *bad],
                                capture_output=True, text=True, timeout=60)
        assert failed.returncode == 1 and message in failed.stderr, failed.stderr


def test_degenerate_camera_is_an_error(real_volume):
    renderer = make_renderer(real_volume[1])
    messages = capture_errors(renderer)
    renderer.SetCameraPosition(1.0, 2.0, 3.0)
    renderer.SetCameraFocalPoint(1.0, 2.0, 3.0)
    assert renderer.Render() == 0
    assert "focal point" in messages[-1]
    renderer.SetCameraFocalPoint(1.0, 2.0, 10.0)
    renderer.SetCameraViewUp(0.0, 0.0, 1.0)  # parallel to the view direction
    assert renderer.Render() == 0
    assert "view up" in messages[-1]
    renderer.SetCameraViewUp(0.0, 1.0, 0.0)
    assert renderer.Render() == 1


def test_empty_and_single_voxel_volumes():
    empty = build(np.zeros((5, 6, 7), np.uint8))
    renderer = make_renderer(empty)
    assert renderer.Render() == 1  # the camera was never set: Render frames the volume
    label, depth = outputs(renderer)
    assert np.all(label == 0) and np.all(depth == DEPTH_MISS)
    one = np.full((1, 1, 1), 3, np.uint8)
    single = build(one, spacing=(2.0, 3.0, 0.5))
    renderer.SetInputData(single)
    renderer.ResetCamera(20, 30, 1.5)
    for lod in LODS:
        label, _ = assert_matches_cpu(one, single, renderer, lod, "single voxel")
        assert np.count_nonzero(label) > WIDTH * HEIGHT // 10


def test_renderer_is_a_pipeline_algorithm():
    """Connected to vtkImageDataToSegmentationSVDAG by SetInputConnection, Update() renders; a
    different label image upstream re-executes the renderer (its Label output follows, checked
    against the CPU ray caster); SetInputData works as well."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG

    def label_image(labels):
        image = vtkImageData()
        image.SetDimensions(labels.shape[2], labels.shape[1], labels.shape[0])
        image.GetPointData().SetScalars(numpy_to_vtk(labels.ravel(), deep=True))
        return image

    first = np.zeros((12, 12, 12), np.uint8)
    first[3:9, 3:9, 3:9] = 4  # one cube of value 4
    second = np.zeros_like(first)
    second[2:10, 2:10, 1:6] = 2  # two boxes of values 2 and 6, larger than the cube
    second[2:10, 2:10, 6:11] = 6

    builder = vtkImageDataToSegmentationSVDAG()
    builder.SetInputData(label_image(first))
    renderer = vtkSegmentationSVDAGRenderer()
    renderer.SetInputConnection(builder.GetOutputPort())
    renderer.SetWidth(WIDTH)
    renderer.SetHeight(HEIGHT)
    assert renderer.ResetCamera(25, 30, 1.0) == 1  # updates the builder to frame its volume
    renderer.Update()
    out = renderer.GetOutput()
    assert out.GetDimensions() == (WIDTH, HEIGHT, 1)
    assert renderer.GetAccumulatedSamples() == 1
    renderer.Update()  # nothing changed: no new pass
    assert renderer.GetAccumulatedSamples() == 1
    assert renderer.GetInput() is builder.GetOutput()

    def check(labels, expected_values):
        volume = builder.GetOutput()
        gpu_label, _ = outputs(renderer)
        cpu_label, _, _ = cpu_reference(volume, renderer, vtkSegmentationSVDAGRenderSettings.LOD_VOXEL)
        assert (gpu_label == cpu_label).mean() >= 0.999
        table = vtk_to_numpy(volume.NewLabelValues()).astype(np.int64)
        assert set(table[np.unique(gpu_label[gpu_label > 0]) - 1]) == expected_values
        return gpu_label

    before = check(first, {4})
    builder.SetInputData(label_image(second))
    renderer.Update()  # re-executes: the builder's output changed
    assert renderer.GetAccumulatedSamples() == 1  # a new volume, a new accumulation
    after = check(second, {2, 6})
    assert np.count_nonzero(after) > np.count_nonzero(before)
    renderer.Update()
    assert renderer.GetAccumulatedSamples() == 1
    # A settings change re-executes too, and so does Render() (one more pass).
    renderer.GetSettings().SetSamplesPerPixel(2)
    renderer.Update()
    assert renderer.GetAccumulatedSamples() == 3
    assert renderer.Render() == 1
    assert renderer.GetAccumulatedSamples() == 5

    # SetInputData: the same volume gives the same Label image.
    direct = vtkSegmentationSVDAGRenderer()
    direct.SetInputData(build(second))
    direct.SetWidth(WIDTH)
    direct.SetHeight(HEIGHT)
    for name in ("CameraPosition", "CameraFocalPoint", "CameraViewUp"):
        getattr(direct, "Set" + name)(getattr(renderer, "Get" + name)())
    direct.Update()
    assert np.array_equal(outputs(direct)[0], after)
