#!/usr/bin/env python3
"""Default label colors: how different are the colors of labels that touch?

Run from the repository root:

    .venv/bin/python bench/palette.py [--quick] [--out bench/out]

For every volume in ../shared/data (or $VTKSVDAG_SHARED_DATA; skipped with a message when
absent) and a generated Voronoi volume, it takes the label pairs that touch across a voxel face
(``SegmentationVolume.label_adjacency``, from the compressed form; checked here against a numpy
brute force on the decoded array, a mismatch stops the run with exit status 1) and measures the
CIELAB (CIE76) distance between the display colors of the two labels of every pair, for three
colorings:

- ``distinct``: the new default (``SegmentationVolume.distinct_colors``: the categorical palette
  assigned over the adjacency);
- ``tab20``: matplotlib's tab20 cycled in label order, as ``add_segmentation(cmap="tab20")``
  does;
- ``hash``: the renderer's hash of the label index (GpuLayout.h's svdagLabelColor, a linear base
  color, shown sRGB-encoded), the default before the palette (``cmap="hash"``).

Columns: the fraction of touching pairs at distance >= 25 (clearly different colors), the median
and the 5th percentile. Target: the distinct coloring has >= 95 % of the pairs at >= 25 on every
volume. Prints a table and writes ``palette.csv`` to the output folder. The Lab conversion here is
this script's own (numpy), independent of the C++ core's.
"""
from __future__ import annotations

import argparse
import csv
import os
import pathlib
import sys
import time

import numpy as np

import vtksvdag
from vtksvdag import synthetic

REPO = pathlib.Path(__file__).resolve().parents[1]
DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")
THRESHOLD = 25.0
TARGET = 0.95
COLUMNS = ["volume", "dims_xyz", "labels", "touching_pairs", "adjacency_s", "coloring",
           "frac_ge_25", "median", "p5"]


def srgb_to_lab(rgb):
    """CIELAB (D65) of display sRGB colors in [0, 1], shape (..., 3)."""
    rgb = np.asarray(rgb, float)
    linear = np.where(rgb <= 0.04045, rgb / 12.92, ((rgb + 0.055) / 1.055) ** 2.4)
    m = np.array([[0.4124, 0.3576, 0.1805], [0.2126, 0.7152, 0.0722], [0.0193, 0.1192, 0.9505]])
    xyz = linear @ m.T / np.array([0.95047, 1.0, 1.08883])
    d = 6 / 29
    f = np.where(xyz > d**3, np.cbrt(xyz), xyz / (3 * d * d) + 4 / 29)
    return np.stack([116 * f[..., 1] - 16, 500 * (f[..., 0] - f[..., 1]),
                     200 * (f[..., 1] - f[..., 2])], axis=-1)


def hash_colors(n):
    """svdagLabelColor of label indices 0..n-1 (linear RGB), sRGB-encoded for display."""
    x = np.arange(n, dtype=np.uint64) & np.uint64(0xFFFFFFFF)
    mask = np.uint64(0xFFFFFFFF)
    x ^= x >> np.uint64(16)
    x = (x * np.uint64(0x7FEB352D)) & mask
    x ^= x >> np.uint64(15)
    x = (x * np.uint64(0x846CA68B)) & mask
    x ^= x >> np.uint64(16)
    c = np.stack([x & np.uint64(255), (x >> np.uint64(8)) & np.uint64(255),
                  (x >> np.uint64(16)) & np.uint64(255)], axis=-1).astype(float) / 255.0
    linear = 0.15 + 0.8 * c
    return np.where(linear <= 0.0031308, 12.92 * linear, 1.055 * linear ** (1 / 2.4) - 0.055)


def tab20_colors(n):
    import matplotlib

    colormap = matplotlib.colormaps["tab20"]
    return np.array([colormap(i % colormap.N)[:3] for i in range(n)])


