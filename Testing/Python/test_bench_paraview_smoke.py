"""Smoke tests of `bench/paraview.py --quick` (the pvbatch, pvbatch --no-mpi and pyvista routes
each run in a process of their own and the CSV has one row per route with positive times, the
host ready before the first image) and of
`bench/paraview_mpi.py --quick`. They assert structure, never
timings. Skipped when the ParaView plugin is not built (scripts/setup-paraview.sh)."""
import csv
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
PLUGIN = REPO / "build-paraview" / "lib" / "paraview-5.11" / "plugins" / "vtkSVDAG" / "vtkSVDAG.so"


@pytest.mark.skipif(not PLUGIN.exists() or shutil.which("pvbatch") is None,
                    reason="the ParaView plugin is not built: run bash scripts/setup-paraview.sh")
def test_paraview_bench_quick(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "paraview.py"), "--quick", "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    assert "pvbatch / pyvista, still frame" in completed.stdout
    with open(tmp_path / "paraview.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert sorted(r["route"] for r in rows) == ["pvbatch", "pvbatch-no-mpi", "pyvista"]
    for r in rows:
        assert 0 < float(r["ready_s"]) < float(r["first_image_s"]) and float(r["frame_ms"]) > 0


@pytest.mark.skipif(not PLUGIN.exists() or shutil.which("mpiexec") is None,
                    reason="the ParaView plugin or mpiexec is missing: run bash scripts/setup-paraview.sh")
def test_paraview_mpi_bench_quick(tmp_path):
    """`bench/paraview_mpi.py --quick`: one row per rank of the 1- and 2-rank runs, each rank's
    piece smaller with 2 ranks than the whole volume with 1."""
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "paraview_mpi.py"), "--quick", "--out",
         str(tmp_path)], capture_output=True, text=True, cwd=REPO, env=os.environ.copy(),
        timeout=600)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    assert "2 ranks / 1 rank, peak memory" in completed.stdout
    with open(tmp_path / "paraview_mpi.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert sorted((int(r["ranks"]), int(r["rank"])) for r in rows) == [(1, 0), (2, 0), (2, 1)]
    whole = next(float(r["piece_mib"]) for r in rows if r["ranks"] == "1")
    for r in rows:
        assert float(r["peak_mib"]) >= float(r["baseline_mib"]) > 0
        if r["ranks"] == "2":
            assert 0 < float(r["piece_mib"]) < whole
