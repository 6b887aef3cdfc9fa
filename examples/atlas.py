"""A brain parcellation with its FreeSurfer color table: names, colors, a legend and a cut.

The workflow of a FreeSurfer user: a label volume (``aparc+aseg.nii.gz``) and a color table
(``FreeSurferColorLUT.txt``, lines ``index name R G B A``) lie side by side;
:func:`vtksvdag.read_label_table` reads the table, ``attributes=`` gives the labels its names and
colors, a coronal clipping plane opens the brain and the legend names the structures on the cut
face (white matter, ventricles, caudate, putamen, pallidum, ... and the cortical parcels around
them):

    xvfb-run -a .venv/bin/python examples/atlas.py [--off-screen] [--output PNG]
        [--volume FILE --lut FILE] [--workdir DIR]

By default the example makes both files itself: a synthetic parcellation (an ellipsoidal
cerebrum split into hemispheres, with cortical parcels, white matter and deep structures, a
cerebellum and a brain stem) that uses FreeSurfer's label values and names, written as NIfTI,
and a table in FreeSurfer's format with FreeSurfer's colors for those labels. They go to
``--workdir`` (default: a temporary directory, removed at the end). ``--volume`` and ``--lut``
use your own files instead, e.g. a subject's ``aparc+aseg.mgz`` converted to NIfTI with
``mri_convert`` and ``$FREESURFER_HOME/FreeSurferColorLUT.txt``; the axes are then the volume's
own, so the cut and the view may need adjusting (``CUT_NORMAL``, ``VIEW``).

The script prints the legend's entries (label value, name, color) and writes the picture to
``--output`` (default ``build/examples/atlas.png``) with ``--off-screen``.
"""
import argparse
import pathlib
import tempfile

import numpy as np
import pyvista as pv

import vtksvdag
from _example import HERE

WINDOW = (640, 400)
SPP = 12
LEGEND_ENTRIES = 14
# The cut: a coronal plane keeping the posterior side (-y), seen from the front, right and above.
CUT_FRACTION = 0.5     # where the plane lies along y, from the back of the volume
CUT_NORMAL = (0.0, -1.0, 0.0)
VIEW = (0.55, 1.0, 0.5)  # from the focal point to the camera
SHIFT = 0.18           # the brain's offset to the left of the frame (a share of the frame's width)
                       # leaves the right side to the legend

# FreeSurfer's label values, names and colors (FreeSurferColorLUT.txt) of what the synthetic
# brain holds: aseg structures of each hemisphere, (left value, right value, name without the
# side, R, G, B) ...
ASEG = [
    (2, 41, "Cerebral-White-Matter", 245, 245, 245),
    (4, 43, "Lateral-Ventricle", 120, 18, 134),
    (7, 46, "Cerebellum-White-Matter", 220, 248, 164),
    (8, 47, "Cerebellum-Cortex", 230, 148, 34),
    (10, 49, "Thalamus", 0, 118, 14),
    (11, 50, "Caudate", 122, 186, 220),
    (12, 51, "Putamen", 236, 13, 176),
    (13, 52, "Pallidum", 12, 48, 255),
    (17, 53, "Hippocampus", 220, 216, 20),
    (18, 54, "Amygdala", 103, 255, 255),
]
MIDLINE = [(14, "3rd-Ventricle", 204, 182, 142), (16, "Brain-Stem", 119, 159, 176)]
# ... and the cortical parcels of the Desikan-Killiany atlas (ctx-lh-* = 1000 + i, ctx-rh-* =
# 2000 + i), each with the direction (lateral, anterior, superior) from the cerebrum's center
# towards its middle: a cortex voxel belongs to the parcel whose direction is nearest its own.
CORTEX = [
    (3, "caudalmiddlefrontal", 100, 25, 0, (0.6, 0.3, 0.7)),
    (8, "inferiorparietal", 220, 60, 220, (0.75, -0.55, 0.3)),
    (9, "inferiortemporal", 180, 40, 120, (0.6, -0.1, -0.8)),
    (11, "lateraloccipital", 20, 30, 140, (0.45, -0.9, 0.0)),
    (12, "lateralorbitofrontal", 35, 75, 50, (0.5, 0.8, -0.3)),
    (15, "middletemporal", 160, 100, 50, (0.9, -0.15, -0.4)),
    (22, "postcentral", 220, 20, 20, (0.7, -0.2, 0.65)),
    (24, "precentral", 60, 20, 220, (0.7, 0.05, 0.7)),
    (25, "precuneus", 160, 140, 180, (0.1, -0.7, 0.6)),
    (27, "rostralmiddlefrontal", 75, 50, 125, (0.6, 0.75, 0.25)),
    (28, "superiorfrontal", 20, 220, 160, (0.25, 0.6, 0.75)),
    (29, "superiorparietal", 20, 180, 140, (0.35, -0.65, 0.65)),
    (30, "superiortemporal", 140, 220, 220, (0.95, 0.1, -0.1)),
    (32, "frontalpole", 100, 0, 100, (0.15, 1.0, 0.0)),
]
# Entries the synthetic brain does not hold, as a real table has hundreds: a color table names
# labels in general, so joining it with a volume that lacks some does not warn.
UNUSED = [(24, "CSF", 60, 60, 60), (77, "WM-hypointensities", 200, 70, 255)]


