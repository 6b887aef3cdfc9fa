"""Generated label volumes for bench/scale.py, written chunk by chunk as Zarr v2 stores.

Every voxel's label is a function of its global (z, y, x) index and the edge N only, evaluated
with vectorised numpy on any box: a chunk, a slab or (for tests, at tiny sizes) the whole volume
give the same values where they overlap. The writer never holds more than one chunk per process.

Two kinds, with the same feature size at every N so that time per voxel is comparable:

* ``dense``: every voxel labelled. Staggered "bricks" of CELL^3 voxels (like a brick wall, each
  layer and row offset by half a cell, so that three cells meet at an edge, as in a foam), whose
  faces are warped by smooth sums of sines (amplitude up to 14 voxels, wavelengths 61-131
  voxels): z + fz(y, x), y + fy(z, x), x + fx(z, y), then integer shifts. About (N / 32)^3
  cells, each its own label (1..(N/32 + 3)^3).
* ``tubes``: background 0 and N^2 / 2048 tubes (at least 4), each its own label 1..T: random
  polylines of SEGMENT-voxel straight pieces whose direction turns a little at each joint and
  reflects at the volume's faces, total length N, radius 3-6 voxels (capsules: the voxels within
  the radius of a piece). Where tubes overlap the larger label wins (independent of evaluation
  order). About 2-3 % of the voxels are labelled at every N.

Stores: Zarr v2 arrays (a ``.zarray`` at the top), dimensions (z, y, x), x fastest, dtype
``<u4``, ``fill_value`` 0, blosc-lz4 with byte shuffle, ``/``-separated chunk keys. A JSON marker
next to the store (``<store>.done.json``) records the parameters once every chunk is written;
a store without a matching marker is generated again.
"""
from __future__ import annotations

import concurrent.futures
import json
import multiprocessing
import os
import pathlib
import shutil
import time

import numpy as np

GENERATOR_VERSION = 1
KINDS = ("dense", "tubes")
DTYPE = np.dtype("<u4")
#: Chunk shape (z, y, x) of the stores, clipped to the volume.
CHUNK = (64, 256, 256)

# -- dense cells --------------------------------------------------------------------------
CELL_SHIFT = 5
CELL = 1 << CELL_SHIFT  # 32 voxels
# Per warped axis: (amplitude, wavelength, phase) of three sines, over the two other axes. The
# amplitudes sum to 14 < CELL / 2, so a warped index moves by less than half a cell.
_WARPS = {
    # axis: [(amplitude, wavelength, phase, which of the two other axes: 0, 1 or both=2), ...]
    "z": [(6.0, 131.0, 0.3, 0), (5.0, 97.0, 1.7, 1), (3.0, 61.0, 4.1, 2)],
    "y": [(6.0, 113.0, 2.2, 0), (5.0, 89.0, 0.9, 1), (3.0, 67.0, 5.3, 2)],
    "x": [(6.0, 127.0, 3.6, 0), (5.0, 101.0, 2.8, 1), (3.0, 71.0, 0.4, 2)],
}


