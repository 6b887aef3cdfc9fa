"""vtkSegmentationVolumeReader: every format, written by OTHER tools, decodes bit-exactly.

Files are written with pynrrd, nibabel, tifffile, h5py, vtkMetaImageWriter and
vtkXMLImageDataWriter (and the project's own .svdag writer), read with the reader, decoded with
vtkSegmentationSVDAGToImageData and compared voxel for voxel with the numpy array, together with
the geometry. Bad files (missing, truncated, corrupt, wrong type, absurd header) run in a
subprocess each, so that a crash would fail the test instead of killing the test run.
"""
import gzip
import json
import os
import subprocess
import sys
import textwrap
import zlib

import h5py
import nibabel
import nrrd
import numpy as np
import pytest
import tifffile
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkCommand
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkIOImage import vtkMetaImageWriter
from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG, vtkSegmentationSVDAGToImageData
from vtksvdag.vtkSVDAGIO import vtkSegmentationSVDAGWriter, vtkSegmentationVolumeReader

from conftest import shared_volumes



class vtkErrorCode:
    """vtkErrorCode::ErrorIds (vtkErrorCode.h; the class is not wrapped for Python)."""

    FileNotFoundError = 20001
    CannotOpenFileError = 20002
    UnrecognizedFileTypeError = 20003
    PrematureEndOfFileError = 20004
    FileFormatError = 20005
    NoFileNameError = 20006
    OutOfDiskSpaceError = 20007
    UnknownError = 20008

    @classmethod
    def name(cls, code):
        return next((k for k, v in vars(cls).items() if v == code), str(code))


DTYPES = ["int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"]
# (z, y, x): a single voxel, odd sizes inside one slab, and more than one slab of 16 slices.
SHAPES = [(1, 1, 1), (19, 21, 37), (40, 33, 17)]


