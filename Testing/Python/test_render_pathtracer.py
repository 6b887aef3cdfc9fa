"""The path tracer of vtkSegmentationSVDAGRenderer on the GPU (lavapipe here): physics checks
(white furnace, NEE against the plain estimator), determinism, robustness under extreme settings,
hidden labels, progressive accumulation and what an edit rebuilds.

Images are small (48 x 32) so that many samples per pixel stay cheap on a CPU device.
"""
import numpy as np
import pytest
from conftest import capture_errors, compress_zyx as build
from vtkmodules.util.numpy_support import vtk_to_numpy

from vtksvdag.vtkSVDAGRendering import (vtkSegmentationSVDAGRenderer,
                                        vtkSegmentationSVDAGRenderSettings)

WIDTH, HEIGHT = 48, 32
VALUES = (3, 5, 9)  # label values; their indices in the label table are 0, 1, 2


def srgb(c):
    """The display (sRGB) encoding of a linear value: SetColor takes display colors and the
    renderer converts them back, so a physics check passes the encoding of the albedo it means."""
    return 12.92 * c if c <= 0.0031308 else 1.055 * c ** (1 / 2.4) - 0.055


@pytest.fixture(scope="module")
def labels():
    """A porous block of three labels: cavities and overhangs, so paths bounce many times."""
    rng = np.random.default_rng(7)
    labels = np.zeros((28, 28, 28), np.uint16)
    labels[4:24, 4:24, 4:24] = rng.choice(VALUES, size=(20, 20, 20))
    labels[rng.random(labels.shape) < 0.35] = 0
    labels[2:4, 2:26, 2:26] = VALUES[0]  # a floor slab
    return labels


@pytest.fixture(scope="module")
def volume(labels):
    return build(labels)


def make_renderer(volume, azimuth=30, elevation=25):
    r = vtkSegmentationSVDAGRenderer()
    r.SetInputData(volume)
    r.SetWidth(WIDTH)
    r.SetHeight(HEIGHT)
    assert r.ResetCamera(azimuth, elevation, 1.1) == 1
    return r


def render(r):
    assert r.Render() == 1
    data = r.GetOutput().GetPointData()
    return {name: vtk_to_numpy(data.GetArray(name)).copy()
            for name in ("Color", "HDR", "Depth", "Label", "Normal")}


def white_lambertian(r, count=len(VALUES)):
    labels = r.GetLabelProperties()
    for value in VALUES[:count]:
        labels.SetColor(value, 1, 1, 1)  # sRGB 1 is linear 1
        labels.SetSpecular(value, 0)
        labels.SetMetallic(value, 0)


def test_white_furnace(volume):
    """Exactly Lambertian white surfaces under a constant environment of radiance 1 reflect all
    light: every pixel that sees a voxel has radiance 1 (up to noise and path truncation)."""
    r = make_renderer(volume)
    white_lambertian(r)
    settings = r.GetSettings()
    settings.SetEnvironmentColor(1, 1, 1)
    settings.SetBackground(1, 1, 1, 1)  # jittered camera samples that miss also see radiance 1
    settings.SetMaximumBounces(64)
    settings.SetSamplesPerPixel(128)
    for nee in (True, False):
        settings.SetNextEventEstimation(nee)
        out = render(r)
        out = render(r)  # accumulates: 256 samples
        assert r.GetAccumulatedSamples() == 256
        hit = out["Label"] > 0
        assert hit.sum() > 0.2 * WIDTH * HEIGHT
        rgb = out["HDR"][hit, :3]
        assert abs(rgb.mean() - 1) < 0.01, (nee, rgb.mean())
        assert rgb.min() > 0.6 and rgb.max() < 1.5, (nee, rgb.min(), rgb.max())


def test_white_furnace_fails_for_a_grey_material(volume):
    """The furnace check can fail: a 50% grey albedo must give a clearly darker mean."""
    r = make_renderer(volume)
    white_lambertian(r)
    grey = srgb(0.5)  # a linear albedo of exactly 0.5
    for value in VALUES:
        r.GetLabelProperties().SetColor(value, grey, grey, grey)
    r.GetSettings().SetMaximumBounces(64)
    r.GetSettings().SetSamplesPerPixel(64)
    out = render(r)
    hit = out["Label"] > 0
    assert out["HDR"][hit, :3].mean() < 0.85


