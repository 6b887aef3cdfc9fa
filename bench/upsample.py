#!/usr/bin/env python3
"""Guided upsampling: error against frame time of reduced frames, guided and pixel-replicated.

Run from the repository root:

    .venv/bin/python bench/upsample.py [--quick] [--volumes NAME ...] [--size 512]
        [--reference-spp 1024] [--frames 5] [--out DIR]

On every volume in ../shared/data (or --volumes), a --size square image framing the volume
(bench/denoise.py's camera, lighting, voxel LOD, 4 bounces, NEE; the denoiser on, as the
mapper's interactive frames have it), with vtkSegmentationSVDAGRenderer, for reductions r = 1,
2, 4, 8 (the mapper's FrameBudget ladder):

  guided      TraceReduction r: one sample per pixel traced at 1/r of the size, shown at full
              size by the renderer's guided upsampling (its frame time includes the guides'
              primary-only trace at full size: every interactive frame has a new view)
  replicated  the same paths traced at ceil(size / r) by a renderer of that size, each pixel
              shown r x r times (what the mapper drew before guided upsampling)

Per row: the median frame milliseconds over --frames restarting frames (GetLastFrameMilliseconds),
the RMSE of the linear RGB against a --reference-spp full-size reference (the denoiser off), over
all pixels and over label-boundary pixels, and the fraction of labelled pixels whose shown label
(the guide's, or the replicated pixel's) differs from the reference's. Writes upsample.csv and
upsample_<volume>.png (guided | replicated at the largest reduction | reference) to --out
(default build/bench). --quick: a generated 48^3 volume at 96x96, a 64-sample reference, 2 frames.
"""
from __future__ import annotations

import argparse
import csv
import pathlib
import statistics
import sys

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import _scenes  # noqa: E402
from denoise import (SHARED_DATA, boundary_mask, generated_volume, make_renderer,  # noqa: E402
                     rmse, to_srgb8)

REDUCTIONS = (1, 2, 4, 8)
COLUMNS = ["volume", "size", "reduction", "kind", "ms_median", "rmse", "rmse_boundary",
           "label_mismatch"]


def frames_of(r, frames):
    """Median ms of restarting one-sample frames, and the last frame's HDR and labels."""
    times = []
    for _ in range(frames):
        r.ResetAccumulation()
        _scenes.render(r)
        times.append(r.GetLastFrameMilliseconds())
    return statistics.median(times), _scenes.hdr(r), _scenes.point_array(r, "Label").copy()


def replicate(image, small, size, reduction):
    """A small image's pixels repeated reduction x reduction times, cut to size x size."""
    channels = image.reshape(small, small, -1)
    big = np.repeat(np.repeat(channels, reduction, axis=0), reduction, axis=1)[:size, :size]
    return big.reshape(size * size, -1)


def measure(volume, name, size, reference_spp, frames):
    reference_renderer = make_renderer(volume, size, False, 1)
    reference_renderer.GetSettings().SetSamplesPerPixel(64)
    reference_renderer.SetPassesPerRender(max(1, reference_spp // 64))
    _scenes.render(reference_renderer)
    reference = _scenes.hdr(reference_renderer)
    reference_labels = _scenes.point_array(reference_renderer, "Label").copy()
    boundary = boundary_mask(reference_renderer, size)
    labelled = reference_labels != 0
    rows, images = [], {}
    for reduction in REDUCTIONS:
        guided = make_renderer(volume, size, True, 2)
        guided.SetTraceReduction(reduction)
        kinds = [("guided", guided, size)]
        if reduction > 1:
            small = (size + reduction - 1) // reduction
            kinds.append(("replicated", make_renderer(volume, small, True, 2), small))
        for kind, r, traced in kinds:
            _scenes.render(r)  # compiles; not timed
            ms, image, labels = frames_of(r, frames)
            if kind == "replicated":
                image = replicate(image, traced, size, reduction)
                labels = replicate(labels.reshape(-1, 1), traced, size, reduction).reshape(-1)
            mismatch = float(np.mean(labels[labelled] != reference_labels[labelled]))
            rows.append({"volume": name, "size": size, "reduction": reduction, "kind": kind,
                         "ms_median": round(ms, 3), "rmse": rmse(image, reference),
                         "rmse_boundary": rmse(image, reference, boundary),
                         "label_mismatch": round(mismatch, 5)})
            images[(kind, reduction)] = image
    top = max(REDUCTIONS)
    strip = np.concatenate([to_srgb8(images[("guided", top)]).reshape(size, size, 3),
                            to_srgb8(images[("replicated", top)]).reshape(size, size, 3),
                            to_srgb8(reference).reshape(size, size, 3)], axis=1)[::-1]
    return rows, strip


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--volumes", nargs="+", help="names in ../shared/data (default: all)")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--reference-spp", type=int, default=1024)
    parser.add_argument("--frames", type=int, default=5)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("build/bench"))
    args = parser.parse_args(argv)
    import vtksvdag
    from PIL import Image

    if args.quick:
        volumes = [("generated48", generated_volume())]
        args.size, args.reference_spp, args.frames = 96, 64, 2
    else:
        names = args.volumes or sorted(p.stem for p in SHARED_DATA.glob("*.nrrd"))
        if not names:
            print(f"BENCHMARK FAILED: no volumes in {SHARED_DATA}")
            return 1
        volumes = [(n, vtksvdag.read(str(SHARED_DATA / f"{n}.nrrd"))) for n in names]
    args.out.mkdir(parents=True, exist_ok=True)
    rows = []
    for name, volume in volumes:
        volume_rows, strip = measure(volume, name, args.size, args.reference_spp, args.frames)
        rows += volume_rows
        Image.fromarray(strip).save(args.out / f"upsample_{name}.png")
    with open(args.out / "upsample.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"{'volume':24} {'r':>2} {'kind':10} {'ms':>8} {'rmse':>8} {'boundary':>9} "
          f"{'labels off':>10}")
    for row in rows:
        print(f"{row['volume']:24} {row['reduction']:2} {row['kind']:10} {row['ms_median']:8.1f} "
              f"{row['rmse']:8.4f} {row['rmse_boundary']:9.4f} {row['label_mismatch']:10.4f}")
    for name, _ in volumes:
        for reduction in REDUCTIONS[1:]:
            g, p = ([row for row in rows if row["volume"] == name and row["reduction"] == reduction
                     and row["kind"] == kind][0] for kind in ("guided", "replicated"))
            print(f"{name} r={reduction}: guided / replicated RMSE {g['rmse'] / p['rmse']:.2f}, "
                  f"boundary {g['rmse_boundary'] / p['rmse_boundary']:.2f}, "
                  f"frame time {g['ms_median'] / p['ms_median']:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
