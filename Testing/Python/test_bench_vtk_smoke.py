"""Smoke test of the VTK comparison benchmark: `bench/vtk.py --quick` runs the three routes and
writes a complete CSV and the side-by-side image. It asserts structure, never absolute timings."""
import csv
import os
import pathlib
import subprocess
import sys

import pytest
from conftest import SHARED_DATA, require_shared_data

REPO = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = REPO / "bench" / "vtk.py"
ROUTES = {"ours", "gpu-raycast", "surfaces"}


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory):
    require_shared_data(SHARED_DATA / "fib25_64.nrrd")  # skips (fails under CI) without it
    out = tmp_path_factory.mktemp("bench_vtk")
    completed = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--out", str(out)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600,
    )
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    with open(out / "vtk.csv", newline="") as f:
        return out, completed.stdout, list(csv.DictReader(f))


def test_csv_has_three_routes_with_positive_times(quick_run):
    out, stdout, rows = quick_run
    assert {r["route"] for r in rows} == ROUTES and len(rows) == 3
    for r in rows:
        assert r["volume"] == "fib25_64" and r["dims_xyz"] == "64x64x64"
        assert float(r["first_image_s"]) > 0
        assert float(r["interact_ms_median"]) > 0 and int(r["interact_frames"]) == 3
        assert float(r["still_ms_median"]) > 0 and int(r["still_frames"]) == 3
        assert float(r["peak_rss_mb"]) >= float(r["baseline_mb"]) > 0
    by_route = {r["route"]: r for r in rows}
    assert int(by_route["surfaces"]["triangles"]) > 0
    ours = by_route["ours"]
    # Still frames restart the accumulation: one sample per pixel, voxel LOD, full resolution.
    assert (ours["still_lod"], ours["still_reduction"], ours["still_spp"]) == ("2", "1", "1")
    assert len(ours["interact_lods"].split()) == 3
    assert (out / "vtk_fib25_64.png").stat().st_size > 0
    assert "Ratios ours / gpu-raycast" in stdout


@pytest.mark.parametrize("backend", ["rt", "compute"])
def test_explore_changes_rebuild_only_for_a_query(tmp_path, backend):
    """bench/explore.py on one small volume: every change traced a new frame, and only the query
    rebuilt the acceleration structure on the rt backend, nothing on compute (hidden bits)
    (structure and counts, no timings)."""
    require_shared_data(SHARED_DATA / "fib25_64.nrrd")
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "explore.py"), "--volumes", "fib25_64",
         "--repeats", "1", "--size", "64", "--out", str(tmp_path), "--backend", backend],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600,
    )
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    with open(tmp_path / "explore.csv", newline="") as f:
        rows = {r["change"]: r for r in csv.DictReader(f)}
    assert set(rows) == {"none", "clip", "query", "color", "highlight"}
    assert {r["backend"] for r in rows.values()} == {backend}
    assert {name: int(r["bvh_builds"]) for name, r in rows.items()} == {
        "none": 0, "clip": 0, "query": int(backend == "rt"), "color": 0, "highlight": 0}
    assert float(rows["none"]["trace_ms"]) == 0  # a refined still view is not traced again
    for name in ("clip", "query", "color", "highlight"):
        assert float(rows[name]["trace_ms"]) > 0, name
