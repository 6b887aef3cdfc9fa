"""pyvista glue: a decoded slice of a segmentation as a flat mesh in the 3D view's label colors.

The slice is decoded from the compressed form alone (:meth:`SegmentationVolume.slice` and
:meth:`SegmentationVolume.resample_plane`); each voxel of it becomes one flat quad colored like
its label in :func:`vtksvdag.add_segmentation`, so a slice and the path-traced volume agree.
"""
import numpy as np

from .plotting import _apply_colors, _own_label_keys, _segmentation_volume

_AXIS_NAMES = ("x", "y", "z")


def _srgb_from_linear(c):
    c = np.clip(np.asarray(c, float), 0.0, 1.0)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)


def label_colors(volume, colors=None, cmap=None):
    """Display (sRGB, 0..1) color of each label of ``volume``, in the order of ``volume.labels``.

    The same precedence as :func:`vtksvdag.add_segmentation`: ``colors`` first, then ``cmap``
    (``"hash"``: the renderer's hash of the label index, its linear colors sRGB-encoded), else
    the distinct default colors (:meth:`SegmentationVolume.distinct_colors`).

    Returns
    -------
    numpy.ndarray of shape (n_labels, 3)
    """
    from .vtkSVDAGRendering import vtkSegmentationSVDAGLabelProperties

    props = vtkSegmentationSVDAGLabelProperties()
    _apply_colors(props, volume, colors, cmap)
    # The renderer's own material (GetMaterial: colors, table, then the hash of the label
    # index), so that the slice cannot drift from the 3D view.
    material = [0.0] * 16
    linear = np.empty((len(volume.labels), 3))
    for index, key in enumerate(_own_label_keys(volume)):
        props.GetMaterial(volume.dataobject, key, material)
        linear[index] = material[:3]
    return _srgb_from_linear(linear)


def _slice_image(volume, normal, origin, index, shape, spacing):
    """The decoded slice as a pyvista.ImageData (axis-aligned where possible)."""
    axis = None
    if isinstance(normal, str):
        if normal.lower() not in _AXIS_NAMES:
            raise ValueError(f"normal must be 'x', 'y', 'z' or 3 numbers, not {normal!r}")
        axis = _AXIS_NAMES.index(normal.lower())
    elif index is not None:
        raise ValueError("index is only for an axis-aligned normal ('x', 'y' or 'z')")
    if axis is not None and shape is None and spacing is None:
        if index is None and origin is not None:
            # The voxel layer nearest to the origin along the axis.
            o = np.asarray(origin, dtype=float)
            if o.shape != (3,) or not np.all(np.isfinite(o)):
                raise ValueError(f"origin must be 3 finite numbers, not {origin!r}")
            rel = np.linalg.solve(volume.direction, o - np.asarray(volume.origin, float))
            index = int(np.floor(rel[axis] / volume.spacing[axis] + 0.5))
            if not 0 <= index < volume.dims[axis]:
                raise IndexError(f"origin {tuple(o)} is outside the volume along {'xyz'[axis]}")
        return volume.slice(axis, index, as_image=True)
    if index is not None:
        raise ValueError("index cannot be combined with shape or spacing (an oblique grid)")
    return volume.resample_plane(normal, origin, shape=shape, spacing=spacing, as_image=True)


def _voxel_quads(image, rgb):
    """An ImageData whose cells are the slice's samples (one quad each, centered on it)."""
    import pyvista as pv

    dims = np.array(image.dimensions)
    spacing = np.array(image.spacing, float)
    direction = np.array(image.direction_matrix, float).reshape(3, 3)
    extent = np.array(image.extent).reshape(3, 2)[:, 0]
    flat = dims == 1
    # Zero-based extent: the first sample's world position, then half a sample back in-plane.
    first = np.array(image.origin, float) + direction @ (spacing * extent)
    corner = first - direction @ (0.5 * spacing * ~flat)
    quads = pv.ImageData(dimensions=tuple(int(d) for d in dims + ~flat), spacing=tuple(spacing),
                         origin=tuple(corner))
    quads.direction_matrix = direction
    quads.cell_data["RGB"] = rgb
    return quads


