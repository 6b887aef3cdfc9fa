"""pyvista glue: path-trace a segmentation in a ``pyvista.Plotter``, refine it, pick labels.

The volume is drawn by ``vtkSegmentationSVDAGVolumeMapper`` inside the plotter's own render
window, depth-composited with every mesh in the scene.
"""
import functools
import numbers
import os
import time
import weakref

import numpy as np

from ._colors import to_rgb as _rgb
from ._labels import check_cast, label_pattern, numpy_dtype_of_vtk_type
from ._options import close_names, keywords_checked as _keywords_checked
from ._settingnames import set_by_name
from ._vtkrun import vtk_errors_raised
from .build import from_image, from_numpy
from .fileio import read
from .volume import SegmentationVolume

# pyvista and the rendering module are imported where they are used: the rest of the package
# works without them (a machine without Vulkan, a script that only compresses).


def _segmentation_volume(data, scalars=None, spacing=None, origin=None, axis_order=None,
                         cast=None):
    """A SegmentationVolume from any of the inputs add_segmentation accepts; each option is for
    the inputs named in add_segmentation (ValueError naming it for the others)."""
    geometry = {k: v for k, v in (("spacing", spacing), ("origin", origin),
                                  ("axis_order", axis_order)) if v is not None}
    is_image = hasattr(data, "IsA") and data.IsA("vtkImageData")
    if geometry and not isinstance(data, np.ndarray):
        raise ValueError(f"{'=, '.join(geometry)}= is for numpy arrays; "
                         f"{type(data).__name__} data carries its own geometry")
    if scalars is not None and not is_image:
        raise ValueError(f"scalars={scalars!r} names an array of a pyvista.ImageData / "
                         f"vtkImageData; {type(data).__name__} data has no named arrays")
    if isinstance(data, SegmentationVolume):
        if cast is not None:
            raise ValueError("cast is for label arrays and files; a SegmentationVolume holds "
                             "integer labels already")
        return data
    if isinstance(data, (str, bytes, os.PathLike)):
        return read(data, cast=cast)
    if isinstance(data, np.ndarray):
        return from_numpy(data, cast=cast, **geometry)
    if is_image:
        return from_image(data, scalars=scalars, cast=cast)
    raise TypeError(
        "data must be a SegmentationVolume, a file path, a numpy label array or a "
        f"pyvista.ImageData / vtkImageData, not {type(data).__name__}"
    )


def _check_fraction(value, what):
    if not isinstance(value, numbers.Real) or not 0 <= float(value) <= 1:
        raise ValueError(f"{what} must be a number in [0, 1], got {value!r}")
    return float(value)


def _own_label_keys(volume):
    """The volume's own labels as the mapper's int64 keys, in the order of ``volume.labels``:
    what :func:`_label_keys` gives for them (no check needed), without a Python call per label
    (EM volumes hold 10^4-10^5 labels)."""
    return volume.labels.astype(np.int64).tolist()


def _label_keys(volume, values, what):
    """Label values as the mapper's int64 keys; values the volume does not hold are errors."""
    keys = []
    present = set(volume.labels.tolist())
    for value in values:
        if value not in present:
            raise ValueError(f"{what} {value!r} is not a label of the volume")
        # The 64-bit pattern (sign-extended for signed types) read as an int64.
        pattern = int(label_pattern(value, volume.dtype, what)) & (2**64 - 1)
        keys.append(pattern - 2**64 if pattern >= 2**63 else pattern)
    return keys


# The pyvista glue's default look (the first image a user sees), applied where add_segmentation's
# options are left at None: a sun with a soft penumbra and a slightly blue sky over the C++
# defaults' neutral-white environment. Only what differs from vtkSegmentationSVDAGRenderSettings'
# defaults is named here; the sun's direction and irradiance stay the C++ core's. The C++ defaults
# themselves are unchanged, so VTK viewers and the C++ regression baselines keep their look.
DEFAULT_SUN_ANGULAR_RADIUS = 4.0  # degrees: shadows with soft edges (the real sun's 0.27 is hard)
DEFAULT_SKY = (0.55, 0.6, 0.7)     # linear radiance of the constant environment


def _apply_colors(props, volume, colors, cmap):
    if cmap is None:
        # The default: palette colors assigned over the label adjacency (svdag::
        # distinctLabelColors), set per label so that GetColor reports them.
        for key, rgb in zip(_own_label_keys(volume), volume.distinct_colors()):
            props.SetColor(key, *rgb)
    elif isinstance(cmap, str) and cmap == "hash":
        pass  # the renderer's hash of each label index (the default before the palette)
    else:
        if hasattr(cmap, "IsA") and cmap.IsA("vtkScalarsToColors"):
            props.SetLookupTable(cmap)
        else:
            from ._attributes import _colormap

            colormap = _colormap(cmap, categorical=True)
            n = len(volume.labels)
            # Categorical: listed colormaps cycle their colors, continuous ones are sampled evenly.
            count = getattr(colormap, "N", 256)
            for index, key in enumerate(_own_label_keys(volume)):
                if count < 256:
                    rgba = colormap(index % count)
                else:
                    rgba = colormap(index / max(n - 1, 1))
                props.SetColor(key, *rgba[:3])
    if colors is not None:
        if not hasattr(colors, "items"):
            raise TypeError("colors must be a dict {label value: color}")
        values = list(colors)
        for key, value in zip(_label_keys(volume, values, "colors label"), values):
            props.SetColor(key, *_rgb(colors[value]))


