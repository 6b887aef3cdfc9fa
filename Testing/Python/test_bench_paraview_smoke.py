"""Smoke test of `bench/paraview.py --quick`: the pvbatch and pyvista routes each run in a process
of their own and the CSV has one row per route with positive times. It asserts structure, never
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
    assert sorted(r["route"] for r in rows) == ["pvbatch", "pyvista"]
    for r in rows:
        assert float(r["first_image_s"]) > 0 and float(r["frame_ms"]) > 0
