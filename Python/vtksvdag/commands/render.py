"""``vtksvdag render INPUT -o OUT.png|OUT.exr``: path-trace a segmentation volume to an image.

The camera frames the whole volume (like VTK's ResetCamera, then an orbit by --azimuth and
--elevation and a dolly by --zoom). The image accumulates --spp passes of one sample per pixel;
``ms_per_frame`` is the mean time of one such pass (without the first, which includes the
driver's shader compilation, when there are several). PNG holds the tone-mapped color, EXR the
linear color with depth (Z) and label channels.
"""
import argparse
import math
import sys
import time

import numpy as np

from .. import _settingnames
from .._attributes import add_render_arguments as add_attribute_arguments
from .._attributes import apply_render_options as apply_attribute_options
from .._vtkrun import vtk_errors_raised
from ._common import (
    add_input_options, finite_float, int_in, label_value, load, output_path, print_json,
    print_table,
)

NAME = "render"
HELP = "path-trace a label volume or .svdag file to a PNG or EXR image (Vulkan)"



def _default_settings():
    """A new vtkSegmentationSVDAGRenderSettings (it holds the C++ defaults), or None where the
    rendering module cannot load (then the options take any value and only this command fails,
    when it runs)."""
    try:
        from ..vtkSVDAGRendering import vtkSegmentationSVDAGRenderSettings
    except ImportError:
        return None
    return vtkSegmentationSVDAGRenderSettings()


def _named_setting(setting, defaults):
    """argparse keywords of a named setting: the C++ class's names and default."""
    if defaults is None:
        return {"choices": None, "default": None}
    return {"choices": _settingnames.names(setting),
            "default": getattr(defaults, f"Get{setting}AsString")()}


#: Ranges of the numeric options (the renderer would clamp the image size silently).
MAX_SIZE = 16384
MAX_SPP = 65536
MAX_BOUNCES = 64


def add_arguments(parser):
    defaults = _default_settings()
    parser.add_argument("input", metavar="INPUT", help="label volume file or .svdag file")
    parser.add_argument("-o", "--output", required=True, type=output_path((".png", ".exr"), "render"),
                        metavar="OUT.png|OUT.exr", help="output image")
    add_input_options(parser)
    parser.add_argument("--width", type=int_in(1, MAX_SIZE), default=512,
                        help=f"pixels, 1-{MAX_SIZE} (default: 512)")
    parser.add_argument("--height", type=int_in(1, MAX_SIZE), default=512,
                        help=f"pixels, 1-{MAX_SIZE} (default: 512)")
    parser.add_argument("--spp", type=int_in(1, MAX_SPP), default=16,
                        help=f"samples per pixel, one per pass, 1-{MAX_SPP} (default: 16)")
    parser.add_argument("--bounces", type=int_in(0, MAX_BOUNCES),
                        default=defaults.GetMaximumBounces() if defaults else None,
                        help=f"maximum bounces, 0-{MAX_BOUNCES} (default: %(default)s)")
    parser.add_argument("--lod", **_named_setting("LOD", defaults),
                        help="level of detail (default: %(default)s)")
    parser.add_argument("--backend", **_named_setting("Backend", defaults),
                        help="how rays find the blocks: the ray tracing pipeline (rt), a compute "
                             "shader walking the cell grid (compute), or per device (auto) "
                             "(default: %(default)s)")
    parser.add_argument("--shading", **_named_setting("Shading", defaults),
                        help="normals for lighting: voxel faces, or smooth ones estimated from the "
                             "label occupancy (no mesh; the hits stay the voxels) "
                             "(default: %(default)s)")
    parser.add_argument("--seed", type=int_in(0, 2**32 - 1),
                        default=defaults.GetSeed() if defaults else None,
                        help=f"random seed, 0-{2**32 - 1} (default: %(default)s)")
    parser.add_argument("--azimuth", type=finite_float(), default=30.0,
                        help="camera orbit, degrees (default: 30)")
    parser.add_argument("--elevation", type=finite_float(), default=20.0,
                        help="camera orbit, degrees (default: 20)")
    parser.add_argument("--zoom", type=finite_float(0.0, exclusive=True), default=1.0,
                        help="dolly factor > 0 (default: 1)")
    parser.add_argument("--hide", type=label_value, nargs="+", default=[], metavar="LABEL",
                        help="label VALUES left out of the image")
    parser.add_argument("--no-nee", action="store_true",
                        help="no next-event estimation (light only where paths escape)")
    parser.add_argument("--denoise", action=argparse.BooleanOptionalAction, default=None,
                        help="the label-aware denoiser on the image (default: on; it fades out "
                             "as samples accumulate)")
    parser.add_argument("--environment", metavar="EXR", help="equirectangular OpenEXR environment map")
    parser.add_argument("--sun", type=finite_float(), nargs=2, metavar=("AZ", "EL"),
                        help="a sun at azimuth AZ (degrees from +x towards +y) and elevation EL "
                             "(degrees above the xy plane, +z up)")
    parser.add_argument("--sky", type=finite_float(0.0), nargs=3, metavar=("R", "G", "B"),
                        help="constant environment radiance, finite and >= 0 (default: 1 1 1, or a "
                             "dim 0.25 0.27 0.3 sky with --sun so that the sun shapes the image)")
    add_attribute_arguments(parser)
    parser.add_argument("--clip", type=_clip_plane, action="append", default=[],
                        metavar="OX,OY,OZ,NX,NY,NZ",
                        help="a clipping plane (world): origin and normal, keeping the side the "
                             "normal points to; repeatable, up to the renderer's limit of 6")
    parser.add_argument("--crop", type=_crop_box, metavar="XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX",
                        help="draw only what lies inside this axis-aligned box (world)")
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    parser.add_argument("--no-progress", action="store_true", help="(no progress bar is shown)")


