#!/usr/bin/env python3
"""Compression benchmark: our SVDAG against compressed_segmentation, zstd and gzip, in one run.

Run from the repository root (see bench/README.md for the columns and the targets):

    .venv/bin/python bench/compression.py [--quick] [--out bench/out]

For every volume (the real ones in ../shared/data and generated ones, written to a temporary
file) it compresses the in-memory array with vtkImageDataToSegmentationSVDAG and the file with
vtkSegmentationVolumeReader, decodes both and compares (a mismatch stops the run with exit
status 1), measures the reference codecs on the same array, measures the peak memory of
compressing from the file in a subprocess, prints plain-text tables, and writes compression.csv
and compression.png to the output folder. Figures reported elsewhere (../shared/notes/anchors.md) are
printed in a separate table and never mixed with measured ones.

    .venv/bin/python bench/compression.py --large [--quick]

measures only the in-memory bytes of EM-like volumes larger than 512^3 (LARGE_VOLUMES) against
compressed_segmentation, both round trips checked, and writes compression_large.csv.
"""
from __future__ import annotations

import argparse
import csv
import gzip
import json
import os
import pathlib
import platform
import resource
import statistics
import subprocess
import sys
import tempfile
import time

# The modules that compressing from a file needs. The memory baseline subprocess imports exactly
# these (by importing this file) and nothing else, so that their footprint cancels out.
import nrrd
import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonCore import vtkSMPTools
from vtkmodules.vtkCommonDataModel import vtkImageData

from vtksvdag import SegmentationVolume, synthetic
from vtksvdag.vtkSVDAGCore import vtkImageDataToSegmentationSVDAG, vtkSegmentationSVDAGToImageData

try:
    from vtksvdag.vtkSVDAGIO import vtkSegmentationVolumeReader
except ImportError:  # an older build without the IO module
    vtkSegmentationVolumeReader = None

REPO = pathlib.Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO / "bench"))
import _em_volumes  # noqa: E402  (bench/ is not a package)

SHARED = REPO.parent / "shared"
# The real volumes: ../shared/data, or where VTKSVDAG_SHARED_DATA points (as the tests).
DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or SHARED / "data")
ANCHORS = SHARED / "notes" / "anchors.md"
MB = 1e6
SLAB_DEPTH = 16  # z-slices per slab of the streaming builder (svdag::Builder::SlabDepth)
# Volumes up to this many voxels are built several times and the median time is reported.
MEDIAN_MAX_VOXELS = 256**3
# Their builds and loads are repeated until they span at least this long (at most MAX_RUNS times):
# the median of seven sub-millisecond runs follows whatever else the machine did in that
# millisecond, and a build and a load of a small volume then disagreed by up to 1.5x from run to run.
MIN_MEASURED_S = 0.2
MAX_RUNS = 1000

REAL_VOLUMES = [
    "voronoi256",
    "voronoi256_sphere",
    "fib_ts2_groundtruth250",
    "gala_train_gt",
    "plantseg_1135_mini",
    "totalseg_ct",
    "fib25_64",
    "dvid_fib19_64",
]
QUICK_REAL_VOLUMES = ["totalseg_ct", "fib25_64", "dvid_fib19_64"]

# name -> generator of a (z, y, x) array. Seeds are fixed so every run measures the same data.
GENERATED_VOLUMES = {
    "voronoi256_1000": lambda: synthetic.voronoi((256, 256, 256), 1000, seed=2024),
    "tubes256": lambda: synthetic.tubes((256, 256, 256), 60, 3.0, seed=2024),
    "checkerboard64_p1": lambda: synthetic.checkerboard((64, 64, 64), 2, 1),
    "checkerboard64_p2": lambda: synthetic.checkerboard((64, 64, 64), 2, 2),
    # Electron-microscopy-like: ~2,500 warped cells, membranes and unannotated space.
    "em_like512": lambda: _em_volumes.em_like(512),
}
QUICK_GENERATED_VOLUMES = {
    "voronoi64_100": lambda: synthetic.voronoi((64, 64, 64), 100, seed=2024),
    "tubes64": lambda: synthetic.tubes((64, 64, 64), 8, 2.0, seed=2024),
    "checkerboard64_p1": GENERATED_VOLUMES["checkerboard64_p1"],
    "checkerboard64_p2": GENERATED_VOLUMES["checkerboard64_p2"],
}

# Issue 23's in-memory target holds on EM-like volumes "of 512^3 and up": larger ones, measured by
# --large for their bytes in memory against compressed_segmentation only (their files, codecs and
# peak memory would take an hour). Eight em_like(512) parts seeded apart (bench/_em_volumes.py).
LARGE_VOLUMES = {"em_mosaic2x512": lambda: _em_volumes.mosaic(512, 2)}
QUICK_LARGE_VOLUMES = {"em_mosaic2x32": lambda: _em_volumes.mosaic(32, 2)}
LARGE_COLUMNS = ["volume", "dims_xyz", "voxels", "labels", "blocks", "root_nodes", "mid_nodes",
                 "leaf_nodes", "bytes_blocks", "bytes_dag", "bytes_labels", "bytes_total", "bits_per_voxel",
                 "generate_s", "build_s", "cseg_bytes", "cseg_s", "ours_over_cseg"]

