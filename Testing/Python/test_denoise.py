"""The label-aware denoiser (DenoiseLayout.h): it never carries one label's radiance into another
pixel's inside, it reduces the noise of a one-sample frame against an independent many-sample
reference, it antialiases label edges from their sub-pixel coverage (GpuLayout.h) and gives way
to the accumulated mean as samples accumulate, and `denoise` reaches it from every layer (VTK
settings, add_segmentation, both command lines)."""
import json
import pathlib
import subprocess
import sys

import numpy as np
import pytest

import vtksvdag
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtksvdag.vtkSVDAGRendering import (vtkSegmentationSVDAGRenderer,
                                         vtkSegmentationSVDAGRenderSettings)

SIZE = 64


@pytest.fixture(scope="module")
def two_boxes():
    """Two touching boxes: label 1 pure red, label 2 pure blue (no specular, direct light only),
    so that a pixel inside label 1 has no blue at all unless blue radiance reached it."""
    labels = np.zeros((28, 24, 20), np.uint8)
    labels[2:14, 2:22, 2:18] = 1
    labels[14:26, 2:22, 2:18] = 2
    return vtksvdag.from_numpy(labels)


def renderer(volume, denoise, seed=5, size=SIZE, colors=((1.0, 0.0, 0.0), (0.0, 0.0, 1.0)),
             sun=True, sky=0.3, camera=(35, 25, 1.0)):
    """Labels 1, 2, ... diffuse in `colors`, a disk sun (or none) and a constant sky, one bounce."""
    r = vtkSegmentationSVDAGRenderer()
    r.SetInputData(volume.dataobject)
    r.SetWidth(size)
    r.SetHeight(size)
    props = r.GetLabelProperties()
    for label, color in enumerate(colors, start=1):
        props.SetColor(label, *color)
        props.SetSpecular(label, 0.0)
        props.SetMetallic(label, 0.0)
    s = r.GetSettings()
    s.SetLOD("voxel")
    s.SetMaximumBounces(1)
    s.SetSeed(seed)
    s.SetDenoise(denoise)
    if sun:
        s.SunOn()
        s.SetSunDirection(0.4, 0.3, 0.85)
        s.SetSunAngularRadius(10.0)
    else:
        s.SunOff()
    s.SetEnvironmentColor(sky, sky, sky)
    assert r.ResetCamera(*camera)
    return r


def output(r, name):
    return vtk_to_numpy(r.GetOutput().GetPointData().GetArray(name)).copy()


def render_to(r, samples):
    while r.GetAccumulatedSamples() < samples:
        assert r.Render() == 1
    return output(r, "HDR")[:, :3].astype(np.float64)


def inside(label_image, label):
    """Pixels of `label` whose 8 neighbours are all `label` (the denoiser's non-edge pixels)."""
    img = label_image.reshape(SIZE, SIZE)
    ok = img == label
    padded = np.pad(img, 1, constant_values=-1)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            ok &= padded[1 + dy:1 + dy + SIZE, 1 + dx:1 + dx + SIZE] == label
    return ok.reshape(-1)


