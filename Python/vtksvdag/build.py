"""Compress label volumes held in memory: numpy arrays and vtkImageData / pyvista.ImageData."""
import time

import numpy as np
from vtkmodules.util.numpy_support import numpy_to_vtk, vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkDataObject, vtkImageData

from ._labels import (
    cast_labels, check_cast, check_label_dtype, label_list, label_pattern, label_patterns,
    numpy_dtype_of_vtk_type,
)
from ._options import keywords_checked
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


@keywords_checked
def from_numpy(
    array,
    spacing=(1.0, 1.0, 1.0),
    origin=(0.0, 0.0, 0.0),
    direction=None,
    background=0,
    exclude=(),
    axis_order="xyz",
    progress=None,
    *,
    cast=None,
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
    cast : {None, "exact"}, default: None
        Float arrays: ``None`` refuses them; ``"exact"`` accepts them when every value is a
        whole number, stored as the narrowest integer dtype that holds them (unsigned when none
        is negative): ``volume.to_numpy()`` equals the array value for value. Integer arrays
        are kept as they are either way.

    Returns
    -------
    SegmentationVolume
        The compressed volume; ``build_seconds`` holds the compression time.

    Raises
    ------
    TypeError
        The array is not an integer, bool or float array (or is a masked array), a label value
        is not an integer, or an option is unknown (the message suggests the closest names).
    ValueError
        The array is not 3D or is empty, a label value does not fit the dtype, the geometry is
        invalid, ``cast`` is not one of its values, or the array holds floats: without
        ``cast="exact"``, or with it when a value is not a whole number an integer type holds
        (the message names the first such value and its index). The float errors are
        ``FloatLabelsError``, a ValueError that is also a TypeError.
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

    Integer-valued floats (a label map saved as float32) with ``cast="exact"``:

    >>> floats = labels.astype(np.float32)
    >>> vtksvdag.from_numpy(floats, cast="exact").to_numpy().dtype
    dtype('uint8')
    """
    if isinstance(array, np.ma.MaskedArray):
        # np.asarray would drop the mask and store whatever lies under it.
        raise TypeError(
            "a masked array cannot be compressed as it is: fill the masked voxels first, "
            "e.g. array.filled(background)"
        )
    array = np.asarray(array)
    check_cast(cast)
    if array.ndim == 3 and array.size:
        # Before the dtype check, which refuses floats; the shape checks below come first for
        # other shapes (no scan of a wrong array).
        array = cast_labels(array, cast)
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


def _label_array(image, scalars):
    """(array, association) of the labels of ``image``: the array named ``scalars``, looked up
    in the point data first and then in the cell data (pyvista's default preference), or the
    active point scalars, else the active cell scalars."""
    point_data, cell_data = image.GetPointData(), image.GetCellData()
    if scalars is None:
        for association, data in (("point", point_data), ("cell", cell_data)):
            if data.GetScalars() is not None:
                return data.GetScalars(), association
        raise KeyError("the image has no active point scalars and no active cell scalars; name "
                       "the label array with scalars=")
    for association, data in (("point", point_data), ("cell", cell_data)):
        array = data.GetArray(scalars)
        if array is not None:
            return array, association

    def names(data):
        return [data.GetArrayName(i) for i in range(data.GetNumberOfArrays())]

    raise KeyError(f"the image has no point data array {scalars!r} and no cell data array of "
                   f"that name (point data: {names(point_data)}, cell data: {names(cell_data)})")


def _voxel_image(image, array, association):
    """An image whose point scalars are ``array`` and whose points are the voxel centers.

    Cell labels are the voxel grid itself: an image of n points along an axis has n - 1 cells,
    and the voxel of cell i spans the points i and i + 1, so the voxel centers are the cell
    centers, half a spacing (along the direction) from the image's origin.
    """
    voxels = vtkImageData()
    spacing = np.asarray(image.GetSpacing(), float)
    origin = np.asarray(image.GetOrigin(), float)
    dims = np.asarray(image.GetDimensions())
    if association == "cell":
        direction = np.array([image.GetDirectionMatrix().GetElement(r, c)
                              for r in range(3) for c in range(3)]).reshape(3, 3)
        flat = dims <= 1  # an axis of one point has one (flat) cell: its voxel sits on it
        origin = origin + direction @ np.where(flat, 0.0, 0.5 * spacing)
        dims = np.where(flat, 1, dims - 1)
    voxels.SetDimensions(*(int(d) for d in dims))
    voxels.SetSpacing(*spacing)
    voxels.SetOrigin(*origin)
    voxels.SetDirectionMatrix(image.GetDirectionMatrix())
    if voxels.GetNumberOfPoints() != array.GetNumberOfTuples():
        raise ValueError(f"the {association} data array {array.GetName()!r} has "
                         f"{array.GetNumberOfTuples()} values for {voxels.GetNumberOfPoints()} "
                         f"voxels")
    voxels.GetPointData().SetScalars(array)
    return voxels


@keywords_checked
def from_image(image, scalars=None, background=0, exclude=(), progress=None, *, cast=None):
    """Compress the integer labels of a vtkImageData or ``pyvista.ImageData`` losslessly.

    Parameters
    ----------
    image : vtkImageData or pyvista.ImageData
        The label image; its spacing, origin and direction are kept.
    scalars : str, optional
        Name of the array holding the labels, point data or cell data (a name in both is taken
        from the point data, pyvista's default preference). By default the active point
        scalars, else the active cell scalars. Point labels put a voxel on every point; cell
        labels are the voxel grid itself: an image of (nx, ny, nz) points with cell labels is a
        volume of (nx - 1, ny - 1, nz - 1) voxels whose boxes are the cells (its origin, the
        first voxel center, is half a voxel inside the image's).
    background : int, default: 0
        Label value that is not stored.
    exclude : sequence of int, default: ()
        Labels left out; they decode as background.
    progress : callable, optional
        Called with the compression progress in [0, 1].
    cast : {None, "exact"}, default: None
        Float labels: refused, or with ``"exact"`` accepted when every value is a whole number
        (see :func:`from_numpy`).

    Returns
    -------
    SegmentationVolume

    Raises
    ------
    TypeError
        ``image`` is not image data, its labels are not integers (or floats, see ``cast``),
        ``scalars`` is not a string, or an option is unknown.
    ValueError
        Float labels without ``cast="exact"`` (or with it, a value that is not a whole number),
        an array of several components, or an empty image.
    KeyError
        There is no point or cell data array called ``scalars`` (or no active scalars).

    Examples
    --------
    >>> import numpy as np, pyvista as pv, vtksvdag
    >>> grid = pv.ImageData(dimensions=(8, 8, 8), spacing=(0.5, 0.5, 0.5))
    >>> grid.point_data["seg"] = (np.arange(grid.n_points) % 3).astype(np.uint8)
    >>> vtksvdag.from_image(grid, scalars="seg").labels
    array([1, 2], dtype=uint8)

    Cell labels: one voxel per cell.

    >>> grid.cell_data["parcels"] = (np.arange(grid.n_cells) % 4).astype(np.int16)
    >>> vtksvdag.from_image(grid, scalars="parcels").dims
    (7, 7, 7)
    """
    if not isinstance(image, vtkImageData):
        raise TypeError(f"expected a vtkImageData or pyvista.ImageData, not {type(image).__name__}")
    if scalars is not None and not isinstance(scalars, str):
        # vtkPointData.GetArray(0) would take an index, and the builder an attribute type.
        raise TypeError(f"scalars must be the name of a point or cell data array, not {scalars!r}")
    check_cast(cast)
    array, association = _label_array(image, scalars)
    if array.GetNumberOfComponents() != 1:
        raise ValueError(f"the label array has {array.GetNumberOfComponents()} components, not 1")
    if image.GetNumberOfPoints() == 0 or array.GetNumberOfTuples() == 0:
        raise ValueError("the image is empty")
    dtype = numpy_dtype_of_vtk_type(array.GetDataType())
    cast_copy = np.dtype(dtype).kind == "f"
    if cast_copy:
        values = cast_labels(vtk_to_numpy(array), cast,
                             f"{association} data array {array.GetName()!r}")
        array = numpy_to_vtk(values, deep=True)
        array.SetName("Labels")
        dtype = values.dtype
    dtype = check_label_dtype(dtype)
    exclude = label_list(exclude)
    label_pattern(background, dtype, "background")
    label_patterns(exclude, dtype)
    if association == "point" and not cast_copy:
        # The image as it is: no copy of its geometry or arrays.
        return _compress(image, dtype, background, exclude, scalars, progress)
    return _compress(_voxel_image(image, array, association), dtype, background, exclude, None,
                     progress)
