"""pyvista's own pick callbacks on a segmentation (the README lists which see it): the pickers that
go through VTK's prop picking or the depth buffer (picker="prop", "world"; pick_click_position,
pick_mouse_position with the interactor's default picker) report the segmentation where it is the
nearest thing under the mouse, a mesh where that is nearer, and nothing over the background.

The reference for every pick is the mapper's own Pick (checked against the CPU ray caster in
test_mapper.py), and the mesh's position from its geometry.
"""
import numpy as np
import pytest

W, H = 200, 150


def scene():
    """An off-screen plotter: two label boxes, and a small sphere in front of part of them."""
    import pyvista as pv

    import vtksvdag

    labels = np.zeros((40, 40, 40), np.uint16)  # [x, y, z]
    labels[10:25, 8:30, 5:20] = 3
    labels[20:38, 12:25, 15:35] = 7
    plotter = pv.Plotter(off_screen=True, window_size=(W, H))
    actor = vtksvdag.add_segmentation(plotter, labels, spp=1)
    sphere = plotter.add_mesh(pv.Sphere(radius=3, center=(30, 2, 30)), color="green")
    plotter.camera_position = [(30, -80, 40), (22, 20, 20), (0, 0, 1)]
    plotter.show(auto_close=False)  # off screen: renders once and returns
    return plotter, actor, sphere


def display_of(plotter, world):
    renderer = plotter.renderer
    renderer.SetWorldPoint(*world, 1.0)
    renderer.WorldToDisplay()
    return renderer.GetDisplayPoint()[:2]


@pytest.fixture(scope="module")
def picked_scene():
    plotter, actor, sphere = scene()
    yield plotter, actor, sphere
    plotter.close()


def pixels_to_try(plotter, actor, sphere):
    """A pixel on the segmentation, one on the sphere (in front of the volume's bounds) and one on
    the background, found with the mapper's Pick and the sphere's projection."""
    mapper = actor.GetMapper()
    on_volume = next((x, y) for y in range(H // 2, H) for x in range(W // 2, W)
                     if mapper.Pick(plotter.renderer, x + 0.5, y + 0.5))
    sx, sy = display_of(plotter, sphere.GetCenter())
    on_sphere = (int(sx), int(sy))
    background = (2, 2)
    assert not mapper.Pick(plotter.renderer, 2.5, 2.5)
    return on_volume, on_sphere, background


@pytest.mark.parametrize("picker", ["prop", "world"])
def test_enable_point_picking_sees_the_segmentation(picked_scene, picker):
    plotter, actor, sphere = picked_scene
    on_volume, on_sphere, background = pixels_to_try(plotter, actor, sphere)
    mapper = actor.GetMapper()
    picks = []
    # The picker is one object: what it picked is read in the callback.
    prop_of = (lambda p: p.GetViewProp()) if picker == "prop" else (lambda p: None)
    plotter.enable_point_picking(callback=lambda point, p: picks.append((np.array(point), prop_of(p))),
                                 picker=picker, use_picker=True, show_point=False,
                                 show_message=False, pickable_window=True)
    try:
        for x, y in (on_volume, on_sphere, background):
            plotter.iren._mouse_right_button_click(x, y)
        assert len(picks) == 3
        # On the segmentation: the picked point is the voxel surface under the pixel.
        assert mapper.Pick(plotter.renderer, on_volume[0] + 0.5, on_volume[1] + 0.5)
        position = [0.0] * 3
        mapper.GetPickedPosition(position)
        np.testing.assert_allclose(picks[0][0], position, atol=0.6)  # within a voxel
        # On the sphere: a point of its surface.
        assert abs(np.linalg.norm(picks[1][0] - np.array(sphere.GetCenter())) - 3) < 0.3
        if picker == "prop":
            assert picks[0][1] is actor
            assert picks[1][1] is sphere
            assert picks[2][1] is None
    finally:
        plotter.disable_picking()


def test_pick_click_position_lands_on_the_segmentation(picked_scene):
    plotter, actor, sphere = picked_scene
    on_volume, _, _ = pixels_to_try(plotter, actor, sphere)
    mapper = actor.GetMapper()
    plotter.iren._mouse_left_button_click(*on_volume)
    position = np.array(plotter.pick_click_position())
    assert mapper.Pick(plotter.renderer, on_volume[0] + 0.5, on_volume[1] + 0.5)
    expected = [0.0] * 3
    mapper.GetPickedPosition(expected)
    np.testing.assert_allclose(position, expected, atol=0.6)
    label = mapper.GetPickedLabel()
    assert label in (3, 7)
