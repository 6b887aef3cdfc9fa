#!/usr/bin/env python3
"""Rendering benchmark: frame times of both backends, device bytes, and the path tracer's error
against run time.

Run from the repository root:

    .venv/bin/python bench/render.py [--quick] [--out bench/out] [--volcanite PATH]

1. Frame time, both backends side by side (`rt`: the ray tracing pipeline over a BVH of block
   boxes; `compute`: the compute shader walking the cell grid), on every volume in ../shared/data
   (dense and sparse), camera framing the volume (azimuth 30, elevation 20), 1 sample per pixel,
   NEE on, 1 bounce (primary ray + one occlusion ray: the work of Volcanite's default frame), at
   256x256 and 512x512, LOD voxel, leaf and block; on voronoi256 also 4 bounces and the paper's
   estimator (NEE off), beside the paper code's reported lavapipe frame times. Per configuration,
   --frames rounds after a warm-up frame (shader compilation), each an accumulating frame (adds
   one sample) and a restarting one (after ResetAccumulation: what every frame costs while the
   camera moves), interleaved so that drifts of the shared machine hit both alike; medians.
   Device bytes per part: encoding (block and DAG streams), acceleration (BLAS + TLAS + instances
   + primitive map, or the cell grid + hidden-label bits), and the renderer's total. Beside each
   compute frame, where its rays spend their steps (one more restarting frame with the step
   counters on): cells visited, block records read, DAG walks and their iterations per ray, their
   sum (steps per ray), and the divergence of the 4 x 2 pixel quads traced side by side (the
   mean over quads of the busiest pixel's steps, and the mean over that). Then the generated
   EM-like volumes (--generated; bench/_em_volumes.py: thousands of labels, unlabelled space
   between the cells) at voxel and block LOD.
2. Volcanite (when a binary is given by --volcanite, the VOLCANITE environment variable or found
   on PATH; it is not a dependency; bench/_volcanite.py runs it): every volume above, the
   generated ones included, written as the NRRD it reads and compressed to its CSGV form once
   (kept in --out/volcanite), at each size in its own default view, still, for
   --volcanite-frames frames through --volcanite-command (its evaluation log's median frame
   time), against ours in the same view (compute and rt, voxel LOD, NEE, 1 bounce: the camera
   ray and one occlusion ray), --volcanite-rounds rounds interleaved, medians of the rounds.
   Without a binary, the same-run figures anchors.md reports (marked as reported, not measured
   here).
3. Error against run time: on voronoi256 at --error-size pixels, lit by a disk sun (8 degrees
   radius) plus a constant sky, a reference image per LOD from the same renderer with NEE and
   --reference-spp samples per pixel (seed 1); then, per LOD, with NEE and without, one sample
   per pixel per pass (seed 2) and, after 1, 2, 4, ... samples, the accumulated image's RMSE
   (over all pixels and RGB channels) and mean relative error (mean over pixels whose reference
   luminance is > 0.01 of |L - L_ref| / L_ref, L = luminance) against the tracing time spent so
   far (the renderer's GetRenderSeconds: GPU passes, no readback); with NEE also with the
   denoiser on (its cost counted in the seconds; everything else here runs with it off, as the
   path tracer's own figures). Default backend (auto).

Prints plain-text tables and writes render.csv (one row per measurement; `kind` is `frame`,
`volcanite`, `matched` (ours in Volcanite's view) or `error`), render_backends.png (ms per frame of both backends at 256x256 (the
smallest size measured), voxel LOD) and render_error.png (RMSE against seconds, log-log) to the output folder. --quick renders
a small volume at a tiny size (a smoke test).
"""
from __future__ import annotations

import argparse
import csv
import os
import pathlib
import shutil
import statistics
import sys
import time

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import _em_volumes  # noqa: E402
import _scenes  # noqa: E402
import _volcanite  # noqa: E402
# The real volumes: ../shared/data, or where VTKSVDAG_SHARED_DATA points (as the tests).
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")