_SUN_FORMS = ("None (the default: the sun with soft shadows), False (no sun), True (the settings' "
              "sun), a direction towards the sun (3 numbers) or a dict with direction, irradiance, "
              "angular_radius")


def _sun_number(value, what):
    try:
        return np.asarray(value, float)
    except (TypeError, ValueError):
        raise ValueError(f"sun {what} must be numbers, got {value!r}") from None


def _apply_sun(settings, sun):
    if isinstance(sun, (str, bytes)) or not (sun is None or isinstance(sun, bool)
                                             or hasattr(sun, "items") or np.iterable(sun)):
        # "yes" would otherwise reach float("yes"), a message that does not name sun.
        raise ValueError(f"sun must be {_SUN_FORMS}; got {sun!r}")
    if sun is False:
        settings.SetSun(False)
        return
    settings.SetSun(True)
    if sun is None:
        settings.SetSunAngularRadius(DEFAULT_SUN_ANGULAR_RADIUS)
        return
    if sun is True:
        return
    if hasattr(sun, "items"):
        unknown = set(sun) - {"direction", "irradiance", "angular_radius"}
        if unknown:
            raise TypeError(f"unknown sun options {sorted(unknown)} (direction, irradiance, angular_radius)")
        direction = sun.get("direction")
        if "irradiance" in sun:
            irradiance = np.broadcast_to(_sun_number(sun["irradiance"], "irradiance"), (3,))
            if not np.all(np.isfinite(irradiance)) or np.any(irradiance < 0):
                raise ValueError("the sun irradiance must be finite and >= 0")
            settings.SetSunIrradiance(*irradiance)
        if "angular_radius" in sun:
            radius = float(_sun_number(sun["angular_radius"], "angular_radius"))
            if not 0 <= radius <= 89.9:
                raise ValueError(f"the sun's angular radius must be in [0, 89.9] degrees, got {radius}")
            settings.SetSunAngularRadius(radius)
    else:
        direction = sun
    if direction is not None:
        d = _sun_number(direction, "direction")
        if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.any(d):
            raise ValueError(f"the sun direction must be 3 finite numbers, not all 0, got {direction!r}")
        settings.SetSunDirection(*d)


def _apply_environment(settings, environment):
    if environment is None:
        settings.SetEnvironmentColor(*DEFAULT_SKY)
        return
    if isinstance(environment, (str, os.PathLike)) and str(environment).lower().endswith(".exr"):
        if not os.path.isfile(environment):
            raise FileNotFoundError(f"environment map {environment} does not exist")
        settings.SetEnvironmentMap(os.fspath(environment))
        return
    settings.SetEnvironmentColor(*_rgb(environment))


def _clipping_plane(plane):
    """A vtkPlane from ``(origin, normal)``; ValueError for a non-finite origin or a zero or
    non-finite normal."""
    from vtkmodules.vtkCommonDataModel import vtkPlane

    try:
        origin, normal = plane
        origin = np.asarray(origin, dtype=float).reshape(3)
        normal = np.asarray(normal, dtype=float).reshape(3)
    except (TypeError, ValueError):
        raise ValueError(f"a clipping plane is (origin, normal) with 3 numbers each, got {plane!r}") from None
    if not np.all(np.isfinite(origin)):
        raise ValueError(f"clipping plane origin must be finite, got {tuple(origin)}")
    if not (np.all(np.isfinite(normal)) and np.linalg.norm(normal) > 0):
        raise ValueError(f"clipping plane normal must be finite and non-zero, got {tuple(normal)}")
    result = vtkPlane()
    result.SetOrigin(*origin)
    result.SetNormal(*normal)
    return result


def _crop_box(crop):
    """The 6 crop bounds as floats; ValueError unless finite with min <= max on every axis."""
    try:
        bounds = np.asarray(crop, dtype=float).reshape(6)
    except (TypeError, ValueError):
        raise ValueError(f"crop must be (xmin, xmax, ymin, ymax, zmin, zmax), got {crop!r}") from None
    if not np.all(np.isfinite(bounds)):
        raise ValueError(f"crop bounds must be finite, got {tuple(bounds)}")
    for axis, (lo, hi) in zip("xyz", bounds.reshape(3, 2)):
        if lo > hi:
            raise ValueError(f"crop box is inverted along {axis}: min {lo} > max {hi}")
    return [float(b) for b in bounds]


