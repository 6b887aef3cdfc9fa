"""Label names and colors from the files users already have: :func:`read_label_table`.

Every reader returns the same shape of table (a ``pandas.DataFrame`` indexed by label value,
index name ``label``, with ``name`` and ``color`` columns first), so that the table can go
straight to ``add_segmentation(attributes=...)`` or :meth:`SegmentationVolume.label_table`.
:func:`vtksvdag.read` uses :func:`nrrd_label_metadata` and :func:`ome_label_metadata` to fill
``SegmentationVolume.label_metadata`` of ``.seg.nrrd`` files and OME-Zarr label images.

Errors are ValueErrors that name the file, the line or field, and what was expected: a table
that is silently wrong (a color scaled twice, a label that overwrote another) is worse than none.
"""
import json
import math
import numbers
import os
import re

import numpy as np

FREESURFER, ITKSNAP, SEG_NRRD, OME_ZARR, NEUROGLANCER, CSV = (
    "freesurfer", "itksnap", "seg.nrrd", "ome-zarr", "neuroglancer", "csv")
#: The names ``read_label_table(format=...)`` accepts.
FORMATS = (FREESURFER, ITKSNAP, SEG_NRRD, OME_ZARR, NEUROGLANCER, CSV)

# ITK-SNAP: IDX -R- -G- -B- -A-- VIS MSH "LABEL" (seven numbers, then the quoted description,
# which may hold spaces).
_ITKSNAP_LINE = re.compile(r'^\s*(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+(\S+)\s+"(.*)"\s*$')
_SEGMENT_FIELD = re.compile(r"^Segment(\d+)_(\w+)$")
_INT = re.compile(r"^[+-]?\d+$")


