"""The vtksvdag Python API: from_numpy / from_image / SegmentationVolume, round trips and errors."""
import numpy as np
import pytest
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData

import vtksvdag

INTEGER_DTYPES = [np.int8, np.uint8, np.int16, np.uint16, np.int32, np.uint32, np.int64, np.uint64]
SHAPES = [(1, 1, 1), (1, 1, 9), (9, 1, 1), (1, 7, 1), (17, 33, 40)]
STATS_KEYS = {
    "dims", "voxels", "labels", "blocks", "dag_nodes", "root_nodes", "mid_nodes", "leaves",
    "bytes_blocks", "bytes_dag", "bytes_labels", "bytes_total", "raw_bytes_32", "bits_per_voxel",
    "build_seconds", "load_seconds", "dtype", "spacing", "origin",
}


def make_pattern(name, shape, dtype, rng):
    """A label volume [x, y, z] of one of the test patterns."""
    info = np.iinfo(dtype)
    if name == "background":
        return np.zeros(shape, dtype)
    if name == "full":
        return np.full(shape, 5, dtype)
    if name == "checkerboard":
        x, y, z = np.indices(shape)
        return ((x + y + z) % 2 * 3).astype(dtype)
    if name == "random":
        return rng.integers(0, 6, size=shape).astype(dtype)
    if name == "extremes":
        # the dtype's min and max, -1 for signed types, and 0 (background) mixed at random
        values = np.array([info.min, info.max, 0, 1, -1 if info.min < 0 else info.max - 1], dtype)
        return rng.choice(values, size=shape)
    raise AssertionError(name)


@pytest.mark.parametrize("dtype", INTEGER_DTYPES, ids=lambda d: np.dtype(d).name)
@pytest.mark.parametrize("shape", SHAPES, ids=lambda s: "x".join(map(str, s)))
@pytest.mark.parametrize("pattern", ["background", "full", "checkerboard", "random", "extremes"])
def test_round_trip_every_dtype_and_shape(dtype, shape, pattern, rng):
    labels = make_pattern(pattern, shape, dtype, rng)
    volume = vtksvdag.from_numpy(labels)
    decoded = volume.to_numpy()
    assert decoded.dtype == np.dtype(dtype)
    assert decoded.shape == shape
    np.testing.assert_array_equal(decoded, labels)
    assert volume.dims == shape
    assert volume.dtype == np.dtype(dtype)
    expected_labels = np.unique(labels[labels != 0])
    np.testing.assert_array_equal(volume.labels, expected_labels)
    assert volume.labels.dtype == np.dtype(dtype)


@pytest.mark.parametrize("dtype", INTEGER_DTYPES, ids=lambda d: np.dtype(d).name)
def test_non_zero_background_at_the_dtype_extremes(dtype, rng):
    info = np.iinfo(dtype)
    for background in (info.min, info.max):
        labels = rng.choice(np.array([info.min, info.max, 0, 3], dtype), size=(17, 18, 19))
        volume = vtksvdag.from_numpy(labels, background=background)
        np.testing.assert_array_equal(volume.to_numpy(), labels)
        assert volume.background == background
        assert volume.background.dtype == np.dtype(dtype)
        assert background not in volume.labels
        stored = labels != background
        assert volume.label_voxel_counts.sum() == stored.sum()


def test_uint64_labels_above_2_63():
    big = np.uint64(2**64 - 1)
    labels = np.zeros((20, 20, 20), np.uint64)
    labels[3:9, 3:9, 3:9] = big
    labels[10:12, :, :] = np.uint64(2**63)
    volume = vtksvdag.from_numpy(labels, background=2**64 - 1)
    np.testing.assert_array_equal(volume.to_numpy(), labels)
    np.testing.assert_array_equal(volume.labels, np.array([0, 2**63], np.uint64))
    assert volume.label_at(4, 4, 4) == big


def test_excluded_labels_decode_as_background(rng):
    labels = rng.integers(0, 8, size=(33, 17, 20)).astype(np.int32) - 2  # -2 .. 5
    volume = vtksvdag.from_numpy(labels, background=-2, exclude=[3, -1])
    expected = np.where(np.isin(labels, [3, -1]), -2, labels)
    np.testing.assert_array_equal(volume.to_numpy(), expected)
    np.testing.assert_array_equal(volume.labels, [0, 1, 2, 4, 5])
    # a single integer is accepted as well
    one = vtksvdag.from_numpy(labels, background=-2, exclude=5)
    assert 5 not in one.labels and 4 in one.labels