def add_segmentation_slice(plotter, data, *, normal="z", origin=None, index=None, colors=None,
                           cmap=None, shape=None, spacing=None, show_background=False,
                           background_color="black", name=None, reset_camera=None, **kwargs):
    """Add one slice of a segmentation to a ``pyvista.Plotter`` as a flat colored mesh.

    The slice is decoded straight from the compressed volume (only the cells it crosses), and
    every sample is drawn as a flat, unlit quad in its label's color, the colors
    :func:`vtksvdag.add_segmentation` gives the same labels (``colors``, then ``cmap``, then the
    distinct default colors), so a slice and the 3D view match.

    Parameters
    ----------
    plotter : pyvista.Plotter
        The plotter; the mesh goes into its active renderer.
    data : SegmentationVolume, str, os.PathLike, numpy.ndarray or pyvista.ImageData
        The segmentation, as :func:`vtksvdag.add_segmentation` takes it.
    normal : {"x", "y", "z"} or sequence of 3 float, default: "z"
        An axis name gives the axis-aligned slice through voxel ``index`` (or the voxel layer
        nearest to ``origin``, or the middle one); 3 numbers give an oblique plane (world
        normal) through ``origin`` (default: the volume's center), resampled nearest (see
        :meth:`SegmentationVolume.resample_plane`; with an axis name and ``shape`` or
        ``spacing`` the plane is resampled the same way).
    origin : sequence of 3 float, optional
        A world point on the plane.
    index : int, optional
        The voxel index of an axis-aligned slice.
    colors : dict, optional
        ``{label value: color}``, as in :func:`vtksvdag.add_segmentation`.
    cmap : str, matplotlib colormap or vtkScalarsToColors, optional
        Colors of the other labels, as in :func:`vtksvdag.add_segmentation`.
    shape, spacing : optional
        The oblique grid's size and sample distance (see ``resample_plane``).
    show_background : bool, default: False
        Draw background samples too, in ``background_color``; by default they are left out.
    background_color : color, default: "black"
        Color of background samples when they are drawn.
    name : str, optional
        Actor name (replaces an actor of the same name).
    reset_camera : bool, optional
        Passed to ``plotter.add_mesh``.
    **kwargs
        Further ``plotter.add_mesh`` options (``opacity``, ``pickable``, ...).

    Returns
    -------
    pyvista.Actor
        The slice's actor; ``actor.mapper.dataset`` holds cell data "RGB" and "Labels".

    Raises
    ------
    ValueError, IndexError, TypeError
        Bad plane, index or color arguments.

    Examples
    --------
    >>> import numpy as np, pyvista as pv, vtksvdag
    >>> labels = np.zeros((32, 32, 32), dtype=np.uint8)
    >>> labels[8:24, 8:24, 8:24] = 1
    >>> plotter = pv.Plotter(off_screen=True)
    >>> actor = vtksvdag.add_segmentation_slice(plotter, labels, normal="z", index=16,
    ...                                         colors={1: "gold"})
    >>> actor.mapper.dataset.n_cells
    256
    """
    from ._colors import to_rgb as _rgb

    volume = _segmentation_volume(data)
    image = _slice_image(volume, normal, origin, index, shape, spacing)
    values = np.asarray(image.point_data["Labels"])
    if values.dtype != volume.dtype:
        values = values.view(volume.dtype)
    palette = label_colors(volume, colors, cmap)
    stored = volume.labels
    position = np.searchsorted(stored, values)
    position_clipped = np.minimum(position, max(len(stored) - 1, 0))
    is_label = (len(stored) > 0) & (stored[position_clipped] == values) if len(stored) else \
        np.zeros(values.shape, dtype=bool)
    rgb = np.empty((values.size, 3), dtype=float)
    rgb[:] = _rgb(background_color)
    if len(stored):
        rgb[is_label] = palette[position_clipped[is_label]]
    quads = _voxel_quads(image, (np.clip(rgb, 0, 1) * 255 + 0.5).astype(np.uint8))
    quads.cell_data["Labels"] = values
    mesh = quads if show_background else quads.extract_cells(np.nonzero(is_label)[0])
    options = {"lighting": False, "show_scalar_bar": False}
    options.update(kwargs)
    actor = plotter.add_mesh(mesh, scalars="RGB", rgb=True, preference="cell", name=name,
                             reset_camera=reset_camera, **options)
    return actor