def make_labels(shape, dtype, rng):
    """A label volume using the dtype's extremes, 0 and a few small values, in blobs and noise."""
    info = np.iinfo(dtype)
    values = np.array([0, 0, 0, 1, 7, info.min, info.max, info.max - 1], dtype=dtype)
    labels = values[rng.integers(0, len(values), size=shape)]
    # A solid region, so that blocks are not all noise.
    labels[: max(1, shape[0] // 2), : max(1, shape[1] // 2)] = values[4]
    return labels


class ErrorLog:
    """Collects the VTK error messages an object emits (and keeps them off the console)."""

    def __init__(self, *objects):
        self.messages = []
        for obj in objects:
            obj.AddObserver(vtkCommand.ErrorEvent, self)

    CallDataType = "string0"  # VTK passes the message text as call data

    def __call__(self, obj, event, data=None):
        self.messages.append(str(data))


def read(path, dataset=None, background=None, excluded=()):
    """Reads a file; returns (reader, decoded (z, y, x) array or None, decoded image, errors)."""
    reader = vtkSegmentationVolumeReader()
    reader.SetFileName(str(path))
    if dataset:
        reader.SetDatasetName(dataset)
    if background is not None:
        reader.SetBackgroundLabel(background)
    for label in excluded:
        reader.AddExcludedLabel(label)
    decode = vtkSegmentationSVDAGToImageData()
    decode.SetInputConnection(reader.GetOutputPort())
    log = ErrorLog(reader, reader.GetExecutive(), decode, decode.GetExecutive())
    decode.Update()
    image = decode.GetOutput()
    scalars = image.GetPointData().GetScalars()
    if scalars is None or log.messages:
        return reader, None, image, log.messages
    dims = image.GetDimensions()
    return reader, vtk_to_numpy(scalars).reshape(dims[::-1]), image, log.messages


def assert_reads(path, expected, fmt, spacing=(1, 1, 1), origin=(0, 0, 0), direction=None):
    reader, decoded, image, errors = read(path)
    assert errors == []
    assert reader.GetErrorCode() == 0
    assert reader.GetFileFormat() == fmt
    assert reader.CanReadFile(str(path)) == 1
    assert decoded.dtype == expected.dtype
    np.testing.assert_array_equal(decoded, expected)
    np.testing.assert_allclose(image.GetSpacing(), spacing, rtol=1e-12)
    np.testing.assert_allclose(image.GetOrigin(), origin, rtol=1e-12, atol=1e-12)
    if direction is not None:
        m = image.GetDirectionMatrix()
        got = [[m.GetElement(r, c) for c in range(3)] for r in range(3)]
        np.testing.assert_allclose(got, direction, atol=1e-12)
    return reader


def image_from_numpy(labels, spacing=(1, 1, 1), origin=(0, 0, 0)):
    image = vtkImageData()
    image.SetDimensions(labels.shape[2], labels.shape[1], labels.shape[0])
    image.SetSpacing(spacing)
    image.SetOrigin(origin)
    image.GetPointData().SetScalars(numpy_to_vtk(labels.ravel(), deep=True))
    return image


# ----------------------------------------------------------------------------------------- NRRD


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("encoding", ["raw", "gzip"])
def test_nrrd(tmp_path, rng, shape, dtype, encoding):
    labels = make_labels(shape, dtype, rng)
    directions = np.array([[0.0, 0.5, 0.0], [2.0, 0.0, 0.0], [0.0, 0.0, -1.25]])  # one row per axis
    header = {
        "encoding": encoding,
        "space": "left-posterior-superior",
        "space directions": directions,
        "space origin": np.array([-4.5, 3.0, 12.0]),
    }
    path = tmp_path / "labels.nrrd"
    nrrd.write(str(path), labels, header, index_order="C")
    assert_reads(path, labels, "NRRD", spacing=(0.5, 2.0, 1.25), origin=(-4.5, 3.0, 12.0),
                 direction=[[0, 1, 0], [1, 0, 0], [0, 0, -1]])


@pytest.mark.parametrize("encoding", ["raw", "gzip"])
def test_nrrd_detached_header(tmp_path, rng, encoding):
    labels = make_labels((40, 33, 17), "uint16", rng)
    path = tmp_path / "labels.nhdr"
    nrrd.write(str(path), labels, {"encoding": encoding, "spacings": [0.5, 1.5, 3.0]},
               detached_header=True, index_order="C")
    assert len(list(tmp_path.iterdir())) == 2
    assert_reads(path, labels, "NRRD", spacing=(0.5, 1.5, 3.0))


@pytest.mark.parametrize("encoding", ["raw", "gzip"])
def test_nrrd_big_endian(tmp_path, rng, encoding):
    labels = make_labels((19, 21, 37), "int32", rng)
    path = tmp_path / "big.nrrd"
    nrrd.write(str(path), labels.astype(">i4"), {"encoding": encoding}, index_order="C")
    with open(path, "rb") as f:
        assert b"endian: big" in f.read(400)
    assert_reads(path, labels, "NRRD")


# The NRRD type spellings teem accepts, one per dtype beside pynrrd's own.
SPELLINGS = [
    ("signed char", "int8"), ("uchar", "uint8"), ("unsigned char", "uint8"),
    ("short int", "int16"), ("signed short int", "int16"), ("ushort", "uint16"),
    ("unsigned short int", "uint16"), ("int", "int32"), ("signed int", "int32"),
    ("uint", "uint32"), ("unsigned int", "uint32"), ("longlong", "int64"),
    ("long long int", "int64"), ("signed long long int", "int64"), ("ulonglong", "uint64"),
    ("unsigned long long int", "uint64"), ("uint64_t", "uint64"), ("int8_t", "int8"),
]


@pytest.mark.parametrize("spelling,dtype", SPELLINGS)
def test_nrrd_type_spellings(tmp_path, rng, spelling, dtype):
    labels = make_labels((3, 4, 5), dtype, rng)
    header = (
        "NRRD0004\n# written by hand\n"
        f"type: {spelling}\ndimension: 3\nsizes: 5 4 3\nendian: little\nencoding: raw\n"
        "spacings: 2 3 4\nsome key:=some value\n\n"
    )
    path = tmp_path / "hand.nrrd"
    path.write_bytes(header.encode() + labels.astype(labels.dtype.newbyteorder("<")).tobytes())
    assert_reads(path, labels, "NRRD", spacing=(2, 3, 4))


def test_slicer_segmentation_labelmap(tmp_path, rng):
    """A 3D Slicer .seg.nrrd holding one labelmap layer (3D) reads like any labelmap."""
    labels = make_labels((19, 21, 37), "uint8", rng)
    header = {
        "encoding": "gzip",
        "space": "right-anterior-superior",
        "space directions": np.eye(3) * 0.75,
        "space origin": np.array([1.0, 2.0, 3.0]),
        "kinds": ["domain", "domain", "domain"],
        "Segment0_ID": "Segment_1",
        "Segment0_LabelValue": "1",
        "Segment0_Layer": "0",
    }
    path = tmp_path / "case.seg.nrrd"
    nrrd.write(str(path), labels, header, index_order="C")
    assert_reads(path, labels, "NRRD", spacing=(0.75,) * 3, origin=(1, 2, 3))


@pytest.mark.parametrize("name", shared_volumes())
def test_shared_volumes(shared_data, name):
    path = shared_data / f"{name}.nrrd"
    expected, header = nrrd.read(str(path), index_order="C")
    reader, decoded, image, errors = read(path)
    assert errors == [] and reader.GetErrorCode() == 0
    assert decoded.dtype == expected.dtype
    np.testing.assert_array_equal(decoded, expected)
    if "space directions" in header:
        np.testing.assert_allclose(
            image.GetSpacing(), np.linalg.norm(header["space directions"], axis=1))


# ----------------------------------------------------------------------------------------- NIfTI


@pytest.mark.parametrize("suffix", [".nii", ".nii.gz"])
@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("dtype", DTYPES)
def test_nifti(tmp_path, rng, suffix, shape, dtype):
    labels = make_labels(shape, dtype, rng)  # (z, y, x)
    # A rotated, anisotropic affine with a negative determinant (qfac = -1 in the qform).
    affine = np.array([[0.0, -2.0, 0.0, 10.0], [1.5, 0.0, 0.0, -3.0], [0.0, 0.0, -0.5, 7.0],
                       [0.0, 0.0, 0.0, 1.0]])
    path = tmp_path / f"labels{suffix}"
    nibabel.save(nibabel.Nifti1Image(np.ascontiguousarray(labels.transpose(2, 1, 0)), affine,
                                      dtype=labels.dtype), path)
    loaded = nibabel.load(path)
    array = np.asarray(loaded.dataobj)  # (x, y, z): nibabel's order
    expected = np.ascontiguousarray(array.transpose(2, 1, 0))
    np.testing.assert_array_equal(expected, labels)
    a = loaded.affine
    spacing = np.linalg.norm(a[:3, :3], axis=0)
    assert_reads(path, expected, "NIfTI", spacing=spacing, origin=a[:3, 3],
                 direction=a[:3, :3] / spacing)


@pytest.mark.parametrize("kind", ["nifti2", "pair"])
def test_nifti2_and_pairs(tmp_path, rng, kind):
    """NIfTI-2 single files and NIfTI-1 .hdr/.img pairs."""
    labels = make_labels((40, 33, 17), "uint32", rng)
    affine = np.diag([0.5, 0.75, 1.25, 1.0])
    affine[:3, 3] = [3.0, -1.0, 2.0]
    data = np.ascontiguousarray(labels.transpose(2, 1, 0))
    if kind == "nifti2":
        path = tmp_path / "labels2.nii"
        nibabel.save(nibabel.Nifti2Image(data, affine, dtype=np.uint32), path)
    else:
        path = tmp_path / "labels.hdr"
        nibabel.save(nibabel.Nifti1Pair(data, affine, dtype=np.uint32), path)
        assert (tmp_path / "labels.img").exists()
    assert_reads(path, labels, "NIfTI", spacing=(0.5, 0.75, 1.25), origin=(3.0, -1.0, 2.0))


@pytest.mark.parametrize("flip", [False, True])
def test_nifti_qform_only(tmp_path, rng, flip):
    """A file with only a qform (sform code 0): geometry from the quaternion, as nibabel."""
    labels = make_labels((40, 33, 17), "int16", rng)
    angle = 0.3
    affine = np.eye(4)
    affine[:3, :3] = np.array([[np.cos(angle), -np.sin(angle), 0], [np.sin(angle), np.cos(angle), 0],
                               [0, 0, 1]]) @ np.diag([0.8, 1.1, -2.0 if flip else 2.0])
    affine[:3, 3] = [5.0, -6.0, 7.0]
    image = nibabel.Nifti1Image(np.ascontiguousarray(labels.transpose(2, 1, 0)), None)
    image.set_qform(affine, code=1)
    image.set_sform(None, code=0)
    path = tmp_path / "qform.nii"
    nibabel.save(image, path)
    loaded = nibabel.load(path)
    assert loaded.header["sform_code"] == 0 and loaded.header["qform_code"] == 1
    a = loaded.affine
    spacing = np.linalg.norm(a[:3, :3], axis=0)
    reader, decoded, out, errors = read(path)
    assert errors == []
    np.testing.assert_array_equal(decoded, np.asarray(loaded.dataobj).transpose(2, 1, 0))
    np.testing.assert_allclose(out.GetSpacing(), spacing, rtol=1e-6)
    np.testing.assert_allclose(out.GetOrigin(), a[:3, 3], atol=1e-6)


# ------------------------------------------------------------------------------------------ TIFF


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("dtype", DTYPES)
def test_tiff(tmp_path, rng, shape, dtype):
    labels = make_labels(shape, dtype, rng)
    path = tmp_path / "labels.tif"
    tifffile.imwrite(path, labels, photometric="minisblack")
    assert len(tifffile.TiffFile(path).pages) == shape[0]
    assert_reads(path, labels, "TIFF")


@pytest.mark.parametrize("options", [dict(tile=(16, 16)), dict(compression="zlib"),
                                     dict(compression="zlib", tile=(16, 32), byteorder=">"),
                                     dict(rowsperstrip=5, byteorder=">")])
def test_tiff_layouts(tmp_path, rng, options):
    labels = make_labels((20, 45, 38), "uint16", rng)
    path = tmp_path / "layout.tif"
    tifffile.imwrite(path, labels, photometric="minisblack", **options)
    assert_reads(path, labels, "TIFF")


# ------------------------------------------------------------------------------------------ HDF5


@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("dtype", DTYPES)
def test_hdf5(tmp_path, rng, shape, dtype):
    labels = make_labels(shape, dtype, rng)
    path = tmp_path / "labels.h5"
    with h5py.File(path, "w") as f:
        f.create_dataset("volumes/labels", data=labels, chunks=True, compression="gzip")
        f["raw_2d"] = np.zeros((4, 4), np.uint8)  # not a volume: ignored
        f["float_3d"] = np.zeros((2, 2, 2), np.float32)  # not integer: ignored
    assert_reads(path, labels, "HDF5")


def test_hdf5_dataset_choice(tmp_path, rng):
    a = make_labels((19, 21, 37), "uint32", rng)
    b = make_labels((3, 4, 5), "int16", rng)
    path = tmp_path / "two.h5"
    with h5py.File(path, "w") as f:
        f["a"] = a
        f["group/b"] = b.astype(">i2")  # big-endian on disk
    reader, decoded, _, errors = read(path)  # ambiguous without a dataset name
    assert decoded is None and reader.GetErrorCode() != 0
    assert any("2 3D integer datasets" in e and "SetDatasetName" in e for e in errors)
    np.testing.assert_array_equal(read(path, dataset="/a")[1], a)
    np.testing.assert_array_equal(read(path, dataset="group/b")[1], b)
    reader, decoded, _, errors = read(path, dataset="/missing")
    assert decoded is None and any("no dataset '/missing'" in e for e in errors)


# ------------------------------------------------------------------------- MetaImage and VTK XML

# vtkMetaImageWriter 9.1 writes no 64-bit types ("Unknown scalar type"): those are written by
# hand below.
METAIMAGE_WRITER_DTYPES = DTYPES[:6]


def metaimage_header_geometry(path):
    """Spacing and origin as the file states them, padded to 3 axes (VTK's writer drops unit
    trailing axes: a 1x1x1 image is written with NDims = 1)."""
    text = path.read_bytes().split(b"ElementDataFile")[0].decode()
    fields = dict(line.split(" = ", 1) for line in text.splitlines() if " = " in line)
    spacing = [float(v) for v in fields["ElementSpacing"].split()]
    origin = [float(v) for v in fields["Offset"].split()]
    return spacing + [1.0] * (3 - len(spacing)), origin + [0.0] * (3 - len(origin))


@pytest.mark.parametrize("suffix,compress", [(".mha", False), (".mha", True), (".mhd", False)])
@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("dtype", METAIMAGE_WRITER_DTYPES)
def test_metaimage(tmp_path, rng, suffix, compress, shape, dtype):
    labels = make_labels(shape, dtype, rng)
    path = tmp_path / f"labels{suffix}"
    writer = vtkMetaImageWriter()
    writer.SetFileName(str(path))
    writer.SetCompression(compress)
    writer.SetInputData(image_from_numpy(labels, (0.5, 0.25, 2.0), (1.0, -2.0, 3.5)))
    writer.Write()
    spacing, origin = metaimage_header_geometry(path)
    if shape != (1, 1, 1):
        assert spacing == [0.5, 0.25, 2.0] and origin == [1.0, -2.0, 3.5]
    assert_reads(path, labels, "MetaImage", spacing=spacing, origin=origin)


@pytest.mark.parametrize("compress", [False, True])
@pytest.mark.parametrize("dtype", ["int64", "uint64"])
@pytest.mark.parametrize("msb", [False, True])
def test_metaimage_by_hand(tmp_path, rng, compress, dtype, msb):
    """64-bit MetaImage written the way ITK writes it (MET_LONG_LONG), either byte order."""
    labels = make_labels((40, 33, 17), dtype, rng)
    data = labels.astype(labels.dtype.newbyteorder(">" if msb else "<")).tobytes()
    if compress:
        data = zlib.compress(data)
    met = "MET_LONG_LONG" if dtype == "int64" else "MET_ULONG_LONG"
    header = (
        "ObjectType = Image\nNDims = 3\nBinaryData = True\n"
        f"BinaryDataByteOrderMSB = {msb}\nCompressedData = {compress}\n"
        + (f"CompressedDataSize = {len(data)}\n" if compress else "")
        + "TransformMatrix = 0 1 0 -1 0 0 0 0 1\nOffset = 1 2 3\nElementSpacing = 0.5 1 2\n"
        f"DimSize = 17 33 40\nElementType = {met}\nElementDataFile = LOCAL\n"
    )
    path = tmp_path / "hand.mha"
    path.write_bytes(header.encode() + data)
    assert_reads(path, labels, "MetaImage", spacing=(0.5, 1, 2), origin=(1, 2, 3),
                 direction=[[0, -1, 0], [1, 0, 0], [0, 0, 1]])


@pytest.mark.parametrize("mode", ["Ascii", "Binary", "Appended"])
@pytest.mark.parametrize("shape", SHAPES)
@pytest.mark.parametrize("dtype", DTYPES)
def test_vti(tmp_path, rng, mode, shape, dtype):
    labels = make_labels(shape, dtype, rng)
    path = tmp_path / "labels.vti"
    image = image_from_numpy(labels, (0.5, 0.25, 2.0), (1.0, -2.0, 3.5))
    image.SetDirectionMatrix(0, -1, 0, 1, 0, 0, 0, 0, 1)
    writer = vtkXMLImageDataWriter()
    writer.SetFileName(str(path))
    getattr(writer, f"SetDataModeTo{mode}")()
    writer.SetInputData(image)
    writer.Write()
    assert_reads(path, labels, "VTKImageData", spacing=(0.5, 0.25, 2.0), origin=(1.0, -2.0, 3.5),
                 direction=[[0, -1, 0], [1, 0, 0], [0, 0, 1]])


# ----------------------------------------------------------------------------------------- .svdag


def test_svdag_file(tmp_path, rng):
    labels = make_labels((40, 33, 17), "int64", rng)
    build = vtkImageDataToSegmentationSVDAG()
    build.SetInputData(image_from_numpy(labels, (1, 2, 3), (4, 5, 6)))
    writer = vtkSegmentationSVDAGWriter()
    path = tmp_path / "labels.svdag"
    writer.SetFileName(str(path))
    writer.SetInputConnection(build.GetOutputPort())
    writer.Write()
    assert writer.GetErrorCode() == 0
    assert_reads(path, labels, "SVDAG", spacing=(1, 2, 3), origin=(4, 5, 6))
    # Other labels than the file's: decoded and compressed again.
    reader, decoded, _, errors = read(path, background=7, excluded=[1])
    assert errors == []
    expected = labels.copy()
    expected[(labels == 7) | (labels == 1)] = 7
    np.testing.assert_array_equal(decoded, expected)


def test_background_and_excluded_labels(tmp_path, rng):
    labels = make_labels((19, 21, 37), "uint8", rng)
    path = tmp_path / "labels.nrrd"
    nrrd.write(str(path), labels, {"encoding": "gzip"}, index_order="C")
    reader, decoded, _, errors = read(path, background=-1, excluded=[7])  # -1 is 255 in uint8
    assert errors == []
    expected = labels.copy()
    expected[(labels == 255) | (labels == 7)] = 255
    np.testing.assert_array_equal(decoded, expected)
    svdag = reader.GetOutput()
    values = vtk_to_numpy(svdag.NewLabelValues())
    assert 255 not in values and 7 not in values


def test_reader_api():
    reader = vtkSegmentationVolumeReader()
    extensions = reader.GetFileExtensions().split()
    for ext in [".nrrd", ".nhdr", ".mha", ".mhd", ".vti", ".nii", ".nii.gz", ".tif", ".h5", ".svdag"]:
        assert ext in extensions
    assert reader.GetDescriptiveName()
    assert reader.GetFileFormat() == ""


def test_progress_events(tmp_path, rng):
    labels = make_labels((40, 33, 17), "uint16", rng)
    path = tmp_path / "labels.nrrd"
    nrrd.write(str(path), labels, {"encoding": "gzip"}, index_order="C")
    reader = vtkSegmentationVolumeReader()
    reader.SetFileName(str(path))
    progress = []
    reader.AddObserver(vtkCommand.ProgressEvent, lambda o, e: progress.append(o.GetProgress()))
    reader.Update()
    # One event per slab of 16 slices (3 slabs); the executive adds its own final 1.0.
    assert sorted(set(p for p in progress if p > 0)) == pytest.approx([16 / 40, 32 / 40, 1.0])


def test_abort_leaves_no_volume(tmp_path, rng):
    labels = make_labels((40, 33, 17), "uint16", rng)
    path = tmp_path / "labels.nrrd"
    nrrd.write(str(path), labels, {"encoding": "gzip"}, index_order="C")
    reader = vtkSegmentationVolumeReader()
    reader.SetFileName(str(path))
    reader.AddObserver(vtkCommand.ProgressEvent, lambda o, e: o.SetAbortExecute(1))
    log = ErrorLog(reader.GetExecutive())
    reader.Update()
    assert not reader.GetOutput().HasVolume()


def test_failed_read_clears_previous_output(tmp_path, rng):
    """After a good file, a bad one leaves no stale volume behind."""
    labels = make_labels((5, 6, 7), "uint8", rng)
    good = tmp_path / "good.nrrd"
    nrrd.write(str(good), labels, index_order="C")
    reader = vtkSegmentationVolumeReader()
    log = ErrorLog(reader, reader.GetExecutive())
    reader.SetFileName(str(good))
    reader.Update()
    assert reader.GetOutput().HasVolume() and reader.GetFileFormat() == "NRRD"
    reader.SetFileName(str(tmp_path / "missing.nrrd"))
    reader.Update()
    assert reader.GetErrorCode() == vtkErrorCode.FileNotFoundError
    assert not reader.GetOutput().HasVolume() and reader.GetFileFormat() == ""
    assert log.messages


def test_information_pass_then_data(tmp_path, rng):
    """UpdateInformation opens the file once; the following Update streams from that source."""
    labels = make_labels((40, 33, 17), "int32", rng)
    path = tmp_path / "labels.nii.gz"
    nibabel.save(nibabel.Nifti1Image(labels.transpose(2, 1, 0), np.eye(4), dtype=np.int32), path)
    reader = vtkSegmentationVolumeReader()
    reader.SetFileName(str(path))
    reader.UpdateInformation()
    assert reader.GetFileFormat() == "NIfTI" and not reader.GetOutput().HasVolume()
    reader.Update()
    decode = vtkSegmentationSVDAGToImageData()
    decode.SetInputConnection(reader.GetOutputPort())
    decode.Update()
    decoded = vtk_to_numpy(decode.GetOutput().GetPointData().GetScalars()).reshape(labels.shape)
    np.testing.assert_array_equal(decoded, labels)
    # A second update with a changed setting reads the file again, from the start.
    reader.SetBackgroundLabel(int(labels[0, 0, 0]))
    decode.Update()
    again = vtk_to_numpy(decode.GetOutput().GetPointData().GetScalars()).reshape(labels.shape)
    np.testing.assert_array_equal(again, labels)


# -------------------------------------------------------------------------------------- bad input

# Runs in a fresh interpreter: reads a file, prints the reader's result as JSON.
CHILD = textwrap.dedent("""
    import json, sys
    from vtkmodules.vtkCommonCore import vtkCommand
    from vtksvdag.vtkSVDAGIO import vtkSegmentationVolumeReader
    errors = []
    def log(obj, event, data=None):
        errors.append(str(data))
    log.CallDataType = "string0"
    reader = vtkSegmentationVolumeReader()
    reader.AddObserver(vtkCommand.ErrorEvent, log)
    reader.GetExecutive().AddObserver(vtkCommand.ErrorEvent, log)
    can = reader.CanReadFile(sys.argv[1])
    reader.SetFileName(sys.argv[1])
    reader.Update()
    out = reader.GetOutput()
    print(json.dumps({"code": reader.GetErrorCode(), "errors": errors, "can": can,
                      "has_volume": bool(out.HasVolume())}))
""")


def read_in_child(path):
    env = dict(os.environ)
    result = subprocess.run([sys.executable, "-c", CHILD, str(path)], capture_output=True,
                            text=True, timeout=120, env=env)
    assert result.returncode == 0, f"reader crashed (rc {result.returncode}): {result.stderr[-2000:]}"
    return json.loads(result.stdout.strip().splitlines()[-1])


def assert_fails(path, code=None, message=None):
    r = read_in_child(path)
    assert r["code"] != 0 and not r["has_volume"] and r["errors"], r
    if code is not None:
        assert r["code"] == code, (vtkErrorCode.name(r["code"]), r)
    if message is not None:
        assert any(message in e for e in r["errors"]), r
    return r


def truncate(path, keep):
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * keep)] if isinstance(keep, float) else data[:keep])