def read_label_table(path, format=None, *, layer=None):
    """Read label names, colors and other per-label metadata from a file.

    Parameters
    ----------
    path : str or os.PathLike
        A label table file, or a directory that holds one (an OME-Zarr label image, a
        neuroglancer precomputed volume or segment properties directory).
    format : str, optional
        Force a format instead of detecting it from the content (and extension):

        - ``"freesurfer"``: a FreeSurfer color table (``FreeSurferColorLUT.txt``): lines
          ``index name R G B A`` with 0-255 integers, ``#`` comment lines. FreeSurfer reads
          ``A`` as transparency, so ``alpha`` is ``1 - A / 255`` (``A`` may be left out).
        - ``"itksnap"``: an ITK-SNAP label description file: ``IDX -R- -G- -B- -A-- VIS MSH
          "LABEL"`` (0-255 colors, ``A`` an opacity in 0-1); columns ``alpha``, ``visible``,
          ``mesh_visible``.
        - ``"seg.nrrd"``: the header of a 3D Slicer segmentation (``.seg.nrrd``, read with
          pynrrd's header reader; the voxels are not read): ``Segment<N>_Name``,
          ``Segment<N>_Color`` (0-1), ``Segment<N>_LabelValue`` (1 when absent, as Slicer
          reads old files) and ``Segment<N>_Layer`` (N when absent); columns ``layer``,
          ``segment_id`` (``_ID``), ``tags``, ``extent`` and any other segment field in
          snake case.
        - ``"ome-zarr"``: the ``image-label`` metadata of an OME-Zarr label image (its
          ``.zattrs`` or ``zarr.json``): ``colors`` (``rgba`` 0-255; column ``alpha``) and
          ``properties`` (one column per key; a ``name`` key is the name).
        - ``"neuroglancer"``: neuroglancer segment properties (an ``info`` JSON file with
          ``"@type": "neuroglancer_segment_properties"``, or a precomputed volume whose
          ``info`` names its ``segment_properties``): the ``label`` property is the name,
          ``description``, ``string`` and ``number`` properties are columns named by their
          id, ``tags`` properties columns of tuples of tag names. Neuroglancer keeps no colors.
        - ``"csv"``: a table with a ``label`` column; ``name`` and ``color`` (``#rrggbb`` or
          ``#rrggbbaa``, the latter also giving ``alpha``) or ``r``, ``g``, ``b`` (``red``,
          ``green``, ``blue``; optional ``a``/``alpha``) columns: integers are 0-255, floats
          0-1. Other columns are kept as they are.
    layer : int, optional
        ``.seg.nrrd`` only: keep the segments of this layer. A file whose segments lie in
        several layers (a 4D segmentation with overlapping segments) otherwise gives a table
        indexed by (``layer``, ``label``), which cannot be joined with a 3D volume's labels.

    Returns
    -------
    pandas.DataFrame
        One row per label, sorted, indexed by the integer label value (index name ``label``;
        int64, or uint64 for ids beyond int64 as neuroglancer's may be), with columns
        ``name`` (str, or None where the file names none) and ``color`` (a tuple of 3 floats
        in 0-1, or None), then what else the file holds. ``table.attrs`` has ``"source"``
        (the file read) and ``"format"``: such a color table names labels in general, so
        joining it with a volume that lacks some of them does not warn.

    Raises
    ------
    FileNotFoundError
        ``path`` does not exist.
    ValueError
        The format is unknown (the message lists the accepted ones) or the file is not valid
        for it: a malformed line or field (named, with what was expected), a color out of
        range, a label value given twice.
    ImportError
        A ``.seg.nrrd`` file and pynrrd is not installed.

    Examples
    --------
    >>> import vtksvdag
    >>> with open("FreeSurferColorLUT.txt", "w") as f:
    ...     _ = f.write("0   Unknown           0   0   0   0\\n"
    ...                 "17  Left-Hippocampus  220 216 20  0\\n")
    >>> table = vtksvdag.read_label_table("FreeSurferColorLUT.txt")
    >>> table.loc[17, "name"]
    'Left-Hippocampus'
    >>> [round(c, 3) for c in table.loc[17, "color"]]
    [0.863, 0.847, 0.078]

    The table names and colors the labels of a segmentation:

    >>> actor = vtksvdag.add_segmentation(plotter, volume, attributes=table,
    ...                                   query="name.str.contains('Hippocampus')")  # doctest: +SKIP
    """
    try:
        path = os.fsdecode(path)
    except TypeError:
        raise TypeError(f"path must be a str, bytes or os.PathLike, not {type(path).__name__}") from None
    if not os.path.exists(path):
        raise FileNotFoundError(2, "No such file or directory", path)
    if format is None:
        format = detect_format(path)
    elif format not in FORMATS:
        raise ValueError(f"unknown label table format {format!r}; the formats are "
                         f"{', '.join(map(repr, FORMATS))}")
    if layer is not None and format != SEG_NRRD:
        raise ValueError(f"{path}: layer={layer!r} is only for .seg.nrrd files, not {format}")
    if format == SEG_NRRD:
        table = _read_seg_nrrd(path, layer)
    else:
        table = _READERS[format](path)
    table.attrs["source"] = path
    table.attrs["format"] = format
    return table


# -- detection ------------------------------------------------------------------------------
def detect_format(path):
    """The format of the label table at ``path`` (one of :data:`FORMATS`), from its content;
    ValueError naming the accepted formats when it is none of them."""
    unknown = (f"{path}: not a label table of a known format (accepted: "
               f"{', '.join(FORMATS)}; pass format= to force one)")
    if os.path.isdir(path):
        if any(os.path.isfile(os.path.join(path, f)) for f in (".zattrs", ".zgroup", "zarr.json")):
            return OME_ZARR
        if os.path.isfile(os.path.join(path, "info")):
            return NEUROGLANCER
        raise ValueError(f"{unknown}: the directory holds no .zattrs, .zgroup, zarr.json or info "
                         f"file")
    if os.path.basename(path) in (".zattrs", "zarr.json"):
        return OME_ZARR
    with open(path, "rb") as f:
        head = f.read(1 << 16)
    if head.startswith(b"NRRD"):
        return SEG_NRRD
    if head.lstrip().startswith(b"{"):
        document = _load_json(path)
        if document.get("@type") == "neuroglancer_segment_properties" or "segment_properties" in document:
            return NEUROGLANCER
        if _image_label(document) is not None or _ome_labels_list(document) is not None:
            return OME_ZARR
        raise ValueError(f"{unknown}: a JSON file with neither neuroglancer segment properties "
                         f"nor OME-Zarr image-label metadata")
    if path.lower().endswith((".csv", ".csv.gz")):
        return CSV
    text = head.decode("utf-8", errors="replace")
    for line in text.splitlines():
        line = line.strip()
        if not line or line.startswith("#"):
            continue
        if _ITKSNAP_LINE.match(line):
            return ITKSNAP
        fields = line.split()
        if len(fields) in (5, 6) and _INT.match(fields[0]) and all(_INT.match(f) for f in fields[2:]):
            return FREESURFER
        if "," in line:
            return CSV
        break
    raise ValueError(unknown)


