#!/usr/bin/env python3
"""Fuzzing harness for vtksvdag.read() over every volume format and the .svdag file format.

One *target* is one format (or one way of mutating it); one process fuzzes one target with
atheris (libFuzzer's mutator, coverage of the Python side), seeded with small valid files that
this script generates (see SEEDS below). For every input:

1. the bytes are written to a file named as the format expects (companion files, such as the raw
   data of a detached header, stay fixed beside it) and ``vtksvdag.read`` opens it;
2. a rejection must be ``OSError``, ``ValueError``, ``MemoryError`` or ``TypeError``: any other
   exception is a crash (atheris saves the input), and so is a signal or a hang (libFuzzer's
   ``-timeout``);
3. an accepted volume is decoded (``to_numpy``) and probed (``label_at``, labels, counts) and
   must be *right*:
   - checksummed formats (``.svdag``; gzip, zlib and ``.nii.gz`` bodies): when the part the
     checksum does not cover is the seed's (the NRRD or MetaImage text header), or always for
     ``.svdag`` and ``.nii.gz``, the volume must be exactly the seed's;
   - raw bodies (no checksum): with the seed's header, the volume must be exactly what the body
     bytes say (a flipped voxel byte is a legitimately different volume);
   - any format: ``to_numpy`` has the volume's shape and dtype, ``label_at`` agrees with it.
   A wrong volume raises ``SilentWrongVolume``, which atheris reports like a crash.

Soft findings (an accepted file whose label table, voxel counts or bounds disagree with its
decoded voxels; nothing in the format promises those are checked for CRC-forged ``.svdag``
files) are counted, and the first few inputs saved under ``<workdir>/soft/<target>/``.

Usage::

    fuzz_readers.py --list
    fuzz_readers.py --target nrrd_gzip --workdir /tmp/fz [libFuzzer flags: -max_total_time=10 ...]
    fuzz_readers.py --target svdag --workdir /tmp/fz --replay FILE [FILE ...]
    fuzz_readers.py --write-regressions Testing/fuzz/crashes

``--replay`` runs the given inputs once each (no atheris needed) and exits 0 when each was
accepted correctly or rejected cleanly. ``<workdir>/stats/<target>.json`` holds the counts
(inputs tried, accepted, rejected, soft findings), refreshed every second.
"""
import argparse
import gzip
import hashlib
import io
import json
import os
import pathlib
import struct
import sys
import time
import zlib

import numpy as np

CLEAN_ERRORS = (OSError, ValueError, MemoryError, TypeError)
MAX_DECODE_VOXELS = 1 << 22  # accepted volumes larger than this are probed, not decoded whole


class SilentWrongVolume(AssertionError):
    """An accepted file decoded to a volume that is not what its bytes say."""


# --------------------------------------------------------------------------------------- volumes


def seed_volumes():
    """Small label volumes, (z, y, x): one inside a cell, one across cells and slabs."""
    rng = np.random.default_rng(20240601)
    a = rng.integers(0, 4, size=(5, 6, 7)).astype(np.uint8)
    b = np.zeros((18, 17, 3), np.uint16)
    b[2:16, 1:15, :] = 700
    b[:, 8:, 1] = 3
    b[17, 16, 2] = 65535
    c = rng.integers(-3, 3, size=(3, 4, 17)).astype(np.int64) * (1 << 40)
    return {"a": a, "b": b, "c": c}


SPACING = (0.5, 1.0, 2.0)
ORIGIN = (1.0, -2.0, 3.5)


def _image(zyx):
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData

    image = vtkImageData()
    image.SetDimensions(zyx.shape[2], zyx.shape[1], zyx.shape[0])
    image.SetSpacing(*SPACING)
    image.SetOrigin(*ORIGIN)
    image.GetPointData().SetScalars(numpy_to_vtk(np.ascontiguousarray(zyx).ravel(), deep=True))
    return image


def _nrrd_header(zyx, encoding, data_file=None):
    types = {"uint8": "uint8", "uint16": "uint16", "int64": "int64"}
    lines = [
        "NRRD0004",
        f"type: {types[zyx.dtype.name]}",
        "dimension: 3",
        f"sizes: {zyx.shape[2]} {zyx.shape[1]} {zyx.shape[0]}",
        "space: left-posterior-superior",
        "space directions: (0.5,0,0) (0,1,0) (0,0,2)",
        "space origin: (1,-2,3.5)",
        "kinds: domain domain domain",
        "endian: little",
        f"encoding: {encoding}",
    ]
    if data_file:
        lines.append(f"data file: {data_file}")
    return ("\n".join(lines) + "\n\n").encode() if not data_file else ("\n".join(lines) + "\n").encode()


