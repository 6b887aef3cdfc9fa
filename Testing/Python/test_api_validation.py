"""The Python API is never silently wrong: byte orders and layouts, label ranges, paths, indices,
file names and levels, and exceptions raised by progress callbacks."""
import os
import pathlib

import nrrd
import numpy as np
import pytest
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData

import vtksvdag

INTEGER_TYPES = [
    np.int8, np.uint8, np.int16, np.uint16, np.int32, np.uint32, np.int64, np.uint64,
    np.byte, np.ubyte, np.short, np.ushort, np.intc, np.uintc, np.int_, np.uint,
    np.longlong, np.ulonglong,
]
SHAPES = [(1, 1, 1), (1, 1, 4097), (3, 5, 7), (17, 2, 33)]


def extreme_labels(shape, dtype, rng):
    """Labels across the whole range of ``dtype``, its extremes included, with many bytes that
    differ when swapped (so that a byte-order mistake cannot go unnoticed)."""
    info = np.iinfo(dtype)
    values = rng.integers(info.min, info.max, size=shape, dtype=dtype, endpoint=True)
    flat = values.reshape(-1)
    flat[0] = info.max
    if flat.size > 1:
        flat[1] = info.min
    if flat.size > 2:
        flat[2] = 0
    if flat.size > 3:
        flat[3] = 1
    return values


@pytest.mark.parametrize("byteorder", ["<", ">"])
@pytest.mark.parametrize("dtype", INTEGER_TYPES, ids=lambda t: np.dtype(t).char)
def test_every_integer_dtype_in_both_byte_orders(dtype, byteorder, rng):
    for shape in SHAPES:
        native = extreme_labels(shape, dtype, rng)
        array = native.astype(np.dtype(dtype).newbyteorder(byteorder))
        assert np.array_equal(array, native)  # same values, other bytes
        volume = vtksvdag.from_numpy(array)
        assert volume.dtype == np.dtype(dtype).newbyteorder("=")
        assert volume.dtype.isnative
        decoded = volume.to_numpy()
        assert decoded.dtype == volume.dtype and decoded.shape == shape
        # bit-exact: the values are the array's values
        assert decoded.tobytes(order="F") == np.asfortranarray(native).tobytes(order="F")
        zyx = volume.to_numpy("zyx")
        assert np.array_equal(zyx, native.transpose(2, 1, 0))
        expected = np.unique(native[native != 0])
        assert np.array_equal(volume.labels, expected)


@pytest.mark.parametrize("byteorder", ["<", ">"])
@pytest.mark.parametrize("dtype", [np.uint8, np.int16, np.uint32, np.int64, np.uint64])
def test_layouts_non_contiguous_fortran_and_views(dtype, byteorder, rng):
    big = extreme_labels((9, 11, 13), dtype, rng).astype(np.dtype(dtype).newbyteorder(byteorder))
    layouts = {
        "C": np.ascontiguousarray(big),
        "F": np.asfortranarray(big),
        "strided": big[::2, 1::3, ::-2],
        "transposed": big.transpose(1, 2, 0),
        "negative": big[::-1, ::-1, ::-1],
        "broadcast": np.broadcast_to(big[:1, :, :], (4, 11, 13)),
        "odd 1x1x4097": np.broadcast_to(big[:1, :1, :1], (1, 1, 4097)),
        "read-only": big.copy(),
    }
    layouts["read-only"].flags.writeable = False
    for name, array in layouts.items():
        volume = vtksvdag.from_numpy(array)
        decoded = volume.to_numpy()
        assert decoded.dtype.isnative, name
        assert decoded.tobytes(order="F") == np.asfortranarray(array.astype(decoded.dtype)).tobytes(
            order="F"
        ), name
        assert np.array_equal(decoded, array), name
        # and the zyx reading of the same array
        zyx = vtksvdag.from_numpy(array, axis_order="zyx")
        assert np.array_equal(zyx.to_numpy("zyx"), array), name


def test_big_endian_with_background_and_exclusions():
    array = np.array([[[0x0102, 0x0201, 7, 0x0102]]], dtype=">u2")
    volume = vtksvdag.from_numpy(array, background=0x0102, exclude=[7])
    assert volume.background == 0x0102
    np.testing.assert_array_equal(volume.labels, [0x0201])
    np.testing.assert_array_equal(volume.to_numpy(), [[[0x0102, 0x0201, 0x0102, 0x0102]]])


def test_big_endian_npy_file(tmp_path):
    array = np.arange(2 * 3 * 4, dtype=">i4").reshape(2, 3, 4) * 1000 - 5000
    np.save(tmp_path / "big.npy", array)
    volume = vtksvdag.read(tmp_path / "big.npy")
    np.testing.assert_array_equal(volume.to_numpy(), array)
    assert volume.dtype == np.int32


def test_masked_arrays_are_refused():
    array = np.ma.masked_array(np.ones((2, 2, 2), np.uint8), mask=np.eye(2, dtype=bool)[None].repeat(2, 0))
    with pytest.raises(TypeError, match="filled"):
        vtksvdag.from_numpy(array)


