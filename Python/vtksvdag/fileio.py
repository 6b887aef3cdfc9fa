"""Files: read label volumes and ``.svdag`` files, write ``.svdag`` files."""
import os
import time
import warnings

import numpy as np

from ._labels import (
    EXACT_CAST_REFUSAL, FloatLabelsError, LabelRangeError, check_cast, label_list, label_pattern,
    label_patterns, numpy_dtype_of_vtk_type,
)
from ._options import keywords_checked
from ._svdagfile import dataobject_from_bytes
from ._vtkrun import run_algorithm
from .volume import SegmentationVolume


def from_bytes(data):
    """Load a volume from the bytes of a ``.svdag`` file.

    The inverse of :meth:`SegmentationVolume.to_bytes`: the bytes are checked as a file is
    (checksums, structure), so corrupt or truncated data raises rather than loading.

    Parameters
    ----------
    data : bytes-like
        The bytes of a ``.svdag`` file (bytes, bytearray, memoryview or a uint8 array).

    Returns
    -------
    SegmentationVolume

    Raises
    ------
    TypeError
        ``data`` is not bytes-like.
    OSError
        The bytes are not a valid ``.svdag`` file (the message says which part is wrong).

    Examples
    --------
    >>> import numpy as np, vtksvdag
    >>> volume = vtksvdag.from_numpy(np.eye(8, dtype=np.uint8)[:, :, None])
    >>> copy = vtksvdag.from_bytes(volume.to_bytes())
    >>> np.array_equal(copy.to_numpy(), volume.to_numpy())
    True
    """
    return SegmentationVolume(dataobject_from_bytes(data))


# The start of the C++ readers' message for float (or other non-integer) voxels
# (svdagThrowNotIntegerLabels in IO/svdagSlabSource.cxx; Testing/Python/test_reader_formats.py
# pins it): the reader reports it with the file-format error code, which would be an OSError.
_NOT_INTEGER_LABELS = "label volumes need integer scalars"


class NotAStoreError(IsADirectoryError, ValueError):
    """``read(directory)`` where the directory holds no store :func:`vtksvdag.read` knows: the
    IsADirectoryError it always was, and a ValueError about the ``path`` argument."""


def _not_a_store(path):
    from .stores import LOOKED_FOR

    return NotAStoreError(
        21, f"Is a directory, and no chunked store that read() knows: path must be a label "
        f"volume file, or a directory holding one of: {'; '.join(LOOKED_FOR)}", path)


def _check_input_file(path):
    try:
        path = os.fsdecode(path)  # str, bytes or os.PathLike
    except TypeError:
        raise TypeError(f"path must be a str, bytes or os.PathLike, not {type(path).__name__}") from None
    if not os.path.exists(path):
        raise FileNotFoundError(2, "No such file or directory", path)
    if os.path.isdir(path):
        raise _not_a_store(path)
    return path


def _chunked_store(path, dataset):
    """(location, kind) when ``path`` is a URL or a directory holding a chunked store (see
    vtksvdag.stores), else None (a file, or a directory that read() reports)."""
    from . import stores

    if stores.is_url(path):
        location, kind = stores.find_store(path, dataset)
        if kind is None:
            if location.local is not None and not os.path.exists(location.local):
                raise FileNotFoundError(2, "No such file or directory", location.text)
            raise OSError(f"{location.text}: no Zarr, N5 or neuroglancer precomputed store there")
        return location, kind
    try:
        text = os.fsdecode(path)
    except TypeError:
        return None  # _check_input_file names the type
    if not os.path.isdir(text):
        return None
    location, kind = stores.find_store(text, dataset)
    if kind is None:
        if dataset is not None and os.path.isdir(location.local):
            raise _not_a_store(location.text)
        return None  # IsADirectoryError from _check_input_file
    return location, kind


def check_cache_bytes(cache_bytes):
    """The chunk cache bound for tensorstore: None (chosen per store, see
    stores.open_for_reading), else an int >= 0."""
    if cache_bytes is None:
        return None
    if isinstance(cache_bytes, bool) or not isinstance(cache_bytes, (int, np.integer)) or cache_bytes < 0:
        raise ValueError(f"cache_bytes must be an integer >= 0 (bytes), not {cache_bytes!r}")
    return int(cache_bytes)


