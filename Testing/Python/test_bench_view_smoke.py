"""Smoke test of `bench/view.py --quick`: every row runs (encoding, delivery, drag, click to
highlight, start-up of both routes, memory per browser) and the CSV has them. It asserts
structure, never timings."""
import csv
import os
import pathlib
import shutil
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_view_quick(tmp_path):
    pytest.importorskip("trame", reason="the viewer extra (pip install .[viewer]) is not installed")
    pytest.importorskip("selenium", reason="selenium is not installed")
    if not (shutil.which("chromium") and shutil.which("chromedriver")):
        pytest.skip("headless chromium is not installed (scripts/install-deps.sh installs "
                    "chromium and chromium-driver)")
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "view.py"), "--quick", "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    assert "targets:" in completed.stdout
    with open(tmp_path / "view.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    names = {r["row"] for r in rows}
    assert names == {"encode-jpeg", "encode-png", "frame-delivery", "drag-fps", "click-to-highlight",
                     "first-image-view", "first-image-pyvista", "memory-server", "memory-per-browser"}
    assert len([r for r in rows if r["row"] == "memory-server"]) == 4
    for r in rows:
        if r["row"] != "memory-per-browser":
            assert float(r["value"]) > 0, r
