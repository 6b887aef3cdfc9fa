"""Writing the ``.svdag`` file format (what :meth:`SegmentationVolume.save` calls).

Kept apart from ``fileio`` (which builds SegmentationVolumes) so that ``volume`` imports it at
the top without an import cycle.
"""
import os

import numpy as np

from ._vtkrun import run_algorithm


def write_svdag(volume, path, compression_level=3, progress=None):
    """Write ``volume`` (a SegmentationVolume) to the ``.svdag`` file ``path``.

    See :meth:`SegmentationVolume.save`.
    """
    from .vtkSVDAGIO import vtkSegmentationSVDAGWriter

    if not isinstance(compression_level, (int, np.integer)) or isinstance(compression_level, bool):
        raise TypeError(f"compression_level must be an integer, not {compression_level!r}")
    writer = vtkSegmentationSVDAGWriter()
    writer.SetInputData(volume.dataobject)
    writer.SetFileName(os.fspath(path))
    writer.SetCompressionLevel(int(compression_level))
    run_algorithm(writer, action="Write", progress=progress, error=OSError, what=os.fspath(path))
