"""`SegmentationVolume`: the Python face of a compressed segmentation (vtkSegmentationSVDAG)."""
import numbers

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkImageData

from vtkmodules.vtkCommonCore import vtkDoubleArray, vtkIdTypeArray

from ._labels import label_pattern, numpy_dtype_of_vtk_type
from ._svdagfile import DEFAULT_FORMAT_VERSION, dataobject_from_bytes, svdag_bytes, write_svdag
from ._vtkrun import run_algorithm, vtk_errors_raised
from .vtkSVDAGCore import (
    vtkSegmentationSVDAG,
    vtkSegmentationSVDAGSlice,
    vtkSegmentationSVDAGToImageData,
)

_AXIS_ORDERS = ("xyz", "zyx")
_AXES = {"x": 0, "y": 1, "z": 2, 0: 0, 1: 1, 2: 2}


def _is_int(value):
    return isinstance(value, (numbers.Integral, np.integer)) and not isinstance(value, (bool, np.bool_))


def check_axis(axis):
    """0, 1 or 2 from "x"/"y"/"z" or 0/1/2; ValueError otherwise."""
    key = axis.lower() if isinstance(axis, str) else axis
    if isinstance(key, (bool, np.bool_)) or not (isinstance(key, str) or _is_int(key)) or key not in _AXES:
        raise ValueError(f"axis must be 'x', 'y', 'z' or 0, 1, 2, not {axis!r}")
    return _AXES[key]


def _vector3(value, what):
    """Three finite floats, or ValueError."""
    try:
        v = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"{what} must be 3 numbers, not {value!r}") from None
    if v.shape != (3,) or not np.all(np.isfinite(v)):
        raise ValueError(f"{what} must be 3 finite numbers, not {value!r}")
    return v


def check_axis_order(axis_order):
    """Raise ValueError unless ``axis_order`` is "xyz" or "zyx"."""
    if axis_order not in _AXIS_ORDERS:
        raise ValueError(f"axis_order must be 'xyz' or 'zyx', not {axis_order!r}")
    return axis_order


