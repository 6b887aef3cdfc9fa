"""Smoke test of the compression benchmark: `bench/compression.py --quick` runs and writes a
complete CSV and a plot. It asserts structure and consistency, never timings."""
import csv
import os
import pathlib
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = REPO / "bench" / "compression.py"

EXPECTED_ROWS = [
    "totalseg_ct",
    "fib25_64",
    "dvid_fib19_64",
    "voronoi64_100",
    "tubes64",
    "checkerboard64_p1",
    "checkerboard64_p2",
]
EXPECTED_COLUMNS = [
    "volume", "source", "dims_xyz", "dtype", "voxels", "labels",
    "blocks", "root_nodes", "mid_nodes", "leaf_nodes",
    "bytes_blocks", "bytes_dag", "bytes_labels", "bytes_total",
    "pct_raw32", "min_width_bytes", "pct_raw_min", "bits_per_voxel",
    "build_s", "build_runs", "voxels_per_s", "file_s", "file_via", "roundtrip",
    "peak_rss_mb", "baseline_rss_mb", "peak_extra_mb", "model_mb",
    "cseg_dtype", "cseg_bytes", "cseg_s", "ours_over_cseg",
    "stream_dtype", "zstd19_bytes", "zstd19_s", "gzip9_bytes", "gzip9_s", "ours_over_zstd19",
    "crackle_bytes", "crackle_s", "ours_over_crackle",
    "file2_bytes", "load2_s", "load2_over_build",
    "file3_bytes", "write3_s", "load3_s", "load3_over_build",
    "file3_over_cseg", "file3_over_crackle", "file3_over_zstd19",
    "file4_bytes", "write4_s", "load4_s", "load4_over_build", "file4_over_cseg",
    "read4_s", "read4_over_build",
    "frame_compute_ms", "frame_rt_ms", "base_frame_compute_ms", "base_frame_rt_ms",
    "frame_compute_over_base", "frame_rt_over_base",
]


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory, shared_data):
    out = tmp_path_factory.mktemp("bench")
    completed = subprocess.run(
        # The frame times through this build's tool twice (as its own baseline): the columns
        # and the interleaving, at the cost of a few seconds of lavapipe.
        [sys.executable, str(SCRIPT), "--quick", "--repeats", "1", "--out", str(out), "--frames",
         "--frame-rounds", "1", "--baseline-render", str(REPO / "build" / "bin" / "vtksvdag-render")],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600,
    )
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    return out, completed.stdout


def read_rows(out):
    with open(out / "compression.csv", newline="") as f:
        reader = csv.DictReader(f)
        return reader.fieldnames, list(reader)


def test_csv_has_the_expected_columns_and_rows(quick_run):
    out, _ = quick_run
    columns, rows = read_rows(out)
    assert columns == EXPECTED_COLUMNS
    assert [r["volume"] for r in rows] == EXPECTED_ROWS
    for r in rows:
        missing = [c for c in EXPECTED_COLUMNS if r[c] == ""]
        assert not missing, f"{r['volume']}: empty {missing}"
        assert r["roundtrip"] == "ok"


