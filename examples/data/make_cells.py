"""Regenerates examples/data/cells.nrrd, the small volume bundled for the README's first command.

Voronoi cells (150 labels, uint16) clipped to an ellipsoid, 96 x 80 x 64 voxels, anisotropic
spacing (1, 1, 1.5): dense cells inside, background outside, like a small tissue segmentation.
"""
import pathlib

import nrrd
import numpy as np

from vtksvdag import synthetic


def make_cells() -> np.ndarray:
    nz, ny, nx = 64, 80, 96
    cells = synthetic.voronoi((nz, ny, nx), n_cells=150, seed=7, dtype=np.uint16)
    z, y, x = np.mgrid[0:nz, 0:ny, 0:nx]
    inside = ((x - 47.5) / 46) ** 2 + ((y - 39.5) / 38) ** 2 + ((z - 31.5) / 30) ** 2 <= 1.0
    return np.where(inside, cells, 0).astype(np.uint16)


if __name__ == "__main__":
    out = pathlib.Path(__file__).with_name("cells.nrrd")
    header = {"encoding": "gzip", "space": "left-posterior-superior",
              "space directions": np.diag([1.0, 1.0, 1.5]), "space origin": np.zeros(3)}
    nrrd.write(str(out), make_cells(), header, index_order="C")
    print(f"wrote {out} ({out.stat().st_size} bytes)")