def test_seed_determinism(volume):
    r = make_renderer(volume)
    r.GetSettings().SetSamplesPerPixel(4)
    r.GetSettings().SetSeed(11)
    first = render(r)
    r.ResetAccumulation()
    again = render(r)
    for name in first:
        assert np.array_equal(first[name], again[name]), name
    # Another renderer (another device context) with the same settings: the same bytes.
    other = make_renderer(volume)
    other.GetSettings().SetSamplesPerPixel(4)
    other.GetSettings().SetSeed(11)
    assert np.array_equal(render(other)["HDR"], first["HDR"])
    other.GetSettings().SetSeed(12)
    different = render(other)
    assert other.GetAccumulatedSamples() == 4  # a new seed restarts the accumulation
    assert not np.array_equal(different["HDR"], first["HDR"])
    # The primary outputs do not depend on the seed.
    for name in ("Label", "Depth", "Normal"):
        assert np.array_equal(different[name], first[name]), name


def test_progressive_accumulation(volume):
    r = make_renderer(volume)
    r.GetSettings().SetSamplesPerPixel(2)
    one = render(r)
    assert r.GetAccumulatedSamples() == 2
    two = render(r)
    assert r.GetAccumulatedSamples() == 4
    assert r.GetRenderSeconds() > 0
    # The mean of 4 samples: samples 0-1 are the first image's, so the second image is the
    # average of the first and of the new samples 2-3 (which a fresh accumulation cannot give).
    assert not np.array_equal(one["HDR"], two["HDR"])
    # Exposure only changes the display color, not the accumulation.
    r.GetSettings().SetExposure(2.0)
    brighter = render(r)
    assert r.GetAccumulatedSamples() == 6
    hit = brighter["Label"] > 0
    assert brighter["Color"][hit, :3].astype(int).sum() > two["Color"][hit, :3].astype(int).sum()
    # A camera change restarts it.
    r.ResetCamera(40, 25, 1.1)
    render(r)
    assert r.GetAccumulatedSamples() == 2
    # More samples reduce the noise: the variance between two independent 32-sample images is
    # well below that of two 2-sample images (the estimator's, the denoiser off).
    r.GetSettings().SetDenoise(False)

    def noise(spp):
        images = []
        for seed in (1, 2):
            r.GetSettings().SetSeed(seed)
            r.GetSettings().SetSamplesPerPixel(spp)
            images.append(render(r)["HDR"][:, :3])
        return np.mean((images[0] - images[1]) ** 2)
    assert noise(32) < 0.3 * noise(2)


# Per label VALUE v, on the renderer's label properties p. Display colors are clamped to [0, 1]
# (SetColor), so "overbright" is the brightest base color (1) with the strongest specular.
EXTREMES = {
    "huge emission": lambda p, v: p.SetEmission(v, 1e30, 1e30, 1e30),
    "mirror": lambda p, v: (p.SetRoughness(v, 0), p.SetMetallic(v, 1)),
    "glass ior 1": lambda p, v: (p.SetTransmission(v, 1), p.SetIOR(v, 1), p.SetRoughness(v, 0)),
    "glass": lambda p, v: (p.SetTransmission(v, 1), p.SetIOR(v, 2.4)),
    "black": lambda p, v: p.SetColor(v, 0, 0, 0),
    "overbright": lambda p, v: (p.SetColor(v, 50, 50, 50), p.SetSpecular(v, 1)),
}


@pytest.mark.parametrize("sun", ["delta", "huge disk", "grazing"])
def test_no_nan_or_inf_under_extremes(volume, sun):
    r = make_renderer(volume)
    for value, setup in zip(VALUES, EXTREMES.values()):
        setup(r.GetLabelProperties(), value)
    settings = r.GetSettings()
    settings.SunOn()
    if sun == "delta":
        settings.SetSunAngularRadius(0)
        settings.SetSunIrradiance(1e20, 1e20, 1e20)
    elif sun == "huge disk":
        settings.SetSunAngularRadius(89)
        settings.SetSunIrradiance(1e6, 0, 1e6)
    else:
        settings.SetSunDirection(1, 0, 1e-7)
        settings.SetSunIrradiance(5, 5, 5)
    settings.SetMaximumBounces(64)
    settings.SetSamplesPerPixel(8)
    out = render(r)
    for name in ("HDR", "Depth", "Normal"):
        assert np.all(np.isfinite(out[name])), name
    assert np.all(out["HDR"] >= 0)
    # And the remaining extremes on the other labels.
    r2 = make_renderer(volume)
    for value, setup in zip(VALUES, list(EXTREMES.values())[3:]):
        setup(r2.GetLabelProperties(), value)
    r2.GetSettings().SetEnvironmentColor(1e10, 0, 1e-10)
    r2.GetSettings().SetSamplesPerPixel(8)
    out = render(r2)
    assert np.all(np.isfinite(out["HDR"])) and np.all(out["HDR"] >= 0)