COLUMNS = [
    "kind", "volume", "device", "backend", "width", "height", "lod", "bounces", "nee", "denoise",
    "spp",
    "frames", "ms_median", "ms_min", "ms_restart_median", "restart_ratio", "seconds", "rmse",
    "mean_rel_error", "setup_seconds", "bytes_blas", "bytes_tlas", "bytes_encoding",
    "bytes_acceleration", "bytes_device",
    # Step statistics of the compute backend's frames (one extra frame with the counters on):
    "rays_per_pixel", "cells_per_ray", "blocks_per_ray", "walks_per_ray", "dag_steps_per_ray",
    "steps_per_ray", "quad_max_steps", "quad_efficiency",
]
LODS = {"block": 0, "leaf": 1, "voxel": 2}
BACKENDS = ("rt", "compute")
# The paper code on lavapipe, 256x256, 1 spp, voronoi256 (ranges over days; anchors.md).
ANCHORS_MS = {("voxel", 1): "140-220", ("voxel", 4): "155-220", ("block", 1): "79-128"}
# Volcanite 0.6 on lavapipe, 256x256, default frame (primary + shadow rays), same-run comparison
# of 2026-12-01 (anchors.md): ms per frame and GPU bytes in use (encoding + brick cache).
VOLCANITE_REPORTED = {"voronoi256": ("9.3 (8.7)", 6.3e6), "fib_ts2_groundtruth250": ("9.3 (8.6)", 6.2e6)}


def load_volume(quick):
    from vtksvdag import read

    name = "plantseg_1135_mini" if quick else "voronoi256"
    return name, read(str(SHARED_DATA / f"{name}.nrrd"))


def make_renderer(volume, size, lod, bounces, nee, backend="auto", denoise=False):
    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGRenderer

    r = vtkSegmentationSVDAGRenderer()
    r.SetInputData(volume.dataobject)
    r.SetWidth(size)
    r.SetHeight(size)
    s = r.GetSettings()
    s.SetBackend(backend)
    s.SetLOD(LODS[lod])
    s.SetMaximumBounces(bounces)
    s.SetNextEventEstimation(nee)
    # The path tracer's own frames and error; the denoiser has its rows in the error curves
    # (and bench/denoise.py).
    s.SetDenoise(denoise)
    s.SetSamplesPerPixel(1)
    if not r.ResetCamera(30, 20, 1.0):
        raise RuntimeError("ResetCamera failed")
    return r


render, hdr = _scenes.render, _scenes.hdr


def configurations(name, quick):
    """(lod, bounces, nee) per volume: Volcanite's work at every LOD; on the anchored volume also
    4 bounces and the paper's estimator."""
    if quick:
        return [("voxel", 1, True), ("block", 1, True), ("voxel", 1, False)]
    configs = [(lod, 1, True) for lod in ("voxel", "leaf", "block")]
    if name == "voronoi256":
        configs += [("voxel", 4, True), ("voxel", 1, False), ("voxel", 4, False), ("block", 1, False)]
    return configs


def frame_times(volume, name, sizes, frames, configs):
    rows = []
    for size in sizes:
        for lod, bounces, nee in configs:
            for backend in BACKENDS:
                r = make_renderer(volume, size, lod, bounces, nee, backend)
                render(r)  # warm-up: shader compilation
                if r.GetBackendInUse() != backend:
                    raise RuntimeError(f"asked for the {backend} backend, got {r.GetBackendInUse()!r}")
                times, restart = [], []
                for _ in range(frames):
                    render(r)
                    times.append(r.GetLastFrameMilliseconds())
                    r.ResetAccumulation()
                    render(r)
                    restart.append(r.GetLastFrameMilliseconds())
                median, restart_median = statistics.median(times), statistics.median(restart)
                steps = step_statistics(r, size) if backend == "compute" else {}
                rows.append(dict(
                    kind="frame", volume=name, device=r.GetDeviceName(), backend=backend,
                    width=size, height=size, lod=lod, bounces=bounces, nee=int(nee), spp=1,
                    frames=frames, ms_median=round(median, 3), ms_min=round(min(times), 3),
                    ms_restart_median=round(restart_median, 3),
                    restart_ratio=round(restart_median / median, 3),
                    setup_seconds=round(r.GetSetupSeconds(), 6), bytes_blas=r.GetBLASBytes(),
                    bytes_tlas=r.GetTLASBytes(), bytes_encoding=r.GetEncodingBytes(),
                    bytes_acceleration=r.GetAccelerationBytes(), bytes_device=r.GetDeviceBytes(),
                    **steps))
                print(f"  {name:<24} {size:>4} {lod:>6} {bounces} bounce{'s' if bounces > 1 else ' '} "
                      f"NEE {'on ' if nee else 'off'} {backend:>7}: {median:8.2f} ms "
                      f"(restarting {restart_median:.2f}, x{restart_median / median:.2f}), "
                      f"{(r.GetEncodingBytes() + r.GetAccelerationBytes()) / 1e6:.2f} MB"
                      + (f", {steps['steps_per_ray']:.1f} steps per ray "
                         f"(cells {steps['cells_per_ray']:.2f}, blocks {steps['blocks_per_ray']:.2f}, "
                         f"DAG steps {steps['dag_steps_per_ray']:.2f}; 4x2 quads: max "
                         f"{steps['quad_max_steps']:.1f}, efficiency {steps['quad_efficiency']:.2f})"
                         if steps else ""), flush=True)
    return rows