def test_axis_orders(rng):
    zyx = rng.integers(0, 4, size=(7, 11, 13)).astype(np.uint16)  # C-ordered (z, y, x)
    volume = vtksvdag.from_numpy(zyx, axis_order="zyx")
    assert volume.dims == (13, 11, 7)
    np.testing.assert_array_equal(volume.to_numpy("zyx"), zyx)
    np.testing.assert_array_equal(volume.to_numpy("xyz"), zyx.transpose(2, 1, 0))
    assert volume.label_at(12, 3, 2) == zyx[2, 3, 12]
    same = vtksvdag.from_numpy(zyx.transpose(2, 1, 0))
    assert same.stats()["bytes_total"] == volume.stats()["bytes_total"]


def test_to_numpy_xyz_is_a_fortran_view_of_the_decoded_buffer(rng):
    labels = rng.integers(0, 3, size=(9, 10, 11)).astype(np.int64)
    decoded = vtksvdag.from_numpy(labels).to_numpy()
    assert decoded.flags.f_contiguous
    assert not decoded.flags.owndata  # a view of the VTK array, not a copy
    zyx = vtksvdag.from_numpy(labels).to_numpy("zyx")
    assert zyx.flags.c_contiguous and zyx.shape == (11, 10, 9)


def test_non_contiguous_and_bool_inputs(rng):
    base = rng.integers(0, 5, size=(30, 20, 26)).astype(np.uint8)
    strided = base[::2, 1::3, ::-1]
    assert not strided.flags.c_contiguous and not strided.flags.f_contiguous
    np.testing.assert_array_equal(vtksvdag.from_numpy(strided).to_numpy(), strided)
    mask = base > 2
    volume = vtksvdag.from_numpy(mask)
    assert volume.dtype == np.uint8  # documented: bool is stored as uint8
    np.testing.assert_array_equal(volume.to_numpy(), mask.astype(np.uint8))


def test_geometry_is_kept(rng):
    labels = rng.integers(0, 3, size=(5, 6, 7)).astype(np.int8)
    angle = 0.3
    direction = np.array(
        [[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0], [0, 0, 1]]
    )
    volume = vtksvdag.from_numpy(labels, spacing=(0.5, 2, 3.25), origin=(-1, 2.5, 1e3), direction=direction)
    assert volume.spacing == (0.5, 2.0, 3.25)
    assert volume.origin == (-1.0, 2.5, 1000.0)
    np.testing.assert_allclose(volume.direction, direction)
    image = volume.to_image()
    assert image.GetSpacing() == (0.5, 2.0, 3.25)
    assert image.GetOrigin() == (-1.0, 2.5, 1000.0)
    np.testing.assert_allclose(
        [image.GetDirectionMatrix().GetElement(r, c) for r in range(3) for c in range(3)], direction.ravel()
    )


def test_pyvista_round_trip(rng):
    import pyvista as pv
    grid = pv.ImageData(dimensions=(12, 9, 17), spacing=(0.5, 1.0, 1.5), origin=(3, 2, 1))
    values = rng.integers(0, 6, size=grid.n_points).astype(np.int32)
    grid.point_data["segments"] = values
    grid.point_data["other"] = np.zeros(grid.n_points)
    volume = vtksvdag.from_image(grid, scalars="segments")
    out = volume.to_pyvista()
    assert isinstance(out, pv.ImageData)
    assert out.dimensions == grid.dimensions
    assert out.spacing == grid.spacing and out.origin == grid.origin
    np.testing.assert_array_equal(out.point_data["Labels"], values)
    # pyvista's flat point order is x fastest, the same as to_numpy("xyz") in Fortran order
    np.testing.assert_array_equal(volume.to_numpy().ravel(order="F"), values)


def test_from_image_uses_the_active_scalars():
    image = vtkImageData()
    image.SetDimensions(4, 3, 2)
    values = np.arange(24, dtype=np.uint16) % 5
    image.GetPointData().SetScalars(numpy_to_vtk(values, deep=True))
    volume = vtksvdag.from_image(image, background=4)
    assert volume.background == 4
    np.testing.assert_array_equal(volume.to_numpy().ravel(order="F"), values)


