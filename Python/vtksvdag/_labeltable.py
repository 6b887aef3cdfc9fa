"""The per-label table of :meth:`SegmentationVolume.label_table` (pandas), and its attribute join."""
import os
import warnings

import numpy as np

_COLUMNS = ("voxel_count", "volume", "xmin", "xmax", "ymin", "ymax", "zmin", "zmax",
            "centroid_i", "centroid_j", "centroid_k", "centroid_x", "centroid_y", "centroid_z",
            "surface_voxels")


def label_table(volume, centroids, surface, attributes=None):
    """Build the DataFrame from the volume's label table and the C++ statistics.

    ``centroids`` is the (n, 3) mean voxel index of each label, ``surface`` the surface voxel
    counts, both in the order of ``volume.labels``.
    """
    import pandas as pd

    labels = volume.labels
    counts = volume.label_voxel_counts
    bounds = volume.label_bounds
    spacing = np.asarray(volume.spacing, float)
    # World position of a continuous index: origin + direction @ (spacing * index).
    world = (np.asarray(volume.origin, float)[None, :]
             + (centroids * spacing[None, :]) @ volume.direction.T) if len(labels) else np.empty((0, 3))
    voxel_volume = float(np.prod(spacing) * abs(np.linalg.det(volume.direction)))
    data = {
        "voxel_count": counts.astype(np.int64),
        "volume": counts * voxel_volume,
    }
    for i, name in enumerate(("xmin", "xmax", "ymin", "ymax", "zmin", "zmax")):
        data[name] = bounds[:, i].astype(np.int64)
    for i, axis in enumerate("ijk"):
        data[f"centroid_{axis}"] = centroids[:, i].astype(float)
    for i, axis in enumerate("xyz"):
        data[f"centroid_{axis}"] = world[:, i]
    data["surface_voxels"] = np.asarray(surface, dtype=np.int64)
    table = pd.DataFrame(data, index=pd.Index(np.asarray(labels), name="label"), columns=list(_COLUMNS))
    if attributes is None:
        return table
    return _join_attributes(table, attributes, volume.dtype)


def read_attributes(attributes):
    """``attributes`` (a DataFrame with a ``label`` column or index, or a CSV path) as a
    DataFrame indexed by integer label value (index name ``label``).

    Raises ValueError for a table without labels, non-integer or duplicate labels, and
    FileNotFoundError for a missing CSV file.
    """
    import pandas as pd

    if isinstance(attributes, (str, bytes, os.PathLike)):
        path = os.fsdecode(attributes)
        if not os.path.isfile(path):
            raise FileNotFoundError(f"attribute table {path} does not exist")
        try:
            table = pd.read_csv(path)
        except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as error:
            raise ValueError(f"attribute table {path} is not a readable CSV file: {error}") from None
        where = f" (in {path})"
    elif isinstance(attributes, pd.DataFrame):
        table = attributes
        where = ""
    else:
        raise TypeError("attributes must be a pandas.DataFrame or the path of a CSV file, not "
                        f"{type(attributes).__name__}")
    if "label" in table.columns:
        table = table.set_index("label")
    elif table.index.name != "label":
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
    return table


def _join_attributes(table, attributes, dtype):
    import pandas as pd

    attributes = read_attributes(attributes)
    clash = sorted(set(attributes.columns) & set(table.columns))
    if clash:
        raise ValueError(f"attribute columns {clash} clash with the label table's own columns")
    keys = [int(k) for k in attributes.index.tolist()]
    # Python ints compare int64 with uint64 exactly (numpy would go through float64); a label
    # outside the volume's type cannot be in it.
    info = np.iinfo(dtype)
    present = set(int(k) for k in table.index.tolist())
    known = np.array([int(info.min) <= k <= int(info.max) and k in present for k in keys], bool)
    unknown = [k for k, ok in zip(keys, known) if not ok]
    if unknown:
        shown = ", ".join(str(k) for k in unknown[:10]) + (" ..." if len(unknown) > 10 else "")
        warnings.warn(f"{len(unknown)} labels of the attributes are not in the volume and are "
                      f"left out: {shown}", UserWarning, stacklevel=3)
    kept = attributes[known].copy()
    kept.index = pd.Index(np.array([k for k, ok in zip(keys, known) if ok], dtype=dtype), name="label")
    return table.join(kept, how="left")