def _apply_clipping(mapper, clipping_planes, crop):
    if clipping_planes is not None:
        planes = [_clipping_plane(p) for p in clipping_planes]
        most = mapper.GetMaximumNumberOfClippingPlanes()
        if len(planes) > most:
            raise ValueError(f"at most {most} clipping planes are supported, got {len(planes)}")
        for plane in planes:
            mapper.AddClippingPlane(plane)
    if crop is not None:
        mapper.SetCroppingRegionPlanes(*_crop_box(crop))
        mapper.CroppingOn()


@_keywords_checked
def add_segmentation(
    plotter,
    data,
    *,
    colors=None,
    cmap=None,
    opacity=1.0,
    hidden_labels=None,
    attributes=None,
    color_by=None,
    clim=None,
    nan_color=None,
    query=None,
    highlight=None,
    dim=None,
    highlight_color=None,
    highlight_intensity=None,
    others_opacity=None,
    lod=None,
    shading=None,
    backend=None,
    spp=None,
    samples_per_pass=None,
    bounces=None,
    seed=None,
    next_event_estimation=None,
    denoise=None,
    exposure=None,
    sun=None,
    environment=None,
    clipping_planes=None,
    crop=None,
    write_depth=None,
    auto_adjust=None,
    error_target=None,
    name=None,
    reset_camera=None,
    scalars=None,
    spacing=None,
    origin=None,
    axis_order=None,
    cast=None,
    show_scalar_bar=None,
):
    """Add a path-traced segmentation volume to a ``pyvista.Plotter``.

    The volume is path-traced with Vulkan (a GPU, or Mesa's lavapipe on the CPU) and
    composited with the plotter's meshes by depth. While the view is still, each render adds
    samples until ``spp`` samples per pixel (see :func:`refine`); while the user interacts,
    frames keep to the plotter's update rate with a coarser LOD and resolution.

    Options left at ``None`` keep the default of the VTK object they set
    (``vtkSegmentationSVDAGRenderSettings`` for the path tracer, whose defaults are the C++ core's,
    or ``vtkSegmentationSVDAGVolumeMapper``); the defaults named below are those, except the
    default look of ``colors``/``cmap``, ``sun`` and ``environment`` (distinct label colors, a
    soft sun and a sky), which this glue applies over the C++ defaults. An unknown option is a
    TypeError that suggests the closest names.

    Parameters
    ----------
    plotter : pyvista.Plotter
        The plotter; the volume goes into its active renderer (subplot).
    data : SegmentationVolume, str, os.PathLike, numpy.ndarray or pyvista.ImageData
        The segmentation: a compressed volume, a file :func:`vtksvdag.read` reads, a 3D integer
        label array indexed ``[x, y, z]``, or a label image.
    colors : dict, optional
        ``{label value: color}``; any color pyvista accepts (name, hex, RGB floats or ints).
    cmap : str, matplotlib colormap or vtkScalarsToColors, optional
        Colors of the labels ``colors`` does not name: a listed (categorical) colormap cycles
        through its colors in label order, a continuous one is sampled evenly; a VTK lookup
        table maps the label values. Without either (the default), the categorical palette
        assigned over the label adjacency, so that touching labels get clearly different colors
        (:meth:`SegmentationVolume.distinct_colors`); ``"hash"``: the renderer's hash of each
        label index (the default before the palette).
        With ``color_by``, the colormap of that column instead (a matplotlib colormap or name).
    opacity : float or dict, default: 1.0
        Opacity of every label, or ``{label value: opacity}``. 0 hides a label; values between
        0 and 1 let that share of the light pass the label's surface (path-traced transmission).
    hidden_labels : iterable of int, optional
        Label values not drawn.
    attributes : pandas.DataFrame, str or os.PathLike, optional
        Per-label attributes: a DataFrame with a ``label`` column (or indexed by label value,
        index name ``label``), or the path of a CSV file with a ``label`` column. It is joined
        on the label value with the volume's own label table (voxel counts, volume, bounds,
        ...; see :meth:`SegmentationVolume.label_table`); rows of labels the volume does not
        hold are left out (with a warning, except for tables from
        :func:`vtksvdag.read_label_table`, which may also be given as a path). Attribute
        columns must not be named like the computed ones (ValueError). A ``color`` column
        (RGB tuples in 0-1, or any color pyvista accepts) colors the labels that have one,
        unless ``cmap`` is given without ``color_by``; ``colors`` wins over it. A ``name``
        column is queried like any other (``query="name.str.contains('Hippocampus')"``).
        Default: the volume's ``label_metadata`` (from a ``.seg.nrrd`` or OME-Zarr file).
    color_by : str, optional
        A column of the joined table that colors the labels with ``cmap``: numbers on a
        continuous scale over the column's range (or ``clim``; default colormap viridis),
        anything else (strings, bools, categories) one color per category in sorted order
        (default tab10, or tab20 beyond 10 categories). Labels without a value get
        ``nan_color`` (default a neutral grey, 0.5 0.5 0.5). ``colors`` wins over it.
    clim : (float, float), optional
        With a numeric ``color_by`` column: the values mapped to the ends of the colormap
        (default: the column's range).
    nan_color : color, optional
        With ``color_by``: the color of labels without a value (default grey 0.5 0.5 0.5).
    query : str, optional
        A pandas query expression over the joined table (``"volume > 1e4 and type ==
        'pyramidal'"``): labels whose row does not satisfy it are hidden. Missing values (labels
        without a row or a value) follow pandas: a comparison with them is false, except ``!=``.
        ValueError for an expression pandas cannot evaluate (the message lists the columns).
    highlight : int or iterable of int, optional
        Labels drawn with an emissive tint (``highlight_color`` times ``highlight_intensity``).
    dim : float, optional
        While labels are highlighted, the other labels' base color is multiplied by ``dim``
        (in [0, 1]; default 1: not dimmed).
    highlight_color : color, optional
        The highlight's tint, any color pyvista accepts (default amber).
    highlight_intensity : float, optional
        The tint's radiance scale (default 1).
    others_opacity : float, optional
        While labels are highlighted, the other labels' opacity factor in [0, 1] (default 1;
        below 1 they are see-through, 0 hides them).
    lod : {"auto", "block", "leaf", "voxel"}, optional
        Level of detail of still frames (default ``"auto"``): ``"voxel"`` is lossless,
        ``"auto"`` is lossless too wherever a voxel covers more than a quarter of a pixel and
        draws leaf or block boxes only where they are below a pixel (faster on huge volumes).
        The names are ``vtkSegmentationSVDAGRenderSettings.GetLODName(i)``.
    shading : {"voxel", "smooth"}, optional
        Default ``"voxel"``.
        The normal surfaces are lit with: the voxel faces' (blocky), or ``"smooth"``, estimated
        from each label's occupancy around the hit point (no mesh; the hit stays the lossless
        voxel surface). Smooth uploads a neighbour table of 108 bytes per block.
    backend : {"auto", "rt", "compute"}, optional
        Default ``"auto"``.
        How rays find the label blocks: ``"rt"``, the ray tracing pipeline over a BVH of block
        boxes (needs a device with ray tracing); ``"compute"``, a compute shader walking the
        volume's grid of 16^3 cells (any Vulkan 1.2 device; no BVH, hiding labels rebuilds
        nothing); ``"auto"`` picks per device (compute on lavapipe, where it is several times
        faster, and on devices without ray tracing). The images are the same.
        ``actor.GetMapper().GetBackendInUse()`` tells which one runs.
    spp : int, optional
        Samples per pixel a still view refines to (1 .. 2**24; default 64, the mapper's
        ``TargetSamplesPerPixel``).
    samples_per_pass : int, optional
        Samples per pixel each render adds (1 .. 65536; default 1).
    bounces : int, optional
        Scattering events per path (0 .. 64; default 4).
    seed : int, optional
        Random seed (0 .. 2**32 - 1; default 0): the same seed and options give the same image.
    next_event_estimation : bool, optional
        Next-event estimation with multiple importance sampling (default True); False: light
        is found only where paths escape (same mean, slower to converge).
    denoise : bool, optional
        The label-aware denoiser (default True): an edge-avoiding filter guided by the traced
        label, depth and normal, which never mixes colors of different labels and fades out by
        itself as samples accumulate, so interactive one-sample frames look smooth and a
        converged image is left as it is.
    exposure : float, optional
        Scale of the linear color before the tone curve (1e-6 .. 1e6; default 1).
    sun : bool, sequence of 3 floats or dict, optional
        A sun light: ``True`` for the C++ default one (a hard-edged real-size sun), a direction
        towards the sun, a dict with ``direction``, ``irradiance`` and ``angular_radius``
        (degrees), or ``False`` for none. Default: the C++ default sun with an angular radius
        of ``DEFAULT_SUN_ANGULAR_RADIUS`` (4 degrees: soft shadows).
    environment : color or str, optional
        The environment light: a constant color, or the path of an equirectangular ``.exr`` map.
        Default: the sky ``DEFAULT_SKY``, a slightly blue constant (linear (0.55, 0.6, 0.7)).
    clipping_planes : sequence of (origin, normal), optional
        Up to 6 clipping planes in world coordinates (VTK's, after the actor's matrix), each
        keeping the side its normal points to. Every ray is clipped, so cut-away parts cast no
        shadow, and a cut through a label shows its cut face (at ``"block"`` / ``"leaf"`` LOD the
        cross-section of the block or leaf box). Later changes: the mapper's
        ``AddClippingPlane`` / ``RemoveAllClippingPlanes`` (``examples/clipping.py``).
    crop : sequence of 6 floats, optional
        ``(xmin, xmax, ymin, ymax, zmin, zmax)``: only what lies inside this axis-aligned box (the
        data's world coordinates, like ``vtkVolumeMapper``'s cropping planes) is drawn. Later
        changes: the mapper's ``SetCroppingRegionPlanes`` / ``SetCropping``.
    write_depth : bool, optional
        Write the volume's first opaque hit into the depth buffer (default True), so that
        meshes drawn later, picking and depth readers see the volume.
    auto_adjust : bool, optional
        Keep interactive frames within the plotter's update rate with a coarser LOD and
        resolution (default True).
    error_target : float, optional
        Stop refining a still view once its error estimate falls to this value (>= 0; default
        0: refine to ``spp``).
    name : str, optional
        Actor name (replaces an actor of the same name).
    reset_camera : bool, optional
        Reset the camera after adding; by default when the camera was not set yet, or was
        last set by this function and not moved since. The reset looks along pyvista's default
        direction and frames the voxels of the visible labels of every segmentation in the
        renderer (hidden and opacity-0 labels do not count), with the other visible props.
    scalars : str, optional
        ``pyvista.ImageData`` / vtkImageData input: the name of the point or cell data array
        holding the labels (see :func:`vtksvdag.from_image`: cell labels are the voxel grid
        itself, one voxel per cell). By default the active point scalars, else the active cell
        scalars. A ValueError for other inputs.
    spacing, origin : sequence of 3 floats, optional
        numpy input: the voxel size and the position of voxel (0, 0, 0), in x, y, z order
        (defaults those of :func:`vtksvdag.from_numpy`: 1 and 0). A ValueError for other
        inputs, which carry their own geometry.
    axis_order : {"xyz", "zyx"}, optional
        numpy input: ``array[x, y, z]`` (the default, pyvista's order) or ``array[z, y, x]``.
    cast : {None, "exact"}, optional
        Float labels (numpy arrays, images, and files and stores of every format
        :func:`vtksvdag.read` reads): refused by default; ``"exact"`` accepts them when every
        value is a whole number (see :func:`vtksvdag.from_numpy` and :func:`vtksvdag.read`).
    show_scalar_bar : bool, optional
        Add the label legend (:func:`vtksvdag.add_label_legend`: label names or values with
        their colors, visible labels first). Default False: unlike a continuous scalar bar, a
        legend of thousands of labels is rarely wanted. ``plotter.add_scalar_bar()`` works on a
        plotter whose only mapper is a segmentation too: a categorical bar of the same entries.

    Returns
    -------
    vtksvdag.actor.SegmentationActor
        The actor, a ``pyvista.Volume``; ``actor.GetMapper()`` is the
        ``vtkSegmentationSVDAGVolumeMapper``. Its methods ``set_query``, ``set_color_by`` and
        ``set_highlight`` change the options above after adding (a query change rebuilds the
        acceleration structure only, a color or highlight change uploads the materials only),
        and ``label_table`` is the joined table.

    Raises
    ------
    RuntimeError
        No usable Vulkan device (the message lists the devices found), or ``backend="rt"`` on
        a device without ray tracing.
    ValueError, TypeError
        An option is out of range or of the wrong type (the message names it and its accepted
        values); an unknown option is a TypeError that suggests the closest names. Float labels
        without ``cast="exact"`` are a ValueError.

    Examples
    --------
    >>> import pyvista as pv
    >>> import vtksvdag
    >>> plotter = pv.Plotter(off_screen=True)
    >>> actor = vtksvdag.add_segmentation(plotter, "examples/data/cells.nrrd", sun=True)  # doctest: +SKIP
    >>> vtksvdag.refine(plotter)  # doctest: +SKIP
    >>> image = plotter.screenshot()  # doctest: +SKIP
    """
    import pyvista as pv  # noqa: F401 (pyvista is required: fail before any work without it)

    check_cast(cast)

    from .vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper

    for value, what, lo, hi in ((spp, "spp", 1, 1 << 24), (bounces, "bounces", 0, 64),
                                (samples_per_pass, "samples_per_pass", 1, 65536),
                                (seed, "seed", 0, 2**32 - 1)):
        if value is None:
            continue
        if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not lo <= value <= hi:
            raise ValueError(f"{what} must be an integer in {lo} .. {hi}, got {value!r}")

    mapper = vtkSegmentationSVDAGVolumeMapper()
    settings = mapper.GetSettings()
    # The names are checked against the C++ class's list and set through its string setters.
    for value, setting, option in ((lod, "LOD", "lod"), (shading, "Shading", "shading"),
                                   (backend, "Backend", "backend")):
        if value is not None:
            set_by_name(settings, setting, value, option)
    if bounces is not None:
        settings.SetMaximumBounces(int(bounces))
    if samples_per_pass is not None:
        settings.SetSamplesPerPixel(int(samples_per_pass))
    if seed is not None:
        settings.SetSeed(int(seed))
    if spp is not None:
        mapper.SetTargetSamplesPerPixel(int(spp))
    if exposure is not None:
        value = float(exposure)
        if not (np.isfinite(value) and 1e-6 <= value <= 1e6):
            raise ValueError(f"exposure must be in [1e-6, 1e6], got {exposure!r}")
        settings.SetExposure(value)
    if next_event_estimation is not None:
        settings.SetNextEventEstimation(bool(next_event_estimation))
    if denoise is not None:
        settings.SetDenoise(bool(denoise))
    if write_depth is not None:
        mapper.SetWriteDepth(bool(write_depth))
    if auto_adjust is not None:
        mapper.SetAutoAdjustToRenderTime(bool(auto_adjust))
    if error_target is not None:
        target = float(error_target)
        if not (target >= 0 and np.isfinite(target)):
            raise ValueError(f"error_target must be a finite number >= 0, got {error_target!r}")
        mapper.SetErrorTarget(target)
    _apply_sun(settings, sun)
    _apply_environment(settings, environment)
    _apply_clipping(mapper, clipping_planes, crop)
    # The device before the volume: its pipelines compile on another thread while the volume is
    # read or built (most of a first image's wait where the driver compiles on the CPU).
    with vtk_errors_raised(mapper, RuntimeError):
        mapper.InitializeDevice()

    # The options are checked before the volume is built or read (the costly part).
    volume = _segmentation_volume(data, scalars=scalars, spacing=spacing, origin=origin,
                                  axis_order=axis_order, cast=cast)
    mapper.SetInputData(volume.dataobject)
    props = mapper.GetLabelProperties()
    # With color_by, cmap colors the column (below), not the labels in order.
    _apply_colors(props, volume, colors, None if color_by is not None else cmap)
    if hasattr(opacity, "items"):
        values = list(opacity)
        for key, value in zip(_label_keys(volume, values, "opacity label"), values):
            props.SetOpacity(key, _check_fraction(opacity[value], f"opacity of label {value}"))
    else:
        alpha = _check_fraction(opacity, "opacity")
        if alpha != 1.0:
            for key in _own_label_keys(volume):
                props.SetOpacity(key, alpha)
    if hidden_labels is not None:
        for key in _label_keys(volume, list(hidden_labels), "hidden label"):
            props.SetVisibility(key, False)
    style = _label_style(volume, props, attributes, colors, hidden_labels, color_by, cmap, clim,
                         nan_color, query, highlight, dim, highlight_color, highlight_intensity,
                         others_opacity)

    from .actor import SegmentationActor

    actor = SegmentationActor()
    actor.SetMapper(mapper)
    # Keep the Python wrapper (and so the SegmentationVolume) alive as long as the actor.
    actor._vtksvdag_volume = volume
    actor._vtksvdag_style = style
    renderer = plotter.renderer
    if reset_camera is None:
        # Not `not renderer.actors`: pyvista puts a border actor in every subplot. A camera
        # this glue framed (and nobody moved since) is framed again for the new volume.
        reset_camera = not renderer.camera_set or _camera_state(renderer) == getattr(
            renderer, "_vtksvdag_framed", None)
    # The legend and the scalar bar find their plotter through the actor (no cycle: a weak
    # reference).
    actor._vtksvdag_plotter = weakref.ref(plotter)
    plotter.add_actor(actor, name=name, reset_camera=False)
    if reset_camera:
        _frame_visible(renderer)
    # Nobody watches an off-screen plotter's frames: each still render is refined to spp before
    # it returns, so show(), screenshot() and VTK's window capture see the refined image.
    mapper.SetRefineStillRenders(bool(getattr(plotter, "off_screen", False)))
    if plotter.mapper is None:
        # pyvista's add_scalar_bar() reads plotter.mapper, which add_actor does not set: a
        # mapper of the label legend's entries as a categorical lookup table (a mesh added later
        # replaces it, as one added before keeps its own).
        from .legend import LabelLegendMapper

        plotter.mapper = LabelLegendMapper(actor)
    if show_scalar_bar:
        from .legend import add_label_legend

        add_label_legend(actor)
    _enable_refinement(plotter)
    _refine_before_screenshots(plotter)
    return actor


