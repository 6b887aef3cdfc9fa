"""Smoke test of the rendering benchmark: `bench/render.py --quick` runs and writes a complete
CSV and the error plot. It asserts structure and consistency, never absolute timings."""
import csv
import os
import pathlib
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = REPO / "bench" / "render.py"
COLUMNS = [
    "kind", "volume", "device", "width", "height", "lod", "bounces", "nee", "spp", "frames",
    "ms_median", "ms_min", "ms_restart_median", "seconds", "rmse", "mean_rel_error",
    "setup_seconds", "bytes_blas", "bytes_tlas",
]


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory, shared_data):
    out = tmp_path_factory.mktemp("bench_render")
    completed = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--out", str(out)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=300,
    )
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    with open(out / "render.csv", newline="") as f:
        reader = csv.DictReader(f)
        return out, completed.stdout, reader.fieldnames, list(reader)


def test_csv_columns_and_rows(quick_run):
    out, stdout, columns, rows = quick_run
    assert columns == COLUMNS
    frames = [r for r in rows if r["kind"] == "frame"]
    errors = [r for r in rows if r["kind"] == "error"]
    assert len(frames) + len(errors) == len(rows)
    # 3 configurations (voxel 1 and 4 bounces, block 1 bounce) x NEE off/on at one size.
    assert {(r["lod"], r["bounces"], r["nee"]) for r in frames} == {
        (lod, b, n) for lod, b in (("voxel", "1"), ("voxel", "4"), ("block", "1")) for n in "01"}
    for r in frames:
        assert float(r["ms_median"]) > 0 and float(r["ms_min"]) <= float(r["ms_median"])
        assert float(r["ms_restart_median"]) > 0
        assert int(r["bytes_blas"]) > 0 and r["device"]
    # Error curves per LOD and estimator at 1, 2, 4, 8 spp, time growing with the samples.
    for lod in ("voxel", "block"):
        for nee in "01":
            curve = [r for r in errors if r["lod"] == lod and r["nee"] == nee]
            assert [int(r["spp"]) for r in curve] == [1, 2, 4, 8]
            seconds = [float(r["seconds"]) for r in curve]
            assert all(b >= a for a, b in zip(seconds, seconds[1:]))
            assert all(float(r["rmse"]) >= 0 and float(r["mean_rel_error"]) >= 0 for r in curve)
        # With NEE, 8 samples are closer to the reference than 1.
        nee_curve = [float(r["rmse"]) for r in errors if r["lod"] == lod and r["nee"] == "1"]
        assert nee_curve[-1] < nee_curve[0]
    assert (out / "render_error.png").stat().st_size > 0
    assert "reported, not measured here" in stdout
