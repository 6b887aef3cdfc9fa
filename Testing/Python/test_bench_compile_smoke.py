"""Smoke test of `bench/compile.py --quick`: one cold-cache and one warm-cache run of every variant
on the compute backend, the CSV and the table. It asserts structure and that the preview was the frame traced
where asked (the script checks each run's `previewed`), never timings."""
import csv
import os
import pathlib
import subprocess
import sys

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_compile_quick(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "compile.py"), "--quick", "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    with open(tmp_path / "compile.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert sorted((r["variant"], r["caches"]) for r in rows) == [
        (v, c) for v in ["clipped", "no-nee", "preview", "sky", "smooth", "sun"]
        for c in ["cold", "warm"]]
    assert all(float(r["compile_seconds"]) > 0 for r in rows)
    assert "preview" in completed.stdout and "/ sun" in completed.stdout