def test_stats_are_consistent(rng):
    labels = np.zeros((40, 35, 30), np.uint32)
    labels[5:30, 5:20, 2:25] = 7
    labels[20:38, 10:33, 10:29] = rng.integers(1, 4, size=(18, 23, 19))
    volume = vtksvdag.from_numpy(labels)
    s = volume.stats()
    assert STATS_KEYS <= set(s)
    assert s["dims"] == [40, 35, 30]
    assert s["voxels"] == labels.size
    assert s["labels"] == len(volume.labels) == 4
    assert s["dag_nodes"] == s["root_nodes"] + s["mid_nodes"] + s["leaves"]
    assert s["bytes_total"] == s["bytes_blocks"] + s["bytes_dag"] + s["bytes_labels"]
    assert s["bytes_total"] == volume.dataobject.GetCompressedSize()
    assert s["raw_bytes_32"] == 4 * labels.size
    assert s["bits_per_voxel"] == pytest.approx(8 * s["bytes_total"] / labels.size)
    assert s["blocks"] >= s["labels"] and s["leaves"] > 0
    assert s["build_seconds"] > 0 and s["load_seconds"] is None
    assert s["dtype"] == "uint32"
    # label table: counts and inclusive bounds from the array itself
    for label, count, bounds in zip(volume.labels, volume.label_voxel_counts, volume.label_bounds):
        where = np.argwhere(labels == label)
        assert count == len(where)
        np.testing.assert_array_equal(bounds, np.column_stack([where.min(0), where.max(0)]).ravel())
    text = repr(volume)
    assert "40x35x30" in text and f"{s['bytes_total']} bytes" in text
    # the same input gives the same compressed volume
    assert vtksvdag.from_numpy(labels).stats()["bytes_total"] == s["bytes_total"]


def test_all_background_volume_is_empty_but_valid():
    volume = vtksvdag.from_numpy(np.zeros((17, 3, 5), np.int16))
    s = volume.stats()
    assert s["labels"] == 0 and s["blocks"] == 0 and volume.labels.size == 0
    assert volume.label_at(16, 2, 4) == 0
    np.testing.assert_array_equal(volume.to_numpy(), 0)


def test_label_at_matches_the_array(rng):
    labels = rng.integers(-3, 3, size=(21, 18, 35)).astype(np.int64)
    volume = vtksvdag.from_numpy(labels, background=-3)
    for i, j, k in rng.integers(0, [21, 18, 35], size=(200, 3)):
        assert volume.label_at(i, j, k) == labels[i, j, k]
    for index in [(21, 0, 0), (0, -1, 0), (0, 0, 35)]:
        with pytest.raises(IndexError):
            volume.label_at(*index)


@pytest.mark.parametrize(
    "array, kwargs, error, match",
    [
        (np.zeros((4, 4, 4), np.float32), {}, TypeError, "dtype float32"),
        (np.zeros((4, 4, 4), np.complex64), {}, TypeError, "integers"),
        (np.zeros((4, 4, 4), object), {}, TypeError, "integers"),
        (np.zeros((2, 4, 4, 4), np.uint8), {}, ValueError, "3D array, not 4D"),
        (np.zeros((4, 4), np.uint8), {}, ValueError, "np.newaxis"),
        (np.zeros((0, 4, 4), np.uint8), {}, ValueError, "empty"),
        (np.zeros((4, 4, 4), np.uint8), {"background": 1.5}, TypeError, "background must be an integer"),
        (np.zeros((4, 4, 4), np.uint8), {"background": "0"}, TypeError, "background must be an integer"),
        (np.zeros((4, 4, 4), np.uint8), {"background": 256}, ValueError, "out of range"),
        (np.zeros((4, 4, 4), np.int8), {"background": -129}, ValueError, "out of range"),
        (np.zeros((4, 4, 4), np.uint8), {"exclude": [1, -1]}, ValueError, "out of range"),
        (np.zeros((4, 4, 4), np.uint8), {"exclude": [2.0]}, TypeError, "must be an integer"),
        (np.zeros((4, 4, 4), np.uint8), {"spacing": (1, 0, 1)}, ValueError, "positive"),
        (np.zeros((4, 4, 4), np.uint8), {"spacing": (1, 1)}, ValueError, "three"),
        (np.zeros((4, 4, 4), np.uint8), {"origin": (0, np.nan, 0)}, ValueError, "finite"),
        (np.zeros((4, 4, 4), np.uint8), {"direction": np.zeros((3, 3))}, ValueError, "invertible"),
        (np.zeros((4, 4, 4), np.uint8), {"axis_order": "yxz"}, ValueError, "axis_order"),
    ],
)
def test_bad_inputs_raise(array, kwargs, error, match):
    with pytest.raises(error, match=match):
        vtksvdag.from_numpy(array, **kwargs)


def test_from_image_errors():
    image = vtkImageData()
    image.SetDimensions(4, 4, 4)
    with pytest.raises(KeyError, match="no active point scalars"):
        vtksvdag.from_image(image)
    image.GetPointData().SetScalars(numpy_to_vtk(np.zeros(64, np.float64), deep=True))
    with pytest.raises(TypeError, match="float64"):
        vtksvdag.from_image(image)
    with pytest.raises(KeyError, match="no point data array 'nope'"):
        vtksvdag.from_image(image, scalars="nope")
    with pytest.raises(TypeError, match="vtkImageData"):
        vtksvdag.from_image(np.zeros((4, 4, 4), np.uint8))
    # an error reported by the C++ filter becomes a Python exception with its message
    image.GetPointData().SetScalars(numpy_to_vtk(np.zeros(10, np.int32), deep=True))
    with pytest.raises(ValueError, match="10 values for 64 voxels"):
        vtksvdag.from_image(image)


