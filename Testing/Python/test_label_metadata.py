"""Label names and colors from the files users have: vtksvdag.read_label_table, the
label_metadata vtksvdag.read picks up, and add_segmentation(attributes=table).

Files come from the formats' own libraries where they are installed here (pynrrd writes the
.seg.nrrd files, zarr-python and tensorstore the OME-Zarr label images); FreeSurfer, ITK-SNAP,
neuroglancer segment properties and CSV tables are written by hand in the layout of the formats'
documentation. Every table read is compared with an expected table written out independently
here (names, 0-255 or 0-1 colors as the file gives them).
"""
import json
import pickle

import numpy as np
import pandas as pd
import pytest

import vtksvdag
from vtksvdag.labelmeta import FORMATS

nrrd = pytest.importorskip("nrrd")

# A FreeSurferColorLUT.txt excerpt as FreeSurfer ships it (comments, blank lines, aligned
# columns; A is 0 throughout): label, name, R, G, B, A.
FREESURFER_ROWS = [
    (0, "Unknown", 0, 0, 0, 0),
    (2, "Left-Cerebral-White-Matter", 245, 245, 245, 0),
    (17, "Left-Hippocampus", 220, 216, 20, 0),
    (18, "Left-Amygdala", 103, 255, 255, 0),
    (53, "Right-Hippocampus", 220, 216, 20, 0),
    (54, "Right-Amygdala", 103, 255, 255, 0),
    (1000, "ctx-lh-unknown", 25, 5, 25, 64),
]


def freesurfer_lut(path, rows=FREESURFER_ROWS):
    lines = ["#$Id: FreeSurferColorLUT.txt,v 1.105 2015/07/29 18:25:57 greve Exp $", "",
             "#No. Label Name:                            R   G   B   A", ""]
    lines += [f"{i:<8d}{name:<40s}{r:<4d}{g:<4d}{b:<4d}{a}" for i, name, r, g, b, a in rows]
    path.write_text("\n".join(lines) + "\n")
    return path


def expect(table, rows, **columns):
    """``table`` holds exactly ``rows`` ((label, name, (r, g, b) in 0-1 or None), ...), in
    label order, with the ``columns`` given as {name: [values in the same order]}."""
    rows = sorted(rows, key=lambda row: row[0])
    assert table.index.name == "label" and table.index.dtype.kind in "iu"
    assert table.index.tolist() == [row[0] for row in rows]
    assert list(table.columns[:2]) == ["name", "color"]
    assert table["name"].tolist() == [row[1] for row in rows]
    for (label, _, color), got in zip(rows, table["color"].tolist()):
        if color is None:
            assert got is None, label
        else:
            assert isinstance(got, tuple) and len(got) == 3, (label, got)
            np.testing.assert_allclose(got, color, rtol=0, atol=1e-12, err_msg=str(label))
    for column, values in columns.items():
        got = table[column].tolist()
        if all(isinstance(v, float) for v in values):
            np.testing.assert_allclose(got, values, rtol=0, atol=1e-12, err_msg=column)
        else:
            assert got == values, column


# -- FreeSurfer ---------------------------------------------------------------------------------
def test_freesurfer_color_table(tmp_path):
    path = freesurfer_lut(tmp_path / "FreeSurferColorLUT.txt")
    table = vtksvdag.read_label_table(path)
    expect(table, [(i, name, (r / 255, g / 255, b / 255)) for i, name, r, g, b, _ in FREESURFER_ROWS],
           # FreeSurfer's A is a transparency: 0 is opaque.
           alpha=[1 - a / 255 for *_, a in FREESURFER_ROWS])
    assert table.attrs == {"source": str(path), "format": "freesurfer"}
    assert table.loc[17, "name"] == "Left-Hippocampus"
    # Tabs and the A column left out (as some tools write them); forcing the format.
    (tmp_path / "short.lut").write_text("# index name R G B\n7\tThalamus\t0\t118\t14\n")
    short = vtksvdag.read_label_table(tmp_path / "short.lut", format="freesurfer")
    expect(short, [(7, "Thalamus", (0, 118 / 255, 14 / 255))])
    assert "alpha" not in short.columns


# -- ITK-SNAP -----------------------------------------------------------------------------------
ITKSNAP_HEADER = """################################################
# ITK-SnAP Label Description File
# File format:
# IDX   -R-  -G-  -B-  -A--  VIS MSH  LABEL
# Fields:
#    IDX:   Zero-based index
#    -R-:   Red color component (0..255)
#    -G-:   Green color component (0..255)
#    -B-:   Blue color component (0..255)
#    -A-:   Label transparency (0.00 .. 1.00)
#    VIS:   Label visibility (0 or 1)
#    IDX:   Label mesh visibility (0 or 1)
#  LABEL:   Label description
################################################
"""


