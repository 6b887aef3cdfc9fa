"""The compute backend's step statistics (vtkSegmentationSVDAGRenderer StepStatistics,
Traversal.h's SVDAG_STAT_* counters) against counts worked out by hand.

A 64 x 16 x 16 volume is a row of four 16^3 cells along x: cell 0 empty, cell 1 holding one
block (label 2: two single voxels at opposite corners, so its box is the whole cell and the DAG
is almost empty), cell 2 empty, cell 3 full of label 1. The camera looks along +x through the
cells' centre line (y = z = 8 in VTK coordinates, the middle of an odd-sized image, so that the
centre pixel's ray is exactly the x axis), with no bounce: that pixel traces one ray, which
visits 4 cells, 2 of them with a block, reads 2 block records, walks 2 DAGs and hits. Its DAG
walk iterations: in label 2's block the ray runs through the empty root octant 6 (x 0..7 of the
cell, one step), then in octant 7 through the mid node's empty children 0 and 1 (x 8..11 and
12..15, one step each) and leaves the block; label 1's full root is solid at the first step:
3 + 1 = 4.
"""
import numpy as np
import pytest
from conftest import compress_zyx as build
from vtkmodules.util.numpy_support import vtk_to_numpy

from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGRenderer

SIZE = 33  # odd: pixel (16, 16) looks exactly along the camera's axis
NAMES = ("rays", "cells", "cells_with_blocks", "blocks", "dag_walks", "dag_steps", "shadow_rays",
         "hits")


@pytest.fixture(scope="module")
def row_of_cells():
    labels = np.zeros((16, 16, 64), np.uint16)  # z, y, x
    labels[0, 0, 16] = 2
    labels[15, 15, 31] = 2
    labels[:, :, 48:] = 1
    return build(labels)


def render(volume, statistics, bounces=0, denoise=False):
    r = vtkSegmentationSVDAGRenderer()
    r.SetInputData(volume)
    r.SetWidth(SIZE)
    r.SetHeight(SIZE)
    s = r.GetSettings()
    s.SetBackend("compute")
    s.SetLOD(s.LOD_VOXEL)
    s.SetMaximumBounces(bounces)
    s.SetDenoise(denoise)
    r.SetCameraPosition(-40.0, 8.0, 8.0)
    r.SetCameraFocalPoint(0.0, 8.0, 8.0)
    r.SetCameraViewUp(0.0, 1.0, 0.0)
    r.SetCameraViewAngle(20.0)
    r.SetStepStatistics(statistics)
    assert r.Render() == 1
    return r


def counts(renderer):
    array = renderer.GetStepCounts()
    assert [array.GetComponentName(c) for c in range(array.GetNumberOfComponents())] == list(NAMES)
    return vtk_to_numpy(array).reshape(-1, len(NAMES)) if array.GetNumberOfTuples() else \
        np.zeros((0, len(NAMES)), np.uint32)


def test_axis_ray_counts_by_hand(row_of_cells):
    r = render(row_of_cells, True)
    c = counts(r)
    assert c.shape == (SIZE * SIZE, len(NAMES))
    centre = dict(zip(NAMES, c[16 + SIZE * 16].tolist()))
    assert centre == dict(rays=1, cells=4, cells_with_blocks=2, blocks=2, dag_walks=2, dag_steps=4,
                          shadow_rays=0, hits=1)
    label = vtk_to_numpy(r.GetOutput().GetPointData().GetArray("Label"))
    assert label[16 + SIZE * 16] == 1 + 0  # label index 0 (label 1) + 1


def test_counters_consistent_and_off_changes_nothing(row_of_cells):
    on = render(row_of_cells, True, bounces=1)
    c = counts(on)
    by = {n: c[:, i].astype(np.int64) for i, n in enumerate(NAMES)}
    # Every pixel traces its camera ray; a hit with a bounce adds at most its shadow ray and its
    # continuation's walk.
    assert np.all(by["rays"] >= 1)
    label = vtk_to_numpy(on.GetOutput().GetPointData().GetArray("Label"))
    assert np.array_equal(by["hits"] >= 1, label != 0) or np.all(by["hits"][label != 0] >= 1)
    assert np.all(by["shadow_rays"] <= by["rays"]) and np.all(by["hits"] <= by["rays"])
    assert np.all(by["cells_with_blocks"] <= by["cells"])
    assert np.all(by["blocks"] >= by["cells_with_blocks"]) and np.all(by["dag_walks"] <= by["blocks"])
    assert np.all(by["dag_steps"] >= by["dag_walks"])
    # A ray that hits walked at least one DAG; rays that miss the volume visit no cell.
    assert np.all(by["dag_walks"][label != 0] >= 1)
    # Off: nothing counted, and the image is the same as with the counters on.
    off = render(row_of_cells, False, bounces=1)
    assert off.GetStepCounts().GetNumberOfTuples() == 0
    for name in ("Label", "Depth", "HDR"):
        a = vtk_to_numpy(on.GetOutput().GetPointData().GetArray(name))
        b = vtk_to_numpy(off.GetOutput().GetPointData().GetArray(name))
        assert np.array_equal(a, b), name


def test_denoiser_coverage_rays_are_not_counted(row_of_cells):
    """With the denoiser on, the first pass also traces the edges' coverage rays (a dispatch of its
    own): the counters stay the frame's rays', the same as with the denoiser off."""
    off, on = render(row_of_cells, True), render(row_of_cells, True, denoise=True)
    label = vtk_to_numpy(on.GetOutput().GetPointData().GetArray("Label"))
    assert len(set(label.tolist())) > 1  # there are edges to cover
    np.testing.assert_array_equal(counts(on), counts(off))


def test_ray_tracing_backend_counts_nothing(row_of_cells):
    r = vtkSegmentationSVDAGRenderer()
    r.SetInputData(row_of_cells)
    r.SetWidth(8)
    r.SetHeight(8)
    r.GetSettings().SetBackend("rt")
    r.SetStepStatistics(True)
    assert r.ResetCamera() == 1
    if r.Render() != 1 or r.GetBackendInUse() != "rt":
        pytest.skip("the ray tracing backend is not available here")
    assert r.GetStepCounts().GetNumberOfTuples() == 0