def test_csv_values_are_consistent(quick_run):
    out, _ = quick_run
    _, rows = read_rows(out)
    for r in rows:
        voxels = int(r["voxels"])
        x, y, z = (int(v) for v in r["dims_xyz"].split("x"))
        assert voxels == x * y * z
        total = int(r["bytes_total"])
        assert total == int(r["bytes_blocks"]) + int(r["bytes_dag"]) + int(r["bytes_labels"])
        assert float(r["bits_per_voxel"]) == pytest.approx(8 * total / voxels, rel=1e-4)
        assert float(r["pct_raw32"]) == pytest.approx(100 * total / (4 * voxels), rel=1e-4)
        assert int(r["min_width_bytes"]) in (1, 2, 4, 8)
        assert int(r["blocks"]) >= int(r["labels"]) >= 1
        assert float(r["ours_over_cseg"]) == pytest.approx(total / int(r["cseg_bytes"]), rel=1e-4)
        assert r["cseg_dtype"] in ("uint32", "uint64")
        assert int(r["zstd19_bytes"]) > 0 and int(r["gzip9_bytes"]) > 0
        assert float(r["ours_over_crackle"]) == pytest.approx(total / int(r["crackle_bytes"]), rel=1e-4)
        assert float(r["peak_rss_mb"]) >= float(r["baseline_rss_mb"]) > 0
        assert r["file_via"] in ("reader", "pynrrd+filter")
        # Format 2 holds the sections zstd-compressed, or stored where that does not pay; format
        # 3 codes the occupancy: far smaller on real volumes, and at worst the checkerboards'
        # few hundred bytes (a DAG of one node each way, against 4096 voxels a cell to code).
        assert 0 < int(r["file2_bytes"]) <= total + 4096
        assert 260 < int(r["file3_bytes"]) <= 1.5 * int(r["file2_bytes"]) + 64
        if r["source"] == "file":
            assert int(r["file3_bytes"]) < 0.6 * int(r["file2_bytes"])
            # Format 4 codes the DAG itself: between the coded volume and format 2.
            assert int(r["file3_bytes"]) < int(r["file4_bytes"]) < int(r["file2_bytes"])
        assert float(r["file4_over_cseg"]) == pytest.approx(
            int(r["file4_bytes"]) / int(r["cseg_bytes"]), rel=1e-4)
        for version in (2, 3, 4):
            assert float(r[f"load{version}_over_build"]) == pytest.approx(
                float(r[f"load{version}_s"]) / float(r["build_s"]), rel=1e-3)
        assert float(r["read4_over_build"]) == pytest.approx(
            float(r["read4_s"]) / float(r["build_s"]), rel=1e-3)
        for backend in ("compute", "rt"):
            ms, base = float(r[f"frame_{backend}_ms"]), float(r[f"base_frame_{backend}_ms"])
            assert ms > 0 and base > 0
            assert float(r[f"frame_{backend}_over_base"]) == pytest.approx(ms / base, rel=1e-3)
        for other in ("cseg", "crackle", "zstd19"):
            assert float(r[f"file3_over_{other}"]) == pytest.approx(
                int(r["file3_bytes"]) / int(r[f"{other}_bytes"]), rel=1e-4)
    by_name = {r["volume"]: r for r in rows}
    # Known facts about the inputs (shared/data/README.md and the generators' definitions).
    assert by_name["fib25_64"]["labels"] == "52" and by_name["fib25_64"]["dtype"] == "uint64"
    assert by_name["totalseg_ct"]["dims_xyz"] == "122x101x30"
    assert by_name["dvid_fib19_64"]["cseg_dtype"] == "uint64"  # label IDs around 5e10
    assert by_name["checkerboard64_p1"]["labels"] == "2"
    assert by_name["checkerboard64_p1"]["source"] == "generated"


def test_report_and_plot(quick_run):
    out, stdout = quick_run
    png = out / "compression.png"
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "machine:" in stdout
    assert "REPORTED, NOT MEASURED HERE" in stdout
    assert "The .svdag file, format 4.0 (DAG streams, the default), 3.0 (coded) and 2.0" in stdout
    for name in EXPECTED_ROWS:
        assert f"{name}: " in stdout and "round trips ok" in stdout


def test_levels_csv_adds_up_to_the_bytes(quick_run):
    out, stdout = quick_run
    _, rows = read_rows(out)
    with open(out / "compression_levels.csv", newline="") as f:
        levels = list(csv.DictReader(f))
    assert [(r["volume"], r["level"]) for r in levels] == [
        (name, level) for name in EXPECTED_ROWS for level in ("blocks", "roots", "mids", "leaves")
    ]
    for r in rows:
        mine = {x["level"]: x for x in levels if x["volume"] == r["volume"]}
        # The bytes held (the compact form) level by level; the pooled form's node counts.
        assert int(mine["blocks"]["compact_bytes"]) == int(r["bytes_blocks"])
        assert sum(int(mine[level]["compact_bytes"]) for level in ("roots", "mids", "leaves")) == int(
            r["bytes_dag"])
        assert int(mine["roots"]["nodes"]) == int(r["root_nodes"])
        assert int(mine["mids"]["nodes"]) == int(r["mid_nodes"])
        assert int(mine["leaves"]["compact_bytes"]) == 8 * int(r["leaf_nodes"])
        assert int(r["leaf_nodes"]) <= int(mine["leaves"]["nodes"])
        # On real volumes most children are used once: the compact form is the smaller one (on
        # the checkerboards, whose few nodes are all shared, its flag bits may cost a few bytes).
        if r["source"] == "file":
            pooled = sum(int(mine[level]["bytes"]) for level in ("blocks", "roots", "mids", "leaves"))
            assert int(r["bytes_blocks"]) + int(r["bytes_dag"]) < 0.95 * pooled
        for x in mine.values():
            assert int(x["symmetry_classes"]) <= int(x["mirror_classes"]) <= int(x["nodes"])
    assert "Where the bytes go" in stdout and "Remedies, estimated" in stdout


