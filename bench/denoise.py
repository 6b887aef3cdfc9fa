#!/usr/bin/env python3
"""The label-aware denoiser: error against run time with it off and on, its cost per frame.

Run from the repository root:

    .venv/bin/python bench/denoise.py [--quick] [--volumes NAME ...] [--sizes 256 512]
        [--reference-spp 4096] [--max-spp 16] [--frames 8] [--out DIR]

On every volume in ../shared/data (or --volumes), at every --sizes (square images), camera
framing the volume (azimuth 30, elevation 20), voxel LOD, 4 bounces, NEE, a disk sun (8 degrees)
and a sky, with vtkSegmentationSVDAGRenderer:

  reference   the denoiser off, seed 1, --reference-spp samples per pixel (64 per pass)
  error       for the denoiser off and on, seed 2, one sample per pass: after 1, 2, 4, ...,
              --max-spp samples, the RMSE of the linear RGB against the reference over every
              pixel, and over the label-boundary pixels only (a labelled pixel with a 4-neighbour
              of another label, background included: where a filter that blurs across objects
              would show), against the renderer's tracing seconds so far (GetRenderSeconds: the
              GPU passes, the denoiser included)
  cost        --frames restarting one-sample frames (ResetAccumulation before each: what every
              frame costs while the camera moves) with the denoiser off and on, interleaved;
              the median wall milliseconds of Render() and the denoiser's share
Prints the tables and the targets (denoised 1-sample RMSE at most the 16-sample RMSE without
the denoiser, on all and on boundary pixels; the denoiser at most 15% of a 1-sample frame at
512x512), writes denoise.csv, denoise_error.png (RMSE against seconds, off and on, per volume
and size) and denoise_<volume>_<size>.png (1 sample off | 1 sample on | 16 samples off |
reference) to --out (default build/bench). --quick: a generated 48^3 volume at 96x96, a
256-sample reference, 3 frames (a smoke test).
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
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import _scenes  # noqa: E402
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")
COLUMNS = ["kind", "volume", "size", "denoise", "spp", "seconds", "rmse", "rmse_boundary",
           "ms_median", "boundary_pixels"]


def generated_volume():
    import vtksvdag

    return vtksvdag.from_numpy(_scenes.generated_labels(48), axis_order="zyx")


def make_renderer(volume, size, denoise, seed):
    from vtksvdag.vtkSVDAGRendering import vtkSegmentationSVDAGRenderer

    r = vtkSegmentationSVDAGRenderer()
    r.SetInputData(volume.dataobject)
    r.SetWidth(size)
    r.SetHeight(size)
    s = r.GetSettings()
    s.SetLOD("voxel")
    s.SetMaximumBounces(4)
    s.SetNextEventEstimation(True)
    s.SetSamplesPerPixel(1)
    s.SetSeed(seed)
    s.SetDenoise(denoise)
    _scenes.sun_and_sky(r)
    if not r.ResetCamera(30, 20, 1.0):
        raise RuntimeError("ResetCamera failed")
    return r


render, hdr = _scenes.render, _scenes.hdr


def boundary_mask(r, size):
    """Labelled pixels with a 4-neighbour of another label (background included)."""
    label = _scenes.point_array(r, "Label").reshape(size, size)
    edge = np.zeros_like(label, dtype=bool)
    edge[:, 1:] |= label[:, 1:] != label[:, :-1]
    edge[:, :-1] |= label[:, :-1] != label[:, 1:]
    edge[1:, :] |= label[1:, :] != label[:-1, :]
    edge[:-1, :] |= label[:-1, :] != label[1:, :]
    return (edge & (label != 0)).reshape(-1)


def rmse(image, reference, mask=None):
    d = image - reference
    if mask is not None:
        d = d[mask]
    return float(np.sqrt(np.mean(d ** 2))) if d.size else float("nan")


def to_srgb8(linear):
    x = np.clip(linear, 0, None)
    x = x / (1 + x)
    x = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return (np.clip(x, 0, 1) * 255 + 0.5).astype(np.uint8)


def measure(volume, name, size, reference_spp, max_spp, frames, out):
    rows = []
    ref = make_renderer(volume, size, False, 1)
    ref.GetSettings().SetSamplesPerPixel(min(reference_spp, 64))
    while ref.GetAccumulatedSamples() < reference_spp:
        render(ref)
    reference = hdr(ref)
    boundary = boundary_mask(ref, size)
    print(f"  {name} {size}x{size}: reference {ref.GetAccumulatedSamples()} spp in "
          f"{ref.GetRenderSeconds():.1f} s; {int(boundary.sum())} boundary pixels", flush=True)
    shots = {}
    for denoise in (False, True):
        r = make_renderer(volume, size, denoise, 2)
        render(r)  # warm-up (shader compilation), then a fresh accumulation
        r.ResetAccumulation()
        render(r)
        checkpoint = 1
        while checkpoint <= max_spp:
            while r.GetAccumulatedSamples() < checkpoint:
                render(r)
            image = hdr(r)
            if checkpoint in (1, max_spp):
                shots[denoise, checkpoint] = image
            rows.append(dict(kind="error", volume=name, size=size, denoise=int(denoise),
                             spp=r.GetAccumulatedSamples(), seconds=round(r.GetRenderSeconds(), 6),
                             rmse=f"{rmse(image, reference):.6g}",
                             rmse_boundary=f"{rmse(image, reference, boundary):.6g}",
                             boundary_pixels=int(boundary.sum())))
            checkpoint *= 2

    renderers = {d: make_renderer(volume, size, d, 3) for d in (False, True)}
    for r in renderers.values():
        render(r)
    times = {False: [], True: []}
    for _ in range(frames):
        for denoise, r in renderers.items():
            r.ResetAccumulation()
            start = time.perf_counter()
            render(r)
            times[denoise].append((time.perf_counter() - start) * 1000)
    for denoise in (False, True):
        rows.append(dict(kind="cost", volume=name, size=size, denoise=int(denoise), spp=1,
                         ms_median=f"{statistics.median(times[denoise]):.3f}"))

    import imageio.v3 as iio

    panels = [shots[False, 1], shots[True, 1], shots[False, max_spp], reference]
    strip = np.concatenate([to_srgb8(p).reshape(size, size, 3)[::-1] for p in panels], axis=1)
    iio.imwrite(out / f"denoise_{name}_{size}.png", strip)
    return rows


def report(rows, max_spp):
    print("\nRMSE against the reference (all pixels / boundary pixels), seconds of tracing")
    print(f"{'volume':24s} {'size':>5s} {'denoise':>7s} " + " ".join(
        f"{'spp ' + str(s):>22s}" for s in (1, max_spp)))
    keys = sorted({(r["volume"], r["size"]) for r in rows})
    ok = True
    for volume, size in keys:
        err = {(r["denoise"], r["spp"]): r for r in rows
               if r["kind"] == "error" and r["volume"] == volume and r["size"] == size}
        for d in (0, 1):
            cells = []
            for s in (1, max_spp):
                e = err.get((d, s))
                cells.append(f"{float(e['rmse']):.4f}/{float(e['rmse_boundary']):.4f} "
                             f"{e['seconds']:.2f}s" if e else "-")
            print(f"{volume:24s} {size:5d} {'on' if d else 'off':>7s} " +
                  " ".join(f"{c:>22s}" for c in cells))
        on1, off16 = err.get((1, 1)), err.get((0, max_spp))
        if on1 and off16:
            a = float(on1["rmse"]) / float(off16["rmse"])
            b = float(on1["rmse_boundary"]) / float(off16["rmse_boundary"])
            ok &= a <= 1 and b <= 1
            print(f"{'':24s} {'':5s} denoised 1 spp / {max_spp} spp off: RMSE {a:.2f}x, "
                  f"boundary {b:.2f}x (target <= 1)")
    print("\ncost of the denoiser: median ms of a restarting 1-sample frame")
    for volume, size in keys:
        cost = {r["denoise"]: float(r["ms_median"]) for r in rows
                if r["kind"] == "cost" and r["volume"] == volume and r["size"] == size}
        share = (cost[1] - cost[0]) / cost[0]
        print(f"{volume:24s} {size:5d}  off {cost[0]:8.2f}  on {cost[1]:8.2f}  denoiser "
              f"{100 * share:5.1f}% of the frame (target <= 15% at 512)")
    return ok


def plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    keys = sorted({(r["volume"], r["size"]) for r in rows if r["kind"] == "error"})
    columns = min(4, len(keys))
    lines = (len(keys) + columns - 1) // columns
    fig, axes = plt.subplots(lines, columns, figsize=(4 * columns, 3.2 * lines), squeeze=False)
    for ax, (volume, size) in zip(axes.flat, keys):
        for d, style in ((0, "o-"), (1, "s-")):
            pts = [r for r in rows if r["kind"] == "error" and r["volume"] == volume
                   and r["size"] == size and r["denoise"] == d]
            ax.loglog([r["seconds"] for r in pts], [float(r["rmse"]) for r in pts], style,
                      label=f"denoise {'on' if d else 'off'}")
            ax.loglog([r["seconds"] for r in pts], [float(r["rmse_boundary"]) for r in pts],
                      style, alpha=0.4, label=f"boundary, {'on' if d else 'off'}")
        ax.set_title(f"{volume} {size}^2", fontsize=9)
        ax.set_xlabel("seconds")
        ax.set_ylabel("RMSE")
    for ax in list(axes.flat)[len(keys):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="a generated volume, tiny (smoke test)")
    parser.add_argument("--volumes", nargs="+", help="names in ../shared/data (default: all)")
    parser.add_argument("--sizes", nargs="+", type=int, default=[256, 512])
    parser.add_argument("--reference-spp", type=int, default=4096)
    parser.add_argument("--max-spp", type=int, default=16)
    parser.add_argument("--frames", type=int, default=8)
    parser.add_argument("--out", default=str(REPO / "build" / "bench"))
    args = parser.parse_args(argv)
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    import vtksvdag

    if args.quick:
        volumes = [("generated48", generated_volume())]
        args.sizes, args.reference_spp, args.frames = [96], 256, 3
    else:
        names = args.volumes or sorted(p.stem for p in SHARED_DATA.glob("*.nrrd"))
        if not names:
            print(f"BENCHMARK FAILED: no volumes in {SHARED_DATA}")
            return 1
        volumes = [(n, vtksvdag.read(str(SHARED_DATA / f"{n}.nrrd"))) for n in names]
    print(f"machine: {os.cpu_count()} cores; sizes {args.sizes}, reference {args.reference_spp} "
          f"spp, up to {args.max_spp} spp", flush=True)
    rows = []
    for name, volume in volumes:
        for size in args.sizes:
            rows += measure(volume, name, size, args.reference_spp, args.max_spp, args.frames, out)
    report(rows, args.max_spp)
    with open(out / "denoise.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    plot(rows, out / "denoise_error.png")
    print(f"\nwrote {out / 'denoise.csv'}, {out / 'denoise_error.png'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
