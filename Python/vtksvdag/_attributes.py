"""Per-label attribute tables, colors by column, queries and the selection highlight.

Shared by :func:`vtksvdag.add_segmentation` (through :class:`vtksvdag.SegmentationActor`) and
``vtksvdag render``: both hold one :class:`LabelStyle` over a volume and the
``vtkSegmentationSVDAGLabelProperties`` its renderer draws with. Every change goes through the
label properties, so what costs what is the renderer's rule: colors and the highlight are a
material upload, a query is a visibility change (the acceleration structure is rebuilt from the
blocks already on the device; the DAG is not uploaded again).

pandas and matplotlib are imported where they are needed: the rest of the package works without
them.
"""
import numbers

import numpy as np

from ._colors import to_rgb as _rgb
from ._labels import label_pattern
from ._labeltable import read_attributes

#: The color of labels without a value in the ``color_by`` column (documented in
#: add_segmentation): a neutral mid grey, darker than the default light background.
NAN_COLOR = (0.5, 0.5, 0.5)


def label_key(value, dtype):
    """A label value as the label properties' int64 key (the 64-bit pattern)."""
    pattern = int(label_pattern(value, dtype, "label")) & (2**64 - 1)
    return pattern - 2**64 if pattern >= 2**63 else pattern


def _pandas():
    try:
        import pandas
    except ImportError:  # pragma: no cover - pandas is a dependency of the plotting extras
        raise ImportError("label attribute tables need pandas (pip install pandas)") from None
    return pandas


def label_table(volume, attributes=None):
    """The volume's label table joined with ``attributes`` (:meth:`SegmentationVolume.label_table`:
    voxel counts, volume, bounds, centroids, surface voxels; one row per label of the volume)."""
    return volume.label_table(attributes=attributes)


def _colormap(cmap, categorical, n_categories=0):
    import matplotlib

    if cmap is None:
        cmap = ("tab10" if n_categories <= 10 else "tab20") if categorical else "viridis"
    if isinstance(cmap, str):
        try:
            return matplotlib.colormaps[cmap]
        except KeyError:
            from ._options import close_names

            raise ValueError(f"cmap {cmap!r}: unknown colormap{close_names(cmap, matplotlib.colormaps)}"
                             f"; the names are those of matplotlib.colormaps, e.g. 'tab20' or "
                             f"'viridis'") from None
    if callable(cmap):
        return cmap
    raise TypeError(f"cmap must be a matplotlib colormap or its name, not {type(cmap).__name__}")


def is_categorical(series):
    """Numbers are colored on a continuous scale, anything else (strings, bools, pandas
    categories) by category."""
    return series.dtype.kind not in "iuf"


def column_colors(series, cmap=None, clim=None, nan_color=NAN_COLOR):
    """RGB (0..1 floats, n x 3) of each value of ``series``.

    Numeric columns: ``cmap`` (default viridis) over ``clim`` (default the finite values'
    range; a constant column takes the colormap's middle), values clipped to it. Others: one
    color per category, in sorted order (a pandas category's own order): a listed colormap
    (default tab10, tab20 beyond 10 categories) cycles, a continuous one is sampled evenly.
    Missing values (NaN, None) take ``nan_color``.
    """
    pd = _pandas()
    missing = series.isna().to_numpy()
    rgb = np.tile(np.asarray(nan_color, float), (len(series), 1))
    if is_categorical(series):
        if isinstance(series.dtype, pd.CategoricalDtype):
            categories = list(series.cat.categories)
        else:
            categories = sorted(series[~missing].unique().tolist(), key=lambda v: (str(type(v)), v))
        colormap = _colormap(cmap, True, len(categories))
        count = getattr(colormap, "N", 256)
        where = {c: i for i, c in enumerate(categories)}
        for row, value in enumerate(series.tolist()):
            if missing[row]:
                continue
            i = where[value]
            t = i % count if count < 256 else (i / max(len(categories) - 1, 1))
            rgb[row] = colormap(t)[:3]
        return rgb
    values = series.to_numpy(dtype=float)
    finite = np.isfinite(values) & ~missing
    if clim is None:
        if not finite.any():
            return rgb
        lo, hi = float(values[finite].min()), float(values[finite].max())
    else:
        lo, hi = (float(v) for v in clim)
        if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi):
            raise ValueError(f"clim must be two finite numbers, low <= high, got {clim!r}")
    colormap = _colormap(cmap, False)
    known = ~missing & ~np.isnan(values)
    t = np.full(len(values), 0.5) if hi == lo else (np.clip(values, lo, hi) - lo) / (hi - lo)
    rgb[known] = np.asarray(colormap(t[known]))[:, :3]
    return rgb


