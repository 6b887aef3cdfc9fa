#!/usr/bin/env python3
"""VTK comparison: our path-traced SVDAG beside VTK's GPU ray caster and label surfaces.

Run from the repository root, under Xvfb (VTK's OpenGL needs a display; llvmpipe here):

    xvfb-run -a -s "-screen 0 1024x768x24" .venv/bin/python bench/vtk.py [--quick] [--out DIR]
        [--volumes voronoi256 fib_ts2_groundtruth250] [--budget-all]

On each volume (../shared/data/<name>.nrrd), at 512x512 in a pyvista off-screen Plotter, same
camera (pyvista's default isometric reset) for all three routes:

  (a) ours: file -> vtksvdag.read (read + compress, one streaming pass) ->
      add_segmentation(plotter, volume, sun=True, spp=1, lod="voxel") -> plotter.screenshot();
  (b) gpu-raycast: vtksvdag.read(path).to_numpy() (Debian's VTK cannot read gzip NRRD, so the
      labels are decoded from our reader; this time is counted as theirs) -> relabel to uint16
      dense indices (fastremap, _scenes.relabel) -> vtkImageData -> vtkGPUVolumeRayCastMapper,
      nearest interpolation, categorical vtkColorTransferFunction (one point per label index,
      random colors, seed 0), opacity 0 for the background (value 0) and 1 for labels, shading off;
  (c) surfaces: the same labels and relabel -> vtkDiscreteFlyingEdges3D (GenerateValues over
      every label index but the background) -> vtkPolyDataMapper (scalar coloring off, one
      color), default shading.

Measured per route, each in its own subprocess (so memory and the GL/Vulkan state are its own):
  first_image_s   wall seconds from the file path to the first screenshot (Plotter creation,
                  reading, compressing / decoding, relabelling, surface extraction, upload and the
                  first render all included). read_s: ours read + compress; (b), (c) read +
                  compress + decode to numpy + relabel. prep_s: after that, before the first
                  render (ours: add_segmentation with the Vulkan device; (b) transfer functions;
                  (c) flying edges). The rest of first_image_s is the Plotter and first render
                  (with the texture / BVH / vertex upload).
  interact_ms     median wall ms of vtkRenderWindow::Render() + WaitForCompletion() over --frames
                  frames with DesiredUpdateRate 10 (a 100 ms budget) and the camera turned by 5
                  degrees of azimuth per frame; for ours also the LOD and reduction factor the
                  mapper chose (GetLastLOD / GetLastReductionFactor; LOD 0 block, 1 leaf, 2 voxel).
  still_ms        median over --still-frames frames with DesiredUpdateRate 0.0001 and the camera
                  turned by 0.01 degrees per frame, so that ours restarts its accumulation every
                  frame: one sample per pixel at voxel LOD, full resolution (checked).
  peak_extra_mb   ru_maxrss of the subprocess (resource.getrusage(RUSAGE_SELF), at the end) minus
                  its ru_maxrss after the imports (baseline_mb), MB = 10^6 bytes. The parent
                  process stays small (no VTK, no data) so the children's figures are their own.
  triangles       triangles of the surfaces (route c).

Prints a table and the ratios ours / gpu-raycast, writes vtk.csv and vtk_<volume>.png (the three
first images side by side, labelled) to --out (default build/bench). --quick: fib25_64 (64^3)
only, 3 frames (a smoke test). --budget-all: only route (a) interacting (--frames frames) on every
volume in ../shared/data; prints the median interaction frame and the chosen LOD / reduction per
volume against the 100 ms target and writes vtk_budget.csv.
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
import tempfile
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import _scenes  # noqa: E402
# The real volumes: ../shared/data, or where VTKSVDAG_SHARED_DATA points (as the tests).
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")

ROUTES = ["ours", "gpu-raycast", "surfaces"]
ROUTE_TITLES = {
    "ours": "(a) ours: SVDAG path tracer (Vulkan)",
    "gpu-raycast": "(b) vtkGPUVolumeRayCastMapper",
    "surfaces": "(c) vtkDiscreteFlyingEdges3D surfaces",
}
LOD_NAMES = {0: "block", 1: "leaf", 2: "voxel", 3: "auto"}
COLUMNS = [
    "route", "volume", "dims_xyz", "labels", "width", "height", "first_image_s", "read_s",
    "prep_s", "interact_ms_median", "interact_ms_max", "interact_frames", "interact_lods",
    "interact_reductions", "still_ms_median", "still_frames", "still_lod", "still_reduction",
    "still_spp", "peak_rss_mb", "baseline_mb", "peak_extra_mb", "triangles", "notes",
]
BUDGET_COLUMNS = [
    "volume", "dims_xyz", "labels", "interact_ms_median", "interact_ms_max", "interact_frames",
    "interact_lods", "interact_reductions", "within_100ms",
]


# ---------------------------------------------------------------------------------------------
# Worker: one route on one volume, in its own process.
# ---------------------------------------------------------------------------------------------
def _maxrss_mb():
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024 / 1e6  # KiB on Linux


def _render_timed(window):
    start = time.perf_counter()
    window.Render()
    window.WaitForCompletion()
    return (time.perf_counter() - start) * 1000.0


def worker(spec):
    import numpy as np
    import pyvista as pv
    from vtkmodules.vtkFiltersGeneral import vtkDiscreteFlyingEdges3D
    from vtkmodules.vtkRenderingCore import vtkActor, vtkPolyDataMapper

    import vtksvdag

    baseline = _maxrss_mb()
    route, path, size = spec["route"], spec["path"], spec["size"]
    result = dict(route=route, baseline_mb=baseline, notes=[])

    start = time.perf_counter()
    plotter = pv.Plotter(off_screen=True, window_size=(size, size))
    window = plotter.render_window
    window.SetDesiredUpdateRate(0.0001)
    volume = vtksvdag.read(path)
    if route == "ours":
        result["read_s"] = time.perf_counter() - start
        t = time.perf_counter()
        actor = vtksvdag.add_segmentation(plotter, volume, sun=True, spp=1, lod="voxel",
                                          bounces=spec.get("bounces", 4))
        mapper = actor.GetMapper()
        result["prep_s"] = time.perf_counter() - t  # device creation, upload happens at render
    else:
        relabelled = _scenes.relabel(volume)
        indices, n_values, background = relabelled
        result["read_s"] = time.perf_counter() - start
        t = time.perf_counter()
        first_label = 0 if background is None else 1
        if route == "gpu-raycast":
            actor, mapper = _scenes.gpu_raycast_volume(volume, relabelled)
            result["notes"].append(f"sample distance {mapper.GetSampleDistance():g}, auto-adjust "
                                   f"{'on' if mapper.GetAutoAdjustSampleDistances() else 'off'}")
        else:
            surfaces = vtkDiscreteFlyingEdges3D()
            surfaces.SetInputData(_scenes.index_image(volume, indices))
            n_labels = n_values - first_label
            surfaces.GenerateValues(n_labels, float(first_label), float(n_values - 1))
            surfaces.ComputeNormalsOff()
            surfaces.ComputeGradientsOff()
            surfaces.Update()
            poly = surfaces.GetOutput()
            result["triangles"] = int(poly.GetNumberOfPolys())
            mapper = vtkPolyDataMapper()
            mapper.SetInputData(poly)
            mapper.ScalarVisibilityOff()
            actor = vtkActor()
            actor.SetMapper(mapper)
            actor.GetProperty().SetColor(0.85, 0.75, 0.6)
            del surfaces
        result["prep_s"] = time.perf_counter() - t
        plotter.add_actor(actor, reset_camera=True)
    result["dims_xyz"] = "x".join(str(d) for d in volume.dims)
    result["labels"] = len(volume.labels)
    if spec["mode"] == "full":
        img = plotter.screenshot(return_img=True)
        result["first_image_s"] = time.perf_counter() - start
        np.save(spec["image"], np.asarray(img))
    else:
        window.Render()

    camera = plotter.renderer.GetActiveCamera()
    renderer = plotter.renderer

    def frames(rate, degrees, count):
        window.SetDesiredUpdateRate(rate)
        times, lods, reductions, spp = [], [], [], []
        for _ in range(count):
            camera.Azimuth(degrees)
            renderer.ResetCameraClippingRange()
            times.append(_render_timed(window))
            if route == "ours":
                lods.append(mapper.GetLastLOD())
                reductions.append(mapper.GetLastReductionFactor())
                spp.append(mapper.GetAccumulatedSamples())
        return times, lods, reductions, spp

    times, lods, reductions, _ = frames(10.0, 5.0, spec["frames"])
    result.update(interact_ms=times, interact_lods=lods, interact_reductions=reductions)
    if spec["mode"] == "full":
        times, lods, reductions, spp = frames(0.0001, 0.01, spec["still_frames"])
        result.update(still_ms=times, still_lods=lods, still_reductions=reductions, still_spp=spp)
        if route == "ours" and (set(lods) != {2} or set(reductions) != {1} or set(spp) != {1}):
            result["notes"].append(f"still frames not 1 spp voxel full-res: LOD {lods}, "
                                   f"reduction {reductions}, spp {spp}")
    if route == "ours":
        result["notes"].append(f"device {mapper.GetDeviceName()}")
    result["peak_rss_mb"] = _maxrss_mb()
    plotter.close()
    return result


def run_worker(spec, timeout):
    with tempfile.NamedTemporaryFile(suffix=".json", delete=False) as f:
        result_path = f.name
    try:
        completed = subprocess.run(
            [sys.executable, str(pathlib.Path(__file__).resolve()), "--worker", json.dumps(spec),
             "--result", result_path],
            capture_output=True, text=True, timeout=timeout)
        if completed.returncode != 0:
            raise RuntimeError(f"route {spec['route']} on {spec['path']} failed "
                               f"(exit {completed.returncode}):\n{completed.stdout[-2000:]}"
                               f"{completed.stderr[-4000:]}")
        with open(result_path) as f:
            return json.load(f)
    finally:
        os.unlink(result_path)


# ---------------------------------------------------------------------------------------------
# Driver (kept small: no VTK, no data in this process).
# ---------------------------------------------------------------------------------------------
def _fmt_list(values):
    return " ".join(str(v) for v in values)


def _row(volume_name, size, result):
    interact = result.get("interact_ms", [])
    still = result.get("still_ms", [])
    row = dict(
        route=result["route"], volume=volume_name, dims_xyz=result["dims_xyz"],
        labels=result["labels"], width=size, height=size,
        first_image_s=round(result["first_image_s"], 4) if "first_image_s" in result else "",
        read_s=round(result["read_s"], 4), prep_s=round(result["prep_s"], 4),
        interact_ms_median=round(statistics.median(interact), 2) if interact else "",
        interact_ms_max=round(max(interact), 2) if interact else "",
        interact_frames=len(interact),
        interact_lods=_fmt_list(result.get("interact_lods", [])),
        interact_reductions=_fmt_list(result.get("interact_reductions", [])),
        still_ms_median=round(statistics.median(still), 2) if still else "",
        still_frames=len(still),
        still_lod=_fmt_list(sorted(set(result.get("still_lods", [])))),
        still_reduction=_fmt_list(sorted(set(result.get("still_reductions", [])))),
        still_spp=_fmt_list(sorted(set(result.get("still_spp", [])))),
        peak_rss_mb=round(result["peak_rss_mb"], 1), baseline_mb=round(result["baseline_mb"], 1),
        peak_extra_mb=round(result["peak_rss_mb"] - result["baseline_mb"], 1),
        triangles=result.get("triangles", ""), notes="; ".join(result["notes"]))
    return row


def _lod_summary(lods, reductions):
    """'voxel/1 x3, leaf/2 x5' from the per-frame LODs and reduction factors."""
    counts = {}
    for lod, red in zip(lods, reductions):
        key = f"{LOD_NAMES.get(int(lod), lod)}/{red}"
        counts[key] = counts.get(key, 0) + 1
    return ", ".join(f"{k} x{n}" for k, n in counts.items())


def side_by_side(images, titles, path):
    import numpy as np
    from PIL import Image, ImageDraw, ImageFont

    height = max(im.shape[0] for im in images)
    header = 28
    tiles = []
    for im, title in zip(images, titles):
        tile = Image.new("RGB", (im.shape[1], height + header), (255, 255, 255))
        tile.paste(Image.fromarray(np.ascontiguousarray(im[..., :3]).astype(np.uint8)), (0, header))
        draw = ImageDraw.Draw(tile)
        try:
            font = ImageFont.load_default(size=15)
        except TypeError:  # Pillow < 10.1
            font = ImageFont.load_default()
        draw.text((6, 5), title, fill=(0, 0, 0), font=font)
        tiles.append(tile)
    out = Image.new("RGB", (sum(t.width for t in tiles) + 4 * (len(tiles) - 1), tiles[0].height),
                    (255, 255, 255))
    x = 0
    for tile in tiles:
        out.paste(tile, (x, 0))
        x += tile.width + 4
    out.save(path)


def print_table(rows):
    print(f"\n{'route':<12} {'volume':<24} {'first s':>8} {'read s':>7} {'prep s':>7} "
          f"{'interact ms':>11} {'still ms':>9} {'peak MB':>8}  notes")
    for r in rows:
        notes = []
        if r["route"] == "ours":
            notes.append("interact LOD/red " + _lod_summary(r["interact_lods"].split(),
                                                           r["interact_reductions"].split()))
            notes.append(f"still LOD {r['still_lod']} red {r['still_reduction']} "
                         f"spp {r['still_spp']}")
        if r["triangles"] != "":
            notes.append(f"{r['triangles']:,} triangles")
        extra = [n for n in r["notes"].split("; ") if n and not n.startswith("device")]
        notes += extra
        print(f"{r['route']:<12} {r['volume']:<24} {r['first_image_s']:>8.2f} {r['read_s']:>7.2f} "
              f"{r['prep_s']:>7.2f} {r['interact_ms_median']:>11.1f} {r['still_ms_median']:>9.1f} "
              f"{r['peak_extra_mb']:>8.1f}  {'; '.join(notes)}")


def print_ratios(rows):
    print("\nRatios ours / gpu-raycast (same run; < 1: ours is faster or smaller):")
    print(f"{'volume':<24} {'first image':>11} {'still frame':>11} {'interact':>9} {'peak MB':>8}"
          f"   surfaces/gpu-raycast first image")
    for volume in dict.fromkeys(r["volume"] for r in rows):
        by = {r["route"]: r for r in rows if r["volume"] == volume}
        if "ours" not in by or "gpu-raycast" not in by:
            continue
        a, b = by["ours"], by["gpu-raycast"]

        def ratio(key, x=a, y=b):
            return float(x[key]) / float(y[key]) if float(y[key]) > 0 else float("nan")

        surf = ""
        if "surfaces" in by:
            surf = f"{ratio('first_image_s', by['surfaces'], b):.2f}"
        print(f"{volume:<24} {ratio('first_image_s'):>11.2f} {ratio('still_ms_median'):>11.2f} "
              f"{ratio('interact_ms_median'):>9.2f} {ratio('peak_extra_mb'):>8.2f}   {surf}")


def budget_all(args, out):
    rows = []
    print(f"Route (a) interacting (DesiredUpdateRate 10: 100 ms budget, azimuth 5 degrees per frame, "
          f"{args.frames} frames, {args.size}x{args.size}) on every shared volume:")
    print(f"{'volume':<24} {'dims':>12} {'labels':>6} {'median ms':>9} {'max ms':>7}  "
          f"{'within 100 ms':<13} LOD/reduction chosen")
    for path in sorted(SHARED_DATA.glob("*.nrrd")):
        name = path.name[: -len(".nrrd")]
        spec = dict(route="ours", path=str(path), size=args.size, frames=args.frames,
                    bounces=args.bounces, still_frames=0, mode="interact", image="")
        result = run_worker(spec, args.timeout)
        median = statistics.median(result["interact_ms"])
        row = dict(volume=name, dims_xyz=result["dims_xyz"], labels=result["labels"],
                   interact_ms_median=round(median, 2),
                   interact_ms_max=round(max(result["interact_ms"]), 2),
                   interact_frames=len(result["interact_ms"]),
                   interact_lods=_fmt_list(result["interact_lods"]),
                   interact_reductions=_fmt_list(result["interact_reductions"]),
                   within_100ms=int(median <= 100.0))
        rows.append(row)
        print(f"{name:<24} {row['dims_xyz']:>12} {row['labels']:>6} {median:>9.1f} "
              f"{row['interact_ms_max']:>7.1f}  {'yes' if median <= 100 else 'NO':<13} "
              f"{_lod_summary(result['interact_lods'], result['interact_reductions'])}", flush=True)
    path = out / "vtk_budget.csv"
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=BUDGET_COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    met = sum(r["within_100ms"] for r in rows)
    print(f"\n{met} of {len(rows)} volumes within 100 ms (median interaction frame); wrote {path}")
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="fib25_64 only, 3 frames (a smoke test)")
    parser.add_argument("--out", default=str(REPO / "build" / "bench"), help="folder for CSV and PNG")
    parser.add_argument("--volumes", nargs="+", default=["voronoi256", "fib_ts2_groundtruth250"],
                        help="names of volumes in ../shared/data")
    parser.add_argument("--routes", nargs="+", default=ROUTES, choices=ROUTES)
    parser.add_argument("--frames", type=int, default=8, help="interaction frames (median)")
    parser.add_argument("--still-frames", type=int, default=5, help="still frames (median)")
    parser.add_argument("--size", type=int, default=512, help="window width and height")
    parser.add_argument("--bounces", type=int, default=4,
                        help="our path tracer's scattering events per path (1: direct light only)")
    parser.add_argument("--timeout", type=float, default=900, help="seconds per route subprocess")
    parser.add_argument("--budget-all", action="store_true",
                        help="only route (a) interacting, on every shared volume")
    parser.add_argument("--worker", help=argparse.SUPPRESS)
    parser.add_argument("--result", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)

    if args.worker:
        result = worker(json.loads(args.worker))
        with open(args.result, "w") as f:
            json.dump(result, f)
        return 0

    if args.quick:
        args.volumes = ["fib25_64"]
        args.frames = min(args.frames, 3)
        args.still_frames = min(args.still_frames, 3)
    if not SHARED_DATA.is_dir():
        print(f"BENCHMARK FAILED: the shared data folder {SHARED_DATA} is missing")
        return 1
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    print(f"machine: {os.cpu_count()} cores; {args.size}x{args.size}, pyvista off-screen Plotter "
          f"(DISPLAY={os.environ.get('DISPLAY', '')})", flush=True)
    if args.budget_all:
        return budget_all(args, out)

    rows = []
    for name in args.volumes:
        path = SHARED_DATA / f"{name}.nrrd"
        if not path.is_file():
            print(f"BENCHMARK FAILED: {path} does not exist")
            return 1
        images, titles = [], []
        with tempfile.TemporaryDirectory() as tmp:
            for route in args.routes:
                spec = dict(route=route, path=str(path), size=args.size, frames=args.frames,
                            bounces=args.bounces,
                            still_frames=args.still_frames, mode="full",
                            image=str(pathlib.Path(tmp) / f"{route}.npy"))
                result = run_worker(spec, args.timeout)
                row = _row(name, args.size, result)
                rows.append(row)
                print(f"  {name} {route}: first image {row['first_image_s']:.2f} s, interact "
                      f"{row['interact_ms_median']:.1f} ms, still {row['still_ms_median']:.1f} ms, "
                      f"peak +{row['peak_extra_mb']:.1f} MB", flush=True)
                import numpy as np

                images.append(np.load(spec["image"]))
                titles.append(f"{ROUTE_TITLES[route]}  {row['first_image_s']:.2f} s")
        side_by_side(images, titles, out / f"vtk_{name}.png")

    print_table(rows)
    print_ratios(rows)
    csv_path = out / "vtk.csv"
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"\nwrote {csv_path} and vtk_<volume>.png for {', '.join(args.volumes)} "
          f"({time.perf_counter() - start:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
