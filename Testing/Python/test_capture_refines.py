"""Captures show the refined image without a refine() call (issue 20's first deliverable).

The reference is a 1024-sample image of the same view; a capture must have the noise (RMSE
against it) of the image refined to the plotter's spp, not of one sample. Every capture route a
pyvista user takes is tried: screenshot() before and after show(), show(screenshot=...),
show(auto_close=False) then screenshot(), and VTK's own vtkWindowToImageFilter; interactive
frames keep to one pass.
"""
import numpy as np
import pytest
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

W, H = 120, 90
SPP = 16


def labels():
    """[x, y, z] uint16: two boxes and a sphere, lit by the sun (shadows make the noise)."""
    x, y, z = np.mgrid[0:40, 0:40, 0:40]
    volume = np.zeros((40, 40, 40), np.uint16)
    volume[5:35, 5:35, 0:6] = 1
    volume[8:20, 10:30, 6:24] = 4
    volume[(x - 27) ** 2 + (y - 20) ** 2 + (z - 16) ** 2 < 81] = 9
    return volume


def plotter(spp, off_screen=True, samples_per_pass=None):
    import pyvista as pv

    import vtksvdag

    p = pv.Plotter(off_screen=off_screen, window_size=(W, H))
    # The denoiser off: its one-sample frames come close to the refined image (test_denoise.py),
    # and what is checked here is which of the two a capture shows.
    actor = vtksvdag.add_segmentation(p, labels(), spp=spp, sun=True, bounces=2,
                                      samples_per_pass=samples_per_pass, denoise=False)
    p.camera_position = [(80, -50, 70), (20, 20, 10), (0, 0, 1)]
    return p, actor.GetMapper()


def rgb(image):
    return np.asarray(image)[..., :3].astype(np.float64)


def rmse(a, b):
    return float(np.sqrt(np.mean((rgb(a) - rgb(b)) ** 2)))


@pytest.fixture(scope="module")
def references():
    """The 1024-sample reference, and the images refined to SPP and to one sample (refine())."""
    import vtksvdag

    images = {}
    for spp, per_pass in ((1024, 64), (SPP, None), (1, None)):
        p, mapper = plotter(spp, samples_per_pass=per_pass)
        mapper.SetRefineStillRenders(False)  # refine() alone, as before this feature
        p.show(auto_close=False)
        stats = vtksvdag.refine(p)
        assert stats[0]["samples"] == spp
        images[spp] = p.screenshot(return_img=True)
        p.close()
    noise_refined, noise_single = rmse(images[SPP], images[1024]), rmse(images[1], images[1024])
    assert noise_refined < 0.6 * noise_single, (noise_refined, noise_single)
    return images


def test_screenshot_without_refine_is_refined(references):
    p, mapper = plotter(SPP)
    try:
        image = p.screenshot(return_img=True)  # the first render happens here
        assert mapper.GetAccumulatedSamples() == SPP and mapper.IsConverged()
        # The same samples as refine() gives: the same pixels.
        assert np.array_equal(image, references[SPP])
        assert rmse(image, references[1024]) < 0.6 * rmse(references[1], references[1024])
    finally:
        p.close()


def test_show_screenshot_and_later_captures_are_refined(references, tmp_path):
    import imageio.v3 as iio

    p, mapper = plotter(SPP)
    path = tmp_path / "shown.png"
    p.show(screenshot=str(path), auto_close=False)
    assert np.array_equal(iio.imread(path)[..., :3], references[SPP][..., :3])
    # A camera move, then a capture through VTK's filter (it re-renders: a still render).
    p.camera.azimuth = 10
    grab = vtkWindowToImageFilter()
    grab.SetInput(p.render_window)
    grab.ReadFrontBufferOff()
    grab.Update()
    assert mapper.GetAccumulatedSamples() == SPP and mapper.IsConverged()
    moved = vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars())
    assert moved.size == W * H * 3
    assert not np.array_equal(moved.reshape(H, W, 3)[::-1], references[SPP][..., :3])
    p.close()


def test_interactive_frames_stay_one_pass():
    p, mapper = plotter(SPP)
    try:
        p.show(auto_close=False)
        assert mapper.GetAccumulatedSamples() == SPP
        window = p.render_window
        window.SetDesiredUpdateRate(15.0)  # what an interactor style sets while the user drags
        p.camera.azimuth = 20
        window.Render()
        assert mapper.GetAccumulatedSamples() == 1
        assert not mapper.IsConverged()
        window.SetDesiredUpdateRate(p.iren.interactor.GetStillUpdateRate())  # the drag ended
        window.Render()
        assert mapper.GetAccumulatedSamples() == SPP
    finally:
        p.close()


def test_on_screen_plotter_refines_progressively_and_before_a_screenshot(references):
    """An on-screen window keeps one pass per render (the interactor's timer refines, the window
    stays responsive); screenshot() after show(auto_close=False) refines first."""
    p, mapper = plotter(SPP, off_screen=False)
    try:
        assert not p.off_screen and not mapper.GetRefineStillRenders()
        # show() ends with the capture pyvista keeps (last_image): refined.
        p.show(auto_close=False, interactive=False)
        assert mapper.GetAccumulatedSamples() == SPP
        assert np.array_equal(p.last_image, references[SPP])
        # A still render of the shown window adds one pass.
        p.camera.azimuth = 10
        p.render_window.Render()
        assert mapper.GetAccumulatedSamples() == 1
        p.camera.azimuth = 0
        image = p.screenshot(return_img=True)
        assert mapper.GetAccumulatedSamples() == SPP
        assert np.array_equal(image, references[SPP])
    finally:
        p.close()


def test_mapper_refine_still_renders_in_vtk():
    """The C++ switch alone, in a plain VTK window without an interactor."""
    from conftest import compress_zyx, mapper_scene

    window, renderer, volume, mapper = mapper_scene(compress_zyx(np.swapaxes(labels(), 0, 2)))
    mapper.SetTargetSamplesPerPixel(5)
    window.Render()
    assert mapper.GetAccumulatedSamples() == 1  # default off
    mapper.RefineStillRendersOn()
    assert mapper.GetRefineStillRenders()
    renderer.GetActiveCamera().Azimuth(5)
    window.Render()
    assert mapper.GetAccumulatedSamples() == 5 and mapper.IsConverged()
    # The time limit stops it early (0 s: the first pass only).
    mapper.SetRefineTimeLimit(0.0)
    mapper.SetTargetSamplesPerPixel(500)
    window.Render()
    assert mapper.GetAccumulatedSamples() == 6


def test_save_graphic_refines_first(tmp_path):
    """pyvista's vector export (PDF here: Debian's GL2PS embeds no raster in SVG) holds the 3-D
    props as a raster of the window: it is refined first."""
    p, mapper = plotter(SPP, off_screen=False)
    try:
        p.show(auto_close=False, interactive=False)
        p.camera.azimuth = 10
        p.render_window.Render()
        assert mapper.GetAccumulatedSamples() == 1
        path = tmp_path / "figure.pdf"
        p.save_graphic(str(path))
        assert mapper.GetAccumulatedSamples() == SPP and mapper.IsConverged()
        assert path.read_bytes().startswith(b"%PDF") and b"/Image" in path.read_bytes()
    finally:
        p.close()
