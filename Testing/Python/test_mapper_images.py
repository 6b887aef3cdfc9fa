"""Image regression of the volume mapper in pyvista (pytest-pyvista's ``verify_image_cache``).

Baselines live in ``Testing/Data/Baseline/pyvista`` (``Testing/Python/pytest.ini``); each was
looked at before it was committed. Every test also checks values independently of its baseline:
the label, position and normal under display pixels against the CPU ray caster
(``vtkSegmentationSVDAGRayCaster``, the same traversal code run on the CPU), cast along the ray
VTK's own display-to-world transform gives for that pixel, in the volume's model coordinates.
Scenes: each LOD, a path-traced scene (fixed seed and samples), a mesh cutting the volume, label
colors / opacity / hidden labels, parallel projection, the camera inside the volume, anisotropic
spacing with a rotated direction matrix and a vtkVolume user matrix, two volumes in one renderer
and two subplots.
"""
import numpy as np
import pytest
import pyvista as pv
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonMath import vtkMatrix4x4

import vtksvdag
from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGRayCaster

SIZE = (240, 180)
SPP = 8


def scene_labels(n=40):
    """A slab (label 3), a ball (label 7) and a thin rod (label 12), indexed [x, y, z]."""
    x, y, z = np.mgrid[0:n, 0:n, 0:n]
    labels = np.zeros((n, n, n), np.uint16)
    labels[((x - 26) ** 2 + (y - 20) ** 2 + (z - 20) ** 2) < 12**2] = 7
    labels[x < 9] = 3
    labels[(np.abs(y - 30) < 2) & (np.abs(z - 30) < 2) & (x >= 9)] = 12
    return labels


def new_plotter(**kwargs):
    plotter = pv.Plotter(off_screen=True, window_size=SIZE, **kwargs)
    plotter.set_background("#1a1a1f")
    return plotter


def model_matrix(actor):
    m = vtkMatrix4x4()
    m.DeepCopy(actor.GetMatrix())
    return np.array([[m.GetElement(r, c) for c in range(4)] for r in range(4)])


def cpu_pick(renderer, actor, x, y, lod=2):
    """Label value, world position and world normal the CPU ray caster finds under a display
    pixel center, or None."""
    points = []
    for depth in (0.0, 1.0):
        renderer.SetDisplayPoint(x + 0.5, y + 0.5, depth)
        renderer.DisplayToWorld()
        w = np.array(renderer.GetWorldPoint())
        points.append(w[:3] / w[3])
    matrix = model_matrix(actor)
    inverse = np.linalg.inv(matrix)
    near, far = (inverse @ np.append(p, 1.0) for p in points)
    near, far = near[:3] / near[3], far[:3] / far[3]
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(actor.GetMapper().GetInput())
    caster.SetLOD(lod)
    caster.SetMaximumDistance(float(np.linalg.norm(far - near)))
    if not caster.CastRay(list(near), list(far - near)):
        return None
    position = np.array(caster.GetHitPosition())
    normal = np.array(caster.GetHitNormal())
    world = (matrix @ np.append(position, 1.0))[:3]
    world_normal = np.linalg.inv(matrix[:3, :3]).T @ normal
    if np.linalg.norm(world_normal) > 0:
        world_normal /= np.linalg.norm(world_normal)
    value = int(vtk_to_numpy(caster.GetHitLabelValue())[0])
    return value, world, world_normal