def _camera_state(renderer):
    camera = renderer.GetActiveCamera()
    return (camera.GetPosition(), camera.GetFocalPoint(), camera.GetViewUp(),
            camera.GetViewAngle(), camera.GetParallelScale())


def _visible_label_bounds(actor):
    """World bounds (after the actor's matrix) of the voxels of the visible labels of a
    segmentation actor (visible and opacity > 0), or None when none is."""
    volume = actor._vtksvdag_volume
    props = actor.GetMapper().GetLabelProperties()
    keys = _own_label_keys(volume)
    visible = np.array([props.GetVisibility(k) and props.GetOpacity(k) > 0 for k in keys], bool)
    if not visible.any():
        return None
    boxes = volume.label_bounds[visible]
    # Voxel (i, j, k) is the box [i, i + 1] of index space, centered on its point in world.
    lo, hi = boxes[:, 0::2].min(axis=0), boxes[:, 1::2].max(axis=0) + 1
    corners = np.array([[(hi if c >> a & 1 else lo)[a] for a in range(3)] for c in range(8)], float)
    frame = np.asarray(volume.direction, float).reshape(3, 3) * np.asarray(volume.spacing, float)
    world = np.asarray(volume.origin, float) + (corners - 0.5) @ frame.T
    matrix = np.array([[actor.GetMatrix().GetElement(r, c) for c in range(4)] for r in range(4)])
    world = world @ matrix[:3, :3].T + matrix[:3, 3]
    return np.ravel([world.min(axis=0), world.max(axis=0)], order="F")