def test_itksnap_label_description(tmp_path):
    path = tmp_path / "labels.txt"
    path.write_text(ITKSNAP_HEADER + """\
    0     0    0    0        0  0  0    "Clear Label"
    1   255    0    0        1  1  1    "Left hippocampus (CA1)"
    2     0  255    0     0.35  1  0    "Label 2"
   12    10   20  230        1  0  1    "White matter"
""")
    table = vtksvdag.read_label_table(path)
    assert table.attrs["format"] == "itksnap"
    expect(table, [(0, "Clear Label", (0, 0, 0)), (1, "Left hippocampus (CA1)", (1, 0, 0)),
                   (2, "Label 2", (0, 1, 0)), (12, "White matter", (10 / 255, 20 / 255, 230 / 255))],
           alpha=[0.0, 1.0, 0.35, 1.0], visible=[False, True, True, False],
           mesh_visible=[False, True, False, True])


# -- 3D Slicer .seg.nrrd (written by pynrrd) ----------------------------------------------------
def slicer_segment(n, name, color, label, layer=0, extent="0 5 0 6 0 7", **extra):
    fields = {f"Segment{n}_Color": " ".join(f"{c:g}" for c in color),
              f"Segment{n}_ColorAutoGenerated": "0",
              f"Segment{n}_Extent": extent,
              f"Segment{n}_ID": f"Segment_{n + 1}",
              f"Segment{n}_LabelValue": str(label),
              f"Segment{n}_Layer": str(layer),
              f"Segment{n}_Name": name,
              f"Segment{n}_NameAutoGenerated": "0",
              f"Segment{n}_Tags": "Segmentation.Status:inprogress|TerminologyEntry:Segmentation "
                                  "category and type - 3D Slicer General Anatomy list~SCT^85756007^"
                                  "Tissue~SCT^85756007^Tissue~^^~Anatomic codes - DICOM master list~^^~^^|"}
    fields.update({f"Segment{n}_{k}": v for k, v in extra.items()})
    return fields


def slicer_header(*segments):
    header = {"space": "left-posterior-superior",
              "space directions": np.diag([0.5, 0.5, 1.5]), "space origin": np.array([-10.0, 5.0, 2.0]),
              "Segmentation_MasterRepresentation": "Binary labelmap",
              "Segmentation_ContainedRepresentationNames": "Binary labelmap|Closed surface|",
              "Segmentation_ReferenceImageExtentOffset": "0 0 0"}
    for segment in segments:
        header.update(segment)
    return header


def slicer_volume():
    """[x, y, z] uint8 labels 1, 2 and 5 of three segments (5 has no voxels: Slicer keeps empty
    segments in the header)."""
    data = np.zeros((6, 7, 8), np.uint8)
    data[1:3, 1:4, 1:5] = 1
    data[3:6, 2:6, 3:8] = 2
    return data


SLICER_SEGMENTS = [(0, "Left hippocampus", (0.862745, 0.847059, 0.0784314), 1),
                   (1, "tumor", (0.5, 0.68, 0.5), 2),
                   (2, "empty", (0.1, 0.2, 0.3), 5)]


def write_seg_nrrd(path, segments=SLICER_SEGMENTS, data=None):
    header = slicer_header(*(slicer_segment(*s) for s in segments))
    nrrd.write(str(path), slicer_volume() if data is None else data, header)
    return path


def test_seg_nrrd_header(tmp_path):
    path = write_seg_nrrd(tmp_path / "brain.seg.nrrd")
    table = vtksvdag.read_label_table(path)
    assert table.attrs["format"] == "seg.nrrd"
    expect(table, [(label, name, color) for _, name, color, label in SLICER_SEGMENTS],
           layer=[0, 0, 0], segment_id=["Segment_1", "Segment_2", "Segment_3"],
           extent=[(0, 5, 0, 6, 0, 7)] * 3, color_auto_generated=[False] * 3,
           name_auto_generated=[False] * 3)
    assert table.loc[1, "tags"].startswith("Segmentation.Status:inprogress|TerminologyEntry:")

    # Only the header is read: the table comes out of a file whose voxels are cut off.
    raw = path.read_bytes()
    cut = tmp_path / "cut.seg.nrrd"
    cut.write_bytes(raw[: raw.index(b"\n\n") + 2] + b"\x1f\x8b\x08")
    pd.testing.assert_frame_equal(vtksvdag.read_label_table(cut), table)
    with pytest.raises((OSError, ValueError)):
        vtksvdag.read(cut)