def test_missing_file(tmp_path):
    assert_fails(tmp_path / "nothing.nrrd", vtkErrorCode.FileNotFoundError, "not found")


def test_random_file_is_not_readable(tmp_path, rng):
    path = tmp_path / "random.nrrd"
    path.write_bytes(rng.integers(0, 256, 5000, dtype=np.uint8).tobytes())
    r = assert_fails(path, vtkErrorCode.UnrecognizedFileTypeError)
    assert r["can"] == 0
    empty = tmp_path / "empty.nii"
    empty.write_bytes(b"")
    assert assert_fails(empty, vtkErrorCode.UnrecognizedFileTypeError)["can"] == 0


def write_good(fmt, tmp_path, labels):
    """Writes a good file of a format (for the truncation tests)."""
    if fmt == "nrrd-raw":
        path = tmp_path / "t.nrrd"
        nrrd.write(str(path), labels, {"encoding": "raw"}, index_order="C")
    elif fmt == "nrrd-gzip":
        path = tmp_path / "t.nrrd"
        nrrd.write(str(path), labels, {"encoding": "gzip"}, index_order="C")
    elif fmt == "nii":
        path = tmp_path / "t.nii"
        nibabel.save(nibabel.Nifti1Image(labels.transpose(2, 1, 0), np.eye(4)), path)
    elif fmt == "nii.gz":
        path = tmp_path / "t.nii.gz"
        nibabel.save(nibabel.Nifti1Image(labels.transpose(2, 1, 0), np.eye(4)), path)
    elif fmt == "tif":
        path = tmp_path / "t.tif"
        tifffile.imwrite(path, labels, photometric="minisblack")
    elif fmt == "h5":
        path = tmp_path / "t.h5"
        with h5py.File(path, "w") as f:
            f["labels"] = labels
    elif fmt in ("mha", "mha-zlib"):
        path = tmp_path / "t.mha"
        writer = vtkMetaImageWriter()
        writer.SetFileName(str(path))
        writer.SetCompression(fmt == "mha-zlib")
        writer.SetInputData(image_from_numpy(labels))
        writer.Write()
    elif fmt == "vti":
        path = tmp_path / "t.vti"
        writer = vtkXMLImageDataWriter()
        writer.SetFileName(str(path))
        writer.SetInputData(image_from_numpy(labels))
        writer.Write()
    elif fmt == "svdag":
        path = tmp_path / "t.svdag"
        build = vtkImageDataToSegmentationSVDAG()
        build.SetInputData(image_from_numpy(labels))
        writer = vtkSegmentationSVDAGWriter()
        writer.SetFileName(str(path))
        writer.SetInputConnection(build.GetOutputPort())
        writer.Write()
    return path


