#!/usr/bin/env python3
"""Scaling benchmark: generated label volumes of 256^3 to 2048^3 voxels in Zarr stores,
compressed streaming on one process and on a Dask LocalCluster with 1 and 2 workers.

Run from the repository root (see bench/README.md for the columns and the targets):

    .venv/bin/python bench/scale.py [--sizes 256 512 1024 2048] [--kinds dense tubes]
        [--modes single dask1 dask2] [--work-dir /tmp/svdag-scale] [--out bench/out/scale]
    .venv/bin/python bench/scale.py --quick            # 64^3 and 128^3 only, seconds

The volumes (bench/_scale_volumes.py) are generated chunk by chunk into Zarr v2 stores under
--work-dir and reused by later runs; generation time is printed apart. Every measurement runs in
a fresh subprocess (for Dask: a fresh LocalCluster in it), so each peak memory is that
process's own. Outputs: scale.csv (one row per measurement, written after each one), scale.md
(tables, targets, the MOUSE extrapolation and the 100-node estimate) and scale.png (log-log:
time and peak memory against voxels). A saved ``.svdag`` that differs between the modes stops
the run with exit status 1 and ``BENCHMARK FAILED: ...`` (after the outputs are written).
"""
from __future__ import annotations

import argparse
import csv
import hashlib
import json
import math
import os
import pathlib
import platform
import resource
import subprocess
import sys
import time

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import _scale_volumes as volumes  # noqa: E402

MB = 1e6
GB = 1e9
FULL_SIZES = [256, 512, 1024, 2048]
QUICK_SIZES = [64, 128]
MODES = ["single", "dask1", "dask2"]
#: Partitions (z-ranges, one Dask task each) of the main Dask runs: None is build_distributed's
#: default, one task per worker thread (the least merging).
DEFAULT_PARTITIONS = None
#: Partition counts of the identity sweep (dask2).
IDENTITY_PARTITIONS = (1, 2, 7)

# MOUSE, from the talk (../shared/reference/svdag-paper-talk.txt): raw 150.0 GB, blocks + BVH +
# SVDAG 12095.48 MB (compression rate 8.06 % = 12095.48 MB / 150.0 GB, so GB = 10^9 bytes).
MOUSE_RAW_BYTES = 150.0e9
MOUSE_SVDAG_BYTES = 12095.48e6
TALK = REPO.parent / "shared" / "reference" / "svdag-paper-talk.txt"

COLUMNS = [
    "role", "kind", "n", "voxels", "mode", "workers", "threads", "partitions", "slab_slices",
    "wall_s", "save_s", "cpu_s", "cores_used", "voxels_per_s", "ns_per_voxel",
    "peak_rss_mb", "peak_extra_mb", "slab_mb", "model_mb",
    "workers_peak_extra_mb", "worker_peak_extra_mb", "worker_slab_mb", "partial_mb", "worker_model_mb",
    "client_peak_extra_mb",
    "labels", "bytes_total", "svdag_bytes", "bytes_per_voxel", "svdag_bytes_per_voxel", "sha256",
    "identical", "partial_s_sum", "partial_s_max", "merge_tasks", "merge_s_sum", "merge_s_max",
    "merge_share", "report_wall_s", "other_cores", "gen_s", "store_bytes",
]


class BenchError(RuntimeError):
    """A check inside the benchmark failed (a probe failed, outputs differ)."""


# ---------------------------------------------------------------------------- process memory
def _status(key: str) -> int:
    """A /proc/self/status entry in bytes (VmHWM, VmRSS)."""
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith(key + ":"):
                return int(line.split()[1]) * 1024
    raise OSError(f"no {key} in /proc/self/status")


def reset_peak() -> int:
    """Resets this process's peak resident memory (VmHWM) to the current one (Linux: "5" to
    /proc/self/clear_refs) and returns the current resident bytes.

    VmHWM rather than getrusage's ru_maxrss: ru_maxrss survives execve (a subprocess reports
    its parent's peak at the fork) and cannot be reset."""
    with open("/proc/self/clear_refs", "w") as f:
        f.write("5")
    return _status("VmRSS")


def peak_bytes() -> int:
    return _status("VmHWM")


def cpu_seconds() -> float:
    """CPU seconds of this process so far (all its threads)."""
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def sha256_of(path) -> str:
    digest = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def memory_constant() -> int:
    """The constant judged on top of the peak memory models (slab + 1.5 x output, slab +
    partial): tensorstore's chunk cache bound (vtksvdag.stores.DEFAULT_CACHE_BYTES) plus 64 MiB
    for libraries, thread pools and read buffers."""
    from vtksvdag import stores

    return stores.DEFAULT_CACHE_BYTES + 64 * 2**20


# ------------------------------------------------------------------------------- the probes
def reader_slab_slices(store: str) -> int:
    """z-slices per slab vtksvdag.read takes from the store (vtksvdag.stores.slab_slices_for)."""
    from vtksvdag import stores

    location, kind = stores.find_store(store)
    array = stores.open_store(location, kind)
    return min(int(stores.slab_slices_for(array)), int(array.dims[2]))