def test_emission_is_the_only_light_in_the_dark(volume):
    """Under a black environment without sun, only emission lights the scene: an emissive label
    glows in its color (with 1 px ~ 1 voxel, jittered samples also see its neighbours, so the
    check is on means), and without emission the image is exactly black."""
    r = make_renderer(volume)
    r.GetSettings().SetEnvironmentColor(0, 0, 0)
    r.GetSettings().SetBackground(0, 0, 0, 1)
    r.GetLabelProperties().SetEmission(VALUES[1], 4, 2, 1)  # label index 1
    r.GetSettings().SetSamplesPerPixel(8)
    out = render(r)
    emitter = out["Label"] == 2
    others = (out["Label"] > 0) & ~emitter
    assert emitter.any() and others.any()
    rgb = out["HDR"][emitter, :3].mean(axis=0)
    assert rgb[0] > 2 and rgb[0] > rgb[1] > rgb[2] > 0
    assert out["HDR"][others, 0].mean() < rgb[0]
    r.GetLabelProperties().SetEmission(VALUES[1], 0, 0, 0)
    dark = render(r)
    assert np.all(dark["HDR"][:, :3] == 0)


def test_hidden_labels_vanish(labels, volume):
    """A label with visibility 0 leaves the Label output and the image: the image equals that of
    a volume built without it (same materials per label value, same seed)."""
    hidden_value = VALUES[1]
    r = make_renderer(volume)
    r.GetLabelProperties().SetVisibility(hidden_value, False)
    r.GetLabelProperties().SetColor(VALUES[0], srgb(0.8), srgb(0.3), srgb(0.2))
    r.GetLabelProperties().SetColor(VALUES[2], srgb(0.2), srgb(0.4), srgb(0.9))
    r.GetSettings().SetSamplesPerPixel(16)
    r.GetSettings().SetSeed(3)
    out = render(r)
    assert not np.any(out["Label"] == 2)

    without = build(labels, excluded=(hidden_value,))  # label table: VALUES[0], VALUES[2]
    ref = make_renderer(without)
    ref.GetLabelProperties().SetColor(VALUES[0], srgb(0.8), srgb(0.3), srgb(0.2))
    ref.GetLabelProperties().SetColor(VALUES[2], srgb(0.2), srgb(0.4), srgb(0.9))
    ref.GetSettings().SetSamplesPerPixel(16)
    ref.GetSettings().SetSeed(3)
    expected = render(ref)
    # Label indices differ (index 2 there is index 1 here); hits and depths are equal.
    remap = np.array([0, 1, 3], np.int64)
    assert np.array_equal(remap[expected["Label"]], out["Label"])
    assert np.array_equal(expected["Depth"], out["Depth"])
    assert np.allclose(expected["HDR"], out["HDR"], atol=1e-4)
    # Shown again: the label returns (the rt backend rebuilds its BVH, compute flips a bit).
    builds = r.GetNumberOfBVHBuilds()
    r.GetLabelProperties().SetVisibility(hidden_value, True)
    assert np.any(render(r)["Label"] == 2)
    assert r.GetNumberOfBVHBuilds() == builds + (r.GetBackendInUse() == "rt")