def test_seg_nrrd_layers_of_a_4d_file(tmp_path):
    # Overlapping segments: two layers along the first axis, label 1 in both.
    data = np.zeros((2, 6, 7, 8), np.uint8)
    data[0, 1:3] = 1
    data[0, 4:6] = 2
    data[1, 2:5] = 1
    header = slicer_header(slicer_segment(0, "liver", (0.8, 0.4, 0.3), 1, layer=0),
                           slicer_segment(1, "vessels", (0.0, 0.2, 1.0), 2, layer=0),
                           slicer_segment(2, "tumor", (0.9, 0.9, 0.1), 1, layer=1))
    header["kinds"] = ["list", "domain", "domain", "domain"]
    header["space directions"] = np.vstack([[np.nan] * 3, np.diag([0.5, 0.5, 1.5])])
    path = tmp_path / "layers.seg.nrrd"
    nrrd.write(str(path), data, header)
    table = vtksvdag.read_label_table(path)
    assert list(table.index.names) == ["layer", "label"]
    assert table.index.tolist() == [(0, 1), (0, 2), (1, 1)]
    assert table["name"].tolist() == ["liver", "vessels", "tumor"]
    np.testing.assert_allclose(table.loc[(1, 1), "color"], (0.9, 0.9, 0.1))
    one = vtksvdag.read_label_table(path, layer=1)
    expect(one, [(1, "tumor", (0.9, 0.9, 0.1))], layer=[1])
    with pytest.raises(ValueError, match=r"layer must be an integer in 0\.\.1, got 2"):
        vtksvdag.read_label_table(path, layer=2)
    # The layered table cannot be joined with a 3D volume's labels: the message says what to do.
    volume = vtksvdag.from_numpy(data[0])
    with pytest.raises(ValueError, match=r"indexed by \['layer', 'label'\].*layer="):
        volume.label_table(table)
    assert volume.label_table(one).loc[1, "name"] == "tumor"


def test_seg_nrrd_before_layers(tmp_path):
    # Files written before Slicer had layers: no LabelValue or Layer; one segment per layer of
    # a 4D file, each of value 1 (Slicer's reading of them).
    header = {"kinds": ["list", "domain", "domain", "domain"]}
    for n, (name, color) in enumerate((("bone", "1 1 0.8"), ("skin", "0.9 0.7 0.6"))):
        header[f"Segment{n}_Name"] = name
        header[f"Segment{n}_Color"] = color
        header[f"Segment{n}_ID"] = name
    path = tmp_path / "old.seg.nrrd"
    nrrd.write(str(path), np.zeros((2, 3, 3, 3), np.uint8), header)
    table = vtksvdag.read_label_table(path)
    assert table.index.tolist() == [(0, 1), (1, 1)]
    assert table["name"].tolist() == ["bone", "skin"]
    np.testing.assert_allclose(table.loc[(1, 1), "color"], (0.9, 0.7, 0.6))


def test_read_picks_up_seg_nrrd_metadata(tmp_path):
    path = write_seg_nrrd(tmp_path / "brain.seg.nrrd")
    volume = vtksvdag.read(path)
    assert volume.labels.tolist() == [1, 2]
    pd.testing.assert_frame_equal(volume.label_metadata, vtksvdag.read_label_table(path))
    # It travels with a pickled volume; a plain NRRD has none.
    assert pickle.loads(pickle.dumps(volume)).label_metadata.loc[2, "name"] == "tumor"
    nrrd.write(str(tmp_path / "plain.nrrd"), slicer_volume())
    assert vtksvdag.read(tmp_path / "plain.nrrd").label_metadata is None
    assert vtksvdag.from_numpy(slicer_volume()).label_metadata is None
    # Malformed metadata: the volume is read, the table left out with a warning saying why.
    bad = tmp_path / "bad.seg.nrrd"
    write_seg_nrrd(bad, [(0, "a", (0.5, 0.5, 0.5), 1), (1, "b", (0.5, 0.5, 0.5), 1)])
    with pytest.warns(UserWarning, match=r"label metadata is left out: .*bad\.seg\.nrrd: label 1 "
                                         r"is given twice \(Segment0_LabelValue and Segment1_LabelValue\)"):
        volume = vtksvdag.read(bad)
    assert volume.label_metadata is None and volume.labels.tolist() == [1, 2]


