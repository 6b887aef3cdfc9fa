"""Smoke test of `bench/upsample.py --quick`: guided and replicated rows at every reduction, the
CSV and the side-by-side image. It asserts structure and the property guided upsampling must
have (the shown labels are the full-size reference's, exactly, at every reduction), never
timings."""
import csv
import os
import pathlib
import subprocess
import sys

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_upsample_quick(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "upsample.py"), "--quick", "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    with open(tmp_path / "upsample.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert sorted((int(r["reduction"]), r["kind"]) for r in rows) == [
        (1, "guided"), (2, "guided"), (2, "replicated"), (4, "guided"), (4, "replicated"),
        (8, "guided"), (8, "replicated")]
    assert all(float(r["label_mismatch"]) == 0 for r in rows if r["kind"] == "guided")
    assert any(float(r["label_mismatch"]) > 0 for r in rows if r["kind"] == "replicated")
    assert (tmp_path / "upsample_generated48.png").exists()
    assert "guided / replicated RMSE" in completed.stdout
