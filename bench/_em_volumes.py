"""Large electron-microscopy-like label volumes for the frame-time benchmarks (bench/render.py).

Real EM segmentations of neurons (the kind Volcanite's 512^3 test volume is) differ from the
shared 256^3 volumes in two ways that matter to a ray: thousands of labels, and unlabelled space
(label 0) between the cells: membranes a few voxels wide around every cell and whole regions
nobody annotated. Rays there cross many cells whose blocks they pass by before they hit.

``em_like(n)``: Voronoi cells (synthetic.voronoi, ~2,500 labels at n = 512 after the removals
below, the same cell size at every n) with their faces warped by smooth sines (curved, irregular shapes like
neurites' cross sections rather than polyhedra), a membrane of label 0 where a voxel's label
differs from a neighbour's within MEMBRANE voxels, and a quarter of the cells removed (label 0:
unannotated space between the remaining ones). Deterministic (seeded).

``mosaic(n, k)``: k^3 em_like(n) volumes side by side, each seeded apart and with labels of its
own: an EM-like volume of (k n)^3 whose every part is different (em_like itself takes minutes at
512^3 and its Voronoi step grows with voxels times cells, so larger ones are built this way).

``tiled(labels, k)``: a real volume repeated k times per axis, each copy's labels offset so that
the copies are distinct objects (k^3 times the labels, as a larger acquisition would have).

``cached_volume(name, out_dir)``: the volume as a vtksvdag SegmentationVolume, built once and
kept as ``<out_dir>/<name>.svdag`` (later runs read the file, seconds instead of minutes).
"""
from __future__ import annotations

import pathlib

import numpy as np

#: Cells of the Voronoi diagram before removal; REMOVED of them become unlabelled space.
SEEDS = 3300
REMOVED = 0.25
#: Voxels of label 0 on each side of a face between two cells.
MEMBRANE = 1
#: Warp of the sampling coordinates: (amplitude in voxels, wavelength as a fraction of n).
_WARP = ((5.0, 0.23, 0.4), (3.0, 0.13, 2.1))
SEED = 20261203


def _warp_offsets(n, a, b):
    """Integer displacement over the 2D grid of two other axes' indices (a, b broadcast)."""
    total = np.zeros(np.broadcast_shapes(a.shape, b.shape), np.float32)
    for amplitude, wavelength, phase in _WARP:
        k = np.float32(2.0 * np.pi / (wavelength * n))
        total += np.float32(amplitude) * np.sin(a * k + np.float32(phase)) * np.cos(b * k * np.float32(0.7))
    return np.rint(total).astype(np.int32)


def cells_at(n: int) -> int:
    """em_like's cells before removal at edge n: SEEDS at 512, the same cell size at other n."""
    return max(8, int(round(SEEDS * (n / 512.0) ** 3)))


def em_like(n: int = 512, seeds: int | None = None, seed: int = SEED) -> np.ndarray:
    """An n^3 EM-like label volume, uint16, indexed [z, y, x] (see the module docstring); seeds
    default to SEEDS at n = 512 and the same cell size at other n; `seed` fixes the random
    cells."""
    from vtksvdag import synthetic

    if seeds is None:
        seeds = cells_at(n)

    cells = synthetic.voronoi((n, n, n), seeds, seed=seed, dtype=np.uint16)
    # Warped sampling: every axis displaced by sines of the two others, clamped to the volume;
    # slice by slice (no n^3 index arrays).
    i = np.arange(n, dtype=np.float32)
    j = np.arange(n, dtype=np.int32)
    wz = _warp_offsets(n, i[:, None], i[None, :])  # over (y, x)
    wy = _warp_offsets(n, i[:, None] + 0.37 * n, i[None, :])  # over (z, x)
    wx = _warp_offsets(n, i[:, None] + 0.61 * n, i[None, :] + 0.19 * n)  # over (z, y)
    labels = np.empty_like(cells)
    for z0 in range(n):
        zi = np.clip(z0 + wz, 0, n - 1)
        yi = np.clip(j[:, None] + wy[z0][None, :], 0, n - 1)
        xi = np.clip(j[None, :] + wx[z0][:, None], 0, n - 1)
        labels[z0] = cells[zi, yi, xi]
    del cells
    # Membranes: label 0 wherever a neighbour within MEMBRANE voxels along an axis differs.
    boundary = np.zeros(labels.shape, bool)
    for axis in range(3):
        for shift in range(1, MEMBRANE + 1):
            lo = [slice(None)] * 3
            hi = [slice(None)] * 3
            lo[axis] = slice(0, n - shift)
            hi[axis] = slice(shift, n)
            differs = labels[tuple(lo)] != labels[tuple(hi)]
            boundary[tuple(lo)] |= differs
            boundary[tuple(hi)] |= differs
    labels[boundary] = 0
    del boundary
    # Unannotated space: a seeded quarter of the cells removed.
    rng = np.random.default_rng(seed)
    removed = rng.choice(np.arange(1, seeds + 1), size=int(REMOVED * seeds), replace=False)
    table = np.arange(seeds + 1, dtype=np.uint16)
    table[removed] = 0
    return table[labels]


