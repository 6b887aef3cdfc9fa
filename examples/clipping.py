"""Cut a segmentation open with an interactive clipping plane and a crop box.

    xvfb-run -a .venv/bin/python examples/clipping.py [--off-screen] [--output PNG]

Drag the plane widget (its arrow is the normal: the side it points to is kept) and the cut faces
follow: labels cut by the plane show flat faces in their colors, and what the plane removes casts
no shadow. The crop box keeps the central part of the volume along x. A plane move is a uniform
update of the tracer (no acceleration-structure rebuild): the refinement restarts at once.
With ``--off-screen`` the widget is moved once by code, as a drag would, the cut label under the
image center is printed with its normal (the plane's) and a screenshot saved to ``--output``
(default ``build/examples/clipping.png``).
"""
import numpy as np
import pyvista as pv
from vtkmodules.vtkCommonDataModel import vtkPlane

import vtksvdag
from _example import CELLS, finish, parse_args


def main():
    args = parse_args(__doc__, "clipping.png")
    volume = vtksvdag.read(CELLS)
    xmin, xmax, ymin, ymax, zmin, zmax = volume.to_pyvista().bounds
    center = np.array([(xmin + xmax) / 2, (ymin + ymax) / 2, (zmin + zmax) / 2])

    plotter = pv.Plotter(off_screen=args.off_screen, window_size=(320, 260))
    # Keep the central 80% along x; the plane starts through the center, keeping +y (the far side
    # from the camera, so the cut faces the viewer).
    margin = 0.1 * (xmax - xmin)
    actor = vtksvdag.add_segmentation(
        plotter, volume, sun=True, spp=16,
        crop=(xmin + margin, xmax - margin, ymin, ymax, zmin, zmax))
    mapper = actor.GetMapper()
    plane = vtkPlane()
    plane.SetOrigin(*center)
    plane.SetNormal(0.0, 1.0, 0.0)
    mapper.AddClippingPlane(plane)

    def move_plane(normal, origin):
        # The mapper keeps this vtkPlane: editing it in place restarts the refinement.
        plane.SetNormal(*normal)
        plane.SetOrigin(*origin)

    plotter.view_vector((-0.35, -1.0, 0.5), viewup=(0, 0, 1))
    plotter.reset_camera()
    if args.off_screen:
        # What a drag of the widget does: a new normal and origin for the callback.
        normal = np.array([0.3, 1.0, 0.2])
        move_plane(normal / np.linalg.norm(normal), center + np.array([0.0, 4.0, 0.0]))
        vtksvdag.refine(plotter, timeout=30)
        width, height = plotter.window_size
        hit = vtksvdag.pick(plotter, width / 2, height / 2)
        if hit is None:
            print("background")
        else:
            print(f"label {hit['label']} at ({', '.join(f'{c:.1f}' for c in hit['position'])}) "
                  f"normal ({', '.join(f'{c:.2f}' for c in hit['normal'])})")
        finish(plotter, args)
        return
    plotter.add_plane_widget(move_plane, normal=(0.0, 1.0, 0.0), origin=center,
                             bounds=(xmin, xmax, ymin, ymax, zmin, zmax), implicit=True)
    plotter.add_text("drag the plane: the side its arrow points to is kept", font_size=8)
    finish(plotter, args)


if __name__ == "__main__":
    main()
