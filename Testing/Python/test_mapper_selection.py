"""VTK's standard picking (vtkPropPicker, vtkHardwareSelector, pyvista's pick helpers) with the
segmentation volume (vtkSegmentationSVDAGVolumeMapper's selection renders).

The scene: two overlapping boxes of labels and a sphere mesh in front of part of them. The
independent references: the CPU ray caster (vtkSegmentationSVDAGRayCaster) through each pixel
center, its hit converted to window depth, against the window depth of the mesh rendered alone
(no multisampling, as selection renders draw).
"""
import numpy as np
import pytest
import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL factory overrides)
from conftest import (two_boxes, mesh_actor, caster_pick, capture_errors, compress_zyx, display_to_world, mapper_pick,
                      mapper_scene, pixel_ray)
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkFloatArray
from vtkmodules.vtkCommonDataModel import vtkDataObject, vtkPlane, vtkSelectionNode
from vtkmodules.vtkFiltersSources import vtkSphereSource
from vtkmodules.vtkRenderingCore import vtkPropPicker, vtkWindowToImageFilter
from vtkmodules.vtkRenderingOpenGL2 import vtkOpenGLHardwareSelector

from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGRayCaster

W, H = 200, 150
LABELS = (3, 7)



@pytest.fixture(scope="module")
def boxes():
    labels = two_boxes()
    return labels, compress_zyx(labels)


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
    return vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars()).reshape(H, W, -1).copy()


def window_depth(renderer, point):
    renderer.SetWorldPoint(*point, 1.0)
    renderer.WorldToDisplay()
    return renderer.GetDisplayPoint()[2]


def scene_with_sphere(svdag, msaa=8):
    window, renderer, volume, mapper = mapper_scene(svdag, size=(W, H))
    window.SetMultiSamples(msaa)
    sphere = vtkSphereSource()
    sphere.SetCenter(30, 10, 35)
    sphere.SetRadius(6)
    sphere.SetThetaResolution(48)
    sphere.SetPhiResolution(48)
    actor = mesh_actor(sphere)
    renderer.AddActor(actor)
    return window, renderer, volume, mapper, actor


def expected_map(window, renderer, volume, actor, caster):
    """Per pixel: 'volume', 'mesh' or None, the caster's (label, position, voxel) and the mesh's
    window depth, from the mesh rendered alone without multisampling and the ray caster."""
    samples = window.GetMultiSamples()
    window.SetMultiSamples(0)
    volume.SetVisibility(0)
    window.Render()
    mesh_depth = zbuffer(window)
    volume.SetVisibility(1)
    window.SetMultiSamples(samples)
    kind = np.full((H, W), None, object)
    hits = {}
    for y in range(H):
        for x in range(W):
            origin, direction = pixel_ray(renderer, x, y)
            hit = caster_pick(caster, origin, direction)
            volume_depth = 1.0 if hit is None else window_depth(renderer, hit[1])
            if hit is not None:
                hits[x, y] = (hit[0], hit[1], tuple(caster.GetHitVoxel()), volume_depth)
            if min(volume_depth, mesh_depth[y, x]) >= 1.0:
                continue
            kind[y, x] = "volume" if volume_depth <= mesh_depth[y, x] else "mesh"
    return kind, hits, mesh_depth


def unambiguous(kind, hits, mesh_depth):
    """Pixels whose 3x3 neighbourhood has one kind (and label) and whose volume and mesh depths
    are not within 1e-4 of each other: elsewhere a sub-pixel or rounding difference may flip it."""
    key = np.empty((H, W), object)
    for y in range(H):
        for x in range(W):
            key[y, x] = (kind[y, x], hits[x, y][0] if kind[y, x] == "volume" else None)
    ok = np.zeros((H, W), bool)
    for y in range(1, H - 1):
        for x in range(1, W - 1):
            block = key[y - 1:y + 2, x - 1:x + 2].ravel()
            tie = (x, y) in hits and abs(hits[x, y][3] - mesh_depth[y, x]) < 1e-4
            ok[y, x] = all(b == key[y, x] for b in block) and not tie
    return ok


def make_caster(svdag):
    caster = vtkSegmentationSVDAGRayCaster()
    caster.SetInputData(svdag)
    return caster