# -- helpers --------------------------------------------------------------------------------
def _pandas():
    import pandas

    return pandas


def _table(rows, where, key_names=("label",)):
    """The DataFrame of ``rows`` (dicts with ``label`` and the columns, each with a ``_where``
    naming its line or field for errors), ``name`` and ``color`` first. A label value given
    twice is a ValueError naming both places."""
    pd = _pandas()
    seen = {}
    for row in rows:
        key = tuple(row[k] for k in key_names)
        if key in seen:
            what = "label" if len(key) == 1 else "/".join(key_names)
            value = key[0] if len(key) == 1 else key
            raise ValueError(f"{where}: {what} {value} is given twice ({seen[key]} and {row['_where']})")
        seen[key] = row["_where"]
    columns = ["name", "color"]
    for row in rows:
        columns += [c for c in row if c not in columns and c not in key_names and c != "_where"]
    data = {c: [row.get(c) for row in rows] for c in columns}
    index_arrays = [_label_index(values, where) for values in
                    ([row[k] for row in rows] for k in key_names)]
    if len(key_names) == 1:
        index = pd.Index(index_arrays[0], name=key_names[0])
    else:
        index = pd.MultiIndex.from_arrays(index_arrays, names=list(key_names))
    # object columns keep None (and tuples) as they are; numeric ones become numbers.
    table = pd.DataFrame({c: pd.Series(v, dtype=object) for c, v in data.items()},
                         columns=columns)
    table.index = index
    table = table.infer_objects()
    return table.sort_index(kind="stable")


def indexed_by_label(table, where):
    """``table`` indexed by its integer ``label`` column (or index), checked: ValueError for no
    labels, non-integer or duplicate ones; ``where`` ends the messages (" (in file)")."""
    pd = _pandas()
    attrs = dict(table.attrs)
    if "label" in table.columns:
        table = table.set_index("label")
    elif table.index.name != "label":
        if "label" in (table.index.names or ()):
            raise ValueError(
                f"the attribute table{where} is indexed by {list(table.index.names)}, not by label "
                f"alone (a .seg.nrrd with several layers: read_label_table(path, layer=...))")
        raise ValueError(
            f"the attribute table{where} needs a 'label' column (or an index named 'label') with "
            f"the label values; its columns are {list(map(str, table.columns))}")
    index = table.index
    if len(index) and index.dtype.kind not in "iu":
        # Whole floats are accepted (labels that passed through a float column); missing
        # labels, fractions and strings are not.
        values = index.to_numpy()
        whole = values.dtype.kind == "f" and bool(np.all(np.isfinite(values))) and bool(
            np.all(values == np.round(values)))
        if not whole:
            raise ValueError(f"the attribute table's labels{where} must be integers (no missing "
                             f"values), got {index.dtype} values such as {index[:3].tolist()}")
        table = table.copy()
        table.index = pd.Index(values.astype(np.int64), name="label")
        index = table.index
    if not index.is_unique:
        duplicates = sorted(set(index[index.duplicated()].tolist()))[:5]
        raise ValueError(f"the attribute table{where} has more than one row for labels {duplicates}")
    table.attrs = attrs
    return table


def _label_index(values, where):
    """Label values as int64, or uint64 when some exceed int64 (neuroglancer's uint64 ids)."""
    if not values:
        return np.empty(0, np.int64)
    low, high = min(values), max(values)
    if low >= -(2**63) and high < 2**63:
        return np.array(values, np.int64)
    if low >= 0 and high < 2**64:
        return np.array(values, np.uint64)
    raise ValueError(f"{where}: label values {low} .. {high} do not fit one 64-bit integer type")