def test_no_radiance_crosses_labels_and_noise_falls(two_boxes):
    raw, denoised = renderer(two_boxes, False), renderer(two_boxes, True)
    raw1, den1 = render_to(raw, 1), render_to(denoised, 1)
    label = output(raw, "Label")
    assert np.array_equal(label, output(denoised, "Label"))
    # Label index + 1 of values 1 and 2 (the label table is sorted).
    red, blue = 1, 2
    red_in, blue_in = inside(label, red), inside(label, blue)
    assert red_in.sum() > 200 and blue_in.sum() > 200
    # The raw samples inside each label carry none of the other's color; the denoised ones
    # neither, although the filter spans up to 33 pixels across the shared edge.
    assert np.all(raw1[red_in, 2] == 0) and np.all(raw1[blue_in, 0] == 0)
    assert np.all(den1[red_in, 2] == 0), "blue radiance reached the inside of the red label"
    assert np.all(den1[blue_in, 0] == 0), "red radiance reached the inside of the blue label"
    # Against an independent reference (the raw path tracer, 512 samples, another seed): inside
    # the labels the denoised frame is much closer than the raw one (measured 0.11x); on edge
    # pixels, whose one-sample error is mostly the missing antialiasing, the coverage of their
    # sub-pixels makes it much closer too (measured 0.18x), and closer than 16 raw samples.
    reference = render_to(renderer(two_boxes, False, seed=11), 512)
    edge = ~(red_in | blue_in | (label == 0))
    edge |= (label == 0) & ~inside(label, 0)

    def error(image, mask):
        return np.sqrt(np.mean((image[mask] - reference[mask]) ** 2))

    assert error(den1, red_in | blue_in) < 0.6 * error(raw1, red_in | blue_in)
    raw16 = render_to(renderer(two_boxes, False), 16)
    assert error(den1, edge) < 0.5 * error(raw1, edge)
    assert error(den1, edge) < error(raw16, edge)
    # Pixels with both boxes among their 8 neighbours and themselves: one raw sample (through
    # the pixel center) shows one box's color, the denoised edge blends both.
    near = {}
    for value in (red, blue):
        padded = np.pad(label.reshape(SIZE, SIZE) == value, 1)
        near[value] = np.zeros((SIZE, SIZE), bool)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                near[value] |= padded[1 + dy:1 + dy + SIZE, 1 + dx:1 + dx + SIZE]
    between = (near[red] & near[blue]).reshape(-1) & (label != 0)
    assert between.sum() > 20
    assert not np.any((raw1[:, 0] > 0) & (raw1[:, 2] > 0) & between)
    # Where the reference blends them (each box's share at least 1/8 of its inside's mean), the
    # denoised frame does too, and where it does not, neither does the frame.
    def blends(image):
        shares = [image[:, c] / reference[inside_, c].mean()
                  for c, inside_ in ((0, red_in), (2, blue_in))]
        return ((shares[0] > 0.125) & (shares[1] > 0.125))[between]

    assert blends(reference).mean() > 0.2
    assert np.mean(blends(den1) == blends(reference)) > 0.9
    # The color output is the denoised HDR tone-mapped (the same encoding as the trace's).
    x = den1 / (1 + den1)
    srgb = np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)
    color = output(denoised, "Color")[:, :3].astype(np.float64)
    assert np.max(np.abs(np.round(np.clip(srgb, 0, 1) * 255) - color)) <= 1


def crease_errors(wall_label):
    """A wall standing on a floor (label 1) under a white sky, both of one gray: the floor darkens
    towards the crease, where the wall hides half the sky. The wall is `wall_label`. Returns the
    floor's crease pixels' (a 4-neighbour on the wall) luminance above a 1024-sample reference
    and their RMSE, for one denoised sample of seeds 5-8, and the RMSE of 16 raw samples."""
    labels = np.zeros((24, 28, 28), np.uint8)  # z, y, x
    labels[0:3] = 1
    labels[3:22, 12:16, 2:26] = 2
    size = 128

    def sky_renderer(volume, denoise, seed):
        return renderer(volume, denoise, seed, size=size, colors=((0.8, 0.8, 0.8),) * 2,
                        sun=False, sky=1.0, camera=(30, 25, 1.2))

    # Where the crease is: the floor's pixels beside the wall's, told apart by their labels.
    two_labels = sky_renderer(vtksvdag.from_numpy(labels), False, 11)
    render_to(two_labels, 1)
    label = output(two_labels, "Label").reshape(size, size)
    padded = np.pad(label, 1)
    on_wall = np.zeros((size, size), bool)
    for dy, dx in ((0, 1), (0, -1), (1, 0), (-1, 0)):
        on_wall |= padded[1 + dy:1 + dy + size, 1 + dx:1 + dx + size] == 2
    crease = ((label == 1) & on_wall).reshape(-1)
    assert crease.sum() > 60
    labels[labels == 2] = wall_label
    volume = vtksvdag.from_numpy(labels)
    reference_renderer = sky_renderer(volume, False, 11)
    reference = render_to(reference_renderer, 1024)
    assert np.array_equal(output(reference_renderer, "Label") != 0, label.reshape(-1) != 0)
    luminance = np.array([0.2126, 0.7152, 0.0722])
    # The occlusion to keep: the reference's crease is well below the rest of the floor.
    floor = (label == 1).reshape(-1) & ~crease
    assert (reference[crease] @ luminance).mean() < 0.8 * (reference[floor] @ luminance).mean()
    brighter, errors = [], []
    for seed in (5, 6, 7, 8):
        denoised = render_to(sky_renderer(volume, True, seed), 1)
        difference = (denoised[crease] - reference[crease]) @ luminance
        brighter.append(difference.mean())
        errors.append(np.sqrt(np.mean((denoised[crease] - reference[crease]) ** 2)))
    raw16 = render_to(sky_renderer(volume, False, 5), 16)
    raw_error = np.sqrt(np.mean((raw16[crease] - reference[crease]) ** 2))
    return brighter, errors, raw_error


