"""Smoke test of the scaling benchmark (bench/scale.py) and its volume generator
(bench/_scale_volumes.py). It checks data and structure, never timings."""
import csv
import os
import pathlib
import subprocess
import sys

import numpy as np
import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
BENCH = REPO / "bench"
SCRIPT = BENCH / "scale.py"
sys.path.insert(0, str(BENCH))
import _scale_volumes as volumes  # noqa: E402

ts = pytest.importorskip("tensorstore")


@pytest.mark.parametrize("kind", volumes.KINDS)
def test_chunk_by_chunk_store_equals_the_whole_volume(tmp_path, kind):
    """A store written chunk by chunk (16 x 32 x 32 chunks, partial ones at the edges of a 48^3
    volume, two writer processes) reads back equal to the generator on the whole volume."""
    n = 48
    path = tmp_path / f"{kind}.zarr"
    info = volumes.generate(path, kind, n, chunk=(16, 32, 32), jobs=2)
    assert not info["cached"] and info["store_bytes"] > 0
    stored = ts.open({"driver": "zarr", "kvstore": {"driver": "file", "path": str(path)}},
                     read=True).result()
    assert stored.shape == (n, n, n)
    assert stored.chunk_layout.read_chunk.shape == (16, 32, 32)
    whole = volumes.whole(kind, n)
    assert whole.dtype == np.uint32
    np.testing.assert_array_equal(stored.read().result(), whole)
    # Any box gives the same voxels as the whole volume there.
    np.testing.assert_array_equal(volumes.box(kind, n, 5, 29, 17, 48, 0, 11), whole[5:29, 17:48, 0:11])
    if kind == "dense":
        assert whole.min() >= 1 and len(np.unique(whole)) > 5  # every voxel labelled, many cells
    else:
        assert 0 < np.count_nonzero(whole) < whole.size // 4  # mostly background
        assert len(np.unique(whole)) > 2
    # A second call reuses the complete store.
    assert volumes.generate(path, kind, n, chunk=(16, 32, 32))["cached"]


def run_quick(out, work, modes):
    completed = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--modes", *modes, "--work-dir", str(work),
         "--out", str(out)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=240,
    )
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    with open(out / "scale.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return rows, completed.stdout


def check_rows(rows, modes):
    main = [r for r in rows if r["role"] == "main"]
    assert sorted((r["kind"], int(r["n"]), r["mode"]) for r in main) == sorted(
        (k, n, m) for k in volumes.KINDS for n in (64, 128) for m in modes)
    for r in rows:
        assert int(r["voxels"]) == int(r["n"]) ** 3
        assert float(r["wall_s"]) > 0 and int(r["bytes_total"]) > 0 and int(r["svdag_bytes"]) > 0
        assert len(r["sha256"]) == 64
        assert r["identical"] == "yes", r


def test_quick_single_process(tmp_path):
    rows, stdout = run_quick(tmp_path / "out", tmp_path / "work", ["single"])
    check_rows(rows, ["single"])
    for r in rows:
        assert float(r["peak_extra_mb"]) > 0 and float(r["model_mb"]) > 0
        assert int(r["threads"]) >= 1
    assert (tmp_path / "out" / "scale.png").stat().st_size > 0
    text = (tmp_path / "out" / "scale.md").read_text()
    assert "MOUSE" in text and "## Targets" in text


def test_quick_dask(tmp_path):
    import vtksvdag

    if not hasattr(vtksvdag, "build_distributed"):
        pytest.skip("vtksvdag.build_distributed is not in this build: the Dask modes cannot run")
    pytest.importorskip("dask.distributed")
    modes = ["single", "dask1", "dask2"]
    rows, stdout = run_quick(tmp_path / "out", tmp_path / "work", modes)
    check_rows(rows, modes)
    dask = [r for r in rows if r["mode"] != "single"]
    for r in dask:
        assert int(r["threads"]) == 1  # one vtkSMPTools thread per worker
        assert len(r["workers_peak_extra_mb"].split(";")) == int(r["workers"])
        assert int(r["merge_tasks"]) == int(r["partitions"]) - 1
        assert 0 <= float(r["merge_share"]) < 1
    # The identity sweep: dask2 with partitions=1, 2 and 7 at 64^3 (4 16-slice slabs: 1, 2, 4).
    sweep = sorted(int(r["partitions"]) for r in rows if r["role"] == "identity")
    assert sweep == sorted([1, 2, 4] * len(volumes.KINDS))
    assert "What a 100-node cluster would need" in (tmp_path / "out" / "scale.md").read_text()