def step_statistics(renderer, size):
    """Where the compute backend's rays spend their steps in one restarting frame traced with
    the step counters on (a pipeline variant of its own, so the timed frames do not count):
    per ray, cells visited, block records read, DAG walks and their iterations, and their sum
    (steps_per_ray); the divergence of the 4 x 2 pixel quads whose rays run side by side
    (camera.comp; lavapipe's SIMD8): the mean over quads of the largest pixel's steps, and
    the mean steps over that (1: no lane waits for another)."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    renderer.SetStepStatistics(True)
    renderer.ResetAccumulation()
    render(renderer)
    counts = vtk_to_numpy(renderer.GetStepCounts()).astype(np.int64).reshape(size, size, 8)
    renderer.SetStepStatistics(False)
    rays, cells, _, blocks, walks, dag_steps = (counts[:, :, i].sum() for i in range(6))
    per_pixel = counts[:, :, 1] + counts[:, :, 3] + counts[:, :, 5]  # [y, x]
    quads = per_pixel[: size - size % 2, : size - size % 4]
    quads = quads.reshape(quads.shape[0] // 2, 2, quads.shape[1] // 4, 4).transpose(0, 2, 1, 3)
    quads = quads.reshape(-1, 8)
    busiest = float(quads.max(axis=1).mean())
    rays = max(int(rays), 1)
    return dict(
        rays_per_pixel=round(rays / (size * size), 4), cells_per_ray=round(cells / rays, 4),
        blocks_per_ray=round(blocks / rays, 4), walks_per_ray=round(walks / rays, 4),
        dag_steps_per_ray=round(dag_steps / rays, 4),
        steps_per_ray=round((cells + blocks + dag_steps) / rays, 4),
        quad_max_steps=round(busiest, 3),
        quad_efficiency=round(float(quads.mean()) / busiest, 4) if busiest > 0 else 1.0)


def print_frame_table(rows, name):
    rows = [r for r in rows if r["kind"] == "frame" and r["volume"] == name]
    anchored = name == "voronoi256"
    print(f"\n{name}: ms per frame, 1 spp (accumulating / restarting), and device bytes of encoding + "
          "acceleration   [paper code on lavapipe, voronoi256, NEE off: reported, not measured here]")
    print(f"{'size':>9} {'LOD':>6} {'b':>2} {'NEE':>4} | {'rt':>15} | {'compute':>15} | {'rt/compute':>10} | "
          f"{'rt MB':>6} {'cmp MB':>6} | {'steps/ray':>9} {'quad max':>8} {'quad eff':>8}   paper")
    keys = []
    for r in rows:
        key = (r["width"], r["lod"], r["bounces"], r["nee"])
        if key not in keys:
            keys.append(key)
    for size, lod, bounces, nee in keys:
        by = {r["backend"]: r for r in rows if (r["width"], r["lod"], r["bounces"], r["nee"]) ==
              (size, lod, bounces, nee)}
        if set(by) != set(BACKENDS):
            continue
        mb = lambda b: (by[b]["bytes_encoding"] + by[b]["bytes_acceleration"]) / 1e6
        anchor = ANCHORS_MS.get((lod, bounces), "") if size == 256 and anchored and not nee else ""
        print(f"{size:>4}x{size:<4} {lod:>6} {bounces:>2} {'on' if nee else 'off':>4} | "
              f"{by['rt']['ms_median']:6.1f} / {by['rt']['ms_restart_median']:6.1f} | "
              f"{by['compute']['ms_median']:6.1f} / {by['compute']['ms_restart_median']:6.1f} | "
              f"{by['rt']['ms_median'] / by['compute']['ms_median']:10.2f} | "
              f"{mb('rt'):6.2f} {mb('compute'):6.2f} | {by['compute'].get('steps_per_ray', float('nan')):9.2f} "
              f"{by['compute'].get('quad_max_steps', float('nan')):8.1f} "
              f"{by['compute'].get('quad_efficiency', float('nan')):8.2f}   {anchor}")


def find_volcanite(path):
    for candidate in (path, os.environ.get("VOLCANITE"), shutil.which("volcanite")):
        if candidate and pathlib.Path(candidate).is_file():
            return str(candidate)
    return None


def volcanite_comparison(binary, template, volumes, sizes, frames, rounds, out):
    """Volcanite's median frame time in its default view against ours in the same view."""
    rows = []
    camera = _volcanite.CAMERA
    for name, volume in volumes:
        nrrd = out / "volcanite" / f"{name}.nrrd"
        if not nrrd.with_suffix(".csgv").is_file():
            _volcanite.write_input(volume.to_numpy(axis_order="zyx"), nrrd)
        csgv = _volcanite.compress(binary, nrrd)
        nrrd.unlink(missing_ok=True)  # raw labels (512 MB for em_like512): the CSGV file is kept
        for size in sizes:
            renderers = {}
            for backend in BACKENDS:
                r = make_renderer(volume, size, "voxel", 1, True, backend)
                r.SetCameraViewAngle(camera["view_angle"])
                if not r.ResetCamera(camera["azimuth"], camera["elevation"], camera["zoom"]):
                    raise RuntimeError("ResetCamera failed")
                render(r)  # warm-up: shader compilation
                renderers[backend] = r
            medians = {key: [] for key in (*BACKENDS, "volcanite")}
            for _ in range(rounds):
                for backend, r in renderers.items():
                    times = []
                    for _ in range(frames):
                        render(r)
                        times.append(r.GetLastFrameMilliseconds())
                    medians[backend].append(statistics.median(times))
                medians["volcanite"].append(_volcanite.frame_ms(
                    binary, template, csgv, size, size, frames, out / "volcanite"))
            for key, values in medians.items():
                rows.append(dict(kind="volcanite" if key == "volcanite" else "matched",
                                 volume=name, backend="" if key == "volcanite" else key,
                                 width=size, height=size, lod="voxel", bounces=1, nee=1, spp=1,
                                 frames=frames, ms_median=round(statistics.median(values), 3),
                                 ms_min=round(min(values), 3)))
            ratio = statistics.median(medians["compute"]) / statistics.median(medians["volcanite"])
            print(f"  {name:<24} {size:>4}: compute {statistics.median(medians['compute']):8.2f} ms, "
                  f"rt {statistics.median(medians['rt']):8.2f} ms, Volcanite "
                  f"{statistics.median(medians['volcanite']):8.2f} ms (rounds "
                  f"{', '.join(f'{v:.1f}' for v in medians['volcanite'])}): compute / Volcanite "
                  f"{ratio:.2f}", flush=True)
    return rows