def freesurfer_lut():
    """The synthetic brain's color table as rows ``(index, name, R, G, B)``, sorted."""
    rows = [(0, "Unknown", 0, 0, 0)]
    for left, right, name, r, g, b in ASEG:
        rows += [(left, f"Left-{name}", r, g, b), (right, f"Right-{name}", r, g, b)]
    rows += MIDLINE + UNUSED
    for i, name, r, g, b, _ in CORTEX:
        rows += [(1000 + i, f"ctx-lh-{name}", r, g, b), (2000 + i, f"ctx-rh-{name}", r, g, b)]
    return sorted(rows)


def write_freesurfer_lut(path):
    """Write :func:`freesurfer_lut` in FreeSurfer's format (``A`` = 0: opaque)."""
    with open(path, "w") as f:
        f.write("#$Id: FreeSurferColorLUT.txt (the labels of the vtkSVDAG atlas example)\n")
        f.write("#No. Label Name:                            R   G   B   A\n")
        for index, name, r, g, b in freesurfer_lut():
            f.write(f"{index:<5d} {name:<40s} {r:3d} {g:3d} {b:3d}   0\n")


def _ellipsoid(x, y, z, center, semi):
    return ((x - center[0]) / semi[0]) ** 2 + ((y - center[1]) / semi[1]) ** 2 + (
        (z - center[2]) / semi[2]) ** 2 <= 1


