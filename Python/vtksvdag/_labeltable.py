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
    """``attributes`` (a DataFrame with a ``label`` column or index, or the path of a label
    table: a CSV file, or any file :func:`vtksvdag.read_label_table` reads) as a DataFrame
    indexed by integer label value (index name ``label``).

    Raises ValueError for a table without labels, non-integer or duplicate labels, and
    FileNotFoundError for a missing file.
    """
    import pandas as pd

    from .labelmeta import CSV, detect_format, indexed_by_label, read_label_table

    if isinstance(attributes, (str, bytes, os.PathLike)):
        path = os.fsdecode(attributes)
        if not os.path.exists(path):
            raise FileNotFoundError(f"attribute table {path} does not exist")
        # A CSV file is read as it is (its columns unchanged); other formats are color tables.
        if os.path.isfile(path) and (path.lower().endswith(".csv") or detect_format(path) == CSV):
            try:
                table = pd.read_csv(path)
            except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as error:
                raise ValueError(f"attribute table {path} is not a readable CSV file: {error}") from None
            return indexed_by_label(table, f" (in {path})")
        return read_label_table(path)
    if isinstance(attributes, pd.DataFrame):
        return indexed_by_label(attributes, "")
    raise TypeError("attributes must be a pandas.DataFrame or the path of a CSV file (or of a "
                    f"label table read_label_table reads), not {type(attributes).__name__}")


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
    # A color table (read_label_table: a FreeSurfer LUT, a .seg.nrrd's segments) names labels
    # in general; that a volume holds only some of them is expected, not worth a warning.
    if unknown and not attributes.attrs.get("format"):
        shown = ", ".join(str(k) for k in unknown[:10]) + (" ..." if len(unknown) > 10 else "")
        warnings.warn(f"{len(unknown)} labels of the attributes are not in the volume and are "
                      f"left out: {shown}", UserWarning, stacklevel=3)
    kept = attributes[known].copy()
    kept.index = pd.Index(np.array([k for k, ok in zip(keys, known) if ok], dtype=dtype), name="label")
    return table.join(kept, how="left")
