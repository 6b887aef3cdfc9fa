"""Smoke test of `bench/devices.py --quick`: a complete CSV, one device for eight volumes, each
mapper's bytes its own. It asserts structure and counts, never timings."""
import csv
import os
import pathlib
import subprocess
import sys

REPO = pathlib.Path(__file__).resolve().parents[2]


def test_devices_quick(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(REPO / "bench" / "devices.py"), "--quick", "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    with open(tmp_path / "devices.csv", newline="") as f:
        rows = {int(r["volumes"]): r for r in csv.DictReader(f)}
    assert set(rows) == {1, 8}
    for count, r in rows.items():
        assert int(r["devices"]) == 1 and int(r["device_users"]) == count
        assert float(r["setup_s"]) > 0
    # Eight volumes of the same size hold about eight times one volume's bytes.
    ratio = int(rows[8]["device_bytes"]) / int(rows[1]["device_bytes"])
    assert 7.5 < ratio < 8.5
    assert (tmp_path / "devices.png").stat().st_size > 0
    assert "8 / 1: threads" in completed.stdout