def probe_single(store: str, out: str) -> dict:
    """Subprocess: vtksvdag.read(store) (timed, peak memory), then save (timed), sha256."""
    import vtksvdag
    from vtkmodules.vtkCommonCore import vtkSMPTools

    slab = reader_slab_slices(store)
    before = reset_peak()
    cpu = cpu_seconds()
    start = time.perf_counter()
    volume = vtksvdag.read(store)
    wall = time.perf_counter() - start
    cpu = cpu_seconds() - cpu
    peak = peak_bytes()
    stats = volume.stats()
    start = time.perf_counter()
    volume.save(out)
    save = time.perf_counter() - start
    return {
        "threads": int(vtkSMPTools.GetEstimatedNumberOfThreads()),
        "backend": vtkSMPTools.GetBackend(), "slab_slices": slab, "wall_s": wall, "save_s": save,
        "cpu_s": cpu,
        "rss_before": before, "peak_rss": peak, "labels": stats["labels"],
        "bytes_total": stats["bytes_total"], "svdag_bytes": os.path.getsize(out),
        "sha256": sha256_of(out),
    }


def _worker_setup(store):
    """On a Dask worker: import what the tasks need and open the store once (tensorstore's
    start-up, as the single probe does before its baseline), report threads, reset the peak."""
    import vtksvdag  # noqa: F401
    from vtkmodules.vtkCommonCore import vtkSMPTools

    reader_slab_slices(store)

    return {"threads": int(vtkSMPTools.GetEstimatedNumberOfThreads()),
            "smp_env": os.environ.get("VTK_SMP_MAX_THREADS"), "pid": os.getpid(),
            "rss_before": reset_peak(), "cpu_before": cpu_seconds()}


def _worker_peak():
    return {"peak": peak_bytes(), "cpu": cpu_seconds()}


def probe_dask(store: str, out: str, workers: int, slab, partitions) -> dict:
    """Subprocess: a fresh LocalCluster of `workers` single-threaded worker processes;
    vtksvdag.build_distributed(store, client, slab= or partitions=) timed, each worker's peak,
    save, sha256."""
    import vtksvdag
    from dask.distributed import Client, LocalCluster

    if not hasattr(vtksvdag, "build_distributed"):
        raise BenchError("vtksvdag.build_distributed is not available in this build")
    nz = volumes_nz(store)
    kwargs = {k: v for k, v in (("slab", slab), ("partitions", partitions)) if v}
    reader_slab = slab or reader_slab_slices(store)
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           memory_limit=0, dashboard_address=None)
    client = Client(cluster)
    try:
        client.wait_for_workers(workers)
        setup = client.run(_worker_setup, store)
        client_before = reset_peak()
        client_cpu = cpu_seconds()
        start = time.perf_counter()
        volume = vtksvdag.build_distributed(store, client=client, **kwargs)
        wall = time.perf_counter() - start
        client_cpu = cpu_seconds() - client_cpu
        client_peak = peak_bytes()
        after = client.run(_worker_peak)
        stats = volume.stats()
        report = dict(getattr(volume, "build_report", None) or {})
        start = time.perf_counter()
        volume.save(out)
        save = time.perf_counter() - start
    finally:
        client.close()
        cluster.close()
    worker_rows = [{"address": a, "threads": s["threads"], "smp_env": s["smp_env"],
                    "rss_before": s["rss_before"], "peak_rss": after[a]["peak"],
                    "cpu_s": after[a]["cpu"] - s["cpu_before"]} for a, s in setup.items()]
    return {
        "threads": max(w["threads"] for w in worker_rows), "workers": worker_rows,
        "wall_s": wall, "save_s": save, "client_rss_before": client_before,
        "cpu_s": client_cpu + sum(w["cpu_s"] for w in worker_rows),
        "client_peak_rss": client_peak, "labels": stats["labels"],
        "bytes_total": stats["bytes_total"], "svdag_bytes": os.path.getsize(out),
        "sha256": sha256_of(out), "report": _jsonable(report),
        "max_range": max((z1 - z0 for z0, z1 in report.get("z_ranges", [])), default=nz),
        "reader_slab_slices": reader_slab,
    }


def volumes_nz(store: str) -> int:
    from vtksvdag import stores

    location, kind = stores.find_store(store)
    return int(stores.open_store(location, kind).dims[2])


def _jsonable(value):
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, (int, float, str, bool)) or value is None:
        return value
    try:
        return float(value)
    except (TypeError, ValueError):
        return str(value)


def run_probe(args) -> int:
    try:
        if args.probe == "single":
            result = probe_single(args.store, args.svdag)
        else:
            result = probe_dask(args.store, args.svdag, args.workers, args.slab, args.partitions)
    except BenchError as error:
        print(json.dumps({"error": str(error)}))
        return 2
    print("PROBE " + json.dumps(result))
    return 0


