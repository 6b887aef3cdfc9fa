"""Base64 in VTK XML image data (.vti): what VTK 9.1's writer produces reads exactly, anything
else in the base64 text is refused (issue 24).

VTK's own decoder stops at the first character outside the base64 alphabet without an error and
leaves the rest of the array 0, and it ignores text past what the array's header gives; the
reader (svdagVTIImageSlabSource's HeaderCheck) checks the text before VTK decodes it: the alphabet,
'=' only as a run's padding, each run exactly as long as the header's byte counts make it, only
white space around an inline array's text, appended arrays back to back. A refusal names the array
and the byte offset in the file.

Layouts as vtkXMLImageDataWriter writes them (checked here, not assumed): uncompressed, the header
word and the data are one padded run; compressed, the header words are one run and all compressed
blocks together the next.
"""
import base64
import re
import subprocess
import sys

import numpy as np
import pytest
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkImageData
from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

import vtksvdag

DTYPES = ["int8", "uint8", "int16", "uint16", "int32", "uint32", "int64", "uint64"]
SHAPE = (20, 9, 11)  # (z, y, x): more than one 16-slice slab; 1980 voxels
COMPRESSORS = ["None", "ZLib", "LZ4", "LZMA"]
# name -> (data mode, EncodeAppendedData)
LAYOUTS = {"inline": ("Binary", None), "appended-base64": ("Appended", True),
           "appended-raw": ("Appended", False), "ascii": ("Ascii", None)}


def labels_of(dtype, seed=5):
    rng = np.random.default_rng(seed)
    info = np.iinfo(dtype)
    values = np.array([0, 1, 2, 77, info.min, info.max], dtype=dtype)
    return values[rng.integers(0, len(values), size=SHAPE)]


def write_vti(path, zyx, layout="inline", compressor="None", header="UInt32", block_size=256):
    """Writes zyx with vtkXMLImageDataWriter (point scalars 'labels', a field data array 'fd');
    returns the file's bytes."""
    image = vtkImageData()
    image.SetDimensions(zyx.shape[2], zyx.shape[1], zyx.shape[0])
    scalars = numpy_to_vtk(np.ascontiguousarray(zyx).ravel(), deep=True)
    scalars.SetName("labels")
    image.GetPointData().SetScalars(scalars)
    field = numpy_to_vtk(np.arange(5, dtype=np.int32), deep=True)
    field.SetName("fd")
    image.GetFieldData().AddArray(field)
    mode, encode = LAYOUTS[layout]
    writer = vtkXMLImageDataWriter()
    writer.SetInputData(image)
    writer.SetFileName(str(path))
    getattr(writer, f"SetDataModeTo{mode}")()
    if encode is not None:
        writer.SetEncodeAppendedData(encode)
    getattr(writer, f"SetCompressorTypeTo{compressor}")()
    getattr(writer, f"SetHeaderTypeTo{header}")()
    writer.SetBlockSize(block_size)
    assert writer.Write() == 1
    return path.read_bytes()


def read_zyx(path):
    return vtksvdag.read(path).to_numpy().transpose(2, 1, 0)


def text_span(data, name):
    """(begin, end) byte offsets of array `name`'s base64 text: inline, between the tags without
    the white space around it; appended, from its offset to the next array's (or the last
    base64 character)."""
    match = re.search(rb'<DataArray[^>]* Name="' + name.encode() + rb'"[^>]*>', data)
    tag = match.group(0)
    if b'format="binary"' in tag:
        begin = match.end()
        while data[begin:begin + 1].isspace():
            begin += 1
        end = data.index(b"<", begin)
        while data[end - 1:end].isspace():
            end -= 1
        return begin, end
    start = data.index(b"_", data.index(b"<AppendedData")) + 1
    offsets = sorted(int(o) for o in re.findall(rb'offset="(\d+)"', data))
    own = int(re.search(rb'offset="(\d+)"', tag).group(1))
    later = [o for o in offsets if o > own]
    if later:
        return start + own, start + later[0]
    end = data.index(b"</AppendedData>")
    while data[end - 1:end].isspace():
        end -= 1
    return start + own, end


