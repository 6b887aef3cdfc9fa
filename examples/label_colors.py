"""Color labels from a table, the rest from a categorical colormap, one label see-through.

A small CSV-like table names the color of some labels (as a label-color table of an atlas
would); every other label takes a color of matplotlib's categorical "tab20" colormap, and
label 145, the large cell in front, has opacity 0.4 so the cells behind show through it:

    xvfb-run -a .venv/bin/python examples/label_colors.py [--off-screen] [--output PNG]

With ``--off-screen`` no window opens; the picture goes to ``--output`` (default
``build/examples/label_colors.png``).
"""
import csv
import io

import pyvista as pv

import vtksvdag
from _example import CELLS, finish, parse_args


# label value, color name (any color pyvista understands)
TABLE = """\
label,color
134,red
129,gold
50,forestgreen
150,royalblue
45,darkorange
"""
SEE_THROUGH = 145


def main():
    args = parse_args(__doc__, "label_colors.png")

    colors = {int(row["label"]): row["color"] for row in csv.DictReader(io.StringIO(TABLE))}
    plotter = pv.Plotter(off_screen=args.off_screen, window_size=(300, 240))
    vtksvdag.add_segmentation(plotter, CELLS, colors=colors, cmap="tab20",
                              opacity={SEE_THROUGH: 0.4}, sun=True, spp=8)
    vtksvdag.refine(plotter, timeout=30)

    finish(plotter, args)


if __name__ == "__main__":
    main()
