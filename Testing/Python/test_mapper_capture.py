"""The volume mapper in pyvista's ways of making pictures: tiled screenshots (``scale=``), the
SSAA render pass, lookup-table colors, and refinement on the interactor's timer in ``show()``.

References are other renderings of the same scene that must agree (a screenshot at scale 1, the
scene without anti-aliasing, the same colors set label by label), and the mapper's own counts.
"""
import numpy as np
import pyvista as pv
from vtkmodules.vtkRenderingCore import vtkColorTransferFunction

import vtksvdag

SIZE = (160, 120)


def labels():
    x, y, z = np.mgrid[0:40, 0:40, 0:40]
    volume = np.zeros((40, 40, 40), np.uint16)
    volume[((x - 26) ** 2 + (y - 20) ** 2 + (z - 20) ** 2) < 12**2] = 7
    volume[x < 9] = 3
    return volume


def scene(anti_aliasing=None, off_screen=True, **options):
    plotter = pv.Plotter(off_screen=off_screen, window_size=SIZE)
    actor = vtksvdag.add_segmentation(plotter, labels(), spp=8, seed=1, lod="voxel", **options)
    plotter.add_mesh(pv.Cylinder(center=(26, 20, 20), direction=(1, 1, 0.3), radius=3, height=60),
                     color="tomato")
    plotter.camera_position = [(70, 60, 110), (20, 20, 20), (0, 1, 0)]
    if anti_aliasing:
        plotter.enable_anti_aliasing(anti_aliasing)
    return plotter, actor.GetMapper()


def test_tiled_screenshot_equals_the_single_one():
    plotter, mapper = scene()
    vtksvdag.refine(plotter)
    one = plotter.screenshot().astype(float)
    two = plotter.screenshot(scale=2).astype(float)
    assert two.shape == (2 * SIZE[1], 2 * SIZE[0], 3)
    # Every tile is refined within its render: the last one holds all samples.
    assert mapper.GetAccumulatedSamples() == 8
    down = two.reshape(SIZE[1], 2, SIZE[0], 2, 3).mean(axis=(1, 3))
    difference = np.abs(down - one)
    # Path-tracing noise (8 samples) and silhouettes sampled at twice the resolution differ; a
    # tile drawn with the wrong camera or at one sample would differ by far more.
    assert difference.mean() < 4.0
    assert np.percentile(difference, 90) < 10.0
    plotter.close()


def test_ssaa_render_pass():
    plain, plain_mapper = scene()
    vtksvdag.refine(plain)
    reference = plain.screenshot().astype(float)
    ssaa, ssaa_mapper = scene("ssaa")
    vtksvdag.refine(ssaa)
    image = ssaa.screenshot().astype(float)
    assert ssaa_mapper.IsConverged()
    assert np.abs(image - reference).mean() < 4.0
    # Picking takes display coordinates, also when the pass draws into a larger framebuffer.
    for x, y in ((100, 60), (40, 60), (130, 90)):
        a, b = vtksvdag.pick(plain, x, y), vtksvdag.pick(ssaa, x, y)
        assert (a is None) == (b is None)
        if a is not None:
            assert a["label"] == b["label"]
            assert np.allclose(a["position"], b["position"], atol=1.0)
    plain.close()
    ssaa.close()


def test_lookup_table_colors_equal_explicit_colors():
    table = vtkColorTransferFunction()
    table.AddRGBPoint(3, 0.2, 0.4, 0.9)
    table.AddRGBPoint(7, 0.9, 0.7, 0.1)
    by_table, _ = scene(cmap=table)
    vtksvdag.refine(by_table)
    explicit, _ = scene(colors={3: (0.2, 0.4, 0.9), 7: (0.9, 0.7, 0.1)})
    vtksvdag.refine(explicit)
    a, b = by_table.screenshot(), explicit.screenshot()
    assert np.array_equal(a, b)
    default, _ = scene()
    vtksvdag.refine(default)
    assert not np.array_equal(default.screenshot(), a), "the table must change the colors"
    for p in (by_table, explicit, default):
        p.close()


def test_show_refines_on_the_interactor_timer():
    plotter, mapper = scene(off_screen=False)
    plotter.show(interactive_update=True, auto_close=False)
    # show() ends with pyvista's capture of the shown image, which refines (test_capture_refines);
    # a still render of the on-screen window after a camera move adds one pass.
    assert mapper.GetAccumulatedSamples() == 8
    plotter.camera.azimuth = 10
    plotter.render()
    first = mapper.GetAccumulatedSamples()
    assert first < 8
    interactor = plotter.iren.interactor
    for _ in range(20):
        interactor.InvokeEvent("TimerEvent")
    assert mapper.GetAccumulatedSamples() == 8 and mapper.IsConverged()
    # Converged: the timer renders no more.
    before = mapper.GetRenderSeconds()
    interactor.InvokeEvent("TimerEvent")
    assert mapper.GetRenderSeconds() == before
    plotter.close()


def test_exposure_recomposites_without_tracing():
    plotter, mapper = scene()
    mapper.SetRefineStillRenders(False)  # one pass per render: the restart below shows
    vtksvdag.refine(plotter)
    before = plotter.screenshot().astype(float)
    samples = mapper.GetAccumulatedSamples()
    mapper.GetSettings().SetExposure(4.0)
    plotter.render()
    after = plotter.screenshot().astype(float)
    assert mapper.GetLastTraceMilliseconds() == 0.0  # only re-composited
    assert mapper.GetAccumulatedSamples() == samples
    volume_pixels = np.abs(after - before).sum(axis=2) > 0
    assert volume_pixels.sum() > 100
    assert (after.sum(axis=2) >= before.sum(axis=2) - 1e-9).all()  # brighter, never darker
    # Any other setting traces anew.
    mapper.GetSettings().SetMaximumBounces(2)
    plotter.render()
    assert mapper.GetAccumulatedSamples() == 1
    plotter.close()


def test_a_capture_keeps_the_refined_image():
    """A capture re-renders the window with camera matrices and mesh depths a float step off,
    and with a share of the frame time: the refined image must be shown as it is (the same
    pixels, no pass traced), never replaced by a restarted one-sample frame."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

    plotter, mapper = scene()
    vtksvdag.refine(plotter)
    assert mapper.GetAccumulatedSamples() == 8
    before = plotter.screenshot().astype(int)
    w, h = plotter.window_size
    captures = []
    for _ in range(3):
        grab = vtkWindowToImageFilter()
        grab.SetInput(plotter.render_window)
        grab.SetInputBufferTypeToRGB()
        grab.ReadFrontBufferOff()
        grab.Update()
        assert mapper.GetAccumulatedSamples() == 8
        assert mapper.GetLastTraceMilliseconds() == 0
        rgb = vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars()).reshape(h, w, 3)
        captures.append(rgb[::-1].astype(int))
    np.testing.assert_array_equal(captures[1], captures[0])
    np.testing.assert_array_equal(captures[2], captures[0])
    # Against the screenshot: only pixels on or next to the mesh may differ (VTK rasterizes it
    # with float-recomputed matrices in a capture: its outline and facet edges move); a
    # restarted one-sample frame would change the volume's pixels everywhere.
    changed = np.any(captures[0] != before, axis=-1)
    plotter.renderer.GetVolumes().GetItemAsObject(0).SetVisibility(False)
    mesh = np.any(plotter.screenshot().astype(int) != 255, axis=-1)
    near_mesh = mesh.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            near_mesh |= np.roll(np.roll(mesh, dy, 0), dx, 1)
    assert not np.any(changed & ~near_mesh), int(np.sum(changed & ~near_mesh))
    plotter.close()