def call_probe(mode: str, store: pathlib.Path, svdag: pathlib.Path, slab=None, partitions=None,
               threads=None) -> dict:
    """Runs one probe subprocess and returns its JSON result (BenchError on failure)."""
    command = [sys.executable, str(pathlib.Path(__file__).resolve()), "--probe",
               "single" if mode == "single" else "dask", "--store", str(store), "--svdag", str(svdag)]
    env = os.environ.copy()
    if mode == "single":
        if threads is not None:
            env["VTK_SMP_MAX_THREADS"] = str(threads)
    else:
        command += ["--workers", str(int(mode[len("dask"):]))]
        command += ["--slab", str(slab)] if slab else []
        command += ["--partitions", str(partitions)] if partitions else []
        # One vtkSMPTools thread per (single-threaded) Dask worker process: the workers inherit it.
        env["VTK_SMP_MAX_THREADS"] = "1"
    for attempt in (1, 2):
        if svdag.exists():
            svdag.unlink()
        busy0, own0, start = busy_cpu_seconds(), children_cpu_seconds(), time.perf_counter()
        completed = subprocess.run(command, capture_output=True, text=True, env=env)
        elapsed = time.perf_counter() - start
        other = (busy_cpu_seconds() - busy0) - (children_cpu_seconds() - own0)
        lines = [line for line in completed.stdout.splitlines() if line.startswith("PROBE ")]
        if completed.returncode == 0 and lines:
            result = json.loads(lines[-1][len("PROBE "):])
            result["other_cores"] = max(0.0, other / elapsed) if elapsed > 0 else None
            return result
        tail = (completed.stdout[-2000:] + completed.stderr[-4000:]).strip()
        message = f"the {mode} probe on {store} failed (exit {completed.returncode}):\n{tail}"
        if attempt == 2 or completed.returncode == 2:  # 2: a BenchError, not worth a retry
            raise BenchError(message)
        # Once more (a shared machine: a rebuild of the modules under a long run, a lost worker);
        # the failure is printed, never hidden.
        print(f"    RETRYING ONCE: {message}", flush=True)


def busy_cpu_seconds() -> float:
    """CPU seconds all processes of the machine have run so far (/proc/stat: not idle, not
    iowait)."""
    with open("/proc/stat") as f:
        fields = [int(v) for v in f.readline().split()[1:]]
    idle = fields[3] + (fields[4] if len(fields) > 4 else 0)
    return (sum(fields[:8]) - idle) / os.sysconf("SC_CLK_TCK")


def children_cpu_seconds() -> float:
    """CPU seconds of this process's finished children and their waited-for descendants."""
    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


# ----------------------------------------------------------------------------- measurement
def make_row(role, kind, n, mode, result, gen) -> dict:
    voxels = n ** 3
    itemsize = volumes.DTYPE.itemsize
    row = {
        "role": role, "kind": kind, "n": n, "voxels": voxels, "mode": mode,
        "workers": 0 if mode == "single" else int(mode[len("dask"):]),
        "threads": result["threads"], "wall_s": result["wall_s"], "save_s": result["save_s"],
        "voxels_per_s": voxels / result["wall_s"], "ns_per_voxel": 1e9 * result["wall_s"] / voxels,
        "labels": result["labels"], "bytes_total": result["bytes_total"],
        "svdag_bytes": result["svdag_bytes"], "bytes_per_voxel": result["bytes_total"] / voxels,
        "svdag_bytes_per_voxel": result["svdag_bytes"] / voxels, "sha256": result["sha256"],
        "gen_s": gen["seconds"], "store_bytes": gen["store_bytes"],
        "other_cores": result.get("other_cores"), "cpu_s": result.get("cpu_s"),
        "cores_used": result["cpu_s"] / result["wall_s"] if result.get("cpu_s") else None,
    }
    if mode == "single":
        slab_bytes = n * n * result["slab_slices"] * itemsize
        row.update({
            "partitions": 1, "slab_slices": result["slab_slices"],
            "peak_rss_mb": result["peak_rss"] / MB,
            "peak_extra_mb": (result["peak_rss"] - result["rss_before"]) / MB,
            "slab_mb": slab_bytes / MB,
            "model_mb": (slab_bytes + 1.5 * result["bytes_total"]) / MB,
        })
        return row
    report = result["report"]
    partial = [float(s) for s in report.get("partial_seconds", [])]
    merge = [float(s) for s in report.get("merge_seconds", [])]
    partitions = int(report.get("partitions", len(partial)))
    slab = result["max_range"]  # the thickest task's z-range
    extras = [(w["peak_rss"] - w["rss_before"]) / MB for w in result["workers"]]
    # What one partial task holds: its slab (the partition is read whole, or in the reader's
    # slabs when thinner) and its partial volume. The partial's bytes: the report's when it
    # gives them, else the partition's share of the output (a proxy).
    read_slices = min(slab, result.get("reader_slab_slices") or slab)
    worker_slab = n * n * read_slices * itemsize
    if report.get("partial_bytes"):
        partial_bytes = max(float(b) for b in report["partial_bytes"])
    else:
        partial_bytes = result["bytes_total"] * min(slab, n) / n
    row.update({
        "partitions": partitions, "slab_slices": slab,
        "peak_rss_mb": result["client_peak_rss"] / MB,
        "workers_peak_extra_mb": ";".join(f"{e:.1f}" for e in extras),
        "worker_peak_extra_mb": max(extras),
        "worker_slab_mb": worker_slab / MB, "partial_mb": partial_bytes / MB,
        "worker_model_mb": (worker_slab + partial_bytes) / MB,
        "client_peak_extra_mb": (result["client_peak_rss"] - result["client_rss_before"]) / MB,
        "partial_s_sum": sum(partial), "partial_s_max": max(partial) if partial else None,
        "merge_tasks": len(merge), "merge_s_sum": sum(merge),
        "merge_s_max": max(merge) if merge else 0.0,
        "merge_share": sum(merge) / (sum(partial) + sum(merge)) if partial else None,
        "report_wall_s": report.get("wall_seconds"),
    })
    return row


# ------------------------------------------------------------------------------ formatting
def fmt(value, digits=3) -> str:
    if value is None or value == "":
        return "-"
    if isinstance(value, float):
        if value != 0 and (abs(value) >= 1e5 or abs(value) < 10 ** -digits):
            return f"{value:.{digits}g}"
        return f"{value:.{digits}f}"
    return str(value)