FORMATS = ["nrrd-raw", "nrrd-gzip", "nii", "nii.gz", "tif", "h5", "mha", "mha-zlib", "vti", "svdag"]


@pytest.mark.parametrize("fmt", FORMATS)
def test_truncated_files(tmp_path, rng, fmt):
    labels = rng.integers(0, 1000, size=(40, 33, 17)).astype(np.uint16)
    path = write_good(fmt, tmp_path, labels)
    assert read(path)[3] == []  # the whole file reads
    truncate(path, 0.6)
    assert_fails(path)
    truncate(path, 40)  # only the start of the header is left
    assert_fails(path)


def test_corrupt_gzip_stream(tmp_path, rng):
    labels = rng.integers(0, 1000, size=(40, 33, 17)).astype(np.uint16)
    path = write_good("nrrd-gzip", tmp_path, labels)
    data = bytearray(path.read_bytes())
    start = data.index(b"\n\n") + 2
    for i in range(start + 200, start + 260):
        data[i] ^= 0x5A
    path.write_bytes(bytes(data))
    assert_fails(path, vtkErrorCode.FileFormatError, "corrupt compressed data")


def test_wrong_magic(tmp_path, rng):
    labels = rng.integers(0, 9, size=(4, 5, 6)).astype(np.uint8)
    path = write_good("nrrd-raw", tmp_path, labels)
    data = path.read_bytes()
    path.write_bytes(b"NRRX" + data[4:])
    r = assert_fails(path, vtkErrorCode.UnrecognizedFileTypeError)
    assert r["can"] == 0