def print_volcanite_table(rows, measured):
    if measured:
        print("\nAgainst Volcanite in its default view, voxel LOD, primary + one shadow/occlusion "
              "ray per pixel (medians of the rounds)")
        print(f"{'volume':<24} {'size':>5} {'compute ms':>10} {'rt ms':>8} {'Volcanite ms':>13} "
              f"{'compute / Volcanite':>20}")
        for r in rows:
            if r["kind"] != "volcanite":
                continue
            ours = {m["backend"]: m["ms_median"] for m in rows if m["kind"] == "matched"
                    and m["volume"] == r["volume"] and m["width"] == r["width"]}
            print(f"{r['volume']:<24} {r['width']:>5} {ours['compute']:10.2f} {ours['rt']:8.2f} "
                  f"{r['ms_median']:13.2f} {ours['compute'] / r['ms_median']:20.2f}")
        return
    print("\nAgainst Volcanite, 256x256, voxel LOD, primary + one shadow/occlusion ray per pixel"
          "   [Volcanite: anchors.md's same-run figures, reported, not measured here]")
    print(f"{'volume':<24} {'compute ms':>10} {'rt ms':>8} {'Volcanite ms':>14} {'compute MB':>10} "
          f"{'Volcanite MB':>12} {'bytes ratio':>11}")
    for name in sorted({r["volume"] for r in rows if r["kind"] == "frame"}):
        pick = {r["backend"]: r for r in rows if r["kind"] == "frame" and r["volume"] == name
                and r["width"] == 256 and r["lod"] == "voxel" and r["bounces"] == 1 and r["nee"] == 1}
        if set(pick) != set(BACKENDS) or name not in VOLCANITE_REPORTED:
            continue
        ours_mb = (pick["compute"]["bytes_encoding"] + pick["compute"]["bytes_acceleration"]) / 1e6
        theirs, theirs_mb = VOLCANITE_REPORTED[name][0], VOLCANITE_REPORTED[name][1] / 1e6
        print(f"{name:<24} {pick['compute']['ms_median']:10.2f} {pick['rt']['ms_median']:8.2f} "
              f"{theirs:>14} {ours_mb:10.2f} {theirs_mb:12.2f} {ours_mb / theirs_mb:11.2f}")


