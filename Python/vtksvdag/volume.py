"""`SegmentationVolume`: the Python face of a compressed segmentation (vtkSegmentationSVDAG)."""
import numbers

import numpy as np
from vtkmodules.util.numpy_support import vtk_to_numpy
from vtkmodules.vtkCommonDataModel import vtkImageData

from ._labels import numpy_dtype_of_vtk_type
from ._svdagfile import write_svdag
from ._vtkrun import run_algorithm
from .vtkSVDAGCore import vtkSegmentationSVDAG, vtkSegmentationSVDAGToImageData

_AXIS_ORDERS = ("xyz", "zyx")


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

    def __init__(self, dataobject, *, build_seconds=None, load_seconds=None):
        if not isinstance(dataobject, vtkSegmentationSVDAG):
            raise TypeError(f"expected a vtkSegmentationSVDAG, not {type(dataobject).__name__}")
        if not dataobject.HasVolume():
            raise ValueError("the vtkSegmentationSVDAG holds no compressed volume")
        self._obj = dataobject
        self.build_seconds = build_seconds
        self.load_seconds = load_seconds
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

    def to_numpy(self, axis_order="xyz", progress=None):
        """Decode losslessly into a numpy array of :attr:`dtype`.

        Parameters
        ----------
        axis_order : {"xyz", "zyx"}, default: "xyz"
            "xyz": shape ``(nx, ny, nz)``, indexed ``[x, y, z]`` (Fortran-ordered: a view of the
            decoded VTK buffer, no copy). "zyx": shape ``(nz, ny, nx)``, C-ordered, as
            ``nrrd.read(..., index_order="C")`` returns.
        progress : callable, optional
            Called with the decoding progress in [0, 1].

        Returns
        -------
        numpy.ndarray
            The label volume.

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
        """
        check_axis_order(axis_order)
        image = self.to_image(progress=progress)
        flat = vtk_to_numpy(image.GetPointData().GetScalars())  # x fastest; keeps the buffer alive
        if flat.dtype != self._dtype:  # same width, other spelling (e.g. VTK_LONG for int64)
            flat = flat.view(self._dtype)
        dims = self.dims
        if axis_order == "xyz":
            return flat.reshape(dims, order="F")
        return flat.reshape(dims[::-1])

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
            ``blocks``, ``dag_nodes`` (= ``root_nodes + mid_nodes + leaves``, unique nodes),
            ``bytes_blocks``, ``bytes_dag``, ``bytes_labels``, ``bytes_total`` (the sum: what
            a renderer holds besides its BVH), ``raw_bytes_32`` (voxels * 4),
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
    def save(self, path, compression_level=3, progress=None):
        """Write the compressed volume to a ``.svdag`` file.

        Parameters
        ----------
        path : str, bytes or os.PathLike
            Output file name; it must end in ``.svdag``.
        compression_level : int, default: 3
            zstd compression level of the file's sections, 1 (fastest) to 22 (smallest); 0
            stores them uncompressed.
        progress : callable, optional
            Called with the writing progress in [0, 1]; an exception it raises is raised from
            here (and a file this call created is removed).

        Raises
        ------
        TypeError
            ``compression_level`` is not an integer.
        ValueError
            ``path`` does not end in ``.svdag``, or ``compression_level`` is not in 0..22.
        OSError
            The file cannot be written.

        Examples
        --------
        >>> import numpy as np, vtksvdag
        >>> volume = vtksvdag.from_numpy(np.eye(8, dtype=np.uint8)[:, :, None])
        >>> volume.save("eye.svdag")  # doctest: +SKIP
        """
        write_svdag(self, path, compression_level=compression_level, progress=progress)

    def __repr__(self):
        s = self.stats()
        dims = "x".join(str(d) for d in s["dims"])
        return (
            f"SegmentationVolume({dims} {s['dtype']}, {s['labels']} labels, "
            f"{s['blocks']} blocks, {s['dag_nodes']} DAG nodes, {s['bytes_total']} bytes, "
            f"{s['bits_per_voxel']:.3f} bits/voxel)"
        )
