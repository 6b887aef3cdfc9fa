#!/usr/bin/env python3
"""One Vulkan device per process: setup time, threads and device bytes of 1 and 8 volumes.

Run from the repository root, under Xvfb (VTK's OpenGL needs a display; llvmpipe here):

    xvfb-run -a -s "-screen 0 1024x768x24" .venv/bin/python bench/devices.py [--quick]
        [--out bench/out] [--size 96] [--repeats 3]

Each run is a fresh subprocess (so the device, its threads and its pipelines are its own): two
512x512 off-screen vtkRenderWindows with four quarter viewports each are drawn once without any
volume (the OpenGL contexts and llvmpipe's GL threads exist from then on), then N volumes
(--size^3 labels, a few random spheres each, a different seed per volume) are shown, one per
viewport, each with its own vtkSegmentationSVDAGVolumeMapper (1 spp), and both windows are
rendered once. Measured:
  setup_s          wall seconds of that first render of both windows: the device (created on the
                   first volume's first frame), pipeline compilation, every volume's upload and
                   grid build, and one frame per volume
  threads_added    entries of /proc/self/task after it minus before it
  device_bytes     the mappers' device bytes summed (GetDeviceBytes: each its own)
  bytes_per_volume device_bytes / N
  device_users     vtkSegmentationSVDAGVolumeMapper.GetDeviceUsers() after the render
  devices          distinct GetDeviceId() over the mappers
Each N is run --repeats times; the table shows the median setup_s (threads and bytes do not
vary). The ratios 8 / 1 are printed against the issue's target (at most 1.2 times the threads and
setup time of one volume plus the per-volume data, the uploads). Writes devices.csv and
devices.png (setup time and threads per N) to --out. --quick: 48^3 volumes, one repeat.
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import pathlib
import statistics
import subprocess
import sys
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
COLUMNS = ["volumes", "size", "repeat", "setup_s", "threads_before", "threads_added",
           "device_bytes", "bytes_per_volume", "device_users", "devices"]
QUARTERS = [(0, 0, 0.5, 0.5), (0.5, 0, 1, 0.5), (0, 0.5, 0.5, 1), (0.5, 0.5, 1, 1)]
WINDOW = 512


def threads():
    return len(os.listdir("/proc/self/task"))


def make_volume(size, seed):
    """A vtkSegmentationSVDAG of `size`^3 labels: 12 random spheres, labels 1..12."""
    import numpy as np
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData
    from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG

    rng = np.random.default_rng(seed)
    z, y, x = np.mgrid[0:size, 0:size, 0:size]
    labels = np.zeros((size, size, size), np.uint16)
    for label in range(1, 13):
        c = rng.uniform(0.2, 0.8, 3) * size
        r = rng.uniform(0.08, 0.2) * size
        labels[(x - c[0]) ** 2 + (y - c[1]) ** 2 + (z - c[2]) ** 2 < r * r] = label
    image = vtkImageData()
    image.SetDimensions(size, size, size)
    image.GetPointData().SetScalars(numpy_to_vtk(labels.ravel(), deep=True))
    builder = vtkImageDataToSegmentationSVDAG()
    builder.SetInputData(image)
    builder.Update()
    return builder.GetOutput()


def worker(count, size):
    """One measurement in this process (see the module docstring); prints a JSON object."""
    import vtkmodules.vtkRenderingOpenGL2  # noqa: F401 (the OpenGL factory overrides)
    from vtkmodules.vtkRenderingCore import vtkRenderer, vtkRenderWindow, vtkVolume
    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGVolumeMapper

    volumes = [make_volume(size, seed) for seed in range(count)]
    windows = []
    for _ in range(2):
        window = vtkRenderWindow()
        window.SetOffScreenRendering(1)
        window.SetSize(WINDOW, WINDOW)
        windows.append(window)
    mappers, props = [], []
    for i, svdag in enumerate(volumes):
        mapper = vtkSegmentationSVDAGVolumeMapper()
        mapper.SetInputData(svdag)
        mapper.GetSettings().SetSamplesPerPixel(1)
        volume = vtkVolume()
        volume.SetMapper(mapper)
        volume.VisibilityOff()
        renderer = vtkRenderer()
        renderer.SetViewport(*QUARTERS[i % 4])
        renderer.AddVolume(volume)
        renderer.ResetCamera()
        windows[i // 4].AddRenderer(renderer)
        mappers.append(mapper)
        props.append(volume)
    for window in windows:
        window.Render()
    before = threads()
    for volume in props:
        volume.VisibilityOn()
    start = time.perf_counter()
    for window in windows:
        window.Render()
    setup = time.perf_counter() - start
    device_bytes = sum(m.GetDeviceBytes() for m in mappers)
    print(json.dumps({
        "setup_s": setup, "threads_before": before, "threads_added": threads() - before,
        "device_bytes": device_bytes, "bytes_per_volume": device_bytes // count,
        "device_users": vtkSegmentationSVDAGVolumeMapper.GetDeviceUsers(),
        "devices": len({m.GetDeviceId() for m in mappers}),
    }))


def measure(count, size):
    completed = subprocess.run([sys.executable, __file__, "--worker", str(count), "--size", str(size)],
                               capture_output=True, text=True, timeout=1200)
    if completed.returncode != 0:
        raise RuntimeError("worker for %d volumes failed:\n%s%s" % (count, completed.stdout[-2000:],
                                                                   completed.stderr[-2000:]))
    return json.loads(completed.stdout.strip().splitlines()[-1])


def plot(rows, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    counts = sorted({r["volumes"] for r in rows})
    setup = [statistics.median(r["setup_s"] for r in rows if r["volumes"] == n) for n in counts]
    added = [next(r["threads_added"] for r in rows if r["volumes"] == n) for n in counts]
    fig, axes = plt.subplots(1, 2, figsize=(8, 3.2))
    labels = ["%d volume%s" % (n, "s" if n > 1 else "") for n in counts]
    axes[0].bar(labels, setup, color="#4c72b0")
    axes[0].set_ylabel("first render of both windows (s)")
    axes[1].bar(labels, added, color="#dd8452")
    axes[1].set_ylabel("threads added")
    fig.suptitle("One Vulkan device per process (lavapipe)")
    fig.tight_layout()
    fig.savefig(path, dpi=100)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(REPO / "bench" / "out"))
    parser.add_argument("--size", type=int, default=96)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--worker", type=int, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.worker:
        worker(args.worker, args.size)
        return
    if args.quick:
        args.size, args.repeats = 48, 1
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    # Interleaved (1, 8, 1, 8...), so that a busy machine slows both alike.
    for repeat in range(args.repeats):
        for count in (1, 8):
            row = {"volumes": count, "size": args.size, "repeat": repeat, **measure(count, args.size)}
            rows.append(row)
            print("  %d volume(s), repeat %d: %.2f s, %d threads added" % (
                count, repeat, row["setup_s"], row["threads_added"]), flush=True)
    with open(out / "devices.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)

    def summary(count):
        mine = [r for r in rows if r["volumes"] == count]
        return statistics.median(r["setup_s"] for r in mine), mine[0]

    print("\n%-8s %10s %14s %14s %16s %6s %8s" % ("volumes", "setup_s", "threads_added",
                                                  "device_bytes", "bytes_per_volume", "users",
                                                  "devices"))
    for count in (1, 8):
        setup, r = summary(count)
        print("%-8d %10.2f %14d %14d %16d %6d %8d" % (count, setup, r["threads_added"],
                                                     r["device_bytes"], r["bytes_per_volume"],
                                                     r["device_users"], r["devices"]))
    (s1, r1), (s8, r8) = summary(1), summary(8)
    print("\n8 / 1: threads %.2fx, setup time %.2fx (target: at most 1.2x plus the per-volume "
          "uploads), device bytes %.2fx" % (r8["threads_added"] / max(r1["threads_added"], 1),
                                            s8 / s1, r8["device_bytes"] / r1["device_bytes"]))
    print("each volume beyond the first adds %.3f s (its upload, grid build and frame)" % ((s8 - s1) / 7))
    try:
        plot(rows, out / "devices.png")
    except ImportError:
        print("(no matplotlib: no plot)")
    print("wrote %s" % (out / "devices.csv"))


if __name__ == "__main__":
    main()
