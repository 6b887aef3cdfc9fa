"""Never a silently wrong volume: every reader verifies what it reads.

Valid small files are written here (pynrrd, nibabel, tifffile, h5py, or by hand), checked to
round-trip bit-exactly through vtksvdag.read, then damaged: gzip/zlib trailers flipped, streams
truncated, bytes appended, raw bodies one byte short or long, header fields outside their
specification. Each damaged file must raise OSError or ValueError from vtksvdag.read with a
message that names the problem.
"""
import gzip
import os
import pathlib
import struct
import zlib

import h5py
import nibabel
import nrrd
import numpy as np
import pytest
import tifffile

import vtksvdag

SHAPE = (17, 23, 37)  # (x, y, z): more than two slabs of 16 slices


@pytest.fixture
def labels():
    rng = np.random.default_rng(7)
    a = rng.integers(0, 40, size=SHAPE).astype(np.uint16)
    a[:5] = 65535  # the dtype's extreme
    return a


def zyx(a):
    """(x, y, z) -> C-ordered (z, y, x) bytes order: x fastest."""
    return np.ascontiguousarray(a.transpose(2, 1, 0))


def assert_round_trip(path, expected):
    got = vtksvdag.read(path).to_numpy()
    assert got.dtype == expected.dtype and got.shape == expected.shape
    np.testing.assert_array_equal(got, expected)


def assert_refused(path, *messages):
    with pytest.raises((OSError, ValueError)) as info:
        vtksvdag.read(path)
    text = str(info.value)
    for m in messages:
        assert m in text, text
    return text


def flip(path, offset, mask=0x01):
    data = bytearray(path.read_bytes())
    data[offset] ^= mask
    path.write_bytes(bytes(data))


def append(path, extra):
    path.write_bytes(path.read_bytes() + extra)


def cut(path, n):
    path.write_bytes(path.read_bytes()[:-n])


# ------------------------------------------------------------------------------ file writers


def nrrd_text(a, encoding, **extra):
    fields = {"type": "uint16", "dimension": "3", "sizes": " ".join(map(str, a.shape)),
              "endian": "little", "encoding": encoding, **extra}
    return ("NRRD0004\n" + "".join(f"{k}: {v}\n" for k, v in fields.items())).encode()


def write_nrrd(tmp_path, a, encoding):
    path = tmp_path / "v.nrrd"
    nrrd.write(str(path), a, {"encoding": encoding})  # Fortran order: x fastest
    return path


def write_mha(tmp_path, a, compressed, local=True, size_field=False):
    body = zyx(a).astype("<u2").tobytes()
    if compressed:
        body = zlib.compress(body)
    header = ("ObjectType = Image\nNDims = 3\nDimSize = {} {} {}\nElementType = MET_USHORT\n"
              "BinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = {}\n"
              .format(*a.shape, "True" if compressed else "False"))
    if size_field:
        header += f"CompressedDataSize = {len(body)}\n"
    if local:
        path = tmp_path / "v.mha"
        path.write_bytes((header + "ElementDataFile = LOCAL\n").encode() + body)
    else:
        path = tmp_path / "v.mhd"
        (tmp_path / "v.raw").write_bytes(body)
        path.write_bytes((header + "ElementDataFile = v.raw\n").encode())
    return path


def write_nifti(tmp_path, a, suffix, cls=nibabel.Nifti1Image):
    path = tmp_path / f"v{suffix}"
    nibabel.save(cls(a, np.eye(4), dtype=a.dtype), path)
    return path


# ------------------------------------------------------------------------ valid files round-trip


