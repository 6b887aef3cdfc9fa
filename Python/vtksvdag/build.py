"""Compress label volumes held in memory: numpy arrays and vtkImageData / pyvista.ImageData."""
import time

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk
from vtkmodules.vtkCommonDataModel import vtkDataObject, vtkImageData

from ._labels import (
    check_label_dtype, label_list, label_pattern, label_patterns, numpy_dtype_of_vtk_type,
)
from ._vtkrun import run_algorithm
from .volume import SegmentationVolume, check_axis_order
from .vtkSVDAGCore import vtkImageDataToSegmentationSVDAG


_MAX_DIMENSION = 2**31 - 1  # vtkImageData dimensions are C ints


def _check_vector(values, name, positive=False):
    try:
        vector = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"{name} must be three numbers, not {values!r}") from None
    if vector.shape != (3,) or not np.isfinite(vector).all():
        raise ValueError(f"{name} must be three finite numbers, not {values!r}")
    if positive and (vector <= 0).any():
        raise ValueError(f"{name} must be positive, not {values!r}")
    return [float(v) for v in vector]


def _check_direction(direction):
    if direction is None:
        return np.eye(3)
    try:
        matrix = np.asarray(direction, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"direction must be a 3x3 matrix of numbers, not {direction!r}") from None
    if matrix.size != 9 or not np.isfinite(matrix).all():
        raise ValueError(f"direction must be a finite 3x3 matrix, not {direction!r}")
    matrix = matrix.reshape(3, 3)
    if abs(np.linalg.det(matrix)) < 1e-12:
        raise ValueError("direction must be an invertible 3x3 matrix")
    return matrix


def _compress(image, dtype, background, exclude, scalars, progress):
    """Run vtkImageDataToSegmentationSVDAG on ``image`` and wrap the result."""
    builder = vtkImageDataToSegmentationSVDAG()
    builder.SetInputData(image)
    if scalars is not None:
        builder.SetInputArrayToProcess(0, 0, 0, vtkDataObject.FIELD_ASSOCIATION_POINTS, scalars)
    builder.SetBackgroundLabel(label_pattern(background, dtype, "background"))
    for value in label_patterns(exclude, dtype):
        builder.AddExcludedLabel(value)
    start = time.perf_counter()
    run_algorithm(builder, progress=progress, what="cannot compress the label volume")
    seconds = time.perf_counter() - start
    output = builder.GetOutput()
    if not output.HasVolume():
        raise ValueError("cannot compress the label volume: the builder produced no volume")
    return SegmentationVolume(output, build_seconds=seconds)


def from_numpy(
    array,
    spacing=(1.0, 1.0, 1.0),
    origin=(0.0, 0.0, 0.0),
    direction=None,
    background=0,
    exclude=(),
    axis_order="xyz",
    progress=None,
):
    """Compress a 3D integer label array losslessly.

    Parameters
    ----------
    array : numpy.ndarray
        3D array of integer labels (int8..int64, uint8..uint64, either byte order, any
        memory layout; ``bool`` is stored as ``uint8``). A 2D slice must be given as 3D, e.g. ``array[:, :, np.newaxis]``: guessing
        which axis is missing would be wrong half of the time.
    spacing : sequence of float, default: (1, 1, 1)
        Positive voxel size along x, y, z.
    origin : sequence of float, default: (0, 0, 0)
        Physical position of voxel (0, 0, 0).
    direction : array_like, optional
        3x3 index-to-physical direction matrix (columns are the x, y, z axes); identity when
        not given.
    background : int, default: 0
        Label value that is not stored (it must fit the array's dtype).
    exclude : sequence of int, default: ()
        Labels left out; they decode as background.
    axis_order : {"xyz", "zyx"}, default: "xyz"
        "xyz": ``array[x, y, z]``, as pyvista, nibabel and ``nrrd.read`` give; "zyx":
        ``array[z, y, x]``, as ``nrrd.read(..., index_order="C")`` gives. Spacing, origin
        and direction are always given in x, y, z order.
    progress : callable, optional
        Called with the compression progress in [0, 1].

    Returns
    -------
    SegmentationVolume
        The compressed volume; ``build_seconds`` holds the compression time.

    Raises
    ------
    TypeError
        The array is not an integer or bool array (or is a masked array), or a label value
        is not an integer.
    ValueError
        The array is not 3D or is empty, a label value does not fit the dtype, or the
        geometry is invalid.
    Exception
        Whatever ``progress`` raised (compression stops).

    Examples
    --------
    >>> import numpy as np
    >>> import vtksvdag
    >>> labels = np.random.default_rng(0).integers(0, 4, size=(40, 30, 20), dtype=np.int16)
    >>> volume = vtksvdag.from_numpy(labels, spacing=(1.0, 1.0, 2.5))
    >>> volume.labels
    array([1, 2, 3], dtype=int16)
    >>> np.array_equal(volume.to_numpy(), labels)
    True
    """
    if isinstance(array, np.ma.MaskedArray):
        # np.asarray would drop the mask and store whatever lies under it.
        raise TypeError(
            "a masked array cannot be compressed as it is: fill the masked voxels first, "
            "e.g. array.filled(background)"
        )
    array = np.asarray(array)
    dtype = check_label_dtype(array.dtype)  # native byte order
    if array.ndim != 3:
        raise ValueError(
            f"a label volume must be a 3D array, not {array.ndim}D with shape {array.shape}"
            + ("; for one slice add an axis, e.g. array[:, :, np.newaxis]" if array.ndim == 2 else "")
        )
    if array.size == 0:
        raise ValueError(f"the label array is empty (shape {array.shape})")
    if max(array.shape) > _MAX_DIMENSION:
        raise ValueError(
            f"the label array has shape {array.shape}; VTK images have at most "
            f"{_MAX_DIMENSION} voxels along an axis"
        )
    check_axis_order(axis_order)
    spacing = _check_vector(spacing, "spacing", positive=True)
    origin = _check_vector(origin, "origin")
    direction = _check_direction(direction)
    exclude = label_list(exclude)  # a generator is read once
    label_pattern(background, dtype, "background")  # fail before any copy of a big array
    label_patterns(exclude, dtype)

    xyz = array if axis_order == "xyz" else array.transpose(2, 1, 0)
    # VTK wants x fastest: a view for Fortran-ordered [x,y,z] (and C-ordered [z,y,x]) arrays;
    # other layouts are copied once here.
    flat = np.ravel(xyz, order="F")
    if flat.dtype != dtype:
        # bool -> uint8, and big-endian -> native: a value conversion, not a reinterpretation
        flat = flat.astype(dtype)
    image = vtkImageData()
    image.SetDimensions(*xyz.shape)
    image.SetSpacing(spacing)
    image.SetOrigin(origin)
    image.SetDirectionMatrix(*direction.ravel())
    scalars = numpy_to_vtk(flat, deep=False)  # shares `flat`, which stays referenced below
    scalars.SetName("Labels")
    image.GetPointData().SetScalars(scalars)
    volume = _compress(image, dtype, background, exclude, None, progress)
    del flat  # the VTK array pointed into it until the builder finished
    return volume