@pytest.mark.parametrize("fmt", ["nrrd", "nii", "tif", "h5", "mha", "vti"])
def test_float_data(tmp_path, fmt):
    data = np.zeros((4, 5, 6), np.float32)
    if fmt == "nrrd":
        path = tmp_path / "f.nrrd"
        nrrd.write(str(path), data, index_order="C")
    elif fmt == "nii":
        path = tmp_path / "f.nii"
        nibabel.save(nibabel.Nifti1Image(data, np.eye(4)), path)
    elif fmt == "tif":
        path = tmp_path / "f.tif"
        tifffile.imwrite(path, data, photometric="minisblack")
    elif fmt == "h5":
        path = tmp_path / "f.h5"
        with h5py.File(path, "w") as f:
            f.create_dataset("labels", data=data)
        # The file holds no integer volume, so the dataset is named explicitly.
        r = read(path, dataset="labels")
        assert r[1] is None and any("label volumes need integer scalars" in e and "float32" in e
                                    for e in r[3])
        return
    else:
        path = tmp_path / f"f.{fmt}"
        writer = vtkMetaImageWriter() if fmt == "mha" else vtkXMLImageDataWriter()
        writer.SetFileName(str(path))
        writer.SetInputData(image_from_numpy(data))
        writer.Write()
    assert_fails(path, vtkErrorCode.FileFormatError, "label volumes need integer scalars")
    assert_fails(path, message=f"{path.name} has float32")