@pytest.mark.parametrize("kind", [
    "nrrd-raw", "nrrd-gzip", "nhdr-raw", "nhdr-gzip", "mha-raw", "mha-zlib", "mhd-raw", "nii",
    "nii.gz", "nifti2", "pair", "pair-gz", "tif", "tif-deflate", "tif-deflate-predictor",
    "tif-deflate-tiles", "tif-deflate-big-endian", "h5", "h5-gzip",
])
def test_valid_files_round_trip(tmp_path, labels, kind):
    a = labels
    if kind.startswith("nrrd"):
        path = write_nrrd(tmp_path, a, kind.split("-")[1])
    elif kind.startswith("nhdr"):
        path = tmp_path / "v.nhdr"
        nrrd.write(str(path), a, {"encoding": kind.split("-")[1]}, detached_header=True)
    elif kind.startswith("mh"):
        path = write_mha(tmp_path, a, kind.endswith("zlib"), local=kind.startswith("mha"))
    elif kind in ("nii", "nii.gz"):
        path = write_nifti(tmp_path, a, "." + kind)
    elif kind == "nifti2":
        path = write_nifti(tmp_path, a, ".nii", nibabel.Nifti2Image)
    elif kind.startswith("pair"):
        path = tmp_path / ("v.hdr.gz" if kind == "pair-gz" else "v.hdr")
        nibabel.save(nibabel.Nifti1Pair(a, np.eye(4), dtype=a.dtype), path)
    elif kind.startswith("tif"):
        path = tmp_path / "v.tif"
        options = {
            "tif": {}, "tif-deflate": dict(compression="zlib"),
            "tif-deflate-predictor": dict(compression="zlib", predictor=True),
            "tif-deflate-tiles": dict(compression="zlib", tile=(16, 16)),
            "tif-deflate-big-endian": dict(compression="zlib", predictor=True, byteorder=">"),
        }[kind]
        tifffile.imwrite(path, zyx(a), photometric="minisblack", **options)
    else:
        path = tmp_path / "v.h5"
        with h5py.File(path, "w") as f:
            f.create_dataset("labels", data=zyx(a),
                             **(dict(compression="gzip", chunks=(4, 8, 8)) if kind == "h5-gzip"
                                else {}))
    assert_round_trip(path, a)


def test_gzip_members_without_data_are_valid(tmp_path, labels):
    """Several gzip members, some empty, concatenated: one stream (RFC 1952)."""
    raw = zyx(labels).tobytes()
    path = tmp_path / "m.nrrd"
    path.write_bytes(nrrd_text(labels, "gzip") + b"\n" + gzip.compress(raw[:1000]) +
                     gzip.compress(b"") + gzip.compress(raw[1000:]) + gzip.compress(b""))
    assert_round_trip(path, labels)


# ------------------------------------------------------------------------- gzip: NRRD, .nii.gz


def gzip_file(tmp_path, labels, fmt):
    if fmt == "nrrd":
        return write_nrrd(tmp_path, labels, "gzip")
    return write_nifti(tmp_path, labels, ".nii.gz")


@pytest.mark.parametrize("fmt", ["nrrd", "nii.gz"])
def test_gzip_crc_flipped(tmp_path, labels, fmt):
    path = gzip_file(tmp_path, labels, fmt)
    flip(path, path.stat().st_size - 8)
    text = assert_refused(path, "gzip CRC-32 mismatch: stored 0x", "computed 0x", path.name)
    stored, computed = [int(w.rstrip(","), 16) for w in text.split() if w.startswith("0x")][:2]
    assert stored ^ computed == 0x01


@pytest.mark.parametrize("fmt", ["nrrd", "nii.gz"])
def test_gzip_isize_flipped(tmp_path, labels, fmt):
    path = gzip_file(tmp_path, labels, fmt)
    flip(path, path.stat().st_size - 4)
    assert_refused(path, "gzip ISIZE mismatch", path.name)


@pytest.mark.parametrize("fmt", ["nrrd", "nii.gz"])
@pytest.mark.parametrize("n,message", [(3, "trailer"), (8, "trailer"), (200, "truncated")])
def test_gzip_truncated(tmp_path, labels, fmt, n, message):
    path = gzip_file(tmp_path, labels, fmt)
    cut(path, n)
    assert_refused(path, message, path.name)


@pytest.mark.parametrize("fmt", ["nrrd", "nii.gz"])
@pytest.mark.parametrize("extra,message", [
    (b"\0", "1 byte of data after the end of the gzip stream"),
    (b"garbage!", "8 bytes of data after the end of the gzip stream"),
    (gzip.compress(b"more voxels"), "11 more bytes than"),
    (gzip.compress(b"x")[:12], "ends before its end marker"),
])
def test_gzip_appended(tmp_path, labels, fmt, extra, message):
    path = gzip_file(tmp_path, labels, fmt)
    append(path, extra)
    assert_refused(path, message, path.name)


def test_gzip_data_longer_than_the_header_says(tmp_path, labels):
    path = tmp_path / "long.nrrd"
    path.write_bytes(nrrd_text(labels, "gzip") + b"\n" + gzip.compress(zyx(labels).tobytes() + b"xy"))
    assert_refused(path, "2 more bytes than", "long.nrrd")