_MET = {"uint8": "MET_UCHAR", "uint16": "MET_USHORT", "int64": "MET_LONG_LONG"}


def _mha_header(zyx, compressed_size=None, data_file="LOCAL"):
    lines = [
        "ObjectType = Image",
        "NDims = 3",
        "BinaryData = True",
        "BinaryDataByteOrderMSB = False",
        f"CompressedData = {compressed_size is not None}",
    ]
    if compressed_size is not None:
        lines.append(f"CompressedDataSize = {compressed_size}")
    lines += [
        "TransformMatrix = 1 0 0 0 1 0 0 0 1",
        "Offset = 1 -2 3.5",
        "ElementSpacing = 0.5 1 2",
        f"DimSize = {zyx.shape[2]} {zyx.shape[1]} {zyx.shape[0]}",
        f"ElementType = {_MET[zyx.dtype.name]}",
        f"ElementDataFile = {data_file}",
    ]
    return ("\n".join(lines) + "\n").encode()


def _svdag_bytes(zyx, version=3):
    import tempfile

    from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG
    from vtksvdag.vtkSVDAGIO import vtkSegmentationSVDAGWriter

    build = vtkImageDataToSegmentationSVDAG()
    build.SetInputData(_image(zyx))
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "s.svdag")
        writer = vtkSegmentationSVDAGWriter()
        writer.SetFormatVersion(version)
        writer.SetFileName(path)
        writer.SetInputConnection(build.GetOutputPort())
        writer.Write()
        return pathlib.Path(path).read_bytes()


def svdag_stored(data):
    """The same .svdag file with every section stored uncompressed (codec 0), CRCs fixed."""
    import zstandard

    (count,) = struct.unpack_from("<I", data, 216)
    table = 220
    body_start = table + 36 * count + 4
    out_table, body = [], b""
    for i in range(count):
        sid, codec, off, stored, raw, crc = struct.unpack_from("<IIQQQI", data, table + 36 * i)
        blob = data[off:off + stored]
        if codec == 1:
            blob = zstandard.ZstdDecompressor().decompress(blob, max_output_size=raw)
        out_table.append(struct.pack("<IIQQQI", sid, 0, body_start + len(body), len(blob), len(blob),
                                     zlib.crc32(blob)))
        body += blob
    head = data[:table] + b"".join(out_table)
    return head + struct.pack("<I", zlib.crc32(head)) + body


def read_varint(data, at):
    """The unsigned LEB128 number at data[at] (the .svdag 4.0 file's) and the offset after it."""
    value, shift = 0, 0
    while True:
        byte = data[at]
        at += 1
        value |= (byte & 0x7F) << shift
        shift += 7
        if not byte & 0x80:
            return value, at


def _put_varint(value):
    out = bytearray()
    while value >= 0x80:
        out.append((value & 0x7F) | 0x80)
        value >>= 7
    out.append(value)
    return bytes(out)


def svdag4_stored(data):
    """The same .svdag 4.0 file with each DAG stream stored as it is (stored size = raw size,
    IO/README.md), CRCs fixed: mutations then reach the streams' decoder, not zstd's."""
    import zstandard

    (count,) = struct.unpack_from("<I", data, 216)
    assert count == 1
    sid, codec, off, stored, raw, crc = struct.unpack_from("<IIQQQI", data, 220)
    section = data[off:off + stored]
    sizes, at = [], 0
    for _ in range(12):
        stored_size, at = read_varint(section, at)
        raw_size, at = read_varint(section, at)
        sizes.append((stored_size, raw_size))
    table, streams = b"", b""
    for stored_size, raw_size in sizes:
        frame = section[at:at + stored_size]
        at += stored_size
        stream = frame if stored_size == raw_size else zstandard.ZstdDecompressor().decompress(
            frame, max_output_size=raw_size)
        table += _put_varint(len(stream)) * 2
        streams += stream
    body = table + streams
    head = bytearray(data[:220 + 36 + 4])
    struct.pack_into("<IIQQQI", head, 220, sid, 0, off, len(body), len(body), zlib.crc32(body))
    struct.pack_into("<I", head, 256, zlib.crc32(bytes(head[:256])))
    return bytes(head) + data[260:off] + body