def test_crease_keeps_its_occlusion():
    """The wall is label 2: the floor's crease pixels are label edge pixels, whose coverage rays
    are whole paths (GpuLayout.h): the denoiser mixes their radiance with the window's estimate of
    each surface, so the crease keeps its darkening rather than take the brighter floor beside it.
    Measured (seeds 5-8, 128^2, against 1024 samples): the denoised crease 0.009 brighter than the
    reference on average (0.003-0.020 per seed; 0.028 from the window's estimate alone, 0.054 when
    that came from the pixels beside the crease), RMSE 0.058-0.067 against 0.077 for 16 raw
    samples."""
    brighter, errors, raw_error = crease_errors(2)
    assert np.mean(brighter) < 0.018, brighter
    assert np.mean(errors) < raw_error, (errors, raw_error)


def test_crease_within_a_label_keeps_its_occlusion():
    """The same wall and floor, both label 1: the crease is a step within a label whose faces meet
    concave, where the coverage's corner rays are whole paths (GpuLayout.h), 4 to a label edge's
    16: the darkening is kept less well. Measured (seeds 5-8, 128^2, against 1024 samples): the
    denoised crease 0.032 brighter than the reference on average (0.019-0.050 per seed; 0.048
    with first hits only there), RMSE 0.060-0.079 against 0.077 for 16 raw samples."""
    brighter, errors, raw_error = crease_errors(1)
    assert np.mean(brighter) < 0.04, brighter
    assert np.mean(errors) < raw_error, (errors, raw_error)


def test_filter_and_edge_estimate_fade_as_samples_converge(two_boxes):
    raw, denoised = renderer(two_boxes, False), renderer(two_boxes, True)
    render_to(raw, 1)
    label = output(raw, "Label")
    hit = label != 0
    edges = hit & ~(inside(label, 1) | inside(label, 2))
    changes, edge_changes = [], []
    for samples in (4, 16, 64):
        # The same samples accumulated (same seed and settings).
        a, b = render_to(raw, samples), render_to(denoised, samples)
        changes.append(float(np.mean(np.abs(a[hit & ~edges] - b[hit & ~edges]))))
        edge_changes.append(float(np.mean(np.abs(a[edges] - b[edges]))))
    # Inside the labels the filter's change shrinks as the variance of the mean falls; on edge
    # pixels the coverage estimate's weight does (16 / (16 + samples)).
    assert changes[0] > changes[1] > changes[2], changes
    assert edge_changes[0] > edge_changes[1] > edge_changes[2] > 0, edge_changes
    # Off, the image is the raw estimator's (the same bytes as a renderer that never denoised).
    off = renderer(two_boxes, True)
    off.GetSettings().SetDenoise(False)
    assert np.array_equal(render_to(off, 4), render_to(renderer(two_boxes, False), 4))


def test_only_the_shown_pass_is_denoised(two_boxes):
    """PassesPerRender: the passes before the last leave the denoiser out and the last is
    filtered, so one execution of 4 passes gives exactly the image of 4 executions of 1 pass
    (the denoiser filters the displayed image, never the accumulation), and the filter runs once.
    """
    each, batched = renderer(two_boxes, True), renderer(two_boxes, True)
    once_raw = renderer(two_boxes, False)
    each_hdr = render_to(each, 4)
    batched.SetPassesPerRender(4)
    assert batched.Render() == 1
    assert batched.GetAccumulatedSamples() == 4
    assert np.array_equal(output(batched, "HDR"), output(each, "HDR"))
    assert np.array_equal(output(batched, "Color"), output(each, "Color"))
    once_raw.SetPassesPerRender(4)
    assert once_raw.Render() == 1
    # The denoiser did run on the last pass (the raw mean differs).
    assert not np.array_equal(output(once_raw, "HDR")[:, :3], each_hdr)
    times = [batched.GetPassMilliseconds(i) for i in range(4)]
    assert all(t > 0 for t in times)
    assert batched.GetPassMilliseconds(4) == 0 and batched.GetPassMilliseconds(-1) == 0
    assert batched.GetLastFrameMilliseconds() == times[-1]
    assert abs(sum(times) / 1000 - batched.GetRenderSeconds()) < 1e-6