def test_gzip_header_crc(tmp_path, labels):
    """FHCRC: the header's own CRC-16 is checked too."""
    body = zlib.compressobj(6, zlib.DEFLATED, -15)
    deflated = body.compress(zyx(labels).tobytes()) + body.flush()
    header = b"\x1f\x8b\x08\x02" + bytes(6)
    crc16 = zlib.crc32(header) & 0xFFFF
    trailer = struct.pack("<II", zlib.crc32(zyx(labels).tobytes()), labels.nbytes)
    path = tmp_path / "fhcrc.nrrd"
    path.write_bytes(nrrd_text(labels, "gzip") + b"\n" + header + struct.pack("<H", crc16) +
                     deflated + trailer)
    assert_round_trip(path, labels)
    path.write_bytes(nrrd_text(labels, "gzip") + b"\n" + header + struct.pack("<H", crc16 ^ 1) +
                     deflated + trailer)
    assert_refused(path, "gzip header CRC-16 mismatch")


# ------------------------------------------------------------------- zlib: MetaImage, TIFF deflate


def test_zlib_adler_flipped(tmp_path, labels):
    path = write_mha(tmp_path, labels, True)
    flip(path, path.stat().st_size - 1)
    assert_refused(path, "zlib Adler-32 mismatch: stored 0x", "computed 0x", "v.mha")


def test_zlib_truncated(tmp_path, labels):
    path = write_mha(tmp_path, labels, True)
    cut(path, 2)
    assert_refused(path, "Adler-32 trailer", "v.mha")
    path = write_mha(tmp_path, labels, True)
    cut(path, 300)
    assert_refused(path, "truncated")


@pytest.mark.parametrize("extra", [b"\0", gzip.compress(b"")])
def test_zlib_appended(tmp_path, labels, extra):
    path = write_mha(tmp_path, labels, True)
    append(path, extra)
    assert_refused(path, f"{len(extra)} bytes of data after the end of the zlib stream")


def tiff_chunks(path):
    with tifffile.TiffFile(path) as t:
        page = t.pages[3]
        return list(page.dataoffsets), list(page.databytecounts)


@pytest.mark.parametrize("tile", [None, (16, 16)])
def test_tiff_deflate_adler_flipped(tmp_path, labels, tile):
    path = tmp_path / "d.tif"
    tifffile.imwrite(path, zyx(labels), photometric="minisblack", compression="zlib",
                     **({"tile": tile} if tile else {}))
    offsets, counts = tiff_chunks(path)
    flip(path, offsets[0] + counts[0] - 1)
    assert_refused(path, "zlib Adler-32 mismatch", "of page 3", "d.tif")


def test_tiff_deflate_strip_with_extra_data(tmp_path, labels):
    """A strip whose stream holds more pixels than the strip has."""
    path = tmp_path / "d.tif"
    tifffile.imwrite(path, zyx(labels), photometric="minisblack", compression="zlib",
                     rowsperstrip=labels.shape[1])
    offsets, counts = tiff_chunks(path)
    data = bytearray(path.read_bytes())
    with tifffile.TiffFile(path) as t:
        strip = zyx(labels)[3].astype("<u2").tobytes()
        stream = zlib.compress(strip + b"\0\0")
        assert len(stream) <= counts[0]
        # Same length: pad the stream with bytes after its end, which is an error too.
        data[offsets[0]:offsets[0] + counts[0]] = stream + b"\0" * (counts[0] - len(stream))
    path.write_bytes(bytes(data))
    assert_refused(path, "strip 0 of page 3")


# ---------------------------------------------------------------------------------- raw bodies