@keywords_checked
def read(path, background=0, exclude=(), dataset=None, progress=None, *, scale=None,
         axis_order=None, cache_bytes=None, cast=None):
    """Read a label volume file, a chunked store, or a compressed ``.svdag`` file, as a
    SegmentationVolume.

    Label volume files (NRRD ``.nrrd``/``.nhdr`` including gzip encoding, MetaImage
    ``.mha``/``.mhd``, VTK ``.vti``, NIfTI ``.nii``/``.nii.gz``, TIFF ``.tif``, HDF5 ``.h5``)
    are read and compressed in one streaming pass by ``vtkSegmentationVolumeReader``. A
    ``.npy`` file is taken as an integer array indexed ``[x, y, z]`` (as ``vtksvdag
    decompress`` writes it), with unit spacing.

    A directory (or a ``file://``, ``gs://``, ``s3://``, ``http(s)://`` URL) holding a chunked
    store is opened with tensorstore and compressed slab by slab (z-slabs of 16·k slices,
    tensorstore's chunk cache bounded), never read whole: a Zarr v2 (``.zarray``) or v3
    (``zarr.json``) array, an OME-Zarr multiscale group, an N5 array (``attributes.json``) or
    a neuroglancer precomputed volume (``info``); see :mod:`vtksvdag.stores`. Zarr arrays are
    taken as (z, y, x), x fastest, unless OME-Zarr ``axes`` say otherwise; N5 and precomputed
    as (x, y, z) (precomputed's channel must be 1). Spacing and origin come from OME-Zarr's
    ``scale``/``translation``, precomputed's ``resolution``/``voxel_offset`` (times the
    resolution) and N5's ``resolution``/``pixelResolution``. Only local stores and ``file://``
    URLs are tested; remote URLs are passed to tensorstore untested.

    Parameters
    ----------
    path : str, bytes or os.PathLike
        The file, store directory or store URL.
    background : int, default: 0
        Label value that is not stored; it must fit the file's label dtype. A ``.svdag`` file
        whose own background differs is compressed again with this one.
    exclude : sequence of int, default: ()
        Labels left out; they decode as background (each must fit the file's label dtype).
    dataset : str, optional
        Name of the dataset inside an HDF5 file, or the path of the array (or OME-Zarr group)
        inside a chunked store's directory (an error for other files).
    progress : callable, optional
        Called with the reading progress in [0, 1]; an exception it raises stops the reading
        and is raised from here.
    scale : int, optional
        Chunked stores only: the index of the OME-Zarr or precomputed scale to read (0, the
        default, is full resolution); a plain array has the one scale 0.
    axis_order : {"zyx", "xyz"}, optional
        Chunked stores only: the order of the store's spatial dimensions, overriding the
        conventions above.
    cache_bytes : int, optional
        Chunked stores only: the bound of tensorstore's chunk cache in bytes. By default there
        is none where the slabs read keep to the store's chunks along z (each chunk is then
        read once), and 256 MiB where they do not.
    cast : {None, "exact"}, default: None
        Float voxels (float32 or float64): ``None`` refuses them (FloatLabelsError, a
        ValueError); ``"exact"`` accepts them when every value is finite and a whole number,
        stored as the narrowest integer dtype that holds them all (unsigned when none is
        negative; see :func:`from_numpy`). Works for every format: label volume files
        (``vtkSegmentationVolumeReader.CastFloatLabels``), ``.npy`` files and chunked stores.
        Files and stores are read twice, slab by slab (a check pass, then the conversion), so
        memory stays that of a slab or two, as for integer files. Integer files are read as they
        are either way.

    Returns
    -------
    SegmentationVolume
        ``load_seconds`` is set for ``.svdag`` files; otherwise ``build_seconds`` holds the time
        of reading and compressing (one streaming pass, they cannot be timed apart).
        ``label_metadata`` holds the segment names and colors of a 3D Slicer ``.seg.nrrd``
        (its header, read with pynrrd) or an OME-Zarr label image's ``image-label`` metadata,
        as :func:`vtksvdag.read_label_table` reads them, else None; malformed metadata is
        left out with a ``UserWarning`` that says what is wrong.

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    IsADirectoryError
        ``path`` is a directory that holds no known chunked store; the message lists the stores
        looked for (it is also a ValueError).
    ImportError
        ``path`` is a chunked store and tensorstore is not installed.
    OSError
        The file cannot be read (unknown format, truncated, corrupt).
    ValueError
        The file holds float voxels (FloatLabelsError: without ``cast="exact"``, or with it a
        value that is not finite, not whole or outside every integer type: the message names
        the first one and its (x, y, z) index), the file holds no
        integer label volume, ``cast`` is not one of its values, ``background`` or an excluded label does not
        fit the file's dtype, ``dataset`` is given for a file that is not HDF5, ``scale`` or
        ``axis_order`` for a file that is no chunked store, ``scale`` is out of range, or a
        store's non-spatial axis (channel) has more than one element.

    Examples
    --------
    >>> import vtksvdag
    >>> volume = vtksvdag.read("fib25_64.nrrd")  # doctest: +SKIP
    >>> volume.dims  # doctest: +SKIP
    (64, 64, 64)
    """
    if dataset is not None and not isinstance(dataset, str):
        raise TypeError(f"dataset must be a str (an HDF5 dataset path), not {dataset!r}")
    if axis_order is not None and axis_order not in ("zyx", "xyz"):
        raise ValueError(f"axis_order must be 'zyx' or 'xyz' (or None), not {axis_order!r}")
    check_cast(cast)
    store = _chunked_store(path, dataset)
    if store is not None:
        from . import stores
        from .stores import read_store

        exclude = label_list(exclude)
        volume = read_store(*store, background=background, exclude=exclude, scale=scale,
                            axis_order=axis_order, progress=progress,
                            cache_bytes=check_cache_bytes(cache_bytes), cast=cast)
        location, kind = store
        if kind == stores.OME:
            from .labelmeta import ome_label_metadata

            volume.label_metadata = _label_metadata(ome_label_metadata,
                                                    stores.ome_attributes(location), location.text)
        return volume
    path = _check_input_file(path)
    exclude = label_list(exclude)  # a generator is read once
    for name, value in (("scale", scale), ("axis_order", axis_order), ("cache_bytes", cache_bytes)):
        if value is not None:
            raise ValueError(f"{path}: {name}={value!r} is only for chunked stores (Zarr, N5, "
                             f"neuroglancer precomputed)")
    if path.lower().endswith(".npy"):
        from .build import from_numpy

        if dataset is not None:
            raise ValueError(f"{path}: dataset={dataset!r} is only for HDF5 files, not .npy")

        try:
            array = np.load(path, mmap_mode="r", allow_pickle=False)
        except ValueError as e:
            raise OSError(f"{path}: not a readable .npy array ({e})") from None
        return from_numpy(array, background=background, exclude=exclude, progress=progress,
                          cast=cast)

    from .vtkSVDAGIO import vtkSegmentationVolumeReader

    reader = vtkSegmentationVolumeReader()
    reader.SetFileName(path)
    reader.SetBackgroundLabel(label_pattern(background, None, "background"))
    for value in label_patterns(exclude, None):
        reader.AddExcludedLabel(value)
    if dataset is not None:
        reader.SetDatasetName(dataset)
    reader.SetCastFloatLabels(cast == "exact")
    start = time.perf_counter()
    try:
        run_algorithm(reader, progress=progress, error=ValueError, what=path)
    except OSError as error:
        # The reader reports both with the file-format error code, which is an OSError.
        if EXACT_CAST_REFUSAL in str(error):
            raise FloatLabelsError(f"cast={cast!r}: {error}") from None
        if _NOT_INTEGER_LABELS not in str(error):
            raise
        hint = ("cast='exact' accepts whole-number floats" if cast is None else
                f"cast={cast!r} accepts float32 and float64 voxels only")
        raise FloatLabelsError(f"{error}; {hint}") from None
    seconds = time.perf_counter() - start
    output = reader.GetOutput()
    if output is None or not output.HasVolume():
        raise OSError(f"{path}: the reader produced no volume")
    if dataset is not None and reader.GetFileFormat() != "HDF5":
        raise ValueError(
            f"{path}: dataset={dataset!r} is only for HDF5 files, not {reader.GetFileFormat()}"
        )
    # The reader takes label values as 64-bit patterns and learns the dtype only from the file:
    # 300 would become 44 in a uint8 volume. Check them against the dtype read (the volume built
    # with a wrapped value is thrown away).
    dtype = numpy_dtype_of_vtk_type(output.GetLabelScalarType())
    try:
        label_pattern(background, dtype, "background")
        label_patterns(exclude, dtype)
    except LabelRangeError as e:
        raise LabelRangeError(
            e.what, e.value, e.low, e.high, e.type_name, f" (the labels of {path})"
        ) from None
    # The reader detects formats by content, so ask it rather than trusting the suffix.
    if reader.GetFileFormat() == "SVDAG":
        return SegmentationVolume(output, load_seconds=seconds)
    volume = SegmentationVolume(output, build_seconds=seconds)
    if reader.GetFileFormat() == "NRRD":
        from .labelmeta import nrrd_label_metadata

        volume.label_metadata = _label_metadata(nrrd_label_metadata, path)  # a .seg.nrrd's segments
    return volume


def _label_metadata(read, *args):
    """The label metadata of a file :func:`read` read, or None. Malformed metadata is warned
    about and left out rather than raised: the volume itself was read correctly."""
    try:
        return read(*args)
    except (ValueError, ImportError) as error:  # ImportError: pynrrd missing
        warnings.warn(f"the label metadata is left out: {error}", UserWarning, stacklevel=3)
        return None