def assert_picks_match_cpu(plotter, actor, renderer_index=0, lod=2, step=23, minimum_hits=5):
    """Mapper picks equal the CPU ray caster on a grid of pixels of one renderer."""
    plotter.renderers[renderer_index]  # the subplot must exist
    renderer = plotter.renderers[renderer_index]
    mapper = actor.GetMapper()
    width, height = plotter.window_size
    x0, y0, x1, y1 = (int(v) for v in np.array(renderer.GetViewport()) * [width, height, width, height])
    hits = agree = total = 0
    for y in range(y0 + 3, y1 - 3, step):
        for x in range(x0 + 3, x1 - 3, step):
            total += 1
            expected = cpu_pick(renderer, actor, x, y, lod)
            got = mapper.Pick(renderer, x + 0.5, y + 0.5)
            if expected is None:
                agree += not got
                continue
            hits += 1
            if not got:
                continue
            position, normal = [0.0] * 3, [0.0] * 3
            mapper.GetPickedPosition(position)
            mapper.GetPickedNormal(normal)
            scale = np.abs(model_matrix(actor)[:3, :3]).max() * 1e-3 + 1e-3
            if (mapper.GetPickedLabel() == expected[0]
                    and np.allclose(position, expected[1], atol=scale * 10)
                    and np.allclose(normal, expected[2], atol=1e-3)):
                agree += 1
    assert hits >= minimum_hits, "the view must see the volume"
    # Pixel centers exactly on a voxel edge may resolve to either neighbour in float precision.
    assert agree >= total - max(1, total // 100), f"{total - agree} of {total} picks disagree"


def window_depth(plotter):
    """The render window's depth buffer (window depth in [0, 1]) as a (height, width) array."""
    from vtkmodules.vtkCommonCore import vtkFloatArray

    width, height = plotter.window_size
    values = vtkFloatArray()
    plotter.render_window.GetZbufferData(0, 0, width - 1, height - 1, values)
    return vtk_to_numpy(values).reshape(height, width)


def show(plotter, verify_image_cache):
    stats = vtksvdag.refine(plotter, timeout=60)
    assert all(s["converged"] for s in stats)
    plotter.show(auto_close=False)
    return stats


@pytest.mark.parametrize("lod", ["block", "leaf", "voxel"])
def test_lod(verify_image_cache, lod):
    plotter = new_plotter()
    actor = vtksvdag.add_segmentation(plotter, scene_labels(), lod=lod, spp=SPP, seed=1)
    plotter.camera_position = [(70, 60, 110), (20, 20, 20), (0, 1, 0)]
    show(plotter, verify_image_cache)
    assert_picks_match_cpu(plotter, actor, lod={"block": 0, "leaf": 1, "voxel": 2}[lod])
    plotter.close()


def test_path_traced(verify_image_cache):
    plotter = new_plotter()
    actor = vtksvdag.add_segmentation(
        plotter, scene_labels(), colors={3: "steelblue", 7: "gold", 12: "white"},
        sun={"direction": (0.4, 0.8, 0.5), "irradiance": 3.0}, environment=(0.3, 0.32, 0.36),
        spp=32, bounces=4, seed=3, lod="voxel")
    plotter.camera_position = [(80, 70, 100), (20, 20, 20), (0, 1, 0)]
    stats = show(plotter, verify_image_cache)
    assert stats[0]["samples"] == 32
    assert 0 < stats[0]["error"] < 0.05
    assert_picks_match_cpu(plotter, actor)
    plotter.close()


def mesh_scene(mesh=True, volume=True):
    """A rod mesh crossing the ball's surface (in front of it at one end, behind it at the other)."""
    plotter = new_plotter()
    if mesh:
        rod = pv.Cylinder(center=(26, 20, 20), direction=(1, 1, 0.3), radius=3, height=60)
        plotter.add_mesh(rod, color="tomato")
    if volume:
        vtksvdag.add_segmentation(plotter, scene_labels(), spp=SPP, seed=1, lod="voxel")
    plotter.camera_position = [(60, 50, 110), (20, 20, 20), (0, 1, 0)]
    return plotter


def depth_at_common_clipping(plotter):
    """The window depth with the same near and far planes in every scene (show() resets them to
    each scene's bounds), refined."""
    plotter.camera.clipping_range = (60, 180)
    vtksvdag.refine(plotter)
    return window_depth(plotter)


def test_mesh_cuts_volume(verify_image_cache):
    plotter = mesh_scene()
    show(plotter, verify_image_cache)
    composited = depth_at_common_clipping(plotter)
    # The same view without the volume, then without the mesh: the composited window depth is
    # the nearer of the two on every pixel, exactly (rays run a hair past the mesh's surface and
    # the nearer depth is chosen in window depth; see the mapper).
    references = []
    for scene in (mesh_scene(volume=False), mesh_scene(mesh=False)):
        references.append(depth_at_common_clipping(scene))  # never shown: no regression image
        scene.close()
    mesh_only, volume_only = references
    both = (mesh_only < 1) & (volume_only < 1)
    assert both.sum() > 100, "the mesh and the volume must overlap"
    assert (mesh_only < volume_only)[both].any() and (volume_only < mesh_only)[both].any()
    np.testing.assert_array_equal(composited, np.minimum(mesh_only, volume_only))
    plotter.close()


def test_label_appearance(verify_image_cache):
    plotter = new_plotter()
    actor = vtksvdag.add_segmentation(
        plotter, scene_labels(), colors={7: "gold"}, cmap="tab10", opacity={3: 0.4},
        hidden_labels=[12], spp=SPP, seed=1, lod="voxel")
    plotter.camera_position = [(70, 60, 110), (20, 20, 20), (0, 1, 0)]
    show(plotter, verify_image_cache)
    mapper = actor.GetMapper()
    renderer = plotter.renderer
    # The hidden rod is never picked: against the CPU ray caster on a volume without it.
    hidden = scene_labels()
    hidden[hidden == 12] = 0
    reference = vtksvdag.add_segmentation(new_plotter(), hidden)
    for y in range(3, SIZE[1] - 3, 11):
        for x in range(3, SIZE[0] - 3, 11):
            if mapper.Pick(renderer, x + 0.5, y + 0.5):
                assert mapper.GetPickedLabel() != 12
    assert reference.GetMapper().GetInput().GetNumberOfLabels() == 2
    props = mapper.GetLabelProperties()
    assert props.GetVisibility(12) is False and props.GetOpacity(3) == pytest.approx(0.4)
    rgb = [0.0] * 3
    assert props.GetColor(7, rgb) and np.allclose(rgb, pv.Color("gold").float_rgb)
    plotter.close()


def test_parallel_projection(verify_image_cache):
    plotter = new_plotter()
    actor = vtksvdag.add_segmentation(plotter, scene_labels(), spp=SPP, seed=1, lod="voxel")
    plotter.camera_position = [(70, 60, 110), (20, 20, 20), (0, 1, 0)]
    plotter.enable_parallel_projection()
    plotter.camera.parallel_scale = 28
    show(plotter, verify_image_cache)
    assert_picks_match_cpu(plotter, actor)
    plotter.close()


def test_camera_inside_volume(verify_image_cache):
    plotter = new_plotter()
    labels = scene_labels()
    actor = vtksvdag.add_segmentation(plotter, labels, spp=SPP, seed=1, lod="voxel")
    # Inside the empty region between the slab and the ball, looking at the slab.
    plotter.camera_position = [(16, 8, 34), (0, 20, 10), (0, 0, 1)]
    plotter.camera.view_angle = 70
    plotter.renderer.ResetCameraClippingRange()
    show(plotter, verify_image_cache)
    assert labels[16, 8, 34] == 0
    assert_picks_match_cpu(plotter, actor)
    plotter.close()


def test_anisotropic_rotated_user_matrix(verify_image_cache):
    plotter = new_plotter()
    angle = np.radians(25)
    direction = [[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]]
    volume = vtksvdag.from_numpy(scene_labels(), spacing=(1.0, 0.6, 2.5), origin=(-10, 5, 3),
                                 direction=direction)
    actor = vtksvdag.add_segmentation(plotter, volume, spp=SPP, seed=1, lod="voxel")
    user = vtkMatrix4x4()
    for r, row in enumerate([[0.8, 0, 0.2, 4], [0, 1.1, 0, -3], [-0.1, 0, 0.9, 2], [0, 0, 0, 1]]):
        for c, value in enumerate(row):
            user.SetElement(r, c, value)
    actor.SetUserMatrix(user)
    actor.SetPosition(2, 1, 0)
    plotter.reset_camera()
    plotter.camera.azimuth = 30
    plotter.camera.elevation = 20
    plotter.renderer.ResetCameraClippingRange()
    show(plotter, verify_image_cache)
    assert_picks_match_cpu(plotter, actor, step=17)
    plotter.close()


def test_two_volumes_one_renderer(verify_image_cache):
    plotter = new_plotter()
    first = vtksvdag.add_segmentation(plotter, scene_labels(), spp=SPP, seed=1, lod="voxel")
    second_labels = np.zeros((24, 24, 24), np.uint8)
    second_labels[4:20, 4:20, 4:20] = 200
    second = vtksvdag.add_segmentation(plotter, second_labels, colors={200: "orchid"},
                                       spp=SPP, seed=1, lod="voxel")
    second.SetPosition(30, 10, 30)  # overlaps the first volume's ball in depth
    plotter.camera_position = [(90, 70, 120), (30, 25, 30), (0, 1, 0)]
    plotter.renderer.ResetCameraClippingRange()
    show(plotter, verify_image_cache)
    found = set()
    width, height = SIZE
    for y in range(2, height - 2, 7):
        for x in range(2, width - 2, 7):
            hit = vtksvdag.pick(plotter, x + 0.5, y + 0.5)
            if hit is None:
                continue
            found.add(hit["label"])
            expected = [cpu_pick(plotter.renderer, a, x, y) for a in (first, second)]
            expected = [e for e in expected if e is not None]
            camera = np.array(plotter.camera.position)
            nearest = min(expected, key=lambda e: np.linalg.norm(e[1] - camera))
            assert hit["label"] == nearest[0]
    assert {7, 200} <= found
    plotter.close()


def test_two_subplots(verify_image_cache):
    plotter = new_plotter(shape=(1, 2))
    plotter.subplot(0, 0)
    left = vtksvdag.add_segmentation(plotter, scene_labels(), spp=SPP, seed=1, lod="voxel")
    plotter.camera_position = [(70, 60, 110), (20, 20, 20), (0, 1, 0)]
    plotter.subplot(0, 1)
    right_labels = np.zeros((20, 20, 20), np.int16)
    right_labels[2:18, 5:15, 2:18] = -4
    right = vtksvdag.add_segmentation(plotter, right_labels, colors={-4: "seagreen"}, spp=SPP,
                                      seed=1, lod="voxel")
    plotter.camera_position = [(40, 30, 50), (10, 10, 10), (0, 1, 0)]
    show(plotter, verify_image_cache)
    assert_picks_match_cpu(plotter, left, renderer_index=0, step=13)
    assert_picks_match_cpu(plotter, right, renderer_index=1, step=13)
    hit = vtksvdag.pick(plotter, SIZE[0] * 0.75, SIZE[1] * 0.5)
    assert hit is not None and hit["label"] == -4
    plotter.close()