def test_nee_and_plain_estimator_agree(volume):
    """Both estimators are unbiased: under a disk sun plus a dim environment their means over the
    image agree within a few percent (the plain one needs many more samples)."""
    means = {}
    for nee in (True, False):
        r = make_renderer(volume, azimuth=20, elevation=35)
        settings = r.GetSettings()
        settings.SunOn()
        settings.SetSunDirection(0.4, 0.5, 0.77)
        settings.SetSunAngularRadius(8)  # large enough that escaping paths find it
        settings.SetSunIrradiance(3, 3, 3)
        settings.SetEnvironmentColor(0.2, 0.25, 0.3)
        settings.SetMaximumBounces(4)
        settings.SetNextEventEstimation(nee)
        settings.SetSamplesPerPixel(512)
        settings.SetSeed(5)
        for _ in range(1 if nee else 8):  # the plain estimator's noise is ~0.5% at 4096 spp
            out = render(r)
        hit = out["Label"] > 0
        means[nee] = out["HDR"][hit, :3].mean(axis=0)
    assert np.all(means[True] > 0.05)
    assert np.allclose(means[True], means[False], rtol=0.03), means


@pytest.mark.parametrize("backend", ["rt", "compute"])
def test_material_edit_does_not_rebuild(volume, backend):
    r = make_renderer(volume)
    r.GetSettings().SetBackend(backend)
    r.GetSettings().SetSamplesPerPixel(2)
    first = render(r)
    assert r.GetBackendInUse() == backend
    builds = r.GetNumberOfBVHBuilds()
    setup = r.GetSetupSeconds()
    pipelines = r.GetNumberOfPipelineBuilds()
    assert builds == (1 if backend == "rt" else 0) and pipelines >= 1
    render(r)
    assert r.GetAccumulatedSamples() == 4
    r.GetLabelProperties().SetColor(VALUES[0], srgb(0.9), srgb(0.1), srgb(0.1))
    r.GetLabelProperties().SetRoughness(VALUES[1], 0.1)
    edited = render(r)
    assert r.GetAccumulatedSamples() == 2  # the edit restarted the accumulation
    assert r.GetNumberOfBVHBuilds() == builds and r.GetSetupSeconds() == setup
    assert r.GetNumberOfPipelineBuilds() == pipelines  # no feature changed
    hit0 = first["Label"] == 1
    assert not np.allclose(edited["HDR"][hit0], first["HDR"][hit0])
    # Emission is a feature compiled in only when used: the pipeline is rebuilt, the BVH not.
    r.GetLabelProperties().SetEmission(VALUES[2], 1, 1, 1)
    render(r)
    assert r.GetNumberOfPipelineBuilds() == pipelines + 1
    assert r.GetNumberOfBVHBuilds() == builds
    # Visibility is a BVH change on the rt backend, a bit on compute: either way a restart.
    r.GetLabelProperties().SetVisibility(VALUES[2], False)
    render(r)
    assert r.GetNumberOfBVHBuilds() == builds + (backend == "rt")
    assert r.GetAccumulatedSamples() == 2
    # Emission off and on again (a highlighted label hidden and shown): the pipelines of both
    # feature sets are kept, nothing more is compiled, and each traces as it did.
    r.GetLabelProperties().SetVisibility(VALUES[2], True)
    images = []
    for value in (0, 1, 0, 1):
        r.GetLabelProperties().SetEmission(VALUES[2], value, value, value)
        images.append(render(r)["HDR"])
    assert r.GetNumberOfPipelineBuilds() == pipelines + 1
    np.testing.assert_array_equal(images[2], images[0])
    np.testing.assert_array_equal(images[3], images[1])
    assert not np.array_equal(images[1], images[0])