@pytest.mark.parametrize("kind", ["nrrd", "nhdr", "mha", "mhd", "nii", "pair"])
@pytest.mark.parametrize("delta", [-1, 1])
def test_raw_body_length(tmp_path, labels, kind, delta):
    if kind == "nrrd":
        path = data = write_nrrd(tmp_path, labels, "raw")
    elif kind == "nhdr":
        path = tmp_path / "v.nhdr"
        nrrd.write(str(path), labels, {"encoding": "raw"}, detached_header=True)
        data = tmp_path / "v.raw"
    elif kind in ("mha", "mhd"):
        path = write_mha(tmp_path, labels, False, local=kind == "mha")
        data = path if kind == "mha" else tmp_path / "v.raw"
    elif kind == "nii":
        path = data = write_nifti(tmp_path, labels, ".nii")
    else:
        path = tmp_path / "v.hdr"
        nibabel.save(nibabel.Nifti1Pair(labels, np.eye(4), dtype=labels.dtype), path)
        data = tmp_path / "v.img"
    assert data.exists()
    assert_round_trip(path, labels)
    if delta < 0:
        cut(data, 1)
        assert_refused(path, f"holds {labels.nbytes - 1} data bytes", str(labels.nbytes),
                       "truncated")
    else:
        append(data, b"\0")
        assert_refused(path, f"holds {labels.nbytes + 1} data bytes", "1 more than",
                       str(labels.nbytes))


def test_tiff_strip_past_the_end(tmp_path, labels):
    """A strip whose byte count runs past the end of the file (a truncated file)."""
    path = tmp_path / "t.tif"
    tifffile.imwrite(path, zyx(labels), photometric="minisblack", rowsperstrip=4)
    with tifffile.TiffFile(path) as t:
        tag = t.pages[3].tags["StripByteCounts"]
        at, n = tag.valueoffset, len(tag.value)
        fmt = "<H" if tag.dtype == 3 else "<I" if tag.dtype == 4 else "<Q"
    data = bytearray(path.read_bytes())
    struct.pack_into(fmt, data, at + (n - 1) * struct.calcsize(fmt), 10**6 if fmt != "<H" else 65535)
    path.write_bytes(bytes(data))
    assert_refused(path, f"strip {n - 1} of page", "runs past the end of the file")


def test_tiff_uncompressed_strip_byte_count(tmp_path, labels):
    """An uncompressed strip whose byte count is not its pixels' size."""
    path = tmp_path / "t.tif"
    tifffile.imwrite(path, zyx(labels), photometric="minisblack", rowsperstrip=labels.shape[1])
    with tifffile.TiffFile(path) as t:
        tag = t.pages[3].tags["StripByteCounts"]
        at, size, count = tag.valueoffset, tag.dtype, tag.value[0]
    data = bytearray(path.read_bytes())
    fmt = "<H" if tag.dtype == 3 else "<I" if tag.dtype == 4 else "<Q"
    struct.pack_into(fmt, data, at, count - 2)
    path.write_bytes(bytes(data))
    assert_refused(path, "byte counts of page 3 do not match its pixels", "StripByteCounts")


def test_hdf5_truncated(tmp_path, labels):
    path = tmp_path / "t.h5"
    with h5py.File(path, "w") as f:
        f["labels"] = zyx(labels)
    assert_round_trip(path, labels)
    cut(path, 100)
    assert_refused(path, "t.h5")


HDF5_CRASHES = sorted((pathlib.Path(__file__).parents[1] / "fuzz" / "crashes").glob("h5--*segfault*"))


@pytest.mark.parametrize("path", HDF5_CRASHES, ids=lambda p: p.name)
def test_hdf5_library_crash_is_an_error(path):
    # These files crash HDF5 1.10 itself (a read out of bounds in its metadata cache); the
    # reader runs HDF5 in a child process, so the crash is an error for the file.
    before = child_processes()
    assert_refused(path, "the HDF5 library crashed")
    assert child_processes() == before, "the HDF5 reader process was not reaped"


def test_hdf5_reader_leaves_no_process(tmp_path, labels):
    path = tmp_path / "t.h5"
    with h5py.File(path, "w") as f:
        f["labels"] = zyx(labels)
    before = child_processes()
    for _ in range(3):
        assert_round_trip(path, labels)
    assert child_processes() == before


def child_processes():
    """PIDs of this process's children (from /proc: Linux), sorted. Compared before and after
    a read: earlier tests may leave helpers of their own (multiprocessing's resource tracker,
    started by the Dask tests, lives as long as the test process)."""
    children = []
    for entry in pathlib.Path("/proc").iterdir():
        try:
            fields = (entry / "stat").read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if int(fields[1]) == os.getpid():
            children.append(int(entry.name))
    return sorted(children)


# ------------------------------------------------------------------------------ header fields


