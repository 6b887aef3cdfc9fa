"""Smoke test of `bench/startup.py --quick`: every route (the CLI main job on both backends, the
pyvista scene on both backends and with compute pipelines instead of shader objects,
vtkGPUVolumeRayCastMapper) runs in its own process with empty and then warm cache folders, and
the CSV has one row per run (the pyvista routes' with the moment their Plotter was ready, the ray
caster's also with the moment it had read the file). It asserts structure, never timings."""
import csv
import os
import pathlib
import subprocess
import sys

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_startup_quick(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "startup.py"), "--quick", "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=900)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    assert "ratio to gpu-raycast" in completed.stdout
    assert "floor" in completed.stdout
    with open(tmp_path / "startup.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    routes = ["cli-compute", "cli-rt", "pyvista-compute", "pyvista-rt", "gpu-raycast",
              "pyvista-compute-pipelines"]
    assert sorted((r["route"], r["cache"]) for r in rows) == sorted(
        (route, cache) for route in routes for cache in ("cold", "warm"))
    for r in rows:
        assert 0 < float(r["first_image_s"]) <= float(r["process_s"])
        if r["route"].startswith("cli-"):
            assert r["plotter_s"] == r["read_s"] == ""
        else:
            assert 0 < float(r["plotter_s"]) < float(r["first_image_s"])
        if r["route"] == "gpu-raycast":
            assert float(r["plotter_s"]) < float(r["read_s"]) < float(r["first_image_s"])
        else:
            assert r["read_s"] == ""