# -- OME-Zarr image-label -----------------------------------------------------------------------
IMAGE_LABEL = {
    "version": "0.4",
    "colors": [{"label-value": 3, "rgba": [255, 0, 0, 255]},
               {"label-value": 7, "rgba": [0, 128, 255, 128]},
               {"label-value": 9, "rgba": [10, 20, 30, 0]}],
    "properties": [{"label-value": 3, "name": "nucleus", "area (pixels)": 27, "class": "organelle"},
                   {"label-value": 7, "class": "membrane"},
                   {"label-value": 11, "name": "unseen", "class": "organelle"}],
    "source": {"image": "../../"},
}
OME_EXPECTED = [(3, "nucleus", (1, 0, 0)), (7, None, (0, 128 / 255, 1)),
                (9, None, (10 / 255, 20 / 255, 30 / 255)), (11, "unseen", None)]


def ome_labels_zyx():
    data = np.zeros((8, 9, 10), np.uint16)
    data[1:4, 2:5, 3:6] = 3
    data[5:7, 5:8, 5:9] = 7
    data[0, 0, 0] = 9
    return data


def multiscale(version):
    return {"version": version, "name": "cells",
            "axes": [{"name": a, "type": "space", "unit": "micrometer"} for a in "zyx"],
            "datasets": [{"path": "0", "coordinateTransformations": [
                {"type": "scale", "scale": [2.0, 0.5, 0.5]}]}]}


def check_ome_table(table):
    expect(table, OME_EXPECTED, alpha=[1.0, 128 / 255, 0.0, np.nan])
    assert table.loc[3, "area (pixels)"] == 27 and np.isnan(table.loc[7, "area (pixels)"])
    assert table["class"].tolist() == ["organelle", "membrane", None, "organelle"]
    assert table.attrs["format"] == "ome-zarr"


def test_ome_zarr_written_by_zarr_python(tmp_path):
    zarr = pytest.importorskip("zarr")
    # An image with a labels group holding one label image, as ome-zarr's writer lays it out.
    root = zarr.open_group(str(tmp_path / "image.zarr"), mode="w")
    labels = root.create_group("labels")
    labels.attrs["labels"] = ["cells"]
    cells = labels.create_group("cells")
    cells.create_dataset("0", data=ome_labels_zyx(), chunks=(4, 4, 4))
    cells.attrs["multiscales"] = [multiscale("0.4")]
    cells.attrs["image-label"] = IMAGE_LABEL
    where = tmp_path / "image.zarr" / "labels" / "cells"
    check_ome_table(vtksvdag.read_label_table(where))
    check_ome_table(vtksvdag.read_label_table(where / ".zattrs"))
    volume = vtksvdag.read(where)
    assert volume.labels.tolist() == [3, 7, 9]
    check_ome_table(volume.label_metadata)
    check_ome_table(vtksvdag.read(tmp_path / "image.zarr", dataset="labels/cells").label_metadata)
    # The labels group itself and the image are no label images.
    with pytest.raises(ValueError, match=r"an OME-Zarr labels group \(label images cells\)"):
        vtksvdag.read_label_table(tmp_path / "image.zarr" / "labels")
    with pytest.raises(ValueError, match="no OME-Zarr image-label metadata"):
        vtksvdag.read_label_table(tmp_path / "image.zarr")


def test_ome_zarr_0_5_array_written_by_tensorstore(tmp_path):
    ts = pytest.importorskip("tensorstore")
    group = tmp_path / "cells.zarr"
    data = ome_labels_zyx()
    store = ts.open({"driver": "zarr3", "kvstore": {"driver": "file", "path": str(group / "0")},
                     "metadata": {"shape": list(data.shape), "data_type": "uint16",
                                  "chunk_grid": {"name": "regular",
                                                 "configuration": {"chunk_shape": [4, 4, 4]}}}},
                    create=True).result()
    store.write(data).result()
    # OME-Zarr 0.5: the group's zarr.json, everything under "ome" (tensorstore writes arrays only).
    label = dict(IMAGE_LABEL, version="0.5")
    (group / "zarr.json").write_text(json.dumps({
        "zarr_format": 3, "node_type": "group",
        "attributes": {"ome": {"version": "0.5", "multiscales": [multiscale("0.5")],
                               "image-label": label}}}))
    check_ome_table(vtksvdag.read_label_table(group))
    check_ome_table(vtksvdag.read_label_table(group / "zarr.json"))
    volume = vtksvdag.read(group)
    np.testing.assert_array_equal(volume.to_numpy("zyx"), data)
    check_ome_table(volume.label_metadata)


