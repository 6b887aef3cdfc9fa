#!/usr/bin/env python3
"""What an exploring user's change costs: the next frame after a clipping-plane move, a query
(labels hidden: the rt backend rebuilds its BVH from the blocks on the device, the compute
backend sets bits), a color change and a highlight change (material uploads), on every shared
volume.

    xvfb-run -a .venv/bin/python bench/explore.py [--size 512] [--repeats 3] [--volumes NAME ...]
        [--backend auto|rt|compute]

In a pyvista off-screen Plotter (--size square pixels), each volume is added with
``add_segmentation(color_by="voxel_count", spp=1, lod="voxel", auto_adjust=False)`` and refined
once; then each change is applied and one render made, --repeats times (changes alternate, so
every repeat changes the state again). Per change: the median wall ms from the change to the
rendered frame, of it the trace (``GetLastTraceMilliseconds``), the rest (rebuild, uploads,
compositing: ``other_ms``), and the BVH builds the change caused; ``backend`` is the backend that
ran. Writes bench/out/explore.csv.
"""
import argparse
import csv
import pathlib
import statistics
import sys
import time

ROOT = pathlib.Path(__file__).resolve().parents[1]
SHARED = ROOT.parent / "shared" / "data"


def measure(path, size, repeats, backend):
    import pyvista as pv

    import vtksvdag

    volume = vtksvdag.read(path)
    plotter = pv.Plotter(off_screen=True, window_size=(size, size))
    try:
        actor = vtksvdag.add_segmentation(plotter, volume, color_by="voxel_count", spp=1,
                                          lod="voxel", auto_adjust=False, backend=backend)
        mapper = actor.GetMapper()
        vtksvdag.refine(plotter)
        plotter.render()
        table = actor.label_table
        median = float(table.voxel_count.median())
        bounds = mapper.GetBounds()
        center = [(bounds[2 * a] + bounds[2 * a + 1]) / 2 for a in range(3)]
        from vtkmodules.vtkCommonDataModel import vtkPlane

        plane = vtkPlane()
        plane.SetOrigin(*center)
        plane.SetNormal(1, 0.3, 0.2)
        mapper.AddClippingPlane(plane)
        plotter.render()
        # Each change alternates between two states of its own, so every call changes something.
        count = {"clip": 0, "query": 0, "color": 0, "highlight": 0}

        def step(name):
            count[name] += 1
            return count[name] % 2

        def clip():
            shift = step("clip") * 0.1 * (bounds[1] - bounds[0])
            plane.SetOrigin(center[0] + shift, center[1], center[2])

        def query():
            actor.set_query(f"voxel_count {'>' if step('query') else '<='} {median}")

        def color():
            actor.set_color_by("volume", cmap="plasma" if step("color") else "viridis")

        def highlight():
            # Another visible label than the highlighted one (a query may have hidden it).
            others = [v for v in actor.visible_labels if v not in actor.highlighted_labels]
            actor.set_highlight([others[step("highlight") % len(others)]], dim=0.3)

        highlight()  # the first highlight switches the emission pipeline on: not a change's cost
        plotter.render()
        changes = {"none": lambda: None, "clip": clip, "query": query, "color": color,
                   "highlight": highlight}
        samples = {name: [] for name in changes}
        for _ in range(repeats):
            for name, change in changes.items():
                builds = mapper.GetNumberOfBVHBuilds()
                start = time.perf_counter()
                change()
                plotter.render()
                wall = 1e3 * (time.perf_counter() - start)
                samples[name].append((wall, mapper.GetLastTraceMilliseconds(),
                                      mapper.GetNumberOfBVHBuilds() - builds))
        rows = []
        for name, values in samples.items():
            wall = statistics.median(v[0] for v in values)
            trace = statistics.median(v[1] for v in values)
            rows.append({"volume": path.stem, "labels": len(volume.labels),
                         "backend": mapper.GetBackendInUse(), "change": name,
                         "frame_ms": round(wall, 2), "trace_ms": round(trace, 2),
                         "other_ms": round(wall - trace, 2),
                         "bvh_builds": max(v[2] for v in values)})
        return rows
    finally:
        plotter.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--volumes", nargs="*")
    parser.add_argument("--out", type=pathlib.Path, default=ROOT / "bench" / "out")
    parser.add_argument("--backend", choices=("auto", "rt", "compute"), default="auto")
    args = parser.parse_args()
    if not SHARED.is_dir():
        print(f"explore.py: {SHARED} not found (the shared volumes); nothing to measure")
        return 0
    paths = sorted(SHARED.glob("*.nrrd"))
    if args.volumes:
        paths = [p for p in paths if p.stem in args.volumes]
    rows = []
    print(f"{'volume':24s} {'labels':>6s} {'change':>9s} {'frame ms':>9s} {'trace ms':>9s} "
          f"{'other ms':>9s} {'BVH':>4s}")
    for path in paths:
        for row in measure(path, args.size, args.repeats, args.backend):
            rows.append(row)
            print(f"{row['volume']:24s} {row['labels']:6d} {row['backend'] + ' ' + row['change']:>17s} "
                  f"{row['frame_ms']:9.1f} {row['trace_ms']:9.1f} {row['other_ms']:9.1f} "
                  f"{row['bvh_builds']:4d}", flush=True)
    args.out.mkdir(parents=True, exist_ok=True)
    with open(args.out / "explore.csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    print(f"wrote {args.out / 'explore.csv'}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
