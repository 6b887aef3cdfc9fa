#!/usr/bin/env python3
"""Pipeline compile times per feature variant and backend, with every shader cache empty.

Run from the repository root (after the build):

    .venv/bin/python bench/compile.py [--quick] [--repeats 3] [--out DIR]

Each measurement is a new process of the C++ tool (build/bin/vtksvdag-render, 64x64, one frame)
with fresh, empty folders for Mesa's shader cache (MESA_SHADER_CACHE_DIR) and for ours
(XDG_CACHE_HOME), so the driver compiles the path tracer's pipeline from SPIR-V ("cold"), then a
second process on the same folders ("warm": where the device has shader objects, lavapipe's
case, the compute shaders come from the binaries the first one saved; the ray tracing pipeline
from whatever the driver's pipeline cache holds). The tool's
JSON gives the pipeline creation time of its frame's pipeline (pipeline_compile_seconds) and the
first frame's wall time (creation, the first dispatch and the trace of 64x64 pixels: lavapipe
translates the shader to machine code at the first dispatch, so there the first frame is the
figure that counts; the ratio column is of it). Variants (the specialization constants a scene
selects, Pipeline.h's ShaderFeatures):

  sky        next-event estimation, a constant environment (the default scene)
  sun        the same with a disk sun (the README's main job)
  no-nee     the plain estimator (no shadow rays)
  smooth     sky with smooth shading normals (--shading smooth)
  clipped    sky with a clipping plane (--clip; where it cuts does not change what is compiled)
  preview    --preview: the small preview pipeline a window shows while the full one compiles
             in the background (its compile time is measured beside that background work);
             warm, the compute backend creates the full one from its binary at once instead
             (the run checks `previewed` either way)

Variants alternate within each repeat. Prints the medians and each variant's first-frame ratio
to `sun`;
writes compile.csv (every run) to --out (default build/bench). --quick: one repeat, compute only
(a smoke test).
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

REPO = pathlib.Path(__file__).resolve().parents[1]
TOOL = REPO / "build" / "bin" / "vtksvdag-render"
CACHES = ["cold", "warm"]
VARIANTS = {
    "sky": [],
    "sun": ["--sun", "0,-20"],
    "no-nee": ["--no-nee"],
    "smooth": ["--shading", "smooth"],
    "clipped": ["--clip", "0,0,0,1,0,0"],
    "preview": ["--preview"],
}


def example_svdag(out: pathlib.Path) -> pathlib.Path:
    """The bundled example as a .svdag file (the tool reads only that format)."""
    path = out / "cells.svdag"
    if not path.exists():
        subprocess.run([sys.executable, "-m", "vtksvdag", "compress",
                        str(REPO / "examples" / "data" / "cells.nrrd"), "-o", str(path)],
                       check=True, capture_output=True, cwd=REPO)
    return path


def measure(svdag: pathlib.Path, backend: str, variant: str, out: pathlib.Path) -> list:
    """Two processes on the same, initially empty cache folders: cold, then warm."""
    rows = []
    with tempfile.TemporaryDirectory() as caches:
        env = dict(os.environ, MESA_SHADER_CACHE_DIR=os.path.join(caches, "mesa"),
                   XDG_CACHE_HOME=os.path.join(caches, "xdg"))
        for state in CACHES:
            completed = subprocess.run(
                [str(TOOL), str(svdag), str(out / "compile.png"), "--width", "64", "--height",
                 "64", "--backend", backend, *VARIANTS[variant]],
                capture_output=True, text=True, env=env, timeout=600)
            if completed.returncode != 0:
                raise RuntimeError(f"{backend} {variant}: {completed.stderr.strip()}")
            result = json.loads(completed.stdout.strip().splitlines()[-1])
            # A warm compute shader comes from its binary at once: no preview then.
            from_binary = state == "warm" and backend == "compute" and result["shader_objects"]
            if result["previewed"] != (variant == "preview" and not from_binary):
                raise RuntimeError(f"{backend} {variant} {state}: previewed is {result['previewed']}")
            rows.append({"backend": backend, "variant": variant, "caches": state,
                         "compile_seconds": result["pipeline_compile_seconds"],
                         "first_frame_seconds": result["ms_per_frame"] / 1000})
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", type=pathlib.Path, default=REPO / "build" / "bench")
    args = parser.parse_args()
    if not TOOL.exists():
        print(f"{TOOL} is missing: build first (bash scripts/setup.sh)", file=sys.stderr)
        return 1
    args.out.mkdir(parents=True, exist_ok=True)
    svdag = example_svdag(args.out)
    backends = ["compute"] if args.quick else ["compute", "rt"]
    repeats = 1 if args.quick else args.repeats
    rows = []
    for _ in range(repeats):
        for backend in backends:
            for variant in VARIANTS:
                rows.extend(measure(svdag, backend, variant, args.out))
    with open(args.out / "compile.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"{'backend':8} {'variant':8} {'caches':6} {'creation s':>10} {'first frame s':>14} "
          f"{'/ sun':>6}")
    for backend in backends:
        for state in CACHES:
            def median(key, variant):
                return statistics.median(r[key] for r in rows if r["backend"] == backend and
                                         r["variant"] == variant and r["caches"] == state)
            for variant in VARIANTS:
                first = median("first_frame_seconds", variant)
                print(f"{backend:8} {variant:8} {state:6} {median('compile_seconds', variant):10.3f} "
                      f"{first:14.3f} {first / median('first_frame_seconds', 'sun'):6.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