def query_labels(table, query):
    """Index values of the rows of ``table`` that satisfy the pandas query expression.

    Evaluated with pandas' python engine, whether or not numexpr is installed: numexpr cannot
    run string methods (``name.str.contains('Hippocampus')``), and one engine keeps one
    behaviour everywhere. A missing value where the expression gives True or False (a label
    without a name) does not match, as a comparison with a missing value is false.
    """
    pd = _pandas()
    if not isinstance(query, str) or not query.strip():
        raise ValueError(f"query must be a non-empty pandas query expression, got {query!r}")
    columns = [str(c) for c in table.columns]
    try:
        result = table.eval(query, engine="python")
    except Exception as error:  # pandas raises NameError, SyntaxError, TypeError, KeyError, ...
        raise ValueError(f"query {query!r} failed on the label table ({type(error).__name__}: "
                         f"{error}); its columns are {columns}") from None
    values = result.to_numpy(dtype=object) if isinstance(result, pd.Series) else None
    known = None if values is None else ~pd.isna(result).to_numpy()
    if (values is None or not result.index.equals(table.index)
            or not all(isinstance(v, (bool, np.bool_)) for v in values[known])):
        raise ValueError(f"query {query!r} does not select rows of the label table (it must be "
                         f"true or false for each label); its columns are {columns}")
    matched = known.copy()
    matched[known] = values[known].astype(bool)
    return table.index[matched]