# -- neuroglancer segment properties ------------------------------------------------------------
SEGMENT_PROPERTIES = {
    "@type": "neuroglancer_segment_properties",
    "inline": {
        "ids": ["5", "17", "18446744073709551557"],
        "properties": [
            {"id": "label", "type": "label", "values": ["axon 5", "soma 17", "glia"]},
            {"id": "description", "type": "description", "values": ["", "pyramidal", "astrocyte"]},
            {"id": "cell_type", "type": "string", "values": ["axon", "neuron", "glia"]},
            {"id": "synapses", "type": "number", "data_type": "int32", "values": [4, 120, 0]},
            {"id": "size_um3", "type": "number", "data_type": "float32", "values": [0.5, 1.25, 2.0]},
            {"id": "tags", "type": "tags", "tags": ["proofread", "excitatory", "partial"],
             "tag_descriptions": ["Proofread", "Excitatory", "Cut at the boundary"],
             "values": [[0, 2], [0, 1], []]},
        ],
    },
}


def test_neuroglancer_segment_properties(tmp_path):
    props = tmp_path / "segment_properties"
    props.mkdir()
    (props / "info").write_text(json.dumps(SEGMENT_PROPERTIES))
    expected_rows = [(5, "axon 5", None), (17, "soma 17", None), (2**64 - 59, "glia", None)]
    columns = dict(description=["", "pyramidal", "astrocyte"], cell_type=["axon", "neuron", "glia"],
                   synapses=[4, 120, 0], size_um3=[0.5, 1.25, 2.0],
                   tags=[("proofread", "partial"), ("proofread", "excitatory"), ()])
    for where in (props / "info", props):
        table = vtksvdag.read_label_table(where)
        expect(table, expected_rows, **columns)
        assert table.attrs["format"] == "neuroglancer"
        # An id beyond int64: the index is uint64, exactly.
        assert table.index.dtype == np.uint64 and table.index[-1] == 2**64 - 59
        assert table["synapses"].dtype == np.int32 and table["size_um3"].dtype == np.float32
    # A precomputed volume's info names its segment properties directory.
    (tmp_path / "info").write_text(json.dumps({
        "@type": "neuroglancer_multiscale_volume", "type": "segmentation", "data_type": "uint64",
        "num_channels": 1, "segment_properties": "segment_properties",
        "scales": [{"key": "8_8_8", "size": [4, 4, 4], "resolution": [8, 8, 8],
                    "voxel_offset": [0, 0, 0], "encoding": "raw", "chunk_sizes": [[4, 4, 4]]}]}))
    expect(vtksvdag.read_label_table(tmp_path), expected_rows, **columns)


# -- CSV ----------------------------------------------------------------------------------------
def test_csv_tables(tmp_path):
    hexes = tmp_path / "hex.csv"
    hexes.write_text("label,name,color,type\n3,Cortex,#FF8000,gray\n1,White matter,,white\n"
                     "7,,#00ff0080,csf\n")
    table = vtksvdag.read_label_table(hexes)
    assert table.attrs["format"] == "csv"
    expect(table, [(1, "White matter", None), (3, "Cortex", (1, 128 / 255, 0)), (7, None, (0, 1, 0))],
           alpha=[np.nan, np.nan, 128 / 255], type=["white", "gray", "csf"])
    ints = tmp_path / "ints.csv"
    ints.write_text("label,name,R,G,B\n1,a,255,0,0\n2,b,0,1,0\n")  # integers: 0-255
    expect(vtksvdag.read_label_table(ints), [(1, "a", (1, 0, 0)), (2, "b", (0, 1 / 255, 0))])
    floats = tmp_path / "floats.txt"
    floats.write_text("label, red, green, blue, alpha\n4, 1, 0.5, 0, 0.25\n6, , , , \n")  # floats: 0-1
    expect(vtksvdag.read_label_table(floats), [(4, None, (1, 0.5, 0)), (6, None, None)],
           alpha=[0.25, np.nan])


# -- errors -------------------------------------------------------------------------------------
def lut(*rows):
    return "#No. Label Name: R G B A\n" + "\n".join(rows) + "\n"


