"""pvbatch / pvpython side of Testing/Python/test_paraview.py: builds the plugin's pipelines in
ParaView and writes what ParaView reports into OUT (results.json, PNG screenshots, slice.npy),
for the test to check against vtksvdag (which runs on Debian's VTK, not ParaView's).

    pvbatch pv_scene.py --plugin vtkSVDAG.so --file cells.nrrd --svdag cells.svdag --out DIR
    pvpython pv_scene.py ... --connect PORT     (client-server: pvserver on 127.0.0.1:PORT)
    mpiexec -n 2 pvbatch --symmetric pv_scene.py ... --image-only --pieces

The view and the render settings are fixed here (SIZE, CAMERA_*) so that every session kind
renders the same image.
"""
import argparse
import json
import os

from paraview import servermanager
from paraview.simple import (Connect, CreateView, GetColorTransferFunction, Hide, LoadPlugin,
                             OpenDataFile, Render, ResetCamera, SaveScreenshot, Show)
import paraview.simple as simple

SIZE = (240, 200)
STEP = 8  # pick every STEP-th pixel in x and y
# The representation's properties whose XML defaults must be the C++ defaults.
DEFAULTS = ("LOD", "Backend", "Shading", "SamplesPerPixel", "TargetSamplesPerPixel",
            "MaximumBounces", "Exposure", "RefineTimeLimit")
CAMERA_DIRECTION = (-1.0, -0.7, -0.5)  # from the focal point towards the camera is its negative


def field_numbers(proxy):
    proxy.UpdatePipeline()
    fields = proxy.GetDataInformation().DataInformation.GetFieldDataInformation()
    numbers = {}
    for name in ("LabelCount", "CompressedBytes", "BitsPerVoxel"):
        info = fields.GetArrayInformation(name)
        numbers[name] = None if info is None else info.GetComponentRange(0)[0]
    return numbers


def plain(value):
    """A property's single value as a JSON type."""
    if not isinstance(value, (str, int, float)):
        value = value[0]
    return value if isinstance(value, str) else float(value)


PICKERS = {}  # display's global id -> its picker


def picker_for(display):
    """The documented pick: a misc/SegmentationPicker on the display (one per display)."""
    key = display.GetGlobalIDAsString()
    if key not in PICKERS:
        PICKERS[key] = servermanager.misc.SegmentationPicker(Representation=display)
    return PICKERS[key]


def pick(display, x, y):
    """PickPixel, then the information properties PickedHit and PickedLabel."""
    picker = picker_for(display)
    picker.PickPixel = [x, y]
    picker.UpdatePropertyInformation()
    if not picker.GetProperty("PickedHit")[0]:
        return None
    return int(picker.GetProperty("PickedLabel")[0])