def test_four_dimensional_volumes_are_rejected(tmp_path):
    nii = tmp_path / "time.nii.gz"
    nibabel.save(nibabel.Nifti1Image(np.zeros((6, 5, 4, 3), np.uint8), np.eye(4), dtype=np.uint8),
                 nii)
    assert_fails(nii, vtkErrorCode.FileFormatError, "label volumes need 3")
    h5 = tmp_path / "planes.h5"
    with h5py.File(h5, "w") as f:
        f["labels"] = np.zeros((4, 5), np.uint8)
    r = read(h5, dataset="labels")
    assert r[1] is None and any("label volumes need 3" in e for e in r[3])
    tif = tmp_path / "mixed.tif"
    with tifffile.TiffWriter(tif) as w:
        w.write(np.zeros((8, 8), np.uint8), photometric="minisblack")
        w.write(np.zeros((8, 9), np.uint8), photometric="minisblack")
    assert_fails(tif, vtkErrorCode.FileFormatError, "differs from page 0")


def test_scaled_nifti_is_rejected(tmp_path):
    image = nibabel.Nifti1Image(np.zeros((6, 5, 4), np.int16), np.eye(4), dtype=np.int16)
    image.header.set_slope_inter(2.0, 1.0)
    path = tmp_path / "scaled.nii"
    nibabel.save(image, path)
    assert_fails(path, vtkErrorCode.FileFormatError, "scales its values")