BAD_FILES = [
    ("fs.txt", lut("0 Unknown 0 0 0 0", "17 Left-Hippocampus 220 216 20 0", "17 Right 1 2 3 0"), None,
     r"fs\.txt: label 17 is given twice \(line 3 and line 4\)"),
    ("fs.txt", lut("17 Left-Hippocampus 256 216 20 0"), None,
     r"fs\.txt, line 2: R G B component must be an integer in 0\.\.255, got 256"),
    ("fs.txt", lut("17 Left-Hippocampus 0.5 0.2 0.1 0"), "freesurfer",
     r"fs\.txt, line 2: R G B component must be an integer in 0\.\.255, got '0\.5'"),
    ("fs.txt", lut("17 Left Hippocampus 220 216 20 0"), "freesurfer",
     r"fs\.txt, line 2: expected 'index name R G B A' \(the name without spaces\)"),
    ("snap.txt", ITKSNAP_HEADER + '    1   255    0    0     1.5  1  1    "Label 1"\n', None,
     r"snap\.txt, line 15: -A- \(the opacity\) must be a number in 0\.0\.\.1\.0, got '1\.5'"),
    ("snap.txt", ITKSNAP_HEADER + '    1   255    0    0     1  2  1    "Label 1"\n', None,
     r"snap\.txt, line 15: VIS must be an integer in 0\.\.1, got 2"),
    ("snap.txt", ITKSNAP_HEADER + '    1   255    0    0     1  1  1    Label 1\n', "itksnap",
     r"snap\.txt, line 15: expected 'IDX -R- -G- -B- -A-- VIS MSH \"LABEL\"'"),
    ("snap.txt", ITKSNAP_HEADER + '  1 1 1 1 1 1 1 "a"\n  1 2 2 2 1 1 1 "b"\n', None,
     r"snap\.txt: label 1 is given twice \(line 15 and line 16\)"),
    (".zattrs", {"image-label": {"colors": [{"label-value": 3, "rgba": [300, 0, 0, 255]}]}}, None,
     r"\.zattrs: image-label\.colors\[0\]\.rgba must be 4 integers in 0\.\.255, got \[300, 0, 0, 255\]"),
    (".zattrs", {"image-label": {"colors": [{"label-value": 3, "rgba": [1.0, 0, 0]}]}}, None,
     r"image-label\.colors\[0\]\.rgba must be 4 integers"),
    (".zattrs", {"image-label": {"colors": [{"label-value": 3, "rgba": [1, 0, 0, 1]},
                                            {"label-value": 3, "rgba": [0, 1, 0, 1]}]}}, None,
     r"label 3 is given twice \(image-label\.colors\[0\] and image-label\.colors\[1\]\)"),
    (".zattrs", {"image-label": {"properties": [{"label-value": 2.5, "name": "x"}]}}, None,
     r"image-label\.properties\[0\]\.label-value must be an integer, got 2\.5"),
    ("info", {"@type": "neuroglancer_segment_properties", "inline": {"ids": ["1", 2]}}, None,
     r"info: inline\.ids\[1\] must be a base-10 uint64 string, got 2"),
    ("info", {"@type": "neuroglancer_segment_properties",
              "inline": {"ids": ["5", "6", "5"], "properties": []}}, None,
     r"info: label 5 is given twice \(inline\.ids\[0\] and inline\.ids\[2\]\)"),
    ("info", {"@type": "neuroglancer_segment_properties",
              "inline": {"ids": ["1"], "properties": [{"id": "c", "type": "color", "values": ["red"]}]}},
     None, r"inline\.properties\[0\]\.type must be one of label, description, string, number, tags, "
           r"got 'color'"),
    ("info", {"@type": "neuroglancer_segment_properties",
              "inline": {"ids": ["1", "2"], "properties": [{"id": "label", "type": "label",
                                                            "values": ["a"]}]}},
     None, r"inline\.properties\[0\]\.values must be a list of 2 values"),
    ("info", {"@type": "neuroglancer_segment_properties",
              "inline": {"ids": ["1"], "properties": [{"id": "t", "type": "tags", "tags": ["a"],
                                                       "values": [[0, 1]]}]}},
     None, r"inline\.properties\[0\]\.values\[0\] must be a list of indices into "
           r"inline\.properties\[0\]\.tags \(0\.\.0\), got \[0, 1\]"),
    ("info", {"@type": "neuroglancer_segment_properties",
              "inline": {"ids": ["1"], "properties": [{"id": "n", "type": "number",
                                                       "data_type": "uint8", "values": [2.5]}]}},
     None, r"inline\.properties\[0\]\.values\[0\] must be an integer that fits uint8, got 2\.5"),
    ("t.csv", "label,name,color\n1,a,#ff00zz\n", None,
     r"t\.csv, data row 1 \(label 1\): the color must be '#rrggbb' or '#rrggbbaa', got '#ff00zz'"),
    ("t.csv", "label,r,g,b\n1,255,0,0\n2,0.5,0,0\n", None,
     r"t\.csv, data row 1 \(label 1\): r \(the columns hold floats, 0-1\) must be a number in "
     r"0\.0\.\.1\.0, got '255'"),
    ("t.csv", "label,r,g,b\n1,255,0,\n", None,
     r"t\.csv, data row 1 \(label 1\): r, g, b must all be given or all be empty"),
    ("t.csv", "label,name\n1,a\n1,b\n", None, r"in .*t\.csv\) has more than one row for labels \[1\]"),
    ("notes.txt", "hello world\n", None,
     r"notes\.txt: not a label table of a known format \(accepted: freesurfer, itksnap, seg\.nrrd, "
     r"ome-zarr, neuroglancer, csv; pass format= to force one\)"),
]