def _frame_visible(renderer):
    """Point the camera the way pyvista's first render would (its theme's direction), framing
    the visible labels of every segmentation in the renderer and the other visible props."""
    boxes = []
    for actor in renderer.actors.values():
        if not actor.GetVisibility() or not actor.IsA("vtkProp3D"):
            continue
        if hasattr(actor, "_vtksvdag_volume"):
            box = _visible_label_bounds(actor)
        else:
            box = actor.GetBounds() if actor.GetUseBounds() else None
        if box is not None and np.all(np.isfinite(box)) and box[0] <= box[1]:
            boxes.append(np.asarray(box, float))
    if not boxes:
        renderer.reset_camera()
        return
    boxes = np.array(boxes)
    bounds = np.ravel([boxes[:, 0::2].min(axis=0), boxes[:, 1::2].max(axis=0)], order="F")
    renderer.camera_position = renderer.get_default_cam_pos()
    renderer.ResetCamera(*bounds)
    renderer._vtksvdag_framed = _camera_state(renderer)


def _label_style(volume, props, attributes, colors, hidden_labels, color_by, cmap, clim, nan_color,
                 query, highlight, dim, highlight_color, highlight_intensity, others_opacity):
    """The attribute table, color column, query and highlight of add_segmentation, applied."""
    from ._attributes import NAN_COLOR, LabelStyle

    explicit = {}
    if colors is not None:
        values = list(colors)
        explicit = {k: _rgb(colors[v]) for k, v in zip(_label_keys(volume, values, "colors label"), values)}
    hidden = _label_keys(volume, list(hidden_labels), "hidden label") if hidden_labels is not None else []
    # A volume read with label metadata (.seg.nrrd, OME-Zarr) is named and colored by it
    # unless attributes are given; checked lazily: it came from the file, not from the caller.
    metadata = getattr(volume, "label_metadata", None) if attributes is None else None
    style = LabelStyle(volume, props, attributes=attributes if metadata is None else metadata,
                       colors=explicit, hidden=hidden, check=metadata is None)
    if cmap is None or color_by is not None:
        # The table's colors are the labels' own: an explicit cmap (without color_by) recolors
        # every label instead; colors= wins over both.
        style.use_color_column()
    if color_by is not None:
        nan = _rgb(nan_color) if nan_color is not None else NAN_COLOR
        style.set_color_by(color_by, cmap=cmap, clim=clim, nan_color=nan)
    if query is not None:
        style.set_query(query)
    if any(v is not None for v in (highlight, dim, highlight_color, highlight_intensity,
                                   others_opacity)):
        style.set_highlight(highlight, dim=dim,
                            color=None if highlight_color is None else _rgb(highlight_color),
                            intensity=highlight_intensity, others_opacity=others_opacity)
    return style