def load_bench_module():
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_compression", SCRIPT)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_round_trip_check_fails_loudly_on_a_mismatch():
    import numpy as np

    bench = load_bench_module()
    labels = np.arange(4 * 5 * 6, dtype=np.uint16).reshape(4, 5, 6)
    svdag, _ = bench.build_svdag(bench.to_image(labels))
    bench.check_round_trip("same", labels, svdag)  # passes
    changed = labels.copy()
    changed[3, 4, 5] += 1
    with pytest.raises(bench.BenchError, match=r"LOSSY ROUND TRIP, 1 voxels differ; first at \(x=5, y=4, z=3\)"):
        bench.check_round_trip("changed", changed, svdag)
    with pytest.raises(bench.BenchError, match="dtype"):
        bench.check_round_trip("wider", labels.astype(np.uint32), svdag)


def test_dense_indices_and_cseg_input():
    import numpy as np

    bench = load_bench_module()
    values, indices = bench.dense_indices(np.array([[7, -3], [7, 10**12]]))
    np.testing.assert_array_equal(values, [-3, 7, 10**12])
    assert indices.dtype == np.uint8
    np.testing.assert_array_equal(indices, [[1, 0], [1, 2]])
    assert bench.dense_indices(np.arange(300))[1].dtype == np.uint16
    assert bench.cseg_input(np.array([1, 2], dtype=np.int64)).dtype == np.uint32
    assert bench.cseg_input(np.array([1, 2**32], dtype=np.int64)).dtype == np.uint64
    negative = bench.cseg_input(np.array([-1, 2], dtype=np.int32))
    assert negative.dtype == np.uint64 and negative[0] == 2**64 - 1
    assert [bench.min_width_bytes(n) for n in (2, 256, 257, 65536, 65537, 2**33)] == [1, 1, 2, 2, 4, 8]


def test_large_mode_writes_its_table(tmp_path):
    completed = subprocess.run(
        [sys.executable, str(SCRIPT), "--large", "--quick", "--out", str(tmp_path)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=600,
    )
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    assert "Larger EM-like volumes in memory" in completed.stdout
    with open(tmp_path / "compression_large.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert [r["volume"] for r in rows] == ["em_mosaic2x32"]
    r = rows[0]
    assert r["dims_xyz"] == "64x64x64" and int(r["voxels"]) == 64 ** 3
    total = int(r["bytes_total"])
    assert total == int(r["bytes_blocks"]) + int(r["bytes_dag"]) + int(r["bytes_labels"])
    assert float(r["ours_over_cseg"]) == pytest.approx(total / int(r["cseg_bytes"]), rel=1e-4)


def test_mosaic_is_its_parts_seeded_apart_with_labels_of_their_own():
    import numpy as np

    sys.path.insert(0, str(REPO / "bench"))
    import _em_volumes as em

    n = 16
    seeds = em.cells_at(n)
    whole = em.mosaic(n, 2, workers=1)
    assert whole.shape == (2 * n,) * 3 and whole.dtype == np.uint32
    labels_of_parts = []
    for c, (cz, cy, cx) in enumerate((z, y, x) for z in range(2) for y in range(2) for x in range(2)):
        part = em.em_like(n, seeds, em.SEED + c).astype(np.uint32)
        expected = np.where(part != 0, part + c * seeds, 0)
        got = whole[cz * n:(cz + 1) * n, cy * n:(cy + 1) * n, cx * n:(cx + 1) * n]
        np.testing.assert_array_equal(got, expected)
        labels_of_parts.append(set(np.unique(got[got != 0]).tolist()))
    for a in range(8):
        for b in range(a + 1, 8):
            assert not labels_of_parts[a] & labels_of_parts[b]
    assert not np.array_equal(whole[:n, :n, :n] != 0, whole[:n, :n, n:] != 0)  # seeded apart


def test_cseg_in_chunks_is_the_sum_of_its_pieces():
    import numpy as np

    bench = load_bench_module()
    labels = np.random.default_rng(5).integers(0, 50, (40, 24, 33)).astype(np.uint32)
    whole = bench.measure_cseg("whole", labels)
    assert bench.measure_cseg_chunked("one chunk", labels, chunk=64)["cseg_bytes"] == whole["cseg_bytes"]
    pieces = [p for zs in np.array_split(labels, [16, 32], axis=0)
              for ys in np.array_split(zs, [16], axis=1)
              for p in np.array_split(ys, [16, 32], axis=2)]
    assert len(pieces) == 18
    expected = sum(bench.measure_cseg("piece", np.ascontiguousarray(p))["cseg_bytes"] for p in pieces)
    assert bench.measure_cseg_chunked("chunks", labels, chunk=16)["cseg_bytes"] == expected