def header_chars(data, begin, compressed, word):
    """The length of the header run of a compressed array whose text starts at `begin`
    (uncompressed: the word's characters, which share the run with the data)."""
    if not compressed:
        return -(-word * 8 // 6)
    first = base64.b64decode(data[begin:begin + 4 * -(-3 * word // 3)])
    blocks = int.from_bytes(first[:word], "little")
    return 4 * -(-(3 + blocks) * word // 3)


def refused(path, name, offset, what):
    with pytest.raises((OSError, ValueError)) as error:
        read_zyx(path)
    message = str(error.value)
    assert f"array '{name}'" in message, message
    assert f"at byte offset {offset}" in message, message
    assert what in message, message
    return message


# ------------------------------------------------------------------------------ valid files


# ascii data is never compressed
WRITTEN = [(layout, c) for layout in LAYOUTS for c in COMPRESSORS
           if layout != "ascii" or c == "None"]


@pytest.mark.parametrize("dtype", DTYPES)
@pytest.mark.parametrize("header", ["UInt32", "UInt64"])
@pytest.mark.parametrize("layout,compressor", WRITTEN, ids=["-".join(w) for w in WRITTEN])
def test_vtk_written_layouts_read_exactly(tmp_path, layout, compressor, header, dtype):
    zyx = labels_of(dtype)
    path = tmp_path / "v.vti"
    write_vti(path, zyx, layout, compressor, header)
    got = read_zyx(path)
    assert got.dtype == zyx.dtype
    np.testing.assert_array_equal(got, zyx)


@pytest.mark.parametrize("compressor", ["None", "ZLib"])
def test_white_space_around_inline_text_is_accepted(tmp_path, compressor):
    """vtkXMLDataParser skips white space before an inline array's text and reads only what the
    header gives: more of it before and after the runs is still the same array."""
    zyx = labels_of("uint16")
    path = tmp_path / "v.vti"
    data = write_vti(path, zyx, "inline", compressor)
    begin, end = text_span(data, "labels")
    path.write_bytes(data[:begin] + b"\r\n\t  \n" + data[begin:end] + b" \t\r\n\n " + data[end:])
    np.testing.assert_array_equal(read_zyx(path), zyx)


# ---------------------------------------------------------------------------- invalid files

# (layout, compressor, header): the four ways base64 text is laid out, both word sizes.
BASE64_LAYOUTS = [("inline", "None", "UInt32"), ("inline", "ZLib", "UInt64"),
                  ("appended-base64", "None", "UInt64"), ("appended-base64", "ZLib", "UInt32")]
LAYOUT_IDS = ["-".join(x) for x in BASE64_LAYOUTS]


def uint8_file(tmp_path, layout, compressor, header):
    path = tmp_path / "bad.vti"
    data = write_vti(path, labels_of("uint8"), layout, compressor, header)
    word = 8 if header == "UInt64" else 4
    begin, end = text_span(data, "labels")
    return path, data, begin, end, header_chars(data, begin, compressor != "None", word)


@pytest.mark.parametrize("char", [b"!", b"-", b"_", b".", b"\xe9", b"\x00"],
                         ids=["bang", "minus", "underscore", "dot", "latin1", "nul"])
@pytest.mark.parametrize("where", ["header", "first-data", "middle", "last"])
@pytest.mark.parametrize("layout", BASE64_LAYOUTS, ids=LAYOUT_IDS)
def test_invalid_character(tmp_path, layout, where, char):
    path, data, begin, end, head = uint8_file(tmp_path, *layout)
    last = begin + len(data[begin:end].rstrip(b"="))  # just past the last non-padding character
    at = {"header": begin + 1, "first-data": begin + head + 1, "middle": (begin + end) // 2,
          "last": last - 1}[where]
    path.write_bytes(data[:at] + char + data[at + 1:])
    refused(path, "labels", at, "invalid base64 character")


@pytest.mark.parametrize("layout", BASE64_LAYOUTS, ids=LAYOUT_IDS)
def test_invalid_character_in_field_data(tmp_path, layout):
    """Arrays outside the pieces are decoded by VTK too and checked alike."""
    path, data, _, _, _ = uint8_file(tmp_path, *layout)
    begin, end = text_span(data, "fd")
    at = end - 3
    path.write_bytes(data[:at] + b"*" + data[at + 1:])
    refused(path, "fd", at, "invalid base64 character '*'")


@pytest.mark.parametrize("layout", BASE64_LAYOUTS, ids=LAYOUT_IDS)
def test_padding_inside_a_run(tmp_path, layout):
    path, data, begin, end, head = uint8_file(tmp_path, *layout)
    at = begin + head + 40
    path.write_bytes(data[:at] + b"=" + data[at + 1:])
    refused(path, "labels", at, "padding '=' before the end of the run")


def test_padding_in_the_header_run(tmp_path):
    """A compressed array's header is its own run: padding where its words need characters."""
    path, data, begin, _, _ = uint8_file(tmp_path, "inline", "ZLib", "UInt32")
    path.write_bytes(data[:begin + 6] + b"==" + data[begin + 8:])
    refused(path, "labels", begin + 6, "padding '=' before the end of the run")


@pytest.mark.parametrize("layout", BASE64_LAYOUTS, ids=LAYOUT_IDS)
def test_padding_replaced_by_data(tmp_path, layout):
    """The run goes on where its padding belongs: longer than the header's byte counts."""
    path, data, begin, end, _ = uint8_file(tmp_path, *layout)
    pad = data.index(b"=", end - 2, end + 1) if data[end - 1:end] == b"=" else None
    if pad is None:
        pytest.skip("this run needs no padding")
    path.write_bytes(data[:pad] + b"A" + data[pad + 1:])
    refused(path, "labels", pad, "it goes on past them")


@pytest.mark.parametrize("layout", BASE64_LAYOUTS, ids=LAYOUT_IDS)
def test_padding_missing(tmp_path, layout):
    path, data, begin, end, _ = uint8_file(tmp_path, *layout)
    stripped = len(data[begin:end].rstrip(b"="))
    if begin + stripped == end:
        pytest.skip("this run needs no padding")
    path.write_bytes(data[:begin + stripped] + data[end:])
    refused(path, "labels", begin + stripped, "padding '=' is missing")


@pytest.mark.parametrize("layout", BASE64_LAYOUTS, ids=LAYOUT_IDS)
def test_extra_padding(tmp_path, layout):
    path, data, begin, end, _ = uint8_file(tmp_path, *layout)
    path.write_bytes(data[:end] + b"=" + data[end:])
    refused(path, "labels", end, "past the end of its data")


@pytest.mark.parametrize("layout", BASE64_LAYOUTS, ids=LAYOUT_IDS)
def test_truncated_run(tmp_path, layout):
    """The text ends 8 characters before the header's byte counts do."""
    path, data, begin, end, _ = uint8_file(tmp_path, *layout)
    path.write_bytes(data[:end - 8] + data[end:])
    refused(path, "labels", end - 8, "the text ends early")


@pytest.mark.parametrize("layout", BASE64_LAYOUTS, ids=LAYOUT_IDS)
def test_run_longer_than_the_header_says(tmp_path, layout):
    """Four more base64 characters after the run: VTK would ignore them."""
    path, data, begin, end, _ = uint8_file(tmp_path, *layout)
    path.write_bytes(data[:end] + b"AAAA" + data[end:])
    refused(path, "labels", end, "past the end of its data")


@pytest.mark.parametrize("header", ["UInt32", "UInt64"])
def test_compressed_sizes_longer_than_the_blocks(tmp_path, header):
    """The header's first compressed block size raised by 3: the blocks' run would need 4
    characters more than it has (it fails at its padding, or where it ends)."""
    word = 8 if header == "UInt64" else 4
    path, data, begin, end, head = uint8_file(tmp_path, "inline", "ZLib", header)
    words = bytearray(base64.b64decode(data[begin:begin + head]))
    size = int.from_bytes(words[3 * word:4 * word], "little") + 3
    words[3 * word:4 * word] = size.to_bytes(word, "little")
    encoded = base64.b64encode(bytes(words))
    assert len(encoded) == head
    path.write_bytes(data[:begin] + encoded + data[begin + head:])
    pads = len(data[begin:end]) - len(data[begin:end].rstrip(b"="))
    refused(path, "labels", end - pads, "base64 compressed blocks of")


def test_white_space_inside_a_run(tmp_path):
    path, data, begin, end, _ = uint8_file(tmp_path, "inline", "None", "UInt32")
    at = (begin + end) // 2
    path.write_bytes(data[:at] + b"\n" + data[at:])
    refused(path, "labels", at, "white space inside the run")


def test_white_space_between_the_header_and_block_runs(tmp_path):
    """VTK writes the compressed blocks' run right after the header's: nothing between them."""
    path, data, begin, end, head = uint8_file(tmp_path, "inline", "ZLib", "UInt32")
    path.write_bytes(data[:begin + head] + b" " + data[begin + head:])
    refused(path, "labels", begin + head, "white space inside the run")


def test_appended_gap_between_arrays(tmp_path):
    """Four base64 characters before the scalars' run, its offset moved past them: VTK reads the
    same array, but it is not what VTK wrote (nothing belongs to them)."""
    path, data, begin, end, _ = uint8_file(tmp_path, "appended-base64", "None", "UInt32")
    tag = re.search(rb'<DataArray[^>]* Name="labels"[^>]*>', data)
    old = re.search(rb'offset="(\d+)"', tag.group(0))
    new = b'offset="%d"' % (int(old.group(1)) + 4)
    shift = len(new) - len(old.group(0))
    mutated = data[:tag.start() + old.start()] + new + data[tag.start() + old.end():]
    b = begin + shift
    mutated = mutated[:b] + b"AAAA" + mutated[b:]
    path.write_bytes(mutated)
    refused(path, "labels", b + 4, f"the base64 before it ends at byte offset {b}")


# --------------------------------------------------------------- one error line, no VTK log


def _bad_files(tmp_path):
    zyx = labels_of("uint8")
    files = {}
    path = tmp_path / "bad_char.vti"
    data = write_vti(path, zyx, "inline", "None")
    begin, end = text_span(data, "labels")
    path.write_bytes(data[:begin + 100] + b"!" + data[begin + 101:])
    files["base64"] = path
    # A zlib block whose base64 is valid but whose deflate data is not: the compressor's error.
    path = tmp_path / "bad_zlib.vti"
    data = write_vti(path, zyx, "inline", "ZLib")
    begin, end = text_span(data, "labels")
    head = header_chars(data, begin, True, 4)
    path.write_bytes(data[:begin + head + 8] + b"QUJD" + data[begin + head + 12:])
    files["zlib"] = path
    # Malformed XML: the XML parser's error.
    path = tmp_path / "bad_xml.vti"
    write_vti(path, zyx, "inline", "None")
    path.write_bytes(path.read_bytes().replace(b"</PointData>", b"</PointDat>"))
    files["xml"] = path
    # A legacy .vtk file (not a format the project reads).
    from vtkmodules.vtkIOLegacy import vtkStructuredPointsWriter

    image = vtkImageData()
    image.SetDimensions(3, 4, 5)
    image.GetPointData().SetScalars(numpy_to_vtk(np.arange(60, dtype=np.uint8), deep=True))
    path = tmp_path / "legacy.vtk"
    writer = vtkStructuredPointsWriter()
    writer.SetInputData(image)
    writer.SetFileName(str(path))
    writer.SetFileTypeToBinary()
    writer.Write()
    path.write_bytes(path.read_bytes()[:200])
    files["legacy"] = path
    return files


READ_SNIPPET = """
import sys, vtksvdag
try:
    vtksvdag.read(sys.argv[1])
except (OSError, ValueError) as error:
    print(error, file=sys.stderr)
    sys.exit(3)
"""


@pytest.mark.parametrize("kind", ["base64", "zlib", "xml", "legacy"])
def test_rejected_file_prints_one_line(tmp_path, kind):
    """The CLI and vtksvdag.read print the project's message only: VTK's parser and compressor
    errors are folded into it, not logged before it as VTK's coloured ERR| lines."""
    path = _bad_files(tmp_path)[kind]
    cli = subprocess.run([sys.executable, "-m", "vtksvdag", "compress", str(path), "-o",
                          str(tmp_path / "out.svdag")], capture_output=True, text=True, timeout=120)
    assert cli.returncode == 1, (cli.stdout, cli.stderr)
    lines = cli.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("vtksvdag: error: "), cli.stderr
    assert "ERR|" not in cli.stderr and str(path) in lines[0]
    read = subprocess.run([sys.executable, "-c", READ_SNIPPET, str(path)], capture_output=True,
                          text=True, timeout=120)
    assert read.returncode == 3, (read.stdout, read.stderr)
    assert len(read.stderr.strip().splitlines()) == 1 and "ERR|" not in read.stderr, read.stderr
    expected = {"base64": "invalid base64 character '!'", "zlib": "Zlib error",
                "xml": "mismatched tag", "legacy": "not a label volume"}[kind]
    assert expected in lines[0], lines[0]
