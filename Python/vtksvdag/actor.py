"""The actor :func:`vtksvdag.add_segmentation` returns: a ``pyvista.Volume`` with label controls.

Imported by add_segmentation (it needs pyvista, which the rest of the package does not).
"""
import numbers

import numpy as np
import pyvista as pv

from ._attributes import NAN_COLOR
from ._colors import to_rgb as _rgb


class SegmentationActor(pv.Volume):
    """A ``pyvista.Volume`` drawn by ``vtkSegmentationSVDAGVolumeMapper``, with the per-label
    controls of :func:`vtksvdag.add_segmentation` for changing them after adding.

    Every method changes the mapper's ``vtkSegmentationSVDAGLabelProperties``; the next render
    of the plotter shows it (call ``plotter.render()`` or :func:`vtksvdag.refine`). Costs:
    :meth:`set_color_by` and :meth:`set_highlight` upload the material table (64 bytes per
    label) and restart the accumulation; :meth:`set_query` changes which labels are visible,
    which rebuilds the acceleration structure from the blocks already on the device (the DAG is
    not uploaded again).

    Examples
    --------
    >>> seg = vtksvdag.add_segmentation(plotter, volume, attributes="cells.csv")  # doctest: +SKIP
    >>> seg.set_query("volume > 1e4 and type == 'pyramidal'")  # doctest: +SKIP
    >>> seg.set_color_by("volume", cmap="viridis")  # doctest: +SKIP
    >>> seg.set_highlight([3, 7], dim=0.3)  # doctest: +SKIP
    >>> seg.label_table.loc[seg.visible_labels]  # doctest: +SKIP
    """

    @property
    def segmentation(self):
        """SegmentationVolume: the volume drawn."""
        return self._vtksvdag_volume

    @property
    def label_properties(self):
        """vtkSegmentationSVDAGLabelProperties: the mapper's per-label appearance."""
        return self.GetMapper().GetLabelProperties()

    @property
    def label_table(self):
        """pandas.DataFrame: the label table (indexed by label value) joined with the
        attributes given to add_segmentation; queries and ``color_by`` read it. Its ``color``
        column holds the colors in effect now (RGB 0-1 tuples, :meth:`get_color`), and
        ``name`` the names where the attributes have them."""
        table = self._vtksvdag_style.table.copy()
        table["color"] = [self.get_color(v) for v in table.index.tolist()]
        return table

    def _label_values(self, labels, what):
        values = [labels] if isinstance(labels, (numbers.Integral, np.integer)) else list(labels)
        for value in values:
            self._vtksvdag_style.key(value, what)  # TypeError / ValueError for a bad value
        return values

    def get_color(self, label):
        """The display color ``label`` is drawn with: an RGB tuple of floats in [0, 1] (what
        :meth:`set_color`, ``colors``, ``cmap``, ``color_by`` or the default palette gave it,
        before a highlight's dimming). ValueError for a label the volume does not hold.

        Examples
        --------
        >>> actor.set_color(7, "red")  # doctest: +SKIP
        >>> actor.get_color(7)  # doctest: +SKIP
        (1.0, 0.0, 0.0)
        """
        key = self._vtksvdag_style.key(label)
        rgb = [0.0, 0.0, 0.0]
        self.label_properties.GetDisplayColor(self.segmentation.dataobject, key, rgb)
        return tuple(rgb)

    def set_color(self, label, color):
        """Color one label (any color pyvista accepts); it wins over ``color_by`` columns, as
        ``colors`` given to add_segmentation does. A material upload, no geometry rebuild."""
        self._vtksvdag_style.set_color(label, _rgb(color))

    def hide(self, labels):
        """Hide labels (an int or an iterable): they stay hidden through :meth:`set_query`,
        like ``hidden_labels``. Rebuilds the acceleration structure from the blocks on the
        device."""
        self._vtksvdag_style.set_hidden(self._label_values(labels, "label to hide"), True)

    def show(self, labels):
        """Show labels hidden by :meth:`hide`, ``hidden_labels`` or a query (an int or an
        iterable); a later :meth:`set_query` decides again for the labels it does not match."""
        self._vtksvdag_style.set_hidden(self._label_values(labels, "label to show"), False)

    @property
    def query(self):
        """str or None: the query in effect."""
        return self._vtksvdag_style.query

    @property
    def color_by(self):
        """str or None: the column the labels are colored by."""
        return self._vtksvdag_style.color_column

    @property
    def highlighted_labels(self):
        """list of int: the highlighted label values."""
        return list(self._vtksvdag_style.highlighted)

    @property
    def visible_labels(self):
        """list of int: label values drawn (not hidden by ``hidden_labels``, the query or the
        label properties)."""
        style = self._vtksvdag_style
        props = self.label_properties
        return [v for v, k in zip(style.values, style.keys)
                if props.GetVisibility(k) and props.GetOpacity(k) > 0]

    def set_query(self, query):
        """Show only the labels whose row of :attr:`label_table` satisfies ``query`` (a pandas
        query expression, e.g. ``"volume > 1e4 and type == 'pyramidal'"``; a comparison with a
        missing value is false, except ``!=``, as in pandas); ``None`` shows every label again. Labels given as
        ``hidden_labels`` stay hidden.

        Returns the matching label values; raises ValueError for an expression pandas cannot
        evaluate on the table (the message lists its columns).
        """
        return self._vtksvdag_style.set_query(query)

    def set_color_by(self, column, cmap=None, clim=None, nan_color=None):
        """Color the labels by a column of :attr:`label_table` (see add_segmentation's
        ``color_by``); ``None`` returns to the colors given when adding. Colors given as
        ``colors={label: color}`` win over the column. ValueError for an unknown column."""
        nan = NAN_COLOR if nan_color is None else _rgb(nan_color)
        self._vtksvdag_style.set_color_by(column, cmap=cmap, clim=clim, nan_color=nan)

    def set_highlight(self, labels, dim=None, color=None, intensity=None, others_opacity=None):
        """Highlight labels with an emissive tint; ``None`` or ``[]`` removes the highlight.

        Parameters
        ----------
        labels : int, iterable of int or None
            Label values to highlight (ValueError for a value the volume does not hold).
        dim : float, optional
            Factor in [0, 1] on the other labels' base color while a highlight is active
            (1: no dimming). Kept until changed.
        color : color, optional
            The tint (default amber); any color pyvista accepts.
        intensity : float, optional
            The tint's radiance scale (default 1).
        others_opacity : float, optional
            Opacity factor in [0, 1] of the other labels while a highlight is active (below 1:
            see-through; 0 hides them, which rebuilds the acceleration structure).

        Returns the highlighted values. A change is a material upload: no geometry rebuild.
        """
        rgb = None if color is None else _rgb(color)
        return self._vtksvdag_style.set_highlight(labels, dim=dim, color=rgb, intensity=intensity,
                                                  others_opacity=others_opacity)
