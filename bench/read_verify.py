#!/usr/bin/env python3
"""Cost of verified reading: vtksvdag.read with the verifying readers against a baseline build.

Run from the repository root, after building the baseline (the commit before the readers
verified their input) in a worktree:

    git worktree add /tmp/svdag-baseline <commit>
    cmake -S /tmp/svdag-baseline -B /tmp/svdag-baseline/build -G Ninja -DCMAKE_BUILD_TYPE=Release \\
          -DPython3_EXECUTABLE=/usr/bin/python3 -DVTKSVDAG_BUILD_TESTING=OFF
    cmake --build /tmp/svdag-baseline/build
    .venv/bin/python bench/read_verify.py [--reps 7] [--baseline /tmp/svdag-baseline]

For every shared volume (../shared/data/*.nrrd, or --data) and every repetition, each build reads
the volume in its own subprocess (PYTHONPATH = <repo>/Python:<build>/python, checked by printing
the path of the vtkSVDAGIO module it loaded), the two builds alternating (which goes first
alternates too). Inside a subprocess one untimed read warms the page cache, then the best of
--inner timed reads is reported. The table shows the median over the repetitions per build and
the ratio verified / baseline; both builds must decode the same voxels (SHA-256 of to_numpy()).
CSV: build/bench/read_verify.csv (--csv to change). Exit status 1 if the builds disagree.
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

ROOT = pathlib.Path(__file__).resolve().parent.parent

CHILD = r"""
import hashlib, json, sys, time
import vtksvdag, vtksvdag.vtkSVDAGIO
path, inner = sys.argv[1], int(sys.argv[2])
seg = vtksvdag.read(path)  # warm-up: page cache, lazy imports
times = []
for _ in range(inner):
    t0 = time.perf_counter()
    seg = vtksvdag.read(path)
    times.append(time.perf_counter() - t0)
labels = seg.to_numpy()
print(json.dumps({"module": vtksvdag.vtkSVDAGIO.__file__, "seconds": min(times),
                  "sha256": hashlib.sha256(labels.tobytes()).hexdigest(),
                  "shape": list(labels.shape), "dtype": str(labels.dtype)}))
"""


def run_child(repo: pathlib.Path, build: pathlib.Path, volume: pathlib.Path, inner: int) -> dict:
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(repo / "Python"), str(build / "python")])
    env.setdefault("OMP_NUM_THREADS", "1")
    result = subprocess.run([sys.executable, "-c", CHILD, str(volume), str(inner)], env=env,
                            capture_output=True, text=True, timeout=600)
    if result.returncode != 0:
        raise RuntimeError(f"read of {volume} with {build} failed:\n{result.stderr[-3000:]}")
    out = json.loads(result.stdout.strip().splitlines()[-1])
    expected = (build / "python").resolve()
    loaded = pathlib.Path(out["module"]).resolve()
    if expected not in loaded.parents:
        raise RuntimeError(f"the subprocess for {build} loaded {loaded}, not a module under {expected}")
    return out


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--baseline", type=pathlib.Path, default=pathlib.Path("/tmp/svdag-baseline"),
                        help="repository of the baseline (its build is <repo>/build)")
    parser.add_argument("--baseline-build", type=pathlib.Path, default=None)
    parser.add_argument("--verified", type=pathlib.Path, default=ROOT,
                        help="repository of the verifying readers (default: this one)")
    parser.add_argument("--verified-build", type=pathlib.Path, default=None)
    parser.add_argument("--data", type=pathlib.Path, default=ROOT.parent / "shared" / "data")
    parser.add_argument("--reps", type=int, default=7, help="subprocesses per build and volume")
    parser.add_argument("--inner", type=int, default=3, help="timed reads per subprocess (best)")
    parser.add_argument("--csv", type=pathlib.Path, default=ROOT / "build" / "bench" / "read_verify.csv")
    args = parser.parse_args()
    builds = {
        "baseline": (args.baseline, args.baseline_build or args.baseline / "build"),
        "verified": (args.verified, args.verified_build or args.verified / "build"),
    }
    volumes = sorted(args.data.glob("*.nrrd"))
    if not volumes:
        print(f"no volumes in {args.data}", file=sys.stderr)
        return 2

    for name, (repo, build) in builds.items():
        print(f"{name}: {repo} ({build}): "
              f"{run_child(repo, build, volumes[0], 1)['module']}")

    rows = []
    mismatch = False
    for volume in volumes:
        seconds = {name: [] for name in builds}
        digests = {}
        for rep in range(args.reps):
            order = list(builds) if rep % 2 == 0 else list(reversed(builds))
            for name in order:
                out = run_child(*builds[name], volume, args.inner)
                seconds[name].append(out["seconds"])
                digests.setdefault(name, out["sha256"])
                if out["sha256"] != digests[name]:
                    mismatch = True
        same = digests["baseline"] == digests["verified"]
        mismatch |= not same
        base = statistics.median(seconds["baseline"])
        verified = statistics.median(seconds["verified"])
        rows.append({
            "volume": volume.name, "bytes": volume.stat().st_size,
            "baseline_s": base, "verified_s": verified, "ratio": verified / base,
            "baseline_all": " ".join(f"{t:.5f}" for t in seconds["baseline"]),
            "verified_all": " ".join(f"{t:.5f}" for t in seconds["verified"]),
            "same_voxels": same,
        })
        print(f"  {volume.name}: done", file=sys.stderr)

    print()
    print(f"vtksvdag.read, median of {args.reps} subprocesses (best of {args.inner} reads each)")
    header = f"{'volume':32} {'file MB':>8} {'baseline s':>11} {'verified s':>11} {'ratio':>7} {'voxels':>7}"
    print(header)
    print("-" * len(header))
    for r in rows:
        print(f"{r['volume']:32} {r['bytes'] / 1e6:8.2f} {r['baseline_s']:11.4f} "
              f"{r['verified_s']:11.4f} {r['ratio']:7.3f} {'same' if r['same_voxels'] else 'DIFFER':>7}")
    ratios = [r["ratio"] for r in rows]
    print(f"ratio verified/baseline: median {statistics.median(ratios):.3f}, max {max(ratios):.3f} "
          f"(target <= 1.05)")

    args.csv.parent.mkdir(parents=True, exist_ok=True)
    with open(args.csv, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.csv}")
    if mismatch:
        print("the builds decode different voxels", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