def _segmentation_mappers(plotter):
    """(renderer, mapper) of every segmentation volume in the plotter."""
    from .vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper

    found = []
    for renderer in plotter.renderers:
        volumes = renderer.GetVolumes()
        volumes.InitTraversal()
        for _ in range(volumes.GetNumberOfItems()):
            mapper = volumes.GetNextVolume().GetMapper()
            if isinstance(mapper, vtkSegmentationSVDAGVolumeMapper):
                found.append((renderer, mapper))
    return found


def _enable_refinement(plotter):
    """While the view is still, re-render on a timer until every segmentation has converged.

    The timer starts with the interactor (``show()`` of an on-screen plotter); off-screen
    plotters refine with :func:`refine`.
    """
    if getattr(plotter, "_vtksvdag_refining", False) or plotter.iren is None:
        return
    plotter._vtksvdag_refining = True
    state = {"timer": None}

    def on_timer(interactor, _event):
        style = interactor.GetInteractorStyle()
        interacting = style is not None and style.GetState() != 0
        if interacting:
            return
        if any(not mapper.IsConverged() for _, mapper in _segmentation_mappers(plotter)):
            plotter.render_window.Render()

    def on_render(*_args):
        interactor = plotter.iren.interactor if plotter.iren is not None else None
        if interactor is None or state["timer"] is not None or not interactor.GetInitialized():
            return
        state["timer"] = interactor.CreateRepeatingTimer(30)

    plotter.iren.interactor.AddObserver("TimerEvent", on_timer)
    plotter.add_on_render_callback(on_render, render_event=False)