def _warp(axis: str, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The integer displacement of ``axis`` on the 2D grid of the two other axes' indices
    (``a`` broadcast against ``b``), rounded to the nearest voxel."""
    total = np.zeros(np.broadcast_shapes(a.shape, b.shape), np.float64)
    for amplitude, wavelength, phase, which in _WARPS[axis]:
        coordinate = a if which == 0 else b if which == 1 else (a + b) * 0.7071067811865476
        total += amplitude * np.sin(coordinate * (2.0 * np.pi / wavelength) + phase)
    return np.rint(total).astype(np.int32)


def dense_box(n: int, z0: int, z1: int, y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
    """Labels of the box [z0, z1) x [y0, y1) x [x0, x1) of the dense volume of edge n, (z, y, x)."""
    z = np.arange(z0, z1, dtype=np.int32)[:, None, None]
    y = np.arange(y0, y1, dtype=np.int32)[None, :, None]
    x = np.arange(x0, x1, dtype=np.int32)[None, None, :]
    m = n // CELL + 3  # cell indices run from -1 to n / CELL + 1: shifted by 1, m per axis
    half = CELL // 2
    # z: bricks' layers
    iw = z + _warp("z", y.astype(np.float64), x.astype(np.float64))
    np.right_shift(iw, CELL_SHIFT, out=iw)  # arithmetic shift: floor division for negatives
    # y: rows, offset by half a cell in every other layer
    iv = (iw & 1) * half
    iv += y
    iv += _warp("y", z.astype(np.float64), x.astype(np.float64))
    np.right_shift(iv, CELL_SHIFT, out=iv)
    # x: bricks along a row, offset by half a cell in every other row (of every other layer)
    iu = iv + iw
    iu &= 1
    iu *= half
    iu += x
    iu += _warp("x", z.astype(np.float64), y.astype(np.float64))
    np.right_shift(iu, CELL_SHIFT, out=iu)
    # label = 1 + (iu + 1) + m * ((iv + 1) + m * (iw + 1))
    iw += 1
    iw *= m
    iw += iv
    iw += 1
    iw *= m
    iw += iu
    iw += 2
    return iw.astype(DTYPE, copy=False)


# -- sparse tubes -------------------------------------------------------------------------
SEGMENT = 48.0  # voxels per straight piece of a tube
TUBE_SEED = 20261201


def tube_count(n: int) -> int:
    return max(4, n * n // 2048)


def tube_segments(n: int):
    """The tubes of the volume of edge n as capsules: (a, b, radius, label), a and b (S, 3)
    arrays of (z, y, x) end points, radius and label (S,). Depends on n only."""
    rng = np.random.default_rng([TUBE_SEED, n])
    count = tube_count(n)
    pieces = max(1, int(round(n / SEGMENT)))
    radius = rng.uniform(3.0, 6.0, count)
    position = rng.uniform(0.0, n - 1.0, (count, 3))
    direction = rng.normal(size=(count, 3))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    starts, ends = [], []
    upper = n - 1.0
    for _ in range(pieces):
        direction = direction + 0.45 * rng.normal(size=(count, 3))
        direction /= np.linalg.norm(direction, axis=1, keepdims=True)
        end = position + SEGMENT * direction
        # Reflect at the faces (the piece is then cut short there: it ends on the face).
        low, high = end < 0.0, end > upper
        direction = np.where(low | high, -direction, direction)
        end = np.clip(end, 0.0, upper)
        starts.append(position)
        ends.append(end)
        position = end
    a = np.concatenate(starts)
    b = np.concatenate(ends)
    labels = np.tile(np.arange(1, count + 1, dtype=np.uint32), pieces)
    return a, b, np.tile(radius, pieces), labels


_TUBE_CACHE: dict = {}


def _cached_segments(n: int):
    if n not in _TUBE_CACHE:
        a, b, r, labels = tube_segments(n)
        lo = np.minimum(a, b) - r[:, None]
        hi = np.maximum(a, b) + r[:, None]
        _TUBE_CACHE.clear()
        _TUBE_CACHE[n] = (a, b, r, labels, lo, hi)
    return _TUBE_CACHE[n]


def tubes_box(n: int, z0: int, z1: int, y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
    """Labels of the box [z0, z1) x [y0, y1) x [x0, x1) of the tubes volume of edge n."""
    out = np.zeros((z1 - z0, y1 - y0, x1 - x0), DTYPE)
    a, b, r, labels, lo, hi = _cached_segments(n)
    box_lo = np.array([z0, y0, x0], np.float64)
    box_hi = np.array([z1 - 1, y1 - 1, x1 - 1], np.float64)
    hits = np.flatnonzero(np.all((lo <= box_hi) & (hi >= box_lo), axis=1))
    for s in hits:
        # The piece's bounding box (integer voxel range) inside this box.
        s_lo = np.maximum(np.ceil(lo[s]), box_lo).astype(np.int64)
        s_hi = np.minimum(np.floor(hi[s]), box_hi).astype(np.int64)
        if np.any(s_hi < s_lo):
            continue
        pz = np.arange(s_lo[0], s_hi[0] + 1, dtype=np.float64)[:, None, None] - a[s, 0]
        py = np.arange(s_lo[1], s_hi[1] + 1, dtype=np.float64)[None, :, None] - a[s, 1]
        px = np.arange(s_lo[2], s_hi[2] + 1, dtype=np.float64)[None, None, :] - a[s, 2]
        d = b[s] - a[s]
        length2 = float(d @ d)
        t = pz * d[0] + py * d[1] + px * d[2]
        if length2 > 0.0:
            t /= length2
            np.clip(t, 0.0, 1.0, out=t)
        else:
            t[...] = 0.0
        dist2 = (pz - t * d[0]) ** 2
        dist2 += (py - t * d[1]) ** 2
        dist2 += (px - t * d[2]) ** 2
        inside = dist2 <= r[s] * r[s]
        view = out[s_lo[0] - z0:s_hi[0] + 1 - z0, s_lo[1] - y0:s_hi[1] + 1 - y0,
                   s_lo[2] - x0:s_hi[2] + 1 - x0]
        np.maximum(view, inside.astype(DTYPE) * labels[s], out=view)
    return out


def box(kind: str, n: int, z0: int, z1: int, y0: int, y1: int, x0: int, x1: int) -> np.ndarray:
    """Labels of a box of the volume ``kind`` of edge ``n``, shape (z1-z0, y1-y0, x1-x0)."""
    if kind == "dense":
        return dense_box(n, z0, z1, y0, y1, x0, x1)
    if kind == "tubes":
        return tubes_box(n, z0, z1, y0, y1, x0, x1)
    raise ValueError(f"unknown volume kind {kind!r} (one of {KINDS})")


def whole(kind: str, n: int) -> np.ndarray:
    """The whole volume in memory: for tests at tiny sizes only."""
    return box(kind, n, 0, n, 0, n, 0, n)


# -- stores -------------------------------------------------------------------------------
def store_path(work_dir, kind: str, n: int) -> pathlib.Path:
    return pathlib.Path(work_dir) / f"{kind}_{n}.zarr"


def _marker(path: pathlib.Path) -> pathlib.Path:
    return path.with_name(path.name + ".done.json")


def _params(kind, n, chunk):
    return {"kind": kind, "n": n, "chunk_zyx": [min(c, n) for c in chunk], "dtype": DTYPE.str,
            "generator_version": GENERATOR_VERSION}


def _spec(path: pathlib.Path, n: int, chunk) -> dict:
    return {
        "driver": "zarr",
        "kvstore": {"driver": "file", "path": str(path.resolve()) + "/"},
        "metadata": {
            "shape": [n, n, n],
            "chunks": [min(c, n) for c in chunk],
            "dtype": DTYPE.str,
            "fill_value": 0,
            "order": "C",
            "dimension_separator": "/",
            "compressor": {"id": "blosc", "cname": "lz4", "clevel": 5, "shuffle": 1},
        },
    }


_OPEN: dict = {}


def _write_chunks(kind: str, n: int, path: str, chunk, origins) -> int:
    """Worker: generate and write the chunks at ``origins`` [(z0, y0, x0), ...]; returns how
    many voxels it wrote. Opens the existing store once per process."""
    import tensorstore as ts

    key = (path, n, tuple(chunk))
    if key not in _OPEN:
        _OPEN.clear()
        # No cache: every chunk is written once, whole.
        _OPEN[key] = ts.open(_spec(pathlib.Path(path), n, chunk), open=True, write=True,
                             context=ts.Context({"cache_pool": {"total_bytes_limit": 0}})).result()
    store = _OPEN[key]
    voxels = 0
    cz, cy, cx = (min(c, n) for c in chunk)
    for z0, y0, x0 in origins:
        z1, y1, x1 = min(n, z0 + cz), min(n, y0 + cy), min(n, x0 + cx)
        labels = box(kind, n, z0, z1, y0, y1, x0, x1)
        store[z0:z1, y0:y1, x0:x1].write(labels).result()
        voxels += labels.size
    return voxels


def is_complete(path, kind: str, n: int, chunk=CHUNK) -> bool:
    path = pathlib.Path(path)
    marker = _marker(path)
    if not (path.is_dir() and marker.is_file()):
        return False
    try:
        return json.loads(marker.read_text()).get("params") == _params(kind, n, chunk)
    except ValueError:
        return False


def recorded_seconds(path) -> float:
    """The generation seconds a complete store's marker recorded (0 when unknown)."""
    try:
        return float(json.loads(_marker(pathlib.Path(path)).read_text()).get("seconds", 0.0))
    except (OSError, ValueError):
        return 0.0


def generate(path, kind: str, n: int, chunk=CHUNK, jobs: int = 1, force: bool = False) -> dict:
    """Write the volume ``kind`` of edge ``n`` to a new Zarr v2 store at ``path``, chunk by chunk
    (``jobs`` processes, each writing whole chunks). Reuses a complete store with the same
    parameters unless ``force``. Returns {"seconds" (of this generation, or the one the reused
    store's marker recorded), "cached", "store_bytes"}."""
    import tensorstore as ts

    path = pathlib.Path(path)
    if kind not in KINDS:
        raise ValueError(f"unknown volume kind {kind!r} (one of {KINDS})")
    if not force and is_complete(path, kind, n, chunk):
        return {"seconds": recorded_seconds(path), "cached": True, "store_bytes": tree_bytes(path)}
    marker = _marker(path)
    if marker.exists():
        marker.unlink()
    if path.exists():
        shutil.rmtree(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    start = time.perf_counter()
    ts.open(_spec(path, n, chunk), create=True, delete_existing=True).result()
    cz, cy, cx = (min(c, n) for c in chunk)
    # One task per z-row of chunks: each process writes whole chunks only.
    tasks = [[(z0, y0, x0) for y0 in range(0, n, cy) for x0 in range(0, n, cx)]
             for z0 in range(0, n, cz)]
    written = 0
    if jobs <= 1:
        for origins in tasks:
            written += _write_chunks(kind, n, str(path), chunk, origins)
    else:
        # spawn: the workers import numpy and tensorstore afresh (no forked threads).
        context = multiprocessing.get_context("spawn")
        with concurrent.futures.ProcessPoolExecutor(jobs, mp_context=context) as pool:
            futures = [pool.submit(_write_chunks, kind, n, str(path), chunk, origins)
                       for origins in tasks]
            for future in futures:
                written += future.result()
    if written != n ** 3:
        raise RuntimeError(f"{path}: wrote {written} voxels, expected {n ** 3}")
    seconds = time.perf_counter() - start
    marker.write_text(json.dumps({"params": _params(kind, n, chunk), "seconds": seconds}, indent=1))
    return {"seconds": seconds, "cached": False, "store_bytes": tree_bytes(path)}


def tree_bytes(path) -> int:
    return sum(os.path.getsize(os.path.join(root, name))
               for root, _, names in os.walk(path) for name in names)
