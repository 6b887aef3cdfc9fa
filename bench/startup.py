#!/usr/bin/env python3
"""Time to the first image, with every shader cache empty and with warm caches, in one run.

Run from the repository root, under Xvfb (VTK's OpenGL needs a display; llvmpipe here):

    xvfb-run -a -s "-screen 0 1024x768x24" .venv/bin/python bench/startup.py [--quick]
        [--volume fib_ts2_groundtruth250] [--size 512] [--repeats 3] [--out DIR]

Every measurement is a new process, started by this one, timed from its start to the moment its
first image is written (Python's start-up and imports included: what a user waits for):

  cli-compute, cli-rt   the README's main job: `vtksvdag render build/cells.svdag -o OUT.png
                        --sun 0 -20` (16 samples, 4 bounces, NEE, a sun) with --backend compute
                        or rt; the whole command.
  pyvista-compute, pyvista-rt
                        a pyvista scene: off-screen Plotter of --size x --size, then
                        `add_segmentation(plotter, VOLUME_FILE, spp=1, backend=...)` and
                        `plotter.screenshot()` (reading and compressing the file included).
  pyvista-compute-pipelines
                        pyvista-compute with SVDAG_VK_NO_SHADER_OBJECTS=1: compute pipelines
                        instead of shader objects, so warm caches hold no compiled shader of ours
                        on lavapipe (what the shader binaries save)
  gpu-raycast           the same file into the same Plotter through vtkGPUVolumeRayCastMapper
                        (labels read with vtksvdag.read and decoded, as bench/vtk.py does:
                        Debian's VTK cannot read gzip NRRD; nearest interpolation, a categorical
                        color per label, shading off), then `plotter.screenshot()`.

Cache states, each in fresh folders of its own:
  cold  Mesa's shader cache (MESA_SHADER_CACHE_DIR, for both lavapipe and llvmpipe) and ours
        (XDG_CACHE_HOME: vtkSVDAG's pipeline cache) empty;
  warm  the same folders after one run of the same route filled them.
Python's bytecode caches are a user's in both states: this bench compiles vtksvdag's modules once
before the runs (as pip does at install, and as pyvista's are) and lets its processes keep them
whatever PYTHONDONTWRITEBYTECODE says (a machine that sets it would otherwise make every process
compile vtksvdag's modules again, a cost no installed copy pays).
Routes alternate within each repeat, so all see the same machine. Prints the medians and the
ratios to gpu-raycast in the same cache state (the issue's targets: pyvista cold <= 1x, the main
job cold <= 2x, pyvista warm <= 0.5x), and the floor of the pyvista routes' ratios: the seconds
until the ray caster's route has read the file (Python, the imports, the Plotter and
`vtksvdag.read`: what every pyvista route pays before a renderer is involved; ours reads with
the same reader) over its first image. Writes startup.csv (every run; plotter_s: the Plotter
ready, the pyvista routes; read_s: the file read, gpu-raycast) to --out (default build/bench).
--quick: a generated 48^3 volume, 128x128, one repeat (a smoke test).
"""
from __future__ import annotations

import argparse
import csv
import os
import pathlib
import shutil
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import _scenes  # noqa: E402
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or REPO.parent / "shared" / "data")
ROUTES = ["cli-compute", "cli-rt", "pyvista-compute", "pyvista-rt", "gpu-raycast",
          "pyvista-compute-pipelines"]
CACHES = ["cold", "warm"]
FIELDS = ["route", "cache", "repeat", "first_image_s", "process_s", "plotter_s", "read_s"]

