"""Smoke test of `bench/composite.py --quick`: both composite paths measured side by side in one
process, every frame traced anew at full size, the copy time part of the mapper's, and the two
windows' images equal. It asserts structure, never timings."""
import csv
import os
import pathlib
import subprocess
import sys

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_composite_quick(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "composite.py"), "--quick", "--size", "96",
         "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    assert "images equal: True" in completed.stdout
    with open(tmp_path / "composite.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert sorted({r["path"] for r in rows}) == ["host", "shared"]
    assert all(r["composite_path"] == "host" for r in rows if r["path"] == "host")
    for r in rows:
        assert 0 < float(r["copy_ms"]) < float(r["mapper_ms"]) <= float(r["render_ms"]) * 1.01
        assert float(r["trace_ms"]) > 0  # every frame traced
    assert len(rows) == 2 * 3
