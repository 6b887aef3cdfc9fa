#!/usr/bin/env python3
"""Rendering benchmark: frame times of the path tracer and its error against run time.

Run from the repository root:

    .venv/bin/python bench/render.py [--quick] [--out bench/out]

1. Frame time: on ../shared/data/voronoi256.nrrd (and, at 256x256, on every other volume there;
   camera framing the volume, azimuth 30,
   elevation 20), milliseconds per 1-sample-per-pixel frame at 256x256, 512x512 and 1024x1024
   for LOD voxel with 1 and 4 bounces and LOD block with 1 bounce, NEE off (the paper's
   estimator, so the work per frame matches the paper code's) and on: the median of --frames
   frames after one warm-up frame (the first frame compiles the shaders). `ms_median` is a frame
   that adds to an accumulation (one camera path per pixel, what the paper code's frames do);
   `ms_restart_median` a frame that starts one (after any change), which also traces the
   pixel-center ray for label, depth and normal.
2. Error against run time: on the same volume and view at --error-size pixels, lit by a disk sun
   (8 degrees radius) plus a constant sky, a reference image per LOD from the same renderer with
   NEE and --reference-spp samples per pixel (seed 1); then, per LOD, with NEE and without, one
   sample per pixel per pass (seed 2) and, after 1, 2, 4, ... samples, the accumulated image's
   RMSE (over all pixels and RGB channels) and mean relative error (mean over pixels whose
   reference luminance is > 0.01 of |L - L_ref| / L_ref, L = luminance) against the tracing time
   spent so far (the renderer's GetRenderSeconds: GPU passes, no readback).

Prints plain-text tables and writes render.csv (one row per measurement; `kind` is `frame` or
`error`) and render_error.png (RMSE against seconds, log-log) to the output folder. The paper
code's lavapipe frame times (../shared/notes/anchors.md) are printed beside ours, marked as
reported, not measured here. --quick renders a small volume at tiny sizes (a smoke test).
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
# The real volumes: ../shared/data, or where VTKSVDAG_SHARED_DATA points (as the tests).
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")

COLUMNS = [
    "kind", "volume", "device", "width", "height", "lod", "bounces", "nee", "spp", "frames",
    "ms_median", "ms_min", "ms_restart_median", "seconds", "rmse", "mean_rel_error",
    "setup_seconds", "bytes_blas", "bytes_tlas",
]
LODS = {"block": 0, "leaf": 1, "voxel": 2}
# The paper code on lavapipe, 256x256, 1 spp, voronoi256 (ranges over days; anchors.md).
ANCHORS_MS = {("voxel", 1): "140-220", ("voxel", 4): "155-220", ("block", 1): "79-128"}


def load_volume(quick):
    from vtksvdag import read

    name = "plantseg_1135_mini" if quick else "voronoi256"
    return name, read(str(SHARED_DATA / f"{name}.nrrd"))


def make_renderer(volume, size, lod, bounces, nee):
    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGRenderer

    r = vtkSegmentationSVDAGRenderer()
    r.SetInputData(volume.dataobject)
    r.SetWidth(size)
    r.SetHeight(size)
    s = r.GetSettings()
    s.SetLOD(LODS[lod])
    s.SetMaximumBounces(bounces)
    s.SetNextEventEstimation(nee)
    s.SetSamplesPerPixel(1)
    if not r.ResetCamera(30, 20, 1.0):
        raise RuntimeError("ResetCamera failed")
    return r


def render(r):
    if not r.Render():
        raise RuntimeError("Render failed (see the VTK error above)")


def hdr(r):
    from vtkmodules.util.numpy_support import vtk_to_numpy

    return vtk_to_numpy(r.GetOutput().GetPointData().GetArray("HDR"))[:, :3].astype(np.float64)


def frame_times(volume, name, sizes, frames):
    rows = []
    for size in sizes:
        for lod, bounces in (("voxel", 1), ("voxel", 4), ("block", 1)):
            for nee in (False, True):
                r = make_renderer(volume, size, lod, bounces, nee)
                render(r)  # warm-up: shader compilation
                times, restart = [], []
                for _ in range(frames):
                    render(r)
                    times.append(r.GetLastFrameMilliseconds())
                for _ in range(frames):
                    r.ResetAccumulation()
                    render(r)
                    restart.append(r.GetLastFrameMilliseconds())
                rows.append(dict(
                    kind="frame", volume=name, device=r.GetDeviceName(), width=size, height=size,
                    lod=lod, bounces=bounces, nee=int(nee), spp=1, frames=frames,
                    ms_median=round(statistics.median(times), 3), ms_min=round(min(times), 3),
                    ms_restart_median=round(statistics.median(restart), 3),
                    setup_seconds=round(r.GetSetupSeconds(), 6), bytes_blas=r.GetBLASBytes(),
                    bytes_tlas=r.GetTLASBytes()))
                print(f"  {size:>5} {lod:>6} {bounces:>2} bounces NEE {'on ' if nee else 'off'}: "
                      f"{rows[-1]['ms_median']:9.1f} ms (min {rows[-1]['ms_min']:.1f}, restarting "
                      f"{rows[-1]['ms_restart_median']:.1f})", flush=True)
    return rows


def light(r):
    s = r.GetSettings()
    s.SunOn()
    s.SetSunDirection(0.45, 0.35, 0.82)
    s.SetSunAngularRadius(8.0)
    s.SetSunIrradiance(3.0, 2.9, 2.7)
    s.SetEnvironmentColor(0.25, 0.3, 0.4)
    s.SetBackground(0.25, 0.3, 0.4, 1.0)


def luminance(rgb):
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def error_curves(volume, name, size, lods, reference_spp, max_spp):
    rows = []
    for lod in lods:
        ref = make_renderer(volume, size, lod, 4, True)
        light(ref)
        ref.GetSettings().SetSeed(1)
        ref.GetSettings().SetSamplesPerPixel(min(reference_spp, 64))
        while ref.GetAccumulatedSamples() < reference_spp:
            render(ref)
        reference = hdr(ref)
        ref_lum = luminance(reference)
        lit = ref_lum > 0.01
        print(f"  {lod}: reference {ref.GetAccumulatedSamples()} spp in {ref.GetRenderSeconds():.1f} s",
              flush=True)
        for nee in (True, False):
            r = make_renderer(volume, size, lod, 4, nee)
            light(r)
            r.GetSettings().SetSeed(2)
            render(r)  # warm-up (shader compilation), then a fresh accumulation
            r.ResetAccumulation()
            render(r)
            checkpoint = 1
            while checkpoint <= max_spp:
                while r.GetAccumulatedSamples() < checkpoint:
                    render(r)
                image = hdr(r)
                rmse = float(np.sqrt(np.mean((image - reference) ** 2)))
                rel = float(np.mean(np.abs(luminance(image)[lit] - ref_lum[lit]) / ref_lum[lit]))
                rows.append(dict(
                    kind="error", volume=name, device=r.GetDeviceName(), width=size, height=size,
                    lod=lod, bounces=4, nee=int(nee), spp=r.GetAccumulatedSamples(),
                    seconds=round(r.GetRenderSeconds(), 6), rmse=f"{rmse:.6g}",
                    mean_rel_error=f"{rel:.6g}"))
                checkpoint *= 2
            last = rows[-1]
            print(f"    NEE {'on ' if nee else 'off'}: {last['spp']} spp, {last['seconds']:.2f} s, "
                  f"RMSE {last['rmse']}, mean relative error {last['mean_rel_error']}", flush=True)
    return rows


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    errors = [r for r in rows if r["kind"] == "error"]
    colors = {"voxel": "tab:blue", "leaf": "tab:green", "block": "tab:orange"}
    for lod in LODS:
        for nee in (1, 0):
            curve = [r for r in errors if r["lod"] == lod and r["nee"] == nee]
            if not curve:
                continue
            ax.loglog([max(r["seconds"], 1e-6) for r in curve], [float(r["rmse"]) for r in curve],
                      "-o" if nee else "--s", color=colors[lod], markersize=3,
                      label=f"{lod}, {'NEE + MIS' if nee else 'no NEE (paper estimator)'}")
    ax.set_xlabel("tracing time (s)")
    ax.set_ylabel("RMSE vs reference")
    ax.set_title("Path tracer error against run time (disk sun + sky)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def print_frame_table(rows, name):
    rows = [r for r in rows if r["kind"] == "frame" and r["volume"] == name]
    anchored = name == "voronoi256"
    print(f"\nFrame time on {name}, 1 spp, median (ms), accumulating frames   "
          "[paper code on lavapipe, voronoi256 only: reported, not measured here]")
    print(f"{'size':>9} {'LOD':>6} {'bounces':>7} {'NEE off':>9} {'NEE on':>9}   paper (256x256)")
    keys = sorted({(r["width"], r["lod"], r["bounces"]) for r in rows},
                  key=lambda k: (k[0], k[1] != "voxel", k[2]))
    for size, lod, bounces in keys:
        ms = {r["nee"]: r["ms_median"] for r in rows
              if (r["width"], r["lod"], r["bounces"]) == (size, lod, bounces)}
        anchor = ANCHORS_MS.get((lod, bounces), "") if size == 256 and anchored else ""
        print(f"{size:>4}x{size:<4} {lod:>6} {bounces:>7} {ms.get(0, float('nan')):9.1f} "
              f"{ms.get(1, float('nan')):9.1f}   {anchor}")


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a small volume at tiny sizes (seconds)")
    parser.add_argument("--out", default=str(REPO / "bench" / "out"), help="folder for the CSV and plot")
    parser.add_argument("--frames", type=int, default=5, help="timed frames per configuration (median)")
    parser.add_argument("--sizes", type=int, nargs="+", help="image sizes (default 256 512 1024)")
    parser.add_argument("--error-size", type=int, default=128, help="image size of the error study")
    parser.add_argument("--reference-spp", type=int, default=2048, help="samples of the reference")
    parser.add_argument("--max-spp", type=int, default=256, help="last checkpoint of the error curves")
    args = parser.parse_args(argv)
    if args.quick:
        sizes = args.sizes or [32]
        args.frames = min(args.frames, 2)
        args.error_size = min(args.error_size, 24)
        args.reference_spp = min(args.reference_spp, 64)
        args.max_spp = min(args.max_spp, 8)
        lods = ["voxel", "block"]
    else:
        sizes = args.sizes or [256, 512, 1024]
        lods = ["voxel", "leaf", "block"]
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    start = time.perf_counter()
    name, volume = load_volume(args.quick)
    print(f"volume {name}: {' x '.join(str(d) for d in volume.dims)} voxels, "
          f"{len(volume.labels)} labels (loaded in {time.perf_counter() - start:.1f} s)")
    print("Frame times:")
    rows = frame_times(volume, name, sizes, args.frames)
    print_frame_table(rows, name)
    if not args.quick:
        # The real volumes too, at the anchors' size.
        for path in sorted(SHARED_DATA.glob("*.nrrd")):
            other = path.name[: -len(".nrrd")]
            if other == name:
                continue
            from vtksvdag import read

            print(f"Frame times, {other}:")
            rows += frame_times(read(str(path)), other, [256], args.frames)
            print_frame_table(rows, other)
    print(f"\nError against run time ({args.error_size}x{args.error_size}, 4 bounces):")
    rows += error_curves(volume, name, args.error_size, lods, args.reference_spp, args.max_spp)

    print(f"\n{'LOD':>6} {'NEE':>4} {'spp':>5} {'seconds':>9} {'RMSE':>10} {'mean rel':>9}")
    for r in rows:
        if r["kind"] == "error":
            print(f"{r['lod']:>6} {'on' if r['nee'] else 'off':>4} {r['spp']:>5} "
                  f"{r['seconds']:9.3f} {float(r['rmse']):10.5f} {float(r['mean_rel_error']):9.4f}")

    csv_path, png_path = out / "render.csv", out / "render_error.png"
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS, restval="")
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, png_path)
    print(f"\nwrote {csv_path} and {png_path} ({time.perf_counter() - start:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