def test_multicomponent_data(tmp_path):
    image = vtkImageData()
    image.SetDimensions(3, 4, 5)
    image.GetPointData().SetScalars(numpy_to_vtk(np.zeros((60, 3), np.uint8), deep=True))
    path = tmp_path / "rgb.vti"
    writer = vtkXMLImageDataWriter()
    writer.SetFileName(str(path))
    writer.SetInputData(image)
    writer.Write()
    assert_fails(path, vtkErrorCode.FileFormatError, "one component per voxel")
    rgb = tmp_path / "rgb.tif"
    tifffile.imwrite(rgb, np.zeros((2, 8, 8, 3), np.uint8), photometric="rgb")
    assert_fails(rgb, vtkErrorCode.FileFormatError, "one sample per pixel")


def nrrd_header(**fields):
    base = {"type": "uint8", "dimension": "3", "sizes": "2 2 2", "encoding": "raw"}
    base.update(fields)
    return ("NRRD0004\n" + "".join(f"{k.replace('_', ' ')}: {v}\n" for k, v in base.items()
                                    if v is not None) + "\n").encode()


@pytest.mark.parametrize("fields,message", [
    (dict(sizes="2000000000 2000000000 2000000000"), "too large"),
    (dict(sizes="0 2 2"), "outside 1 .. 2^31-1"),
    (dict(sizes="99999999999 2 2"), "outside 1 .. 2^31-1"),
    (dict(sizes="2 2"), "'sizes' must list 3 values"),
    (dict(dimension="2", sizes="2 2"), "label volumes need 3"),
    (dict(type="float"), "label volumes need integer scalars"),
    (dict(type="complex"), "unknown NRRD type"),
    (dict(type=None), "no 'type' field"),
    (dict(encoding="bzip2"), "not supported"),
    (dict(type="uint16", endian=None), "no 'endian' field"),
    (dict(space_directions="(1,0,0) (0,0,0) (0,0,1)"), "zero length"),
    (dict(space_directions="(1,0,0) (0,1,0)"), "3 vectors"),
    (dict(space_directions="(1,0) (0,1) (0,1)"), "3-D vectors"),
    (dict(space_origin="(nan,0,0)"), "non-finite"),
    (dict(spacings="1 0 1"), "spacing must be finite and positive"),
    (dict(kinds="RGB-color domain domain"), "one integer component"),
    (dict(data_file="missing.raw"), "cannot open its data file"),
])
def test_bad_nrrd_headers(tmp_path, fields, message):
    path = tmp_path / "bad.nrrd"
    path.write_bytes(nrrd_header(**fields) + bytes(64))
    assert_fails(path, message=message)