class SegmentationVolume:
    """A segmentation (label) volume compressed losslessly into blocks and a shared SVDAG.

    Make one with :func:`vtksvdag.from_numpy`, :func:`vtksvdag.from_image` or
    :func:`vtksvdag.read`; it is immutable. Arrays are indexed ``[x, y, z]`` unless an
    ``axis_order="zyx"`` argument says otherwise.

    Parameters
    ----------
    dataobject : vtkSegmentationSVDAG
        A built compressed volume (the output of a vtkSVDAG algorithm).
    build_seconds : float, optional
        Wall time the compression took, when known.
    load_seconds : float, optional
        Wall time reading an already compressed ``.svdag`` file took.
    label_metadata : pandas.DataFrame, optional
        Names, colors and other metadata of the labels, as
        :func:`vtksvdag.read_label_table` returns them.

    Attributes
    ----------
    label_metadata : pandas.DataFrame or None
        The label metadata of the file the volume was read from (:func:`vtksvdag.read` fills
        it from a 3D Slicer ``.seg.nrrd`` header or an OME-Zarr label image's
        ``image-label``), or None. :func:`vtksvdag.add_segmentation` uses it as the attributes
        by default (names and colors). It is pickled with the volume, not saved into
        ``.svdag`` files.

    Examples
    --------
    >>> import numpy as np
    >>> import vtksvdag
    >>> labels = np.zeros((32, 32, 32), dtype=np.uint16)
    >>> labels[4:20, 8:30, 0:9] = 7
    >>> volume = vtksvdag.from_numpy(labels, spacing=(0.5, 0.5, 2.0))
    >>> volume.labels
    array([7], dtype=uint16)
    >>> int(volume.label_at(5, 9, 0))
    7
    >>> bool((volume.to_numpy() == labels).all())
    True
    """

    def __init__(self, dataobject, *, build_seconds=None, load_seconds=None, label_metadata=None):
        if not isinstance(dataobject, vtkSegmentationSVDAG):
            raise TypeError(f"expected a vtkSegmentationSVDAG, not {type(dataobject).__name__}")
        if not dataobject.HasVolume():
            raise ValueError("the vtkSegmentationSVDAG holds no compressed volume")
        self._obj = dataobject
        self.build_seconds = build_seconds
        self.load_seconds = load_seconds
        self.label_metadata = label_metadata
        self._dtype = numpy_dtype_of_vtk_type(dataobject.GetLabelScalarType())
        self._labels = None
        self._counts = None
        self._bounds = None

    # -- geometry ---------------------------------------------------------------------------
    @property
    def dataobject(self):
        """vtkSegmentationSVDAG: the wrapped VTK data object (shared, not copied)."""
        return self._obj

    @property
    def dims(self):
        """tuple of int: number of voxels along x, y and z."""
        dims = [0, 0, 0]
        self._obj.GetDimensions(dims)
        return tuple(int(d) for d in dims)

    @property
    def spacing(self):
        """tuple of float: voxel size along x, y and z."""
        spacing = [0.0, 0.0, 0.0]
        self._obj.GetSpacing(spacing)
        return tuple(spacing)

    @property
    def origin(self):
        """tuple of float: physical position of voxel (0, 0, 0)."""
        origin = [0.0, 0.0, 0.0]
        self._obj.GetOrigin(origin)
        return tuple(origin)

    @property
    def direction(self):
        """numpy.ndarray: 3x3 index-to-physical direction matrix (columns are the x, y, z axes)."""
        direction = [0.0] * 9
        self._obj.GetDirection(direction)
        return np.array(direction, dtype=float).reshape(3, 3)

    @property
    def n_voxels(self):
        """int: number of voxels of the original image."""
        return int(self._obj.GetNumberOfVoxels())

    # -- labels -----------------------------------------------------------------------------
    @property
    def dtype(self):
        """numpy.dtype: dtype of the original labels (``uint8`` for volumes built from bool)."""
        return self._dtype

    @property
    def background(self):
        """numpy scalar: the background label (not stored), in :attr:`dtype`."""
        return vtk_to_numpy(self._obj.NewBackgroundValue()).astype(self._dtype)[0]

    @property
    def labels(self):
        """numpy.ndarray: label values stored (background excluded), ascending, in :attr:`dtype`."""
        if self._labels is None:
            n = self._obj.GetNumberOfLabels()
            values = vtk_to_numpy(self._obj.NewLabelValues()) if n else np.empty(0)
            self._labels = np.array(values, dtype=self._dtype)
            self._labels.flags.writeable = False
        return self._labels

    @property
    def label_voxel_counts(self):
        """numpy.ndarray of int64: number of voxels of each label, in the order of :attr:`labels`."""
        if self._counts is None:
            n = self._obj.GetNumberOfLabels()
            self._counts = np.array([self._obj.GetLabelVoxelCount(i) for i in range(n)], dtype=np.int64)
            self._counts.flags.writeable = False
        return self._counts

    @property
    def label_bounds(self):
        """numpy.ndarray of shape (n_labels, 6): inclusive voxel bounds of each label,
        ``[xmin, xmax, ymin, ymax, zmin, zmax]``, in the order of :attr:`labels`."""
        if self._bounds is None:
            n = self._obj.GetNumberOfLabels()
            bounds = np.zeros((n, 6), dtype=np.int64)
            box = [0] * 6
            for i in range(n):
                self._obj.GetLabelBounds(i, box)
                bounds[i] = box
            bounds.flags.writeable = False
            self._bounds = bounds
        return self._bounds

    def label_at(self, i, j, k):
        """Label value at voxel index ``(i, j, k)`` (x, y, z), without decoding the volume.

        Returns
        -------
        numpy scalar
            The label in :attr:`dtype`; the background label where no label is stored.

        Parameters
        ----------
        i, j, k : int
            The voxel index along x, y and z (Python or numpy integers; no negative indices
            counted from the end).

        Raises
        ------
        TypeError
            An index is not an integer (``1.7`` is not truncated).
        IndexError
            The index is outside the volume.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> volume = vtksvdag.from_numpy(np.arange(8, dtype=np.int8).reshape(2, 2, 2))
        >>> int(volume.label_at(1, 0, 1))
        5
        """
        for name, v in zip("ijk", (i, j, k)):
            if not isinstance(v, (numbers.Integral, np.integer)) or isinstance(v, (bool, np.bool_)):
                raise TypeError(f"label_at: index {name} must be an integer, not {v!r}")
        index = tuple(int(v) for v in (i, j, k))
        dims = self.dims
        if any(not 0 <= v < d for v, d in zip(index, dims)):
            raise IndexError(f"voxel {index} is outside the volume of {dims} voxels")
        label_index = self._obj.GetLabelIndexAt(*index)
        return self.background if label_index < 0 else self.labels[label_index]

    # -- decoding ---------------------------------------------------------------------------
    def to_image(self, progress=None):
        """Decode into a new vtkImageData with point scalars "Labels" of :attr:`dtype`.

        Parameters
        ----------
        progress : callable, optional
            Called with the decoding progress in [0, 1].

        Returns
        -------
        vtkImageData
            The decoded image, with the original spacing, origin and direction.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> volume = vtksvdag.from_numpy(np.ones((3, 4, 5), dtype=np.int32), spacing=(1, 1, 2))
        >>> image = volume.to_image()
        >>> image.GetDimensions(), image.GetSpacing(), image.GetPointData().GetScalars().GetName()
        ((3, 4, 5), (1.0, 1.0, 2.0), 'Labels')
        """
        decoder = vtkSegmentationSVDAGToImageData()
        decoder.SetInputDataObject(0, self._obj)
        run_algorithm(decoder, progress=progress, what="cannot decode the volume")
        image = vtkImageData()
        image.ShallowCopy(decoder.GetOutput())
        return image

    def to_numpy(self, axis_order="xyz", progress=None, bounds=None):
        """Decode losslessly into a numpy array of :attr:`dtype`.

        Parameters
        ----------
        axis_order : {"xyz", "zyx"}, default: "xyz"
            "xyz": shape ``(nx, ny, nz)``, indexed ``[x, y, z]`` (Fortran-ordered: a view of the
            decoded VTK buffer, no copy). "zyx": shape ``(nz, ny, nx)``, C-ordered, as
            ``nrrd.read(..., index_order="C")`` returns.
        progress : callable, optional
            Called with the decoding progress in [0, 1] (whole-volume decodes only).
        bounds : sequence of 6 int, optional
            Decode only the box ``(xmin, xmax, ymin, ymax, zmin, zmax)`` of INCLUSIVE voxel
            indices (the convention of :attr:`label_bounds` and VTK extents): only the 16^3
            cells that meet the box are decoded. The result has shape
            ``(xmax - xmin + 1, ymax - ymin + 1, zmax - zmin + 1)`` (reversed for "zyx") and
            equals ``to_numpy()[xmin:xmax + 1, ymin:ymax + 1, zmin:zmax + 1]``.

        Returns
        -------
        numpy.ndarray
            The label volume (or box).

        Raises
        ------
        TypeError
            A bound is not an integer.
        ValueError
            ``bounds`` is not 6 values, or a minimum is above its maximum (an empty box).
        IndexError
            The box is not inside the volume.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> zyx = np.zeros((3, 4, 5), dtype=np.uint32)
        >>> zyx[1, 2, 3] = 9
        >>> volume = vtksvdag.from_numpy(zyx, axis_order="zyx")
        >>> volume.dims
        (5, 4, 3)
        >>> volume.to_numpy("zyx")[1, 2, 3], volume.to_numpy()[3, 2, 1]
        (9, 9)
        >>> volume.to_numpy(bounds=(3, 4, 2, 2, 0, 2))[0, 0]
        array([0, 9, 0], dtype=uint32)
        """
        check_axis_order(axis_order)
        if bounds is not None:
            box = self._check_bounds(bounds, "bounds")
            image = vtkImageData()
            with vtk_errors_raised(self._obj, ValueError):
                self._obj.DecodeExtentTo(box, image)
            return self._image_array(image, axis_order)
        image = self.to_image(progress=progress)
        return self._image_array(image, axis_order)

    def _image_array(self, image, axis_order, dtype=None):
        """The point scalars of a decoded image (of any extent) as an array in axis_order."""
        flat = vtk_to_numpy(image.GetPointData().GetScalars())  # x fastest; keeps the buffer alive
        dtype = self._dtype if dtype is None else dtype
        if flat.dtype != dtype:  # same width, other spelling (e.g. VTK_LONG for int64)
            flat = flat.view(dtype)
        dims = image.GetDimensions()
        if axis_order == "xyz":
            return flat.reshape(dims, order="F")
        return flat.reshape(dims[::-1])

    def _check_bounds(self, bounds, what):
        """bounds as a list of 6 ints inside the volume (see to_numpy for the errors)."""
        if isinstance(bounds, (str, bytes)) or not hasattr(bounds, "__len__") or len(bounds) != 6:
            raise ValueError(f"{what} must be 6 integers (xmin, xmax, ymin, ymax, zmin, zmax), "
                             f"not {bounds!r}")
        for v in bounds:
            if not _is_int(v):
                raise TypeError(f"{what} must be integers, not {v!r}")
        box = [int(v) for v in bounds]
        for a in range(3):
            if box[2 * a] > box[2 * a + 1]:
                raise ValueError(f"{what} {tuple(box)} are empty along {'xyz'[a]} (min > max)")
        dims = self.dims
        for a in range(3):
            if box[2 * a] < 0 or box[2 * a + 1] >= dims[a]:
                raise IndexError(f"{what} {tuple(box)} are not inside the volume of {dims} voxels "
                                 f"(0 .. {dims[a] - 1} along {'xyz'[a]}; inclusive bounds)")
        return box

    # -- random access ----------------------------------------------------------------------
    def slice(self, axis="z", index=None, *, as_image=False, axis_order="xyz"):
        """One axis-aligned slice, decoded from the compressed form alone.

        Only the 16^3 cells the slice crosses are decoded, and in them only the part of each
        block's occupancy tree the slice meets: a small fraction of :meth:`to_numpy`'s time.

        Parameters
        ----------
        axis : {"x", "y", "z", 0, 1, 2}, default: "z"
            The axis the slice is perpendicular to.
        index : int, optional
            Voxel index along ``axis``, 0 .. dims[axis] - 1 (no negative indices); the middle
            slice ``dims[axis] // 2`` by default.
        as_image : bool, default: False
            Return a ``pyvista.ImageData`` one voxel thick, in the volume's world geometry
            (its extent is the slice's within the volume), with point data "Labels".
        axis_order : {"xyz", "zyx"}, default: "xyz"
            Order of the two remaining axes, as in :meth:`to_numpy`: for ``axis="z"``, "xyz"
            gives shape ``(nx, ny)`` and "zyx" ``(ny, nx)``.

        Returns
        -------
        numpy.ndarray or pyvista.ImageData
            ``to_numpy(axis_order)`` with the axis removed: for "xyz", ``slice("z", k)`` equals
            ``to_numpy()[:, :, k]``.

        Raises
        ------
        ValueError
            A bad ``axis`` or ``axis_order``.
        TypeError
            ``index`` is not an integer.
        IndexError
            ``index`` is outside the volume.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> labels = np.arange(24, dtype=np.int16).reshape(2, 3, 4)
        >>> volume = vtksvdag.from_numpy(labels)
        >>> volume.slice("y", 1)
        array([[ 4,  5,  6,  7],
               [16, 17, 18, 19]], dtype=int16)
        >>> bool((volume.slice("z", 3) == labels[:, :, 3]).all())
        True
        """
        a = check_axis(axis)
        check_axis_order(axis_order)
        n = self.dims[a]
        if index is None:
            index = n // 2
        if not _is_int(index):
            raise TypeError(f"slice index must be an integer, not {index!r}")
        index = int(index)
        if not 0 <= index < n:
            raise IndexError(f"slice index {index} is outside the volume along {'xyz'[a]} "
                             f"(0 .. {n - 1})")
        slicer = vtkSegmentationSVDAGSlice()
        slicer.SetInputDataObject(0, self._obj)
        slicer.SetAxis(a)
        slicer.SetIndex(index)
        image = self._run_slicer(slicer)
        if as_image:
            import pyvista

            return pyvista.wrap(image)
        array = self._image_array(image, axis_order)
        return array.take(0, axis=a if axis_order == "xyz" else 2 - a)

    def resample_plane(self, normal, origin=None, *, shape=None, spacing=None, x_axis=None,
                       as_image=False):
        """An oblique plane through the volume, resampled nearest, from the compressed form.

        The plane is sampled on a regular grid; each sample takes the label of the voxel whose
        center is nearest (``floor(index + 0.5)`` per continuous index coordinate), samples
        outside the volume the :attr:`background`. Everything is in world coordinates (the
        volume's origin, spacing and direction apply).

        Parameters
        ----------
        normal : {"x", "y", "z"} or sequence of 3 float
            The plane normal (world); an axis name means that index axis's world direction.
        origin : sequence of 3 float, optional
            A point of the plane (world); the center of the volume by default.
        shape : (int, int), optional
            Samples ``(nu, nv)`` of the grid, centered on ``origin``. By default the grid covers
            the projection of the volume's voxel centers on the plane, from its smallest corner.
        spacing : float or (float, float), optional
            World distance between samples; the smallest voxel spacing by default.
        x_axis : sequence of 3 float, optional
            Direction of the grid's first axis u (projected on the plane). By default the
            volume axis most nearly in the plane (x for a z normal, y for an x normal). The
            second axis is ``v = normal x u``.
        as_image : bool, default: False
            Return a ``pyvista.ImageData`` (one sample thick, placed in world space: origin at
            sample (0, 0), direction matrix columns u, v, normal) with point data "Labels".

        Returns
        -------
        numpy.ndarray or pyvista.ImageData
            An array of shape ``(nu, nv)`` indexed ``[a, b]`` for the sample at
            ``image origin + a * su * u + b * sv * v``.

        Raises
        ------
        ValueError
            A zero or non-finite normal, origin or axis, an axis along the normal, a
            non-positive spacing or shape, or a grid too large for memory.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> labels = np.arange(27, dtype=np.uint8).reshape(3, 3, 3)
        >>> volume = vtksvdag.from_numpy(labels)
        >>> bool((volume.resample_plane("z", origin=(1, 1, 2)) == labels[:, :, 2]).all())
        True
        >>> # u is z here: the volume axis in the plane
        >>> volume.resample_plane((1, 1, 0), origin=(1, 1, 1), shape=(3, 1))[:, 0]
        array([12, 13, 14], dtype=uint8)
        """
        if isinstance(normal, str):
            normal = self.direction[:, check_axis(normal)]
        n = _vector3(normal, "normal")
        if not np.any(n):
            raise ValueError("the plane normal must not be (0, 0, 0)")
        if origin is None:
            dims = np.asarray(self.dims, float)
            center = (dims - 1) / 2 * np.asarray(self.spacing, float)
            origin = np.asarray(self.origin, float) + self.direction @ center
        o = _vector3(origin, "origin")
        slicer = vtkSegmentationSVDAGSlice()
        slicer.SetInputDataObject(0, self._obj)
        slicer.SetModeToOblique()
        slicer.SetPlaneNormal(*n)
        slicer.SetPlaneOrigin(*o)
        if x_axis is not None:
            u = _vector3(x_axis, "x_axis")
            if not np.any(u):
                raise ValueError("x_axis must not be (0, 0, 0)")
            slicer.SetPlaneXAxis(*u)
        if shape is not None:
            if (isinstance(shape, (str, bytes)) or not hasattr(shape, "__len__") or len(shape) != 2
                    or not all(_is_int(v) for v in shape)):
                raise ValueError(f"shape must be 2 integers (nu, nv), not {shape!r}")
            if not all(0 < int(v) < 2**31 for v in shape):
                raise ValueError(f"shape must be positive, not {tuple(shape)!r}")
            slicer.SetOutputDimensions(int(shape[0]), int(shape[1]))
        if spacing is not None:
            s = np.broadcast_to(np.asarray(spacing, dtype=float), (2,)) if np.ndim(spacing) <= 1 else None
            if s is None or not np.all(np.isfinite(s)) or np.any(s <= 0):
                raise ValueError(f"spacing must be one or two positive numbers, not {spacing!r}")
            slicer.SetOutputSpacing(float(s[0]), float(s[1]))
        image = self._run_slicer(slicer)
        if as_image:
            import pyvista

            return pyvista.wrap(image)
        return self._image_array(image, "xyz")[:, :, 0]

    def _run_slicer(self, slicer):
        run_algorithm(slicer, what="cannot slice the volume")
        image = vtkImageData()
        image.ShallowCopy(slicer.GetOutput())
        return image

    def mask(self, label_value, *, bounds=None, axis_order="xyz"):
        """Where the volume holds one label, decoded from that label's blocks alone.

        Parameters
        ----------
        label_value : int
            A label value of :attr:`dtype` (the :attr:`background` too: then the mask is where
            no label is stored). A value the volume does not hold gives an all-False mask.
        bounds : "label" or sequence of 6 int, optional
            The box the mask covers: the whole volume by default, ``"label"`` for the label's
            own inclusive bounds (:attr:`label_bounds`), or inclusive voxel bounds
            ``(xmin, xmax, ymin, ymax, zmin, zmax)`` as in :meth:`to_numpy`.
        axis_order : {"xyz", "zyx"}, default: "xyz"
            As in :meth:`to_numpy`.

        Returns
        -------
        numpy.ndarray of bool
            ``to_numpy(axis_order, bounds=...) == label_value``.

        Raises
        ------
        TypeError
            ``label_value`` or a bound is not an integer.
        ValueError
            ``label_value`` does not fit :attr:`dtype`; bad bounds (see :meth:`to_numpy`);
            ``bounds="label"`` for a value the volume does not hold.
        IndexError
            The box is not inside the volume.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> labels = np.zeros((4, 4, 4), dtype=np.uint8)
        >>> labels[1:3, 2, 0] = 5
        >>> volume = vtksvdag.from_numpy(labels)
        >>> int(volume.mask(5).sum())
        2
        >>> volume.mask(5, bounds="label").shape
        (2, 1, 1)
        """
        check_axis_order(axis_order)
        if isinstance(label_value, (bool, np.bool_)):
            raise TypeError(f"label_value must be an integer, not {label_value!r}")
        label_pattern(label_value, self._dtype, "label_value")  # type and range checks
        value = int(label_value)
        matches = np.nonzero(self.labels == np.array(value, dtype=self._dtype))[0]
        if isinstance(bounds, str):
            if bounds != "label":
                raise ValueError(f"bounds must be 'label' or 6 integers, not {bounds!r}")
            if not len(matches):
                raise ValueError(f"bounds='label': {value} is not a label of the volume")
            box = [int(b) for b in self.label_bounds[matches[0]]]
        else:
            box = self._check_bounds(bounds, "bounds") if bounds is not None else \
                [0, self.dims[0] - 1, 0, self.dims[1] - 1, 0, self.dims[2] - 1]
        if value == int(self.background):
            return self.to_numpy(axis_order, bounds=box) == self.background
        if not len(matches):
            shape = (box[1] - box[0] + 1, box[3] - box[2] + 1, box[5] - box[4] + 1)
            return np.zeros(shape if axis_order == "xyz" else shape[::-1], dtype=bool)
        image = vtkImageData()
        with vtk_errors_raised(self._obj, ValueError):
            self._obj.DecodeLabelMaskTo(int(matches[0]), box, image)
        return self._image_array(image, axis_order, dtype=np.uint8).view(bool)

    def label_table(self, attributes=None):
        """Per-label statistics as a ``pandas.DataFrame``, computed from the compressed form.

        Counts and bounds come from the label table; centroids and surface voxels are computed
        block by block, one 16-voxel layer of cells at a time (no dense decode).

        Parameters
        ----------
        attributes : pandas.DataFrame, str or os.PathLike, optional
            Extra columns per label (names, classes, ...): a DataFrame, or the path of a CSV
            file, with a ``label`` column (or an index named ``label``) of integer label
            values. It is LEFT-joined on the label value: every label of the volume is kept
            (NaN where the attributes have no row); attribute rows of labels the volume does
            not hold are left out with a ``UserWarning`` naming them.

        Returns
        -------
        pandas.DataFrame
            One row per stored label (the background is not a row), indexed by the original
            label value (index name "label", :attr:`dtype`), ascending, with columns:

            - ``voxel_count`` (int64) and ``volume`` (voxel_count times the voxel volume,
              the product of the spacing, in world units cubed);
            - ``xmin``, ``xmax``, ``ymin``, ``ymax``, ``zmin``, ``zmax``: inclusive voxel
              index bounds (int64), as :attr:`label_bounds`;
            - ``centroid_i``, ``centroid_j``, ``centroid_k``: mean voxel index of the label's
              voxels; ``centroid_x``, ``centroid_y``, ``centroid_z``: the same point in world
              coordinates (origin + direction @ (spacing * index));
            - ``surface_voxels`` (int64): voxels of the label with at least one of their 6
              face neighbours of another label (background included) or outside the volume.

            followed by the attribute columns, and ``color``: the display color each label
            is drawn with by default (an RGB tuple of floats in [0, 1], the default palette of
            ``vtkSegmentationSVDAGLabelProperties``; ``actor.label_table`` has the colors in
            effect in a plotter). Attributes with a ``color`` column keep theirs instead.

        Raises
        ------
        TypeError
            ``attributes`` is neither a DataFrame nor a path.
        FileNotFoundError
            The CSV file does not exist.
        ValueError
            No ``label`` column, non-integer or repeated labels, or attribute columns named
            like the table's own.

        Examples
        --------
        >>> import numpy as np, pandas as pd, vtksvdag
        >>> labels = np.zeros((4, 4, 4), dtype=np.uint16)
        >>> labels[0:2, 0:2, 0:2] = 3
        >>> volume = vtksvdag.from_numpy(labels, spacing=(1, 1, 2))
        >>> table = volume.label_table(pd.DataFrame({"label": [3], "name": ["cell"]}))
        >>> table.loc[3, ["voxel_count", "volume", "centroid_z", "surface_voxels", "name"]].tolist()
        [8, 16.0, 1.0, 8, 'cell']
        """
        from ._labeltable import label_table

        centroids = vtkDoubleArray()
        surface = vtkIdTypeArray()
        with vtk_errors_raised(self._obj, ValueError):
            self._obj.ComputeLabelStatistics(centroids, surface)
        n = len(self.labels)
        c = vtk_to_numpy(centroids).reshape(n, 3) if n else np.empty((0, 3))
        s = vtk_to_numpy(surface) if n else np.empty(0, dtype=np.int64)
        table = label_table(self, c, s, attributes)
        if "color" not in table.columns:
            table["color"] = self._default_colors(table.index.tolist())
        return table

    def _default_colors(self, values):
        """The display colors of ``values`` (labels of the volume) as a fresh label properties
        object gives them: the palette is defined once, in the rendering module."""
        from ._attributes import label_key
        from .vtkSVDAGRendering import vtkSegmentationSVDAGLabelProperties

        props = vtkSegmentationSVDAGLabelProperties()
        colors = []
        for value in values:
            rgb = [0.0, 0.0, 0.0]
            props.GetDisplayColor(self._obj, label_key(value, self.dtype), rgb)
            colors.append(tuple(rgb))
        return colors

    def label_adjacency(self):
        """The label pairs that touch across a voxel face (6-neighbourhood).

        Computed from the compressed form one 16-voxel layer of cells at a time (a few z-slices
        of memory, never the dense volume). The background is not a label.

        Returns
        -------
        numpy.ndarray of shape (n_pairs, 2), in :attr:`dtype`
            Label values ``[a, b]`` with ``a < b`` (in the order of :attr:`labels`), each pair
            once, sorted.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> labels = np.zeros((6, 1, 1), dtype=np.uint8)
        >>> labels[:, 0, 0] = [1, 1, 2, 0, 3, 2]
        >>> vtksvdag.from_numpy(labels).label_adjacency().tolist()
        [[1, 2], [2, 3]]
        """
        pairs = vtkIdTypeArray()
        with vtk_errors_raised(self._obj, ValueError):
            self._obj.ComputeLabelAdjacency(pairs)
        if pairs.GetNumberOfTuples() == 0:
            return np.empty((0, 2), dtype=self._dtype)
        return self.labels[vtk_to_numpy(pairs).reshape(-1, 2)]

    def encoding_statistics(self):
        """Where the compressed bytes go, level by level, and what known remedies would save.

        The levels are the block records (``blocks``) and the three node pools of the occupancy
        DAG (``roots`` 16^3, ``mids`` 8^3, ``leaves`` 4^3; see ``Module/core/svdag/Layout.h``).

        Returns
        -------
        pandas.DataFrame
            One row per level, indexed by ``level``. ``compact_bytes``: the level's bytes in
            the compact form the volume holds in memory (they sum with the label table to
            ``stats()["bytes_total"]``: leaves referenced once are inline in their mid node,
            mids referenced once chained after their root's base offset). The other columns
            describe the pooled form (every node once in its pool, as ``.svdag`` files store
            it): ``nodes``, ``bits``,
            ``bytes``, ``header_bits`` (masks, or the blocks' cell, bounds and label fields),
            ``reference_bits``, ``references`` and ``reference_width`` (the level's references
            into the next one). Skew of the references *into* the level:
            ``incoming_references``, ``referenced_once`` (nodes used once), ``max_incoming``,
            ``top1_percent_share`` and ``top10_percent_share`` (share of the references that
            the most used 1% and 10% of the nodes receive), ``reference_entropy_bits`` (bits an
            ideal static code would spend per reference, against the parent's
            ``reference_width``). Symmetry-aware sharing: ``mirror_classes`` and
            ``symmetry_classes`` (distinct nodes if nodes equal up to one of the 8 mirrors, or
            one of the 48 symmetries of the cube, were stored once; complements are shared as
            today; leaves already are stored once per symmetry class), and ``mirror_bytes``
            and ``symmetry_bytes``, the level's bytes in such a DAG (3 or 6 more bits per
            reference name the transform).

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> labels = np.zeros((16, 16, 16), dtype=np.uint8)
        >>> labels[:, :, :3] = 1      # a slab on the x = 0 side ...
        >>> labels[:, :, -3:] = 2     # ... and its mirror image
        >>> table = vtksvdag.from_numpy(labels).encoding_statistics()
        >>> int(table.loc["leaves", "nodes"])  # leaves are stored once per symmetry class
        1
        >>> int(table.loc["mids", "nodes"]), int(table.loc["mids", "mirror_classes"])
        (2, 1)
        """
        import pandas as pd
        from vtkmodules.vtkCommonDataModel import vtkTable

        table = vtkTable()
        with vtk_errors_raised(self._obj, ValueError):
            self._obj.ComputeEncodingStatistics(table)
        columns = {}
        for c in range(table.GetNumberOfColumns()):
            array = table.GetColumn(c)
            name = array.GetName()
            if name == "level":
                columns[name] = [array.GetValue(r) for r in range(array.GetNumberOfValues())]
            else:
                columns[name] = vtk_to_numpy(array).copy()
        frame = pd.DataFrame(columns).set_index("level")
        for bits in ("bits", "mirror_bits", "symmetry_bits"):
            frame.insert(frame.columns.get_loc(bits) + 1, bits.replace("bits", "bytes"),
                         (frame[bits] + 7) // 8)
        return frame

    def distinct_colors(self):
        """The default label colors: a categorical palette assigned over :meth:`label_adjacency`
        so that touching labels get clearly different colors (the C++ core's
        ``svdag::distinctLabelColors``; ``add_segmentation`` uses them when no colors are given).

        Returns
        -------
        numpy.ndarray of shape (n_labels, 3)
            Display sRGB colors in [0, 1], in the order of :attr:`labels`.
        """
        colors = vtkDoubleArray()
        with vtk_errors_raised(self._obj, ValueError):
            self._obj.ComputeDistinctLabelColors(colors)
        if colors.GetNumberOfTuples() == 0:
            return np.empty((0, 3))
        return vtk_to_numpy(colors).reshape(-1, 3).copy()

    def to_pyvista(self):
        """Decode into a ``pyvista.ImageData`` with point data "Labels".

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> grid = vtksvdag.from_numpy(np.ones((4, 5, 6), dtype=np.uint8)).to_pyvista()
        >>> grid.dimensions
        (4, 5, 6)
        """
        import pyvista

        return pyvista.wrap(self.to_image())

    # -- statistics -------------------------------------------------------------------------
    def stats(self):
        """Sizes and counts of the compressed volume.

        Returns
        -------
        dict
            ``dims`` [x, y, z], ``voxels``, ``labels`` (stored labels, background excluded),
            ``blocks``, ``dag_nodes`` (= ``root_nodes + mid_nodes + leaves``, unique nodes;
            ``leaves`` counts the 4^3 leaves stored apart, those several mid nodes share: in
            memory a leaf used once is inline in its mid node),
            ``bytes_blocks``, ``bytes_dag``, ``bytes_labels``, ``bytes_total`` (the sum, in the
            compact form held in memory: what a renderer holds besides its BVH), ``raw_bytes_32`` (voxels * 4),
            ``bits_per_voxel`` (8 * bytes_total / voxels), ``compression_ratio_32``
            (raw_bytes_32 / bytes_total), ``build_seconds`` (None when not known, e.g. for a
            volume loaded from a ``.svdag`` file), ``load_seconds`` (None unless loaded from a
            ``.svdag`` file), ``dtype`` (name), ``background``, ``spacing``, ``origin``.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> s = vtksvdag.from_numpy(np.ones((16, 16, 16), dtype=np.uint8)).stats()
        >>> s["labels"], s["blocks"], s["voxels"]
        (1, 1, 4096)
        """
        o = self._obj
        voxels = self.n_voxels
        total = int(o.GetCompressedSize())
        return {
            "dims": list(self.dims),
            "voxels": voxels,
            "labels": int(o.GetNumberOfLabels()),
            "blocks": int(o.GetNumberOfBlocks()),
            "dag_nodes": int(o.GetNumberOfDAGNodes()),
            "root_nodes": int(o.GetNumberOfRootNodes()),
            "mid_nodes": int(o.GetNumberOfMidNodes()),
            "leaves": int(o.GetNumberOfLeaves()),
            "bytes_blocks": int(o.GetBlocksMemorySize()),
            "bytes_dag": int(o.GetDAGMemorySize()),
            "bytes_labels": int(o.GetLabelTableMemorySize()),
            "bytes_total": total,
            "raw_bytes_32": voxels * 4,
            "bits_per_voxel": 8.0 * total / voxels if voxels else 0.0,
            "compression_ratio_32": voxels * 4 / total if total else None,
            "build_seconds": self.build_seconds,
            "load_seconds": self.load_seconds,
            "dtype": self._dtype.name,
            "background": int(self.background),
            "spacing": list(self.spacing),
            "origin": list(self.origin),
        }

    # -- files ------------------------------------------------------------------------------
    def save(self, path, compression_level=3, progress=None, format_version=DEFAULT_FORMAT_VERSION):
        """Write the compressed volume to a ``.svdag`` file.

        Parameters
        ----------
        path : str, bytes or os.PathLike
            Output file name; it must end in ``.svdag``.
        compression_level : int, default: 3
            Format version 2 only: zstd compression level of the file's sections, 1 (fastest)
            to 22 (smallest); 0 stores them uncompressed.
        progress : callable, optional
            Called with the writing progress in [0, 1]; an exception it raises is raised from
            here (and a file this call created is removed).
        format_version : {4, 3, 2}, default: 4
            4 writes the shared DAG as byte streams under zstd: on the shared volumes a file
            smaller than Volcanite's CSGV files, loaded in a fraction of a build's time. 3 writes the labels and occupancy
            arithmetic-coded, the smallest file (about half of 4's); reading it rebuilds the
            DAG, about a build's time. 2 writes the volume as it is in memory under zstd: a
            larger file, read by vtksvdag versions before format 3 too.

        Raises
        ------
        TypeError
            ``compression_level`` or ``format_version`` is not an integer.
        ValueError
            ``path`` does not end in ``.svdag``, ``compression_level`` is not in 0..22, or
            ``format_version`` is not 2, 3 or 4.
        OSError
            The file cannot be written.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> volume = vtksvdag.from_numpy(np.eye(8, dtype=np.uint8)[:, :, None])
        >>> volume.save("eye.svdag")  # doctest: +SKIP
        """
        write_svdag(self, path, compression_level=compression_level, progress=progress,
                    format_version=format_version)

    def to_bytes(self, compression_level=3, format_version=DEFAULT_FORMAT_VERSION):
        """The compressed volume as the bytes of a ``.svdag`` file.

        For sending a volume to another process or storing it in a database; load it back with
        :func:`vtksvdag.from_bytes`. Pickling a volume (``pickle``, ``multiprocessing``, Dask)
        goes through these bytes too, in format version 2 at compression level 1 (the fastest
        both ways, and bit-identical whatever the volume's layout).

        Parameters
        ----------
        compression_level : int, default: 3
            Format version 2 only: zstd level of the sections, 1 (fastest) to 22 (smallest); 0
            stores them uncompressed.
        format_version : {4, 3, 2}, default: 4
            As for :meth:`save`: 4 small and fast to load, 3 the smallest bytes.

        Returns
        -------
        bytes

        Raises
        ------
        TypeError
            ``compression_level`` or ``format_version`` is not an integer.
        ValueError
            ``compression_level`` is not in 0..22, or ``format_version`` is not 2, 3 or 4.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> volume = vtksvdag.from_numpy(np.eye(8, dtype=np.uint8)[:, :, None])
        >>> vtksvdag.from_bytes(volume.to_bytes()).labels
        array([1], dtype=uint8)
        """
        return svdag_bytes(self, compression_level, format_version)

    def __reduce__(self):
        # The timings and the label metadata are part of the object, not of the volume: they
        # travel as well.
        return (_unpickle, (svdag_bytes(self, 1, format_version=2), self.build_seconds, self.load_seconds,
                            self.label_metadata))

    def __repr__(self):
        s = self.stats()
        dims = "x".join(str(d) for d in s["dims"])
        return (
            f"SegmentationVolume({dims} {s['dtype']}, {s['labels']} labels, "
            f"{s['blocks']} blocks, {s['dag_nodes']} DAG nodes, {s['bytes_total']} bytes, "
            f"{s['bits_per_voxel']:.3f} bits/voxel)"
        )


def _unpickle(data, build_seconds, load_seconds, label_metadata=None):
    volume = SegmentationVolume(dataobject_from_bytes(data), label_metadata=label_metadata)
    volume.build_seconds = build_seconds
    volume.load_seconds = load_seconds
    return volume