def nifti_patched(tmp_path, labels, **fields):
    """A .nii with header fields overwritten: name -> (offset, struct format, value)."""
    path = write_nifti(tmp_path, labels, ".nii")
    data = bytearray(path.read_bytes())
    for offset, fmt, value in fields.values():
        struct.pack_into("<" + fmt, data, offset, value)
    path.write_bytes(bytes(data))
    return path


@pytest.mark.parametrize("fields,messages", [
    (dict(dim0=(40, "h", 0)), ["dim[0] = 0", "1 to 7"]),
    (dict(dim0=(40, "h", 8)), ["dim[0] = 8", "1 to 7"]),
    (dict(dim0=(40, "h", 4), dim4=(48, "h", 2)), ["dim[4] = 2", "label volumes need 3"]),
    (dict(dim2=(44, "h", 0)), ["dim[2] = 0"]),
    (dict(vox=(108, "f", 348.0)), ["vox_offset", ">= 352"]),
    (dict(vox=(108, "f", 352.5)), ["vox_offset"]),
    (dict(datatype=(70, "h", 16), bitpix=(72, "h", 32)), ["label volumes need integer scalars",
                                                         "float32"]),
    (dict(datatype=(70, "h", 99)), ["unknown NIfTI datatype 99"]),
    (dict(bitpix=(72, "h", 8)), ["bitpix 8 does not match"]),
    (dict(sizeof_hdr=(0, "i", 347)), ["not a label volume in a known format"]),
])
def test_nifti_header_fields(tmp_path, labels, fields, messages):
    assert_refused(nifti_patched(tmp_path, labels, **fields), *messages)


def test_nifti_dims_of_size_one_past_the_third_are_fine(tmp_path, labels):
    path = nifti_patched(tmp_path, labels, dim0=(40, "h", 5), dim4=(48, "h", 1),
                         dim5=(50, "h", 1))
    assert_round_trip(path, labels)


@pytest.mark.parametrize("sizes,message", [
    ("2000000000 2000000000 2000000000", "more than 2^40"),
    ("1048576 1048576 2", "more than 2^40"),
    ("0 4 4", "outside 1 .. 2^31-1"),
    ("-3 4 4", "outside 1 .. 2^31-1"),
    ("4 4", "'sizes' must list 3 values"),
])
def test_nrrd_sizes(tmp_path, sizes, message):
    path = tmp_path / "s.nrrd"
    path.write_bytes(f"NRRD0004\ntype: uint8\ndimension: 3\nsizes: {sizes}\nencoding: raw\n\n"
                     .encode() + bytes(64))
    assert_refused(path, message)


@pytest.mark.parametrize("lines,message", [
    ("NDims = 3\nDimSize = 2000000 2000000 2000000\nElementType = MET_UCHAR\n", "more than 2^40"),
    ("NDims = 3\nDimSize = 4 0 4\nElementType = MET_UCHAR\n", "outside 1 .. 2^31-1"),
    ("NDims = 3\nDimSize = 4 4\nElementType = MET_UCHAR\n", "DimSize must list NDims values"),
    ("NDims = 4\nDimSize = 4 4 4 4\nElementType = MET_UCHAR\n", "label volumes need 1 to 3"),
    ("NDims = 3\nDimSize = 4 4 4.5\nElementType = MET_UCHAR\n", "outside 1 .. 2^31-1"),
    ("NDims = 3\nDimSize = 4 4 4\nElementType = MET_FLOAT\n", "label volumes need integer"),
    ("NDims = 3\nDimSize = 4 4 4\nElementType = MET_STRING\n", "not supported"),
])
def test_metaimage_header_fields(tmp_path, lines, message):
    path = tmp_path / "h.mha"
    path.write_bytes(("ObjectType = Image\n" + lines + "ElementDataFile = LOCAL\n").encode() +
                     bytes(64))
    assert_refused(path, message)


def test_metaimage_compressed_data_size(tmp_path, labels):
    """CompressedDataSize, when given, must be the size of the stream in the file."""
    path = write_mha(tmp_path, labels, True, size_field=True)
    assert_round_trip(path, labels)
    text = path.read_bytes()
    stored = len(zlib.compress(zyx(labels).astype("<u2").tobytes()))
    path.write_bytes(text.replace(f"CompressedDataSize = {stored}".encode(),
                                  f"CompressedDataSize = {stored + 1}".encode()))
    assert_refused(path, "CompressedDataSize", str(stored + 1), str(stored))