def mosaic(n: int = 512, k: int = 2, workers: int = 2) -> np.ndarray:
    """k^3 em_like(n) volumes side by side ([z, y, x], uint32), part c seeded SEED + c and its
    non-zero labels offset by c times the largest label em_like(n) can give; parts are made
    `workers` at a time."""
    import concurrent.futures

    seeds = cells_at(n)
    out = np.empty((k * n,) * 3, np.uint32)
    corners = [(cz, cy, cx) for cz in range(k) for cy in range(k) for cx in range(k)]
    with concurrent.futures.ProcessPoolExecutor(max_workers=workers) as pool:
        parts = pool.map(em_like, [n] * len(corners), [seeds] * len(corners),
                         [SEED + c for c in range(len(corners))])
        for c, ((cz, cy, cx), part) in enumerate(zip(corners, parts)):
            block = part.astype(np.uint32)
            block[part != 0] += np.uint32(c * seeds)
            out[cz * n:(cz + 1) * n, cy * n:(cy + 1) * n, cx * n:(cx + 1) * n] = block
    return out


def tiled(labels: np.ndarray, k: int = 2) -> np.ndarray:
    """`labels` ([z, y, x], 0 = background) repeated k times per axis, copy c's non-zero labels
    offset by c * (max label): k^3 distinct copies, uint32."""
    labels = np.asarray(labels)
    top = int(labels.max())
    if top * k ** 3 >= 2 ** 32:
        raise ValueError(f"{k}^3 copies of labels up to {top} do not fit uint32")
    nz, ny, nx = labels.shape
    out = np.empty((k * nz, k * ny, k * nx), np.uint32)
    base = labels.astype(np.uint32)
    copy = 0
    for cz in range(k):
        for cy in range(k):
            for cx in range(k):
                block = base + np.uint32(copy * top)
                block[base == 0] = 0
                out[cz * nz:(cz + 1) * nz, cy * ny:(cy + 1) * ny, cx * nx:(cx + 1) * nx] = block
                copy += 1
    return out


def _make(name: str, shared_data: pathlib.Path) -> np.ndarray:
    if name.startswith("em_like"):
        return em_like(int(name[len("em_like"):]))
    if name.startswith("em_mosaic2x"):
        return mosaic(int(name[len("em_mosaic2x"):]), 2)
    if name.startswith("tiled2_"):
        import nrrd

        data, _ = nrrd.read(str(shared_data / f"{name[len('tiled2_'):]}.nrrd"), index_order="C")
        return tiled(data, 2)
    raise ValueError(f"unknown generated volume {name!r} "
                     "(em_like<n>, em_mosaic2x<n> or tiled2_<shared volume>)")


def cached_volume(name: str, out_dir, shared_data):
    """The generated volume `name` (em_like512, tiled2_fib_ts2_groundtruth250, ...) as a
    SegmentationVolume, built on the first call and read from ``<out_dir>/<name>.svdag`` after."""
    import vtksvdag

    path = pathlib.Path(out_dir) / f"{name}.svdag"
    if path.is_file():
        return vtksvdag.read(str(path))
    labels = _make(name, pathlib.Path(shared_data))
    volume = vtksvdag.from_numpy(labels, axis_order="zyx")
    path.parent.mkdir(parents=True, exist_ok=True)
    volume.save(str(path))
    return volume