COLUMNS = [
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


class BenchError(RuntimeError):
    """A check inside the benchmark failed (lossless round trip, reference codec, subprocess)."""


# ----------------------------------------------------------------------------------- machine
def machine_description() -> str:
    model = platform.processor() or "unknown CPU"
    try:
        for line in pathlib.Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                model = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    return (
        f"{model}; {os.cpu_count()} logical CPUs ({usable} usable); "
        f"vtkSMPTools backend {vtkSMPTools.GetBackend()} with "
        f"{vtkSMPTools.GetEstimatedNumberOfThreads()} threads; {platform.platform()}; "
        f"Python {platform.python_version()}, numpy {np.__version__}"
    )


# ------------------------------------------------------------------------------ our codec
def to_image(labels: np.ndarray) -> vtkImageData:
    """A vtkImageData viewing a (z, y, x) label array (x fastest), without copying."""
    labels = np.ascontiguousarray(labels)
    image = vtkImageData()
    image.SetDimensions(labels.shape[2], labels.shape[1], labels.shape[0])
    scalars = numpy_to_vtk(labels.ravel(), deep=False)
    scalars.SetName("Labels")
    image.GetPointData().SetScalars(scalars)  # numpy_to_vtk keeps a reference to `labels`
    return image


def build_svdag(image: vtkImageData):
    """Compresses an image; returns the output and the seconds the filter took."""
    build = vtkImageDataToSegmentationSVDAG()
    build.SetInputData(image)
    start = time.perf_counter()
    build.Update()
    seconds = time.perf_counter() - start
    if build.GetErrorCode() != 0:
        raise BenchError(f"vtkImageDataToSegmentationSVDAG failed with error code {build.GetErrorCode()}")
    svdag = build.GetOutput()
    if not svdag.HasVolume():
        raise BenchError("vtkImageDataToSegmentationSVDAG produced no volume")
    return svdag, seconds


def decode_svdag(svdag, shape) -> np.ndarray:
    decode = vtkSegmentationSVDAGToImageData()
    decode.SetInputData(svdag)
    decode.Update()
    scalars = decode.GetOutput().GetPointData().GetScalars()
    if scalars is None:
        raise BenchError("vtkSegmentationSVDAGToImageData produced no scalars")
    return vtk_to_numpy(scalars).reshape(shape)


def check_round_trip(name: str, labels: np.ndarray, svdag) -> None:
    decoded = decode_svdag(svdag, labels.shape)
    if decoded.dtype.kind != labels.dtype.kind or decoded.dtype.itemsize != labels.dtype.itemsize:
        raise BenchError(f"{name}: decoded dtype {decoded.dtype} differs from the input's {labels.dtype}")
    if not np.array_equal(decoded, labels):
        bad = np.argwhere(decoded != labels)
        z, y, x = bad[0]
        raise BenchError(
            f"{name}: LOSSY ROUND TRIP, {len(bad)} voxels differ; first at (x={x}, y={y}, z={z}): "
            f"expected {labels[z, y, x]}, decoded {decoded[z, y, x]}"
        )


def reader_class():
    """vtkSegmentationVolumeReader once it is a real reader (it was a placeholder at first)."""
    if vtkSegmentationVolumeReader is None or not hasattr(vtkSegmentationVolumeReader, "SetFileName"):
        return None
    return vtkSegmentationVolumeReader


def compress_file(path: str):
    """Reads and compresses a label volume file the way a user would; returns (svdag, how)."""
    reader = reader_class()
    if reader is not None:
        r = reader()
        r.SetFileName(path)
        r.Update()
        if r.GetErrorCode() != 0:
            raise BenchError(f"vtkSegmentationVolumeReader failed on {path}: error code {r.GetErrorCode()}")
        return r.GetOutput(), "reader"
    labels, _ = nrrd.read(path, index_order="C")
    svdag, _ = build_svdag(to_image(labels))
    return svdag, "pynrrd+filter"


# ---------------------------------------------------------------------------- memory probe
def memory_probe(path: str) -> None:
    """Subprocess entry: compress `path` (or nothing for "-") and print the peak RSS as JSON."""
    result = {"how": "baseline", "bytes_total": 0}
    if path != "-":
        svdag, how = compress_file(path)
        result = {"how": how, "bytes_total": int(svdag.GetCompressedSize())}
    result["maxrss_kb"] = peak_rss_kb()
    print(json.dumps(result))


def peak_rss_kb() -> int:
    """Peak resident memory of this process in KiB.

    On Linux, getrusage's ru_maxrss survives execve: a subprocess started from this big benchmark
    process would report the parent's peak. VmHWM in /proc/self/status is the peak of the
    current address space only, so it is used where it exists.
    """
    try:
        for line in pathlib.Path("/proc/self/status").read_text().splitlines():
            if line.startswith("VmHWM:"):
                return int(line.split()[1])
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # KiB on Linux


def measure_peak_rss(path: str) -> dict:
    completed = subprocess.run(
        [sys.executable, str(pathlib.Path(__file__).resolve()), "--memory-probe", path],
        capture_output=True, text=True, env=os.environ.copy(),
    )
    if completed.returncode != 0:
        raise BenchError(f"memory probe on {path} failed:\n{completed.stderr.strip()}")
    return json.loads(completed.stdout.strip().splitlines()[-1])


# ------------------------------------------------------------------------ reference codecs
def cseg_input(labels: np.ndarray) -> np.ndarray:
    """compressed_segmentation takes uint32 or uint64: uint32 when every value fits, else the
    64-bit pattern (negative values keep their two's complement bits)."""
    lo, hi = int(labels.min()), int(labels.max())
    if lo >= 0 and hi <= np.iinfo(np.uint32).max:
        return labels.astype(np.uint32, copy=False)
    return labels.astype(np.int64, copy=False).view(np.uint64) if lo < 0 else labels.astype(np.uint64, copy=False)


def measure_cseg(name: str, labels: np.ndarray) -> dict:
    import compressed_segmentation as cseg

    data = cseg_input(labels)
    # Neuroglancer's format is x fastest: hand it the (x, y, z) view of our (z, y, x) array,
    # which is Fortran-ordered, with order='F'.
    xyz = data.T
    start = time.perf_counter()
    encoded = cseg.compress(xyz, block_size=(8, 8, 8), order="F")
    seconds = time.perf_counter() - start
    decoded = cseg.decompress(encoded, xyz.shape, data.dtype, block_size=(8, 8, 8), order="F")
    if not np.array_equal(np.asarray(decoded).reshape(xyz.shape), xyz):
        raise BenchError(f"{name}: compressed_segmentation round trip is not lossless")
    return {"cseg_dtype": str(data.dtype), "cseg_bytes": len(encoded), "cseg_s": seconds}


# compressed_segmentation's format holds one encoding's tables in 24-bit offsets: past 512^3 EM-like
# voxels it overflows, so larger volumes are encoded in chunks of this edge (as Neuroglancer
# stores them: in chunks, most often far smaller ones, which cost cseg more).
CSEG_CHUNK = 512


def measure_cseg_chunked(name: str, labels: np.ndarray, chunk: int = CSEG_CHUNK) -> dict:
    """measure_cseg over chunk^3 pieces of `labels`: their bytes and seconds summed."""
    total = {"cseg_bytes": 0, "cseg_s": 0.0}
    nz, ny, nx = labels.shape
    for z in range(0, nz, chunk):
        for y in range(0, ny, chunk):
            for x in range(0, nx, chunk):
                piece = np.ascontiguousarray(labels[z:z + chunk, y:y + chunk, x:x + chunk])
                row = measure_cseg(f"{name} chunk ({x}, {y}, {z})", piece)
                total["cseg_bytes"] += row["cseg_bytes"]
                total["cseg_s"] += row["cseg_s"]
                total["cseg_dtype"] = row["cseg_dtype"]
    return total


def dense_indices(labels: np.ndarray):
    """The distinct values and, per voxel, the index of its value among them, in the narrowest
    unsigned type that holds the count (1, 2, 4 or 8 bytes)."""
    values, inverse = np.unique(labels, return_inverse=True)
    width = min_width_bytes(len(values))
    return values, inverse.astype(np.dtype(f"uint{8 * width}")).reshape(labels.shape)


def measure_stream_codecs(name: str, labels: np.ndarray) -> dict:
    """zstd -19 and gzip -9 of the dense label indices (x fastest), as anchors.md measured them
    (its figures are reproduced that way, not with the original values); the small table of
    distinct values is left out of the byte counts."""
    import zstandard

    values, indices = dense_indices(labels)
    if not np.array_equal(values[indices], labels):
        raise BenchError(f"{name}: relabelling to dense indices is not lossless")
    raw = indices.tobytes(order="C")
    start = time.perf_counter()
    z = zstandard.ZstdCompressor(level=19).compress(raw)
    zstd_s = time.perf_counter() - start
    start = time.perf_counter()
    g = gzip.compress(raw, compresslevel=9, mtime=0)
    gzip_s = time.perf_counter() - start
    if zstandard.ZstdDecompressor().decompress(z) != raw or gzip.decompress(g) != raw:
        raise BenchError(f"{name}: zstd or gzip round trip is not lossless")
    return {"distinct_values": len(values), "stream_dtype": str(indices.dtype),
            "zstd19_bytes": len(z), "zstd19_s": zstd_s, "gzip9_bytes": len(g), "gzip9_s": gzip_s,
            **measure_crackle(name, indices)}


def measure_crackle(name: str, indices: np.ndarray) -> dict:
    """crackle (archival, no random access) of the same dense indices: it takes no signed types,
    and on these volumes its Markov model of order 3 is its smallest setting tried."""
    import crackle

    start = time.perf_counter()
    encoded = crackle.compress(indices, markov_model_order=3)
    seconds = time.perf_counter() - start
    if not np.array_equal(crackle.decompress(encoded), indices):
        raise BenchError(f"{name}: crackle round trip is not lossless")
    return {"crackle_bytes": len(encoded), "crackle_s": seconds}


# ------------------------------------------------------------------------------ one volume
def min_width_bytes(distinct_values: int) -> int:
    """Bytes per voxel of a raw array of dense label indices: 1, 2, 4 or 8."""
    for width in (1, 2, 4):
        if distinct_values <= 1 << (8 * width):
            return width
    return 8


def repeated(measure, runs: int) -> list:
    """The seconds of `runs` calls of measure() (which returns its own seconds), and where runs
    is more than one and they sum to less than MIN_MEASURED_S, of more calls until they do (at
    most MAX_RUNS)."""
    times = []
    while len(times) < runs or (runs > 1 and sum(times) < MIN_MEASURED_S and len(times) < MAX_RUNS):
        times.append(measure())
    return times


def measure_volume(name, source, labels, file_path, repeats, baseline_kb, frames=None) -> dict:
    """Measures one volume held both in memory (`labels`) and in a file (`file_path`).
    baseline_kb None skips the peak memory subprocess; `frames` (rounds, baseline tool or None)
    adds the frame times."""
    labels = np.ascontiguousarray(labels)
    image = to_image(labels)
    voxels = labels.size
    runs = repeats if voxels <= MEDIAN_MAX_VOXELS else 1
    built = []

    def build():
        svdag, seconds = build_svdag(image)
        built[:] = [svdag]
        return seconds

    times = repeated(build, runs)
    svdag = built[0]
    build_s = statistics.median(times)
    check_round_trip(name, labels, svdag)
    total = svdag.GetCompressedSize()

    # The same volume from its file, as a user compresses it: timed, round trip checked too.
    file_times = []
    for _ in range(runs):
        start = time.perf_counter()
        from_file, how = compress_file(str(file_path))
        file_times.append(time.perf_counter() - start)
    check_round_trip(f"{name} ({how})", labels, from_file)
    if from_file.GetCompressedSize() != total:
        raise BenchError(f"{name}: compressing the file ({how}) gave {from_file.GetCompressedSize()} "
                         f"bytes, the in-memory array {total}")
    del from_file

    n_labels = svdag.GetNumberOfLabels()
    labelled = sum(svdag.GetLabelVoxelCount(i) for i in range(n_labels))
    distinct = n_labels + (1 if labelled < voxels else 0)  # the background, when present
    width = min_width_bytes(distinct)
    row = {
        "volume": name, "source": source,
        "dims_xyz": "x".join(str(d) for d in labels.shape[::-1]), "dtype": str(labels.dtype),
        "voxels": voxels, "labels": n_labels,
        "blocks": svdag.GetNumberOfBlocks(), "root_nodes": svdag.GetNumberOfRootNodes(),
        "mid_nodes": svdag.GetNumberOfMidNodes(), "leaf_nodes": svdag.GetNumberOfLeaves(),
        "bytes_blocks": svdag.GetBlocksMemorySize(), "bytes_dag": svdag.GetDAGMemorySize(),
        "bytes_labels": svdag.GetLabelTableMemorySize(), "bytes_total": total,
        "pct_raw32": 100.0 * total / (4 * voxels), "min_width_bytes": width,
        "pct_raw_min": 100.0 * total / (width * voxels), "bits_per_voxel": 8.0 * total / voxels,
        "build_s": build_s, "build_runs": len(times), "voxels_per_s": voxels / build_s,
        "file_s": statistics.median(file_times), "file_via": how, "roundtrip": "ok",
    }
    if baseline_kb is not None:
        probe = measure_peak_rss(str(file_path))
        if probe["bytes_total"] != total:
            raise BenchError(f"{name}: the memory subprocess got {probe['bytes_total']} bytes, "
                             f"the in-memory array {total}")
        slab = labels.shape[2] * labels.shape[1] * min(SLAB_DEPTH, labels.shape[0]) * labels.itemsize
        row.update({
            "peak_rss_mb": probe["maxrss_kb"] * 1024 / MB,
            "baseline_rss_mb": baseline_kb * 1024 / MB,
            "peak_extra_mb": (probe["maxrss_kb"] - baseline_kb) * 1024 / MB,
            "model_mb": (slab + 1.5 * total) / MB,
        })
    row.update(measure_cseg(name, labels))
    row["ours_over_cseg"] = total / row["cseg_bytes"]
    row.update(measure_stream_codecs(name, labels))
    if row.pop("distinct_values") != distinct:
        raise BenchError(f"{name}: the label table and background account for {distinct} distinct "
                         "values, numpy finds another number")
    row["ours_over_zstd19"] = total / row["zstd19_bytes"]
    row["ours_over_crackle"] = total / row["crackle_bytes"]
    for version in (2, 3, 4):
        row.update(measure_svdag_file(name, svdag, labels, runs, version))
        row[f"load{version}_over_build"] = row[f"load{version}_s"] / build_s
    row["read4_over_build"] = row["read4_s"] / build_s
    for other in ("cseg", "crackle", "zstd19"):
        row[f"file3_over_{other}"] = row["file3_bytes"] / row[f"{other}_bytes"]
    row["file4_over_cseg"] = row["file4_bytes"] / row["cseg_bytes"]
    if frames is not None:
        row.update(measure_frames(name, svdag, frames[1], frames[0]))
    # Builds from before encoding_statistics (a baseline build on PYTHONPATH) have no levels.
    if hasattr(SegmentationVolume, "encoding_statistics"):
        row["levels"] = SegmentationVolume(svdag).encoding_statistics()
    return row


def measure_svdag_file(name, svdag, labels, runs, version) -> dict:
    """Bytes of the .svdag file in a format version (2: zstd level 3, its default) and the
    seconds to load it: `load` is vtkSegmentationVolumeReader's Update, the VTK algorithm that
    makes the data object from the file, as build_s times the one that makes it from the array;
    for the default version 4 also `read`, vtksvdag.read (the same plus Python's checks and
    wrapper, what a pyvista script waits for). Medians of repeated(load, runs). For versions 3 and 4
    also the seconds to write the file (which decodes what it wrote once more to check it)."""
    import vtksvdag

    with tempfile.TemporaryDirectory(prefix="svdag-bench-file-") as folder:
        path = pathlib.Path(folder) / f"{name}.svdag"
        start = time.perf_counter()
        SegmentationVolume(svdag).save(str(path), format_version=version)
        written = time.perf_counter() - start
        if path.read_bytes()[8] != version:
            raise BenchError(f"{name}: the file written is not format version {version}")
        read_times, readers = [], []

        def load():
            reader = vtkSegmentationVolumeReader()
            reader.SetFileName(str(path))
            start = time.perf_counter()
            reader.Update()
            seconds = time.perf_counter() - start
            if reader.GetErrorCode() != 0 or reader.GetFileFormat() != "SVDAG":
                raise BenchError(f"{name}: vtkSegmentationVolumeReader failed on the {version}.0 file")
            readers[:] = [reader]
            if version == 4:
                start = time.perf_counter()
                vtksvdag.read(str(path))
                read_times.append(time.perf_counter() - start)
            return seconds

        load_times = repeated(load, runs)
        loaded = readers[0].GetOutput()
        check_round_trip(f"{name} (.svdag {version}.0 file)", labels, loaded)
        if loaded.GetCompressedSize() != svdag.GetCompressedSize():
            raise BenchError(f"{name}: the .svdag {version}.0 file loads to another byte count")
        row = {f"file{version}_bytes": path.stat().st_size,
               f"load{version}_s": statistics.median(load_times)}
        if read_times:
            row[f"read{version}_s"] = statistics.median(read_times)
        if version >= 3:
            row[f"write{version}_s"] = written
        return row


# ------------------------------------------------------------------------- frame times
RENDER_TOOL = REPO / "build" / "bin" / "vtksvdag-render"
# What issue 23's frame time target is measured with: restarting frames of the primary hit and
# one bounce at voxel LOD, no denoiser, 256x256 (vtksvdag-render prints the median frame).
FRAME_OPTIONS = ["--width", "256", "--height", "256", "--lod", "voxel", "--bounces", "1",
                 "--frames", "12", "--restart", "--no-denoise"]
BACKENDS = ("compute", "rt")


def frame_ms(tool, path, backend: str) -> float:
    with tempfile.TemporaryDirectory(prefix="svdag-bench-frame-") as folder:
        done = subprocess.run(
            [str(tool), str(path), str(pathlib.Path(folder) / "frame.png"), *FRAME_OPTIONS,
             "--backend", backend], capture_output=True, text=True, timeout=900)
    if done.returncode != 0:
        raise BenchError(f"{tool} failed on {path} ({backend}): {done.stderr.strip()[-500:]}")
    return float(json.loads(done.stdout)["ms_median"])


def measure_frames(name, svdag, baseline_tool, rounds: int) -> dict:
    """Median frame time (ms) of this build's vtksvdag-render on the volume's .svdag file, both
    backends; with `baseline_tool` (another build's vtksvdag-render, e.g. of the commit before a
    change of the encoding) the same file through it too, the two interleaved round by round."""
    tools = {"": RENDER_TOOL}
    if baseline_tool is not None:
        tools["base_"] = pathlib.Path(baseline_tool)
    times = {(prefix, backend): [] for prefix in tools for backend in BACKENDS}
    with tempfile.TemporaryDirectory(prefix="svdag-bench-frames-") as folder:
        path = pathlib.Path(folder) / f"{name}.svdag"
        SegmentationVolume(svdag).save(str(path))
        for _ in range(rounds):
            for backend in BACKENDS:
                for prefix, tool in tools.items():
                    times[(prefix, backend)].append(frame_ms(tool, path, backend))
    row = {f"{prefix}frame_{backend}_ms": statistics.median(t) for (prefix, backend), t in times.items()}
    if baseline_tool is not None:
        for backend in BACKENDS:
            row[f"frame_{backend}_over_base"] = (row[f"frame_{backend}_ms"]
                                                 / row[f"base_frame_{backend}_ms"])
    return row


def print_frames(rows):
    table = [[r["volume"]] + [r.get(k) for k in (
        "frame_compute_ms", "base_frame_compute_ms", "frame_compute_over_base",
        "frame_rt_ms", "base_frame_rt_ms", "frame_rt_over_base")] for r in rows]
    print_table(
        "Frame times (vtksvdag-render " + " ".join(FRAME_OPTIONS) + "; ms, medians of the "
        "rounds; base = --baseline-render, interleaved; issue 23: at most 1.1x)",
        ["volume", "compute ms", "base ms", "compute/base", "rt ms", "base ms", "rt/base"],
        table,
    )


# ------------------------------------------------------------------ where the bytes go
LEVEL_COLUMNS = [
    "volume", "level", "nodes", "bytes", "header_bits", "reference_bits", "references",
    "reference_width", "incoming_references", "referenced_once", "max_incoming",
    "top1_percent_share", "top10_percent_share", "reference_entropy_bits",
    "mirror_classes", "mirror_bytes", "symmetry_classes", "symmetry_bytes", "compact_bytes",
]
LEAF_SYMMETRY_BITS = 6  # bits naming one of the 48 symmetries in a leaf reference (Layout.h)


def remedy_bytes(levels) -> dict:
    """Bytes of blocks + DAG under each remedy, estimated from the per-level counts of the
    pooled form ("pooled": every node once in its pool, a reference per mixed child, as files
    store it), beside the compact form built and held in memory ("compact", measured).

    "mirror" and "symmetry" share nodes equal up to a mirror (a cube symmetry) on every level
    (leaves already are, up to the 48 symmetries); "entropy refs" keeps the nodes but spends on each reference the entropy of
    its level's target distribution (a bound for a static code: no random access, a file form);
    "inline leaves" stores each leaf referenced once inside its mid node instead of a reference
    (the unused mixed-and-full child state would mark it), so the leaf pool keeps only shared
    leaves and the references into it narrow (the compact form does that and chains the mids
    referenced once after their root). Leaf references carry their 6 symmetry bits throughout.
    """
    pooled = int(levels["bytes"].sum())
    mids, leaves = levels.loc["mids"], levels.loc["leaves"]
    # References into the next level at that level's entropy (the leaves' symmetry field kept).
    entropy_bits = sum(
        levels.loc[parent, "header_bits"] + levels.loc[parent, "references"]
        * levels.loc[child, "reference_entropy_bits"]
        for parent, child in (("blocks", "roots"), ("roots", "mids"), ("mids", "leaves"))
    ) + leaves["header_bits"] + mids["references"] * LEAF_SYMMETRY_BITS
    width = lambda units: max(int(units) - 1, 0).bit_length() + 1  # noqa: E731
    once = int(leaves["referenced_once"])
    shared_leaves = int(leaves["nodes"]) - once
    leaf_ref = width(shared_leaves) + LEAF_SYMMETRY_BITS
    mid_bits = mids["header_bits"] + (mids["references"] - once) * leaf_ref + once * 64
    root_bits = levels.loc["roots", "header_bits"] + levels.loc["roots", "references"] * width(mid_bits)
    block_bits = levels.loc["blocks", "header_bits"] + levels.loc["blocks", "references"] * width(root_bits)
    inline_bits = block_bits + root_bits + mid_bits + 64 * shared_leaves
    return {
        "pooled": pooled,
        "compact": int(levels["compact_bytes"].sum()),
        "mirror": int(levels["mirror_bytes"].sum()),
        "symmetry": int(levels["symmetry_bytes"].sum()),
        "entropy refs": int(np.ceil(entropy_bits / 8)),
        "inline leaves": int(np.ceil(inline_bits / 8)),
    }


def print_files(rows, anchors):
    table = []
    for r in rows:
        csgv = anchor_value(anchors.get(r["volume"], {}), "CSGV file MB")
        table.append([r["volume"], r["file4_bytes"] / MB, r["file3_bytes"] / MB,
                      r["file2_bytes"] / MB, csgv,
                      r["file4_bytes"] / MB / csgv if csgv else None,
                      r["file3_bytes"] / MB / csgv if csgv else None,
                      r["file3_over_crackle"], r["file3_over_zstd19"], r["file3_over_cseg"],
                      r["build_s"], r["write4_s"], r["write3_s"], r["load4_over_build"],
                      r["read4_over_build"], r["load3_over_build"], r["load2_over_build"]])
    print_table(
        "The .svdag file, format 4.0 (DAG streams, the default), 3.0 (coded) and 2.0 (zstd level "
        "3), measured; CSGV file MB reported in anchors.md, not measured here; crackle, zstd -19 "
        "and cseg measured in this run; load = vtkSegmentationVolumeReader.Update() on the file "
        "(build = the filter's Update() on the array), read = vtksvdag.read, medians of at least `runs` "
        f"(short ones repeated for {MIN_MEASURED_S} s)",
        ["volume", "4.0 MB", "3.0 MB", "2.0 MB", "CSGV file MB", "4.0/CSGV", "3.0/CSGV",
         "3.0/crackle", "3.0/zstd19", "3.0/cseg", "build s", "write 4.0 s", "write 3.0 s",
         "load 4.0/build", "read 4.0/build", "load 3.0/build", "load 2.0/build"],
        table,
    )


def print_levels(rows):
    table = []
    for r in rows:
        levels = r["levels"]
        total = levels["bytes"].sum()
        for level, x in levels.iterrows():
            table.append([
                r["volume"], level, int(x["nodes"]), int(x["bytes"]),
                100.0 * x["bytes"] / total if total else 0.0, int(x["compact_bytes"]),
                int(x["reference_width"]), int(x["references"]),
                100.0 * x["referenced_once"] / x["nodes"] if level != "blocks" and x["nodes"] else None,
                x["top10_percent_share"] if level != "blocks" else None,
                x["reference_entropy_bits"] if level != "blocks" else None,
                100.0 * x["mirror_classes"] / x["nodes"] if x["nodes"] else None,
                100.0 * x["symmetry_classes"] / x["nodes"] if x["nodes"] else None,
            ])
    print_table(
        "Where the bytes go (measured: SegmentationVolume.encoding_statistics; nodes, bytes and "
        "the rest: the pooled form; compact: the level's bytes in memory; once% = nodes "
        "referenced once, top10 = share of the references into the level that its most used 10% "
        "of nodes receive, H = entropy bits per reference into the level, mirror%/sym% = distinct "
        "nodes up to the 8 mirrors / 48 cube symmetries, in % of the pooled nodes)",
        ["volume", "level", "nodes", "bytes", "% of DAG+blocks", "compact", "ref bits", "refs", "once%",
         "top10", "H bits", "mirror%", "sym%"],
        table,
    )
    remedies = []
    for r in rows:
        est = remedy_bytes(r["levels"])
        other = r["bytes_labels"]  # the label table, unchanged by every remedy
        remedies.append([r["volume"]] + [(v + other) / r["cseg_bytes"] for v in est.values()])
    print_table(
        "Remedies, estimated from the counts above (total bytes / compressed_segmentation's; "
        "target 0.5)",
        ["volume"] + [f"{name}/cseg" for name in remedy_bytes(rows[0]["levels"])],
        remedies,
    )


def write_levels_csv(rows, path: pathlib.Path):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=LEVEL_COLUMNS)
        writer.writeheader()
        for r in rows:
            for level, x in r["levels"].iterrows():
                values = {"volume": r["volume"], "level": level}
                values.update({k: x[k] for k in LEVEL_COLUMNS[2:]})
                writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v)
                                 for k, v in values.items()})


