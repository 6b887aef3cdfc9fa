"""Smoke test of `bench/denoise.py --quick`: error rows with the denoiser off and on at every
checkpoint, cost rows, the report's target lines, the plot and the side-by-side image. It asserts
structure and one property the denoiser must have (one denoised sample closer to the reference
than one raw sample), never timings."""
import csv
import os
import pathlib
import subprocess
import sys

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_denoise_quick(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "denoise.py"), "--quick", "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    assert "denoised 1 spp / 16 spp off" in completed.stdout
    assert "of the frame (target <= 15% at 512)" in completed.stdout
    with open(tmp_path / "denoise.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    errors = [r for r in rows if r["kind"] == "error"]
    for denoise in "01":
        curve = [r for r in errors if r["denoise"] == denoise]
        assert [int(r["spp"]) for r in curve] == [1, 2, 4, 8, 16]
        assert all(float(r["rmse"]) > 0 and float(r["rmse_boundary"]) > 0 for r in curve)
    first = {r["denoise"]: float(r["rmse"]) for r in errors if r["spp"] == "1"}
    assert first["1"] < first["0"]
    assert sorted(r["denoise"] for r in rows if r["kind"] == "cost") == ["0", "1"]
    assert (tmp_path / "denoise_error.png").stat().st_size > 0
    assert (tmp_path / "denoise_generated48_96.png").stat().st_size > 0