class LabelStyle:
    """The attribute-driven appearance of one volume's labels on a label-properties object.

    Keeps what add_segmentation set up (explicit colors, hidden labels) so that a new color
    column or query is applied on top of it, and changes only the labels whose state changes.
    """

    def __init__(self, volume, props, *, attributes=None, colors=None, hidden=(), check=True):
        self.volume = volume
        self.props = props
        self.values = volume.labels.tolist()
        self.keys = [label_key(v, volume.dtype) for v in self.values]
        self._key_of = dict(zip(self.values, self.keys))
        # Read (a file) and checked once; joined with the label statistics when first needed.
        self._attributes = None if attributes is None else read_attributes(attributes)
        self._table = None
        # Colors set before any color_by (cmap, colors): restored by color_by(None).
        self._base_colors = {}
        for key in self.keys:
            rgb = [0.0] * 3
            if props.GetColor(key, rgb):
                self._base_colors[key] = tuple(rgb)
        self._explicit = dict(colors or {})  # {key: rgb}: win over any color column
        self._hidden = set(hidden)           # keys hidden whatever the query
        self.query = None
        self.color_column = None
        self.highlighted = []
        # check=False: a table that came with the volume's file is joined on first use, so
        # that adding the volume does not make the statistics pass for it.
        if attributes is not None and check:
            self.table  # noqa: B018 (read and check the attributes now, not on first use)

    @property
    def table(self):
        if self._table is None:
            self._table = label_table(self.volume, self._attributes)
        return self._table

    def key(self, value, what="label"):
        if value not in self._key_of:
            if not isinstance(value, (numbers.Integral, np.integer)) or isinstance(value, bool):
                raise TypeError(f"{what} must be an integer label value, not {value!r}")
            raise ValueError(f"{what} {value!r} is not a label of the volume")
        return self._key_of[value]

    # -- colors ---------------------------------------------------------------------------
    def use_color_column(self):
        """The attributes' ``color`` column (from :func:`vtksvdag.read_label_table`, or any
        color pyvista accepts) as the labels' base colors, under the explicit ones; labels
        without a value keep theirs. Read from the attributes alone: the label statistics
        are not computed for it."""
        attributes = self._attributes
        if attributes is None or "color" not in attributes.columns:
            return
        props = self.props
        index = {int(v): i for i, v in enumerate(attributes.index.tolist())}
        column = attributes["color"].tolist()
        for value, key in zip(self.values, self.keys):
            row = index.get(int(value))
            color = None if row is None else column[row]
            if color is None or (not isinstance(color, (tuple, list, np.ndarray, str))
                                 and _pandas().isna(color)):
                continue
            try:
                rgb = _rgb(color)
            except (ValueError, TypeError) as error:
                raise ValueError(f"the color column's value for label {value} is not a color: "
                                 f"{color!r} ({error})") from None
            self._base_colors[key] = rgb
            props.SetColor(key, *rgb)
        for key, color in self._explicit.items():
            props.SetColor(key, *color)

    def set_color_by(self, column, cmap=None, clim=None, nan_color=NAN_COLOR):
        props = self.props
        if column is None:
            for key in self.keys:
                if key in self._base_colors:
                    props.SetColor(key, *self._base_colors[key])
                else:
                    props.RemoveColor(key)
        else:
            table = self.table
            if column not in table.columns:
                raise ValueError(f"color_by column {column!r} is not in the label table; its "
                                 f"columns are {[str(c) for c in table.columns]}")
            series = table[column].reindex(self.values)
            rgb = column_colors(series, cmap=cmap, clim=clim, nan_color=nan_color)
            for key, color in zip(self.keys, rgb):
                props.SetColor(key, *(float(c) for c in color))
        for key, color in self._explicit.items():
            props.SetColor(key, *color)
        self.color_column = column

    def set_color(self, value, rgb):
        """One label's color, kept like add_segmentation's ``colors`` (it wins over columns)."""
        key = self.key(value)
        self._explicit[key] = tuple(rgb)
        self.props.SetColor(key, *rgb)

    # -- visibility -----------------------------------------------------------------------
    def set_hidden(self, values, hidden):
        """Hide labels (kept hidden through queries, as ``hidden_labels``), or show them (the
        query in effect is not applied again to them; the next set_query is)."""
        keys = [self.key(v) for v in values]
        for key in keys:
            (self._hidden.add if hidden else self._hidden.discard)(key)
            if bool(self.props.GetVisibility(key)) == hidden:
                self.props.SetVisibility(key, not hidden)

    def set_query(self, query):
        if query is None:
            shown = set(self.values)
        else:
            shown = set(query_labels(self.table, query).tolist())
        props = self.props
        for value, key in zip(self.values, self.keys):
            visible = value in shown and key not in self._hidden
            # Only changes: each call marks the properties modified.
            if bool(props.GetVisibility(key)) != visible:
                props.SetVisibility(key, visible)
        self.query = query
        return sorted(shown)

    # -- highlight ------------------------------------------------------------------------
    def set_highlight(self, labels, dim=None, color=None, intensity=None, others_opacity=None):
        props = self.props
        values = [] if labels is None else (
            [labels] if isinstance(labels, (numbers.Integral, np.integer)) else list(labels))
        keys = [self.key(v, "highlight label") for v in values]
        for name, value in (("dim", dim), ("others_opacity", others_opacity)):
            if value is not None and (isinstance(value, bool) or not isinstance(value, numbers.Real)
                                      or not 0 <= float(value) <= 1):
                raise ValueError(f"{name} must be a number in [0, 1], got {value!r}")
        if intensity is not None and (isinstance(intensity, bool)
                                      or not isinstance(intensity, numbers.Real)
                                      or not (0 <= float(intensity) <= 1e6)):
            raise ValueError(f"highlight intensity must be a number in [0, 1e6], got {intensity!r}")
        if color is not None:
            props.SetHighlightColor(*color)
        if intensity is not None:
            props.SetHighlightIntensity(float(intensity))
        if dim is not None:
            props.SetDimOthers(float(dim))
        if others_opacity is not None:
            props.SetOthersOpacity(float(others_opacity))
        wanted = set(keys)
        current = {props.GetHighlightedLabel(i) for i in range(props.GetNumberOfHighlightedLabels())}
        for key in current - wanted:
            props.RemoveHighlightedLabel(key)
        for key in wanted - current:
            props.AddHighlightedLabel(key)
        self.highlighted = sorted(set(values))
        return self.highlighted


