"""What the example scripts share: their command line and how they end.

Every example runs in a window, or with ``--off-screen`` saves its result to ``--output``
(default ``build/examples/<name>``) and exits; the test suite runs them that way.
"""
import argparse
import pathlib

HERE = pathlib.Path(__file__).resolve().parent
CELLS = HERE / "data" / "cells.nrrd"  # the bundled example volume


def parse_args(doc, output_name):
    """The examples' command line: ``--off-screen`` and ``--output`` (its folder is created)."""
    parser = argparse.ArgumentParser(description=doc.splitlines()[0])
    parser.add_argument("--off-screen", action="store_true",
                        help="no window: save the result to --output")
    parser.add_argument("--output", type=pathlib.Path,
                        default=HERE.parent / "build" / "examples" / output_name)
    args = parser.parse_args()
    args.output.parent.mkdir(parents=True, exist_ok=True)
    return args


def finish(plotter, args):
    """Off screen: save a screenshot to ``args.output``; on screen: show the window."""
    if args.off_screen:
        plotter.screenshot(str(args.output))
        print(f"wrote {args.output}")
        plotter.close()
    else:
        plotter.show()