# The child of the pyvista routes: argv = route, volume file, size, output .png, bench folder.
# Prints the wall-clock times (time.time()) at which its Plotter was ready, at which the ray
# caster's route had read the file, and at which the first image was written.
CHILD = r"""
import sys, time
route, path, size, out = sys.argv[1], sys.argv[2], int(sys.argv[3]), sys.argv[4]
sys.path.insert(0, sys.argv[5])
import pyvista as pv
import vtksvdag
import _scenes
plotter = pv.Plotter(off_screen=True, window_size=(size, size))
print(f"PLOTTER_READY {time.time():.6f}", flush=True)
if route.startswith("pyvista-"):
    vtksvdag.add_segmentation(plotter, path, spp=1, backend=route.split("-")[1])
else:
    volume = vtksvdag.read(path)
    print(f"READ_DONE {time.time():.6f}", flush=True)
    actor, _ = _scenes.gpu_raycast_volume(volume)
    plotter.add_actor(actor, reset_camera=True)
plotter.screenshot(out)
print(f"FIRST_IMAGE {time.time():.6f}", flush=True)
plotter.close()
"""


def generated_volume(path):
    """A 48^3 gzip NRRD of _scenes.generated_labels (no ../shared needed)."""
    import nrrd

    import vtksvdag

    labels = _scenes.generated_labels(48)
    nrrd.write(str(path), np.ascontiguousarray(labels.transpose(2, 1, 0)),
               {"encoding": "gzip"}, index_order="F")
    vtksvdag.read(str(path))  # checks that the file reads
    return path


def user_environment():
    """This process's environment, Python's bytecode caching as a user has it."""
    env = os.environ.copy()
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def compile_package():
    """Compiles vtksvdag's modules into their __pycache__ folders, as pip does at install (where
    they can be written)."""
    import importlib.util

    package = pathlib.Path(importlib.util.find_spec("vtksvdag").origin).parent
    subprocess.run([sys.executable, "-m", "compileall", "-q", str(package)], check=False,
                   env=user_environment())