def pick_grid(display):
    return [[x, y, pick(display, x + 0.5, y + 0.5)]
            for y in range(STEP // 2, SIZE[1], STEP) for x in range(STEP // 2, SIZE[0], STEP)]


def camera_of(view):
    camera = view.GetActiveCamera()
    return {
        "position": list(camera.GetPosition()),
        "focal_point": list(camera.GetFocalPoint()),
        "view_up": list(camera.GetViewUp()),
        "view_angle": camera.GetViewAngle(),
        "clipping_range": list(camera.GetClippingRange()),
        "size": list(SIZE),
    }


def set_up_view(view, display, bounces):
    view.ViewSize = list(SIZE)
    view.OrientationAxesVisibility = 0
    view.Background = [0.1, 0.1, 0.12]
    try:
        view.UseColorPaletteForBackground = 0
    except AttributeError:
        pass
    ResetCamera(view)
    camera = view.GetActiveCamera()
    focal = camera.GetFocalPoint()
    distance = camera.GetDistance()
    norm = sum(c * c for c in CAMERA_DIRECTION) ** 0.5
    camera.SetPosition(*[f - distance * c / norm for f, c in zip(focal, CAMERA_DIRECTION)])
    camera.SetViewUp(0, 0, 1)
    view.CameraParallelProjection = 0
    ResetCamera(view)
    camera.Dolly(1.5)
    # Render settings the images depend on: every session kind draws the same frame.
    display.MaximumBounces = bounces
    display.TargetSamplesPerPixel = 16
    display.SamplesPerPixel = 16


def write_piece(reader, rank, out):
    """This rank's piece (the reader's output here) and the process's peak memory."""
    import resource

    fields = reader.GetClientSideObject().GetOutputDataObject(0).GetFieldData()
    info = {"rank": rank, "peak_rss_kib": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}
    for name in ("LabelCount", "CompressedBytes", "Dimensions"):
        array = fields.GetArray(name)
        info[name] = None if array is None else [
            array.GetComponent(0, c) for c in range(array.GetNumberOfComponents())]
    with open(os.path.join(out, f"piece-{rank}.json"), "w") as f:
        json.dump(info, f)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--plugin", required=True)
    parser.add_argument("--file", required=True)
    parser.add_argument("--svdag")
    parser.add_argument("--out", required=True)
    parser.add_argument("--connect", type=int)
    parser.add_argument("--image-only", action="store_true")
    parser.add_argument("--bounces", type=int, default=1)
    parser.add_argument("--pieces", action="store_true",
                        help="write piece-RANK.json: what this rank's reader holds")
    args = parser.parse_args()

    if args.connect:
        Connect("127.0.0.1", args.connect)
        LoadPlugin(args.plugin, remote=True)
        # The server's image comes uncompressed (the default compressors are lossy).
        simple.GetSettingsProxy("RenderViewSettings").CompressorConfig = "NULL"
    LoadPlugin(args.plugin, remote=False)
    results = {}
    rank = servermanager.vtkProcessModule.GetProcessModule().GetPartitionId()

    reader = simple.SegmentationVolumeReader(FileName=args.file)
    view = CreateView("RenderView")
    display = Show(reader, view)
    results["defaults"] = {name: plain(display.GetPropertyValue(name)) for name in DEFAULTS}
    set_up_view(view, display, args.bounces)
    display.SetRepresentationType("Segmentation Path Tracing")
    Render(view)
    SaveScreenshot(os.path.join(args.out, "scene.png"), view, ImageResolution=list(SIZE))
    results["representation"] = display.GetXMLName()
    picker = picker_for(display)
    picker.UpdatePropertyInformation()
    results["samples"] = picker.GetProperty("AccumulatedSamples")[0]
    results["camera"] = camera_of(view)
    # Every rank picks (the representation's pick is collective); a client reads the server's.
    results["picks"] = pick_grid(display)
    if args.pieces:
        write_piece(reader, rank, args.out)
    if not args.image_only:
        results["reader"] = field_numbers(reader)

        # Hidden labels: the three labels picked most often are hidden, and never picked.
        counts = {}
        for _, _, label in results["picks"]:
            if label is not None:
                counts[label] = counts.get(label, 0) + 1
        hidden = sorted(counts, key=lambda label: -counts[label])[:3]
        display.HiddenLabels = hidden
        Render(view)
        results["hidden"] = hidden
        results["picks_hidden"] = pick_grid(display)
        display.HiddenLabels = []

        # A clipping plane through the centre (ResetCamera's focal point) keeping -x -z: the cut faces the camera.
        centre = results["camera"]["focal_point"]
        plane = servermanager.implicit_functions.Plane(Origin=centre, Normal=[-0.6, 0.0, -0.8])
        display.ClippingPlanes = [plane]
        Render(view)
        results["clip_plane"] = {"origin": centre, "normal": [-0.6, 0.0, -0.8]}
        results["picks_clipped"] = pick_grid(display)
        SaveScreenshot(os.path.join(args.out, "clipped.png"), view, ImageResolution=list(SIZE))
        display.ClippingPlanes = []
        Render(view)  # picks read the last frame

        # Label colors from a categorical lookup table: the label at the centre turns red.
        centre = pick(display, SIZE[0] / 2, SIZE[1] / 2)
        lut = GetColorTransferFunction("SegmentationLabels")
        lut.InterpretValuesAsCategories = 1
        lut.Annotations = [str(centre), str(centre)]
        lut.IndexedColors = [1.0, 0.0, 0.0]
        display.LookupTable = lut
        Render(view)
        SaveScreenshot(os.path.join(args.out, "colored.png"), view, ImageResolution=list(SIZE))
        results["colored_label"] = centre

        # The other proxies: .svdag through OpenDataFile, ParaView's NRRD reader + compress,
        # and the decoded slice.
        Hide(reader, view)
        if args.svdag:
            opened = OpenDataFile(args.svdag)
            results["svdag_reader"] = opened.GetXMLName()
            results["svdag"] = field_numbers(opened)
        image = simple.NrrdReader(FileName=args.file) if hasattr(simple, "NrrdReader") else \
            OpenDataFile(args.file)
        compressed = simple.CompressSegmentation(Input=image)
        results["compressed"] = field_numbers(compressed)
        sliced = simple.SegmentationSlice(Input=compressed, Axis=2, Index=7)
        sliced.UpdatePipeline()
        results["slice_representation"] = Show(sliced, view).GetXMLName()
        data = servermanager.Fetch(sliced)
        from vtkmodules.util.numpy_support import vtk_to_numpy
        import numpy as np

        scalars = data.GetPointData().GetScalars()
        dims = data.GetDimensions()
        np.save(os.path.join(args.out, "slice.npy"),
                vtk_to_numpy(scalars).reshape(dims[1], dims[0]))
    if rank == 0:
        with open(os.path.join(args.out, "results.json"), "w") as f:
            json.dump(results, f)


if __name__ == "__main__":
    main()
