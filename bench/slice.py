#!/usr/bin/env python3
"""Random-access benchmark: one axis-aligned slice from the compressed form vs a full decode.

Run from the repository root:

    .venv/bin/python bench/slice.py [--quick] [--repeats 5] [--out bench/out]

For a generated 512^3 Voronoi volume (``--quick``: 256^3) and the real volumes in
../shared/data (or $VTKSVDAG_SHARED_DATA; skipped with a message when absent) it times, in the
same run: a full decode (vtkSegmentationSVDAGToImageData, what ``to_numpy`` runs) and the middle
slice on each axis through ``SegmentationVolume.slice`` (the Python API, vtkSegmentationSVDAGSlice
plus its numpy view), each the median of ``--repeats`` runs. Every slice is checked against the
same slice of the full decode (a mismatch stops the run with exit status 1). It prints a table and
writes ``slice.csv`` to the output folder. Target: a slice takes at most 1/50 of a full decode on
every axis (``ratio`` = full / slice >= 50), for volumes large enough that a full decode is not
dominated by the fixed cost of a pipeline update (the table marks the others).
"""
from __future__ import annotations

import argparse
import csv
import os
import pathlib
import platform
import statistics
import sys
import time

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkSMPTools

import vtksvdag
from vtksvdag import synthetic
from vtksvdag.vtkSVDAGCore import vtkSegmentationSVDAGToImageData

REPO = pathlib.Path(__file__).resolve().parents[1]
DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")
TARGET = 50.0
# Below this many voxels a full decode takes about as long as one pipeline update, so the ratio
# measures Python and VTK overhead rather than decoding; such rows are reported, not judged.
JUDGED_MIN_VOXELS = 128**3


def median_seconds(function, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        function()
        times.append(time.perf_counter() - start)
    return statistics.median(times)


def full_decode(volume):
    decoder = vtkSegmentationSVDAGToImageData()
    decoder.SetInputDataObject(0, volume.dataobject)
    decoder.Update()
    image = decoder.GetOutput()
    return vtk_to_numpy(image.GetPointData().GetScalars()).reshape(volume.dims, order="F")


def bench_volume(name, volume, repeats):
    dense = full_decode(volume)  # also the reference of the slice checks
    full = median_seconds(lambda: full_decode(volume), repeats)
    rows = []
    for axis in range(3):
        index = volume.dims[axis] // 2
        got = volume.slice(axis, index)
        if not np.array_equal(got, np.take(dense, index, axis=axis)):
            print(f"BENCHMARK FAILED: the {'xyz'[axis]} slice {index} of {name} differs from the full decode")
            sys.exit(1)
        seconds = median_seconds(lambda: volume.slice(axis, index), max(repeats, 5))
        rows.append({
            "volume": name,
            "dims_xyz": "x".join(str(d) for d in volume.dims),
            "dtype": volume.dtype.name,
            "labels": len(volume.labels),
            "axis": "xyz"[axis],
            "index": index,
            "full_decode_ms": round(full * 1e3, 3),
            "slice_ms": round(seconds * 1e3, 3),
            "ratio": round(full / seconds, 1),
            "judged": volume.n_voxels >= JUDGED_MIN_VOXELS,
            "meets_target": full / seconds >= TARGET,
        })
    return rows


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="256^3 generated volume, no 512^3")
    parser.add_argument("--repeats", type=int, default=3, help="runs per timing (median)")
    parser.add_argument("--out", default=str(REPO / "bench" / "out"), help="output folder")
    args = parser.parse_args(argv)

    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"vtkSMPTools {vtkSMPTools.GetBackend()} with {vtkSMPTools.GetEstimatedNumberOfThreads()} threads")
    rows = []
    n = 256 if args.quick else 512
    start = time.perf_counter()
    array = synthetic.voronoi((n, n, n), 2000, seed=1)
    volume = vtksvdag.from_numpy(array, axis_order="zyx")
    del array
    print(f"generated voronoi{n}_2000 in {time.perf_counter() - start:.1f} s")
    rows += bench_volume(f"voronoi{n}_2000", volume, args.repeats)
    del volume

    if DATA.is_dir():
        for path in sorted(DATA.glob("*.nrrd")):
            rows += bench_volume(path.name[:-len(".nrrd")], vtksvdag.read(path), args.repeats)
    else:
        print(f"skipping the real volumes: {DATA} is missing (set VTKSVDAG_SHARED_DATA)")

    header = f"{'volume':<28} {'dims':>12} {'axis':>4} {'full ms':>9} {'slice ms':>9} {'ratio':>7}  target"
    print(header)
    print("-" * len(header))
    for r in rows:
        verdict = ("ok" if r["meets_target"] else "MISSED") if r["judged"] else "(small: not judged)"
        print(f"{r['volume']:<28} {r['dims_xyz']:>12} {r['axis']:>4} {r['full_decode_ms']:>9.2f} "
              f"{r['slice_ms']:>9.3f} {r['ratio']:>7.1f}  {verdict}")
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    with open(out / "slice.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {out / 'slice.csv'}")
    missed = [r for r in rows if r["judged"] and not r["meets_target"]]
    if missed:
        print(f"target missed (ratio < {TARGET:g}) on {len(missed)} judged rows")


if __name__ == "__main__":
    main()