def table(headers, rows) -> list:
    """A markdown table (list of lines)."""
    lines = ["| " + " | ".join(headers) + " |", "|" + "---|" * len(headers)]
    lines += ["| " + " | ".join(fmt(v) for v in r) + " |" for r in rows]
    return lines


def main_rows(rows):
    return sorted((r for r in rows if r["role"] == "main"),
                  key=lambda r: (r["kind"], r["n"], MODES.index(r["mode"]) if r["mode"] in MODES else 9))


# ---------------------------------------------------------------------------------- checks
def check_identity(rows) -> tuple[list, list]:
    """Marks each row identical yes/no against the single-process row of the same volume (else
    the first row of that volume); returns (lines, failures)."""
    lines, failures = [], []
    groups = {}
    for r in rows:
        groups.setdefault((r["kind"], r["n"]), []).append(r)
    for (kind, n), group in sorted(groups.items()):
        reference = next((r for r in group if r["mode"] == "single" and r["role"] == "main"),
                         group[0])
        for r in group:
            r["identical"] = "yes" if r["sha256"] == reference["sha256"] else "NO"
        names = ", ".join(f"{r['mode']} ({r['partitions']} part.)" for r in group)
        if all(r["identical"] == "yes" for r in group):
            lines.append(f"- {kind} {n}^3: one sha256 {reference['sha256'][:16]}... for {names}")
        else:
            bad = [f"{r['mode']} ({r['partitions']} part.) {r['sha256'][:16]}" for r in group
                   if r["identical"] != "yes"]
            failures.append(f"{kind} {n}^3: .svdag bytes differ from {reference['mode']}'s "
                            f"{reference['sha256'][:16]}: {', '.join(bad)}")
            lines.append(f"- {kind} {n}^3: DIFFERENT: {', '.join(bad)}")
    return lines, failures


#: Other processes' CPU use (cores) above which a timing is flagged as taken on a busy machine.
BUSY_CORES = 0.25


def busy_note(rows) -> str:
    loads = [r.get("other_cores") for r in rows if r.get("other_cores") not in (None, "")]
    if loads and max(loads) > BUSY_CORES:
        return (f" (BUSY MACHINE: other processes used up to {max(loads):.2f} cores during these "
                "measurements; not conclusive)")
    return ""


def check_targets(rows, quick) -> list:
    """Lines for targets (2)-(5); 'met' / 'NOT met' / 'not judged'."""
    lines = []
    main = main_rows(rows)
    constant = memory_constant()
    # (2) time per voxel flat on one process
    for kind in sorted({r["kind"] for r in main}):
        single = [r for r in main if r["kind"] == kind and r["mode"] == "single" and r["n"] >= 256]
        if len(single) < 2:
            lines.append(f"- (2) {kind}: time per voxel flat: not judged (needs two sizes >= 256^3"
                         f"{'; --quick' if quick else ''})")
            continue
        ns = [r["ns_per_voxel"] for r in single]
        ratio = max(ns) / min(ns)
        lines.append(f"- (2) {kind}: ns/voxel on one process {', '.join(f'{v:.2f}' for v in ns)} "
                     f"at {', '.join(str(r['n']) for r in single)}^3: max/min {ratio:.2f} "
                     f"(target <= 1.5): {'met' if ratio <= 1.5 else 'NOT met'}{busy_note(single)}")
    # (3) peak memory
    for r in main:
        if r["mode"] == "single":
            over = r["peak_extra_mb"] - r["model_mb"]
            ok = r["peak_extra_mb"] <= r["model_mb"] + constant / MB
            lines.append(
                f"- (3) {r['kind']} {r['n']}^3 single: peak extra {r['peak_extra_mb']:.1f} MB vs "
                f"slab {r['slab_mb']:.1f} + 1.5 x output {1.5 * r['bytes_total'] / MB:.1f} = "
                f"{r['model_mb']:.1f} MB ({over:+.1f} MB; constant allowed {constant / MB:.0f} MB): "
                f"{'met' if ok else 'NOT met'}")
        elif r.get("worker_peak_extra_mb") not in (None, ""):
            over = r["worker_peak_extra_mb"] - r["worker_model_mb"]
            ok = r["worker_peak_extra_mb"] <= r["worker_model_mb"] + constant / MB
            lines.append(
                f"- (3) {r['kind']} {r['n']}^3 {r['mode']}: worker peaks extra "
                f"{r['workers_peak_extra_mb']} MB vs slab {r['worker_slab_mb']:.1f} + partial "
                f"{r['partial_mb']:.1f} = {r['worker_model_mb']:.1f} MB ({over:+.1f} MB for the "
                f"largest; constant allowed {constant / MB:.0f} MB): {'met' if ok else 'NOT met'}; "
                f"client {r['client_peak_extra_mb']:.1f} MB")
    # (4) dask2 within 1.3x of one process (2 threads) at 1024^3
    for kind in sorted({r["kind"] for r in main}):
        pair = {r["mode"]: r for r in main if r["kind"] == kind and r["n"] == 1024}
        if "single" in pair and "dask2" in pair:
            ratio = pair["dask2"]["wall_s"] / pair["single"]["wall_s"]
            lines.append(f"- (4) {kind} 1024^3: dask2 (2 x 1 thread) {pair['dask2']['wall_s']:.1f} s "
                         f"/ single ({pair['single']['threads']} threads) "
                         f"{pair['single']['wall_s']:.1f} s = {ratio:.2f} (target <= 1.3): "
                         f"{'met' if ratio <= 1.3 else 'NOT met'}"
                         f"{busy_note([pair['single'], pair['dask2']])}")
        else:
            lines.append(f"- (4) {kind}: not judged (needs single and dask2 at 1024^3)")
    # (5) merge share
    for r in main:
        if r["mode"] != "single" and r.get("merge_share") not in (None, ""):
            lines.append(
                f"- (5) {r['kind']} {r['n']}^3 {r['mode']}: merge {r['merge_s_sum']:.2f} s over "
                f"{r['merge_tasks']} merges of {r['partitions']} partials "
                f"({r['partial_s_sum']:.2f} s): {100 * r['merge_share']:.1f} % of the task time; "
                f"largest merge {r['merge_s_max']:.2f} s = {100 * r['merge_s_max'] / r['wall_s']:.1f} "
                f"% of the wall time")
    return lines


