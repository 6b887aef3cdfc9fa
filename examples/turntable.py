"""A turntable movie: orbit the camera around a segmentation and write each frame to a GIF.

Each of the 12 frames turns the camera 30 degrees about the view up axis and refines the
path-traced picture for at most about a second before ``write_frame`` stores it:

    xvfb-run -a .venv/bin/python examples/turntable.py [--off-screen] [--output GIF]

The movie goes to ``--output`` (default ``build/examples/turntable.gif``); with
``--off-screen`` no window opens.
"""
import pyvista as pv

import vtksvdag
from _example import CELLS, parse_args

FRAMES = 12


def main():
    args = parse_args(__doc__, "turntable.gif")

    plotter = pv.Plotter(off_screen=args.off_screen, window_size=(300, 240))
    vtksvdag.add_segmentation(plotter, CELLS, sun=True, spp=8)
    plotter.open_gif(str(args.output), fps=6)
    if not args.off_screen:
        plotter.show(interactive_update=True)  # open the window, keep control here
    for frame in range(FRAMES):
        stats = vtksvdag.refine(plotter, timeout=1.0)
        plotter.write_frame()
        print(f"frame {frame + 1}/{FRAMES}: {stats[0]['samples']} samples per pixel")
        plotter.camera.azimuth += 360 / FRAMES
    print(f"wrote {args.output}")
    plotter.close()


if __name__ == "__main__":
    main()