def svdag_fix_crcs(data):
    """Recompute the section and header CRC-32s of a (mutated) .svdag file, where it parses."""
    if len(data) < 224:
        return data
    data = bytearray(data)
    (count,) = struct.unpack_from("<I", data, 216)
    if count > 64 or 224 + 36 * count > len(data):
        return bytes(data)
    for i in range(count):
        at = 220 + 36 * i
        sid, codec, off, stored, raw, _ = struct.unpack_from("<IIQQQI", data, at)
        if codec == 0 and off + stored <= len(data):
            struct.pack_into("<I", data, at + 32, zlib.crc32(data[off:off + stored]))
    end = 220 + 36 * count
    struct.pack_into("<I", data, end, zlib.crc32(data[:end]))
    return bytes(data)


def _nifti_bytes(zyx, gz):
    import nibabel

    image = nibabel.Nifti1Image(zyx.transpose(2, 1, 0), np.diag([0.5, 1, 2, 1]), dtype=zyx.dtype)
    image.header.set_xyzt_units("mm")
    raw = image.to_bytes()  # header, 4 extension bytes, data at vox_offset 352
    return gzip.compress(raw, mtime=0) if gz else raw


def _tiff_bytes(zyx, **options):
    import tifffile

    buffer = io.BytesIO()
    tifffile.imwrite(buffer, zyx, photometric="minisblack", **options)
    return buffer.getvalue()


def _h5_bytes(zyx):
    import h5py

    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        f.create_dataset("labels", data=zyx)
    return buffer.getvalue()


def _vti_bytes(zyx, raw):
    import tempfile

    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    writer = vtkXMLImageDataWriter()
    writer.SetInputData(_image(zyx))
    if raw:
        writer.SetDataModeToAppended()
        writer.EncodeAppendedDataOff()
        writer.SetCompressorTypeToNone()
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "s.vti")
        writer.SetFileName(path)
        writer.Write()
        return pathlib.Path(path).read_bytes()


def _vti_base64_bytes(zyx, compressor="None", mode="Binary"):
    """VTI with its scalars as base64 text: inline (``Binary``) or in a base64 AppendedData."""
    import tempfile

    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    writer = vtkXMLImageDataWriter()
    writer.SetInputData(_image(zyx))
    getattr(writer, f"SetDataModeTo{mode}")()
    getattr(writer, f"SetCompressorTypeTo{compressor}")()
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "s.vti")
        writer.SetFileName(path)
        writer.Write()
        return pathlib.Path(path).read_bytes()


def _h5_chunked_bytes(zyx, chunks):
    """A gzip-chunked int32 dataset, every chunk written (h5py's default, earliest format: the
    chunk index is a version-1 B-tree)."""
    import h5py

    buffer = io.BytesIO()
    with h5py.File(buffer, "w") as f:
        f.create_dataset("labels", data=zyx.astype(np.int32), chunks=chunks, compression="gzip")
    return buffer.getvalue()


# ------------------------------------------------------------------ generators of one damage
# Issue 24: two inputs that read as silently wrong volumes, which the whole-file mutations above
# did not find (a VTI target only had to be consistent; HDF5 lost track of chunks and read fill
# values). Each target below draws its inputs from a generator of that one kind of damage (a
# custom mutator, sometimes after libFuzzer's own mutation) and judges an accepted input by what
# the damage implies, whoever made it (so a saved input replays alike).

