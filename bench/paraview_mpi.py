#!/usr/bin/env python3
"""The ParaView plugin on MPI ranks: each rank's peak memory with 2 ranks against 1, in one run.

Run from the repository root after `bash scripts/setup-paraview.sh`, under Xvfb:

    xvfb-run -a -s "-screen 0 1024x768x24" .venv/bin/python bench/paraview_mpi.py [--quick]
        [--volume em_like512] [--size 256] [--repeats 2] [--out DIR]

The volume is a raw NRRD file (uint32, x fastest), written once into --out from a generated
volume (bench/_em_volumes.py: em_like512, 512^3, ~2,500 labels; or tiled2_<shared volume>).
Each measurement is `mpiexec -n RANKS pvbatch --symmetric` (RANKS 1 and 2 alternating within a
repeat): LoadPlugin, SegmentationVolumeReader on the file (each rank reads and compresses its
own z-range), Show ('Segmentation Path Tracing', 1 sample, no bounces), one render at --size.
Every rank reports:

  baseline_mib   resident memory after ParaView's start-up and LoadPlugin, before the reader;
  read_peak_mib  the process's peak resident memory (VmHWM) after the reader's update;
  peak_mib       the process's peak resident memory after the render (the renderer's device,
                 pipelines and images: on lavapipe device memory is host memory);
  piece_mib      the compressed bytes of the rank's piece;
  read_s         the reader's update (reading, compressing).

The ratios printed are 2-rank / 1-rank of the largest rank's: peak, peak above baseline (the
volume and the renderer), and reading peak above baseline (what reading and compressing cost:
one slab, the builder's pools, the piece). Writes
paraview_mpi.csv to --out (default build/bench).
--quick: the bundled examples/data/cells.nrrd, 64x64, one repeat (a smoke test).
"""
from __future__ import annotations

import argparse
import csv
import json
import os
import pathlib
import shutil
import statistics
import subprocess
import sys

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "bench"))
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")
from _paraview_env import PLUGIN, paraview_env  # noqa: E402
FIELDS = ["ranks", "repeat", "rank", "baseline_mib", "read_peak_mib", "peak_mib", "piece_mib",
          "read_s"]

# argv = volume file, size, plugin, output folder. Each rank writes rank-R.json.
CHILD = r"""
import json, os, sys, time
path, size, plugin, out = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]

def status_mib(key):
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) / 1024.0

from paraview import servermanager
from paraview.simple import *
LoadPlugin(plugin, remote=False, ns=globals())
rank = servermanager.vtkProcessModule.GetProcessModule().GetPartitionId()
baseline = status_mib("VmRSS")
reader = SegmentationVolumeReader(FileName=path)
start = time.perf_counter()
reader.UpdatePipeline()
read_s = time.perf_counter() - start
read_peak = status_mib("VmHWM")
view = CreateView("RenderView")
view.ViewSize = [size, size]
display = Show(reader, view)
display.SetRepresentationType("Segmentation Path Tracing")
display.SamplesPerPixel = 1
display.TargetSamplesPerPixel = 1
display.MaximumBounces = 0
ResetCamera(view)
Render(view)
fields = reader.GetClientSideObject().GetOutputDataObject(0).GetFieldData()
piece = fields.GetArray("CompressedBytes")
with open(os.path.join(out, f"rank-{rank}.json"), "w") as f:
    json.dump({"rank": rank, "baseline_mib": baseline, "read_peak_mib": read_peak,
               "peak_mib": status_mib("VmHWM"),
               "piece_mib": 0.0 if piece is None else piece.GetValue(0) / 2**20,
               "read_s": read_s}, f)
"""


def raw_nrrd(name, out):
    """The generated volume `name` as a raw uint32 NRRD in `out` (written once)."""
    path = out / f"{name}.nrrd"
    if not path.is_file():
        import nrrd
        import numpy as np
        from _em_volumes import cached_volume

        volume = cached_volume(name, out, SHARED_DATA)
        labels = volume.to_numpy(axis_order="xyz").astype(np.uint32, copy=False)
        nrrd.write(str(path), labels, {"encoding": "raw"})
    return path


