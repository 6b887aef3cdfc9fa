"""An EM connectome: pick a neuron, highlight it and show only the neurons that touch it.

Reads a FIB-SEM neuron segmentation (``fib25_64.nrrd`` of the shared test data, a 64^3 crop of
the FIB-25 fly connectome, when it is there; else a synthetic stand-in of dense Voronoi cells
made with :mod:`vtksvdag.synthetic`), picks the neuron under the window center with
:func:`vtksvdag.pick`, finds its neighbours (the labels that share a voxel face with it, from
:meth:`SegmentationVolume.label_adjacency`, computed on the compressed form), hides every other
neuron and highlights the picked one:

    xvfb-run -a .venv/bin/python examples/connectome.py [--off-screen] [--output PNG] [--data FILE]

Interactively, a left click picks another neuron and shows its neighbourhood; a click on the
background shows every neuron again. With ``--off-screen`` it picks once at the window center,
prints the picked label and its neighbours and saves a screenshot to ``--output`` (default
``build/examples/connectome.png``).
"""
import argparse
import os
import pathlib

import numpy as np
import pyvista as pv

import vtksvdag
import vtksvdag.synthetic
from _example import HERE

WINDOW = (400, 320)
SPP = 12
# The shared test volumes next to the checkout (VTKSVDAG_SHARED_DATA elsewhere), as the tests
# find them.
SHARED_DATA = pathlib.Path(os.environ.get("VTKSVDAG_SHARED_DATA") or HERE.parents[1] / "shared" / "data")
EM_VOLUME = SHARED_DATA / "fib25_64.nrrd"
DIM = 0.3  # the neighbours' brightness beside the highlighted neuron
# Looking at the middle of a face of the block: the window center then hits a neuron well
# inside it, rather than the fragment at a corner that pyvista's isometric view shows there.
VIEW = (0.35, -1.0, 0.45)


def load_volume(path=None):
    """The EM segmentation and where it came from: ``path``, else the shared FIB-25 crop, else
    synthetic Voronoi cells (64^3, 60 cells, seeded: the same volume on every run)."""
    path = path or (EM_VOLUME if EM_VOLUME.is_file() else None)
    if path is not None:
        return vtksvdag.read(path), str(path)
    cells = vtksvdag.synthetic.voronoi((64, 64, 64), 60, seed=7)  # (z, y, x)
    return vtksvdag.from_numpy(cells, axis_order="zyx"), "synthetic voronoi((64, 64, 64), 60, seed=7)"


def neighbours_of(pairs, label):
    """The labels paired with ``label`` in ``label_adjacency()``'s pairs, sorted."""
    touching = np.concatenate([pairs[pairs[:, 0] == label, 1], pairs[pairs[:, 1] == label, 0]])
    return sorted(touching.tolist())


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--off-screen", action="store_true",
                        help="no window: save the result to --output")
    parser.add_argument("--output", type=pathlib.Path,
                        default=HERE.parent / "build" / "examples" / "connectome.png")
    parser.add_argument("--data", type=pathlib.Path, help="a label volume (default: FIB-25 crop)")
    args = parser.parse_args()
    args.output.parent.mkdir(parents=True, exist_ok=True)

    volume, source = load_volume(args.data)
    print(f"volume: {source}")
    print(volume)
    # Every touching pair at once: one pass over the compressed form, reused for every pick.
    pairs = volume.label_adjacency()

    plotter = pv.Plotter(off_screen=args.off_screen, window_size=WINDOW)
    actor = vtksvdag.add_segmentation(plotter, volume, spp=SPP)
    plotter.view_vector(VIEW, viewup=(0, 0, 1))
    all_labels = volume.labels.tolist()

    def show_neighbourhood(label):
        """Show ``label`` and its neighbours only, the picked one highlighted; None: all."""
        if label is None:
            actor.show(all_labels)
            actor.set_highlight(None)
            return []
        neighbours = neighbours_of(pairs, label)
        keep = set(neighbours) | {label}
        actor.show(sorted(keep))
        actor.hide([v for v in all_labels if v not in keep])
        # A material change only: the neuron lit by an emissive tint, the neighbours dimmed. The
        # picked neuron stays in sight: the pick's ray reached it from the camera.
        actor.set_highlight([label], dim=DIM)
        return neighbours

    def pick_at(x, y):
        hit = vtksvdag.pick(plotter, x, y)
        label = None if hit is None else hit["label"]
        neighbours = show_neighbourhood(label)
        if label is None:
            print("background: every neuron shown")
        else:
            print(f"picked label {label} at ({', '.join(f'{c:.1f}' for c in hit['position'])})")
            print(f"neighbours ({len(neighbours)}): {' '.join(map(str, neighbours))}")
        plotter.render()

    if args.off_screen:
        # A pick reads the last frame: render one (refine also puts pyvista's camera in place
        # first, which a bare render() of a fresh plotter does not).
        vtksvdag.refine(plotter, timeout=30)
        width, height = plotter.window_size
        pick_at(width / 2, height / 2)
        plotter.add_text(f"neuron {actor.highlighted_labels[0]} and its "
                         f"{len(actor.visible_labels) - 1} neighbours", font_size=9)
        plotter.screenshot(str(args.output))  # refines first: no refine() call needed
        print(f"wrote {args.output}")
        plotter.close()
        return
    plotter.iren.track_click_position(lambda pos: pick_at(*pos), side="left", viewport=True)
    plotter.add_text("click: a neuron and its neighbours   background: all", font_size=8)
    plotter.show()


if __name__ == "__main__":
    main()
