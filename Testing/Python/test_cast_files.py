"""vtksvdag.read(path, cast="exact") for float label files of every format (issue 20, item 5).

Each file is written by a library independent of the reader (pynrrd, nibabel, tifffile, h5py,
VTK's MetaImage and XML image writers through test_reader_formats.write_good, numpy for .npy,
tensorstore for a Zarr store) from a float32 or float64 array of an odd shape, and read back with
cast="exact": the labels must equal the values bit for bit, in the narrowest integer dtype. The
refusals (not whole, not finite, outside every integer type) must name the first offending value
in C order of the [x, y, z] array and its index, as cast_labels does for numpy arrays.
"""
import re

import numpy as np
import pytest
import tifffile

import vtksvdag
from vtksvdag import stores
from vtksvdag._labels import FloatLabelsError

from test_reader_formats import write_good

SHAPE_XYZ = (13, 7, 5)
FILE_FORMATS = ["nrrd-raw", "nrrd-gzip", "nii", "nii.gz", "tif", "h5", "mha", "mha-zlib", "vti",
                "npy"]
FORMATS = FILE_FORMATS + ["zarr"]
FLOATS = [np.float32, np.float64]


def write(fmt, directory, xyz):
    """Writes the [x, y, z] array ``xyz`` in format ``fmt`` into ``directory``; returns the path."""
    directory.mkdir(parents=True, exist_ok=True)
    if fmt == "npy":
        path = directory / "t.npy"
        np.save(path, xyz)  # read() takes .npy arrays as [x, y, z]
        return path
    if fmt == "zarr":
        ts = pytest.importorskip("tensorstore")
        path = directory / "t.zarr"
        zyx = xyz.transpose(2, 1, 0)
        spec = {"driver": "zarr", "kvstore": {"driver": "file", "path": str(path)},
                "metadata": {"shape": list(zyx.shape), "chunks": [2, 7, 6], "dtype": zyx.dtype.str}}
        ts.open(spec, create=True, delete_existing=True).result()[...].write(zyx).result()
        return path
    return write_good(fmt, directory, np.ascontiguousarray(xyz.transpose(2, 1, 0)))  # (z, y, x)


def values_xyz(values, dtype, shape=SHAPE_XYZ):
    """An [x, y, z] array of ``dtype`` cycling through ``values`` (each voxel next to others)."""
    count = int(np.prod(shape))
    return np.resize(np.array(values, dtype=dtype), count).reshape(shape)


# The values, and the narrowest dtype holding them (unsigned when none is negative).
CASES = {
    "uint8": (list(range(0, 201, 7)) + [200], np.uint8),
    "int8": ([-100, 0, 5, 100, -1], np.int8),
    "int16": ([-300, 0, 7, 200], np.int16),
    "uint32": ([0, 3, 70000, 255], np.uint32),
    "int32": ([-70000, 0, 9, 65535], np.int32),
    "uint64": ([0, 2**63, 2**40 + 2**39], np.uint64),  # 2**63: beyond int64, exact as a float
    "int64": ([-(2**63), 0, 2**53], np.int64),
}


@pytest.mark.parametrize("case", CASES)
@pytest.mark.parametrize("dtype", FLOATS)
@pytest.mark.parametrize("fmt", FORMATS)
def test_whole_floats_read_exactly_as_the_narrowest_dtype(tmp_path, fmt, dtype, case):
    values, expected = CASES[case]
    floats = values_xyz(values, dtype)
    path = write(fmt, tmp_path, floats)
    volume = vtksvdag.read(path, cast="exact")
    assert volume.dtype == expected
    labels = volume.to_numpy()
    assert labels.dtype == expected and labels.shape == SHAPE_XYZ
    np.testing.assert_array_equal(labels, values_xyz(values, object).astype(expected))
    assert np.array_equal(labels.astype(dtype), floats)  # value for value, back to the floats


@pytest.mark.parametrize("dtype", FLOATS)
@pytest.mark.parametrize("fmt", FORMATS)
def test_floats_without_cast_are_refused(tmp_path, fmt, dtype):
    path = write(fmt, tmp_path, values_xyz([0, 1, 2], dtype))
    with pytest.raises(FloatLabelsError, match=r"float(32|64).*cast='exact' accepts") as error:
        vtksvdag.read(path)
    assert isinstance(error.value, ValueError)


# The offender, where it is planted, and a later one in C order of [x, y, z] that a reader going
# through the file in its own order (z slowest) would meet first.
FIRST, LATER = (11, 4, 3), (12, 6, 0)
REFUSALS = [
    (0.5, 0.25, "not a whole number"),
    (np.nan, 0.25, "not finite"),
    (-np.inf, 0.25, "not finite"),
    (2.0**64, 2.0**65, r"outside every integer type \(with the other values\)"),
]


@pytest.mark.parametrize("value, later, reason", REFUSALS)
@pytest.mark.parametrize("dtype", FLOATS)
@pytest.mark.parametrize("fmt", FORMATS)
def test_refusals_name_the_first_offending_value_and_its_index(tmp_path, fmt, dtype, value, later,
                                                              reason):
    floats = values_xyz([0, 1, 2], dtype)
    floats[FIRST] = value
    floats[LATER] = later
    path = write(fmt, tmp_path, floats)
    # The value as cast_labels names it: numpy's repr of the file's scalar type.
    expected = (rf"\({dtype.__name__}\) holds {re.escape(repr(dtype(value)))} at index "
                rf"\(11, 4, 3\), {reason}")
    with pytest.raises(FloatLabelsError, match=r"cast='exact'.*" + expected + "; only whole"):
        vtksvdag.read(path, cast="exact")
    with pytest.raises(FloatLabelsError, match=expected):  # the same as for the numpy array
        vtksvdag.from_numpy(floats, cast="exact")


