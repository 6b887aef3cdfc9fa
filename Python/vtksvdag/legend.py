"""The label legend of a segmentation: label names (or values) with their colors.

:func:`add_label_legend` draws it with pyvista's ``add_legend`` (a ``vtkLegendBoxActor``);
:class:`LabelLegendMapper` offers the same entries to pyvista's ``plotter.add_scalar_bar()`` as
a categorical lookup table (one annotated color per label) for a ``vtkScalarBarActor``.

Which labels come first: the visible ones (not hidden by ``hidden_labels``, a query, opacity 0
or the label properties), then the hidden ones, each group by voxel count in the volume,
largest first (ties by label value). The voxel count in the volume, not on screen: it is known
without rendering, does not change while the camera moves, and ranks the labels a user sees
most in the default view (the whole volume) first.
"""
import numbers

import numpy as np
import pyvista as pv

from ._options import keywords_checked

#: The entries a legend shows by default (more are summarized in a last "+N more" entry): a
#: legend box of 200x150 pixels stays readable up to about this many lines.
MAX_ENTRIES = 12


def _plotter_of(actor):
    reference = getattr(actor, "_vtksvdag_plotter", None)
    plotter = reference() if reference is not None else None
    if plotter is None:
        raise ValueError("the actor is not in a live plotter: pass plotter=, or add it with "
                         "vtksvdag.add_segmentation")
    return plotter


def _check_actor(actor):
    from .actor import SegmentationActor

    if not isinstance(actor, SegmentationActor):
        raise TypeError(f"actor must be the SegmentationActor vtksvdag.add_segmentation returns, "
                        f"not {type(actor).__name__}")


def _check_max_entries(max_entries):
    if isinstance(max_entries, bool) or not isinstance(max_entries, numbers.Integral) or max_entries < 1:
        raise ValueError(f"max_entries must be an integer >= 1, got {max_entries!r}")
    return int(max_entries)


def label_entries(actor, labels=None, max_entries=MAX_ENTRIES):
    """The legend's entries: ``(entries, more)``, ``entries`` a list of ``(value, text, rgb)``
    (``text`` the ``name`` column of ``actor.label_table`` where present, else the value; ``rgb``
    the display color in effect), ``more`` the number of labels left out.

    ``labels``: the label values to list, in their order; by default every label, visible
    first, each group by voxel count (largest first).
    """
    _check_actor(actor)
    max_entries = _check_max_entries(max_entries)
    volume = actor.segmentation
    if labels is None:
        visible = set(actor.visible_labels)
        counts = volume.label_voxel_counts
        order = sorted(range(len(volume.labels)),
                       key=lambda i: (volume.labels[i].item() not in visible, -int(counts[i]),
                                      volume.labels[i].item()))
        values = [volume.labels[i].item() for i in order]
    else:
        values = [labels] if isinstance(labels, (numbers.Integral, np.integer)) else list(labels)
        for value in values:
            actor._vtksvdag_style.key(value, "legend label")  # TypeError/ValueError for a bad one
    table = actor.label_table
    names = table["name"] if "name" in table.columns else None
    entries = []
    for value in values[:max_entries]:
        name = names.get(value) if names is not None else None
        text = str(value) if name is None or (isinstance(name, float) and np.isnan(name)) else str(name)
        entries.append((value, text, actor.get_color(value)))
    return entries, max(len(values) - max_entries, 0)