# ------------------------------------------------------------------------------- anchors
def read_anchors(path: pathlib.Path) -> dict:
    """The first markdown table of anchors.md whose header starts with "volume", by volume."""
    if not path.is_file():
        return {}
    rows, header = {}, None
    for line in path.read_text().splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if header is None:
            if line.startswith("|") and cells[0] == "volume" and "paper SVDAG MB" in cells:
                header = cells
            continue
        if not line.startswith("|"):
            break
        if set("".join(cells)) <= set("-: "):
            continue  # the separator row
        rows[cells[0]] = dict(zip(header, cells))
    return rows


def anchor_value(anchor: dict, key: str):
    try:
        return float(anchor[key])
    except (KeyError, ValueError):
        return None


# ------------------------------------------------------------------------------ printing
def fmt(value, digits=3) -> str:
    if value is None or value == "":
        return "-"
    if isinstance(value, float):
        if value != 0 and (abs(value) >= 1e5 or abs(value) < 10 ** -digits):
            return f"{value:.{digits}g}"
        return f"{value:.{digits}f}"
    return str(value)


def print_table(title, headers, rows):
    text = [[fmt(v) for v in row] for row in rows]
    widths = [max(len(h), *(len(r[i]) for r in text)) if text else len(h) for i, h in enumerate(headers)]
    print(f"\n{title}")
    print("  ".join(h.rjust(w) for h, w in zip(headers, widths)))
    print("  ".join("-" * w for w in widths))
    for r in text:
        print("  ".join(c.rjust(w) for c, w in zip(r, widths)))


