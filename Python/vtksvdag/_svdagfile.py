"""Writing the ``.svdag`` file format (what :meth:`SegmentationVolume.save` calls).

Kept apart from ``fileio`` (which builds SegmentationVolumes) so that ``volume`` imports it at
the top without an import cycle.
"""
import contextlib
import numbers
import os

import numpy as np

from ._vtkrun import run_algorithm


#: zstd levels the writer takes (vtkSegmentationSVDAGWriter would clamp others silently).
COMPRESSION_LEVELS = range(0, 23)


def check_compression_level(level):
    """Return ``level`` as an int, or raise TypeError / ValueError naming the range 0..22."""
    if not isinstance(level, (numbers.Integral, np.integer)) or isinstance(level, (bool, np.bool_)):
        raise TypeError(f"compression_level must be an integer, not {level!r}")
    level = int(level)
    if level not in COMPRESSION_LEVELS:
        raise ValueError(
            f"compression_level must be in {COMPRESSION_LEVELS.start}..{COMPRESSION_LEVELS.stop - 1} "
            f"(0 stores the sections uncompressed, 1..22 are zstd levels), not {level}"
        )
    return level


def svdag_output_path(path):
    """``path`` as a str; ValueError unless it ends in ``.svdag`` (the only format written)."""
    try:
        path = os.fsdecode(path)
    except TypeError:
        raise TypeError(f"path must be a str, bytes or os.PathLike, not {type(path).__name__}") from None
    if not path.lower().endswith(".svdag"):
        suffix = os.path.splitext(path)[1]
        found = f"the suffix {suffix!r}" if suffix else "no suffix"
        raise ValueError(
            f"cannot write {path!r}: it has {found}, but the file written is in the .svdag format; "
            "name it with the suffix '.svdag' (to write a NRRD, VTI or .npy label volume, decode "
            "it with 'vtksvdag decompress' or vtksvdag.export.write_label_volume)"
        )
    return path


def write_svdag(volume, path, compression_level=3, progress=None):
    """Write ``volume`` (a SegmentationVolume) to the ``.svdag`` file ``path``.

    See :meth:`SegmentationVolume.save`.
    """
    from .vtkSVDAGIO import vtkSegmentationSVDAGWriter

    path = svdag_output_path(path)
    level = check_compression_level(compression_level)
    writer = vtkSegmentationSVDAGWriter()
    writer.SetInputData(volume.dataobject)
    writer.SetFileName(path)
    writer.SetCompressionLevel(level)
    existed = os.path.lexists(path)
    try:
        run_algorithm(writer, action="Write", progress=progress, error=OSError, what=path)
    except BaseException:
        # A file started here and not finished (progress raised, the disk filled up) must not be
        # left behind looking like a result.
        if not existed and os.path.isfile(path):
            with contextlib.suppress(OSError):
                os.remove(path)
        raise