def synthetic_parcellation(shape=(80, 100, 80)):
    """A brain-like label array indexed ``[x, y, z]`` (x: left to right, y: posterior to
    anterior, z: inferior to superior, 1 mm voxels) with the labels of :func:`freesurfer_lut`."""
    nx, ny, nz = shape
    x, y, z = np.meshgrid(np.arange(nx), np.arange(ny), np.arange(nz), indexing="ij",
                          sparse=True)
    labels = np.zeros(shape, np.uint16)
    c = np.array([nx / 2 - 0.5, ny / 2, nz * 0.58])  # the cerebrum's center
    semi = np.array([nx / 2 - 3, ny / 2 - 3, nz * 0.4])
    u, v, w = (x - c[0]) / semi[0], (y - c[1]) / semi[1], (z - c[2]) / semi[2]
    r = np.sqrt(u * u + v * v + w * w)
    right = x > c[0]  # index x grows to the right (RAS), as in FreeSurfer's volumes
    # A longitudinal fissure of 2 voxels splits the hemispheres (deep structures stay whole).
    cerebrum = (r <= 1) & (np.abs(x - c[0]) > 1)

    def sided(left_value, right_value):
        return np.broadcast_to(np.where(right, right_value, left_value).astype(np.uint16), shape)

    # Cortex: the outer shell, parcelled by direction (mirrored for the left hemisphere).
    directions = np.array([d for *_, d in CORTEX], float)
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)
    shell = cerebrum & (r > 0.86)
    lateral = np.abs(np.broadcast_to(u, shape))[shell]
    toward = np.stack([lateral, np.broadcast_to(v, shape)[shell], np.broadcast_to(w, shape)[shell]], 1)
    parcel = np.argmax(toward @ directions.T, axis=1)  # the nearest direction: largest cosine
    parcel_ids = np.array([i for i, *_ in CORTEX])[parcel]
    labels[shell] = np.where(np.broadcast_to(right, shape)[shell], 2000, 1000) + parcel_ids
    labels[cerebrum & (r <= 0.86)] = sided(2, 41)[cerebrum & (r <= 0.86)]

    # Deep structures: ellipsoids at FreeSurfer-like places, (center offset, semi-axes) in
    # voxels from the cerebrum's center, mirrored to both sides.
    deep = [(4, 43, (7, 2, 6), (4, 17, 4)),      # lateral ventricles
            (11, 50, (9, 12, 7), (3.5, 6, 4)),   # caudate
            (12, 51, (19, 4, 0), (3.5, 8, 6)),   # putamen
            (13, 52, (15, 2, -1), (2.5, 5, 4)),  # pallidum
            (10, 49, (6, -7, 2), (5, 8, 5)),     # thalamus
            (17, 53, (21, -9, -12), (3, 10, 3)),  # hippocampus
            (18, 54, (21, 5, -14), (3.5, 3.5, 3.5))]  # amygdala
    for left_value, right_value, offset, axes in deep:
        for side, value in ((-1, left_value), (1, right_value)):
            center = c + np.array(offset) * (side, 1, 1)
            labels[_ellipsoid(x, y, z, center, axes) & (r <= 0.86)] = value
    third = (np.abs(x - c[0]) <= 1) & (np.abs(y - (c[1] - 2)) <= 8) & (np.abs(z - (c[2] + 1)) <= 5)
    labels[third] = 14

    # Cerebellum below the back of the cerebrum (cortex shell around white matter), and the
    # brain stem from the bottom of the volume up into the cerebrum.
    cb_center, cb_semi = np.array([c[0], ny * 0.25, nz * 0.2]), np.array([nx * 0.33, ny * 0.15, nz * 0.15])
    cb_r = np.sqrt(((x - cb_center[0]) / cb_semi[0]) ** 2 + ((y - cb_center[1]) / cb_semi[1]) ** 2
                   + ((z - cb_center[2]) / cb_semi[2]) ** 2)
    cerebellum = (cb_r <= 1) & (labels == 0) & (np.abs(x - c[0]) > 0.5)
    labels[cerebellum & (cb_r > 0.7)] = sided(8, 47)[cerebellum & (cb_r > 0.7)]
    labels[cerebellum & (cb_r <= 0.7)] = sided(7, 46)[cerebellum & (cb_r <= 0.7)]
    stem = ((x - c[0]) ** 2 + (y - (c[1] - 12)) ** 2 <= 6.5 ** 2) & (z <= c[2] - 6)
    labels[np.broadcast_to(stem, shape)] = 16
    return labels


def write_nifti(labels, path):
    """Write a label array indexed ``[x, y, z]`` (1 mm voxels) as NIfTI, with VTK's writer."""
    from vtkmodules.vtkIOImage import vtkNIFTIImageWriter

    grid = pv.ImageData(dimensions=labels.shape)
    grid.point_data["labels"] = labels.ravel(order="F")  # VTK's point order: x fastest
    writer = vtkNIFTIImageWriter()
    writer.SetInputData(grid)
    writer.SetFileName(str(path))
    writer.Write()


def parse_args():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--off-screen", action="store_true",
                        help="no window: save the result to --output")
    parser.add_argument("--output", type=pathlib.Path,
                        default=HERE.parent / "build" / "examples" / "atlas.png")
    parser.add_argument("--volume", type=pathlib.Path, help="a label volume (default: synthetic)")
    parser.add_argument("--lut", type=pathlib.Path, help="its FreeSurfer-style color table")
    parser.add_argument("--workdir", type=pathlib.Path,
                        help="where the synthetic volume and table are written (default: a "
                             "temporary directory)")
    args = parser.parse_args()
    if (args.volume is None) != (args.lut is None):
        parser.error("--volume and --lut go together")
    args.output.parent.mkdir(parents=True, exist_ok=True)
    return args