@keywords_checked
def add_label_legend(actor, labels=None, *, max_entries=MAX_ENTRIES, plotter=None,
                     size=(0.2, 0.2), loc="upper right", face="rectangle", bcolor=None,
                     border=False, background_opacity=1.0, font_family=None):
    """Add a legend of a segmentation's labels: their names (or values) with their colors.

    Built with pyvista's ``add_legend`` in the renderer that holds the actor (one legend per
    renderer: it replaces a legend there). The colors are those in effect when it is called
    (``actor.get_color``); call it again after changing colors, a query or hidden labels.

    Parameters
    ----------
    actor : vtksvdag.actor.SegmentationActor
        The actor :func:`vtksvdag.add_segmentation` returned.
    labels : int or iterable of int, optional
        The labels to list, in this order. By default every label: the visible ones first, then
        the hidden ones, each group by voxel count in the volume (largest first).
    max_entries : int, default: 12
        At most this many labels; one more entry says how many were left out ("+N more").
    plotter : pyvista.Plotter, optional
        The plotter of the actor (default: the one it was added to).
    size, loc, face, bcolor, border, background_opacity, font_family
        pyvista's ``add_legend`` options (``face`` the symbol: ``"rectangle"``, ``"circle"``,
        ``"triangle"``, ``"line"``).

    Returns
    -------
    vtkLegendBoxActor
        The legend; ``GetEntryString(i)`` and ``GetEntryColor(i)`` are its entries.

    Raises
    ------
    TypeError
        ``actor`` is not a segmentation actor, or a label is not an integer.
    ValueError
        A label the volume does not hold, ``max_entries`` < 1, or an actor in no live plotter.

    Examples
    --------
    >>> import pandas as pd
    >>> names = pd.DataFrame({"label": [3, 7], "name": ["slab", "box"]})
    >>> actor = vtksvdag.add_segmentation(plotter, labels, attributes=names)  # doctest: +SKIP
    >>> legend = vtksvdag.add_label_legend(actor, max_entries=5)  # doctest: +SKIP
    >>> legend.GetEntryString(0)  # doctest: +SKIP
    'box'
    """
    entries, more = label_entries(actor, labels, max_entries)
    plotter = _plotter_of(actor) if plotter is None else plotter
    renderer = next((r for r in plotter.renderers if r.GetVolumes().IsItemPresent(actor)), None)
    if renderer is None:
        raise ValueError("the actor is not in this plotter's renderers")
    rows = [[text, rgb, face] for _, text, rgb in entries]
    if more:
        rows.append([f"+{more} more", renderer.background_color, "none"])
    return renderer.add_legend(rows, bcolor=bcolor, border=border, size=size, loc=loc,
                               face=face, font_family=font_family,
                               background_opacity=background_opacity)


def categorical_lookup_table(actor, labels=None, max_entries=MAX_ENTRIES):
    """A ``pyvista.LookupTable`` in indexed mode: one annotated color per legend entry (the
    entries of :func:`add_label_legend`), the form a ``vtkScalarBarActor`` draws as categories."""
    entries, _ = label_entries(actor, labels, max_entries)
    table = pv.LookupTable()
    table.SetNumberOfTableValues(max(len(entries), 1))
    table.IndexedLookupOn()
    for i, (value, text, rgb) in enumerate(entries):
        table.SetTableValue(i, *rgb, 1.0)
        table.SetAnnotation(float(value), text)
    if entries:
        values = [float(v) for v, _, _ in entries]
        table.SetTableRange(min(values), max(values))
    return table


class LabelLegendMapper(pv.DataSetMapper):
    """What ``plotter.add_scalar_bar()`` needs of ``plotter.mapper`` for a segmentation: a
    lookup table of the label legend's entries (categorical, see
    :func:`categorical_lookup_table`), built when the scalar bar is added so that it shows the
    colors then in effect. It maps nothing: the segmentation has its own mapper."""

    def __init__(self, actor):
        super().__init__()
        import weakref

        self._actor = weakref.ref(actor)

    @property
    def lookup_table(self):  # numpydoc ignore=RT01
        """pyvista.LookupTable: the legend's entries, rebuilt from the actor's colors."""
        actor = self._actor()
        if actor is None:
            raise ValueError("the segmentation of this scalar bar was deleted")
        table = categorical_lookup_table(actor)
        self.SetLookupTable(table)
        self.SetScalarRange(table.GetTableRange())
        return table

    @lookup_table.setter
    def lookup_table(self, table):
        self.SetLookupTable(table)