def print_report(rows, anchors):
    mb = lambda b: None if b in (None, "") else b / MB  # noqa: E731
    print_table(
        "Structure (measured)",
        ["volume", "dims x*y*z", "dtype", "voxels", "labels", "blocks", "roots", "mids", "leaves"],
        [[r["volume"], r["dims_xyz"], r["dtype"], r["voxels"], r["labels"], r["blocks"],
          r["root_nodes"], r["mid_nodes"], r["leaf_nodes"]] for r in rows],
    )
    print_table(
        "Bytes (measured; MB = 10^6 bytes; zstd/gzip/crackle of the dense label indices in "
        "stream_dtype)",
        ["volume", "blocks MB", "DAG MB", "labels MB", "total MB", "%raw32", "%rawmin(B)",
         "bits/vox", "cseg MB", "zstd19 MB", "gzip9 MB", "crackle MB", "stream", "ours/cseg",
         "ours/zstd", "ours/crackle"],
        [[r["volume"], mb(r["bytes_blocks"]), mb(r["bytes_dag"]), mb(r["bytes_labels"]),
          mb(r["bytes_total"]), r["pct_raw32"], f"{r['pct_raw_min']:.2f}({r['min_width_bytes']})",
          r["bits_per_voxel"], mb(r["cseg_bytes"]), mb(r["zstd19_bytes"]), mb(r["gzip9_bytes"]),
          mb(r["crackle_bytes"]), r["stream_dtype"], r["ours_over_cseg"], r["ours_over_zstd19"],
          r["ours_over_crackle"]] for r in rows],
    )
    print_table(
        "Time and memory (measured; build = compress an in-memory array, medians of `runs` "
        f"(short ones repeated for {MIN_MEASURED_S} s); file = read + compress the gzip NRRD "
        "file, medians of --repeats; peak = a subprocess reading + compressing the file; model = "
        "one slab + 1.5 x output)",
        ["volume", "build s", "runs", "Mvox/s", "file s", "cseg s", "zstd19 s", "gzip9 s",
         "peak MB", "baseline MB", "peak-base MB", "model MB", "file via"],
        [[r["volume"], r["build_s"], r["build_runs"], r["voxels_per_s"] / 1e6, r["file_s"],
          r["cseg_s"], r["zstd19_s"], r["gzip9_s"], r.get("peak_rss_mb"), r.get("baseline_rss_mb"),
          r.get("peak_extra_mb"), r.get("model_mb"), r["file_via"]] for r in rows],
    )
    if not anchors:
        print(f"\n(no reported anchors: no table with a 'paper SVDAG MB' column in {ANCHORS})")
        return
    reported = [r for r in rows if r["volume"] in anchors]
    table = []
    for r in reported:
        a = anchors[r["volume"]]
        paper_mb, paper_s = anchor_value(a, "paper SVDAG MB"), anchor_value(a, "paper build s")
        csgv_mb, cseg_mb = anchor_value(a, "CSGV file MB"), anchor_value(a, "cseg MB")
        ours = r["bytes_total"] / MB
        table.append([
            r["volume"], paper_mb, paper_s, csgv_mb, anchor_value(a, "CSGV GPU MB"), cseg_mb,
            ours, ours / paper_mb if paper_mb else None, r["build_s"] / paper_s if paper_s else None,
            r["file_s"] / paper_s if paper_s else None,
            ours / csgv_mb if csgv_mb else None,
            (r["cseg_bytes"] / MB) / cseg_mb if cseg_mb else None,
        ])
    print_table(
        f"REPORTED, NOT MEASURED HERE (from {ANCHORS.relative_to(REPO.parent)}; other runs, other "
        "days) beside our measured bytes and build time",
        ["volume", "paper MB", "paper build s", "CSGV file MB", "CSGV GPU MB", "cseg MB (rep.)",
         "ours MB", "ours/paper", "build/paper", "file/paper", "ours/CSGV file", "cseg here/rep."],
        table,
    )