def _bounds(low, high):
    """The range an error message names: ' in 0..255', ' >= 0' or ''."""
    if low is not None and high is not None:
        return f" in {low}..{high}"
    return f" >= {low}" if low is not None else (f" <= {high}" if high is not None else "")


def _integer(text, where, what, low=None, high=None):
    text = str(text).strip()
    if not _INT.match(text):
        raise ValueError(f"{where}: {what} must be an integer{_bounds(low, high)}, got {text!r}")
    value = int(text)
    if (low is not None and value < low) or (high is not None and value > high):
        raise ValueError(f"{where}: {what} must be an integer{_bounds(low, high)}, got {value}")
    return value


def _number(text, where, what, low=None, high=None):
    try:
        value = float(text)
    except (TypeError, ValueError):
        value = math.nan  # fails the check below, with the same message
    if not math.isfinite(value) or (low is not None and value < low) or (high is not None and value > high):
        raise ValueError(f"{where}: {what} must be a number{_bounds(low, high)}, got {text!r}")
    return value


def _rgb255(values, where, what="R G B"):
    """0-255 integer components as 0-1 floats."""
    return tuple(_integer(v, where, f"{what} component", 0, 255) / 255.0 for v in values)


def _lines(path):
    """(line number, stripped line) of the non-blank, non-comment lines of a text file."""
    try:
        with open(path, encoding="utf-8") as f:
            text = f.read()
    except UnicodeDecodeError:
        with open(path, encoding="latin-1") as f:  # old tables with accented names
            text = f.read()
    for number, line in enumerate(text.splitlines(), 1):
        line = line.strip()
        if line and not line.startswith("#"):
            yield number, line


