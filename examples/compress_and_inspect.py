"""Compress a segmentation volume, print what the compressed form holds, and render a slice.

Run it headless (Debian's VTK 9.1 renders through X only):

    xvfb-run -a .venv/bin/python examples/compress_and_inspect.py [VOLUME] [--z Z]

VOLUME defaults to the bundled ``examples/data/cells.nrrd``; any format ``vtksvdag.read``
knows works, for example ``../shared/data/totalseg_ct.nrrd``. The picture of a decoded z-slice
(every label its own color, background transparent) goes to ``examples/out/<name>_slice.png``.
"""
import argparse
import pathlib

import numpy as np
import pyvista as pv

import vtksvdag

HERE = pathlib.Path(__file__).resolve().parent


def print_stats(volume):
    stats = volume.stats()
    width = max(map(len, stats))
    for key, value in stats.items():
        text = f"{value:.4f}" if isinstance(value, float) else str(value)
        print(f"  {key:<{width}}  {text}")
    largest = np.argsort(volume.label_voxel_counts)[::-1][:5]
    print("  largest labels (value: voxels, bounds [x0 x1 y0 y1 z0 z1]):")
    for i in largest:
        print(f"    {volume.labels[i]}: {volume.label_voxel_counts[i]}, {volume.label_bounds[i].tolist()}")


def render_slice(volume, decoded, z, png):
    """Render z-slice ``z`` of the decoded array, one flat color per label, no background."""
    labels_xy = decoded[:, :, z]
    nx, ny = labels_xy.shape
    sx, sy, _ = volume.spacing
    # one cell per voxel, so that colors are never interpolated between labels
    image = pv.ImageData(dimensions=(nx + 1, ny + 1, 1), spacing=(sx, sy, 1.0))
    stored = labels_xy != volume.background
    # shuffled label indices: neighbouring label values get distinct colors
    shuffle = np.random.default_rng(0).permutation(max(len(volume.labels), 1))
    index = np.searchsorted(volume.labels, labels_xy)
    color = np.where(stored, shuffle[np.clip(index, 0, len(shuffle) - 1)], -1)
    image.cell_data["color"] = color.ravel(order="F")
    plotter = pv.Plotter(off_screen=True, window_size=(800, 700))
    plotter.add_mesh(image.outline(), color="black")
    if stored.any():
        cells = image.threshold(value=-0.5, scalars="color")
        plotter.add_mesh(cells, scalars="color", cmap="tab20", show_scalar_bar=False)
    count = len(np.unique(labels_xy[stored]))
    plotter.add_text(f"z = {z}: {count} labels", font_size=12)
    plotter.view_xy()
    png.parent.mkdir(parents=True, exist_ok=True)
    plotter.screenshot(str(png))
    plotter.close()


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("volume", nargs="?", default=str(HERE / "data" / "cells.nrrd"))
    parser.add_argument("--z", type=int, help="slice to render (default: the middle one)")
    args = parser.parse_args()

    volume = vtksvdag.read(args.volume)
    print(volume)
    print_stats(volume)

    # lossless: the decoded array is the original, voxel for voxel
    decoded = volume.to_numpy()  # indexed [x, y, z], the original dtype
    i, j, k = (d // 2 for d in volume.dims)
    assert decoded[i, j, k] == volume.label_at(i, j, k)
    print(f"  label at the center voxel {(i, j, k)}: {volume.label_at(i, j, k)}")

    z = args.z if args.z is not None else volume.dims[2] // 2
    png = HERE / "out" / f"{pathlib.Path(args.volume).name.split('.')[0]}_slice.png"
    render_slice(volume, decoded, z, png)
    print(f"wrote {png}")


if __name__ == "__main__":
    main()
