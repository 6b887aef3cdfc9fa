"""Compress a label volume a few z-slices at a time: :class:`Builder`.

For volumes that do not fit in memory at once (chunked stores, slice-by-slice readers). The
result is bit-identical to :func:`vtksvdag.from_numpy` on the whole volume; the C++ side
(vtkSegmentationSVDAGStreamBuilder) keeps at most one 16-slice slab of the caller's data.
"""
import numbers
import time

import numpy as np
from vtkmodules.util.numpy_support import get_vtk_array_type, numpy_to_vtk

from ._labels import check_label_dtype, label_list, label_pattern, label_patterns
from ._vtkrun import vtk_errors_raised
from .build import _MAX_DIMENSION, _check_direction, _check_vector
from .volume import SegmentationVolume, check_axis_order
from .vtkSVDAGCore import vtkSegmentationSVDAG, vtkSegmentationSVDAGStreamBuilder


def _check_dims(dims):
    """Three positive ints (x, y, z), each at most a VTK image's limit."""
    try:
        values = list(dims)
    except TypeError:
        raise TypeError(f"dims must be three integers (nx, ny, nz), not {dims!r}") from None
    if len(values) != 3:
        raise ValueError(f"dims must be three integers (nx, ny, nz), not {dims!r}")
    for v in values:
        if not isinstance(v, (numbers.Integral, np.integer)) or isinstance(v, (bool, np.bool_)):
            raise TypeError(f"dims must be three integers (nx, ny, nz), not {dims!r}")
    values = [int(v) for v in values]
    if min(values) < 1 or max(values) > _MAX_DIMENSION:
        raise ValueError(
            f"dims must be between 1 and {_MAX_DIMENSION} along each axis, not {tuple(values)}"
        )
    return tuple(values)


