"""vtkSegmentationSVDAGVolumeMapper and its pyvista glue (vtksvdag.add_segmentation/refine/pick).

The independent reference for picking is the CPU ray caster (vtkSegmentationSVDAGRayCaster),
fed the world ray through each pixel center as VTK's own DisplayToWorld computes it; depth is
checked against VTK's depth buffer and against renders of a mesh alone and the volume alone.
Small volumes and 200x150 windows keep the file fast on lavapipe.
"""
import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL factory overrides)
from conftest import mapper_scene, REPO, tilted_slab, two_boxes, caster_pick, interior, compress_zyx, display_to_world, mapper_pick, pixel_ray
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonMath import vtkMatrix4x4
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGRayCaster
from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper

W, H = 200, 150
DEPTH_STEP = 1.0 / (1 << 24)



def make_scene(svdag, **options):
    return mapper_scene(svdag, **{"size": (W, H), **options})


def compare_picks(mapper, renderer, svdag_reference, step=5, to_world=None, position_tol=1e-3):
    """Fraction of grid pixels where the mapper's pick and the ray caster agree; and the hits."""
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(svdag_reference)
    total = agree = hits = 0
    labels_seen = set()
    disagreements = []
    for y in range(step // 2, H, step):
        for x in range(step // 2, W, step):
            origin, direction = pixel_ray(renderer, x, y)
            expected = caster_pick(caster, origin, direction, to_world)
            got = mapper_pick(mapper, renderer, x + 0.5, y + 0.5)
            total += 1
            if got is not None:
                labels_seen.add(got[0])
            if expected is None or got is None:
                ok = expected is None and got is None
            else:
                hits += 1
                ok = (expected[0] == got[0]
                      and np.linalg.norm(expected[1] - got[1]) <= position_tol
                      and np.allclose(expected[2], got[2], atol=1e-5))
            agree += ok
            if not ok and len(disagreements) < 5:
                disagreements.append(((x, y), expected, got))
    return agree / total, hits, labels_seen, disagreements


def zbuffer(window):
    data = vtkFloatArray()
    window.GetZbufferData(0, 0, W - 1, H - 1, data)
    return vtk_to_numpy(data).reshape(H, W).astype(np.float64)


def rgb(window):
    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.SetInputBufferTypeToRGB()
    grab.ReadFrontBufferOff()
    grab.Update()
    image = grab.GetOutput()
    return vtk_to_numpy(image.GetPointData().GetScalars()).reshape(H, W, -1)[:, :, :3].astype(int)


@pytest.fixture(scope="module")
def boxes():
    labels = two_boxes()
    return labels, compress_zyx(labels)


# 1 ---------------------------------------------------------------------------------------------
def test_pick_matches_ray_caster(boxes):
    labels, svdag = boxes
    window, renderer, _, mapper = make_scene(svdag)
    window.Render()
    assert mapper.GetDeviceName() != ""
    fraction, hits, seen, bad = compare_picks(mapper, renderer, svdag, step=4)
    assert fraction >= 0.99, bad
    assert hits > 200
    assert seen == {3, 7}
    # Outside the viewport and in the background: no hit.
    assert not mapper.Pick(renderer, -5.0, 10.0)
    assert not mapper.Pick(renderer, W + 3.0, 10.0)
    assert not mapper.Pick(renderer, 0.5, 0.5)


def test_pick_uses_pixel_center(boxes):
    _, svdag = boxes
    window, renderer, _, mapper = make_scene(svdag)
    window.Render()
    center = mapper_pick(mapper, renderer, 100.5, 75.5)
    corner = mapper_pick(mapper, renderer, 100.02, 75.97)
    assert center is not None and corner is not None
    assert center[0] == corner[0]
    np.testing.assert_array_equal(center[1], corner[1])


# 2 ---------------------------------------------------------------------------------------------
def test_depth_written_matches_pick(boxes):
    _, svdag = boxes
    window, renderer, _, mapper = make_scene(svdag)
    assert mapper.GetWriteDepth()
    window.Render()
    depth = zbuffer(window)
    checked = 0
    for x, y in [(100, 75), (80, 60), (120, 90), (60, 80), (140, 70)]:
        hit = mapper_pick(mapper, renderer, x + 0.5, y + 0.5)
        if hit is None:
            assert depth[y, x] == 1.0
            continue
        assert depth[y, x] < 1.0
        world = display_to_world(renderer, x + 0.5, y + 0.5, depth[y, x])
        assert np.linalg.norm(world - hit[1]) <= 1e-2, (x, y, world, hit[1])
        checked += 1
    assert checked >= 3
    # Misses leave the cleared depth.
    assert depth[2, 2] == 1.0

    mapper.WriteDepthOff()
    window.Render()
    assert mapper.Pick(renderer, 100.5, 75.5)  # still traced
    depth = zbuffer(window)
    assert np.all(depth == 1.0)


def test_depth_written_on_every_hit_pixel(boxes):
    """After a single-sample frame, every pixel whose pick hits has depth < 1, and vice versa."""
    _, svdag = boxes
    window, renderer, _, mapper = make_scene(svdag)
    window.Render()
    assert mapper.GetAccumulatedSamples() == 1
    depth = zbuffer(window)
    mismatches = [(x, y, depth[y, x]) for y in range(H) for x in range(W)
                  if mapper.Pick(renderer, x + 0.5, y + 0.5) != (depth[y, x] < 1.0)]
    assert not mismatches, f"{len(mismatches)} pixels, e.g. (x, y, depth) {mismatches[:4]}"


# 3 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("spp", [1, 16])
@pytest.mark.parametrize("msaa", [0, 8])
def test_depth_compositing_with_mesh(boxes, msaa, spp):
    """Composited depth == min(mesh alone, volume alone) within one depth step, every pixel."""
    _, svdag = boxes
    window, renderer, volume, mapper = make_scene(svdag)
    window.SetMultiSamples(msaa)
    mapper.SetTargetSamplesPerPixel(spp)
    props = mapper.GetLabelProperties()
    props.SetColor(3, 1.0, 0.0, 0.0)
    props.SetColor(7, 0.0, 0.0, 1.0)
    # A slab through the middle of the volume, tilted with respect to the voxel faces.
    actor = tilted_slab()
    renderer.AddActor(actor)

    volume.SetVisibility(0)
    window.Render()
    mesh_depth = zbuffer(window)
    volume.SetVisibility(1)
    actor.SetVisibility(0)
    mapper.RenderUntilConverged(window, 30.0)
    assert mapper.GetAccumulatedSamples() == spp
    volume_depth = zbuffer(window)
    actor.SetVisibility(1)
    mapper.RenderUntilConverged(window, 30.0)
    assert mapper.GetAccumulatedSamples() == spp
    depth = zbuffer(window)
    color = rgb(window)

    expected = np.minimum(mesh_depth, volume_depth)
    error = np.abs(depth - expected)
    worst = np.unravel_index(np.argmax(error), error.shape)
    largest = float(error.max())
    wrong = int((error > DEPTH_STEP * 1.01).sum())
    assert largest <= DEPTH_STEP * 1.01, (
        f"{wrong} pixels off; max |depth - min(mesh, volume)| = {largest / DEPTH_STEP:.0f} steps at "
        f"(y, x) = {tuple(int(i) for i in worst)}: composite {depth[worst]}, mesh "
        f"{mesh_depth[worst]}, volume {volume_depth[worst]}")
    both = (mesh_depth < 1.0) & (volume_depth < 1.0)
    mesh_front = both & (mesh_depth < volume_depth - 1e-4)
    volume_front = both & (volume_depth < mesh_depth - 1e-4)
    assert mesh_front.sum() > 100 and volume_front.sum() > 100

    front = interior(mesh_front)
    assert front.sum() > 50
    green = (color[:, :, 0] <= 2) & (color[:, :, 1] >= 253) & (color[:, :, 2] <= 2)
    assert green[front].all(), np.argwhere(front & ~green)[:5]
    behind = interior(volume_front)
    assert behind.sum() > 50
    assert not green[behind].any()


# 4 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("backend", ["rt", "compute"])
def test_hidden_label_and_opacity_zero(boxes, backend):
    labels, svdag = boxes
    without7 = labels.copy()
    without7[without7 == 7] = 0
    reference = compress_zyx(without7)

    window, renderer, _, mapper = make_scene(svdag)
    mapper.GetSettings().SetBackend(backend)
    window.Render()
    assert mapper.GetBackendInUse() == backend
    builds = mapper.GetNumberOfBVHBuilds()
    rebuild = 1 if backend == "rt" else 0  # compute: hidden labels are bits
    assert builds == rebuild
    props = mapper.GetLabelProperties()
    props.SetVisibility(7, False)
    assert not props.GetVisibility(7)
    window.Render()
    assert mapper.GetNumberOfBVHBuilds() == builds + rebuild
    fraction, hits, seen, bad = compare_picks(mapper, renderer, reference, step=6)
    assert 7 not in seen
    assert fraction >= 0.99, bad
    assert hits > 50

    props.SetColor(3, 0.2, 0.9, 0.4)
    window.Render()
    assert mapper.GetNumberOfBVHBuilds() == builds + rebuild

    # Opacity 0 hides like visibility.
    window2, renderer2, _, mapper2 = make_scene(svdag)
    mapper2.GetLabelProperties().SetOpacity(7, 0.0)
    window2.Render()
    fraction, hits, seen, bad = compare_picks(mapper2, renderer2, reference, step=6)
    assert 7 not in seen
    assert fraction >= 0.99, bad


# 5 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("parallel", [False, True])
def test_pick_with_volume_matrix(boxes, parallel):
    _, svdag = boxes
    window, renderer, volume, mapper = make_scene(
        svdag, camera_position=(90, -70, 100), focal=(15, 25, 25), parallel=parallel,
        clipping=(10.0, 400.0))
    volume.SetPosition(5.0, -3.0, 2.0)
    volume.SetScale(1.25, 0.8, 1.1)
    volume.RotateZ(25.0)
    user = vtkMatrix4x4()
    user.Identity()
    user.SetElement(2, 3, 4.0)  # a translation along z from the user matrix
    volume.SetUserMatrix(user)
    window.Render()
    matrix = vtkMatrix4x4()
    volume.GetMatrix(matrix)
    to_world = np.array([[matrix.GetElement(i, j) for j in range(4)] for i in range(4)])
    assert abs(to_world[2, 3] - 2.0) > 1.0  # the user matrix is part of it
    fraction, hits, seen, bad = compare_picks(mapper, renderer, svdag, step=5, to_world=to_world,
                                              position_tol=2e-3)
    assert fraction >= 0.99, bad
    assert hits > 100
    assert seen == {3, 7}


# 6 ---------------------------------------------------------------------------------------------
def test_progressive_refinement(boxes):
    _, svdag = boxes
    window, renderer, _, mapper = make_scene(svdag)
    mapper.SetTargetSamplesPerPixel(8)
    assert mapper.GetTargetSamplesPerPixel() == 8
    window.Render()
    assert mapper.GetAccumulatedSamples() == 1
    assert not mapper.IsConverged()
    window.Render()
    assert mapper.GetAccumulatedSamples() == 2
    error2 = mapper.GetErrorEstimate()
    assert error2 > 0
    renders = mapper.RenderUntilConverged(window, 30.0)
    assert renders >= 1
    assert mapper.GetAccumulatedSamples() == 8
    assert mapper.IsConverged()
    error8 = mapper.GetErrorEstimate()
    assert 0 < error8 < error2
    window.Render()
    assert mapper.GetAccumulatedSamples() == 8
    assert mapper.IsConverged()
    renderer.GetActiveCamera().Azimuth(10.0)
    window.Render()
    assert mapper.GetAccumulatedSamples() == 1
    assert not mapper.IsConverged()


# 7 ---------------------------------------------------------------------------------------------
def test_time_budget():
    n = 64
    labels = np.zeros((n, n, n), np.uint16)
    labels[4:60, 6:58, 5:59] = 2
    labels[20:40, 10:50, 20:40] = 9
    svdag = compress_zyx(labels)
    window, renderer, volume, mapper = make_scene(
        svdag, camera_position=(130, -90, 140), focal=(32, 32, 32), clipping=(20.0, 500.0))
    assert mapper.GetAutoAdjustToRenderTime()
    mapper.GetSettings().SetLODToVoxel()  # a fixed LOD for the budget to coarsen (default: auto)
    mapper.GetSettings().SetMaximumBounces(8)
    window.SetDesiredUpdateRate(1000.0)
    window.Render()  # a first frame measures the cost
    camera = renderer.GetActiveCamera()
    camera.Azimuth(5.0)
    window.Render()
    assert volume.GetAllocatedRenderTime() < 0.01
    assert mapper.GetLastReductionFactor() > 1 or mapper.GetLastLOD() < 2, (
        mapper.GetLastReductionFactor(), mapper.GetLastLOD(), mapper.GetLastTraceMilliseconds())
    assert not mapper.IsConverged()

    window.SetDesiredUpdateRate(0.0001)
    camera.Azimuth(5.0)
    window.Render()
    assert mapper.GetLastReductionFactor() == 1
    assert mapper.GetLastLOD() == 2  # the settings' LOD (voxel)

    # Off: full quality whatever the budget.
    mapper.AutoAdjustToRenderTimeOff()
    window.SetDesiredUpdateRate(1000.0)
    camera.Azimuth(5.0)
    window.Render()
    assert mapper.GetLastReductionFactor() == 1
    assert mapper.GetLastLOD() == 2


# 8 ---------------------------------------------------------------------------------------------
def xyz_boxes():
    """[x, y, z] labels for pyvista: a big label 7 box around the center and a label 3 slab."""
    labels = np.zeros((32, 32, 32), np.uint8)
    labels[6:26, 6:26, 6:26] = 7
    labels[0:4, 0:32, 0:32] = 3
    return labels


def test_pyvista_add_refine_pick():
    import pyvista as pv

    import vtksvdag

    plotter = pv.Plotter(off_screen=True, window_size=(W, H))
    try:
        actor = vtksvdag.add_segmentation(plotter, xyz_boxes(), colors={7: "red"}, sun=True, spp=4)
        assert isinstance(actor, pv.Volume)
        mapper = actor.GetMapper()
        assert isinstance(mapper, vtkSegmentationSVDAGVolumeMapper)
        color = [0.0] * 3
        assert mapper.GetLabelProperties().GetColor(7, color)
        np.testing.assert_allclose(color, (1, 0, 0))
        assert mapper.GetSettings().GetSun()
        assert mapper.GetTargetSamplesPerPixel() == 4
        stats = vtksvdag.refine(plotter)
        assert isinstance(stats, list) and len(stats) == 1
        assert stats[0]["samples"] == 4
        assert stats[0]["converged"] is True
        hit = vtksvdag.pick(plotter, W / 2, H / 2)
        assert hit is not None
        assert type(hit["label"]) is int and hit["label"] == 7
        assert len(hit["position"]) == 3 and len(hit["normal"]) == 3
        assert abs(np.linalg.norm(hit["normal"]) - 1) < 1e-6
        assert vtksvdag.pick(plotter, 1, 1) is None
    finally:
        plotter.close()


@pytest.mark.parametrize("options, error", [
    ({"lod": "fine"}, ValueError),
    ({"spp": 0}, ValueError),
    ({"opacity": 2}, ValueError),
    ({"no_such_option": 1}, TypeError),
    ({"hidden_labels": [999]}, ValueError),
])
def test_pyvista_bad_options(options, error):
    import pyvista as pv

    import vtksvdag

    plotter = pv.Plotter(off_screen=True, window_size=(W, H))
    try:
        with pytest.raises(error):
            vtksvdag.add_segmentation(plotter, xyz_boxes(), **options)
        assert plotter.renderer.GetVolumes().GetNumberOfItems() == 0
    finally:
        plotter.close()


def test_pyvista_inputs(tmp_path):
    import nrrd
    import pyvista as pv

    import vtksvdag

    labels = np.zeros((24, 24, 24), np.uint16)
    labels[4:20, 4:20, 4:20] = 9
    path = tmp_path / "box.nrrd"
    nrrd.write(str(path), labels)  # [x, y, z]
    image = pv.ImageData(dimensions=labels.shape)
    image.point_data["labels"] = (labels * 2).ravel(order="F")  # label 18
    cells, _ = nrrd.read(str(REPO / "examples" / "data" / "cells.nrrd"))
    cell_labels = set(np.unique(cells).tolist()) - {0}

    for data, expected in [(str(path), {9}), (path, {9}), (image, {18}),
                           (str(REPO / "examples" / "data" / "cells.nrrd"), cell_labels)]:
        plotter = pv.Plotter(off_screen=True, window_size=(W, H))
        try:
            vtksvdag.add_segmentation(plotter, data, spp=1)
            stats = vtksvdag.refine(plotter)
            assert stats[0]["samples"] == 1
            hits = [vtksvdag.pick(plotter, x, y) for x, y in
                    [(W / 2, H / 2), (W / 2 + 7, H / 2 - 5), (W / 2 - 9, H / 2 + 4)]]
            hits = [h for h in hits if h is not None]
            assert hits, data
            assert {h["label"] for h in hits} <= expected, (data, hits)
            assert vtksvdag.pick(plotter, 1, 1) is None
        finally:
            plotter.close()


@pytest.mark.parametrize("reset_camera", [None, True])
def test_pyvista_subplots(reset_camera):
    """Default reset_camera: the segmentation is each subplot's first 3D actor."""
    import pyvista as pv

    import vtksvdag

    left = np.zeros((24, 24, 24), np.uint8)
    left[3:21, 3:21, 3:21] = 3
    right = np.zeros((24, 24, 24), np.uint8)
    right[3:21, 3:21, 3:21] = 5
    plotter = pv.Plotter(off_screen=True, shape=(1, 2), window_size=(2 * W, H))
    try:
        plotter.subplot(0, 0)
        vtksvdag.add_segmentation(plotter, left, spp=1, reset_camera=reset_camera)
        plotter.subplot(0, 1)
        vtksvdag.add_segmentation(plotter, right, spp=1, reset_camera=reset_camera)
        stats = vtksvdag.refine(plotter)
        assert len(stats) == 2 and all(s["samples"] == 1 for s in stats)
        left_hit = vtksvdag.pick(plotter, W / 2, H / 2)
        right_hit = vtksvdag.pick(plotter, W + W / 2, H / 2)
        assert left_hit is not None and left_hit["label"] == 3, left_hit
        assert right_hit is not None and right_hit["label"] == 5, right_hit
        assert vtksvdag.pick(plotter, 2, 2) is None
        assert vtksvdag.pick(plotter, W + 2, 2) is None
    finally:
        plotter.close()


# 9 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("dtype, value", [(np.int64, -5), (np.uint64, 2**63 + 3)])
def test_extreme_label_values(dtype, value):
    import pyvista as pv

    import vtksvdag

    labels = np.zeros((20, 20, 20), dtype)
    labels[3:17, 3:17, 3:17] = value
    labels[0:2, :, :] = 1
    plotter = pv.Plotter(off_screen=True, window_size=(W, H))
    try:
        actor = vtksvdag.add_segmentation(plotter, labels, colors={value: "blue"}, spp=1)
        vtksvdag.refine(plotter)
        hit = vtksvdag.pick(plotter, W / 2, H / 2)
        assert hit is not None
        assert type(hit["label"]) is int
        assert hit["label"] == value
        mapper = actor.GetMapper()
        expected_key = int(np.array(value, dtype=dtype).view(np.int64))
        assert mapper.GetPickedLabel() == expected_key
        color = [0.0] * 3
        assert mapper.GetLabelProperties().GetColor(expected_key, color)
        np.testing.assert_allclose(color, (0, 0, 1))
    finally:
        plotter.close()


# 10 --------------------------------------------------------------------------------------------
def test_missing_device_raises():
    script = textwrap.dedent("""
        import numpy as np
        import pyvista as pv
        import vtksvdag
        labels = np.zeros((8, 8, 8), np.uint8)
        labels[2:6, 2:6, 2:6] = 1
        plotter = pv.Plotter(off_screen=True, window_size=(64, 48))
        try:
            vtksvdag.add_segmentation(plotter, labels)
        except RuntimeError as error:
            print("RUNTIME-ERROR:", error)
        else:
            print("NO-ERROR")
        finally:
            plotter.close()
    """)
    env = dict(os.environ, SVDAG_VK_DEVICE="no-such-device")
    result = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                            text=True, timeout=60, cwd=str(REPO))
    assert result.returncode == 0, result.stderr
    assert "RUNTIME-ERROR:" in result.stdout, (result.stdout, result.stderr)
    message = result.stdout.split("RUNTIME-ERROR:", 1)[1]
    assert "no-such-device" in message


# Pipeline, bounds, resizes, graphics resources -------------------------------------------------
def test_pipeline_input_follows_upstream_changes():
    """Connected to the builder filter, the mapper re-renders what the filter's input becomes."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData

    from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG

    labels = two_boxes()
    image = vtkImageData()
    image.SetDimensions(labels.shape[2], labels.shape[1], labels.shape[0])
    image.GetPointData().SetScalars(numpy_to_vtk(labels.ravel(), deep=True))
    builder = vtkImageDataToSegmentationSVDAG()
    builder.SetInputData(image)
    window, renderer, volume, mapper = make_scene(None)
    mapper.SetInputConnection(builder.GetOutputPort())
    window.Render()
    assert mapper.GetInput() is not None
    assert np.allclose(volume.GetBounds(), [-0.5, 39.5] * 3)
    hits = {mapper_pick(mapper, renderer, x, y)[0] for y in range(0, H, 10) for x in range(0, W, 10)
            if mapper_pick(mapper, renderer, x, y) is not None}
    assert hits == {3, 7}
    # Relabel upstream: 7 becomes 9; the next render shows it without touching the mapper.
    changed = np.where(labels == 7, 9, labels).astype(np.uint16)
    image.GetPointData().SetScalars(numpy_to_vtk(changed.ravel(), deep=True))
    image.Modified()
    window.Render()
    hits = {mapper_pick(mapper, renderer, x, y)[0] for y in range(0, H, 10) for x in range(0, W, 10)
            if mapper_pick(mapper, renderer, x, y) is not None}
    assert hits == {3, 9}
    assert mapper.GetAccumulatedSamples() == 1  # a new volume restarts the accumulation


def test_reader_connection_and_bounds():
    """The reader's output through SetInputConnection; bounds as the image's voxel boxes."""
    from vtksvdag.vtkSVDAGIO import vtkSegmentationVolumeReader

    reader = vtkSegmentationVolumeReader()
    reader.SetFileName(str(REPO / "examples" / "data" / "cells.nrrd"))
    window, renderer, volume, mapper = make_scene(None)
    mapper.SetInputConnection(reader.GetOutputPort())
    bounds = mapper.GetBounds()  # updates the pipeline
    svdag = mapper.GetInput()
    dims, spacing, origin = [0] * 3, [0.0] * 3, [0.0] * 3
    svdag.GetDimensions(dims)
    svdag.GetSpacing(spacing)
    svdag.GetOrigin(origin)
    expected = []
    for a in range(3):
        expected += [origin[a] - 0.5 * spacing[a], origin[a] + (dims[a] - 0.5) * spacing[a]]
    assert np.allclose(bounds, expected)
    renderer.ResetCamera()
    window.Render()
    assert mapper.Pick(renderer, W / 2, H / 2)


def test_window_resize_and_release(boxes):
    """A resized window is traced at its new size; released graphics resources come back."""
    _, svdag = boxes
    window, renderer, volume, mapper = make_scene(svdag)
    window.Render()
    before = mapper_pick(mapper, renderer, W / 2, H / 2)
    window.SetSize(2 * W, 2 * H)
    window.Render()
    after = mapper_pick(mapper, renderer, W, H)  # the same view point, at twice the size
    assert before is not None and after is not None
    assert before[0] == after[0]
    assert np.allclose(before[1], after[1], atol=1.0)
    # Every pixel of the new size is traced: the far corner pixels pick like the ray caster.
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(svdag)
    for x, y in ((2 * W - 1, 2 * H - 1), (3, 5), (W + 17, H - 9)):
        expected = caster_pick(caster, *pixel_ray(renderer, x, y))
        got = mapper_pick(mapper, renderer, x + 0.5, y + 0.5)
        assert (expected is None) == (got is None)
    volume.ReleaseGraphicsResources(window)
    renderer.ReleaseGraphicsResources(window)
    window.Render()
    assert mapper_pick(mapper, renderer, W, H)[0] == after[0]


# Backends -----------------------------------------------------------------------------------------
def test_backend_setting_names_and_errors(boxes):
    """Backend is one setting for the renderer, the mapper and pyvista: names, clamped ints, a
    clear error for a wrong name; pyvista's backend= reaches the mapper, which reports what
    runs, and both backends draw the same picks."""
    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGRenderSettings as S

    settings = S()
    assert settings.GetBackend() == S.BACKEND_AUTO and settings.GetBackendAsString() == "auto"
    settings.SetBackend("compute")
    assert settings.GetBackend() == S.BACKEND_COMPUTE
    from conftest import capture_errors

    messages = capture_errors(settings)
    settings.SetBackend("optix")
    assert settings.GetBackendAsString() == "compute"  # unchanged, reported
    assert len(messages) == 1 and "unknown backend 'optix' (auto, rt or compute)" in messages[0]
    settings.SetBackend(9)  # ints clamp, like the other enumerations
    assert settings.GetBackend() == S.BACKEND_COMPUTE
    settings.SetBackendToRT()
    assert settings.GetBackendAsString() == "rt"

    import pyvista as pv

    import vtksvdag

    labels, _ = boxes
    picks = {}
    for backend in ("rt", "compute"):
        plotter = pv.Plotter(off_screen=True, window_size=(96, 80))
        try:
            actor = vtksvdag.add_segmentation(plotter, labels, spp=1, lod="voxel", backend=backend)
            vtksvdag.refine(plotter)
            mapper = actor.GetMapper()
            assert mapper.GetBackendInUse() == backend
            assert (mapper.GetAccelerationBytes() > 0 and mapper.GetEncodingBytes() > 0
                    and mapper.GetDeviceBytes() > mapper.GetEncodingBytes())
            renderer = plotter.renderer
            picks[backend] = [mapper.GetPickedLabel() if mapper.Pick(renderer, x, y) else None
                              for x in range(2, 96, 4) for y in range(2, 80, 4)]
        finally:
            plotter.close()
    agree = np.mean([a == b for a, b in zip(picks["rt"], picks["compute"])])
    assert agree >= 0.97 and sum(p is not None for p in picks["rt"]) > 50

    plotter = pv.Plotter(off_screen=True, window_size=(32, 32))
    try:
        with pytest.raises(ValueError, match="backend must be one of"):
            vtksvdag.add_segmentation(plotter, np.ones((4, 4, 4), np.uint8), backend="optix")
    finally:
        plotter.close()
    result = subprocess.run([sys.executable, "-m", "vtksvdag", "render", "x.nrrd", "-o", "x.png",
                             "--backend", "optix"], capture_output=True, text=True, cwd=REPO)
    assert result.returncode == 2 and "--backend" in result.stderr and "compute" in result.stderr
