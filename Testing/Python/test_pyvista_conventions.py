"""pyvista's conventions in add_segmentation / from_numpy / from_image / read (issue 20, item 5):
scalars= for point and cell data, spacing=/origin=/axis_order= for numpy input, cast="exact",
"did you mean" for misspelled options, and errors that name the argument and its values.

Small volumes and 200x150 windows: the plotter tests run on lavapipe."""
import math

import nrrd
import numpy as np
import pytest

import vtksvdag
from vtksvdag._labels import FloatLabelsError

W, H = 200, 150


def labels_xyz(shape=(6, 5, 4), dtype=np.uint16):
    """[x, y, z] labels where every voxel differs: a wrong axis or offset cannot go unseen."""
    return (np.arange(np.prod(shape)).reshape(shape) % 7 + 1).astype(dtype)


@pytest.fixture
def plotter():
    import pyvista as pv

    p = pv.Plotter(off_screen=True, window_size=(W, H))
    yield p
    p.close()


# -- scalars= for ImageData: point data and cell data ---------------------------------------------
def test_point_scalars_by_name():
    import pyvista as pv

    labels = labels_xyz()
    grid = pv.ImageData(dimensions=labels.shape, spacing=(0.5, 1, 2), origin=(3, 4, 5))
    grid.point_data["seg"] = labels.ravel(order="F")
    grid.point_data["other"] = np.zeros(grid.n_points, np.uint8)  # the active scalars: not used
    grid.set_active_scalars("other")
    volume = vtksvdag.from_image(grid, scalars="seg")
    np.testing.assert_array_equal(volume.to_numpy(), labels)
    assert volume.spacing == (0.5, 1, 2) and volume.origin == (3, 4, 5)


def test_cell_scalars_are_the_voxel_grid():
    import pyvista as pv

    cells = labels_xyz((6, 5, 4), np.int16)
    # (7, 6, 5) points hold (6, 5, 4) cells.
    grid = pv.ImageData(dimensions=(7, 6, 5), spacing=(0.5, 1, 2), origin=(3, 4, 5))
    grid.cell_data["parcels"] = cells.ravel(order="F")
    volume = vtksvdag.from_image(grid, scalars="parcels")
    assert volume.dims == (6, 5, 4)
    np.testing.assert_array_equal(volume.to_numpy(), cells)
    # Voxel (0, 0, 0) is the first cell: centered half a spacing inside the image's origin,
    # so the voxel boxes are the cells and the bounds are the image's.
    np.testing.assert_allclose(volume.origin, (3.25, 4.5, 6.0))
    assert volume.spacing == (0.5, 1, 2)
    # The active cell scalars when no name is given (the image has no point scalars).
    np.testing.assert_array_equal(vtksvdag.from_image(grid).to_numpy(), cells)


def test_cell_scalars_follow_the_direction():
    import pyvista as pv

    cells = labels_xyz((3, 4, 2), np.uint8)
    grid = pv.ImageData(dimensions=(4, 5, 3), spacing=(2, 1, 1))
    rotation = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]], float)  # x axis along world y
    grid.direction_matrix = rotation
    grid.cell_data["c"] = cells.ravel(order="F")
    volume = vtksvdag.from_image(grid, scalars="c")
    np.testing.assert_allclose(volume.direction, rotation)
    # Half a voxel along each index axis: (1, 0.5, 0.5) in index space, rotated.
    np.testing.assert_allclose(volume.origin, rotation @ [1.0, 0.5, 0.5])
    np.testing.assert_array_equal(volume.to_numpy(), cells)


def test_point_name_wins_over_cell_name_and_missing_names_listed():
    import pyvista as pv

    grid = pv.ImageData(dimensions=(3, 3, 3))
    grid.point_data["seg"] = np.full(grid.n_points, 4, np.uint8)
    grid.cell_data["seg"] = np.full(grid.n_cells, 9, np.uint8)
    assert vtksvdag.from_image(grid, scalars="seg").labels.tolist() == [4]
    with pytest.raises(KeyError, match=r"no point data array 'nope' and no cell data array.*'seg'"):
        vtksvdag.from_image(grid, scalars="nope")