class Builder:
    """Compress a label volume given in z-slabs, in order, losslessly.

    Feed the z-slices in increasing order with :meth:`add_slab` (any number per call), then
    call :meth:`finish`. The volume is the same, byte for byte, as :func:`vtksvdag.from_numpy`
    gives for the whole array with the same arguments, while only the slab being added (and at
    most one 16-slice slab buffered by the builder) is held at a time.

    Parameters
    ----------
    dims : sequence of int
        Number of voxels along x, y, z (whatever ``axis_order``).
    dtype : numpy.dtype or str
        Label dtype (int8..int64, uint8..uint64, either byte order; ``bool`` is stored as
        ``uint8``). Every slab must have this dtype (byte order aside).
    spacing : sequence of float, default: (1, 1, 1)
        Positive voxel size along x, y, z.
    origin : sequence of float, default: (0, 0, 0)
        Physical position of voxel (0, 0, 0).
    direction : array_like, optional
        3x3 index-to-physical direction matrix (columns are the x, y, z axes); identity when
        not given.
    background : int, default: 0
        Label value that is not stored (it must fit ``dtype``).
    exclude : sequence of int, default: ()
        Labels left out; they decode as background.
    axis_order : {"xyz", "zyx"}, default: "xyz"
        Index order of the slabs: "xyz" takes arrays of shape ``(nx, ny, nz_slab)``, "zyx"
        arrays of shape ``(nz_slab, ny, nx)``.

    Raises
    ------
    TypeError
        ``dims`` are not integers, ``dtype`` is not an integer dtype, or a label value is not
        an integer.
    ValueError
        ``dims`` are not positive, a label value does not fit ``dtype``, or the geometry is
        invalid.

    Examples
    --------
    >>> import numpy as np
    >>> import vtksvdag
    >>> labels = np.random.default_rng(0).integers(0, 4, size=(40, 30, 20), dtype=np.int16)
    >>> builder = vtksvdag.Builder(labels.shape, labels.dtype, spacing=(1.0, 1.0, 2.5))
    >>> for z0 in range(0, 20, 7):
    ...     builder.add_slab(labels[:, :, z0:z0 + 7])
    >>> builder.next_z
    20
    >>> volume = builder.finish()
    >>> volume.labels
    array([1, 2, 3], dtype=int16)
    >>> np.array_equal(volume.to_numpy(), labels)
    True

    It is also a context manager, which releases the builder's memory on leaving:

    >>> with vtksvdag.Builder((8, 8, 3), np.uint8, axis_order="zyx") as builder:
    ...     builder.add_slab(np.ones((3, 8, 8), np.uint8))
    ...     volume = builder.finish()
    >>> volume.dims
    (8, 8, 3)
    """

    def __init__(self, dims, dtype, *, spacing=(1.0, 1.0, 1.0), origin=(0.0, 0.0, 0.0),
                 direction=None, background=0, exclude=(), axis_order="xyz"):
        self._dims = _check_dims(dims)
        try:
            dtype = np.dtype(dtype)
        except TypeError:
            raise TypeError(f"dtype must be a numpy integer dtype, not {dtype!r}") from None
        self._dtype = check_label_dtype(dtype, "label volume")  # native byte order
        self._axis_order = check_axis_order(axis_order)
        spacing = _check_vector(spacing, "spacing", positive=True)
        origin = _check_vector(origin, "origin")
        direction = _check_direction(direction)
        exclude = label_list(exclude)  # a generator is read once
        self._cpp = vtkSegmentationSVDAGStreamBuilder()
        self._cpp.SetBackgroundLabel(label_pattern(background, self._dtype, "background"))
        for value in label_patterns(exclude, self._dtype):
            self._cpp.AddExcludedLabel(value)
        with vtk_errors_raised(self._cpp, ValueError):
            ok = self._cpp.Initialize(
                list(self._dims), get_vtk_array_type(self._dtype), spacing, origin,
                [float(v) for v in direction.ravel()],
            )
        if not ok:
            raise ValueError("cannot start the label volume")
        self._seconds = 0.0
        self._finished = False
        self._closed = None  # why the builder cannot be used any more, once it cannot

    # -- state ------------------------------------------------------------------------------
    @property
    def dims(self):
        """tuple of int: voxels along x, y, z."""
        return self._dims

    @property
    def dtype(self):
        """numpy.dtype: the label dtype (native byte order)."""
        return self._dtype

    @property
    def axis_order(self):
        """str: index order of the slabs, "xyz" or "zyx"."""
        return self._axis_order

    @property
    def next_z(self):
        """int: index of the next z-slice :meth:`add_slab` expects (``dims[2]`` when complete,
        and after :meth:`finish`)."""
        if self._finished:
            return self._dims[2]
        self._check_open()
        return int(self._cpp.GetNextSlice())

    def _check_open(self):
        if self._closed is not None:
            raise RuntimeError(f"this Builder cannot be used any more: {self._closed}")

    # -- building ---------------------------------------------------------------------------
    def add_slab(self, array):
        """Add the next z-slices.

        Parameters
        ----------
        array : numpy.ndarray
            The next ``nz >= 1`` z-slices: shape ``(nx, ny, nz)`` for axis order "xyz",
            ``(nz, ny, nx)`` for "zyx"; the builder's dtype, either byte order, any memory
            layout. It is not kept after the call.

        Raises
        ------
        TypeError
            The array's dtype is not the builder's (or it is a masked array).
        ValueError
            The array is not 3D, its x/y size is not the volume's, or it has more slices than
            are missing.
        RuntimeError
            The builder was finished (or closed).

        Notes
        -----
        The builder reads x fastest: a Fortran-ordered ``(nx, ny, n)`` slab, or a C-ordered
        ``(n, ny, nx)`` one with ``axis_order="zyx"``, is read in place; any other layout is
        copied once, for the duration of the call. Slices that do not complete a 16-slice slab
        are copied into the builder's one-slab buffer until the next call completes it.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> builder = vtksvdag.Builder((4, 4, 3), np.uint8)
        >>> builder.add_slab(np.zeros((4, 4, 2), np.uint8))
        >>> builder.next_z
        2
        """
        self._check_open()
        if isinstance(array, np.ma.MaskedArray):
            raise TypeError(
                "a masked array cannot be compressed as it is: fill the masked voxels first, "
                "e.g. array.filled(background)"
            )
        array = np.asarray(array)
        try:
            dtype = check_label_dtype(array.dtype, "slab")
        except TypeError as e:
            raise TypeError(f"{e} The builder's dtype is {self._dtype}.") from None
        if dtype != self._dtype:
            raise TypeError(
                f"the slab has dtype {array.dtype}, but the builder's dtype is {self._dtype}; "
                f"convert it (array.astype(np.{self._dtype.name})) if its values fit"
            )
        nx, ny, nz = self._dims
        expected = f"(nx, ny, n) = ({nx}, {ny}, n)" if self._axis_order == "xyz" else \
            f"(n, ny, nx) = (n, {ny}, {nx})"
        if array.ndim != 3:
            raise ValueError(
                f"a slab must be a 3D array of shape {expected} for axis_order "
                f"{self._axis_order!r}, not {array.ndim}D with shape {array.shape}"
            )
        xyz = array if self._axis_order == "xyz" else array.transpose(2, 1, 0)
        if xyz.shape[:2] != (nx, ny) or xyz.shape[2] < 1:
            raise ValueError(
                f"the slab has shape {array.shape}; axis_order {self._axis_order!r} of a "
                f"{nx} x {ny} x {nz} volume needs {expected} with n >= 1"
            )
        next_z = int(self._cpp.GetNextSlice())
        count = xyz.shape[2]
        if count > nz - next_z:
            raise ValueError(
                f"too many slices: {count} from z = {next_z}, but the volume has {nz} slices "
                f"({nz - next_z} missing)"
            )
        start = time.perf_counter()
        # x fastest, as the C++ builder reads it: a view for a Fortran-ordered [x, y, z] (or
        # C-ordered [z, y, x]) slab, one transient copy otherwise.
        flat = np.ravel(xyz, order="F")
        if flat.dtype != self._dtype:
            flat = flat.astype(self._dtype)  # bool -> uint8, big-endian -> native: by value
        values = numpy_to_vtk(flat, deep=False)
        with vtk_errors_raised(self._cpp, ValueError):
            ok = self._cpp.AddSlab(values, next_z, count)
        self._seconds += time.perf_counter() - start
        if not self._cpp.IsInitialized():
            # A failure inside the core discards the volume (see the C++ class).
            self._closed = "compressing a slab failed"
        if not ok:
            raise ValueError("cannot add the slices")

    def add_volume(self, volume):
        """Add the next z-slices as an already compressed volume.

        ``volume`` must have been compressed from the next ``volume.dims[2]`` z-slices with the
        same dtype, background and excluded labels (by another :class:`Builder`, on another
        process or machine: :func:`vtksvdag.build_distributed` merges its parts this way).
        The result is then the same, byte for byte, as adding those slices with
        :meth:`add_slab`. Its spacing, origin and direction are not used.

        Parameters
        ----------
        volume : SegmentationVolume
            The compressed slices. A volume whose depth is not a multiple of 16 must be the
            last one.

        Raises
        ------
        TypeError
            ``volume`` is not a SegmentationVolume.
        ValueError
            Its x/y size, dtype or background is not the builder's, it holds a label the
            builder excludes, it does not fit the slices missing, or the slices added so far
            do not end on a multiple of 16.
        RuntimeError
            The builder was finished (or closed).

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> labels = np.arange(4 * 4 * 20, dtype=np.uint8).reshape(4, 4, 20) % 3
        >>> builder = vtksvdag.Builder((4, 4, 20), np.uint8)
        >>> builder.add_volume(vtksvdag.from_numpy(labels[:, :, :16]))
        >>> builder.add_slab(labels[:, :, 16:])
        >>> builder.finish().to_bytes() == vtksvdag.from_numpy(labels).to_bytes()
        True
        """
        self._check_open()
        if not isinstance(volume, SegmentationVolume):
            raise TypeError(f"volume must be a SegmentationVolume, not {type(volume).__name__}")
        if volume.dtype != self._dtype:
            raise ValueError(
                f"the volume has dtype {volume.dtype}, but the builder's dtype is {self._dtype}"
            )
        start = time.perf_counter()
        with vtk_errors_raised(self._cpp, ValueError):
            ok = self._cpp.AddVolume(volume.dataobject)
        self._seconds += time.perf_counter() - start
        if not self._cpp.IsInitialized():
            self._closed = "appending a volume failed"
        if not ok:
            raise ValueError("cannot add the volume")

    def finish(self):
        """Compress what remains and return the volume.

        Returns
        -------
        SegmentationVolume
            The compressed volume; ``build_seconds`` holds the time spent in :meth:`add_slab`
            and here.

        Raises
        ------
        ValueError
            Slices are missing (the builder stays usable: add them and finish again), or the
            volume cannot be compressed.
        RuntimeError
            The builder was already finished (or closed).

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> builder = vtksvdag.Builder((4, 4, 1), np.uint8)
        >>> builder.add_slab(np.eye(4, dtype=np.uint8)[:, :, None])
        >>> builder.finish().labels
        array([1], dtype=uint8)
        """
        self._check_open()
        next_z, nz = int(self._cpp.GetNextSlice()), self._dims[2]
        if next_z != nz:
            raise ValueError(
                f"cannot finish: {nz - next_z} of {nz} slices are missing (next slice z = {next_z})"
            )
        start = time.perf_counter()
        output = vtkSegmentationSVDAG()
        with vtk_errors_raised(self._cpp, ValueError):
            ok = self._cpp.Finish(output)
        self._seconds += time.perf_counter() - start
        self._closed = "it was finished"
        self._finished = bool(ok)
        if not ok or not output.HasVolume():
            raise ValueError("cannot compress the label volume")
        return SegmentationVolume(output, build_seconds=self._seconds)

    def close(self):
        """Release the builder's memory; it cannot be used afterwards. Idempotent."""
        if self._closed is None:
            self._closed = "it was closed"
        self._cpp = None

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False

    def __repr__(self):
        nx, ny, nz = self._dims
        state = f"next_z={self._cpp.GetNextSlice()}" if self._closed is None else "closed"
        return f"Builder({nx}x{ny}x{nz} {self._dtype}, axis_order={self._axis_order!r}, {state})"
