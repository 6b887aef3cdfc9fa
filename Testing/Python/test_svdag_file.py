"""The .svdag writer and reader from Python: a real volume through the VTK pipeline into a file and
back (bit-identical), in every format version written, the file checked against the format as
IO/README.md documents it (parsed independently of the library, with struct, zlib, zstandard and
the fuzz harness's varint reader), and the error codes of both on bad input."""
import pathlib
import struct
import sys
import zlib

import nrrd
import numpy as np
import pytest
import zstandard
from conftest import compress_zyx
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonMisc import vtkErrorCode
from vtkmodules.vtkCommonDataModel import vtkImageData

from vtksvdag.vtkSVDAGCore import (
    vtkImageDataToSegmentationSVDAG,
    vtkSegmentationSVDAG,
    vtkSegmentationSVDAGToImageData,
)
from vtksvdag._svdagfile import DEFAULT_FORMAT_VERSION
from vtksvdag.vtkSVDAGIO import vtkSegmentationSVDAGWriter, vtkSegmentationVolumeReader

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "fuzz"))
from fuzz_readers import read_varint  # noqa: E402

MAGIC = b"\x89SVDAG\r\n"
SECTIONS = {1: "labels", 2: "blocks", 3: "roots", 4: "mids", 5: "leaves", 6: "coded volume",
            7: "DAG streams"}
#: The DAG streams of a 4.0 file, in their order (IO/README.md).
DAG_STREAMS = ("label values", "block cells", "block labels", "block roots", "root indices",
               "root headers", "root references", "mid indices", "mid headers", "mid references",
               "leaf indices", "leaves")


def compress_real_volume(path, spacing=(0.5, 0.75, 2.0), origin=(-4.0, 3.5, 10.0)):
    labels, _ = nrrd.read(str(path), index_order="C")  # (z, y, x)
    image = vtkImageData()
    image.SetDimensions(labels.shape[2], labels.shape[1], labels.shape[0])
    image.SetSpacing(*spacing)
    image.SetOrigin(*origin)
    image.GetPointData().SetScalars(numpy_to_vtk(np.ascontiguousarray(labels).ravel(), deep=True))
    build = vtkImageDataToSegmentationSVDAG()
    build.SetInputData(image)
    build.Update()
    return labels, build


def parse(data):
    """The header and raw section contents of a .svdag file, following IO/README.md."""
    assert data[:8] == MAGIC
    major, minor = struct.unpack_from("<HH", data, 8)
    header = {
        "version": (major, minor),
        "dims": struct.unpack_from("<3i", data, 12),
        "spacing": struct.unpack_from("<3d", data, 24),
        "origin": struct.unpack_from("<3d", data, 48),
        "direction": struct.unpack_from("<9d", data, 72),
        "scalar_type": struct.unpack_from("<I", data, 144)[0],
        "background": struct.unpack_from("<Q", data, 148)[0],
        "widths": struct.unpack_from("<5I", data, 156),
        "counts": dict(zip(("labels", "blocks", "roots", "mids", "leaves"),
                           struct.unpack_from("<5Q", data, 176))),
    }
    (count,) = struct.unpack_from("<I", data, 216)
    table_end = 220 + 36 * count
    (header_crc,) = struct.unpack_from("<I", data, table_end)
    assert header_crc == zlib.crc32(data[:table_end])
    sections = {}
    for i in range(count):
        sid, codec, offset, stored, raw, crc = struct.unpack_from("<IIQQQI", data, 220 + 36 * i)
        assert offset >= table_end + 4 and offset + stored <= len(data)
        payload = data[offset:offset + stored]
        if codec == 1:
            payload = zstandard.ZstdDecompressor().decompress(payload)
        else:
            assert codec == 0 and stored == raw
        assert len(payload) == raw
        assert zlib.crc32(payload) == crc
        sections[SECTIONS[sid]] = (codec, payload)
    return header, sections