def test_outside_int64_with_a_negative_value(tmp_path):
    floats = values_xyz([0, -1, 2], np.float64)
    floats[FIRST] = 2.0**63  # a uint64 label, but no integer type holds it with -1
    for fmt in ("nrrd-gzip", "h5", "zarr"):
        path = write(fmt, tmp_path / fmt, floats)
        with pytest.raises(FloatLabelsError, match=r"holds 9.223372036854776e\+18 at index "
                                                   r"\(11, 4, 3\), outside every integer type"):
            vtksvdag.read(path, cast="exact")


@pytest.mark.parametrize("fmt", ["nrrd-gzip", "nii.gz", "h5", "mha-zlib", "vti", "zarr"])
def test_slab_streaming_finds_the_offender_in_the_last_slab(tmp_path, monkeypatch, fmt):
    """More than one slab of 16 z-slices: the check pass reads slab after slab (the index of
    an offender in the last one is right), and the conversion pass reopens the file (gzip
    streams cannot rewind) and converts every slab."""
    monkeypatch.setattr(stores, "SLAB_BYTES", 1)  # stores: slabs of 16 slices, as the reader's
    shape = (13, 7, 40)
    floats = values_xyz(list(range(300)), np.float32, shape)
    path = write(fmt, tmp_path / "good", floats)
    progress = []
    volume = vtksvdag.read(path, cast="exact", progress=progress.append)
    assert volume.dtype == np.uint16
    np.testing.assert_array_equal(volume.to_numpy(), floats.astype(np.uint16))
    assert progress[-1] == 1.0
    if fmt == "zarr":  # two passes over 3 slabs, each half of the progress
        assert progress == pytest.approx([16 / 80, 32 / 80, 0.5, 0.5 + 16 / 80, 0.5 + 32 / 80, 1])
    floats[12, 6, 37] = 299.5
    path = write(fmt, tmp_path / "bad", floats)
    with pytest.raises(FloatLabelsError, match=r"holds 299.5 at index \(12, 6, 37\), not a whole"):
        vtksvdag.read(path, cast="exact")


def test_hdf5_dataset_choice_with_cast(tmp_path):
    import h5py

    ints = np.arange(2 * 3 * 4, dtype=np.int16).reshape(2, 3, 4)
    floats = np.full((5, 6, 7), 3.0, np.float32)
    path = tmp_path / "both.h5"
    with h5py.File(path, "w") as f:
        f["ints"] = ints
        f["floats"] = floats
    # An integer file reads the same with cast: its integer volume, not a choice of two.
    assert vtksvdag.read(path, cast="exact").dtype == np.int16
    volume = vtksvdag.read(path, dataset="floats", cast="exact")
    assert volume.dtype == np.uint8 and volume.dims == (7, 6, 5)
    only = tmp_path / "floats.h5"
    with h5py.File(only, "w") as f:
        f["a/b"] = floats.astype(np.float64)
    np.testing.assert_array_equal(vtksvdag.read(only, cast="exact").to_numpy(), 3)


def test_other_float_widths_are_refused_with_cast(tmp_path):
    path = tmp_path / "half.tif"
    tifffile.imwrite(path, np.zeros((3, 4, 5), np.float16), photometric="minisblack")
    with pytest.raises(FloatLabelsError, match=r"has float16; cast='exact' accepts float32 and "
                                               r"float64 voxels only"):
        vtksvdag.read(path, cast="exact")


def test_integer_files_read_the_same_with_cast(tmp_path):
    labels = values_xyz([0, 7, 300], np.uint16)
    for fmt in FORMATS:
        path = write(fmt, tmp_path / fmt, labels)
        volume = vtksvdag.read(path, cast="exact")
        assert volume.dtype == np.uint16, fmt
        np.testing.assert_array_equal(volume.to_numpy(), labels)


def test_reader_property_and_a_file_changed_between_the_passes(tmp_path):
    from vtksvdag.vtkSVDAGIO import vtkSegmentationVolumeReader

    from test_reader_formats import ErrorLog, vtkErrorCode

    reader = vtkSegmentationVolumeReader()
    assert not reader.GetCastFloatLabels()  # off by default
    reader.CastFloatLabelsOn()
    assert "CastFloatLabels: On" in str(reader)
    floats = values_xyz([0, 1, 2], np.float32, (13, 7, 40))
    path = write("nrrd-raw", tmp_path, floats)
    reader.SetFileName(str(path))
    log = ErrorLog(reader, reader.GetExecutive())
    # The check pass runs with the header (RequestInformation); then the file changes, and the
    # conversion pass (RequestData, a second reading) finds a value the check did not see.
    reader.UpdateInformation()
    assert log.messages == [] and reader.GetFileFormat() == "NRRD"
    floats[3, 2, 33] = 0.5
    write("nrrd-raw", tmp_path, floats)
    reader.Update()
    assert reader.GetErrorCode() == vtkErrorCode.FileFormatError
    assert any("changed while it was read: z-slices 32..39" in m for m in log.messages)