def test_add_segmentation_scalars(plotter):
    import pyvista as pv

    grid = pv.ImageData(dimensions=(17, 17, 17))
    cells = np.zeros((16, 16, 16), np.uint8)
    cells[2:14, 2:14, 2:14] = 6
    grid.cell_data["seg"] = cells.ravel(order="F")
    grid.point_data["noise"] = np.ones(grid.n_points, np.uint8)
    actor = vtksvdag.add_segmentation(plotter, grid, scalars="seg", spp=1)
    assert actor.segmentation.dims == (16, 16, 16)
    np.testing.assert_array_equal(actor.segmentation.to_numpy(), cells)
    vtksvdag.refine(plotter)
    assert vtksvdag.pick(plotter, W / 2, H / 2)["label"] == 6


# -- spacing=, origin=, axis_order= for numpy input ------------------------------------------------
def test_add_segmentation_numpy_geometry(plotter):
    labels = labels_xyz((6, 5, 4), np.uint8)
    actor = vtksvdag.add_segmentation(plotter, np.ascontiguousarray(labels.transpose(2, 1, 0)),
                                      spacing=(2, 3, 4), origin=(-1, 0, 1), axis_order="zyx", spp=1)
    volume = actor.segmentation
    assert volume.spacing == (2, 3, 4) and volume.origin == (-1, 0, 1)
    np.testing.assert_array_equal(volume.to_numpy(), labels)
    # Bounds of the voxel boxes (centered on the points) in world units.
    np.testing.assert_allclose(actor.GetMapper().GetBounds(), (-2, 10, -1.5, 13.5, -1, 15))


@pytest.mark.parametrize("option, value", [("spacing", (1, 2, 3)), ("origin", (0, 0, 1)),
                                           ("axis_order", "zyx")])
def test_numpy_geometry_refused_for_other_inputs(plotter, tmp_path, option, value):
    path = tmp_path / "box.nrrd"
    nrrd.write(str(path), labels_xyz())
    with pytest.raises(ValueError, match=rf"{option}= is for numpy arrays; str data"):
        vtksvdag.add_segmentation(plotter, str(path), **{option: value})
    assert plotter.renderer.GetVolumes().GetNumberOfItems() == 0


def test_scalars_refused_for_numpy(plotter):
    with pytest.raises(ValueError, match=r"scalars='seg' names an array of a pyvista.ImageData"):
        vtksvdag.add_segmentation(plotter, labels_xyz(), scalars="seg")


# -- cast="exact" --------------------------------------------------------------------------------
@pytest.mark.parametrize("dtype", [np.float32, np.float64])
def test_cast_exact_round_trip(dtype):
    labels = labels_xyz((6, 5, 4), np.uint16) * 1000  # up to 7000: beyond uint8
    floats = labels.astype(dtype)
    volume = vtksvdag.from_numpy(floats, cast="exact")
    assert volume.dtype == np.uint16  # the narrowest type holding the values
    decoded = volume.to_numpy()
    np.testing.assert_array_equal(decoded, labels)
    np.testing.assert_array_equal(decoded.astype(dtype), floats)  # value for value
    negative = vtksvdag.from_numpy(-floats, cast="exact")
    assert negative.dtype == np.int16
    np.testing.assert_array_equal(negative.to_numpy(), -labels.astype(np.int16))


def test_cast_exact_big_values_are_exact():
    labels = np.zeros((3, 3, 3), np.float64)
    labels[1, 1, 1] = 2.0**63  # whole, beyond int64: uint64
    labels[0, 0, 0] = 2.0**53 + 2
    volume = vtksvdag.from_numpy(labels, cast="exact")
    assert volume.dtype == np.uint64
    assert volume.labels.tolist() == [2**53 + 2, 2**63]


@pytest.mark.parametrize("value, index, reason", [
    (2.5, (1, 2, 3), "not a whole number"),
    (np.nan, (0, 4, 1), "not finite"),
    (-np.inf, (5, 0, 0), "not finite"),
])
def test_cast_exact_refuses_with_the_first_offending_value(value, index, reason):
    floats = labels_xyz((6, 5, 4)).astype(np.float32)
    floats[index] = value
    floats[5, 4, 3] = 0.25  # a later one: not the first
    with pytest.raises(ValueError, match=rf"holds {value!r} at index {index}, {reason}".replace(
            "(", r"\(").replace(")", r"\)")) as error:
        vtksvdag.from_numpy(floats, cast="exact")
    assert isinstance(error.value, TypeError)  # still what a float array raised before cast