BASE64_ALPHABET = frozenset(b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/=")
XML_SPACE = frozenset(b" \t\r\n")
# Neither base64, '=', XML white space nor '<' (which would end the text instead).
NOT_BASE64 = b"!\"#$%&'()*,-.:;?@[\\]^_`{|}~\x00\x01\x7f\x80\xc3\xe9\xff"


def base64_texts(data):
    """(begin, end) of every base64 text VTK decodes in a VTI file: each inline binary
    DataArray's text and a base64 AppendedData section after its '_', without the white space
    around them."""
    import re

    spans = []
    for match in re.finditer(rb"<DataArray[^>]* format=\"binary\"[^>]*>", data):
        spans.append((match.end(), data.find(b"<", match.end())))
    match = re.search(rb"<AppendedData[^>]* encoding=\"base64\"[^>]*>\s*_", data)
    if match:
        spans.append((match.end(), data.find(b"<", match.end())))
    out = []
    for begin, end in spans:
        end = len(data) if end < 0 else end
        while begin < end and data[begin] in XML_SPACE:
            begin += 1
        while end > begin and data[end - 1] in XML_SPACE:
            end -= 1
        if begin < end:
            out.append((begin, end))
    return out


def first_invalid_base64(data):
    """Byte offset of the first character in a VTI file's base64 text that is neither base64,
    '=' nor white space, or None. Such a file must be refused: VTK's decoder stops there without
    an error and leaves the rest of the array 0."""
    for begin, end in base64_texts(data):
        for i in range(begin, end):
            if data[i] not in BASE64_ALPHABET and data[i] not in XML_SPACE:
                return i
    return None


def inject_invalid_base64(data, rng):
    """Inserts or overwrites 1-3 characters that are not base64 inside a VTI file's base64 text
    (unchanged when it has none)."""
    for _ in range(rng.randint(1, 3)):
        spans = base64_texts(data)
        if not spans:
            return data
        begin, end = rng.choice(spans)
        at = rng.randrange(begin, end)
        char = NOT_BASE64[rng.randrange(len(NOT_BASE64))]
        keep = 0 if rng.random() < 0.5 else 1  # insert, or overwrite the character there
        data = data[:at] + bytes([char]) + data[at + keep:]
    return data


H5_CHUNK_KEY_BYTES = 4 + 4 + 8 * 4  # chunk size, filter mask, 3 offsets and the element's
H5_CHUNK_ENTRY_BYTES = H5_CHUNK_KEY_BYTES + 8  # a key and its child's address


def chunk_btree(raw):
    """(offset, entries) of the first leaf node of an HDF5 file's raw-data-chunk B-tree
    (version 1, node type 1, level 0) for rank-3 datasets; None when there is none."""
    import struct

    at = raw.find(b"TREE")
    while 0 <= at <= len(raw) - 8:
        node_type, level, entries = struct.unpack_from("<BBH", raw, at + 4)
        if node_type == 1 and level == 0:
            return at, entries
        at = raw.find(b"TREE", at + 4)
    return None


def chunk_index_span(raw):
    """(begin, end): the keys and child addresses of the chunk B-tree leaf; None without one.
    Bytes there only locate the chunks: with every chunk written, damage there can make a file
    unreadable but never hold other voxels."""
    found = chunk_btree(raw)
    if found is None:
        return None
    node, entries = found
    begin = node + 24  # signature, type, level, entries used, two sibling addresses
    return begin, min(len(raw), begin + entries * H5_CHUNK_ENTRY_BYTES + H5_CHUNK_KEY_BYTES)


def flip_chunk_index(data, rng):
    """XORs 1-2 bytes of the chunk B-tree's keys and child addresses with random non-zero
    values (unchanged when the file has no such B-tree)."""
    span = chunk_index_span(data)
    if span is None or span[0] >= span[1]:
        return data
    data = bytearray(data)
    for _ in range(rng.randint(1, 2)):
        data[rng.randrange(*span)] ^= rng.randrange(1, 256)
    return bytes(data)


class Seed:
    """One valid input of a target: its bytes, the volume it holds (z, y, x), how to check."""

    def __init__(self, data, zyx, header_len=None, body_dtype=None, exact=False, companions=None,
                 index_span=None):
        self.data = data
        self.zyx = zyx
        self.header_len = header_len  # bytes not covered by a checksum / before the raw body
        self.body_dtype = body_dtype  # raw body: what the bytes after header_len must decode to
        self.exact = exact  # checksummed: an accepted file holds exactly zyx
        self.companions = companions or {}  # file name -> bytes, written once beside the input
        # (begin, end) of bytes that only locate the data (a chunk index): an accepted file
        # equal to this seed outside them holds exactly zyx
        self.index_span = index_span


def _seeds_nrrd_raw(v):
    return [Seed(_nrrd_header(z, "raw") + z.tobytes(), z, header_len=len(_nrrd_header(z, "raw")),
                 body_dtype=z.dtype.newbyteorder("<")) for z in v.values()]


def _seeds_nrrd_gzip(v):
    out = []
    for z in v.values():
        h = _nrrd_header(z, "gzip")
        out.append(Seed(h + gzip.compress(z.tobytes(), mtime=0), z, header_len=len(h), exact=True))
    return out


def _seeds_nhdr(v):
    out = []
    for name, z in v.items():
        out.append(Seed(_nrrd_header(z, "raw", data_file=f"{name}.raw"), z,
                        companions={f"{name}.raw": z.tobytes()}))
    return out


def _seeds_nhdr_gzip(v):
    out = []
    for name, z in v.items():
        out.append(Seed(_nrrd_header(z, "gzip", data_file=f"{name}.raw.gz"), z,
                        companions={f"{name}.raw.gz": gzip.compress(z.tobytes(), mtime=0)}))
    return out


def _seeds_mha_raw(v):
    return [Seed(_mha_header(z) + z.tobytes(), z, header_len=len(_mha_header(z)),
                 body_dtype=z.dtype.newbyteorder("<")) for z in v.values()]


def _seeds_mha_zlib(v):
    out = []
    for z in v.values():
        body = zlib.compress(z.tobytes())
        h = _mha_header(z, compressed_size=len(body))
        out.append(Seed(h + body, z, header_len=len(h), exact=True))
    return out


def _seeds_mhd(v):
    return [Seed(_mha_header(z, data_file=f"{n}.raw"), z, companions={f"{n}.raw": z.tobytes()})
            for n, z in v.items()]


def _seeds_nii(v):
    return [Seed(_nifti_bytes(z, False), z, header_len=352, body_dtype=z.dtype.newbyteorder("<"))
            for z in v.values()]


def _seeds_nii_gz(v):
    return [Seed(_nifti_bytes(z, True), z, exact=True) for z in v.values()]


def _seeds_tif(v):
    out = [Seed(_tiff_bytes(z), z) for z in v.values() if z.dtype != np.int64]
    out.append(Seed(_tiff_bytes(v["b"], compression="zlib", tile=(16, 16)), v["b"]))
    return out


def _seeds_h5(v):
    return [Seed(_h5_bytes(z), z) for z in v.values()]


def _seeds_vti(v):
    return [Seed(_vti_bytes(z, False), z) for z in v.values()]


def _seeds_vti_raw(v):
    return [Seed(_vti_bytes(z, True), z) for z in v.values()]


def _seeds_vti_base64(v):
    out = [Seed(_vti_base64_bytes(z), z) for z in v.values()]
    out.append(Seed(_vti_base64_bytes(v["b"], "ZLib"), v["b"]))
    out.append(Seed(_vti_base64_bytes(v["b"], "None", "Appended"), v["b"]))
    return out


def _seeds_h5_chunk_index(v):
    out = []
    for name, chunks in (("a", (2, 4, 4)), ("b", (4, 8, 2))):
        z = v[name].astype(np.int32)
        data = _h5_chunked_bytes(z, chunks)
        out.append(Seed(data, z, index_span=chunk_index_span(data)))
    return out


def _seeds_svdag(v):
    return [Seed(_svdag_bytes(z), z, exact=True) for z in v.values()]


def _seeds_svdag_fixcrc(v):
    return [Seed(svdag_stored(_svdag_bytes(z)), z) for z in v.values()]


def _seeds_svdag2(v):
    return [Seed(_svdag_bytes(z, version=2), z, exact=True) for z in v.values()]


def _seeds_svdag2_fixcrc(v):
    return [Seed(svdag_stored(_svdag_bytes(z, version=2)), z) for z in v.values()]


def _seeds_svdag4(v):
    return [Seed(_svdag_bytes(z, version=4), z, exact=True) for z in v.values()]


def _seeds_svdag4_fixcrc(v):
    return [Seed(svdag4_stored(_svdag_bytes(z, version=4)), z) for z in v.values()]


# target -> (seed maker, file name of the input, transform applied before writing)
TARGETS = {
    "svdag": (_seeds_svdag, "in.svdag", None),
    "svdag_fixcrc": (_seeds_svdag_fixcrc, "in.svdag", svdag_fix_crcs),
    "svdag2": (_seeds_svdag2, "in.svdag", None),
    "svdag2_fixcrc": (_seeds_svdag2_fixcrc, "in.svdag", svdag_fix_crcs),
    "svdag4": (_seeds_svdag4, "in.svdag", None),
    "svdag4_fixcrc": (_seeds_svdag4_fixcrc, "in.svdag", svdag_fix_crcs),
    "nrrd_raw": (_seeds_nrrd_raw, "in.nrrd", None),
    "nrrd_gzip": (_seeds_nrrd_gzip, "in.nrrd", None),
    "nhdr": (_seeds_nhdr, "in.nhdr", None),
    "nhdr_gzip": (_seeds_nhdr_gzip, "in.nhdr", None),
    "mha_raw": (_seeds_mha_raw, "in.mha", None),
    "mha_zlib": (_seeds_mha_zlib, "in.mha", None),
    "mhd": (_seeds_mhd, "in.mhd", None),
    "nii": (_seeds_nii, "in.nii", None),
    "nii_gz": (_seeds_nii_gz, "in.nii.gz", None),
    "tif": (_seeds_tif, "in.tif", None),
    "h5": (_seeds_h5, "in.h5", None),
    "vti": (_seeds_vti, "in.vti", None),
    "vti_raw": (_seeds_vti_raw, "in.vti", None),
    "vti_base64": (_seeds_vti_base64, "in.vti", None),
    "h5_chunk_index": (_seeds_h5_chunk_index, "in.h5", None),
}

# target -> the generator of its damage, mutate(data, random.Random) -> bytes
GENERATORS = {"vti_base64": inject_invalid_base64, "h5_chunk_index": flip_chunk_index}


def regression_inputs():
    """The two inputs of issue 24, rebuilt deterministically from the seeds:
    {file name in crashes/: bytes}. Both read as silently wrong volumes before the fix."""
    volumes = seed_volumes()
    vti = _vti_base64_bytes(volumes["a"])  # inline binary, uncompressed, uint8
    begin, end = base64_texts(vti)[0]
    at = begin + (end - begin) // 3
    vti = vti[:at] + b"!" + vti[at + 1:]
    h5 = bytearray(_h5_chunked_bytes(volumes["b"].astype(np.int32), (4, 8, 2)))
    node, _ = chunk_btree(h5)
    key = node + 24 + 5 * H5_CHUNK_ENTRY_BYTES  # the 6th chunk's key: its first offset (z)
    h5[key + 8] ^= 0x5A
    h5[key + 9] ^= 0x01
    return {
        "vti_base64--invalid-character-in-inline-base64-read-as-zeros.vti": vti,
        "h5_chunk_index--two-corrupt-btree-key-bytes-read-as-fill-value.h5": bytes(h5),
    }


def write_seed_corpus(target, directory):
    """Write the seeds of ``target`` into ``directory`` (one file each); returns their paths."""
    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    paths = []
    for seed in TARGETS[target][0](seed_volumes()):
        path = directory / hashlib.sha1(seed.data).hexdigest()
        path.write_bytes(seed.data)
        paths.append(path)
    return paths


# ------------------------------------------------------------------------------------- the check


class Harness:
    def __init__(self, target, workdir):
        import vtksvdag
        from vtkmodules.vtkCommonCore import vtkOutputWindow

        # VTK readers inside the project's reader print their own errors: keep them off stderr
        # (ErrorEvent observers, which vtksvdag uses, still get them).
        vtkOutputWindow.GetInstance().SetDisplayModeToNever()
        self.vtksvdag = vtksvdag
        self.target = target
        make, self.name, self.transform = TARGETS[target]
        self.seeds = make(seed_volumes())
        self.workdir = pathlib.Path(workdir)
        self.dir = self.workdir / "run" / f"{target}-{os.getpid()}"
        self.dir.mkdir(parents=True, exist_ok=True)
        for seed in self.seeds:
            for name, data in seed.companions.items():
                (self.dir / name).write_bytes(data)
        self.path = self.dir / self.name
        self.soft_dir = self.workdir / "soft" / target
        self.stats_path = self.workdir / "stats" / f"{target}.json"
        self.stats_path.parent.mkdir(parents=True, exist_ok=True)
        self.stats = {"target": target, "inputs": 0, "accepted": 0, "rejected": 0,
                      "accepted_exact_checked": 0, "soft": 0, "soft_kinds": {}, "seconds": 0.0}
        self.start = time.time()
        self.last_write = 0.0

    def write_stats(self, force=False):
        now = time.time()
        if force or now - self.last_write > 1.0:
            self.stats["seconds"] = round(now - self.start, 1)
            tmp = self.stats_path.with_suffix(".tmp")
            tmp.write_text(json.dumps(self.stats, indent=1))
            tmp.replace(self.stats_path)
            self.last_write = now

    def soft(self, kind, data):
        self.stats["soft"] += 1
        self.stats["soft_kinds"][kind] = self.stats["soft_kinds"].get(kind, 0) + 1
        if self.stats["soft_kinds"][kind] <= 5:
            self.soft_dir.mkdir(parents=True, exist_ok=True)
            (self.soft_dir / f"{kind}-{hashlib.sha1(data).hexdigest()[:12]}").write_bytes(data)

    def one(self, data):
        """Run one input; raises on a crash-worthy outcome."""
        self.stats["inputs"] += 1
        if self.transform is not None:
            data = self.transform(data)
        self.path.write_bytes(data)
        try:
            volume = self.vtksvdag.read(self.path)
        except CLEAN_ERRORS as error:
            self.stats["rejected"] += 1
            self.stats["last_rejection"] = f"{type(error).__name__}: {error}"  # for reports
            self.write_stats()
            return
        self.stats["accepted"] += 1
        try:
            self.check_accepted(volume, data)
        finally:
            self.write_stats()

    def expected_for(self, data):
        """(expected zyx array, kind) for an accepted ``data``, or (None, None) when any volume
        is legitimate (the bytes that define it differ from every seed's)."""
        for seed in self.seeds:
            if data == seed.data:
                return seed.zyx, "seed"
        if self.target == "vti_base64":
            bad = first_invalid_base64(data)
            if bad is not None:
                raise SilentWrongVolume(f"{self.target}: accepted a file with a character that "
                                        f"is not base64 at byte offset {bad}")
        for seed in self.seeds:
            span = seed.index_span
            if span and len(data) == len(seed.data) and data[:span[0]] == seed.data[:span[0]] \
                    and data[span[1]:] == seed.data[span[1]:]:
                return seed.zyx, "damaged chunk index"
        for seed in self.seeds:
            if seed.exact and seed.header_len is None:
                continue
            if seed.header_len is not None and data[:seed.header_len] == seed.data[:seed.header_len]:
                if seed.exact:
                    return seed.zyx, "checksummed body"
                body = data[seed.header_len:]
                n = seed.zyx.size * seed.zyx.dtype.itemsize
                if len(body) < n:
                    raise SilentWrongVolume(
                        f"{self.target}: accepted a raw body of {len(body)} bytes, {n} needed")
                values = np.frombuffer(body[:n], dtype=seed.body_dtype).astype(seed.zyx.dtype)
                return values.reshape(seed.zyx.shape), "raw body"
        if any(s.exact and s.header_len is None for s in self.seeds):
            # The whole file is checksummed: an accepted one holds one of the seeds' volumes.
            return None, "whole file"
        return None, None

    def check_accepted(self, volume, data):
        dims = tuple(volume.dims)
        if len(dims) != 3 or min(dims) < 1:
            raise SilentWrongVolume(f"{self.target}: accepted with dimensions {dims}")
        expected, kind = self.expected_for(data)
        n = dims[0] * dims[1] * dims[2]
        if n > MAX_DECODE_VOXELS:
            if kind is not None:
                raise SilentWrongVolume(f"{self.target}: accepted {dims}, the seed is smaller")
            corners = [(x, y, z) for x in (0, dims[0] - 1) for y in (0, dims[1] - 1)
                       for z in (0, dims[2] - 1)]
            for p in corners:
                volume.label_at(*p)
            return
        labels = volume.to_numpy()
        if labels.shape != dims or labels.dtype != volume.dtype:
            raise SilentWrongVolume(f"{self.target}: to_numpy gave {labels.shape} {labels.dtype}, "
                                    f"the volume says {dims} {volume.dtype}")
        zyx = labels.transpose(2, 1, 0)
        if kind == "whole file":
            if not any(s.zyx.shape == zyx.shape and s.zyx.dtype == zyx.dtype
                       and np.array_equal(s.zyx, zyx) for s in self.seeds):
                raise SilentWrongVolume(f"{self.target}: an accepted file (checksummed whole) "
                                        f"decodes to a volume that is none of the seeds'")
            self.stats["accepted_exact_checked"] += 1
        elif expected is not None:
            if (zyx.shape != expected.shape or zyx.dtype != expected.dtype
                    or not np.array_equal(zyx, expected)):
                raise SilentWrongVolume(
                    f"{self.target}: accepted with the seed's header, the {kind} says "
                    f"{expected.shape} {expected.dtype}, the reader gave {zyx.shape} {zyx.dtype}"
                    + ("" if zyx.shape != expected.shape else
                       f", {int(np.count_nonzero(zyx != expected))} voxels differ"))
            self.stats["accepted_exact_checked"] += 1
        # label_at (DAG traversal) against the decoder, at corners and a few voxels.
        rng = np.random.default_rng(len(data))
        points = [(0, 0, 0), tuple(d - 1 for d in dims)]
        points += [tuple(int(rng.integers(0, d)) for d in dims) for _ in range(6)]
        for p in points:
            got = volume.label_at(*p)
            if got != labels[p]:
                self.soft("label_at_vs_to_numpy", data)
                break
        # The label table against the decoded voxels.
        background = volume.background
        values, counts = np.unique(labels[labels != background], return_counts=True)
        if not (np.array_equal(values, volume.labels)
                and np.array_equal(counts, volume.label_voxel_counts)):
            self.soft("label_table_vs_voxels", data)


def main(argv=None):
    argv = list(sys.argv if argv is None else argv)
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0], add_help=True)
    parser.add_argument("--target", choices=sorted(TARGETS))
    parser.add_argument("--workdir", default="/tmp/vtksvdag-fuzz")
    parser.add_argument("--list", action="store_true")
    parser.add_argument("--write-seeds", metavar="DIR", help="write the seed corpus and exit")
    parser.add_argument("--replay", nargs="+", metavar="FILE")
    parser.add_argument("--write-regressions", metavar="DIR",
                        help="write the generated regression inputs (regression_inputs) and exit")
    args, rest = parser.parse_known_args(argv[1:])
    if args.list:
        print("\n".join(TARGETS))
        return 0
    if args.write_regressions:
        for name, data in regression_inputs().items():
            (pathlib.Path(args.write_regressions) / name).write_bytes(data)
        return 0
    if not args.target:
        parser.error("--target is required")
    if args.write_seeds:
        write_seed_corpus(args.target, args.write_seeds)
        return 0
    if not args.replay:
        import atheris

        with atheris.instrument_imports():  # coverage of the package's Python side
            import vtksvdag  # noqa: F401
    if args.replay and "libasan" not in os.environ.get("LD_PRELOAD", ""):
        # A replayed input that makes a reader allocate absurdly must fail, not take the machine
        # (ASan reserves terabytes of address space: there max_allocation_size_mb does this).
        import resource

        limit = 4 << 30
        resource.setrlimit(resource.RLIMIT_AS, (limit, limit))
    harness = Harness(args.target, args.workdir)
    if args.replay:
        for path in args.replay:
            harness.one(pathlib.Path(path).read_bytes())
        harness.write_stats(force=True)
        print(json.dumps(harness.stats))
        return 0

    def test_one_input(data):
        harness.one(bytes(data))

    # Under an LD_PRELOADed libasan (scripts/sanitize.sh, FUZZ_ASAN=1), libasan's coverage
    # symbols shadow libFuzzer's: no input ever adds coverage, the corpus collapses to one empty
    # input and the seeds are dropped. Then every input is a mutation of a seed (or of an input
    # that was accepted), by libFuzzer's own mutator.
    pooled = ("libasan" in os.environ.get("LD_PRELOAD", "")
              or os.environ.get("VTKSVDAG_FUZZ_SEED_MUTATOR"))
    generator = GENERATORS.get(args.target)
    if pooled or generator:
        import random

        pool = [s.data for s in harness.seeds]

        def mutate(data, max_size, seed):
            rng = random.Random(seed)
            if pooled:
                data = rng.choice(pool)
            # A generator target's inputs carry its damage, now and then on top of libFuzzer's
            # own mutations (so that the readers' other checks meet it too).
            if generator is None or rng.random() < 0.25:
                for _ in range(rng.randint(1, 4)):
                    data = atheris.Mutate(data, max_size)
            if generator is not None:
                data = generator(bytes(data), rng)
            return data[:max_size]

        def test_pooled(data):
            before = harness.stats["accepted"]
            harness.one(bytes(data))
            if harness.stats["accepted"] > before and len(pool) < 256:
                pool.append(bytes(data))

        atheris.Setup([argv[0]] + rest, test_pooled if pooled else test_one_input,
                      custom_mutator=mutate)
    else:
        atheris.Setup([argv[0]] + rest, test_one_input)
    atheris.Fuzz()
    return 0


if __name__ == "__main__":
    sys.exit(main())
