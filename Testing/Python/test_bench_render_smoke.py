"""Smoke test of the rendering benchmark: `bench/render.py --quick` runs and writes a complete
CSV and the error plot. It asserts structure and consistency, never absolute timings."""
import csv
import os
import pathlib
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SCRIPT = REPO / "bench" / "render.py"
COLUMNS = [
    "kind", "volume", "device", "backend", "width", "height", "lod", "bounces", "nee", "denoise",
    "spp",
    "frames", "ms_median", "ms_min", "ms_restart_median", "restart_ratio", "seconds", "rmse",
    "mean_rel_error", "setup_seconds", "bytes_blas", "bytes_tlas", "bytes_encoding",
    "bytes_acceleration", "bytes_device",
    "rays_per_pixel", "cells_per_ray", "blocks_per_ray", "walks_per_ray", "dag_steps_per_ray",
    "steps_per_ray", "quad_max_steps", "quad_efficiency",
]
STEP_COLUMNS = COLUMNS[COLUMNS.index("rays_per_pixel"):]


@pytest.fixture(scope="module")
def quick_run(tmp_path_factory, shared_data):
    out = tmp_path_factory.mktemp("bench_render")
    completed = subprocess.run(
        [sys.executable, str(SCRIPT), "--quick", "--out", str(out)],
        capture_output=True, text=True, cwd=REPO, env=os.environ.copy(), timeout=300,
    )
    assert completed.returncode == 0, completed.stdout[-3000:] + completed.stderr[-3000:]
    with open(out / "render.csv", newline="") as f:
        reader = csv.DictReader(f)
        return out, completed.stdout, reader.fieldnames, list(reader)


def test_csv_columns_and_rows(quick_run):
    out, stdout, columns, rows = quick_run
    assert columns == COLUMNS
    frames = [r for r in rows if r["kind"] == "frame"]
    errors = [r for r in rows if r["kind"] == "error"]
    assert len(frames) + len(errors) == len(rows)
    # A shared volume and a generated EM-like one, each: 3 configurations (voxel and block with
    # NEE, voxel without) x both backends at one size.
    assert sorted({r["volume"] for r in frames}) == ["em_like48", "plantseg_1135_mini"]
    for volume in ("plantseg_1135_mini", "em_like48"):
        assert sorted((r["lod"], r["nee"], r["backend"]) for r in frames if r["volume"] == volume) == sorted(
            (lod, nee, backend) for lod, nee in (("voxel", "1"), ("block", "1"), ("voxel", "0"))
            for backend in ("rt", "compute"))
    # Step statistics beside the compute frames (none for rt): every ray visits at most the cells
    # of the grid, steps per ray is the sum of its parts, quads' busiest pixel >= the mean.
    for r in frames:
        if r["backend"] == "rt":
            assert all(r[c] == "" for c in STEP_COLUMNS)
            continue
        v = {c: float(r[c]) for c in STEP_COLUMNS}
        assert v["rays_per_pixel"] >= 1.0
        assert v["walks_per_ray"] <= v["blocks_per_ray"] <= v["steps_per_ray"]
        assert abs(v["cells_per_ray"] + v["blocks_per_ray"] + v["dag_steps_per_ray"]
                   - v["steps_per_ray"]) < 1e-3
        assert 0.0 < v["quad_efficiency"] <= 1.0 and v["quad_max_steps"] > 0
        if r["lod"] == "block":
            assert v["dag_steps_per_ray"] == 0.0  # block LOD hits the box: no DAG walk
    for r in frames:
        assert float(r["ms_median"]) > 0 and float(r["ms_min"]) <= float(r["ms_median"])
        assert float(r["ms_restart_median"]) > 0
        assert abs(float(r["restart_ratio"]) - float(r["ms_restart_median"]) / float(r["ms_median"])) < 0.01
        assert r["device"] and int(r["bytes_encoding"]) > 0 and int(r["bytes_acceleration"]) > 0
        assert int(r["bytes_device"]) > int(r["bytes_encoding"]) + int(r["bytes_acceleration"])
        # The compute backend holds no BVH; the rt one does, and more acceleration bytes.
        assert (int(r["bytes_blas"]) > 0) == (r["backend"] == "rt")
    for lod, nee in (("voxel", "1"), ("block", "1")):
        pair = {r["backend"]: r for r in frames
                if (r["volume"], r["lod"], r["nee"]) == ("plantseg_1135_mini", lod, nee)}
        assert int(pair["rt"]["bytes_acceleration"]) > int(pair["compute"]["bytes_acceleration"])
        assert pair["rt"]["bytes_encoding"] == pair["compute"]["bytes_encoding"]
    # Error curves per LOD and estimator at 1, 2, 4, 8 spp, time growing with the samples.
    # Error curves per LOD and estimator (NEE off, NEE on, NEE on denoised) at 1, 2, 4, 8 spp,
    # time growing with the samples.
    for lod in ("voxel", "block"):
        for nee, denoise in (("0", "0"), ("1", "0"), ("1", "1")):
            curve = [r for r in errors
                     if r["lod"] == lod and r["nee"] == nee and r["denoise"] == denoise]
            assert [int(r["spp"]) for r in curve] == [1, 2, 4, 8]
            seconds = [float(r["seconds"]) for r in curve]
            assert all(b >= a for a, b in zip(seconds, seconds[1:]))
            assert all(float(r["rmse"]) >= 0 and float(r["mean_rel_error"]) >= 0 for r in curve)
        # With NEE, 8 samples are closer to the reference than 1; one denoised sample is closer
        # than one raw sample.
        nee_curve = [float(r["rmse"]) for r in errors
                     if r["lod"] == lod and r["nee"] == "1" and r["denoise"] == "0"]
        assert nee_curve[-1] < nee_curve[0]
        denoised = [float(r["rmse"]) for r in errors
                    if r["lod"] == lod and r["nee"] == "1" and r["denoise"] == "1"]
        assert denoised[0] < nee_curve[0]
    assert (out / "render_error.png").stat().st_size > 0
    assert (out / "render_backends.png").exists()
    assert "reported, not measured here" in stdout
    assert "Against Volcanite" in stdout