def _load_json(path):
    try:
        with open(path, "rb") as f:
            document = json.loads(f.read())
    except (ValueError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: not valid JSON ({e})") from None
    if not isinstance(document, dict):
        raise ValueError(f"{path}: expected a JSON object, got {type(document).__name__}")
    return document


# -- FreeSurfer -----------------------------------------------------------------------------
def _read_freesurfer(path):
    rows = []
    for number, line in _lines(path):
        where = f"line {number}"
        fields = line.split()
        if len(fields) not in (5, 6):
            raise ValueError(f"{path}, {where}: expected 'index name R G B A' (the name without "
                             f"spaces), got {line!r}")
        row = {"label": _integer(fields[0], f"{path}, {where}", "the index"),
               "name": fields[1],
               "color": _rgb255(fields[2:5], f"{path}, {where}"), "_where": where}
        if len(fields) == 6:
            # FreeSurfer's 4th value is a transparency (0 in FreeSurferColorLUT.txt: opaque).
            row["alpha"] = 1.0 - _integer(fields[5], f"{path}, {where}", "A", 0, 255) / 255.0
        rows.append(row)
    return _table(rows, path)


# -- ITK-SNAP -------------------------------------------------------------------------------
def _read_itksnap(path):
    rows = []
    for number, line in _lines(path):
        where = f"{path}, line {number}"
        match = _ITKSNAP_LINE.match(line)
        if match is None:
            raise ValueError(f'{where}: expected \'IDX -R- -G- -B- -A-- VIS MSH "LABEL"\' (seven '
                             f"numbers and a quoted description), got {line!r}")
        idx, r, g, b, a, vis, msh, label = match.groups()
        rows.append({"label": _integer(idx, where, "IDX"), "name": label,
                     "color": _rgb255((r, g, b), where, "-R- -G- -B-"),
                     "alpha": _number(a, where, "-A- (the opacity)", 0.0, 1.0),
                     "visible": bool(_integer(vis, where, "VIS", 0, 1)),
                     "mesh_visible": bool(_integer(msh, where, "MSH", 0, 1)),
                     "_where": f"line {number}"})
    return _table(rows, path)


# -- 3D Slicer .seg.nrrd --------------------------------------------------------------------
def _snake(name):
    return re.sub(r"(?<=[a-z0-9])(?=[A-Z])", "_", name).lower()


def _nrrd_header(path):
    try:
        import nrrd
    except ImportError:
        raise ImportError("reading .seg.nrrd segment names and colors needs pynrrd "
                          "(pip install pynrrd)") from None
    try:
        return nrrd.read_header(path)
    except (nrrd.NRRDError, ValueError, UnicodeDecodeError) as e:
        raise ValueError(f"{path}: not a readable NRRD header ({e})") from None


def _segment_table(header, where, layer=None):
    """The label table of the ``Segment<N>_`` fields of a NRRD header (a dict of strings, as
    pynrrd reads it); None when there are none (a NRRD that is no Slicer segmentation)."""
    segments = {}
    for key, value in header.items():
        match = _SEGMENT_FIELD.match(str(key))
        if match:
            segments.setdefault(int(match.group(1)), {})[match.group(2)] = value
    if not segments:
        return None
    dimension = int(header.get("dimension", 3))
    sizes = header.get("sizes")
    layers = int(sizes[0]) if dimension == 4 and sizes is not None else 1
    rows = []
    for n in sorted(segments):
        fields = segments[n]
        field = f"Segment{n}_"

        def text(name, fields=fields):
            return None if name not in fields else str(fields[name]).strip()

        color = text("Color")
        if color is not None:
            parts = color.split()
            if len(parts) != 3:
                raise ValueError(f"{where}: {field}Color must be 3 numbers in 0..1, got {color!r}")
            color = tuple(_number(p, where, f"{field}Color", 0.0, 1.0) for p in parts)
        # Files written before Slicer kept layers have one segment per layer, of value 1.
        label = 1 if text("LabelValue") is None else _integer(text("LabelValue"), where, f"{field}LabelValue")
        segment_layer = n if text("Layer") is None else _integer(text("Layer"), where, f"{field}Layer", 0)
        if segment_layer >= layers:
            raise ValueError(f"{where}: {field}Layer is {segment_layer}, but the file has "
                             f"{layers} layer{'s' if layers != 1 else ''} (dimension {dimension})")
        row = {"layer": segment_layer, "label": label, "name": text("Name"), "color": color,
               "segment_id": text("ID"), "_where": f"{field}LabelValue"}
        for name, value in fields.items():
            if name in ("Name", "Color", "LabelValue", "Layer", "ID"):
                continue
            value = str(value).strip()
            if name == "Extent":
                parts = value.split()
                if len(parts) != 6:
                    raise ValueError(f"{where}: {field}Extent must be 6 integers, got {value!r}")
                value = tuple(_integer(p, where, f"{field}Extent") for p in parts)
            elif name.endswith("AutoGenerated"):
                value = bool(_integer(value, where, f"{field}{name}", 0, 1))
            row[_snake(name)] = value
        rows.append(row)
    several = len({row["layer"] for row in rows}) > 1
    if layer is not None:
        integral = isinstance(layer, (numbers.Integral, np.integer)) and not isinstance(layer, bool)
        if not integral or not 0 <= layer < layers:
            raise ValueError(f"{where}: layer must be an integer in 0..{layers - 1}, got {layer!r}")
        rows = [row for row in rows if row["layer"] == int(layer)]
        several = False
    return _table(rows, where, ("layer", "label") if several else ("label",))


def _read_seg_nrrd(path, layer=None):
    table = _segment_table(_nrrd_header(path), path, layer)
    if table is None:
        raise ValueError(f"{path}: a NRRD file without Segment<N>_ fields (not a 3D Slicer "
                         f"segmentation)")
    return table


def _has_segment_fields(path, limit=64 << 20):
    """Whether the header of the NRRD file at ``path`` (the text up to its first blank line)
    has a ``Segment<N>_`` field: plain NRRD files are then not parsed a second time."""
    head = b""
    with open(path, "rb") as f:
        while len(head) < limit:
            chunk = f.read(1 << 16)
            if not chunk:
                break
            head += chunk
            end = re.search(rb"\r?\n\r?\n", head)
            if end:
                head = head[:end.start()]
                break
    return re.search(rb"^Segment\d+_\w+:=", head, re.M) is not None


def nrrd_label_metadata(path):
    """``label_metadata`` of a NRRD file for :func:`vtksvdag.read`: its segment table, or None
    for a NRRD file without segments."""
    if not _has_segment_fields(path):
        return None
    table = _segment_table(_nrrd_header(path), path)
    if table is not None:
        table.attrs["source"] = path
        table.attrs["format"] = SEG_NRRD
    return table


# -- OME-Zarr image-label -------------------------------------------------------------------
def _attributes_of(document):
    """Group attributes of a ``.zattrs`` document, or of a ``zarr.json`` one (``attributes``)."""
    if "zarr_format" in document and isinstance(document.get("attributes"), dict):
        return document["attributes"]
    return document


def _image_label(document):
    """The ``image-label`` object of group attributes (OME-Zarr 0.4 at the top, 0.5 under
    ``ome``), or None."""
    attributes = _attributes_of(document)
    for holder in (attributes.get("ome"), attributes):
        if isinstance(holder, dict) and "image-label" in holder:
            return holder["image-label"]
    return None


def _ome_labels_list(document):
    attributes = _attributes_of(document)
    for holder in (attributes.get("ome"), attributes):
        if isinstance(holder, dict) and isinstance(holder.get("labels"), list):
            return holder["labels"]
    return None


def _ome_label_table(attributes, where):
    """The label table of OME-Zarr group ``attributes`` (a dict), or None when they hold no
    ``image-label``."""
    image_label = _image_label(attributes)
    if image_label is None:
        return None
    if not isinstance(image_label, dict):
        raise ValueError(f"{where}: image-label must be an object, got {image_label!r}")
    rows = {}

    def entries(key):
        listed = image_label.get(key, [])
        if not isinstance(listed, list):
            raise ValueError(f"{where}: image-label.{key} must be a list, got {listed!r}")
        seen = {}
        for i, entry in enumerate(listed):
            field = f"image-label.{key}[{i}]"
            if not isinstance(entry, dict) or "label-value" not in entry:
                raise ValueError(f"{where}: {field} must be an object with a 'label-value', got {entry!r}")
            value = entry["label-value"]
            if isinstance(value, bool) or not isinstance(value, int):
                raise ValueError(f"{where}: {field}.label-value must be an integer, got {value!r}")
            if value in seen:
                raise ValueError(f"{where}: label {value} is given twice ({seen[value]} and {field})")
            seen[value] = field
            row = rows.setdefault(value, {"label": value, "_where": field})
            yield field, entry, row

    for field, entry, row in entries("colors"):
        rgba = entry.get("rgba")
        if not isinstance(rgba, list) or len(rgba) != 4 or not all(
                isinstance(c, int) and not isinstance(c, bool) and 0 <= c <= 255 for c in rgba):
            raise ValueError(f"{where}: {field}.rgba must be 4 integers in 0..255, got {rgba!r}")
        row["color"] = tuple(c / 255.0 for c in rgba[:3])
        row["alpha"] = rgba[3] / 255.0
    for field, entry, row in entries("properties"):
        for key, value in entry.items():
            if key == "label-value":
                continue
            if key in ("color", "alpha"):
                raise ValueError(f"{where}: {field} has a property {key!r}, which would hide the "
                                 f"one read from image-label.colors")
            row[key] = value
    return _table(list(rows.values()), where)


def _read_ome_zarr(path):
    if os.path.isdir(path):
        candidates = [os.path.join(path, f) for f in ("zarr.json", ".zattrs")]
        files = [f for f in candidates if os.path.isfile(f)]
    else:
        files = [path]
    for file in files:
        document = _load_json(file)
        table = _ome_label_table(document, file)
        if table is not None:
            return table
        labels = _ome_labels_list(document)
        if labels is not None:
            raise ValueError(f"{file}: an OME-Zarr labels group (label images "
                             f"{', '.join(map(str, labels))}); read one of those label images")
    raise ValueError(f"{path}: no OME-Zarr image-label metadata (expected an 'image-label' object "
                     f"in the group attributes: .zattrs, or zarr.json's 'attributes')")


def ome_label_metadata(attributes, where):
    """``label_metadata`` of an OME-Zarr label image for :func:`vtksvdag.read`: the table of
    its group ``attributes``, or None for an image without ``image-label``."""
    table = _ome_label_table(attributes, where)
    if table is not None:
        table.attrs["source"] = where
        table.attrs["format"] = OME_ZARR
    return table


# -- neuroglancer segment properties --------------------------------------------------------
_NUMBER_TYPES = ("uint8", "int8", "uint16", "int16", "uint32", "int32", "float32")


def _read_neuroglancer(path):
    file = os.path.join(path, "info") if os.path.isdir(path) else path
    document = _load_json(file)
    if document.get("@type") != "neuroglancer_segment_properties":
        # A precomputed volume's info points at its properties directory.
        relative = document.get("segment_properties")
        if not isinstance(relative, str):
            raise ValueError(f"{file}: expected \"@type\": \"neuroglancer_segment_properties\" (or "
                             f"a precomputed info with a \"segment_properties\" directory), got "
                             f"@type {document.get('@type')!r}")
        file = os.path.join(os.path.dirname(file), relative, "info")
        if not os.path.isfile(file):
            raise FileNotFoundError(2, "No such file or directory (the segment_properties info)", file)
        document = _load_json(file)
        if document.get("@type") != "neuroglancer_segment_properties":
            raise ValueError(f"{file}: expected \"@type\": \"neuroglancer_segment_properties\", "
                             f"got {document.get('@type')!r}")
    inline = document.get("inline")
    if not isinstance(inline, dict):
        raise ValueError(f"{file}: expected an \"inline\" object with \"ids\" and \"properties\"")
    ids = inline.get("ids")
    if not isinstance(ids, list):
        raise ValueError(f"{file}: inline.ids must be a list of segment ids (strings)")
    rows = []
    for i, text in enumerate(ids):
        field = f"inline.ids[{i}]"
        if not isinstance(text, str) or not text.isdigit():
            raise ValueError(f"{file}: {field} must be a base-10 uint64 string, got {text!r}")
        rows.append({"label": _integer(text, f"{file}: {field}", "a segment id", 0, 2**64 - 1),
                     "_where": field})
    properties = inline.get("properties", [])
    if not isinstance(properties, list):
        raise ValueError(f"{file}: inline.properties must be a list")
    kinds = ("label", "description", "string", "number", "tags")
    for p, prop in enumerate(properties):
        field = f"inline.properties[{p}]"
        if not isinstance(prop, dict) or not isinstance(prop.get("id"), str):
            raise ValueError(f"{file}: {field} must be an object with a string 'id'")
        kind, values = prop.get("type"), prop.get("values")
        if kind not in kinds:
            raise ValueError(f"{file}: {field}.type must be one of {', '.join(kinds)}, got {kind!r}")
        if not isinstance(values, list) or len(values) != len(rows):
            raise ValueError(f"{file}: {field}.values must be a list of {len(rows)} values (one "
                             f"per id), got {values!r:.80}")
        column = "name" if kind == "label" else prop["id"]
        if any(column in row for row in rows[:1]) or column in ("label", "color"):
            raise ValueError(f"{file}: {field} (id {prop['id']!r}) gives column {column!r} twice")
        if kind == "tags":
            tags = prop.get("tags")
            if not isinstance(tags, list) or not all(isinstance(t, str) for t in tags):
                raise ValueError(f"{file}: {field}.tags must be a list of tag names")
        for i, (row, value) in enumerate(zip(rows, values)):
            where = f"{field}.values[{i}]"
            if kind in ("label", "description", "string"):
                if not isinstance(value, str):
                    raise ValueError(f"{file}: {where} must be a string, got {value!r}")
            elif kind == "number":
                if prop.get("data_type") not in _NUMBER_TYPES:
                    raise ValueError(f"{file}: {field}.data_type must be one of "
                                     f"{', '.join(_NUMBER_TYPES)}, got {prop.get('data_type')!r}")
                dtype = np.dtype(prop["data_type"])
                if isinstance(value, bool) or not isinstance(value, (int, float)):
                    raise ValueError(f"{file}: {where} must be a number, got {value!r}")
                # The column is of data_type: a value it cannot hold would change silently.
                if dtype.kind in "iu" and not (isinstance(value, int) and np.iinfo(dtype).min
                                               <= value <= np.iinfo(dtype).max):
                    raise ValueError(f"{file}: {where} must be an integer that fits "
                                     f"{prop['data_type']}, got {value!r}")
            else:
                if not isinstance(value, list) or not all(
                        isinstance(t, int) and not isinstance(t, bool) and 0 <= t < len(tags) for t in value):
                    raise ValueError(f"{file}: {where} must be a list of indices into "
                                     f"{field}.tags (0..{len(tags) - 1}), got {value!r}")
                value = tuple(tags[t] for t in value)
            row[column] = value
    table = _table(rows, file)
    for prop in properties:
        if prop["type"] == "number":
            table[prop["id"]] = table[prop["id"]].astype(prop["data_type"])
    return table


# -- CSV ------------------------------------------------------------------------------------
def _hex_color(text, where):
    text = text.strip()
    if not re.fullmatch(r"#(?:[0-9a-fA-F]{6}|[0-9a-fA-F]{8})", text):
        raise ValueError(f"{where}: the color must be '#rrggbb' or '#rrggbbaa', got {text!r}")
    values = [int(text[i:i + 2], 16) / 255.0 for i in range(1, len(text), 2)]
    return tuple(values[:3]), (values[3] if len(values) == 4 else None)


def _read_csv(path):
    pd = _pandas()
    try:
        table = pd.read_csv(path, skipinitialspace=True)
        # The same cells as text: whether a color component is written as an integer (0-255)
        # or a float (0-1) is in the text, not in the type pandas infers (an empty cell makes
        # an integer column float).
        text = pd.read_csv(path, skipinitialspace=True, dtype=str, keep_default_na=False)
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as error:
        raise ValueError(f"{path} is not a readable CSV file: {error}") from None
    table = indexed_by_label(table, f" (in {path})")

    def where(i):
        return f"{path}, data row {i + 1} (label {table.index[i]})"

    lower = {str(c).lower(): c for c in table.columns}
    channels = next((names for names in (("r", "g", "b"), ("red", "green", "blue"))
                     if all(n in lower for n in names)), None)
    colors, alphas = [None] * len(table), [None] * len(table)
    if "color" in table.columns:
        if channels is not None:
            raise ValueError(f"{path}: both a 'color' column and {'/'.join(channels)} columns")
        for i, value in enumerate(text["color"].tolist()):
            if value.strip():
                colors[i], alphas[i] = _hex_color(value, where(i))
        table = table.drop(columns="color")
    elif channels is not None:
        names = [lower[n] for n in channels]
        names += [lower[n] for n in ("a", "alpha") if n in lower][:1]
        cells = [[c.strip() for c in text[name].tolist()] for name in names]

        def integers(columns):
            # One scale for R, G and B of the whole table (and one for alpha): a "1" beside
            # "0.5" is 1.0, not 1/255.
            return all(_INT.match(c) for column in columns for c in column if c)

        scales = [integers(cells[:3])] * 3 + [integers(cells[3:])] * (len(names) - 3)
        for i in range(len(table)):
            row = [column[i] for column in cells]
            if not any(row):
                continue
            if not all(row):
                raise ValueError(f"{where(i)}: {', '.join(names)} must all be given or all be "
                                 f"empty, got {row}")
            values = []
            for name, cell, integer in zip(names, row, scales):
                if integer:
                    values.append(_integer(cell, where(i), f"{name} (the column holds integers, "
                                                         f"0-255)", 0, 255) / 255.0)
                else:
                    values.append(_number(cell, where(i), f"{name} (the columns hold floats, "
                                                        f"0-1)", 0.0, 1.0))
            colors[i] = tuple(values[:3])
            alphas[i] = values[3] if len(values) == 4 else None
        table = table.drop(columns=names)
    if any(a is not None for a in alphas):
        if "alpha" in table.columns:
            raise ValueError(f"{path}: an 'alpha' column and an alpha in the colors")
        table.insert(0, "alpha", [np.nan if a is None else a for a in alphas])
    names = table.pop("name") if "name" in table.columns else pd.Series(None, index=table.index,
                                                                          dtype=object)
    table.insert(0, "name", names.astype(object).where(names.notna(), None))
    table.insert(1, "color", pd.Series(colors, index=table.index, dtype=object))
    return table.sort_index(kind="stable")


_READERS = {FREESURFER: _read_freesurfer, ITKSNAP: _read_itksnap, OME_ZARR: _read_ome_zarr,
            NEUROGLANCER: _read_neuroglancer, CSV: _read_csv}
