"""Explore a segmentation interactively: pick and highlight labels, hide them, switch the LOD.

    xvfb-run -a .venv/bin/python examples/explorer.py [--off-screen] [--output PNG]

Left-click prints the label under the mouse and where the ray hit it, and highlights it (an
emissive tint; the other labels are dimmed): the next frame shows it, without rebuilding any
geometry. A click on the background removes the highlight. 'h' hides the label under the mouse,
'a' shows all labels again (and removes the highlight), 'l' cycles the LOD (block, leaf, voxel,
auto). With ``--off-screen`` it picks once at the image center, prints the hit, highlights that
label and saves a screenshot to ``--output`` (default ``build/examples/explorer.png``).
"""
import pyvista as pv

import vtksvdag
from _example import CELLS, finish, parse_args

LODS = ["block", "leaf", "voxel", "auto"]  # the mapper's SetLOD values 0 .. 3
DIM = 0.35  # the other labels' brightness while one is highlighted


def main():
    args = parse_args(__doc__, "explorer.png")

    plotter = pv.Plotter(off_screen=args.off_screen, window_size=(300, 240))
    actor = vtksvdag.add_segmentation(plotter, CELLS, sun=True, spp=8)
    mapper = actor.GetMapper()

    def pick_at(x, y):
        hit = vtksvdag.pick(plotter, x, y)
        print("background" if hit is None else
              f"label {hit['label']} at ({', '.join(f'{c:.1f}' for c in hit['position'])})")
        return hit

    def highlight_at(x, y):
        hit = pick_at(x, y)
        # A material upload only: the next frame restarts refining, the BVH stays.
        actor.set_highlight(None if hit is None else [hit["label"]], dim=DIM)
        if hit is not None:
            print(f"highlighted label {hit['label']}")
        plotter.render()

    def hide_picked():
        hit = pick_at(*plotter.iren.get_event_position())
        if hit is not None:
            mapper.GetLabelProperties().SetVisibility(hit["label"], False)
            plotter.render()

    def show_all():
        mapper.GetLabelProperties().ShowAllLabels()
        actor.set_highlight(None)
        plotter.render()

    def cycle_lod():
        lod = (mapper.GetSettings().GetLOD() + 1) % len(LODS)
        mapper.GetSettings().SetLOD(lod)
        print(f"LOD {LODS[lod]}")
        plotter.render()

    if args.off_screen:
        vtksvdag.refine(plotter, timeout=30)
        width, height = plotter.window_size
        highlight_at(width / 2, height / 2)
        vtksvdag.refine(plotter, timeout=30)
        finish(plotter, args)
        return
    plotter.add_key_event("h", hide_picked)
    plotter.add_key_event("a", show_all)
    plotter.add_key_event("l", cycle_lod)
    plotter.iren.track_click_position(lambda pos: highlight_at(*pos), side="left", viewport=True)
    plotter.add_text("click: pick + highlight   h: hide   a: show all   l: LOD", font_size=8)
    finish(plotter, args)


if __name__ == "__main__":
    main()