def brute_force_pairs(dense):
    """Touching label pairs of a dense (x, y, z) array, values a < b, without the background."""
    background = 0
    found = []
    for axis in range(3):
        a = np.moveaxis(dense, axis, 0)
        lo, hi = a[:-1].ravel(), a[1:].ravel()
        keep = (lo != hi) & (lo != background) & (hi != background)
        pairs = np.stack([np.minimum(lo[keep], hi[keep]), np.maximum(lo[keep], hi[keep])], axis=1)
        found.append(np.unique(pairs, axis=0) if len(pairs) else pairs)
    allpairs = np.concatenate(found) if found else np.empty((0, 2), dense.dtype)
    return np.unique(allpairs, axis=0) if len(allpairs) else allpairs


def measure(name, volume, check=True):
    start = time.perf_counter()
    pairs = volume.label_adjacency()
    seconds = time.perf_counter() - start
    if check:
        expected = brute_force_pairs(volume.to_numpy())
        if not np.array_equal(pairs, expected.astype(pairs.dtype)):
            print(f"BENCHMARK FAILED: {name}: adjacency differs from the numpy brute force",
                  file=sys.stderr)
            sys.exit(1)
    index = np.searchsorted(volume.labels, pairs)
    n = len(volume.labels)
    colorings = {"distinct": volume.distinct_colors(), "tab20": tab20_colors(n),
                 "hash": hash_colors(n)}
    rows = []
    for coloring, rgb in colorings.items():
        lab = srgb_to_lab(rgb)
        d = np.linalg.norm(lab[index[:, 0]] - lab[index[:, 1]], axis=1) if len(index) else np.zeros(0)
        rows.append({
            "volume": name, "dims_xyz": "x".join(str(v) for v in volume.dims), "labels": n,
            "touching_pairs": len(index), "adjacency_s": f"{seconds:.3f}", "coloring": coloring,
            "frac_ge_25": f"{np.mean(d >= THRESHOLD) if len(d) else 1.0:.4f}",
            "median": f"{np.median(d) if len(d) else 0:.1f}",
            "p5": f"{np.percentile(d, 5) if len(d) else 0:.1f}",
        })
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--quick", action="store_true", help="the small volumes only (a smoke test)")
    parser.add_argument("--out", default=str(REPO / "bench" / "out"), help="output folder")
    args = parser.parse_args(argv)

    volumes = [("voronoi64_100", lambda: vtksvdag.from_numpy(synthetic.voronoi((64, 64, 64), 100, seed=1)))]
    if DATA.is_dir():
        for path in sorted(DATA.glob("*.nrrd")):
            if args.quick and path.stat().st_size > 2_000_000:
                continue
            volumes.append((path.stem, lambda path=path: vtksvdag.read(path)))
    else:
        print(f"skipping the real volumes: {DATA} is missing (set VTKSVDAG_SHARED_DATA)")

    rows = []
    for name, load in volumes:
        rows.extend(measure(name, load()))
    header = f"{'volume':28} {'labels':>6} {'pairs':>7} {'adj s':>6}  " + "  ".join(
        f"{c + ' >=25':>14} {'med':>5} {'p5':>5}" for c in ("distinct", "tab20", "hash"))
    print(header)
    failed = []
    for i in range(0, len(rows), 3):
        r = rows[i:i + 3]
        print(f"{r[0]['volume']:28} {r[0]['labels']:>6} {r[0]['touching_pairs']:>7} "
              f"{r[0]['adjacency_s']:>6}  " + "  ".join(
                  f"{100 * float(x['frac_ge_25']):>13.1f}% {x['median']:>5} {x['p5']:>5}" for x in r))
        if float(r[0]["frac_ge_25"]) < TARGET:
            failed.append(r[0]["volume"])
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "palette.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {out / 'palette.csv'}")
    print(f"target (distinct >= {100 * TARGET:.0f}% of touching pairs at CIELAB distance >= "
          f"{THRESHOLD:.0f}): " + ("met on every volume" if not failed else "MISSED on " + ", ".join(failed)))


if __name__ == "__main__":
    main()