def _numbers(text, count, what):
    parts = text.split(",")
    try:
        values = [float(p) for p in parts]
    except ValueError:
        values = []
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise argparse.ArgumentTypeError(f"{what} must be {count} finite numbers separated by commas, got {text!r}")
    return values


def _clip_plane(text):
    """argparse type of --clip: OX,OY,OZ,NX,NY,NZ with a non-zero normal."""
    values = _numbers(text, 6, "--clip")
    if not any(values[3:]):
        raise argparse.ArgumentTypeError(f"--clip: the normal must not be zero, got {text!r}")
    return values


def _crop_box(text):
    """argparse type of --crop: XMIN,XMAX,YMIN,YMAX,ZMIN,ZMAX with min <= max."""
    values = _numbers(text, 6, "--crop")
    for axis, lo, hi in zip("xyz", values[0::2], values[1::2]):
        if lo > hi:
            raise argparse.ArgumentTypeError(f"--crop: inverted along {axis} (min {lo:g} > max {hi:g})")
    return values


def _fail(message):
    """One line for the command line's error format."""
    return " ".join(message.split())


def run(args):
    # Imported here: the other commands must work where the rendering module cannot load.
    try:
        from ..vtkSVDAGRendering import vtkSegmentationSVDAGRenderer
        from vtkmodules.vtkCommonDataModel import vtkPlane
    except ImportError as error:
        print(f"vtksvdag: error: the rendering module cannot be loaded: {_fail(str(error))}",
              file=sys.stderr)
        return 1

    volume = load(args, args.input)
    values = {int(v) for v in volume.labels}  # exact: numpy compares uint64 with int via float
    for value in args.hide:
        if value not in values:
            raise ValueError(f"--hide: label {value} is not in the volume")

    renderer = vtkSegmentationSVDAGRenderer()

    def check(call, what):
        try:
            # The executive's "returned failure" message only repeats that the pass failed.
            with vtk_errors_raised([renderer, renderer.GetExecutive(), settings], RuntimeError):
                ok = call()
        except RuntimeError as error:
            detail = str(error)
            if "devices found" in detail:
                detail = "no usable Vulkan device: " + detail
            raise RuntimeError(_fail(f"{what}: {detail}")) from None
        if not ok:
            raise RuntimeError(_fail(f"{what}: unknown error"))

    renderer.SetInputData(volume.dataobject)
    renderer.SetWidth(args.width)
    renderer.SetHeight(args.height)
    settings = renderer.GetSettings()
    # The C++ string setters; argparse checked the names against the C++ class's list.
    settings.SetLOD(args.lod)
    settings.SetBackend(args.backend)
    settings.SetShading(args.shading)
    settings.SetMaximumBounces(args.bounces)
    settings.SetSeed(args.seed)
    settings.SetNextEventEstimation(not args.no_nee)
    if args.denoise is not None:
        settings.SetDenoise(args.denoise)
    settings.SetSamplesPerPixel(1)
    if args.environment:
        settings.SetEnvironmentMap(args.environment)
    sky = args.sky if args.sky else ((0.25, 0.27, 0.3) if args.sun else (1.0, 1.0, 1.0))
    settings.SetEnvironmentColor(*sky)
    if args.sun:
        az, el = (math.radians(a) for a in args.sun)
        settings.SunOn()
        settings.SetSunDirection(math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el))
    most = renderer.GetMaximumNumberOfClippingPlanes()
    if len(args.clip) > most:
        raise ValueError(f"--clip: at most {most} clipping planes, got {len(args.clip)}")
    for values in args.clip:
        plane = vtkPlane()
        plane.SetOrigin(*values[:3])
        plane.SetNormal(*values[3:])
        renderer.AddClippingPlane(plane)
    if args.crop:
        renderer.SetCroppingRegionPlanes(*args.crop)
        renderer.CroppingOn()
    for value in args.hide:
        # A uint64 label of 2^63 or more is named by the int64 with the same bits.
        renderer.GetLabelProperties().SetVisibility(value - 2 ** 64 if value >= 2 ** 63 else value, False)
    # --attributes, --color-by, --query, --highlight, --dim (ValueError names the option).
    style = apply_attribute_options(args, volume, renderer.GetLabelProperties(), args.hide)
    try:
        check(lambda: renderer.ResetCamera(args.azimuth, args.elevation, args.zoom), "camera")
        start = time.perf_counter()
        # All passes in one execution: the denoiser filters only the last, the one written.
        renderer.SetPassesPerRender(args.spp)
        check(renderer.Render, "render")
        pass_ms = [renderer.GetPassMilliseconds(i) for i in range(args.spp)]
        wall = time.perf_counter() - start
        check(lambda: renderer.WriteImage(args.output), "write")
    except RuntimeError as error:
        print(f"vtksvdag: error: {error}", file=sys.stderr)
        return 1

    timed = pass_ms[1:] if len(pass_ms) > 1 else pass_ms
    result = {
        "input": args.input,
        "output": args.output,
        "device": renderer.GetDeviceName(),
        "width": args.width,
        "height": args.height,
        "spp": renderer.GetAccumulatedSamples(),
        "bounces": settings.GetMaximumBounces(),
        "nee": not args.no_nee,
        "denoise": settings.GetDenoise(),
        "seed": settings.GetSeed(),
        "lod": settings.GetLODAsString(),
        "backend": renderer.GetBackendInUse(),
        "shading": settings.GetShadingAsString(),
        "setup_seconds": renderer.GetSetupSeconds(),
        "render_seconds": renderer.GetRenderSeconds(),
        "wall_seconds": wall,
        "ms_per_frame": float(np.mean(timed)),
        "bytes_blas": renderer.GetBLASBytes(),
        "bytes_tlas": renderer.GetTLASBytes(),
        "bytes_neighbour_table": renderer.GetNeighbourTableBytes(),
        # Device memory by part: encoding (block and DAG streams), acceleration (BLAS + TLAS +
        # primitive map, or the compute backend's cell grid), materials, images, and the total.
        "bytes_device": {
            "encoding": renderer.GetEncodingBytes(),
            "acceleration": renderer.GetAccelerationBytes(),
            "materials": renderer.GetMaterialBytes(),
            "images": renderer.GetImageBytes(),
            "total": renderer.GetDeviceBytes(),
        },
        "hidden_labels": args.hide,
        "clip": args.clip,
        "crop": args.crop,
    }
    if style is not None:
        result["visible_labels"] = [v for v, k in zip(style.values, style.keys)
                                    if renderer.GetLabelProperties().GetVisibility(k)]
        result["highlighted_labels"] = style.highlighted
    if args.json:
        print_json(result)
    else:
        print_table([
            ("input", args.input),
            ("device", result["device"]),
            ("image", f"{args.width} x {args.height}, {result['spp']} spp, LOD {result['lod']}, "
                      f"{result['shading']} shading, "
                      f"{result['bounces']} bounces, NEE {'on' if result['nee'] else 'off'}, "
                      f"denoiser {'on' if result['denoise'] else 'off'}"),
            ("backend", result["backend"]),
            ("setup", f"{result['setup_seconds']:.3f} s (upload + "
                      f"{'BVH' if result['backend'] == 'rt' else 'cell grid'})"),
            ("render", f"{result['render_seconds']:.3f} s ({result['ms_per_frame']:.1f} ms per pass)"),
            ("device bytes", ", ".join(f"{k} {v:,}" for k, v in result["bytes_device"].items())),
            ("output", args.output),
        ])
    return 0