def run_once(ranks, volume, size, out):
    """One `mpiexec -n ranks pvbatch` run: the ranks' reports."""
    folder = out / f"mpi-{ranks}"
    shutil.rmtree(folder, ignore_errors=True)
    folder.mkdir(parents=True)
    script = folder / "child.py"
    script.write_text(CHILD)
    command = ["mpiexec", "--allow-run-as-root", "--oversubscribe", "-n", str(ranks), "pvbatch",
               "--symmetric", str(script), str(volume), str(size), str(PLUGIN), str(folder)]
    for _ in range(3):  # ParaView's X window sometimes fails to open on Xvfb: again
        done = subprocess.run(command, capture_output=True, text=True, env=paraview_env(),
                              timeout=1800)
        if done.returncode == 0 or "bad X server connection" not in done.stdout + done.stderr:
            break
    reports = sorted(folder.glob("rank-*.json"))
    if done.returncode != 0 or len(reports) != ranks:
        raise RuntimeError(f"{ranks} ranks failed (exit {done.returncode}):\n"
                           f"{done.stdout[-2000:]}{done.stderr[-3000:]}")
    return [json.loads(p.read_text()) for p in reports]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="examples/data/cells.nrrd, 64x64, one repeat (a smoke test)")
    parser.add_argument("--volume", default="em_like512",
                        help="generated volume (bench/_em_volumes.py): em_like<n>, tiled2_<name>")
    parser.add_argument("--size", type=int, default=256, help="view width and height")
    parser.add_argument("--repeats", type=int, default=2, help="runs per rank count")
    parser.add_argument("--out", default=str(REPO / "build" / "bench"), help="folder for the CSV")
    args = parser.parse_args(argv)
    if not PLUGIN.is_file() or shutil.which("mpiexec") is None:
        print("the ParaView plugin or mpiexec is missing: run bash scripts/setup-paraview.sh")
        return 1
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    if args.quick:
        volume = REPO / "examples" / "data" / "cells.nrrd"
        args.size, args.repeats = 64, 1
    else:
        volume = raw_nrrd(args.volume, out)

    rows = []
    for repeat in range(args.repeats):
        for ranks in (1, 2):
            for report in run_once(ranks, volume, args.size, out):
                rows.append({"ranks": ranks, "repeat": repeat, **{
                    k: round(v, 4) if isinstance(v, float) else v for k, v in report.items()}})
                print(f"  {ranks} rank(s), repeat {repeat}, rank {report['rank']}: peak "
                      f"{report['peak_mib']:.0f} MiB (baseline {report['baseline_mib']:.0f}), "
                      f"piece {report['piece_mib']:.2f} MiB, read {report['read_s']:.2f} s",
                      flush=True)
    with open(out / "paraview_mpi.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows(rows)

    def largest(ranks, key):
        """Median over repeats of the largest rank's value."""
        return statistics.median(
            max(r[key] for r in rows if r["ranks"] == ranks and r["repeat"] == k)
            for k in range(args.repeats))

    def above(ranks, key="peak_mib"):
        return statistics.median(
            max(r[key] - r["baseline_mib"] for r in rows
                if r["ranks"] == ranks and r["repeat"] == k) for k in range(args.repeats))

    print(f"\n{volume.name}, {args.size}x{args.size}, {args.repeats} repeats "
          "(medians of the largest rank)")
    print(f"{'ranks':>5s} {'peak MiB':>9s} {'above baseline':>15s} {'reading':>8s} "
          f"{'piece MiB':>10s} {'read s':>7s}")
    for ranks in (1, 2):
        print(f"{ranks:5d} {largest(ranks, 'peak_mib'):9.0f} {above(ranks):15.0f} "
              f"{above(ranks, 'read_peak_mib'):8.1f} {largest(ranks, 'piece_mib'):10.2f} "
              f"{largest(ranks, 'read_s'):7.2f}")
    print(f"2 ranks / 1 rank, peak memory: {largest(2, 'peak_mib') / largest(1, 'peak_mib'):.2f} "
          "(target <= 0.6)")
    print(f"2 ranks / 1 rank, peak above baseline: {above(2) / above(1):.2f}")
    print(f"2 ranks / 1 rank, reading peak above baseline: "
          f"{above(2, 'read_peak_mib') / max(above(1, 'read_peak_mib'), 1e-9):.2f}")
    print(f"CSV: {out / 'paraview_mpi.csv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