def write_plot(rows, path: pathlib.Path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    names = [r["volume"] for r in rows]
    series = [("ours (SVDAG)", "bytes_total"), ("compressed_segmentation", "cseg_bytes"),
              ("zstd -19 (dense indices)", "zstd19_bytes")]
    x = np.arange(len(rows))
    width = 0.8 / len(series)
    fig, ax = plt.subplots(figsize=(max(6.0, 1.1 * len(rows) + 2), 4.5))
    for i, (label, key) in enumerate(series):
        ax.bar(x + (i - (len(series) - 1) / 2) * width, [r[key] for r in rows], width, label=label)
    ax.set_yscale("log")
    ax.set_ylabel("bytes (log scale)")
    ax.set_xticks(x)
    ax.set_xticklabels(names, rotation=30, ha="right")
    ax.set_title("Compressed size per volume, measured in one run")
    ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


# ---------------------------------------------------------------------------------- main
def measure_large(name: str, make) -> dict:
    """In-memory bytes of a generated volume against compressed_segmentation (in CSEG_CHUNK^3
    chunks), both round trips checked."""
    start = time.perf_counter()
    labels = make()
    generate_s = time.perf_counter() - start
    svdag, build_s = build_svdag(to_image(labels))
    check_round_trip(name, labels, svdag)
    total = svdag.GetCompressedSize()
    row = {
        "volume": name, "dims_xyz": "x".join(str(d) for d in labels.shape[::-1]),
        "voxels": labels.size, "labels": svdag.GetNumberOfLabels(),
        "blocks": svdag.GetNumberOfBlocks(), "root_nodes": svdag.GetNumberOfRootNodes(),
        "mid_nodes": svdag.GetNumberOfMidNodes(), "leaf_nodes": svdag.GetNumberOfLeaves(),
        "bytes_blocks": svdag.GetBlocksMemorySize(), "bytes_dag": svdag.GetDAGMemorySize(),
        "bytes_labels": svdag.GetLabelTableMemorySize(), "bytes_total": total,
        "bits_per_voxel": 8.0 * total / labels.size, "generate_s": generate_s, "build_s": build_s,
    }
    del svdag
    row.update(measure_cseg_chunked(name, labels))
    row["ours_over_cseg"] = total / row["cseg_bytes"]
    return row


def run_large(args) -> int:
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    print(f"machine: {machine_description()}")
    rows = []
    for name, make in (QUICK_LARGE_VOLUMES if args.quick else LARGE_VOLUMES).items():
        rows.append(measure_large(name, make))
        print(f"  {name}: {rows[-1]['bytes_total'] / MB:.3f} MB, round trips ok", flush=True)
    print_table(f"Larger EM-like volumes in memory (MB), against compressed_segmentation in "
                f"{CSEG_CHUNK}^3 chunks",
                ["volume", "dims", "labels", "blocks", "ours", "cseg", "ours/cseg", "bits/voxel",
                 "generate s", "build s"],
                [[r["volume"], r["dims_xyz"], r["labels"], r["blocks"], r["bytes_total"] / MB,
                  r["cseg_bytes"] / MB, r["ours_over_cseg"], r["bits_per_voxel"], r["generate_s"],
                  r["build_s"]] for r in rows])
    csv_path = out / "compression_large.csv"
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=LARGE_COLUMNS, extrasaction="ignore")
        writer.writeheader()
        for r in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    print(f"\nwrote {csv_path}")
    return 0