def test_denoise_in_every_layer(two_boxes, tmp_path):
    settings = vtkSegmentationSVDAGRenderSettings()
    assert settings.GetDenoise() is True  # the core's default
    settings.DenoiseOff()
    assert settings.GetDenoise() is False
    assert "Denoise: 0" in str(settings)
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=(64, 64))
    actor = vtksvdag.add_segmentation(plotter, two_boxes, denoise=False)
    assert actor.GetMapper().GetSettings().GetDenoise() is False
    actor = vtksvdag.add_segmentation(plotter, two_boxes)
    assert actor.GetMapper().GetSettings().GetDenoise() is True
    plotter.close()
    path = tmp_path / "boxes.svdag"
    two_boxes.save(str(path))
    # The Python command line and the C++ tool (beside the build's Python modules).
    import vtksvdag.vtkSVDAGRendering as module

    tool = pathlib.Path(module.__file__).resolve().parents[2] / "bin" / "vtksvdag-render"
    for flag, expected in (("--no-denoise", False), ("--denoise", True)):
        run = subprocess.run([sys.executable, "-m", "vtksvdag", "render", str(path), "-o",
                              str(tmp_path / "a.png"), "--width", "32", "--height", "32", flag,
                              "--json"], capture_output=True, text=True, timeout=300)
        assert run.returncode == 0, run.stderr
        assert json.loads(run.stdout.strip().splitlines()[-1])["denoise"] is expected
        if tool.is_file():
            run = subprocess.run([str(tool), str(path), str(tmp_path / "b.png"), "--width", "32",
                                  "--height", "32", flag], capture_output=True, text=True,
                                 timeout=300)
            assert run.returncode == 0, run.stderr
            assert json.loads(run.stdout.strip().splitlines()[-1])["denoise"] is expected


def test_denoiser_switched_on_mid_accumulation(two_boxes):
    """Edge coverage is traced on an accumulation's first pass: a denoiser switched on later in
    the accumulation (which goes on) leaves the edges as the samples have them, from 4 samples on,
    rather than resolving them from the records of another view."""
    raw, later = renderer(two_boxes, False), renderer(two_boxes, True)
    expected = render_to(raw, 4)
    # Records of another view first (the denoiser on), then this view's accumulation without it.
    assert later.ResetCamera(70, 40, 1.0)
    render_to(later, 1)
    later.GetSettings().SetDenoise(False)
    assert later.ResetCamera(35, 25, 1.0)
    render_to(later, 3)
    later.GetSettings().SetDenoise(True)
    got = render_to(later, 4)
    assert later.GetAccumulatedSamples() == 4  # the accumulation went on
    label = output(raw, "Label")
    edges = (label != 0) & ~(inside(label, 1) | inside(label, 2))
    assert edges.sum() > 50
    assert np.array_equal(got[edges], expected[edges])
    # Inside the labels the filter did run.
    assert not np.array_equal(got[~edges & (label != 0)], expected[~edges & (label != 0)])


def test_edge_coverage_alike_on_both_backends(two_boxes):
    """The compute backend shares a subgroup's coverage rays among its lanes; the ray tracing
    backend traces each edge pixel's own. Both must count the same rays for the same pixels: the
    denoised one-sample images agree (a ray handed to the wrong pixel would swap red and blue)."""
    images = {}
    for backend in ("compute", "rt"):
        r = renderer(two_boxes, True)
        r.GetSettings().SetBackend(backend)
        images[backend] = render_to(r, 1)
        assert r.GetBackendInUse() == backend
        labels = output(r, "Label")
    edges = ~inside(labels, 1) & ~inside(labels, 2) & ~inside(labels, 0)
    assert edges.sum() > 100
    np.testing.assert_allclose(images["compute"], images["rt"], atol=1e-4)
    # The edges are blends, not one label's color: coverage was traced.
    blended = (images["compute"][edges, 0] > 0.01) & (images["compute"][edges, 2] > 0.01)
    assert blended.sum() > 20