def test_nrrd_gzip_claiming_too_many_voxels(tmp_path):
    """Well-formed but absurd sizes with little gzip data: refused before any allocation."""
    path = tmp_path / "bomb.nrrd"
    path.write_bytes(nrrd_header(type="uint64", endian="little", encoding="gzip",
                                 sizes="65536 65536 16") + gzip.compress(bytes(1000)))
    assert_fails(path, vtkErrorCode.FileFormatError, "compressed bytes can hold")


def test_hdf5_slab_larger_than_memory(tmp_path):
    """A valid HDF5 file (chunked, nothing written) whose one slab would not fit in memory."""
    path = tmp_path / "huge.h5"
    with h5py.File(path, "w") as f:
        # 2^40 voxels (the most a volume may have), 8 TiB per slab of 16 slices.
        f.create_dataset("labels", shape=(16, 2**18, 2**18), dtype=np.uint64, chunks=(1, 64, 64))
    assert_fails(path, vtkErrorCode.OutOfDiskSpaceError, "more than this machine's memory")
    with h5py.File(path, "w") as f:
        f.create_dataset("labels", shape=(16, 2**20, 2**20), dtype=np.uint64, chunks=(1, 64, 64))
    assert_fails(path, vtkErrorCode.FileFormatError, "more than 2^40")


def test_nrrd_short_raw_data(tmp_path):
    path = tmp_path / "short.nrrd"
    path.write_bytes(nrrd_header(sizes="4 4 4") + bytes(63))
    assert_fails(path, vtkErrorCode.PrematureEndOfFileError, "truncated")


def test_nrrd_header_without_data(tmp_path):
    path = tmp_path / "nodata.nrrd"
    path.write_bytes(nrrd_header()[:-1])  # no blank line, no data
    assert_fails(path, vtkErrorCode.PrematureEndOfFileError)


def test_binary_garbage_after_magic(tmp_path, rng):
    path = tmp_path / "garbage.nrrd"
    path.write_bytes(b"NRRD0004" + rng.integers(0, 256, 3_000_000, dtype=np.uint8).tobytes())
    assert_fails(path, vtkErrorCode.FileFormatError)


def test_slicer_multilayer_segmentation_is_rejected(tmp_path):
    data = np.zeros((2, 5, 6, 7), np.uint8)  # (layer, x, y, z) as Slicer writes it, Fortran order
    header = {
        "encoding": "gzip",
        "kinds": ["list", "domain", "domain", "domain"],
        "space": "right-anterior-superior",
        "space directions": [[np.nan] * 3, [1, 0, 0], [0, 1, 0], [0, 0, 1]],
        "space origin": [0.0, 0.0, 0.0],
    }
    path = tmp_path / "layers.seg.nrrd"
    nrrd.write(str(path), data, header)
    assert_fails(path, vtkErrorCode.FileFormatError, "multi-layer segmentations")


def test_gzip_with_trailing_gzip_member(tmp_path, rng):
    """gzip files may hold several members; the data may span them."""
    labels = rng.integers(0, 9, size=(40, 33, 17)).astype(np.uint8)
    raw = labels.tobytes()
    half = len(raw) // 2
    path = tmp_path / "members.nrrd"
    path.write_bytes(nrrd_header(sizes="17 33 40", encoding="gzip") + gzip.compress(raw[:half]) +
                     gzip.compress(raw[half:]))
    assert_reads(path, labels, "NRRD")