def test_progress_is_reported(rng):
    seen = []
    labels = rng.integers(0, 3, size=(20, 20, 50)).astype(np.uint8)
    volume = vtksvdag.from_numpy(labels, progress=seen.append)
    assert seen and seen[-1] == pytest.approx(1.0)
    assert all(0.0 <= f <= 1.0 for f in seen) and seen == sorted(seen)
    decoded = []
    volume.to_numpy(progress=decoded.append)
    assert all(0.0 <= f <= 1.0 for f in decoded)


@pytest.mark.parametrize(
    "module",
    ["vtksvdag", "vtksvdag.volume", "vtksvdag.build", "vtksvdag.fileio", "vtksvdag.export",
     "vtksvdag.progress", "vtksvdag.cli", "vtksvdag.labelmeta"],
)
def test_docstring_examples(module, tmp_path, monkeypatch):
    import doctest
    import importlib

    monkeypatch.chdir(tmp_path)  # examples that write files write here
    result = doctest.testmod(importlib.import_module(module), optionflags=doctest.NORMALIZE_WHITESPACE)
    assert result.failed == 0


def test_save_and_read_round_trip(rng, tmp_path):
    labels = rng.integers(0, 6, size=(33, 20, 17)).astype(np.int64) * 1_000_000_007
    volume = vtksvdag.from_numpy(labels, spacing=(1, 2, 3), origin=(4, 5, 6), background=0)
    path = tmp_path / "v.svdag"
    volume.save(path, compression_level=1)
    loaded = vtksvdag.read(path)
    assert loaded.load_seconds > 0 and loaded.build_seconds is None
    assert loaded.dtype == np.int64 and loaded.spacing == (1, 2, 3) and loaded.origin == (4, 5, 6)
    np.testing.assert_array_equal(loaded.to_numpy(), labels)
    saved, again = volume.stats(), loaded.stats()
    for key in ("blocks", "dag_nodes", "bytes_total", "labels"):
        assert saved[key] == again[key], key
    with pytest.raises(OSError, match="missing_dir"):
        volume.save(tmp_path / "missing_dir" / "v.svdag")
    with pytest.raises(TypeError, match="compression_level"):
        volume.save(tmp_path / "w.svdag", compression_level="high")


def test_read_label_files_with_options(rng, tmp_path):
    import h5py
    import nrrd

    labels = rng.integers(0, 5, size=(12, 9, 20)).astype(np.uint16)  # [x, y, z]
    nrrd_path = tmp_path / "l.nrrd"
    nrrd.write(str(nrrd_path), labels, header={"encoding": "gzip"}, index_order="F")
    volume = vtksvdag.read(nrrd_path, background=4, exclude=[2])
    assert volume.build_seconds > 0 and volume.load_seconds is None
    np.testing.assert_array_equal(volume.to_numpy(), np.where(labels == 2, 4, labels))
    np.testing.assert_array_equal(volume.labels, [0, 1, 3])
    with pytest.raises(ValueError, match="out of range"):
        vtksvdag.read(nrrd_path, background=2**64)
    with pytest.raises(TypeError, match="background"):
        vtksvdag.read(nrrd_path, background=0.5)

    h5_path = tmp_path / "l.h5"
    with h5py.File(h5_path, "w") as f:
        f["raw"] = labels.transpose(2, 1, 0).astype(np.uint8)  # (z, y, x) as h5py writes numpy
        f["seg/labels"] = labels.transpose(2, 1, 0)
    volume = vtksvdag.read(h5_path, dataset="seg/labels")
    np.testing.assert_array_equal(volume.to_numpy(), labels)
    assert volume.dtype == np.uint16

    np.save(tmp_path / "l.npy", labels)
    np.testing.assert_array_equal(vtksvdag.read(tmp_path / "l.npy").to_numpy(), labels)


def test_read_errors(tmp_path):
    with pytest.raises(FileNotFoundError):
        vtksvdag.read(tmp_path / "missing.nrrd")
    text = tmp_path / "notes.nrrd"
    text.write_text("NRRD0004\nthis header is broken\n")
    with pytest.raises(OSError, match="notes.nrrd"):
        vtksvdag.read(text)
    floats = tmp_path / "f.npy"
    np.save(floats, np.zeros((3, 3, 3), np.float32))
    with pytest.raises(TypeError, match="float32"):
        vtksvdag.read(floats)
