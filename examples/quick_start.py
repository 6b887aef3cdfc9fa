"""Quick start: path-trace the bundled cells segmentation in a pyvista plotter.

Reads ``examples/data/cells.nrrd`` (150 Voronoi cells clipped to an ellipsoid), adds it to a
``pyvista.Plotter`` lit by a sun, refines it to the target samples per pixel and shows it:

    xvfb-run -a .venv/bin/python examples/quick_start.py [--off-screen] [--output PNG]

With ``--off-screen`` no window opens; the picture goes to ``--output`` (default
``build/examples/quick_start.png``).
"""
import pyvista as pv

import vtksvdag
from _example import CELLS, finish, parse_args


def main():
    args = parse_args(__doc__, "quick_start.png")

    volume = vtksvdag.read(CELLS)
    print(volume)
    plotter = pv.Plotter(off_screen=args.off_screen, window_size=(300, 240))
    vtksvdag.add_segmentation(plotter, volume, sun=True, spp=8)
    plotter.add_axes()
    stats = vtksvdag.refine(plotter, timeout=30)
    print(f"refined to {stats[0]['samples']} samples per pixel in {stats[0]['seconds']:.2f} s")

    finish(plotter, args)


if __name__ == "__main__":
    main()