def run(args) -> int:
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    real = QUICK_REAL_VOLUMES if args.quick else REAL_VOLUMES
    generated = QUICK_GENERATED_VOLUMES if args.quick else GENERATED_VOLUMES
    print(f"machine: {machine_description()}")
    print(f"mode: {'quick' if args.quick else 'full'}; data: {DATA}")
    print("from a file: " + ("vtkSegmentationVolumeReader" if reader_class() else
          "pynrrd + vtkImageDataToSegmentationSVDAG (vtkSegmentationVolumeReader not available)"))

    baseline_kb = None if args.no_memory else measure_peak_rss("-")["maxrss_kb"]
    rows = []
    with tempfile.TemporaryDirectory(prefix="svdag-bench-") as tmp:
        volumes = [(name, "file", DATA / f"{name}.nrrd", None) for name in real]
        volumes += [(name, "generated", pathlib.Path(tmp) / f"{name}.nrrd", make)
                    for name, make in generated.items()]
        for name, source, path, make in volumes:
            if make is None:
                if not path.is_file():
                    raise BenchError(f"missing volume {path}")
                labels, _ = nrrd.read(str(path), index_order="C")
            else:
                labels = make()
                # Written to a file so that it is read and measured like the real volumes.
                nrrd.write(str(path), labels, index_order="C", compression_level=1)
            frames = (args.frame_rounds, args.baseline_render) if args.frames else None
            rows.append(measure_volume(name, source, labels, path, args.repeats, baseline_kb, frames))
            print(f"  {name}: {rows[-1]['bytes_total'] / MB:.3f} MB, round trips ok", flush=True)

    anchors = read_anchors(ANCHORS)
    print_report(rows, anchors)
    print_files(rows, anchors)
    levels_path = out / "compression_levels.csv"
    with_levels = all("levels" in r for r in rows)
    if with_levels:
        print_levels(rows)
        write_levels_csv(rows, levels_path)
    if args.frames:
        print_frames(rows)
    csv_path, png_path = out / "compression.csv", out / "compression.png"
    with open(csv_path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS, restval="", extrasaction="ignore")
        writer.writeheader()
        for r in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})
    write_plot(rows, png_path)
    written = [csv_path] + ([levels_path] if with_levels else []) + [png_path]
    print("\nwrote " + ", ".join(str(p) for p in written))
    return 0


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="small volumes only (a few seconds)")
    parser.add_argument("--out", default=str(REPO / "bench" / "out"), help="folder for the CSV and plot")
    parser.add_argument("--repeats", type=int, default=3, help="builds and loads per volume up to 256^3 voxels, at least (median; short ones "
                        "repeat until they span 0.2 s)")
    parser.add_argument("--no-memory", action="store_true", help="skip the peak memory subprocesses")
    parser.add_argument("--frames", action="store_true",
                        help="also time frames of each volume with build/bin/vtksvdag-render "
                             "(both backends; needs Vulkan)")
    parser.add_argument("--baseline-render", metavar="TOOL",
                        help="with --frames: another build's vtksvdag-render, timed on the same "
                             "files, interleaved (the encoding before a change)")
    parser.add_argument("--frame-rounds", type=int, default=3, help="with --frames: rounds (median)")
    parser.add_argument("--large", action="store_true",
                        help="instead: EM-like volumes larger than 512^3 in memory against "
                             "compressed_segmentation (1024^3: about 10 minutes, 10 GB)")
    parser.add_argument("--memory-probe", metavar="PATH", help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.memory_probe is not None:
        memory_probe(args.memory_probe)
        return 0
    if args.repeats < 1:
        parser.error("--repeats must be at least 1")
    if args.frame_rounds < 1:
        parser.error("--frame-rounds must be at least 1")
    if args.baseline_render is not None and not args.frames:
        parser.error("--baseline-render needs --frames")
    if args.frames and not RENDER_TOOL.is_file():
        parser.error(f"--frames needs {RENDER_TOOL} (cmake --build build)")
    try:
        return run_large(args) if args.large else run(args)
    except BenchError as error:
        print(f"\nBENCHMARK FAILED: {error}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
