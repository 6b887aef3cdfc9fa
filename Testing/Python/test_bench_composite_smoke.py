"""Smoke test of `bench/composite.py --quick`: the composite paths (color and depth shared, the
color shared with the depth through the host, both through the host) measured side by side in one
process, every frame traced anew at full size, the copy time part of the mapper's, and the
windows' images and z-buffers equal. It asserts structure, never timings."""
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
    assert sorted({r["path"] for r in rows}) == ["host", "shared", "shared-color"]
    assert all(r["composite_path"] == r["depth_path"] == "host" for r in rows if r["path"] == "host")
    assert all(r["depth_path"] == "host" for r in rows if r["path"] == "shared-color")
    # The depth is shared only where the color is (the same check, plus shaderFloat64).
    assert all(r["composite_path"] == "shared memory" for r in rows
               if r["path"] == "shared" and r["depth_path"] == "shared memory")
    for r in rows:
        assert 0 < float(r["copy_ms"]) < float(r["mapper_ms"]) <= float(r["render_ms"]) * 1.01
        assert float(r["trace_ms"]) > 0  # every frame traced
    assert len(rows) == 3 * 3