def _refine_before_screenshots(plotter):
    """Make ``plotter.screenshot()`` (which ``show(screenshot=...)`` and pyvista's closing capture
    call) and ``plotter.save_graphic()`` (whose PDF/EPS/PS output holds the 3-D props as a raster
    of the window) refine every segmentation first: an on-screen plotter refines progressively
    while it is shown, and a capture after it was shown would otherwise keep what it had reached.

    pyvista has no hook before a capture, so these plotter methods are wrapped, once.
    """
    if getattr(plotter, "_vtksvdag_screenshot_refines", False):
        return
    plotter._vtksvdag_screenshot_refines = True

    def refining(capture):
        @functools.wraps(capture)
        def refined_capture(*args, **kwargs):
            # Before the first render pyvista renders itself (and placed the camera only then);
            # a closed plotter returns its last image.
            if plotter.render_window is not None and not getattr(plotter, "_first_time", True):
                refine(plotter)
            return capture(*args, **kwargs)

        return refined_capture

    for name in ("screenshot", "save_graphic"):
        if hasattr(plotter, name):
            setattr(plotter, name, refining(getattr(plotter, name)))


@_keywords_checked
def refine(plotter, timeout=60.0):
    """Render until every segmentation in the plotter has converged, or ``timeout`` seconds.

    Parameters
    ----------
    plotter : pyvista.Plotter
        A plotter with segmentations added by :func:`add_segmentation`.
    timeout : float, default: 60.0
        Seconds after which refinement stops.

    Returns
    -------
    list of dict
        Per segmentation: ``samples`` (per pixel), ``error`` (the error estimate: root mean
        square standard error of the pixel luminances), ``seconds`` (of tracing) and
        ``converged``.

    Examples
    --------
    >>> stats = vtksvdag.refine(plotter, timeout=10)  # doctest: +SKIP
    >>> stats[0]["samples"]  # doctest: +SKIP
    64
    """
    if not (isinstance(timeout, numbers.Real) and timeout > 0):
        raise ValueError(f"timeout must be a number > 0, got {timeout!r}")
    mappers = _segmentation_mappers(plotter)
    start = time.perf_counter()
    # Before its first show or screenshot, a plotter still has to put its cameras in their
    # default place (pyvista does it on the first render request); refining at another view
    # would be lost.
    first_render = getattr(plotter, "_on_first_render_request", None)
    if first_render is not None:
        first_render()
    with vtk_errors_raised([m for _, m in mappers], RuntimeError):
        plotter.render()
        while any(not m.IsConverged() for _, m in mappers) and time.perf_counter() - start < timeout:
            plotter.render()
    return [
        {
            "samples": m.GetAccumulatedSamples(),
            "error": m.GetErrorEstimate(),
            "seconds": m.GetRenderSeconds(),
            "converged": bool(m.IsConverged()),
        }
        for _, m in mappers
    ]


