#!/usr/bin/env python3
"""The volume mapper's ways of moving the traced image and the depth between OpenGL and Vulkan,
side by side.

Run from the repository root, under Xvfb (VTK's OpenGL needs a display; llvmpipe here):

    xvfb-run -a -s "-screen 0 1024x768x24" .venv/bin/python bench/composite.py [--quick]
        [--volume fib25_64] [--size 512] [--frames 12] [--paths shared shared-color host]
        [--out DIR]

Off-screen windows of --size x --size pixels in one process, each with the same volume
(../shared/data/<volume>.nrrd; --quick or without ../shared: a generated 64^3 volume) drawn by
vtkSegmentationSVDAGVolumeMapper beside a mesh (a tilted slab through it, so the scene depth and
the written depth are real work), one window per path:

  shared        SharedMemory on: color and depth through shared memory (where they can)
  shared-color  SharedMemory on, SharedDepth off: the color shared, the depth through the host
  host          SharedMemory off: both through the host

Per frame: 1 sample per pixel at voxel LOD, full resolution (AutoAdjustToRenderTime off), the
camera turned by 0.01 degrees so that every frame traces anew; the windows take turns, frame by
frame, so that all see the same machine. Measured per frame:

  render_ms   wall time of vtkRenderWindow::Render() + WaitForCompletion() (the whole frame: the
              mesh, the trace and the composite)
  mapper_ms   the mapper's own time (GetLastFrameMilliseconds)
  trace_ms    the Vulkan pass (GetLastTraceMilliseconds)
  copy_ms     what the mapper spent moving depth and image between OpenGL, the host and Vulkan
              (GetLastCopyMilliseconds: scene depth read, and on the host path turned into ray
              limits, outputs read back, written depth composited, depth and color uploaded and
              drawn; on the shared depth path the ray limits are computed in the trace's
              submission, so they count in trace_ms)

Prints the medians per path with the paths the color and the depth ran as and the copy share
(copy_ms / mapper_ms), and the ratios of each path to host (and shared to shared-color: the
depth path alone); writes composite.csv (every frame) to --out (default build/bench). The
windows' final images and z-buffers are compared (they must be equal).
"""
from __future__ import annotations

import argparse
import csv
import os
import pathlib
import statistics
import sys
import time

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")
FIELDS = ["render_ms", "mapper_ms", "trace_ms", "copy_ms"]
PATHS = ["shared", "shared-color", "host"]


def generated_volume():
    """64^3 uint16: nested boxes and a sphere of labels (no ../shared needed)."""
    n = 64
    z, y, x = np.mgrid[0:n, 0:n, 0:n]
    labels = np.zeros((n, n, n), np.uint16)
    labels[4:60, 6:58, 5:59] = 2
    labels[20:40, 10:50, 20:40] = 9
    labels[(x - 40) ** 2 + (y - 30) ** 2 + (z - 20) ** 2 < 15 ** 2] = 5
    return labels


def load_volume(name, quick):
    import vtksvdag

    path = SHARED_DATA / f"{name}.nrrd"
    if quick or not path.exists():
        return vtksvdag.from_numpy(generated_volume(), axis_order="zyx"), "generated 64^3"
    return vtksvdag.read(str(path)), name


def scene(volume, size, path):
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL factory overrides)
    from vtkmodules.vtkFiltersSources import vtkCubeSource
    from vtkmodules.vtkRenderingCore import (vtkActor, vtkPolyDataMapper, vtkRenderer,
                                             vtkRenderWindow, vtkVolume)

    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper

    mapper = vtkSegmentationSVDAGVolumeMapper()
    mapper.SetInputData(volume.dataobject)
    shared = path != "host"
    if hasattr(mapper, "SetSharedMemory"):
        mapper.SetSharedMemory(shared)
    elif shared:
        raise SystemExit("this build has no shared-memory path: run it with --paths host")
    if hasattr(mapper, "SetSharedDepth"):
        mapper.SetSharedDepth(path == "shared")
    elif path == "shared-color":
        raise SystemExit("this build has no shared depth path: run it with --paths shared host")
    mapper.AutoAdjustToRenderTimeOff()
    mapper.SetTargetSamplesPerPixel(1)
    mapper.GetSettings().SetLODToVoxel()
    mapper.GetSettings().SetSamplesPerPixel(1)
    prop = vtkVolume()
    prop.SetMapper(mapper)
    renderer = vtkRenderer()
    renderer.AddVolume(prop)
    bounds = prop.GetBounds()
    center = [(bounds[2 * a] + bounds[2 * a + 1]) / 2 for a in range(3)]
    extent = max(bounds[2 * a + 1] - bounds[2 * a] for a in range(3))
    slab = vtkCubeSource()
    slab.SetXLength(1.5 * extent)
    slab.SetYLength(0.05 * extent)
    slab.SetZLength(1.5 * extent)
    mesh = vtkPolyDataMapper()
    mesh.SetInputConnection(slab.GetOutputPort())
    actor = vtkActor()
    actor.SetMapper(mesh)
    actor.SetPosition(*center)
    actor.RotateZ(30)
    renderer.AddActor(actor)
    window = vtkRenderWindow()
    window.SetOffScreenRendering(1)
    window.SetMultiSamples(0)
    window.SetSize(size, size)
    window.AddRenderer(renderer)
    renderer.ResetCamera()
    renderer.GetActiveCamera().Azimuth(30)
    renderer.GetActiveCamera().Elevation(20)
    renderer.ResetCameraClippingRange()
    return window, renderer, mapper


