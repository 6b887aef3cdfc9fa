"""Synthetic label volumes for tests and benchmarks (numpy only, seeded, deterministic).

Every generator takes ``shape = (nz, ny, nx)`` and returns a C-ordered numpy array of that shape,
so x varies fastest in memory, as in ``nrrd.read(path, index_order='C')`` and in VTK's point
order. Dense generators (:func:`voronoi`, :func:`checkerboard`, :func:`random_labels`) label every
voxel with values ``1..n``; :func:`tubes` leaves the background at 0. The same arguments always
give the same array, on any machine.

They span the range of what a segmentation codec sees: dense cells with smooth boundaries
(Voronoi, like a whole-tissue neuron segmentation), sparse thin objects (tubes, like traced
neurites), and two adversarial cases (checkerboard: a boundary at every voxel; random labels:
no spatial coherence at all).
"""
from __future__ import annotations

import numpy as np

__all__ = ["voronoi", "tubes", "checkerboard", "random_labels"]


def _shape3(shape) -> tuple[int, int, int]:
    shape = tuple(int(s) for s in shape)
    if len(shape) != 3 or min(shape) < 1:
        raise ValueError(f"shape must be three positive sizes (nz, ny, nx), got {shape}")
    return shape


def _label_dtype(max_label: int, dtype) -> np.dtype:
    dtype = np.dtype(dtype)
    if dtype.kind not in "iu":
        raise ValueError(f"label dtype must be an integer type, got {dtype}")
    if max_label > np.iinfo(dtype).max:
        raise ValueError(f"{max_label} labels do not fit in {dtype}")
    return dtype


def _positive(name: str, value) -> int:
    value = int(value)
    if value < 1:
        raise ValueError(f"{name} must be at least 1, got {value}")
    return value


# Voxels per edge of the tiles that share one candidate list in voronoi(): small enough that few
# seeds can be nearest to some voxel of a tile, large enough that the tiles are few.
_VORONOI_TILE = 8
# Distance evaluations per chunk in voronoi(), bounding its temporary memory (~8 bytes each).
_VORONOI_CHUNK = 1 << 21


