"""Smoke test of the palette benchmark: `bench/palette.py --quick` runs, checks its adjacency
against numpy, writes a complete CSV and meets the target on the volumes it measures. It asserts
structure and the documented target, never timings."""
import csv
import os
import pathlib
import subprocess
import sys

REPO = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = REPO / "bench" / "palette.py"
COLUMNS = ["volume", "dims_xyz", "labels", "touching_pairs", "adjacency_s", "coloring",
           "frac_ge_25", "median", "p5"]


def test_quick_run(tmp_path):
    completed = subprocess.run([sys.executable, str(SCRIPT), "--quick", "--out", str(tmp_path)],
                               capture_output=True, text=True, cwd=REPO, env=os.environ.copy(),
                               timeout=300)
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    with open(tmp_path / "palette.csv", newline="") as f:
        reader = csv.DictReader(f)
        assert reader.fieldnames == COLUMNS
        rows = list(reader)
    volumes = {r["volume"] for r in rows}
    assert "voronoi64_100" in volumes
    for volume in volumes:
        by = {r["coloring"]: r for r in rows if r["volume"] == volume}
        assert sorted(by) == ["distinct", "hash", "tab20"]
        assert len({(r["labels"], r["touching_pairs"]) for r in by.values()}) == 1
        for r in by.values():
            assert 0 <= float(r["frac_ge_25"]) <= 1
            assert float(r["p5"]) <= float(r["median"]) or int(r["touching_pairs"]) == 0
        assert float(by["distinct"]["frac_ge_25"]) >= 0.95, volume
    # The generated Voronoi volume has many touching pairs; there the palette beats both.
    by = {r["coloring"]: r for r in rows if r["volume"] == "voronoi64_100"}
    assert int(by["distinct"]["touching_pairs"]) > 300
    assert float(by["distinct"]["p5"]) > max(float(by["tab20"]["p5"]), float(by["hash"]["p5"]))
    assert "met on every volume" in completed.stdout