def prop_picks(renderer, volume, actor, step):
    picker = vtkPropPicker()
    got = {}
    for y in range(step // 2, H, step):
        for x in range(step // 2, W, step):
            picked = picker.PickProp(x, y, renderer)
            prop = picker.GetViewProp()
            name = "volume" if prop is volume else ("mesh" if prop is actor else prop)
            got[x, y] = (name if picked else None, np.array(picker.GetPickPosition()))
    return got


def check_prop_picks(got, kind, hits, ok, mapper, renderer):
    checked = {"volume": 0, "mesh": 0, None: 0}
    wrong = []
    for (x, y), (name, position) in got.items():
        if not ok[y, x]:
            continue
        checked[kind[y, x]] += 1
        if name != kind[y, x]:
            wrong.append(((x, y), kind[y, x], name))
            continue
        if name == "volume":
            label, hit_depth = hits[x, y][0], hits[x, y][3]
            # vtkWorldPointPicker's position: display point (x, y) (the pixel's corner) at the
            # depth read there, so the ray caster's hit depth within the depth buffer's 24 bits.
            expected = display_to_world(renderer, x, y, hit_depth)
            assert np.linalg.norm(position - expected) <= 0.02, ((x, y), position, expected)
            # ... and the label one call away.
            picked = mapper_pick(mapper, renderer, x + 0.5, y + 0.5)
            assert picked is not None and picked[0] == label, ((x, y), picked, label)
    assert not wrong, f"{len(wrong)} pixels, e.g. (pixel, expected, picked) {wrong[:5]}"
    return checked


# 1 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("msaa", [0, 8])
def test_prop_picker_reports_volume_mesh_or_nothing(boxes, msaa):
    _, svdag = boxes
    window, renderer, volume, mapper, actor = scene_with_sphere(svdag, msaa)
    kind, hits, mesh_depth = expected_map(window, renderer, volume, actor, make_caster(svdag))
    ok = unambiguous(kind, hits, mesh_depth)
    window.Render()
    checked = check_prop_picks(prop_picks(renderer, volume, actor, 4), kind, hits, ok,
                               mapper, renderer)
    assert checked["volume"] > 150 and checked["mesh"] > 20 and checked[None] > 500, checked


def test_prop_picker_before_any_render_and_after_camera_move(boxes):
    """The first render of the window may be the pick's own; a moved camera is traced anew."""
    _, svdag = boxes
    window, renderer, volume, mapper, actor = scene_with_sphere(svdag, 0)
    picker = vtkPropPicker()
    assert picker.PickProp(100, 75, renderer) == 1
    assert picker.GetViewProp() in (volume, actor)
    camera = renderer.GetActiveCamera()
    camera.Azimuth(25)
    camera.SetClippingRange(20.0, 300.0)
    kind, hits, mesh_depth = expected_map(window, renderer, volume, actor, make_caster(svdag))
    ok = unambiguous(kind, hits, mesh_depth)
    # No ordinary render at this view before the picks.
    check_prop_picks(prop_picks(renderer, volume, actor, 6), kind, hits, ok, mapper, renderer)


# 2 ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("association", ["cells", "points"])
def test_hardware_selector_names_visible_labels_and_voxels(boxes, association):
    labels, svdag = boxes
    window, renderer, volume, mapper, actor = scene_with_sphere(svdag)
    kind, hits, mesh_depth = expected_map(window, renderer, volume, actor, make_caster(svdag))
    window.Render()
    selector = vtkOpenGLHardwareSelector()
    selector.SetRenderer(renderer)
    selector.SetArea(0, 0, W - 1, H - 1)
    selector.SetFieldAssociation(vtkDataObject.FIELD_ASSOCIATION_CELLS if association == "cells"
                                 else vtkDataObject.FIELD_ASSOCIATION_POINTS)
    selection = selector.Select()
    pixels, voxels = {}, {}
    mesh_nodes = 0
    for i in range(selection.GetNumberOfNodes()):
        node = selection.GetNode(i)
        properties = node.GetProperties()
        prop = properties.Get(vtkSelectionNode.PROP())
        if prop is actor:
            mesh_nodes += 1
            continue
        assert prop is volume
        label = mapper.GetLabelForCompositeIndex(properties.Get(vtkSelectionNode.COMPOSITE_INDEX()))
        assert label not in pixels, "one node per label"
        pixels[label] = properties.Get(vtkSelectionNode.PIXEL_COUNT())
        voxels[label] = set(vtk_to_numpy(node.GetSelectionList()).tolist())
    assert mesh_nodes == 1
    visible = {}
    for y in range(H):
        for x in range(W):
            if kind[y, x] == "volume":
                visible.setdefault(hits[x, y][0], []).append(hits[x, y][2])
    assert set(pixels) == set(visible) == set(LABELS)
    flat = labels.ravel()
    for label, seen in visible.items():
        # Pixel counts agree but for silhouette and tie pixels.
        assert abs(pixels[label] - len(seen)) <= 0.03 * len(seen), (label, pixels[label], len(seen))
        # The ids are voxels of that label (the input image's point ids i + nx (j + ny k)) ...
        ids = np.array(sorted(voxels[label]))
        assert np.all(flat[ids] == label), label
        # ... the voxels the ray caster hits through the visible pixels.
        expected = {i + 40 * (j + 40 * k) for i, j, k in seen}
        overlap = len(expected & voxels[label]) / len(expected | voxels[label])
        assert overlap >= 0.9, (label, overlap)


def test_label_for_composite_index_errors(boxes):
    _, svdag = boxes
    _, _, _, mapper = mapper_scene(svdag, size=(W, H))
    assert [mapper.GetLabelForCompositeIndex(i) for i in (1, 2)] == list(LABELS)
    errors = capture_errors(mapper)
    assert mapper.GetLabelForCompositeIndex(0) == 0
    assert mapper.GetLabelForCompositeIndex(3) == 0
    assert len(errors) == 2 and "names no label" in errors[0], errors


# 3 ---------------------------------------------------------------------------------------------
def test_picking_leaves_the_image_and_refinement(boxes):
    _, svdag = boxes
    window, renderer, volume, mapper, actor = scene_with_sphere(svdag)
    mapper.SetTargetSamplesPerPixel(8)
    mapper.RenderUntilConverged(window, 60.0)
    assert mapper.IsConverged() and mapper.GetAccumulatedSamples() == 8
    before_color, before_depth = rgb(window), zbuffer(window)
    prop_picks(renderer, volume, actor, 25)
    selector = vtkOpenGLHardwareSelector()
    selector.SetRenderer(renderer)
    selector.SetArea(0, 0, W - 1, H - 1)
    selector.Select()
    assert mapper.GetAccumulatedSamples() == 8 and mapper.IsConverged()
    window.Render()
    np.testing.assert_array_equal(rgb(window), before_color)
    np.testing.assert_array_equal(zbuffer(window), before_depth)


# 4 ---------------------------------------------------------------------------------------------
def test_hidden_label_is_not_picked(boxes):
    labels, svdag = boxes
    window, renderer, volume, mapper, actor = scene_with_sphere(svdag)
    mapper.GetLabelProperties().SetVisibility(7, False)
    # The reference: the volume compressed without label 7.
    reference = compress_zyx(labels, excluded=(7,))
    kind, hits, mesh_depth = expected_map(window, renderer, volume, actor, make_caster(reference))
    ok = unambiguous(kind, hits, mesh_depth)
    window.Render()
    got = prop_picks(renderer, volume, actor, 4)
    checked = check_prop_picks(got, kind, hits, ok, mapper, renderer)
    assert checked["volume"] > 50
    selector = vtkOpenGLHardwareSelector()
    selector.SetRenderer(renderer)
    selector.SetArea(0, 0, W - 1, H - 1)
    selection = selector.Select()
    seen = {mapper.GetLabelForCompositeIndex(n.GetProperties().Get(vtkSelectionNode.COMPOSITE_INDEX()))
            for n in (selection.GetNode(i) for i in range(selection.GetNumberOfNodes()))
            if n.GetProperties().Get(vtkSelectionNode.PROP()) is volume}
    assert seen == {3}


def test_clipped_part_is_not_picked(boxes):
    _, svdag = boxes
    window, renderer, volume, mapper, actor = scene_with_sphere(svdag)
    origin, normal = (0.0, 0.0, 22.0), (0.3, 0.0, -1.0)
    plane = vtkPlane()
    plane.SetOrigin(origin)
    plane.SetNormal(normal)
    mapper.AddClippingPlane(plane)
    caster = make_caster(svdag)
    assert caster.AddClippingPlane(origin, normal) == 1
    kind, hits, mesh_depth = expected_map(window, renderer, volume, actor, caster)
    ok = unambiguous(kind, hits, mesh_depth)
    window.Render()
    checked = check_prop_picks(prop_picks(renderer, volume, actor, 4), kind, hits, ok,
                               mapper, renderer)
    assert checked["volume"] > 50
    # Every volume pick lies on the kept side.
    assert all(np.dot(np.array(h[1]) - origin, normal) >= -1e-6 for h in hits.values())