def pooled_counts(svdag):
    """Nodes per level of the pooled form files store (the data object holds the compact form,
    whose leaf count is of the leaves stored apart), and that form's DAG bytes as a 2.0 file's
    sections hold them (the streams without their padding word)."""
    from vtksvdag import SegmentationVolume

    table = SegmentationVolume(svdag).encoding_statistics()
    words = lambda bits: -(-int(bits) // 32) * 4  # noqa: E731
    dag_bytes = words(table.loc["roots", "bits"]) + words(table.loc["mids", "bits"]) + int(
        table.loc["leaves", "bytes"])
    nodes = {level: int(table.loc[level, "nodes"]) for level in table.index}
    nodes["block_bytes"] = int(table.loc["blocks", "bytes"])
    return nodes, dag_bytes


@pytest.mark.parametrize("level", [0, 3, 19])
def test_writer_on_a_real_volume_follows_the_documented_format(shared_data, tmp_path, level):
    labels, build = compress_real_volume(shared_data / "dvid_fib19_64.nrrd")
    svdag = build.GetOutput()
    path = tmp_path / "fib19.svdag"
    writer = vtkSegmentationSVDAGWriter()
    writer.SetInputConnection(build.GetOutputPort())
    writer.SetFileName(str(path))
    writer.SetCompressionLevel(level)
    writer.SetFormatVersion(2)
    assert writer.Write() == 1
    assert writer.GetErrorCode() == vtkErrorCode.NoError
    data = path.read_bytes()
    assert not (tmp_path / "fib19.svdag.partial").exists()

    header, sections = parse(data)
    assert header["version"] == (2, 0)
    assert header["dims"] == (64, 64, 64)
    assert header["spacing"] == (0.5, 0.75, 2.0)
    assert header["origin"] == (-4.0, 3.5, 10.0)
    assert header["direction"] == (1, 0, 0, 0, 1, 0, 0, 0, 1)
    assert header["scalar_type"] == 7  # uint64
    assert header["background"] == 0
    counts = header["counts"]
    nodes, dag_bytes = pooled_counts(svdag)
    assert counts["blocks"] == svdag.GetNumberOfBlocks()
    assert counts["roots"] == svdag.GetNumberOfRootNodes() == nodes["roots"]
    assert counts["mids"] == svdag.GetNumberOfMidNodes() == nodes["mids"]
    assert counts["leaves"] == nodes["leaves"] >= svdag.GetNumberOfLeaves()

    # The label table holds the volume's labels with their exact voxel counts and bounds.
    table = np.frombuffer(sections["labels"][1], dtype=np.dtype(
        [("value", "<u8"), ("voxels", "<u8"), ("bounds", "<i4", 6)]))
    values, voxel_counts = np.unique(labels[labels != 0], return_counts=True)
    np.testing.assert_array_equal(table["value"], values)
    np.testing.assert_array_equal(table["value"], vtk_to_numpy(svdag.NewLabelValues()))
    np.testing.assert_array_equal(table["voxels"], voxel_counts)
    first = int(np.argmax(table["voxels"]))
    z, y, x = np.nonzero(labels == table["value"][first])
    assert list(table["bounds"][first]) == [x.min(), x.max(), y.min(), y.max(), z.min(), z.max()]

    # Section sizes: the counts, the block records and the in-memory sizes without padding.
    widths = header["widths"]
    block_bits = widths[0] + 24 + widths[1] + widths[2]
    assert len(sections["blocks"][1]) == 4 * -(-counts["blocks"] * block_bits // 32)
    assert len(sections["leaves"][1]) == 8 * counts["leaves"]
    assert len(sections["blocks"][1]) == 4 * -(-nodes["block_bytes"] // 4)  # whole words
    assert (len(sections["roots"][1]) + len(sections["mids"][1])
            + len(sections["leaves"][1])) == dag_bytes
    leaves = np.frombuffer(sections["leaves"][1], dtype="<u8")
    assert not np.any(leaves & 1)  # canonical leaves: voxel (0, 0, 0) empty

    if level == 0:
        assert all(codec == 0 for codec, _ in sections.values())
        assert len(data) == 220 + 36 * 5 + 4 + sum(len(p) for _, p in sections.values())
    else:
        assert sections["leaves"][0] == 1  # zstd
        assert len(data) < 220 + 36 * 5 + 4 + sum(len(p) for _, p in sections.values())


def test_format_3_holds_one_coded_section_and_the_rebuilt_counts(shared_data, tmp_path):
    labels, build = compress_real_volume(shared_data / "dvid_fib19_64.nrrd")
    svdag = build.GetOutput()
    writer = vtkSegmentationSVDAGWriter()
    writer.SetFormatVersion(3)
    writer.SetInputData(svdag)
    writer.SetFileName(str(tmp_path / "v3.svdag"))
    assert writer.Write() == 1
    header, sections = parse((tmp_path / "v3.svdag").read_bytes())
    assert header["version"] == (3, 0)
    assert header["dims"] == (64, 64, 64) and header["spacing"] == (0.5, 0.75, 2.0)
    assert list(sections) == ["coded volume"]
    codec, payload = sections["coded volume"]
    assert codec == 0  # stored as coded
    # Its table: one chunk for 64^3 voxels (one per 1024 cells), streams that fill the section,
    # block counts that add up; every stream starts with a range coder's zero byte.
    chunks, label_bytes = struct.unpack_from("<IQ", payload, 0)
    assert chunks == 1
    table = [struct.unpack_from("<QQ", payload, 12 + 16 * i) for i in range(chunks)]
    assert sum(n for _, n in table) == header["counts"]["blocks"]
    start = 12 + 16 * chunks
    assert start + label_bytes + sum(b for b, _ in table) == len(payload)
    for size in [label_bytes] + [b for b, _ in table]:
        assert payload[start] == 0
        start += size
    counts = header["counts"]
    nodes, _ = pooled_counts(svdag)
    assert counts["labels"] == len(np.unique(labels[labels != 0]))
    assert counts["blocks"] == svdag.GetNumberOfBlocks()
    assert counts["roots"] == svdag.GetNumberOfRootNodes() == nodes["roots"]
    assert counts["mids"] == svdag.GetNumberOfMidNodes() == nodes["mids"]
    assert counts["leaves"] == nodes["leaves"]
    # Far smaller than the volume in memory, and than format 2 at zstd's strongest level.
    assert len(payload) < 0.5 * svdag.GetCompressedSize()
    v2 = write(svdag, tmp_path / "v2.svdag", level=19, version=2)
    assert (tmp_path / "v3.svdag").stat().st_size < 0.6 * len(v2)

    writer.SetFormatVersion(7)
    assert writer.GetFormatVersion() == 4
    writer.SetFormatVersion(1)
    assert writer.GetFormatVersion() == 2
    assert "FormatVersion: 2" in str(writer)  # PrintSelf


def varints(data, at, n):
    """n unsigned LEB128 numbers of data from offset at, and the offset after them."""
    out = []
    for _ in range(n):
        value, at = read_varint(data, at)
        out.append(value)
    return out, at


def test_format_4_holds_the_dag_streams_and_the_decoded_counts(shared_data, tmp_path):
    labels, build = compress_real_volume(shared_data / "dvid_fib19_64.nrrd")
    svdag = build.GetOutput()
    writer = vtkSegmentationSVDAGWriter()
    assert writer.GetFormatVersion() == 4  # the default, the Python layer's too
    assert DEFAULT_FORMAT_VERSION == writer.GetFormatVersion()
    writer.SetInputData(svdag)
    writer.SetFileName(str(tmp_path / "v4.svdag"))
    assert writer.Write() == 1
    data = (tmp_path / "v4.svdag").read_bytes()
    header, sections = parse(data)
    assert header["version"] == (4, 0)
    assert list(sections) == ["DAG streams"]
    codec, payload = sections["DAG streams"]
    assert codec == 0
    sizes, at = varints(payload, 0, 2 * len(DAG_STREAMS))
    stored, raw = sizes[0::2], sizes[1::2]
    assert at + sum(stored) == len(payload)  # the frames fill the section
    streams = {}
    for name, n, r in zip(DAG_STREAMS, stored, raw):
        frame = payload[at:at + n]
        at += n
        streams[name] = frame if n == r else zstandard.ZstdDecompressor().decompress(frame)
        assert len(streams[name]) == r, name
    counts = header["counts"]
    nodes, _ = pooled_counts(svdag)
    assert counts["blocks"] == svdag.GetNumberOfBlocks() == len(streams["block roots"])
    assert counts["roots"] == svdag.GetNumberOfRootNodes() == len(streams["root headers"]) // 2
    assert counts["mids"] == svdag.GetNumberOfMidNodes() == len(streams["mid headers"]) // 2
    assert counts["leaves"] == nodes["leaves"] == len(streams["leaves"]) // 8
    assert counts["labels"] == len(np.unique(labels[labels != 0]))
    # One reference byte per mixed child; a reference to a node not referenced before costs no
    # index, so every node of a pool is reached first by a reference without the shared flag.
    root_mixed = np.frombuffer(streams["root headers"], np.uint8)[0::2]
    mid_mixed = np.frombuffer(streams["mid headers"], np.uint8)[0::2]
    popcount = np.unpackbits(root_mixed[:, None], axis=1).sum()
    assert len(streams["root references"]) == popcount
    assert len(streams["mid references"]) == np.unpackbits(mid_mixed[:, None], axis=1).sum()
    block_roots = np.frombuffer(streams["block roots"], np.uint8)
    assert np.count_nonzero(block_roots & 2 == 0) == counts["roots"]
    mid_refs = np.frombuffer(streams["mid references"], np.uint8)
    assert np.count_nonzero(mid_refs & 0x80 == 0) == counts["leaves"]
    assert np.all((mid_refs & 0x7F) >> 1 < 48)  # one of the cube's 48 symmetries
    leaves = np.frombuffer(streams["leaves"], "<u8")
    assert not np.any(leaves & 1)  # canonical leaves
    # Between the coded volume and format 2 at zstd's strongest level in size.
    v2 = write(svdag, tmp_path / "v2.svdag", level=19, version=2)
    v3 = write(svdag, tmp_path / "v3.svdag", version=3)
    assert len(v3) < len(data) < 0.8 * len(v2)


def write(svdag, path, level=3, version=3):
    writer = vtkSegmentationSVDAGWriter()
    writer.SetInputData(svdag)
    writer.SetFileName(str(path))
    writer.SetCompressionLevel(level)
    writer.SetFormatVersion(version)
    assert writer.Write() == 1
    return path.read_bytes()


def read(path):
    reader = vtkSegmentationVolumeReader()
    errors = ErrorCatcher(reader)
    reader.SetFileName(str(path))
    reader.Update()
    return reader, errors


@pytest.mark.parametrize("version", [2, 3, 4])
@pytest.mark.parametrize("name", ["totalseg_ct", "gala_train_gt", "fib25_64"])
def test_round_trip_through_the_reader_is_bit_identical(shared_data, tmp_path, name, version):
    labels, build = compress_real_volume(shared_data / f"{name}.nrrd")
    original = build.GetOutput()
    data = write(original, tmp_path / "a.svdag", version=version)
    reader, errors = read(tmp_path / "a.svdag")
    assert reader.GetErrorCode() == vtkErrorCode.NoError and not errors.messages
    loaded = reader.GetOutput()
    for getter in ("GetNumberOfBlocks", "GetNumberOfRootNodes", "GetNumberOfMidNodes",
                   "GetNumberOfLeaves", "GetNumberOfLabels", "GetCompressedSize",
                   "GetLabelScalarType", "GetNumberOfVoxels"):
        assert getattr(loaded, getter)() == getattr(original, getter)(), getter
    geometry = [0.0] * 3
    loaded.GetSpacing(geometry)
    assert tuple(geometry) == (0.5, 0.75, 2.0)
    loaded.GetOrigin(geometry)
    assert tuple(geometry) == (-4.0, 3.5, 10.0)
    # Same bytes when the loaded volume is written again: nothing was lost or reinterpreted.
    assert write(loaded, tmp_path / "b.svdag", version=version) == data
    decode = vtkSegmentationSVDAGToImageData()
    decode.SetInputData(loaded)
    decode.Update()
    decoded = vtk_to_numpy(decode.GetOutput().GetPointData().GetScalars()).reshape(labels.shape)
    assert decoded.dtype == labels.dtype
    np.testing.assert_array_equal(decoded, labels)


@pytest.mark.parametrize("version", [2, 3, 4])
def test_reader_reports_damaged_files(shared_data, tmp_path, version):
    _, build = compress_real_volume(shared_data / "fib25_64.nrrd")
    data = write(build.GetOutput(), tmp_path / "good.svdag", version=version)
    rng = np.random.default_rng(5)
    damaged = {
        "truncated": data[: len(data) // 2],
        "header cut": data[:100],
        "bit flip in a section": bytearray(data),
        "bit flip in the header": bytearray(data),
        "unknown major version": bytearray(data),
    }
    damaged["bit flip in a section"][len(data) - 1 - int(rng.integers(0, 1000))] ^= 0x10
    damaged["bit flip in the header"][30] ^= 0x01
    damaged["unknown major version"][8:10] = struct.pack("<H", 9)
    for what, content in damaged.items():
        path = tmp_path / "bad.svdag"
        path.write_bytes(bytes(content))
        reader, errors = read(path)
        assert reader.GetErrorCode() != vtkErrorCode.NoError, what
        assert errors.messages, what
        assert not reader.GetOutput().HasVolume(), what


def test_writer_output_is_deterministic(shared_data, tmp_path):
    _, build = compress_real_volume(shared_data / "plantseg_1135_mini.nrrd")
    outputs = []
    for name in ("a.svdag", "b.svdag"):
        writer = vtkSegmentationSVDAGWriter()
        writer.SetInputData(build.GetOutput())
        writer.SetFileName(str(tmp_path / name))
        assert writer.Write() == 1
        outputs.append((tmp_path / name).read_bytes())
    assert outputs[0] == outputs[1]


class ErrorCatcher:
    def __init__(self, algorithm):
        self.messages = []
        algorithm.AddObserver("ErrorEvent", self)

    def __call__(self, obj, event, data=None):
        self.messages.append(event)


def test_writer_errors(tmp_path, rng):
    labels = rng.integers(0, 4, size=(6, 7, 8)).astype(np.uint8)

    writer = vtkSegmentationSVDAGWriter()
    errors = ErrorCatcher(writer)
    writer.SetInputData(compress_zyx(labels))
    assert writer.Write() == 0  # no file name
    assert writer.GetErrorCode() == vtkErrorCode.NoFileNameError

    writer.SetFileName(str(tmp_path / "missing-folder" / "x.svdag"))
    assert writer.Write() == 0
    assert writer.GetErrorCode() == vtkErrorCode.CannotOpenFileError

    writer.SetInputData(vtkSegmentationSVDAG())  # an empty data object
    writer.SetFileName(str(tmp_path / "empty.svdag"))
    assert writer.Write() == 0
    assert writer.GetErrorCode() == vtkErrorCode.UnknownError
    assert not (tmp_path / "empty.svdag").exists()
    assert len(errors.messages) == 3

    writer.SetCompressionLevel(99)
    assert writer.GetCompressionLevel() == 22
    assert "CompressionLevel: 22" in str(writer) and "empty.svdag" in str(writer)  # PrintSelf
    writer.SetCompressionLevel(-4)
    assert writer.GetCompressionLevel() == 0


# -- content checks: valid checksums, impossible content ---------------------------------------

def reseal(data, sections):
    """`data` (an uncompressed .svdag file) with each raw section in `sections` (id -> bytes of
    the same size) written over its place, every section CRC and the header CRC recomputed."""
    data = bytearray(data)
    (count,) = struct.unpack_from("<I", data, 216)
    for i in range(count):
        entry = 220 + 36 * i
        sid, codec, offset, stored, raw, _ = struct.unpack_from("<IIQQQI", data, entry)
        if sid in sections:
            assert codec == 0 and len(sections[sid]) == raw == stored
            data[offset:offset + raw] = sections[sid]
            struct.pack_into("<I", data, entry + 32, zlib.crc32(sections[sid]))
    table_end = 220 + 36 * count
    struct.pack_into("<I", data, table_end, zlib.crc32(bytes(data[:table_end])))
    return bytes(data)


def raw_sections(data):
    _, sections = parse(data)
    return {sid: bytearray(sections[name][1]) for sid, name in SECTIONS.items() if name in sections}


class Blocks:
    """The bit-packed block records of a file (IO/README.md), as one little-endian integer."""

    def __init__(self, data):
        header, sections = parse(data)
        self.widths = header["widths"]
        self.count = header["counts"]["blocks"]
        self.raw_size = len(sections["blocks"][1])
        self.bits = int.from_bytes(sections["blocks"][1], "little")
        cell, label, root = self.widths[0], self.widths[1], self.widths[2]
        self.record = cell + 24 + label + root
        self.fields = {"cell": (0, cell), "box": (cell, 24), "label": (cell + 24, label),
                       "root": (cell + 24 + label, root)}

    def get(self, i, field):
        at, width = self.fields[field]
        return (self.bits >> (i * self.record + at)) & ((1 << width) - 1)

    def set(self, i, field, value):
        at, width = self.fields[field]
        shift = i * self.record + at
        self.bits &= ~(((1 << width) - 1) << shift)
        self.bits |= (value & ((1 << width) - 1)) << shift

    def box(self, i):
        b = self.get(i, "box")
        return [(b >> (4 * a)) & 15 for a in range(3)], [(b >> (12 + 4 * a)) & 15 for a in range(3)]

    def set_box(self, i, lo, hi):
        self.set(i, "box", sum(lo[a] << (4 * a) | hi[a] << (12 + 4 * a) for a in range(3)))

    def bytes(self):
        return self.bits.to_bytes(self.raw_size, "little")


def three_labels():
    z, y, x = np.mgrid[0:26, 0:32, 0:37]
    d2 = (x - 16) ** 2 + (y - 14) ** 2 + (z - 12) ** 2
    labels = np.where(d2 < 30, 5, np.where(d2 < 100, 9, np.where(y > 25, 40, 0))).astype(np.uint16)
    return labels


def expect_refused(tmp_path, data, rule):
    path = tmp_path / "impossible.svdag"
    path.write_bytes(data)
    reader, errors = read(path)
    assert reader.GetErrorCode() == vtkErrorCode.FileFormatError, rule
    assert not reader.GetOutput().HasVolume(), rule
    import vtksvdag
    with pytest.raises(OSError, match=rule):
        vtksvdag.read(path)


def test_impossible_content_is_refused_naming_the_rule(tmp_path):
    labels = three_labels()
    good = write(compress_zyx(labels), tmp_path / "good.svdag", level=0, version=2)
    blocks = Blocks(good)
    assert blocks.count >= 4
    # Unchanged sections load.
    assert reseal(good, {2: blocks.bytes()}) == good

    def with_blocks(edit):
        b = Blocks(good)
        edit(b)
        return reseal(good, {2: b.bytes()})

    def first(predicate):
        return next(i for i in range(blocks.count) if predicate(i))

    cells_x = -(-labels.shape[2] // 16)
    edge = first(lambda i: blocks.get(i, "cell") % cells_x == cells_x - 1)
    wide = first(lambda i: blocks.box(i)[0][0] < blocks.box(i)[1][0])
    pair = first(lambda i: i + 1 < blocks.count
                 and blocks.get(i, "cell") == blocks.get(i + 1, "cell"))

    def past_edge(b):
        lo, hi = b.box(edge)
        b.set_box(edge, lo, [15, hi[1], hi[2]])

    def inverted(b):
        lo, hi = b.box(wide)
        b.set_box(wide, [hi[0], lo[1], lo[2]], [lo[0], hi[1], hi[2]])

    def shrunk(b):
        lo, hi = b.box(wide)
        b.set_box(wide, lo, [hi[0] - 1, hi[1], hi[2]])

    def swapped(b):
        for field in ("box", "label", "root"):
            first_value, second_value = b.get(pair, field), b.get(pair + 1, field)
            b.set(pair, field, second_value)
            b.set(pair + 1, field, first_value)

    def duplicate(b):
        b.set(pair + 1, "label", b.get(pair, "label"))

    def mid_node_reference(b):
        b.set(0, "root", b.get(0, "root") + (3 << 1))

    def overlapping(b):
        lo, hi = b.box(pair)
        b.set_box(pair + 1, lo, hi)
        b.set(pair + 1, "root", b.get(pair, "root"))

    for edit, rule in [
        (past_edge, "bounds outside the volume"),
        (inverted, "bounds inverted"),
        (shrunk, "occupancy outside its declared bounds"),
        (duplicate, "holds two blocks of one label"),
        (mid_node_reference, "root reference does not point at a root node"),
        (overlapping, r"overlap \(a voxel has one label\)"),
    ]:
        expect_refused(tmp_path, with_blocks(edit), rule)

    # Blocks of one cell in scan order (as files written before the builder sorted them by label
    # within a cell) load, and decode to the same voxels.
    import vtksvdag

    path = tmp_path / "scan_order.svdag"
    path.write_bytes(with_blocks(swapped))
    assert np.array_equal(vtksvdag.read(path).to_numpy(axis_order="zyx"), labels)

    # The label table must hold what the blocks hold.
    def with_labels(edit):
        raw = raw_sections(good)[1]
        edit(raw)
        return reseal(good, {1: bytes(raw)})

    record = 40
    for edit, rule in [
        (lambda raw: struct.pack_into("<Q", raw, record + 8,
                                      struct.unpack_from("<Q", raw, record + 8)[0] - 1),
         "voxel count"),
        (lambda raw: struct.pack_into("<i", raw, 16, struct.unpack_from("<i", raw, 16)[0] - 1),
         "bounds in the label table differ"),
        (lambda raw: raw.__setitem__(slice(0, 2 * record),
                                     raw[record:2 * record] + raw[0:record]),
         "not sorted by value or not unique"),
        (lambda raw: raw.__setitem__(slice(record, record + 8), raw[0:8]),
         "not sorted by value or not unique"),
        (lambda raw: raw.__setitem__(slice(0, 8), bytes(8)), "background"),
    ]:
        expect_refused(tmp_path, with_labels(edit), rule)


def empty_volume_file(dims, scalar_type=5):
    """A valid uncompressed .svdag file of an all-background volume: 404 bytes at any size."""
    header = MAGIC + struct.pack("<HH3i", 1, 0, *dims)
    header += struct.pack("<3d3d9d", 1, 1, 1, 0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1)
    cells = int(np.prod([-(-d // 16) for d in dims]))
    header += struct.pack("<IQ", scalar_type, 0)
    header += struct.pack("<5I5QI", (cells - 1).bit_length(), 0, 1, 1, 1, 0, 0, 0, 0, 0, 5)
    for sid in range(1, 6):
        header += struct.pack("<IIQQQI", sid, 0, 220 + 36 * 5 + 4, 0, 0, zlib.crc32(b""))
    return header + struct.pack("<I", zlib.crc32(header))


def test_huge_empty_volume_gives_an_exception_not_an_abort(tmp_path):
    import os

    import vtksvdag

    path = tmp_path / "huge.svdag"
    path.write_bytes(empty_volume_file((4096, 4096, 4096)))
    assert path.stat().st_size == 404
    volume = vtksvdag.read(path)  # valid and tiny: loads
    assert volume.dims == (4096, 4096, 4096)
    memory = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    if memory >= 256 << 30:
        pytest.skip("this machine could hold the decoded volume")
    # Refused before anything is allocated, with the bytes a decode needs.
    with pytest.raises((MemoryError, ValueError, OSError), match=r"274877906944 bytes \(256 GiB\)"):
        volume.to_numpy()
    # The filter reports an error and leaves its output empty.
    decoder = vtkSegmentationSVDAGToImageData()
    errors = ErrorCatcher(decoder)
    decoder.SetInputData(volume.dataobject)
    decoder.Update()
    assert errors.messages
    assert decoder.GetOutput().GetNumberOfPoints() == 0


DTYPES = ["int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"]


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("level, version", [(0, 2), (3, 2), (3, 3), (3, 4)])
def test_every_dtype_round_trips_bit_exactly(tmp_path, rng, dtype, level, version):
    import vtksvdag

    info = np.iinfo(dtype)
    labels = rng.integers(0, 6, size=(21, 34, 19)).astype(dtype)
    labels[labels == 1] = info.min
    labels[labels == 2] = info.max
    labels[3:9, 4:30, 2:17] = info.max - 1  # a solid region spanning cells
    write(compress_zyx(labels), tmp_path / "v.svdag", level=level, version=version)
    decoded = vtksvdag.read(tmp_path / "v.svdag").to_numpy("zyx")
    assert decoded.dtype == np.dtype(dtype)
    np.testing.assert_array_equal(decoded, labels)