# ------------------------------------------------------------------------- extrapolations
def mouse_lines(rows) -> list:
    main = main_rows(rows)
    talk = TALK.read_text(errors="replace") if TALK.is_file() else ""
    found = "150.0 GB" in talk and "12095.48" in talk
    lines = ["## MOUSE, by extrapolation",
             "",
             ("(both figures found in the talk's text by this run)" if found else
              f"(the talk's text {TALK} was not found or lacks the figures: they are this "
              "script's constants)"),
             "",
             "REPORTED, NOT MEASURED HERE: the talk (`../shared/reference/svdag-paper-talk.txt`) gives "
             "MOUSE as raw 150.0 GB and its SVDAG (blocks + BVH + SVDAG, GPU memory) as 12095.48 MB "
             "(compression rate 8.06 %, so GB = 10^9 bytes). It does not give the voxel count or the "
             "dtype: with 32-bit labels the raw size is 37.5 G voxels, with 64-bit labels 18.75 G. "
             "Both are extrapolated below from the largest size measured per kind (time per voxel and "
             "bytes per voxel held constant: the generators keep the feature size fixed, so both are "
             "per-voxel constants if the scaling holds; the content is synthetic, not cortex)."]
    rows_out = []
    for kind in sorted({r["kind"] for r in main}):
        for mode in MODES:
            candidates = [r for r in main if r["kind"] == kind and r["mode"] == mode]
            if not candidates:
                continue
            r = max(candidates, key=lambda r: r["n"])
            for bits in (32, 64):
                voxels = MOUSE_RAW_BYTES / (bits // 8)
                hours = voxels * r["ns_per_voxel"] * 1e-9 / 3600
                out = voxels * r["bytes_per_voxel"]
                rows_out.append([kind, mode, f"{r['n']}^3", f"uint{bits}", voxels / 1e9, hours,
                                 out / GB, voxels * r["svdag_bytes_per_voxel"] / GB,
                                 out / MOUSE_SVDAG_BYTES])
    lines += [""] + table(["kind", "mode", "from", "MOUSE dtype", "G voxels", "time h",
                           "ours in memory GB", "ours .svdag GB", "ours / paper's 12.1 GB"], rows_out)
    lines += ["", "ours in memory = bytes_total (blocks + DAG + label table, what a renderer holds "
              "besides its BVH), against the paper's blocks + BVH + SVDAG; ours .svdag = the file."]
    return lines


def cluster_lines(rows) -> list:
    """What a 100-node cluster would need for MOUSE, from the Dask runs at the largest size."""
    dask = [r for r in main_rows(rows) if r["mode"] != "single"
            and r.get("merge_tasks") not in (None, "") and int(r["partitions"]) > 1]
    lines = ["", "## What a 100-node cluster would need", ""]
    if not dask:
        return lines + ["Not estimated: no Dask run with more than one partition was measured "
                        "(vtksvdag.build_distributed missing, or --modes without dask1/dask2)."]
    nodes, partitions = 100, 128
    levels = int(math.log2(partitions))
    voxels_m = MOUSE_RAW_BYTES / 4
    edge = voxels_m ** (1 / 3)
    slab_slices = volumes.CHUNK[0]
    lines.append(
        f"Model and assumptions: {nodes} nodes, one single-threaded worker each, each as fast as "
        f"one worker here; MOUSE as 37.5 G voxels (32-bit raw), a cube of edge {edge:.0f}; "
        f"{partitions} z-partitions (a power of two >= {nodes}), merged by a tree reduction of "
        f"log2({partitions}) = {levels} levels. Partials: all partial-task seconds per voxel at the "
        "largest size (the least of dask1 and dask2: the run least disturbed by other processes), "
        "perfectly parallel (each node reads its own z-range from a store that delivers nodes "
        "times the rate here). Merges: the merge work per tree level W is taken as constant "
        "(each level reads about the whole output once), measured as (all merge seconds) / "
        "log2(our partitions) per output byte (the least of dask1 and dask2); level l from the "
        "root runs its 2^l merges of W / 2^l on min(2^l, nodes) nodes, so the merge's critical "
        "path is sum_l W / 2^l, about 2 W (the root merge alone is W). Network transfers are not "
        "counted (each level moves about the output once: 2 GB at 10 Gbit/s is under 2 s). "
        f"Memory: one slab of {slab_slices} slices (the chunk depth of these stores; the reader "
        f"reads at least a chunk along z) of a {edge:.0f}^2 face plus one partial (output / "
        f"{partitions}); the root merge's node holds its two inputs and its result, about 2.5 x "
        "the output.")
    rows_out, checks = [], []
    for kind in sorted({r["kind"] for r in dask}):
        cand = [r for r in dask if r["kind"] == kind]
        largest = max(r["n"] for r in cand)
        cand = [r for r in cand if r["n"] == largest]
        partial_per_voxel = min(r["partial_s_sum"] / r["voxels"] for r in cand)
        level_per_byte = min(r["merge_s_sum"] / max(1.0, math.log2(r["partitions"])) / r["bytes_total"]
                             for r in cand)
        single = [r for r in main_rows(rows) if r["kind"] == kind and r["mode"] == "single"
                  and r["n"] == largest]
        bytes_per_voxel = cand[0]["bytes_per_voxel"]
        out_bytes = voxels_m * bytes_per_voxel
        partial_phase = voxels_m * partial_per_voxel / nodes
        level = level_per_byte * out_bytes
        merge_path = sum(level / min(2 ** l, nodes) for l in range(levels))
        total = partial_phase + merge_path
        single_h = voxels_m * single[0]["ns_per_voxel"] * 1e-9 / 3600 if single else None
        slab_bytes = slab_slices * edge * edge * 4
        rows_out.append([kind, f"{largest}^3", partial_per_voxel * 1e9, partial_phase / 60,
                         level, merge_path / 60, total / 60,
                         100 * merge_path / total if total else None,
                         (single_h * 3600 / total) if single_h and total else None,
                         nodes * 4 / (partial_per_voxel * 1e9), out_bytes / GB,
                         (slab_bytes + out_bytes / partitions) / GB, 2.5 * out_bytes / GB])
        for r in cand:
            per_level = r["merge_s_sum"] / max(1.0, math.log2(r["partitions"]))
            checks.append(f"{kind} {r['mode']}: root merge {r['merge_s_max']:.2f} s, "
                          f"all merges / levels {per_level:.2f} s")
    lines += [""] + table(
        ["kind", "from", "partial ns/voxel/worker", "partials min", "W (one level) s",
         "merge path min", "total min", "merge share %", "speed-up over one process",
         "store read GB/s (raw)", "output GB", "per node GB (slab + partial)",
         "root merge node GB"], rows_out)
    lines += ["", "Check of the constant-work-per-level assumption at the largest size (the root "
              "merge should take about all merges / levels): " + "; ".join(checks) + ".",
              "", "The merge share grows with the node count: the partial phase shrinks as "
              "1/nodes while the root merge, which reads the whole output on one node, does not "
              "shrink at all; past a few dozen nodes the merge tree, not the reading, sets the "
              "time, and a faster merge (or a wider tree root: merging more than two parts at "
              "once does not shorten the root's pass over the output) is what more nodes need."]
    return lines


# --------------------------------------------------------------------------------- outputs
def write_csv(rows, path):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS, restval="", extrasaction="ignore")
        writer.writeheader()
        for r in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def read_csv(path) -> list:
    if not path.is_file():
        return []
    numeric_int = {"n", "voxels", "workers", "threads", "partitions", "slab_slices", "labels",
                   "bytes_total", "svdag_bytes", "merge_tasks", "store_bytes"}
    rows = []
    with open(path, newline="") as f:
        for raw in csv.DictReader(f):
            row = {}
            for k, v in raw.items():
                if v == "" or k in ("role", "kind", "mode", "sha256", "identical",
                                    "workers_peak_extra_mb"):
                    row[k] = v
                elif k in numeric_int:
                    row[k] = int(v)
                else:
                    row[k] = float(v)
            rows.append(row)
    return rows