def test_cast_exact_refuses_values_no_integer_type_holds():
    floats = np.zeros((2, 2, 2))
    floats[0, 1, 0] = -1.0
    floats[1, 1, 1] = 2.0**63  # with a negative value: beyond int64
    with pytest.raises(ValueError, match=r"holds 9.223372036854776e\+18 at index \(1, 1, 1\), outside"):
        vtksvdag.from_numpy(floats, cast="exact")


def test_floats_without_cast_and_bad_cast_values(tmp_path):
    floats = np.ones((4, 4, 4), np.float32)
    with pytest.raises(ValueError, match=r"float32.*cast='exact'"):
        vtksvdag.from_numpy(floats)
    for bad in ("round", "EXACT", True, 1):
        with pytest.raises(ValueError, match=r"cast must be one of \[None, 'exact'\], got"):
            vtksvdag.from_numpy(floats, cast=bad)
    # Integer arrays: as they are, with or without cast.
    ints = labels_xyz()
    assert vtksvdag.from_numpy(ints, cast="exact").dtype == np.uint16


def test_read_float_nrrd(tmp_path):
    labels = labels_xyz((6, 5, 4), np.uint8)
    header = {"space": "left-posterior-superior", "space directions": [[0, 0.5, 0], [2, 0, 0], [0, 0, 3]],
              "space origin": [1.0, 2.0, 3.0]}
    floats = tmp_path / "floats.nrrd"
    nrrd.write(str(floats), labels.astype(np.float32), header=header)
    ints = tmp_path / "ints.nrrd"
    nrrd.write(str(ints), labels, header=header)
    # Was an OSError; the docstring promised a ValueError.
    with pytest.raises(ValueError, match=r"floats.nrrd has float32; cast='exact' accepts whole-number floats"):
        vtksvdag.read(floats)
    volume = vtksvdag.read(floats, cast="exact")
    reference = vtksvdag.read(ints)  # the C++ reader: the same geometry
    np.testing.assert_array_equal(volume.to_numpy(), reference.to_numpy())
    assert volume.dtype == reference.dtype == np.uint8
    np.testing.assert_allclose(volume.spacing, reference.spacing)
    np.testing.assert_allclose(volume.origin, reference.origin)
    np.testing.assert_allclose(volume.direction, reference.direction)
    bad = labels.astype(np.float64)
    bad[2, 3, 1] = 7.5
    nrrd.write(str(floats), bad, header=header)
    with pytest.raises(ValueError, match=r"holds 7.5 at index \(2, 3, 1\)"):
        vtksvdag.read(floats, cast="exact")


def test_read_float_npy_and_other_formats(tmp_path):
    import tifffile

    labels = labels_xyz()
    npy = tmp_path / "f.npy"
    np.save(npy, labels.astype(np.float64))
    with pytest.raises(ValueError, match="cast='exact'"):
        vtksvdag.read(npy)
    np.testing.assert_array_equal(vtksvdag.read(npy, cast="exact").to_numpy(), labels)
    # Every other format too (Testing/Python/test_cast_files.py has them all).
    tif = tmp_path / "f.tif"
    tifffile.imwrite(tif, labels.astype(np.float32).transpose(2, 1, 0), photometric="minisblack")
    with pytest.raises(ValueError, match=r"f.tif has float32; cast='exact' accepts"):
        vtksvdag.read(tif)
    np.testing.assert_array_equal(vtksvdag.read(tif, cast="exact").to_numpy(), labels)


def test_add_segmentation_cast(plotter):
    labels = np.zeros((16, 16, 16), np.uint8)
    labels[3:13, 3:13, 3:13] = 4
    with pytest.raises(ValueError, match="cast='exact'"):
        vtksvdag.add_segmentation(plotter, labels.astype(np.float32))
    actor = vtksvdag.add_segmentation(plotter, labels.astype(np.float32), cast="exact", spp=1)
    np.testing.assert_array_equal(actor.segmentation.to_numpy(), labels)
    with pytest.raises(ValueError, match=r"cast must be one of"):
        vtksvdag.add_segmentation(plotter, labels, cast="nearest")


