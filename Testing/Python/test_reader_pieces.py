"""Piece requests (UpdatePiece, what ParaView's ranks send) to vtkSegmentationVolumeReader and
vtkImageDataToSegmentationSVDAG: each piece is the volume's z-range of whole 16-slice slabs,
read and compressed alone, with the geometry of those slices, and the pieces together are the
whole volume bit for bit. The reference is numpy's slicing of the array the file was written
from (pynrrd, tifffile, VTK's XML writer)."""
import nrrd
import numpy as np
import pytest
import tifffile

import vtksvdag
from vtksvdag.volume import SegmentationVolume
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkIOXML import vtkXMLImageDataReader, vtkXMLImageDataWriter

from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG
from vtksvdag.vtkSVDAGIO import vtkSegmentationVolumeReader

from conftest import capture_errors

SHAPE = (70, 23, 19)  # (z, y, x): 5 slabs, the last one of 6 slices
DIRECTION = np.array([[0.0, -1.0, 0.0], [0.6, 0.0, 0.8], [-0.8, 0.0, 0.6]])  # rotation (rows)
SPACING = (0.5, 1.25, 2.0)
ORIGIN = (3.0, -7.0, 11.0)


def expected_ranges(depth, pieces):
    """The reader's rule, written out: the slabs in order, the first pieces one more."""
    slabs = -(-depth // 16)
    count = min(pieces, slabs)
    ranges, first = [], 0
    for p in range(pieces):
        n = 0 if p >= count else slabs // count + (1 if p < slabs % count else 0)
        ranges.append((16 * first, min(depth, 16 * (first + n))) if n else None)
        first += n
    return ranges


@pytest.fixture(scope="module")
def labels():
    rng = np.random.default_rng(7)
    coarse = rng.integers(0, 40, size=(8, 3, 3), dtype=np.uint16)
    zyx = np.kron(coarse, np.ones((9, 8, 7), dtype=np.uint16))[:SHAPE[0], :SHAPE[1], :SHAPE[2]]
    zyx[rng.random(SHAPE) < 0.02] = 1000  # noise: labels in many cells
    return zyx


@pytest.fixture(scope="module")
def files(labels, tmp_path_factory):
    out = tmp_path_factory.mktemp("pieces")
    xyz = np.ascontiguousarray(labels.transpose(2, 1, 0))
    # NRRD space directions are columns: the i-th is the world step along axis i.
    directions = (DIRECTION * np.array(SPACING)).T
    paths = {}
    for encoding in ("raw", "gzip"):
        paths[encoding] = out / f"labels_{encoding}.nrrd"
        nrrd.write(str(paths[encoding]), xyz, {
            "encoding": encoding, "space": "left-posterior-superior",
            "space directions": directions, "space origin": np.array(ORIGIN)})
    paths["tiff"] = out / "labels.tif"
    tifffile.imwrite(str(paths["tiff"]), labels)
    paths["svdag"] = out / "labels.svdag"
    vtksvdag.read(str(paths["raw"])).save(str(paths["svdag"]))
    return paths


def read_piece(path, piece, pieces):
    reader = vtkSegmentationVolumeReader()
    reader.SetFileName(str(path))
    errors = capture_errors(reader)
    reader.UpdatePiece(piece, pieces, 0)
    assert not errors, errors
    return reader.GetOutput()


def world(volume, ijk):
    return np.asarray(volume.origin) + np.asarray(volume.direction) @ (
        np.asarray(ijk, float) * np.asarray(volume.spacing))


@pytest.mark.parametrize("kind", ["raw", "gzip", "tiff", "svdag"])
@pytest.mark.parametrize("pieces", [1, 2, 3, 5, 7])
def test_pieces_are_the_volume_z_ranges(files, labels, kind, pieces):
    whole = vtksvdag.read(str(files[kind]))
    ranges = expected_ranges(SHAPE[0], pieces)
    parts = []
    for piece, z_range in enumerate(ranges):
        output = read_piece(files[kind], piece, pieces)
        if z_range is None:
            assert not output.HasVolume(), f"piece {piece} of {pieces} should be empty"
            continue
        z0, z1 = z_range
        volume = SegmentationVolume(output)
        assert volume.dims == (SHAPE[2], SHAPE[1], z1 - z0)
        assert volume.dtype == whole.dtype
        np.testing.assert_array_equal(volume.spacing, whole.spacing)
        np.testing.assert_array_equal(volume.direction, whole.direction)
        # The piece's first voxel is where the whole volume's voxel (0, 0, z0) is.
        np.testing.assert_allclose(volume.origin, world(whole, (0, 0, z0)), atol=1e-12)
        got = volume.to_numpy(axis_order="zyx")
        np.testing.assert_array_equal(got, labels[z0:z1])
        present = np.unique(labels[z0:z1])
        np.testing.assert_array_equal(volume.labels, present[present != whole.background])
        counts = dict(zip(*np.unique(labels[z0:z1], return_counts=True)))
        assert list(volume.label_voxel_counts) == [counts[v] for v in volume.labels]
        parts.append(got)
    np.testing.assert_array_equal(np.concatenate(parts), labels)


def test_nrrd_geometry_is_the_files(files):
    """The direction, spacing and origin written with pynrrd are what the whole read reports,
    so the pieces' origins above are checked against the file's own geometry."""
    whole = vtksvdag.read(str(files["raw"]))
    np.testing.assert_allclose(whole.direction, DIRECTION, atol=1e-12)
    np.testing.assert_allclose(whole.spacing, SPACING)
    np.testing.assert_allclose(whole.origin, ORIGIN)


def test_piece_builds_equal_a_build_of_the_slices(files, labels):
    """A piece is compressed exactly as its slices alone would be (same bytes in memory)."""
    z0, z1 = expected_ranges(SHAPE[0], 3)[1]
    piece = SegmentationVolume(read_piece(files["gzip"], 1, 3))
    alone = vtksvdag.from_numpy(labels[z0:z1], axis_order="zyx")
    assert piece.stats()["bytes_total"] == alone.stats()["bytes_total"]
    np.testing.assert_array_equal(piece.to_numpy(), alone.to_numpy())


def test_a_piece_outside_the_pieces_is_an_error(files):
    reader = vtkSegmentationVolumeReader()
    reader.SetFileName(str(files["raw"]))
    errors = capture_errors(reader)
    reader.UpdatePiece(3, 2, 0)
    assert not reader.GetOutput().HasVolume()
    assert errors and "piece 3 of 2" in errors[-1], errors


def label_image(labels):
    """`labels` (z, y, x) as a vtkImageData with extent starting at (2, -3, 5), the test's
    spacing, origin and direction."""
    image = vtkImageData()
    image.SetExtent(2, 2 + SHAPE[2] - 1, -3, -3 + SHAPE[1] - 1, 5, 5 + SHAPE[0] - 1)
    image.SetSpacing(SPACING)
    image.SetOrigin(ORIGIN)
    image.SetDirectionMatrix(DIRECTION.ravel())
    image.GetPointData().SetScalars(numpy_to_vtk(labels.ravel(), deep=True))
    return image


@pytest.mark.parametrize("source", ["image", "vti"])
@pytest.mark.parametrize("pieces", [1, 3, 7])
def test_compress_filter_pieces(labels, tmp_path, source, pieces):
    """The compress filter's pieces: from an image in memory (which brings its whole extent:
    the filter cuts the piece out) and from the XML reader (which reads the requested extent)."""
    image = label_image(labels)
    whole = SegmentationVolume(run_filter(image, 0, 1))
    np.testing.assert_array_equal(whole.to_numpy(axis_order="zyx"), labels)
    if source == "vti":
        writer = vtkXMLImageDataWriter()
        writer.SetFileName(str(tmp_path / "labels.vti"))
        writer.SetInputData(image)
        assert writer.Write() == 1
        upstream = vtkXMLImageDataReader()
        upstream.SetFileName(str(tmp_path / "labels.vti"))
    else:
        upstream = image
    parts = []
    for piece, z_range in enumerate(expected_ranges(SHAPE[0], pieces)):
        output = run_filter(upstream, piece, pieces)
        if z_range is None:
            assert not output.HasVolume()
            continue
        z0, z1 = z_range
        volume = SegmentationVolume(output)
        assert volume.dims == (SHAPE[2], SHAPE[1], z1 - z0)
        np.testing.assert_allclose(volume.origin, world(whole, (0, 0, z0)), atol=1e-12)
        np.testing.assert_allclose(volume.direction, DIRECTION, atol=1e-12)
        if source == "vti":  # only the piece's slices were read
            assert upstream.GetOutput().GetExtent()[4:] == (5 + z0, 5 + z1 - 1)
        parts.append(volume.to_numpy(axis_order="zyx"))
        np.testing.assert_array_equal(parts[-1], labels[z0:z1])
    np.testing.assert_array_equal(np.concatenate(parts), labels)


def run_filter(upstream, piece, pieces):
    compress = vtkImageDataToSegmentationSVDAG()
    if isinstance(upstream, vtkImageData):
        compress.SetInputData(upstream)
    else:
        compress.SetInputConnection(upstream.GetOutputPort())
    errors = capture_errors(compress)
    compress.UpdatePiece(piece, pieces, 0)
    assert not errors, errors
    return compress.GetOutput()