def run_once(route, volume, svdag, size, caches, out_png):
    """One process of `route` with the cache folders `caches`: {first_image_s, process_s,
    plotter_s (the Plotter ready; None for the CLI routes), read_s (the file read; gpu-raycast
    only, else None)}."""
    env = user_environment()
    env.pop("MESA_SHADER_CACHE_DISABLE", None)
    env.pop("VTKSVDAG_PIPELINE_CACHE", None)
    env["MESA_SHADER_CACHE_DIR"] = str(caches / "mesa")
    env["XDG_CACHE_HOME"] = str(caches / "xdg")
    env.pop("SVDAG_VK_NO_SHADER_OBJECTS", None)
    if route.endswith("-pipelines"):
        env["SVDAG_VK_NO_SHADER_OBJECTS"] = "1"
    if route.startswith("cli-"):
        command = [str(pathlib.Path(sys.executable).parent / "vtksvdag"), "render", str(svdag),
                   "-o", str(out_png), "--sun", "0", "-20", "--backend", route.split("-", 1)[1]]
    else:
        command = [sys.executable, "-c", CHILD, route, str(volume), str(size), str(out_png),
                   str(pathlib.Path(__file__).resolve().parent)]
    start = time.time()
    completed = subprocess.run(command, capture_output=True, text=True, env=env, timeout=900)
    end = time.time()
    if completed.returncode != 0 or not out_png.is_file():
        raise RuntimeError(f"{route} failed (exit {completed.returncode}):\n"
                           f"{completed.stdout[-2000:]}{completed.stderr[-3000:]}")
    marks = {"FIRST_IMAGE": end}
    for line in completed.stdout.splitlines():
        name, _, value = line.partition(" ")
        if name in ("FIRST_IMAGE", "PLOTTER_READY", "READ_DONE"):
            marks[name] = float(value)

    def since(name):
        return marks[name] - start if name in marks else None

    return dict(first_image_s=since("FIRST_IMAGE"), process_s=end - start,
                plotter_s=since("PLOTTER_READY"), read_s=since("READ_DONE"))


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true",
                        help="a generated 48^3 volume, 128x128, one repeat (a smoke test)")
    parser.add_argument("--volume", default="fib_ts2_groundtruth250",
                        help="name of a volume in ../shared/data (the pyvista routes)")
    parser.add_argument("--size", type=int, default=512, help="window width and height")
    parser.add_argument("--repeats", type=int, default=3, help="runs per route and cache state")
    parser.add_argument("--routes", nargs="+", default=ROUTES, choices=ROUTES)
    parser.add_argument("--out", default=str(REPO / "build" / "bench"), help="folder for the CSV")
    args = parser.parse_args(argv)
    if args.quick:
        args.size, args.repeats = 128, 1
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    work = pathlib.Path(tempfile.mkdtemp(prefix="svdag-startup-"))
    try:
        volume = SHARED_DATA / f"{args.volume}.nrrd"
        if args.quick or not volume.is_file():
            if not args.quick:
                print(f"note: {volume} is missing; a generated 48^3 volume stands in")
            volume = generated_volume(work / "generated.nrrd")
        # The main job's input, compressed as the README's first command does.
        svdag = work / "cells.svdag"
        import vtksvdag

        vtksvdag.read(str(REPO / "examples" / "data" / "cells.nrrd")).save(str(svdag))
        compile_package()
        print(f"machine: {os.cpu_count()} cores; pyvista routes on {volume.name} at "
              f"{args.size}x{args.size}; {args.repeats} repeat(s)", flush=True)
        rows = []
        for repeat in range(args.repeats):
            for route in args.routes:
                caches = work / f"caches-{route}-{repeat}"
                for cache in CACHES:  # cold fills the folders that warm then uses
                    png = work / f"{route}-{cache}-{repeat}.png"
                    times = run_once(route, volume, svdag, args.size, caches, png)
                    rows.append(dict(route=route, cache=cache, repeat=repeat, **{
                        k: "" if v is None else round(v, 3) for k, v in times.items()}))
                    print(f"  {route:16s} {cache}: first image {times['first_image_s']:6.2f} s "
                          f"(process {times['process_s']:6.2f} s)", flush=True)
                shutil.rmtree(caches, ignore_errors=True)
    finally:
        shutil.rmtree(work, ignore_errors=True)

    def median_of(field, route, cache):
        return statistics.median(r[field] for r in rows
                                 if r["route"] == route and r["cache"] == cache)

    median = {(route, cache): median_of("first_image_s", route, cache)
              for route in args.routes for cache in CACHES}
    print("\nmedian seconds to the first image")
    print(f"{'route':16s} " + " ".join(f"{c:>8s}" for c in CACHES))
    for route in args.routes:
        print(f"{route:16s} " + " ".join(f"{median[route, c]:8.2f}" for c in CACHES))
    if "gpu-raycast" in args.routes:
        print("\nratio to gpu-raycast in the same cache state (targets: pyvista cold <= 1, "
              "cli cold <= 2, pyvista warm <= 0.5)")
        for route in args.routes:
            if route != "gpu-raycast":
                print(f"{route:16s} " + " ".join(
                    f"{median[route, c] / median['gpu-raycast', c]:8.2f}" for c in CACHES))
        # What every pyvista route pays before its renderer is involved: Python, the imports,
        # the Plotter and the file's read (ours reads with the same vtksvdag.read).
        shared = {(field, c): median_of(field, "gpu-raycast", c)
                  for field in ("plotter_s", "read_s") for c in CACHES}
        print("\nthe ray caster's route until its Plotter is ready and until it has read the "
              "file, median s,\nand the latter over its first image: the floor of the pyvista "
              "routes' ratios")
        print(f"{'Plotter ready':16s} " +
              " ".join(f"{shared['plotter_s', c]:8.2f}" for c in CACHES))
        print(f"{'file read':16s} " + " ".join(f"{shared['read_s', c]:8.2f}" for c in CACHES))
        print(f"{'floor':16s} " + " ".join(
            f"{shared['read_s', c] / median['gpu-raycast', c]:8.2f}" for c in CACHES))
    with open(out / "startup.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=FIELDS)
        writer.writeheader()
        writer.writerows(rows)
    print(f"\nwrote {out / 'startup.csv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