# -- "did you mean" for misspelled options -------------------------------------------------------
@pytest.mark.parametrize("call, option, suggestion", [
    (lambda **kw: vtksvdag.from_numpy(labels_xyz(), **kw), "spacings", "spacing"),
    (lambda **kw: vtksvdag.from_numpy(labels_xyz(), **kw), "axes_order", "axis_order"),
    (lambda **kw: vtksvdag.read("x.nrrd", **kw), "backgound", "background"),
    (lambda **kw: vtksvdag.from_image(None, **kw), "scalar", "scalars"),
    (lambda **kw: vtksvdag.refine(None, **kw), "time_out", "timeout"),
    (lambda **kw: vtksvdag.pick(None, 1, 2, **kw), "xx", "x"),
    (lambda **kw: vtksvdag.add_label_legend(None, **kw), "max_entry", "max_entries"),
    (lambda **kw: vtksvdag.add_segmentation(None, None, **kw), "show_scalarbar", "show_scalar_bar"),
])
def test_did_you_mean(call, option, suggestion):
    with pytest.raises(TypeError, match=rf"unknown options: '{option}' \(did you mean '{suggestion}'"):
        call(**{option: 1})


# -- errors that name the argument ----------------------------------------------------------------
@pytest.mark.parametrize("sun, message", [
    ("yes", r"sun must be None.*False.*True.*direction.*dict.*got 'yes'"),
    (3.0, r"sun must be .* got 3.0"),
    ({"angular_radius": "big"}, r"sun angular_radius must be numbers, got 'big'"),
    (("a", "b", "c"), r"sun direction must be numbers"),
])
def test_sun_errors_name_sun(plotter, sun, message):
    with pytest.raises(ValueError, match=message):
        vtksvdag.add_segmentation(plotter, labels_xyz(), sun=sun)
    assert plotter.renderer.GetVolumes().GetNumberOfItems() == 0


def test_unknown_cmap_is_a_value_error(plotter):
    with pytest.raises(ValueError, match=r"cmap 'tab2O': unknown colormap \(did you mean 'tab20'"):
        vtksvdag.add_segmentation(plotter, labels_xyz(), cmap="tab2O")
    # Still one for color_by's colormap.
    import pandas as pd

    table = pd.DataFrame({"label": [1, 2], "score": [0.5, 1.0]})
    with pytest.raises(ValueError, match=r"cmap 'viridiss': unknown colormap \(did you mean 'viridis'"):
        vtksvdag.add_segmentation(plotter, labels_xyz(), attributes=table, color_by="score",
                                  cmap="viridiss")


def test_pick_outside_the_window_or_not_finite(plotter):
    labels = np.zeros((16, 16, 16), np.uint8)
    labels[2:14, 2:14, 2:14] = 5
    vtksvdag.add_segmentation(plotter, labels, spp=1)
    vtksvdag.refine(plotter)
    assert vtksvdag.pick(plotter, W / 2, H / 2)["label"] == 5
    assert vtksvdag.pick(plotter, 0, 0) is None  # background: inside the window
    for x, y, what in [(1000, 1000, "x"), (W, 3, "x"), (-1, 3, "x"), (3, H, "y"),
                       (math.nan, 3, "x"), (3, math.inf, "y")]:
        with pytest.raises(ValueError, match=rf"{what} must be a display coordinate in \[0, "
                                             rf"{W if what == 'x' else H}\) \(the window is {W} x {H}"):
            vtksvdag.pick(plotter, x, y)
    with pytest.raises(TypeError, match="x must be a number"):
        vtksvdag.pick(plotter, "10", 3)


def test_read_directory_names_the_stores_looked_for(tmp_path):
    (tmp_path / "notes.txt").write_text("no store here")
    with pytest.raises(ValueError, match=r"no chunked store.*Zarr v2 array \(.zarray\).*"
                                         r"zarr.json.*OME-Zarr.*N5 array.*neuroglancer precomputed") as error:
        vtksvdag.read(tmp_path)
    assert isinstance(error.value, IsADirectoryError)  # what it was, and still is
    assert error.value.filename == str(tmp_path)


def test_float_labels_error_is_both_types():
    assert issubclass(FloatLabelsError, ValueError) and issubclass(FloatLabelsError, TypeError)