# -- label values -----------------------------------------------------------------------------
@pytest.fixture
def uint8_nrrd(tmp_path):
    labels = np.arange(64, dtype=np.uint8).reshape(4, 4, 4)
    path = tmp_path / "u8.nrrd"
    nrrd.write(str(path), labels, index_order="F")
    return path, labels


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"background": 300}, r"background 300 is out of range for dtype uint8 \[0, 255\]"),
        ({"background": -1}, r"background -1 is out of range for dtype uint8"),
        ({"exclude": [3, 300]}, r"excluded label 300 is out of range for dtype uint8"),
        ({"exclude": -1}, r"excluded label -1 is out of range for dtype uint8"),
    ],
)
def test_read_refuses_labels_outside_the_files_dtype(uint8_nrrd, tmp_path, kwargs, match):
    path, labels = uint8_nrrd
    with pytest.raises(ValueError, match=match) as info:
        vtksvdag.read(path, **kwargs)
    assert "u8.nrrd" in str(info.value)
    # the same for a .svdag file, which would be compressed again with that background
    svdag = tmp_path / "u8.svdag"
    vtksvdag.read(path).save(svdag)
    with pytest.raises(ValueError, match=match):
        vtksvdag.read(svdag, **kwargs)
    # and a .npy file
    np.save(tmp_path / "u8.npy", labels)
    with pytest.raises(ValueError, match=match):
        vtksvdag.read(tmp_path / "u8.npy", **kwargs)


def test_read_accepts_the_dtype_extremes(uint8_nrrd):
    path, labels = uint8_nrrd
    volume = vtksvdag.read(path, background=63, exclude={0, 255})  # a set is an iterable too
    assert volume.background == 63
    np.testing.assert_array_equal(volume.to_numpy(), np.where(labels == 0, 63, labels))


def test_exclude_iterables(rng):
    labels = rng.integers(0, 6, size=(5, 6, 7)).astype(np.int16)
    expected = np.where(np.isin(labels, [2, 3]), 0, labels)
    for exclude in ([2, 3], (2, 3), {2, 3}, range(2, 4), (v for v in (2, 3)), np.array([[2], [3]])):
        volume = vtksvdag.from_numpy(labels, exclude=exclude)
        np.testing.assert_array_equal(volume.to_numpy(), expected)
    for bad in ("23", b"23", 2.0, [2.5], object()):
        with pytest.raises(TypeError, match="integer"):
            vtksvdag.from_numpy(labels, exclude=bad)


def test_from_image_checks_labels_and_scalars():
    image = vtkImageData()
    image.SetDimensions(2, 2, 2)
    image.GetPointData().SetScalars(numpy_to_vtk(np.arange(8, dtype=np.uint8), deep=True))
    with pytest.raises(ValueError, match="background 256 is out of range for dtype uint8"):
        vtksvdag.from_image(image, background=256)
    with pytest.raises(ValueError, match="excluded label -3 is out of range"):
        vtksvdag.from_image(image, exclude=[-3])
    with pytest.raises(TypeError, match="scalars must be the name"):
        vtksvdag.from_image(image, scalars=0)


# -- paths ------------------------------------------------------------------------------------
def test_read_accepts_str_bytes_and_path_like(uint8_nrrd, tmp_path):
    path, labels = uint8_nrrd

    class PathLike:
        def __fspath__(self):
            return str(path)

    for given in (str(path), os.fsencode(path), pathlib.Path(path), PathLike()):
        np.testing.assert_array_equal(vtksvdag.read(given).to_numpy(), labels)
    np.save(tmp_path / "l.npy", labels)
    np.testing.assert_array_equal(vtksvdag.read(os.fsencode(tmp_path / "l.npy")).to_numpy(), labels)
    with pytest.raises(TypeError, match="path must be"):
        vtksvdag.read(3.5)
    volume = vtksvdag.read(path)
    volume.save(os.fsencode(tmp_path / "b.svdag"))
    np.testing.assert_array_equal(vtksvdag.read(tmp_path / "b.svdag").to_numpy(), labels)


def test_dataset_is_only_for_hdf5(uint8_nrrd, tmp_path):
    path, labels = uint8_nrrd
    with pytest.raises(ValueError, match="only for HDF5"):
        vtksvdag.read(path, dataset="labels")
    np.save(tmp_path / "l.npy", labels)
    with pytest.raises(ValueError, match="only for HDF5"):
        vtksvdag.read(tmp_path / "l.npy", dataset="labels")
    with pytest.raises(TypeError, match="dataset must be a str"):
        vtksvdag.read(path, dataset=0)