@pytest.mark.parametrize("backend", ["rt", "compute"])
def test_smooth_shading_and_clipping_are_compiled_in_only_when_used(volume, backend):
    """Each is a specialization of the path tracer (Pipeline.h's ShaderFeatures): switched on, one
    more pipeline is compiled, and the frame is a fresh renderer's with that setting; switched off
    again, nothing is compiled and the frame is the first one again."""
    from vtkmodules.vtkCommonDataModel import vtkPlane

    smooth = vtkSegmentationSVDAGRenderSettings.SHADING_SMOOTH
    voxel = vtkSegmentationSVDAGRenderSettings.SHADING_VOXEL
    plane = vtkPlane()
    plane.SetOrigin(14.0, 14.0, 14.0)
    plane.SetNormal(1.0, 0.3, 0.0)

    def configured(r, shading, clipped):
        r.GetSettings().SetBackend(backend)
        r.GetSettings().SetShading(shading)
        r.RemoveAllClippingPlanes()
        if clipped:
            r.AddClippingPlane(plane)
        return r

    r = configured(make_renderer(volume), voxel, False)
    first = render(r)
    pipelines = r.GetNumberOfPipelineBuilds()
    frames = {}
    for step, (shading, clipped) in enumerate([(smooth, False), (voxel, True), (smooth, True)]):
        frames[shading, clipped] = render(configured(r, shading, clipped))
        assert r.GetNumberOfPipelineBuilds() == pipelines + step + 1
        fresh = render(configured(make_renderer(volume), shading, clipped))
        for name in ("Label", "Depth", "Normal", "HDR"):
            np.testing.assert_array_equal(frames[shading, clipped][name], fresh[name], err_msg=name)
    hit = first["Label"] > 0
    assert not np.array_equal(frames[smooth, False]["Normal"][hit], first["Normal"][hit])
    np.testing.assert_array_equal(frames[smooth, False]["Label"], first["Label"])
    assert (frames[voxel, True]["Label"] > 0).sum() < 0.9 * hit.sum()  # the plane cut some away
    again = render(configured(r, voxel, False))
    assert r.GetNumberOfPipelineBuilds() == pipelines + 3
    for name in ("Label", "Depth", "Normal", "HDR"):
        np.testing.assert_array_equal(again[name], first[name], err_msg=name)


def test_bad_settings_fail_cleanly(volume, tmp_path):
    r = make_renderer(volume)
    plain = render(r)
    # Label properties are keyed by label value: a value the volume does not hold is ignored.
    r.GetLabelProperties().SetColor(7, 1, 0, 0)
    again = render(r)
    assert r.GetAccumulatedSamples() == 2  # no material changed: the accumulation continues
    assert np.array_equal(again["Label"], plain["Label"])
    r.GetLabelProperties().RemoveAllLabels()
    assert r.Render() == 1
    settings = r.GetSettings()
    settings.SetEnvironmentMap(str(tmp_path / "missing.exr"))
    assert r.Render() == 0
    settings.SetEnvironmentMap(None)
    settings.SunOn()
    # A zero sun direction is rejected where it is set (the direction stays).
    messages = capture_errors(settings)
    settings.SetSunDirection(0, 0, 0)
    assert messages and "direction" in messages[0]
    direction = [0.0] * 3
    settings.GetSunDirection(direction)
    assert np.allclose(direction, (0.3, 0.4, 0.866))
    assert r.Render() == 1
    settings.SetSunDirection(0, 0, 1)
    assert r.Render() == 1
    assert r.WriteImage(str(tmp_path / "image.bmp")) == 0


def test_environment_map_and_write_image(volume, tmp_path):
    """An equirectangular EXR lights the scene: the renderer's own EXR output serves as a map.
    PNG and EXR outputs are written."""
    r = make_renderer(volume)
    r.GetSettings().SetSamplesPerPixel(4)
    out = render(r)
    assert r.WriteImage(str(tmp_path / "image.png")) == 1
    assert r.WriteImage(str(tmp_path / "map.exr")) == 1
    assert (tmp_path / "image.png").stat().st_size > 0
    pipelines = r.GetNumberOfPipelineBuilds()
    r.GetSettings().SetEnvironmentMap(str(tmp_path / "map.exr"))
    lit = render(r)
    assert r.GetNumberOfPipelineBuilds() == pipelines + 1  # the map feature is compiled in
    assert np.all(np.isfinite(lit["HDR"]))
    hit = lit["Label"] > 0
    assert not np.allclose(lit["HDR"][hit], out["HDR"][hit])


def fresnel_dielectric(cos_i, eta):
    """Unpolarised Fresnel reflectance, written independently of Shading.h."""
    sin2_t = (1 - cos_i ** 2) / eta ** 2
    cos_t = np.sqrt(np.maximum(0.0, 1 - sin2_t))
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs ** 2 + rp ** 2)


PANE, FLOOR = 3, 5  # the pane fixture's label values (indices 0 and 1)


@pytest.fixture(scope="module")
def pane():
    """A glass pane (value 3, index 0) two voxels thick, inside one 16^3 cell along z, above a
    floor (value 5, index 1) that covers the whole volume."""
    labels = np.zeros((16, 32, 32), np.uint16)  # z, y, x
    labels[0:2, :, :] = 5
    labels[10:12, 8:24, 8:24] = 3
    return build(labels)


