"""Writes the format 1.0 .svdag fixtures of test_svdag_format1.py and expected.json (the SHA-256
of each source array, computed from the array, not from any codec).

It was run once with the last build that wrote format 1.0 (commit 10fb071's tree, before leaf
references carried a symmetry), from the repository root:

    PYTHONPATH=OLD/Python:OLD/build/python /usr/bin/python3 Testing/Data/format1/make_format1.py

Running it with a later build would write format 2.0 files instead; the test checks the version.
"""
import hashlib
import json
import pathlib

import numpy as np

import vtksvdag

HERE = pathlib.Path(__file__).resolve().parent


def arrays():
    rng = np.random.default_rng(20261204)
    # Cells: nearest of 14 seeds in an odd-sized box (x, y, z), uint16.
    shape = (37, 29, 35)
    seeds = rng.random((14, 3)) * shape
    grid = np.stack(np.meshgrid(*[np.arange(s) + 0.5 for s in shape], indexing="ij"), axis=-1)
    cells = np.argmin(((grid[..., None, :] - seeds) ** 2).sum(-1), axis=-1).astype(np.uint16) + 1
    cells[grid[..., 0] < 6] = 0
    # Noise: three labels and background at random (many distinct leaves), uint8.
    noise = rng.integers(0, 4, size=(21, 18, 17)).astype(np.uint8)
    # Wide signed values, int64: blocks of labels around -2^62 and 2^40.
    wide = np.zeros((33, 17, 19), dtype=np.int64)
    wide[2:20, 3:15, 1:18] = -(2**62) + 5
    wide[10:30, 0:9, 4:12] = 2**40
    wide[rng.random(wide.shape) < 0.05] = 77
    return {
        "cells_uint16": (cells, 3),
        "noise_uint8_uncompressed": (noise, 0),
        "wide_int64": (wide, 3),
        "empty_uint8": (np.zeros((5, 6, 7), dtype=np.uint8), 3),
    }


def main():
    expected = {}
    for name, (labels, level) in arrays().items():
        labels = np.ascontiguousarray(labels)
        vtksvdag.from_numpy(labels).save(str(HERE / f"{name}.svdag"), compression_level=level)
        expected[name] = {
            "shape_xyz": list(labels.shape), "dtype": str(labels.dtype),
            "sha256_xyz_c_order": hashlib.sha256(labels.tobytes()).hexdigest(),
            "labels": sorted(int(v) for v in np.unique(labels) if v != 0),
        }
    (HERE / "expected.json").write_text(json.dumps(expected, indent=1) + "\n")


if __name__ == "__main__":
    main()