# -- label_at ---------------------------------------------------------------------------------
def test_label_at_requires_integers():
    labels = np.arange(2 * 3 * 4, dtype=np.int32).reshape(2, 3, 4)
    volume = vtksvdag.from_numpy(labels)
    assert volume.label_at(1, 2, 3) == labels[1, 2, 3]
    assert volume.label_at(np.int64(1), np.uint8(2), np.int16(3)) == labels[1, 2, 3]
    for index in [(1.7, 0, 0), (0, 1.0, 0), (0, 0, np.float64(2)), (0, "1", 0), (True, 0, 0),
                  (0, np.bool_(True), 0), (None, 0, 0)]:
        with pytest.raises(TypeError, match="must be an integer"):
            volume.label_at(*index)
    for index in [(2, 0, 0), (0, 3, 0), (0, 0, 4), (-1, 0, 0), (0, 0, 2**70), (np.int64(-5), 0, 0)]:
        with pytest.raises(IndexError, match="outside the volume"):
            volume.label_at(*index)


# -- save -------------------------------------------------------------------------------------
def test_save_refuses_other_suffixes(tmp_path):
    volume = vtksvdag.from_numpy(np.ones((2, 2, 2), np.uint8))
    for name, found in [("x.nrrd", "'.nrrd'"), ("x.npy", "'.npy'"), ("x.svdag.gz", "'.gz'"),
                        ("x", "no suffix")]:
        with pytest.raises(ValueError, match=found) as info:
            volume.save(tmp_path / name)
        assert ".svdag" in str(info.value)
        assert not (tmp_path / name).exists()
    volume.save(tmp_path / "UPPER.SVDAG")
    assert vtksvdag.read(tmp_path / "UPPER.SVDAG").labels.tolist() == [1]


def test_save_checks_the_compression_level(tmp_path):
    volume = vtksvdag.from_numpy(np.arange(27, dtype=np.uint8).reshape(3, 3, 3))
    for level in (100, 23, -1, -5):
        with pytest.raises(ValueError, match=r"compression_level must be in 0\.\.22"):
            volume.save(tmp_path / "x.svdag", compression_level=level)
    for level in (1.5, True, "3", None):
        with pytest.raises(TypeError, match="compression_level must be an integer"):
            volume.save(tmp_path / "x.svdag", compression_level=level)
    assert not (tmp_path / "x.svdag").exists()
    for level in (0, 1, np.int8(22)):
        volume.save(tmp_path / f"l{level}.svdag", compression_level=level)
        np.testing.assert_array_equal(vtksvdag.read(tmp_path / f"l{level}.svdag").to_numpy(),
                                      volume.to_numpy())


# -- progress callbacks -----------------------------------------------------------------------
class Stop(Exception):
    pass


def raising_after(n):
    calls = []

    def progress(fraction):
        calls.append(fraction)
        if len(calls) > n:
            raise Stop(f"stop at {fraction}")

    return progress, calls


def test_a_raising_progress_callback_propagates(uint8_nrrd, tmp_path, recwarn):
    labels = np.zeros((8, 8, 200), np.uint16)  # 13 slabs of 16 z-slices
    labels[2:5, 1:7, 10:190] = 3
    path = tmp_path / "tall.nrrd"
    nrrd.write(str(path), labels, index_order="F")

    progress, calls = raising_after(1)
    with pytest.raises(Stop):
        vtksvdag.from_numpy(labels, progress=progress)
    assert len(calls) == 2  # aborted: not called again after raising

    progress, calls = raising_after(1)
    with pytest.raises(Stop):
        vtksvdag.read(path, progress=progress)
    assert len(calls) == 2

    volume = vtksvdag.read(path)
    for call in (volume.to_numpy, volume.to_image):
        progress, calls = raising_after(0)
        with pytest.raises(Stop):
            call(progress=progress)

    out = tmp_path / "v.svdag"
    progress, calls = raising_after(0)
    with pytest.raises(Stop):
        volume.save(out, progress=progress)
    assert not out.exists()  # no half-written file left behind

    # nothing was printed or warned, and the same objects work again afterwards
    assert not [w for w in recwarn.list if "abort" in str(w.message)]
    np.testing.assert_array_equal(vtksvdag.from_numpy(labels).to_numpy(), labels)
    np.testing.assert_array_equal(vtksvdag.read(path).to_numpy(), labels)
    volume.save(out)
    np.testing.assert_array_equal(vtksvdag.read(out).to_numpy(), labels)


def test_keyboard_interrupt_in_progress_propagates(rng):
    def interrupt(fraction):
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        vtksvdag.from_numpy(rng.integers(0, 3, size=(4, 4, 40)).astype(np.uint8), progress=interrupt)


def test_progress_must_be_callable():
    with pytest.raises(TypeError, match="progress must be a callable"):
        vtksvdag.from_numpy(np.ones((2, 2, 2), np.uint8), progress=True)


def test_write_label_volume_accepts_bytes_paths(tmp_path):
    from vtksvdag.export import write_label_volume

    labels = np.arange(24, dtype=">u4").reshape(2, 3, 4)
    volume = vtksvdag.from_numpy(labels)
    write_label_volume(volume, os.fsencode(tmp_path / "l.npy"))
    np.testing.assert_array_equal(np.load(tmp_path / "l.npy"), labels)
    with pytest.raises(ValueError, match="unsupported format"):
        write_label_volume(volume, os.fsencode(tmp_path / "l.png"))