def row_key(r):
    return (r["role"], r["kind"], int(r["n"]), r["mode"], int(r["partitions"] or 0)
            if r["role"] == "identity" else 0)


def write_markdown(rows, path, machine, identity_lines, target_lines, commandline):
    main = main_rows(rows)
    lines = ["# Scaling benchmark (bench/scale.py)", "", f"Machine: {machine}", "",
             f"Last command: `{commandline}` (with `--keep` or `--report-only`, rows of earlier "
             "runs are kept: each row's own columns, e.g. other_cores, describe its run)", "",
             "MB = 10^6 bytes. wall = read + compress (single: `vtksvdag.read` on the store; Dask: "
             "`vtksvdag.build_distributed`, cluster already started), not the save. Peak extra = "
             "peak resident memory (VmHWM) minus the resident memory before, per process.", "",
             "## Generation (chunk by chunk, not part of the figures)", ""]
    gen = {}
    for r in rows:
        gen.setdefault((r["kind"], r["n"]), r)
    lines += table(["kind", "N", "voxels", "generation s", "store MB"],
                   [[k, n, r["voxels"], r["gen_s"], r["store_bytes"] / MB]
                    for (k, n), r in sorted(gen.items())])
    lines += ["", "## Time, throughput, bytes", ""]
    lines += table(
        ["kind", "N", "mode", "threads", "partitions", "slab", "wall s", "Mvox/s", "ns/voxel",
         "cores used", "other cores", "labels", "in-memory MB", "B/voxel", ".svdag MB",
         "identical"],
        [[r["kind"], r["n"], r["mode"], r["threads"], r["partitions"], r["slab_slices"],
          r["wall_s"], r["voxels_per_s"] / 1e6, r["ns_per_voxel"], r.get("cores_used"),
          r.get("other_cores"),
          r["labels"], r["bytes_total"] / MB, r["bytes_per_voxel"], r["svdag_bytes"] / MB,
          r["identical"]] for r in main])
    lines += ["", "cores used = CPU seconds of the measured processes (single: the process; Dask: "
              "the workers and the client) during the wall time, over it; other cores = CPU time of "
              "every other process on the machine during the "
              f"measurement, in cores (of {os.cpu_count()}): above {BUSY_CORES} the timings are "
              "those of a shared machine (the targets on time say so)."]
    lines += ["", "## Peak memory per process (MB)", ""]
    lines += table(
        ["kind", "N", "mode", "peak extra", "model (slab + 1.5 x out)", "slab", "workers' peak extra",
         "worker model (slab + partial)", "client peak extra"],
        [[r["kind"], r["n"], r["mode"], r.get("peak_extra_mb") if r["mode"] == "single" else None,
          r.get("model_mb"), r.get("slab_mb") if r["mode"] == "single" else r.get("worker_slab_mb"),
          r.get("workers_peak_extra_mb"), r.get("worker_model_mb"), r.get("client_peak_extra_mb")]
         for r in main])
    dask = [r for r in main if r["mode"] != "single"]
    if dask:
        lines += ["", "## Dask tasks", ""]
        lines += table(["kind", "N", "mode", "partitions", "partials s (sum)", "largest partial s",
                        "merges", "merge s (sum)", "largest merge s", "merge share %", "report wall s"],
                       [[r["kind"], r["n"], r["mode"], r["partitions"], r["partial_s_sum"],
                         r["partial_s_max"], r["merge_tasks"], r["merge_s_sum"], r["merge_s_max"],
                         100 * r["merge_share"] if r.get("merge_share") not in (None, "") else None,
                         r["report_wall_s"]] for r in dask])
    ident = sorted((r for r in rows if r["role"] == "identity"),
                   key=lambda r: (r["kind"], r["n"], r["mode"], r["partitions"]))
    if ident:
        lines += ["", "## Identity sweep (partition counts)", ""]
        lines += table(["kind", "N", "mode", "partitions", "slab", "wall s", "sha256", "identical"],
                       [[r["kind"], r["n"], r["mode"], r["partitions"], r["slab_slices"], r["wall_s"],
                         r["sha256"][:16], r["identical"]] for r in ident])
    lines += ["", "## Targets", "", "(1) the same .svdag bytes (sha256) in every mode:"] + identity_lines
    lines += target_lines + [""] + mouse_lines(rows) + cluster_lines(rows)
    path.write_text("\n".join(lines) + "\n")