@pytest.mark.parametrize("name, content, format, match", BAD_FILES,
                         ids=[f"{n}-{i}" for i, (n, *_) in enumerate(BAD_FILES)])
def test_malformed_files_raise_value_error(tmp_path, name, content, format, match):
    path = tmp_path / name
    path.write_text(content if isinstance(content, str) else json.dumps(content))
    with pytest.raises(ValueError, match=match):
        vtksvdag.read_label_table(path, format=format)


def test_malformed_seg_nrrd(tmp_path):
    def header_error(segments, match):
        path = tmp_path / "bad.seg.nrrd"
        nrrd.write(str(path), slicer_volume(), slicer_header(*segments))
        with pytest.raises(ValueError, match=match):
            vtksvdag.read_label_table(path)

    header_error([slicer_segment(0, "a", (1.2, 0, 0), 1)],
                 r"bad\.seg\.nrrd: Segment0_Color must be a number in 0\.0\.\.1\.0, got '1\.2'")
    segment = slicer_segment(0, "a", (1, 0, 0), 1)
    segment["Segment0_Color"] = "1 0"
    header_error([segment], r"Segment0_Color must be 3 numbers in 0\.\.1, got '1 0'")
    header_error([slicer_segment(0, "a", (1, 0, 0), "one")],
                 r"Segment0_LabelValue must be an integer, got 'one'")
    header_error([slicer_segment(0, "a", (1, 0, 0), 1, layer=1)],
                 r"Segment0_Layer is 1, but the file has 1 layer \(dimension 3\)")
    header_error([slicer_segment(0, "a", (1, 0, 0), 1), slicer_segment(3, "b", (0, 1, 0), 1)],
                 r"label 1 is given twice \(Segment0_LabelValue and Segment3_LabelValue\)")
    nrrd.write(str(tmp_path / "plain.nrrd"), slicer_volume())
    with pytest.raises(ValueError, match=r"plain\.nrrd: a NRRD file without Segment<N>_ fields"):
        vtksvdag.read_label_table(tmp_path / "plain.nrrd")


def test_bad_arguments(tmp_path):
    path = freesurfer_lut(tmp_path / "lut.txt")
    with pytest.raises(ValueError, match=r"unknown label table format 'nifti'; the formats are "
                                         r"'freesurfer', 'itksnap', 'seg\.nrrd', 'ome-zarr', "
                                         r"'neuroglancer', 'csv'"):
        vtksvdag.read_label_table(path, format="nifti")
    assert FORMATS == ("freesurfer", "itksnap", "seg.nrrd", "ome-zarr", "neuroglancer", "csv")
    with pytest.raises(ValueError, match=r"layer=0 is only for \.seg\.nrrd files, not freesurfer"):
        vtksvdag.read_label_table(path, layer=0)
    with pytest.raises(FileNotFoundError):
        vtksvdag.read_label_table(tmp_path / "missing.txt")
    with pytest.raises(TypeError, match="path must be"):
        vtksvdag.read_label_table(17)
    # A LUT read as the wrong format fails, it does not give a table.
    with pytest.raises(ValueError, match=r"lut\.txt, line 5: expected 'IDX"):
        vtksvdag.read_label_table(path, format="itksnap")


# -- add_segmentation: colors and names from the table ------------------------------------------
ATLAS_LABELS = [2, 17, 18, 53, 77]  # 77: in the volume, not in the color table


def atlas():
    """[x, y, z] uint16 slabs of the ATLAS_LABELS side by side."""
    labels = np.zeros((44, 24, 24), np.uint16)
    for i, value in enumerate(ATLAS_LABELS):
        labels[2 + 8 * i: 8 + 8 * i, 2:22, 2:22] = value
    return labels


def label_color(actor, label):
    """The color the mapper's label properties hold for ``label``, or None."""
    rgb = [0.0] * 3
    return tuple(rgb) if actor.GetMapper().GetLabelProperties().GetColor(label, rgb) else None


def palette_color(actor, label):
    """The default color of a label the table does not color: the volume's distinct palette."""
    volume = actor.segmentation
    return tuple(volume.distinct_colors()[list(volume.labels).index(label)])