def plot_backends(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    frames = [r for r in rows if r["kind"] == "frame"]
    if not frames:
        return
    size = 256 if any(r["width"] == 256 for r in frames) else min(r["width"] for r in frames)
    picked = [r for r in frames if r["width"] == size and r["lod"] == "voxel" and r["bounces"] == 1
              and r["nee"] == 1]
    names = sorted({r["volume"] for r in picked})
    if not names:
        return
    fig, ax = plt.subplots(figsize=(8, 4))
    x = np.arange(len(names))
    for offset, backend, color in ((-0.2, "rt", "tab:orange"), (0.2, "compute", "tab:blue")):
        ms = [next((r["ms_median"] for r in picked if r["volume"] == n and r["backend"] == backend),
                   np.nan) for n in names]
        ax.bar(x + offset, ms, width=0.4, color=color, label=backend)
    ax.set_xticks(x)
    ax.set_xticklabels(names, rotation=30, ha="right", fontsize=8)
    ax.set_ylabel(f"ms per frame ({size}x{size}, voxel LOD, 1 spp)")
    ax.set_title("Both backends, primary + occlusion ray")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


light = _scenes.sun_and_sky


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
        for nee, denoise in ((True, False), (False, False), (True, True)):
            r = make_renderer(volume, size, lod, 4, nee, denoise=denoise)
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
                    lod=lod, bounces=4, nee=int(nee), denoise=int(denoise),
                    spp=r.GetAccumulatedSamples(),
                    seconds=round(r.GetRenderSeconds(), 6), rmse=f"{rmse:.6g}",
                    mean_rel_error=f"{rel:.6g}"))
                checkpoint *= 2
            last = rows[-1]
            print(f"    NEE {'on ' if nee else 'off'}, denoiser {'on ' if denoise else 'off'}: "
                  f"{last['spp']} spp, {last['seconds']:.2f} s, "
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
        for nee, denoise, style, name in ((1, 0, "-o", "NEE + MIS"),
                                          (0, 0, "--s", "no NEE (paper estimator)"),
                                          (1, 1, ":^", "NEE + MIS, denoised")):
            curve = [r for r in errors if r["lod"] == lod and r["nee"] == nee
                     and r.get("denoise", 0) == denoise]
            if not curve:
                continue
            ax.loglog([max(r["seconds"], 1e-6) for r in curve], [float(r["rmse"]) for r in curve],
                      style, color=colors[lod], markersize=3, label=f"{lod}, {name}")
    ax.set_xlabel("tracing time (s)")
    ax.set_ylabel("RMSE vs reference")
    ax.set_title("Path tracer error against run time (disk sun + sky)")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a small volume at a tiny size (seconds)")
    parser.add_argument("--out", default=str(REPO / "bench" / "out"), help="folder for the CSV and plots")
    parser.add_argument("--frames", type=int, default=5, help="timed rounds per configuration (median)")
    parser.add_argument("--sizes", type=int, nargs="+", help="image sizes (default 256 512)")
    parser.add_argument("--volumes", nargs="+", help="shared volumes to time (default: all)")
    parser.add_argument("--error-size", type=int, default=128, help="image size of the error study")
    parser.add_argument("--reference-spp", type=int, default=2048, help="samples of the reference")
    parser.add_argument("--max-spp", type=int, default=256, help="last checkpoint of the error curves")
    parser.add_argument("--generated", nargs="*", default=None,
                        help="generated volumes to time as well (bench/_em_volumes.py: em_like<n>, "
                             "tiled2_<shared volume>; built once, kept in --out as .svdag); "
                             "default em_like512 (--quick: em_like48)")
    parser.add_argument("--volcanite", help="path of a Volcanite binary (else $VOLCANITE or PATH)")
    parser.add_argument("--volcanite-command", default=_volcanite.DEFAULT_COMMAND,
                        help="how Volcanite renders one volume (placeholders {binary} {volume} "
                             "{width} {height} {frames} {image} {log}); its frame time is the "
                             "median its evaluation log {log} gets, else the last '<n> ms' it "
                             "prints")
    parser.add_argument("--volcanite-frames", type=int, default=60,
                        help="frames per Volcanite run, and per round of ours in its view")
    parser.add_argument("--volcanite-rounds", type=int, default=3,
                        help="interleaved rounds of Volcanite and ours (medians)")
    args = parser.parse_args(argv)
    if args.quick:
        sizes = args.sizes or [32]
        args.frames = min(args.frames, 2)
        args.error_size = min(args.error_size, 24)
        args.reference_spp = min(args.reference_spp, 64)
        args.max_spp = min(args.max_spp, 8)
        lods = ["voxel", "block"]
    else:
        sizes = args.sizes or [256, 512]
        lods = ["voxel", "leaf", "block"]
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    start = time.perf_counter()
    name, volume = load_volume(args.quick)
    print(f"volume {name}: {' x '.join(str(d) for d in volume.dims)} voxels, "
          f"{len(volume.labels)} labels (loaded in {time.perf_counter() - start:.1f} s)")
    print("Frame times:")
    rows = frame_times(volume, name, sizes, args.frames, configurations(name, args.quick))
    print_frame_table(rows, name)
    volumes = [(name, volume)]  # what Volcanite renders too
    if not args.quick:
        from vtksvdag import read

        for path in sorted(SHARED_DATA.glob("*.nrrd")):
            other = path.name[: -len(".nrrd")]
            if other == name or (args.volumes and other not in args.volumes):
                continue
            shared = read(str(path))
            volumes.append((other, shared))
            print(f"Frame times, {other}:")
            rows += frame_times(shared, other, sizes, args.frames, configurations(other, False))
            print_frame_table(rows, other)
    generated = args.generated if args.generated is not None else (
        ["em_like48"] if args.quick else ["em_like512"])
    for other in generated:
        built = time.perf_counter()
        em = _em_volumes.cached_volume(other, out, SHARED_DATA)
        print(f"Frame times, {other} (generated, {' x '.join(str(d) for d in em.dims)} voxels, "
              f"{len(em.labels)} labels, ready in {time.perf_counter() - built:.1f} s):")
        configs = configurations(other, True) if args.quick else [(lod, 1, True) for lod in ("voxel", "block")]
        rows += frame_times(em, other, sizes, args.frames, configs)
        print_frame_table(rows, other)
        volumes.append((other, em))

    binary = find_volcanite(args.volcanite)
    if binary:
        print(f"\nVolcanite ({binary}) and ours in its default view:")
        rows += volcanite_comparison(binary, args.volcanite_command, volumes, sizes,
                                     args.volcanite_frames, args.volcanite_rounds, out)
    print_volcanite_table(rows, measured=binary is not None)

    print(f"\nError against run time ({args.error_size}x{args.error_size}, 4 bounces):")
    rows += error_curves(volume, name, args.error_size, lods, args.reference_spp, args.max_spp)

    print(f"\n{'LOD':>6} {'NEE':>4} {'spp':>5} {'seconds':>9} {'RMSE':>10} {'mean rel':>9}")
    for r in rows:
        if r["kind"] == "error":
            print(f"{r['lod']:>6} {'on' if r['nee'] else 'off':>4} {r['spp']:>5} "
                  f"{r['seconds']:9.3f} {float(r['rmse']):10.5f} {float(r['mean_rel_error']):9.4f}")

    csv_path = out / "render.csv"
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS, restval="")
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, out / "render_error.png")
    plot_backends(rows, out / "render_backends.png")
    print(f"\nwrote {csv_path}, render_error.png and render_backends.png "
          f"({time.perf_counter() - start:.0f} s)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