def write_plot(rows, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    main = main_rows(rows)
    fig, (ax_t, ax_m) = plt.subplots(1, 2, figsize=(12, 5))
    colors = {"single": "C0", "dask1": "C1", "dask2": "C2"}
    styles = {"dense": "-", "tubes": "--"}
    for kind in sorted({r["kind"] for r in main}):
        for mode in MODES:
            series = [r for r in main if r["kind"] == kind and r["mode"] == mode]
            if not series:
                continue
            x = [r["voxels"] for r in series]
            style = dict(color=colors.get(mode), linestyle=styles.get(kind, ":"), marker="o",
                         label=f"{kind}, {mode}")
            ax_t.plot(x, [r["wall_s"] for r in series], **style)
            memory = [r["peak_extra_mb"] if mode == "single" else r["worker_peak_extra_mb"]
                      for r in series]
            ax_m.plot(x, memory, **style)
    all_x = sorted({r["voxels"] for r in main})
    if all_x:
        ref = [r for r in main if r["voxels"] == all_x[0]]
        if ref:
            t0 = min(r["wall_s"] for r in ref)
            ax_t.plot(all_x, [t0 * v / all_x[0] for v in all_x], color="0.6", linewidth=0.8,
                      label="slope 1 (time per voxel constant)")
    for ax, ylabel, title in ((ax_t, "wall s (read + compress)", "Time"),
                              (ax_m, "peak extra MB (single: the process; Dask: largest worker)",
                               "Peak memory")):
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("voxels")
        ax.set_ylabel(ylabel)
        ax.set_title(title)
        ax.grid(True, which="both", alpha=0.3)
    ax_t.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


# ---------------------------------------------------------------------------------- machine
def machine_description() -> str:
    model = platform.processor() or "unknown CPU"
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    memory = ""
    try:
        for line in pathlib.Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                memory = f"; {int(line.split()[1]) / 2**20:.0f} GiB memory"
    except OSError:
        pass
    return f"{model}; {os.cpu_count()} logical CPUs{memory}; {platform.platform()}"


# ------------------------------------------------------------------------------------ main
def run(args) -> int:
    import vtksvdag

    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    work = pathlib.Path(args.work_dir)
    work.mkdir(parents=True, exist_ok=True)
    sizes = sorted(QUICK_SIZES if args.quick else args.sizes)
    modes = list(dict.fromkeys(args.modes))
    machine = machine_description()
    csv_path = out / "scale.csv"
    if args.report_only:
        rows = read_csv(csv_path)
        if not rows:
            raise BenchError(f"--report-only: no rows in {csv_path}")
        return report(rows, out, machine, args)
    has_distributed = hasattr(vtksvdag, "build_distributed")
    if not has_distributed and any(m != "single" for m in modes):
        raise BenchError("vtksvdag.build_distributed is not available in this build: run with "
                         "--modes single")
    print(f"machine: {machine}")
    print(f"sizes {sizes}, kinds {args.kinds}, modes {modes}; stores in {work}; "
          f"single: vtkSMPTools threads {args.threads or 'default'}; Dask workers: "
          "VTK_SMP_MAX_THREADS=1, threads_per_worker=1", flush=True)
    rows = read_csv(csv_path) if args.keep else []

    def record(row):
        key = row_key(row)
        rows[:] = [r for r in rows if row_key(r) != key] + [row]
        write_csv(rows, csv_path)

    plan = [(kind, n) for n in sizes for kind in args.kinds]
    gens = {}

    def store_for(kind, n):
        path = volumes.store_path(work, kind, n)
        if (kind, n) not in gens:
            gen = volumes.generate(path, kind, n, jobs=args.jobs)
            gens[(kind, n)] = gen
            print(f"  {kind} {n}^3: store {'reused (generated' if gen['cached'] else 'generated ('}"
                  f" in {gen['seconds']:.1f} s{')' if gen['cached'] else ''}, "
                  f"{gen['store_bytes'] / MB:.1f} MB on disk)", flush=True)
        return path

    svdag = work / "scale-output.svdag"
    split = {"slab": args.slab, "partitions": args.partitions}
    for kind, n in plan:
        store = store_for(kind, n)
        for mode in modes:
            result = call_probe(mode, store, svdag, threads=args.threads, **split)
            row = make_row("main", kind, n, mode, result, gens[(kind, n)])
            record(row)
            extra = row["peak_extra_mb"] if mode == "single" else row["worker_peak_extra_mb"]
            print(f"    {mode:6s} {kind} {n}^3: {row['wall_s']:.2f} s, "
                  f"{row['voxels_per_s'] / 1e6:.1f} Mvox/s, {row['bytes_total'] / MB:.2f} MB, "
                  f"{row['partitions']} partition(s), peak extra {extra:.1f} MB, "
                  f"sha256 {row['sha256'][:12]}", flush=True)
    if not args.no_identity and any(m != "single" for m in modes):
        n = sizes[0]
        print(f"identity sweep at {n}^3: dask2 with partitions {IDENTITY_PARTITIONS}", flush=True)
        for kind in args.kinds:
            store = store_for(kind, n)
            for p in IDENTITY_PARTITIONS:
                result = call_probe("dask2", store, svdag, partitions=p)
                row = make_row("identity", kind, n, "dask2", result, gens[(kind, n)])
                record(row)
                print(f"    dask2 {kind} {n}^3, partitions={p}: {row['partitions']} partitions "
                      f"(thickest {row['slab_slices']} slices), sha256 {row['sha256'][:12]}",
                      flush=True)
    return report(rows, out, machine, args)


def report(rows, out, machine, args) -> int:
    """Checks, scale.csv, scale.md and scale.png from the rows; BenchError if outputs differ."""
    csv_path, md_path, png_path = out / "scale.csv", out / "scale.md", out / "scale.png"
    for r in rows:  # rows from a run that reused a store: its marker has the generation time
        if not r.get("gen_s"):
            r["gen_s"] = volumes.recorded_seconds(volumes.store_path(args.work_dir, r["kind"], r["n"]))
    identity_lines, failures = check_identity(rows)
    target_lines = check_targets(rows, args.quick)
    write_csv(rows, csv_path)
    commandline = " ".join([".venv/bin/python", "bench/scale.py"] + sys.argv[1:])
    write_markdown(rows, md_path, machine, identity_lines, target_lines, commandline)
    write_plot(rows, png_path)
    print("\n" + md_path.read_text())
    print(f"wrote {csv_path}, {md_path} and {png_path}")
    if failures:
        raise BenchError("; ".join(failures))
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=FULL_SIZES,
                        help="volume edges N (N^3 voxels)")
    parser.add_argument("--kinds", nargs="+", default=list(volumes.KINDS), choices=volumes.KINDS)
    parser.add_argument("--modes", nargs="+", default=MODES, choices=MODES)
    parser.add_argument("--work-dir", default="/tmp/svdag-scale", help="where the stores are cached")
    parser.add_argument("--out", default=str(REPO / "bench" / "out" / "scale"))
    parser.add_argument("--quick", action="store_true", help="sizes 64 and 128 only")
    parser.add_argument("--jobs", type=int, default=min(2, os.cpu_count() or 1),
                        help="processes generating the stores")
    parser.add_argument("--partitions", type=int, default=DEFAULT_PARTITIONS,
                        help="Dask tasks reading the store (build_distributed's partitions=; "
                        "default: one per worker)")
    parser.add_argument("--slab", type=int, default=None,
                        help="z-slices a Dask task reads at a time (build_distributed's slab=, a "
                        "multiple of 16; default: as vtksvdag.read)")
    parser.add_argument("--threads", type=int, default=None,
                        help="VTK_SMP_MAX_THREADS of the single-process runs (default: VTK's)")
    parser.add_argument("--keep", action="store_true",
                        help="keep the rows of an existing scale.csv that this run does not redo")
    parser.add_argument("--no-identity", action="store_true", help="skip the partition sweep")
    parser.add_argument("--report-only", action="store_true",
                        help="measure nothing: checks, scale.md and scale.png from scale.csv")
    parser.add_argument("--probe", choices=["single", "dask"], help=argparse.SUPPRESS)
    parser.add_argument("--store", help=argparse.SUPPRESS)
    parser.add_argument("--svdag", help=argparse.SUPPRESS)
    parser.add_argument("--workers", type=int, default=1, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.probe:
        return run_probe(args)
    if min(args.sizes) < 16:
        parser.error("sizes must be at least 16")
    try:
        return run(args)
    except BenchError as error:
        print(f"\nBENCHMARK FAILED: {error}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