def pane_renderer(pane):
    r = vtkSegmentationSVDAGRenderer()
    r.SetInputData(pane)
    r.SetWidth(WIDTH)
    r.SetHeight(HEIGHT)
    r.SetCameraPosition(15.5, 15.5, 60)
    r.SetCameraFocalPoint(15.5, 15.5, 0)
    r.SetCameraViewUp(0, 1, 0)
    r.SetCameraViewAngle(30)
    r.GetSettings().SetSamplesPerPixel(64)
    r.GetSettings().SetMaximumBounces(16)
    return r


def pane_pixels(out):
    """Pixels whose pixel-center ray and all four neighbours' hit the pane (no jittered sample
    strays off it), and the cosine of their incidence (the pane's normal is +z)."""
    pane = (out["Label"] == 1).reshape(HEIGHT, WIDTH)
    inner = pane.copy()
    inner[1:, :] &= pane[:-1, :]
    inner[:-1, :] &= pane[1:, :]
    inner[:, 1:] &= pane[:, :-1]
    inner[:, :-1] &= pane[:, 1:]
    inner[0, :] = inner[-1, :] = inner[:, 0] = inner[:, -1] = False
    return inner.ravel()


def test_transmission_shows_what_is_behind(pane):
    """Thin-walled glass (transmission 1, IOR 1.5, white) in front of an emissive floor under a
    black sky: the pane's pixels show the floor through it, at the Fresnel-transmitted share of
    its radiance; opaque white (transmission 0) shows nothing there (it only faces the sky)."""
    r = pane_renderer(pane)
    r.GetSettings().SetEnvironmentColor(0, 0, 0)
    r.GetSettings().SetBackground(0, 0, 0, 1)
    labels = r.GetLabelProperties()
    labels.SetColor(PANE, 1, 1, 1)
    labels.SetTransmission(PANE, 1)
    labels.SetIOR(PANE, 1.5)
    labels.SetRoughness(PANE, 0)
    labels.SetColor(FLOOR, 0, 0, 0)
    labels.SetEmission(FLOOR, 1, 1, 1)
    out = render(r)
    for name in ("HDR", "Depth", "Normal"):
        assert np.all(np.isfinite(out[name])), name
    inner = pane_pixels(out)
    assert inner.sum() >= 20
    floor = (out["Label"] == 2)
    assert floor.any() and abs(out["HDR"][floor, 0].mean() - 1) < 0.05  # the floor seen directly
    # Expected: (1 - F) at each pixel's incidence angle (the camera ray's direction, from the
    # depth: the pane's top face is at z = 11.5 in world coordinates).
    normals = out["Normal"].reshape(-1, 3)[inner]
    assert np.allclose(normals, [0, 0, 1])
    depth = out["Depth"][inner]
    cos_i = np.clip((60 - 11.5) / depth, 0, 1)
    expected = (1 - fresnel_dielectric(cos_i, 1.5)).mean()
    seen = out["HDR"][inner, :3].mean(axis=0)
    assert np.all(np.abs(seen - expected) < 0.03), (seen, expected)

    labels.SetTransmission(PANE, 0)
    opaque = render(r)
    assert np.all(np.isfinite(opaque["HDR"]))
    assert opaque["HDR"][pane_pixels(opaque), :3].mean() < 0.02


def test_transmissive_white_furnace(pane):
    """Transmission conserves energy: with every label clear white glass under a constant sky of
    radiance 1, every pixel has radiance 1."""
    r = pane_renderer(pane)
    labels = r.GetLabelProperties()
    for value in (PANE, FLOOR):
        labels.SetColor(value, 1, 1, 1)
        labels.SetTransmission(value, 1)
        labels.SetIOR(value, 1.5)
        labels.SetRoughness(value, 0)
    r.GetSettings().SetEnvironmentColor(1, 1, 1)
    r.GetSettings().SetBackground(1, 1, 1, 1)
    r.GetSettings().SetMaximumBounces(64)
    out = render(r)
    assert np.all(np.isfinite(out["HDR"]))
    hit = out["Label"] > 0
    assert hit.sum() > 0.5 * WIDTH * HEIGHT
    rgb = out["HDR"][hit, :3]
    assert abs(rgb.mean() - 1) < 0.01, rgb.mean()
    assert rgb.min() > 0.6 and rgb.max() < 1.5, (rgb.min(), rgb.max())