# -- ``vtksvdag render`` options ------------------------------------------------------------------
def _label_list_option(text):
    """``3,7`` -> [3, 7] (argparse type of --highlight)."""
    import argparse

    try:
        values = [int(part) for part in text.split(",") if part.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected label values separated by commas, got {text!r}") from None
    if not values:
        raise argparse.ArgumentTypeError("expected at least one label value")
    return values


def _fraction_option(text):
    import argparse

    try:
        value = float(text)
    except ValueError:
        value = float("nan")  # fails the range check below, with the same message
    if not 0 <= value <= 1:
        raise argparse.ArgumentTypeError(f"expected a number in [0, 1], got {text!r}")
    return value


def add_render_arguments(parser):
    """The attribute-table options of ``vtksvdag render``."""
    group = parser.add_argument_group("label attributes")
    group.add_argument("--attributes", metavar="TABLE.csv",
                       help="CSV table of per-label attributes with a 'label' column, joined on the "
                            "label value with the computed columns (voxel_count, volume, ...), or "
                            "a label table vtksvdag.read_label_table reads (FreeSurfer, ITK-SNAP, "
                            ".seg.nrrd, ...); its 'color' column colors the labels")
    group.add_argument("--color-by", metavar="COLUMN",
                       help="color the labels by a column: numbers on a continuous colormap over its "
                            "range, other values one color per category; labels without a value grey")
    group.add_argument("--cmap", metavar="NAME",
                       help="matplotlib colormap for --color-by (default: viridis for numbers, "
                            "tab10/tab20 for categories)")
    group.add_argument("--query", metavar="EXPR",
                       help="pandas query over the label table; labels that do not match are hidden, "
                            "e.g. \"volume > 1e4 and type == 'pyramidal'\"")
    group.add_argument("--highlight", type=_label_list_option, metavar="L1,L2,...",
                       help="label values drawn with an emissive tint")
    group.add_argument("--dim", type=_fraction_option, metavar="F",
                       help="with --highlight: factor in [0, 1] on the other labels' colors")


def apply_render_options(args, volume, props, hidden_values=()):
    """Applies --attributes/--color-by/--query/--highlight/--dim to a renderer's label
    properties; returns the LabelStyle (None when none is given). ValueError names the option."""
    if args.color_by is None and args.query is None and args.highlight is None and args.dim is None:
        if args.attributes is not None or args.cmap is not None:
            raise ValueError("--attributes and --cmap need --color-by or --query")
        return None
    if args.cmap is not None and args.color_by is None:
        raise ValueError("--cmap needs --color-by")
    hidden = [label_key(v, volume.dtype) for v in hidden_values]
    try:
        style = LabelStyle(volume, props, attributes=args.attributes, hidden=hidden)
        style.use_color_column()
    except ValueError as error:
        raise ValueError(f"--attributes: {error}") from None
    for option, apply in (("--color-by", lambda: args.color_by is not None and style.set_color_by(
                              args.color_by, cmap=args.cmap)),
                          ("--query", lambda: args.query is not None and style.set_query(args.query)),
                          ("--highlight", lambda: (args.highlight is not None or args.dim is not None)
                           and style.set_highlight(args.highlight, dim=args.dim))):
        try:
            apply()
        except (ValueError, TypeError) as error:
            raise ValueError(f"{option}: {error}") from None
    return style
