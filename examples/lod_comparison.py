"""Compare the levels of detail side by side: "block", "leaf" and "voxel".

The same segmentation in three linked subplots: "block" draws every non-empty block of the
SVDAG as one box, "leaf" its leaf cells, "voxel" the lossless voxels. Turning one view turns
all three:

    xvfb-run -a .venv/bin/python examples/lod_comparison.py [--off-screen] [--output PNG]

With ``--off-screen`` no window opens; the picture goes to ``--output`` (default
``build/examples/lod_comparison.png``).
"""
import pyvista as pv

import vtksvdag
from _example import CELLS, finish, parse_args

LODS = ("block", "leaf", "voxel")


def main():
    args = parse_args(__doc__, "lod_comparison.png")

    volume = vtksvdag.read(CELLS)  # compressed once, drawn three times
    plotter = pv.Plotter(shape=(1, 3), off_screen=args.off_screen, window_size=(900, 300))
    for column, lod in enumerate(LODS):
        plotter.subplot(0, column)
        vtksvdag.add_segmentation(plotter, volume, lod=lod, sun=True, spp=8)
        plotter.add_text(f'lod="{lod}"', font_size=10)
    plotter.link_views()
    plotter.camera.zoom(1.3)
    vtksvdag.refine(plotter, timeout=30)

    finish(plotter, args)


if __name__ == "__main__":
    main()
