"""pyvista glue: path-trace a segmentation in a ``pyvista.Plotter``, refine it, pick labels.

The volume is drawn by ``vtkSegmentationSVDAGVolumeMapper`` inside the plotter's own render
window, depth-composited with every mesh in the scene.
"""
import difflib
import functools
import inspect
import numbers
import os
import time

import numpy as np

from ._colors import to_rgb as _rgb
from ._labels import label_pattern, numpy_dtype_of_vtk_type
from ._settingnames import set_by_name
from ._vtkrun import vtk_errors_raised
from .build import from_image, from_numpy
from .fileio import read
from .volume import SegmentationVolume

# pyvista and the rendering module are imported where they are used: the rest of the package
# works without them (a machine without Vulkan, a script that only compresses).


def _keywords_checked(function):
    """Makes an unknown keyword argument of ``function`` a TypeError that suggests the closest
    option names (difflib), instead of Python's bare "unexpected keyword argument"."""
    parameters = inspect.signature(function).parameters

    @functools.wraps(function)
    def checked(*args, **kwargs):
        unknown = sorted(set(kwargs) - set(parameters))
        if unknown:
            hints = []
            for option in unknown:
                close = difflib.get_close_matches(option, parameters, n=3)
                hints.append(f"{option!r}" + (f" (did you mean {' or '.join(map(repr, close))}?)"
                                              if close else ""))
            raise TypeError(f"{function.__name__}() got unknown options: {', '.join(hints)}")
        return function(*args, **kwargs)

    return checked


def _segmentation_volume(data):
    """A SegmentationVolume from any of the inputs add_segmentation accepts."""
    if isinstance(data, SegmentationVolume):
        return data
    if isinstance(data, (str, bytes, os.PathLike)):
        return read(data)
    if isinstance(data, np.ndarray):
        return from_numpy(data)
    if hasattr(data, "IsA") and data.IsA("vtkImageData"):
        return from_image(data)
    raise TypeError(
        "data must be a SegmentationVolume, a file path, a numpy label array or a "
        f"pyvista.ImageData / vtkImageData, not {type(data).__name__}"
    )


def _check_fraction(value, what):
    if not isinstance(value, numbers.Real) or not 0 <= float(value) <= 1:
        raise ValueError(f"{what} must be a number in [0, 1], got {value!r}")
    return float(value)


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


def _apply_colors(props, volume, colors, cmap):
    if cmap is not None:
        if hasattr(cmap, "IsA") and cmap.IsA("vtkScalarsToColors"):
            props.SetLookupTable(cmap)
        else:
            import matplotlib

            colormap = matplotlib.colormaps[cmap] if isinstance(cmap, str) else cmap
            n = len(volume.labels)
            # Categorical: listed colormaps cycle their colors, continuous ones are sampled evenly.
            count = getattr(colormap, "N", 256)
            for index, key in enumerate(_label_keys(volume, volume.labels.tolist(), "label")):
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


def _apply_sun(settings, sun):
    if sun is None or sun is False:
        settings.SetSun(False)
        return
    settings.SetSun(True)
    if sun is True:
        return
    if hasattr(sun, "items"):
        unknown = set(sun) - {"direction", "irradiance", "angular_radius"}
        if unknown:
            raise TypeError(f"unknown sun options {sorted(unknown)} (direction, irradiance, angular_radius)")
        direction = sun.get("direction")
        if "irradiance" in sun:
            irradiance = np.broadcast_to(np.asarray(sun["irradiance"], float), (3,))
            if not np.all(np.isfinite(irradiance)) or np.any(irradiance < 0):
                raise ValueError("the sun irradiance must be finite and >= 0")
            settings.SetSunIrradiance(*irradiance)
        if "angular_radius" in sun:
            radius = float(sun["angular_radius"])
            if not 0 <= radius <= 89.9:
                raise ValueError(f"the sun's angular radius must be in [0, 89.9] degrees, got {radius}")
            settings.SetSunAngularRadius(radius)
    else:
        direction = sun
    if direction is not None:
        d = np.asarray(direction, float)
        if d.shape != (3,) or not np.all(np.isfinite(d)) or not np.any(d):
            raise ValueError(f"the sun direction must be 3 finite numbers, not all 0, got {direction!r}")
        settings.SetSunDirection(*d)


def _apply_environment(settings, environment):
    if environment is None:
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
):
    """Add a path-traced segmentation volume to a ``pyvista.Plotter``.

    The volume is path-traced with Vulkan (a GPU, or Mesa's lavapipe on the CPU) and
    composited with the plotter's meshes by depth. While the view is still, each render adds
    samples until ``spp`` samples per pixel (see :func:`refine`); while the user interacts,
    frames keep to the plotter's update rate with a coarser LOD and resolution.

    Options left at ``None`` keep the default of the VTK object they set
    (``vtkSegmentationSVDAGRenderSettings`` for the path tracer, whose defaults are the C++ core's,
    or ``vtkSegmentationSVDAGVolumeMapper``); the defaults named below are those. An unknown
    option is a TypeError that suggests the closest names.

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
        table maps the label values. Without either, colors come from a hash of each label.
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
    exposure : float, optional
        Scale of the linear color before the tone curve (1e-6 .. 1e6; default 1).
    sun : bool, sequence of 3 floats or dict, optional
        A sun light: ``True`` for the default one, a direction towards the sun, or a dict with
        ``direction``, ``irradiance`` and ``angular_radius`` (degrees).
    environment : color or str, optional
        The environment light: a constant color, or the path of an equirectangular ``.exr`` map.
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
        Reset the camera after adding; by default only when it is the first actor.

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
        An option is out of range or of the wrong type; TypeError for an unknown option.

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

    # The options are checked before the volume is built or read (the costly part).
    volume = _segmentation_volume(data)
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
            for key in _label_keys(volume, volume.labels.tolist(), "label"):
                props.SetOpacity(key, alpha)
    if hidden_labels is not None:
        for key in _label_keys(volume, list(hidden_labels), "hidden label"):
            props.SetVisibility(key, False)
    style = _label_style(volume, props, attributes, colors, hidden_labels, color_by, cmap, clim,
                         nan_color, query, highlight, dim, highlight_color, highlight_intensity,
                         others_opacity)

    with vtk_errors_raised(mapper, RuntimeError):
        mapper.InitializeDevice()

    from .actor import SegmentationActor

    actor = SegmentationActor()
    actor.SetMapper(mapper)
    # Keep the Python wrapper (and so the SegmentationVolume) alive as long as the actor.
    actor._vtksvdag_volume = volume
    actor._vtksvdag_style = style
    if reset_camera is None:
        # Not `not renderer.actors`: pyvista puts a border actor in every subplot.
        reset_camera = not plotter.renderer.camera_set
    plotter.add_actor(actor, name=name, reset_camera=bool(reset_camera))
    _enable_refinement(plotter)
    return actor


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

    Examples
    --------
    >>> hit = vtksvdag.pick(plotter, 150, 120)  # doctest: +SKIP
    >>> hit["label"]  # doctest: +SKIP
    7
    """
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