def test_add_segmentation_colors_and_queries_by_table(tmp_path, plotter):
    table = vtksvdag.read_label_table(freesurfer_lut(tmp_path / "FreeSurferColorLUT.txt"))
    lut_rgb = {i: (r / 255, g / 255, b / 255) for i, _, r, g, b, _ in FREESURFER_ROWS}
    import warnings

    with warnings.catch_warnings():
        # The table names labels the volume lacks (0, 54, 1000): expected of a color table.
        warnings.simplefilter("error")
        actor = vtksvdag.add_segmentation(plotter, atlas(), attributes=table, spp=1,
                                          query="name.str.contains('Hippocampus')")
    for label in (2, 17, 18, 53):
        np.testing.assert_allclose(label_color(actor, label), lut_rgb[label], rtol=0, atol=1e-12)
    assert label_color(actor, 77) == palette_color(actor, 77)  # no row: the default color
    # The query on names: label 77 has no name (NaN), which does not match.
    assert actor.visible_labels == [17, 53]
    assert actor.set_query("name == 'Left-Amygdala' or name.isna()") == [18, 77]
    assert actor.visible_labels == [18, 77]
    assert actor.label_table.loc[17, "name"] == "Left-Hippocampus"
    assert actor.label_table.loc[17, "voxel_count"] == 6 * 20 * 20
    # color_by recolors; without it again the table's colors come back.
    actor.set_color_by("voxel_count", cmap="viridis")
    assert label_color(actor, 17) != pytest.approx(lut_rgb[17])
    actor.set_color_by(None)
    np.testing.assert_allclose(label_color(actor, 17), lut_rgb[17], rtol=0, atol=1e-12)
    assert label_color(actor, 77) == palette_color(actor, 77)

    # colors= wins over the table; an explicit cmap recolors every label instead of it.
    red = vtksvdag.add_segmentation(plotter, atlas(), attributes=table, colors={17: "red"}, spp=1,
                                    name="red")
    assert label_color(red, 17) == (1.0, 0.0, 0.0)
    np.testing.assert_allclose(label_color(red, 53), lut_rgb[53], rtol=0, atol=1e-12)
    import matplotlib

    tab10 = vtksvdag.add_segmentation(plotter, atlas(), attributes=table, cmap="tab10", spp=1,
                                      name="tab10")
    for index, label in enumerate(ATLAS_LABELS):
        np.testing.assert_allclose(label_color(tab10, label), matplotlib.colormaps["tab10"](index)[:3])
    # A path works as the attributes too, and a DataFrame's color column of any pyvista color.
    by_path = vtksvdag.add_segmentation(plotter, atlas(), attributes=tmp_path / "FreeSurferColorLUT.txt",
                                        spp=1, name="path")
    np.testing.assert_allclose(label_color(by_path, 18), lut_rgb[18], rtol=0, atol=1e-12)
    own = pd.DataFrame({"label": [2, 18], "color": ["#0000ff", "gold"]})
    own_actor = vtksvdag.add_segmentation(plotter, atlas(), attributes=own, spp=1, name="own")
    assert label_color(own_actor, 2) == (0.0, 0.0, 1.0)
    np.testing.assert_allclose(label_color(own_actor, 18), (1.0, 215 / 255, 0.0))
    with pytest.raises(ValueError, match=r"color column's value for label 2 is not a color: 'nope'"):
        vtksvdag.add_segmentation(plotter, atlas(), attributes=own.assign(color=["nope", "red"]),
                                  spp=1, name="bad")


def test_add_segmentation_uses_the_volume_label_metadata(tmp_path, plotter):
    path = write_seg_nrrd(tmp_path / "brain.seg.nrrd")
    volume = vtksvdag.read(path)
    actor = vtksvdag.add_segmentation(plotter, volume, spp=1, query="name.str.contains('hippo')")
    for _, _, color, label in SLICER_SEGMENTS[:2]:
        np.testing.assert_allclose(label_color(actor, label), color, rtol=0, atol=1e-12)
    assert actor.visible_labels == [1]
    assert actor.label_table.loc[2, "name"] == "tumor"
    # From the path as well; explicit attributes replace the metadata.
    from_path = vtksvdag.add_segmentation(plotter, path, spp=1, name="path")
    np.testing.assert_allclose(label_color(from_path, 2), SLICER_SEGMENTS[1][2], rtol=0, atol=1e-12)
    other = vtksvdag.add_segmentation(plotter, volume, spp=1, name="other",
                                      attributes=pd.DataFrame({"label": [1], "kind": ["x"]}))
    assert label_color(other, 1) == palette_color(other, 1)
    assert "name" not in other.label_table.columns