def cut_face_labels(volume, plane_y):
    """The labels on the cut face (the voxel slice the plane passes through), most voxels
    first: what the legend lists."""
    index = int(round((plane_y - volume.origin[1]) / volume.spacing[1]))
    face = volume.slice("y", min(max(index, 0), volume.dims[1] - 1))
    values, counts = np.unique(face[face != volume.background], return_counts=True)
    return values[np.argsort(-counts, kind="stable")].tolist()


def main():
    args = parse_args()
    with tempfile.TemporaryDirectory() as temporary:
        if args.volume is None:
            workdir = args.workdir or pathlib.Path(temporary)
            workdir.mkdir(parents=True, exist_ok=True)
            args.volume = workdir / "aparc+aseg.nii.gz"
            args.lut = workdir / "FreeSurferColorLUT.txt"
            write_nifti(synthetic_parcellation(), args.volume)
            write_freesurfer_lut(args.lut)
        # What a user does with the two files.
        volume = vtksvdag.read(args.volume)
        table = vtksvdag.read_label_table(args.lut)
    print(volume)
    print(f"{args.lut.name}: {len(table)} entries ({table.attrs['format']} format), "
          f"{table.index.isin(volume.labels.tolist()).sum()} of them in the volume")

    xmin, xmax, ymin, ymax, zmin, zmax = volume.to_pyvista().bounds
    center = np.array([(xmin + xmax) / 2, ymin + CUT_FRACTION * (ymax - ymin), (zmin + zmax) / 2])
    plotter = pv.Plotter(off_screen=args.off_screen, window_size=WINDOW)
    # The table's color column colors the labels; its name column names them in the legend.
    actor = vtksvdag.add_segmentation(plotter, volume, attributes=table, spp=SPP,
                                      shading="smooth", clipping_planes=[(center, CUT_NORMAL)])

    # The view: the camera looks at the cut face; the brain moves left to make room for the
    # legend (the camera is moved, not the window's center, so every renderer agrees).
    plotter.view_vector(VIEW, viewup=(0, 0, 1))
    plotter.reset_camera()
    camera = plotter.camera
    position, focal = np.array(camera.position), np.array(camera.focal_point)
    forward = (focal - position) / np.linalg.norm(focal - position)
    right = np.cross(forward, np.array(camera.up))
    right /= np.linalg.norm(right)
    half_width = np.linalg.norm(focal - position) * np.tan(np.radians(camera.view_angle) / 2) * (
        WINDOW[0] / WINDOW[1])
    offset = right * SHIFT * 2 * half_width
    camera.position, camera.focal_point = position + offset, focal + offset
    camera.zoom(1.3)

    # FreeSurfer colors both sides of a structure alike: the legend lists the left hemisphere's
    # labels and the midline's, found by their names in the table.
    names = table["name"].reindex(cut_face_labels(volume, center[1]))
    legend_labels = names[~names.str.startswith(("Right-", "ctx-rh-"))].index.tolist()
    legend = vtksvdag.add_label_legend(actor, labels=legend_labels, max_entries=LEGEND_ENTRIES,
                                       bcolor=(0.93, 0.93, 0.93), background_opacity=0.9)
    # The legend box beside the brain, not over it: the right third of the window.
    legend.SetPosition(0.66, 0.1)
    legend.SetPosition2(0.32, 0.8)
    # The entries' text is drawn in the label's color (vtkLegendBoxActor's way): a dark shadow
    # keeps white and yellow names readable on the light box.
    legend.GetEntryTextProperty().SetShadow(True)
    plotter.add_text("coronal cut, posterior half (left = right colors)", position="upper_left", font_size=10)
    print(f"legend: the {min(len(legend_labels), LEGEND_ENTRIES)} largest of the "
          f"{len(legend_labels)} left and midline labels on the cut face")
    for i, value in enumerate(legend_labels[:LEGEND_ENTRIES]):
        rgb = legend.GetEntryColor(i)
        print(f"  {value} {legend.GetEntryString(i)} "
              f"({', '.join(f'{c:.3f}' for c in rgb)})")

    if args.off_screen:
        plotter.screenshot(str(args.output))  # refines first: no refine() call needed
        print(f"wrote {args.output}")
        plotter.close()
    else:
        plotter.show()


if __name__ == "__main__":
    main()