def voronoi(shape, n_cells: int, seed: int = 0, dtype=np.uint32) -> np.ndarray:
    """Dense Voronoi cells: each voxel gets the label (1..n_cells) of its nearest seed point.

    Seeds are uniform random points in the volume (continuous coordinates). Distances are
    Euclidean between voxel centres (integer coordinates) and seeds; ties go to the lower label.

    The exact nearest seed is found without a KD-tree: the volume is cut into 8^3 tiles, and for
    each tile only the seeds that can be nearest to one of its voxels are tried. A seed can be
    nearest only if its distance to the tile's box is at most the smallest, over all seeds, of
    the largest distance from a seed to the box; that bound leaves a few dozen candidates per
    tile, so 256^3 voxels with 1000 cells take a few seconds.
    """
    nz, ny, nx = shape = _shape3(shape)
    n_cells = _positive("n_cells", n_cells)
    dtype = _label_dtype(n_cells, dtype)
    rng = np.random.default_rng(seed)
    # Seeds span the voxel centres' range [0, n - 1] on every axis, stored as (x, y, z).
    seeds = rng.random((n_cells, 3)) * (np.array([nx, ny, nz], dtype=np.float64) - 1.0)

    t = _VORONOI_TILE
    tiles = [(n + t - 1) // t for n in (nx, ny, nz)]
    # Tile boxes (inclusive voxel-centre bounds), one row per tile, x fastest.
    tz, ty, tx = np.meshgrid(*(np.arange(c) for c in tiles[::-1]), indexing="ij")
    lo = np.stack([tx.ravel(), ty.ravel(), tz.ravel()], axis=1) * t
    hi = np.minimum(lo + (t - 1), np.array([nx, ny, nz]) - 1)

    candidates = []
    step = max(1, _VORONOI_CHUNK // n_cells)
    for start in range(0, len(lo), step):
        blo = lo[start : start + step, None, :]
        bhi = hi[start : start + step, None, :]
        below = np.maximum(blo - seeds, 0.0)
        above = np.maximum(seeds - bhi, 0.0)
        near = np.sum((below + above) ** 2, axis=2)  # squared distance from seed to box
        far = np.sum(np.maximum(np.abs(seeds - blo), np.abs(seeds - bhi)) ** 2, axis=2)
        bound = far.min(axis=1, keepdims=True)
        # A tiny tolerance keeps seeds that tie with the bound up to rounding.
        candidates.extend(np.nonzero(row)[0] for row in near <= bound * (1 + 1e-9) + 1e-9)

    out = np.empty(shape, dtype=dtype)
    offsets = np.stack(np.meshgrid(np.arange(t), np.arange(t), np.arange(t), indexing="ij"), -1)
    offsets = offsets.reshape(-1, 3)[:, ::-1]  # (x, y, z) offsets within a tile, x fastest
    # Group tiles by candidate count so each group is one vectorised distance computation.
    counts = np.array([len(c) for c in candidates])
    for k in np.unique(counts):
        members = np.nonzero(counts == k)[0]
        step = max(1, _VORONOI_CHUNK // (len(offsets) * int(k)))
        for start in range(0, len(members), step):
            group = members[start : start + step]
            cand = np.stack([candidates[i] for i in group])  # (g, k) seed indices, ascending
            voxels = lo[group, None, :] + offsets[None, :, :]  # (g, t^3, 3)
            d = np.sum((voxels[:, :, None, :] - seeds[cand][:, None, :, :]) ** 2, axis=3)
            # argmin picks the first minimum; candidates are ascending, so ties go to lower labels.
            nearest = cand[np.arange(len(group))[:, None], np.argmin(d, axis=2)] + 1
            inside = np.all(voxels <= np.array([nx, ny, nz]) - 1, axis=2)
            v = voxels[inside]
            out[v[:, 2], v[:, 1], v[:, 0]] = nearest[inside]
    return out


def tubes(shape, n_tubes: int, radius: float, seed: int = 0, dtype=np.uint32) -> np.ndarray:
    """Sparse tube-like "neurons" (labels 1..n_tubes) on background 0.

    Each tube is a smooth random polyline: a walk that starts at a random point, takes steps of
    half a radius and turns a little at each step (its direction is a slowly drifting random
    vector), reflecting off the volume's faces, for a length of about twice the volume's largest
    edge. Voxels within `radius` of a vertex of the polyline get the tube's label; where tubes
    cross, the later one wins.
    """
    nz, ny, nx = shape = _shape3(shape)
    n_tubes = _positive("n_tubes", n_tubes)
    radius = float(radius)
    if not radius > 0:
        raise ValueError(f"radius must be positive, got {radius}")
    dtype = _label_dtype(n_tubes, dtype)
    rng = np.random.default_rng(seed)
    upper = np.array([nx, ny, nz], dtype=np.float64) - 1.0
    step = max(radius * 0.5, 0.25)
    n_steps = int(np.ceil(2.0 * max(shape) / step))

    # Integer stencil around a vertex's rounded position that covers every voxel within radius.
    reach = int(np.ceil(radius)) + 1
    r = np.arange(-reach, reach + 1)
    stencil = np.stack(np.meshgrid(r, r, r, indexing="ij"), -1).reshape(-1, 3)

    out = np.zeros(shape, dtype=dtype)
    for label in range(1, n_tubes + 1):
        pos = rng.random(3) * upper
        direction = rng.normal(size=3)
        path = np.empty((n_steps, 3))
        for i in range(n_steps):
            path[i] = pos
            direction = direction / np.linalg.norm(direction) + rng.normal(scale=0.15, size=3)
            direction /= np.linalg.norm(direction)
            pos = pos + step * direction
            # Reflect off the faces so the walk stays inside the volume.
            for axis in range(3):
                if pos[axis] < 0 or pos[axis] > upper[axis]:
                    direction[axis] = -direction[axis]
                    pos[axis] = min(max(pos[axis], 0.0), upper[axis])
        voxels = np.rint(path).astype(np.int64)[:, None, :] + stencil[None, :, :]
        dist2 = np.sum((voxels - path[:, None, :]) ** 2, axis=2)
        inside = (dist2 <= radius * radius) & np.all((voxels >= 0) & (voxels <= upper), axis=2)
        v = voxels[inside]
        out[v[:, 2], v[:, 1], v[:, 0]] = label
    return out


def checkerboard(shape, n_labels: int = 2, period: int = 1, dtype=np.uint32) -> np.ndarray:
    """A 3D checkerboard of labels 1..n_labels in cubes of `period` voxels: the worst case.

    Voxel (x, y, z) gets ``1 + (x // period + y // period + z // period) % n_labels``, so with
    period 1 every pair of face neighbours differs: a boundary at every voxel face.
    """
    shape = _shape3(shape)
    n_labels = _positive("n_labels", n_labels)
    period = _positive("period", period)
    dtype = _label_dtype(n_labels, dtype)
    z, y, x = np.ogrid[: shape[0], : shape[1], : shape[2]]
    return (1 + (x // period + y // period + z // period) % n_labels).astype(dtype)


def random_labels(shape, n_labels: int, seed: int = 0, dtype=np.uint32) -> np.ndarray:
    """Independent uniform random labels 1..n_labels at every voxel (no spatial coherence)."""
    shape = _shape3(shape)
    n_labels = _positive("n_labels", n_labels)
    dtype = _label_dtype(n_labels, dtype)
    rng = np.random.default_rng(seed)
    return rng.integers(1, n_labels + 1, size=shape, dtype=np.int64).astype(dtype)