def frame(window, renderer, mapper):
    renderer.GetActiveCamera().Azimuth(0.01)
    start = time.perf_counter()
    window.Render()
    window.WaitForCompletion()
    render_ms = (time.perf_counter() - start) * 1000
    assert mapper.GetAccumulatedSamples() == 1 and mapper.GetLastReductionFactor() == 1
    return {"render_ms": render_ms, "mapper_ms": mapper.GetLastFrameMilliseconds(),
            "trace_ms": mapper.GetLastTraceMilliseconds(),
            # Builds before the shared path had no copy timing.
            "copy_ms": getattr(mapper, "GetLastCopyMilliseconds", lambda: float("nan"))()}


def pixels(window):
    """The window's color and z-buffer."""
    from vtkmodules.util.numpy_support import vtk_to_numpy
    from vtkmodules.vtkCommonCore import vtkFloatArray
    from vtkmodules.vtkRenderingCore import vtkWindowToImageFilter

    grab = vtkWindowToImageFilter()
    grab.SetInput(window)
    grab.ReadFrontBufferOff()
    grab.ShouldRerenderOff()
    grab.Update()
    width, height = window.GetSize()
    depth = vtkFloatArray()
    window.GetZbufferData(0, 0, width - 1, height - 1, depth)
    return np.concatenate([vtk_to_numpy(grab.GetOutput().GetPointData().GetScalars()).ravel(),
                           vtk_to_numpy(depth).view(np.uint8).ravel()])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="generated 64^3 volume, 3 frames")
    parser.add_argument("--volume", default="fib25_64", help="a volume of ../shared/data")
    parser.add_argument("--size", type=int, default=512, help="window width and height")
    parser.add_argument("--frames", type=int, default=12, help="frames per path (after 2 warm-up)")
    parser.add_argument("--paths", nargs="+", default=PATHS, choices=PATHS,
                        help="the paths to measure (an older build: host, or shared host)")
    parser.add_argument("--out", default=str(REPO / "build" / "bench"), help="folder for the CSV")
    args = parser.parse_args(argv)
    frames = 3 if args.quick else args.frames

    volume, name = load_volume(args.volume, args.quick)
    paths = {}
    for label in args.paths:
        paths[label] = scene(volume, args.size, label)
    rows = []
    for index in range(frames + 2):
        for label, (window, renderer, mapper) in paths.items():
            measured = frame(window, renderer, mapper)
            if index >= 2:  # the first frames compile shaders and build the BVH
                ran_as = getattr(mapper, "GetCompositePath", lambda: "host")()
                depth_as = getattr(mapper, "GetDepthPath", lambda: "host")()
                rows.append({"path": label, "composite_path": ran_as, "depth_path": depth_as,
                             "frame": index - 2, **measured})
    # The same camera for all (each turned by the same angles): the same pixels and depth.
    images = [pixels(window) for window, _, _ in paths.values()]
    same = all(np.array_equal(images[0], image) for image in images[1:])

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "composite.csv", "w", newline="") as f:
        writer = csv.DictWriter(
            f, fieldnames=["path", "composite_path", "depth_path", "frame", *FIELDS])
        writer.writeheader()
        writer.writerows(rows)

    medians = {label: {field: statistics.median(r[field] for r in rows if r["path"] == label)
                       for field in FIELDS} for label in paths}
    ran = {label: (", ".join(sorted({r["composite_path"] for r in rows if r["path"] == label})),
                   ", ".join(sorted({r["depth_path"] for r in rows if r["path"] == label})))
           for label in paths}
    device = next(iter(paths.values()))[2].GetDeviceName()
    print(f"volume {name}, {args.size}x{args.size}, 1 spp, voxel LOD, {frames} frames per path, "
          f"device {device}")
    print(f"{'path':<13} {'color as':<14} {'depth as':<14} " + " ".join(f"{f:>10}" for f in FIELDS) +
          "  copy share")
    for label in paths:
        m = medians[label]
        print(f"{label:<13} {ran[label][0]:<14} {ran[label][1]:<14} " +
              " ".join(f"{m[f]:10.2f}" for f in FIELDS) +
              f"  {m['copy_ms'] / m['mapper_ms']:10.1%}")
    ratios = [(a, b) for a, b in (("shared", "host"), ("shared-color", "host"),
                                  ("shared", "shared-color")) if a in paths and b in paths]
    for a, b in ratios:
        print(f"{a} / {b}: " + ", ".join(f"{f} {medians[a][f] / medians[b][f]:.2f}x"
                                         for f in FIELDS))
    print(f"images equal: {same}")
    print(f"wrote {out / 'composite.csv'}")
    return 0 if same else 1


if __name__ == "__main__":
    sys.exit(main())
