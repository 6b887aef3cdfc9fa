"""Scenes the benchmarks share: a small generated label volume, the lighting and helpers of the
vtkSegmentationSVDAGRenderer runs (bench/render.py, bench/denoise.py), and VTK's GPU ray caster
set up on a segmentation the way bench/vtk.py and bench/startup.py compare against."""
from __future__ import annotations

import numpy as np


def generated_labels(n=48):
    """An n^3 uint16 label array indexed [z, y, x]: nested boxes and a sphere (no ../shared)."""
    z, y, x = np.mgrid[0:n, 0:n, 0:n]
    labels = np.zeros((n, n, n), np.uint16)
    labels[n // 16:n - n // 16, n // 10:n - n // 10, n // 12:n - n // 12] = 2
    labels[n // 3:(5 * n) // 8, n // 6:(4 * n) // 5, n // 3:(5 * n) // 8] = 9
    labels[(x - (5 * n) // 8) ** 2 + (y - (11 * n) // 24) ** 2 + (z - (5 * n) // 16) ** 2
           < ((11 * n) // 48) ** 2] = 5
    return labels


def sun_and_sky(renderer):
    """The error curves' lighting: a disk sun of 8 degrees and a constant sky (the background)."""
    s = renderer.GetSettings()
    s.SunOn()
    s.SetSunDirection(0.45, 0.35, 0.82)
    s.SetSunAngularRadius(8.0)
    s.SetSunIrradiance(3.0, 2.9, 2.7)
    s.SetEnvironmentColor(0.25, 0.3, 0.4)
    s.SetBackground(0.25, 0.3, 0.4, 1.0)


def render(renderer):
    """One pass of a vtkSegmentationSVDAGRenderer; an exception where it fails."""
    if not renderer.Render():
        raise RuntimeError("Render failed (see the VTK error above)")


def point_array(renderer, name):
    """An output array of the renderer (HDR, Color, Label, Depth, ...) as numpy."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    return vtk_to_numpy(renderer.GetOutput().GetPointData().GetArray(name))


def hdr(renderer):
    """The renderer's linear RGB, float64, one row per pixel."""
    return point_array(renderer, "HDR")[:, :3].astype(np.float64)


def relabel(volume):
    """The decoded labels as dense uint16 indices in VTK order (x fastest; index i is the i-th
    smallest value), their count and the index of value 0 (None without background).

    fastremap, connectomics' tool for this, as a ray caster's user would relabel: np.unique's
    return_inverse sorts every voxel (1.9 s on a 250^3 volume, against 0.1 s here), which the
    start-up bench would otherwise charge to vtkGPUVolumeRayCastMapper."""
    import fastremap

    flat = volume.to_numpy().ravel(order="F")
    values, inverse = fastremap.unique(flat, return_inverse=True)
    if len(values) > 65536:
        raise RuntimeError(f"{len(values)} distinct values do not fit uint16 indices")
    background = int(np.searchsorted(values, 0)) if values[0] == 0 else None
    return inverse.astype(np.uint16).reshape(-1), len(values), background


def index_image(volume, indices):
    """A vtkImageData of the volume's geometry holding `indices` as its point scalars."""
    from vtkmodules.util.numpy_support import numpy_to_vtk
    from vtkmodules.vtkCommonDataModel import vtkImageData

    image = vtkImageData()
    image.SetDimensions(*volume.dims)
    image.SetSpacing(*volume.spacing)
    image.SetOrigin(*volume.origin)
    scalars = numpy_to_vtk(indices, deep=False)
    scalars.SetName("label_index")
    image.GetPointData().SetScalars(scalars)
    image._keep = indices  # the VTK array borrows the numpy buffer
    return image


def gpu_raycast_volume(volume, relabelled=None):
    """A vtkVolume of `volume` through vtkGPUVolumeRayCastMapper: nearest interpolation, a random
    categorical color per label (seed 0), opacity 0 for the background and 1 for labels, shading
    off (VTK would shade with the label-index field's gradient, which is zero inside a label: its
    inside black, only the borders colored). `relabelled`: relabel(volume) where the caller made
    it already. Returns (vtkVolume, mapper)."""
    import vtkmodules.vtkRenderingVolumeOpenGL2  # noqa: F401  (the OpenGL volume mappers)
    from vtkmodules.vtkCommonDataModel import vtkPiecewiseFunction
    from vtkmodules.vtkRenderingCore import vtkColorTransferFunction, vtkVolume, vtkVolumeProperty
    from vtkmodules.vtkRenderingVolume import vtkGPUVolumeRayCastMapper

    indices, n_values, background = relabelled or relabel(volume)
    first = 0 if background is None else 1
    colors = np.random.default_rng(0).uniform(0.15, 1.0, size=(n_values, 3))
    ctf = vtkColorTransferFunction()
    for i in range(n_values):
        ctf.AddRGBPoint(float(i), *colors[i])
    otf = vtkPiecewiseFunction()
    if background is not None:
        otf.AddPoint(0.0, 0.0)
    otf.AddPoint(float(first), 1.0)
    otf.AddPoint(float(max(n_values - 1, first)), 1.0)
    prop = vtkVolumeProperty()
    prop.SetColor(ctf)
    prop.SetScalarOpacity(otf)
    prop.SetInterpolationTypeToNearest()
    prop.ShadeOff()
    mapper = vtkGPUVolumeRayCastMapper()
    mapper.SetInputData(index_image(volume, indices))
    actor = vtkVolume()
    actor.SetMapper(mapper)
    actor.SetProperty(prop)
    return actor, mapper
