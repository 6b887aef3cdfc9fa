"""Labels over an intensity image: a path-traced segmentation and a grey slice in one renderer.

    xvfb-run -a .venv/bin/python examples/labels_over_intensity.py [--off-screen] [--output PNG]

A synthetic grey image (a smooth field: distance to the center plus a few sine waves, as an
MRI's or EM stack's intensities would vary) and a segmentation of blobs in it share one
geometry (same dimensions, spacing and origin). The intensity is shown as an axial slice
through the middle (pyvista ``add_mesh`` of ``ImageData.slice``, grey colormap, unlit), the
segmentation by ``vtksvdag.add_segmentation``; the mapper composites the two by depth, so the
blobs above the slice are drawn over it and the parts below it are hidden by it.

With ``--off-screen`` no window opens; the picture goes to ``--output`` (default
``build/examples/labels_over_intensity.png``).
"""
import numpy as np
import pyvista as pv

import vtksvdag
from _example import finish, parse_args

SHAPE = (64, 56, 48)             # x, y, z voxels
SPACING = (0.8, 0.8, 1.25)       # anisotropic, as most scans are
ORIGIN = (10.0, -5.0, 3.0)
# (center in voxels, radius in world units, label value)
BLOBS = [((18, 18, 30), 9.0, 3), ((44, 24, 14), 11.0, 7), ((46, 42, 26), 8.0, 12)]


def make_volumes():
    """(labels [x, y, z] uint16, intensity pyvista.ImageData with point data "intensity")."""
    i, j, k = np.meshgrid(*(np.arange(n) for n in SHAPE), indexing="ij")
    world = [o + s * a for o, s, a in zip(ORIGIN, SPACING, (i, j, k))]
    labels = np.zeros(SHAPE, np.uint16)
    for center, radius, value in BLOBS:
        c = [o + s * a for o, s, a in zip(ORIGIN, SPACING, center)]
        inside = sum((w - ci) ** 2 for w, ci in zip(world, c)) <= radius ** 2
        labels[inside] = value
    middle = [o + s * (n - 1) / 2 for o, s, n in zip(ORIGIN, SPACING, SHAPE)]
    r = np.sqrt(sum((w - m) ** 2 for w, m in zip(world, middle)))
    field = (np.cos(r / 6.0) + 0.35 * np.sin(world[0] / 3.1) * np.sin(world[1] / 4.3)
             + 0.25 * np.cos(world[2] / 2.7))
    field = (field - field.min()) / (field.max() - field.min())  # 0 .. 1
    intensity = pv.ImageData(dimensions=SHAPE, spacing=SPACING, origin=ORIGIN)
    intensity.point_data["intensity"] = field.astype(np.float32).ravel(order="F")
    return labels, intensity


def add_scene(plotter, labels, intensity, spp=8):
    """The segmentation and the axial slice through the middle: (segmentation actor, slice
    actor). The slice is unlit, so its pixels are exactly the grey colormap's values."""
    volume = vtksvdag.from_numpy(labels, spacing=SPACING, origin=ORIGIN)
    segmentation = vtksvdag.add_segmentation(
        plotter, volume, colors={3: "tomato", 7: "royalblue", 12: "gold"}, spp=spp)
    section = intensity.slice(normal="z", origin=intensity.center)
    grey = plotter.add_mesh(section, scalars="intensity", cmap="gray", clim=(0, 1),
                            lighting=False, show_scalar_bar=False)
    return segmentation, grey


def main():
    args = parse_args(__doc__, "labels_over_intensity.png")
    labels, intensity = make_volumes()
    plotter = pv.Plotter(off_screen=args.off_screen, window_size=(320, 240))
    add_scene(plotter, labels, intensity)
    plotter.camera_position = [(0, -60, 110), intensity.center, (0, 0, 1)]
    vtksvdag.refine(plotter, timeout=30)
    finish(plotter, args)


if __name__ == "__main__":
    main()