def from_image(image, scalars=None, background=0, exclude=(), progress=None):
    """Compress the integer labels of a vtkImageData or ``pyvista.ImageData`` losslessly.

    Parameters
    ----------
    image : vtkImageData or pyvista.ImageData
        The label image; its spacing, origin and direction are kept.
    scalars : str, optional
        Name of the point data array holding the labels; the active point scalars by default.
    background : int, default: 0
        Label value that is not stored.
    exclude : sequence of int, default: ()
        Labels left out; they decode as background.
    progress : callable, optional
        Called with the compression progress in [0, 1].

    Returns
    -------
    SegmentationVolume

    Raises
    ------
    TypeError
        ``image`` is not image data, its labels are not integers, or ``scalars`` is not a
        string.
    KeyError
        There is no point data array called ``scalars`` (or no active scalars).

    Examples
    --------
    >>> import numpy as np, pyvista as pv, vtksvdag
    >>> grid = pv.ImageData(dimensions=(8, 8, 8), spacing=(0.5, 0.5, 0.5))
    >>> grid.point_data["seg"] = (np.arange(grid.n_points) % 3).astype(np.uint8)
    >>> vtksvdag.from_image(grid, scalars="seg").labels
    array([1, 2], dtype=uint8)
    """
    if not isinstance(image, vtkImageData):
        raise TypeError(f"expected a vtkImageData or pyvista.ImageData, not {type(image).__name__}")
    if scalars is not None and not isinstance(scalars, str):
        # vtkPointData.GetArray(0) would take an index, and the builder an attribute type.
        raise TypeError(f"scalars must be the name of a point data array, not {scalars!r}")
    point_data = image.GetPointData()
    array = point_data.GetArray(scalars) if scalars is not None else point_data.GetScalars()
    if array is None:
        if scalars is None:
            raise KeyError("the image has no active point scalars; name the label array with scalars=")
        names = [point_data.GetArrayName(i) for i in range(point_data.GetNumberOfArrays())]
        raise KeyError(f"the image has no point data array {scalars!r} (it has {names})")
    if array.GetNumberOfComponents() != 1:
        raise ValueError(f"the label array has {array.GetNumberOfComponents()} components, not 1")
    dtype = check_label_dtype(numpy_dtype_of_vtk_type(array.GetDataType()))
    if image.GetNumberOfPoints() == 0:
        raise ValueError("the image is empty")
    exclude = label_list(exclude)
    label_pattern(background, dtype, "background")
    label_patterns(exclude, dtype)
    return _compress(image, dtype, background, exclude, scalars, progress)