@_keywords_checked
def pick(plotter, x, y):
    """The segmentation label under a display pixel of the last rendered frame.

    Parameters
    ----------
    plotter : pyvista.Plotter
    x, y : float
        Display coordinates as VTK's: pixels, origin at the bottom left of the window.

    Returns
    -------
    dict or None
        ``{"label": value, "position": (x, y, z), "normal": (nx, ny, nz),
        "shading_normal": (sx, sy, sz)}`` in world coordinates for the nearest segmentation
        hit, or ``None`` on background: ``normal`` is the entered voxel face's, ``shading_normal``
        the one the frame was lit with (the same with ``shading="voxel"``, the smooth estimate
        with ``shading="smooth"``).

    Raises
    ------
    TypeError
        ``x`` or ``y`` is not a number.
    ValueError
        ``x`` or ``y`` is not finite, or lies outside the window (0 <= x < width,
        0 <= y < height): ``None`` means background, not a pixel that does not exist.

    Examples
    --------
    >>> hit = vtksvdag.pick(plotter, 150, 120)  # doctest: +SKIP
    >>> hit["label"]  # doctest: +SKIP
    7
    """
    width, height = plotter.render_window.GetSize() if plotter.render_window is not None else (
        plotter.window_size)
    for value, what, size in ((x, "x", width), (y, "y", height)):
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise TypeError(f"{what} must be a number (display pixels), got {value!r}")
        if not (np.isfinite(value) and 0 <= value < size):
            raise ValueError(f"{what} must be a display coordinate in [0, {size}) (the window "
                             f"is {width} x {height} pixels, origin bottom left), got {value!r}")
    best = None
    for renderer, mapper in _segmentation_mappers(plotter):
        if not mapper.Pick(renderer, float(x), float(y)):
            continue
        position = [0.0, 0.0, 0.0]
        normal = [0.0, 0.0, 0.0]
        shading_normal = [0.0, 0.0, 0.0]
        mapper.GetPickedPosition(position)
        mapper.GetPickedNormal(normal)
        mapper.GetPickedShadingNormal(shading_normal)
        camera = np.array(renderer.GetActiveCamera().GetPosition())
        distance = float(np.linalg.norm(np.array(position) - camera))
        if best is None or distance < best[0]:
            # The mapper names labels by their 64-bit pattern as an int64.
            value = np.array(mapper.GetPickedLabel(), dtype=np.int64).astype(_label_dtype(mapper))
            best = (distance, {"label": value.item(), "position": tuple(position),
                               "normal": tuple(normal), "shading_normal": tuple(shading_normal)})
    return None if best is None else best[1]


def _label_dtype(mapper):
    return numpy_dtype_of_vtk_type(mapper.GetInput().GetLabelScalarType())