def test_edge_coverage_of_a_straight_boundary_counts_every_grid_ray():
    """An edge pixel traces its coverage grid's corners first and, where they hit one surface,
    lets that surface count for all 16 rays (GpuLayout.h, SVDAG_COVERAGE_CORNERS). Across a
    straight boundary that is what tracing all 16 gives. Against a brute force: the same view at
    4x the size, whose pixel centers are the coverage rays; through emissive labels on a black
    background (one surface, one color each), an edge pixel's denoised value is
    own + (sum of count_k color_k / 16 - own) * 16 / 17, which gives each pixel's count back."""
    labels = np.zeros((4, 40, 40), np.uint8)  # z, y, x: a slab split at x = 20
    labels[1:3, 2:38, 2:20] = 1
    labels[1:3, 2:38, 20:38] = 2
    volume = vtksvdag.from_numpy(labels, axis_order="zyx")
    size, tilt = 48, np.radians(20.0)  # the boundary crosses the image at 20 degrees

    def render(denoise, scale, backend):
        r = vtkSegmentationSVDAGRenderer()
        r.SetInputData(volume.dataobject)
        r.SetWidth(size * scale)
        r.SetHeight(size * scale)
        props = r.GetLabelProperties()
        for label, emission in ((1, (1.0, 0.0, 0.0)), (2, (0.0, 0.0, 1.0))):
            props.SetColor(label, 0.0, 0.0, 0.0)
            props.SetSpecular(label, 0.0)
            props.SetEmission(label, *emission)
        s = r.GetSettings()
        s.SetLOD("voxel")
        s.SetBackend(backend)
        s.SunOff()
        s.SetEnvironmentColor(0.0, 0.0, 0.0)
        s.SetDenoise(denoise)
        r.SetCameraFocalPoint(20.0, 20.0, 2.0)
        r.SetCameraPosition(20.0, 20.0, 42.0)
        r.SetCameraViewUp(np.sin(tilt), np.cos(tilt), 0.0)
        r.SetCameraViewAngle(30.0)
        assert r.Render() == 1
        return r

    fine = output(render(False, 4, "compute"), "Label").reshape(size, 4, size, 4)
    blocks = fine.transpose(0, 2, 1, 3).reshape(size, size, 16)
    reds = (blocks == 1).sum(-1)
    for backend in ("compute", "rt"):
        r = render(True, 1, backend)
        label = output(r, "Label").reshape(size, size)
        hdr = output(r, "HDR")[:, :3].astype(np.float64).reshape(size, size, 3)
        assert set(np.unique(label)) == {1, 2}, "the slab fills the view"
        padded = np.pad(label, 1, mode="edge")
        edge = np.zeros_like(label, dtype=bool)
        for dy in (-1, 0, 1):
            for dx in (-1, 0, 1):
                edge |= padded[1 + dy:1 + dy + size, 1 + dx:1 + dx + size] != label
        only_two = np.all((blocks == 1) | (blocks == 2), axis=-1)
        check = edge & only_two
        own = np.where((label == 1)[..., None], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0])
        blend = own + (hdr - own) * 17.0 / 16.0
        counted = np.rint(16.0 * blend[..., 0]).astype(int)
        assert np.allclose(blend[check].sum(-1), 1.0, atol=1e-4), "the counts add up to 16"
        # Settled by their corners (16 of one label) and traced in full (both labels) alike.
        settled, split = check & ((reds == 0) | (reds == 16)), check & (reds > 0) & (reds < 16)
        assert settled.sum() > 10 and split.sum() > 30, backend
        # A coverage ray and the fine image's ray may round differently where a sub-pixel center
        # lies on the boundary: at most one pixel apart by one ray.
        wrong = counted[check] != reds[check]
        assert wrong.sum() <= 1 and np.all(np.abs(counted[check] - reds[check]) <= 1), backend
