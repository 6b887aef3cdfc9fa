"""Files: read label volumes and ``.svdag`` files, write ``.svdag`` files."""
import os
import time

import numpy as np

from ._labels import (
    LabelRangeError, label_list, label_pattern, label_patterns, numpy_dtype_of_vtk_type,
)
from ._vtkrun import run_algorithm
from .volume import SegmentationVolume

def _check_input_file(path):
    try:
        path = os.fsdecode(path)  # str, bytes or os.PathLike
    except TypeError:
        raise TypeError(f"path must be a str, bytes or os.PathLike, not {type(path).__name__}") from None
    if not os.path.exists(path):
        raise FileNotFoundError(2, "No such file or directory", path)
    if os.path.isdir(path):
        raise IsADirectoryError(21, "Is a directory", path)
    return path


def read(path, background=0, exclude=(), dataset=None, progress=None):
    """Read a label volume file, or a compressed ``.svdag`` file, as a SegmentationVolume.

    Label volume files (NRRD ``.nrrd``/``.nhdr`` including gzip encoding, MetaImage
    ``.mha``/``.mhd``, VTK ``.vti``, NIfTI ``.nii``/``.nii.gz``, TIFF ``.tif``, HDF5 ``.h5``)
    are read and compressed in one streaming pass by ``vtkSegmentationVolumeReader``. A
    ``.npy`` file is taken as an integer array indexed ``[x, y, z]`` (as ``vtksvdag
    decompress`` writes it), with unit spacing.

    Parameters
    ----------
    path : str, bytes or os.PathLike
        The file.
    background : int, default: 0
        Label value that is not stored; it must fit the file's label dtype. A ``.svdag`` file
        whose own background differs is compressed again with this one.
    exclude : sequence of int, default: ()
        Labels left out; they decode as background (each must fit the file's label dtype).
    dataset : str, optional
        Name of the dataset inside an HDF5 file (an error for other files).
    progress : callable, optional
        Called with the reading progress in [0, 1]; an exception it raises stops the reading
        and is raised from here.

    Returns
    -------
    SegmentationVolume
        ``load_seconds`` is set for ``.svdag`` files; otherwise ``build_seconds`` holds the time
        of reading and compressing (one streaming pass, they cannot be timed apart).

    Raises
    ------
    FileNotFoundError
        The file does not exist.
    OSError
        The file cannot be read (unknown format, truncated, corrupt).
    ValueError
        The file holds no integer label volume, ``background`` or an excluded label does not
        fit the file's dtype, or ``dataset`` is given for a file that is not HDF5.

    Examples
    --------
    >>> import vtksvdag
    >>> volume = vtksvdag.read("fib25_64.nrrd")  # doctest: +SKIP
    >>> volume.dims  # doctest: +SKIP
    (64, 64, 64)
    """
    path = _check_input_file(path)
    exclude = label_list(exclude)  # a generator is read once
    if dataset is not None and not isinstance(dataset, str):
        raise TypeError(f"dataset must be a str (an HDF5 dataset path), not {dataset!r}")
    if path.lower().endswith(".npy"):
        from .build import from_numpy

        if dataset is not None:
            raise ValueError(f"{path}: dataset={dataset!r} is only for HDF5 files, not .npy")

        try:
            array = np.load(path, mmap_mode="r", allow_pickle=False)
        except ValueError as e:
            raise OSError(f"{path}: not a readable .npy array ({e})") from None
        return from_numpy(array, background=background, exclude=exclude, progress=progress)

    from .vtkSVDAGIO import vtkSegmentationVolumeReader

    reader = vtkSegmentationVolumeReader()
    reader.SetFileName(path)
    reader.SetBackgroundLabel(label_pattern(background, None, "background"))
    for value in label_patterns(exclude, None):
        reader.AddExcludedLabel(value)
    if dataset is not None:
        reader.SetDatasetName(dataset)
    start = time.perf_counter()
    run_algorithm(reader, progress=progress, error=ValueError, what=path)
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
    return SegmentationVolume(output, build_seconds=seconds)
