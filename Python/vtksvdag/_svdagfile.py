"""The ``.svdag`` format as files and bytes (what :meth:`SegmentationVolume.save`,
:meth:`SegmentationVolume.to_bytes` and :func:`vtksvdag.from_bytes` call).

Works on VTK data objects only, never on SegmentationVolume (which imports this module): the
package's imports form no cycle (Testing/Python/test_imports.py).
"""
import contextlib
import numbers
import os

import numpy as np

from ._vtkrun import run_algorithm


#: zstd levels the writer takes (vtkSegmentationSVDAGWriter would clamp others silently).
COMPRESSION_LEVELS = range(0, 23)

#: .svdag format versions the writer writes: 4, the DAG as byte streams (smaller than CSGV's
#: files, loads in a fraction of a build; the default), 3, the coded volume (the smallest file,
#: loads in about a build's time), or 2, the in-memory sections under zstd (read by readers older
#: than 3.0 too).
FORMAT_VERSIONS = (2, 3, 4)
DEFAULT_FORMAT_VERSION = 4


def _integer(value, name):
    """``value`` as an int; TypeError naming ``name`` unless it is an integer (a bool is not)."""
    if not isinstance(value, (numbers.Integral, np.integer)) or isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} must be an integer, not {value!r}")
    return int(value)


def check_compression_level(level):
    """Return ``level`` as an int, or raise TypeError / ValueError naming the range 0..22."""
    level = _integer(level, "compression_level")
    if level not in COMPRESSION_LEVELS:
        raise ValueError(
            f"compression_level must be in {COMPRESSION_LEVELS.start}..{COMPRESSION_LEVELS.stop - 1} "
            f"(0 stores the sections uncompressed, 1..22 are zstd levels), not {level}"
        )
    return level


def check_format_version(version):
    """Return ``version`` as an int, or raise TypeError / ValueError naming the versions written."""
    version = _integer(version, "format_version")
    if version not in FORMAT_VERSIONS:
        raise ValueError(
            f"format_version must be 4 (the DAG streams, the default), 3 (the coded volume, the "
            f"smallest file) or 2 (the in-memory sections, read by older readers), not {version}"
        )
    return version


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


def write_svdag(volume, path, compression_level=3, progress=None,
                format_version=DEFAULT_FORMAT_VERSION):
    """Write ``volume`` (a SegmentationVolume) to the ``.svdag`` file ``path``.

    See :meth:`SegmentationVolume.save`.
    """
    from .vtkSVDAGIO import vtkSegmentationSVDAGWriter

    path = svdag_output_path(path)
    level = check_compression_level(compression_level)
    version = check_format_version(format_version)
    writer = vtkSegmentationSVDAGWriter()
    writer.SetInputData(volume.dataobject)
    writer.SetFileName(path)
    writer.SetCompressionLevel(level)
    writer.SetFormatVersion(version)
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


#: Where the .svdag header holds the background label (a little-endian 64-bit pattern).
_BACKGROUND_OFFSET = 148


def svdag_bytes(volume, compression_level=3, format_version=DEFAULT_FORMAT_VERSION):
    """The ``.svdag`` file of ``volume`` (a SegmentationVolume) as bytes.

    See :meth:`SegmentationVolume.to_bytes`.
    """
    from vtkmodules.util.numpy_support import vtk_to_numpy

    from .vtkSVDAGIO import vtkSegmentationSVDAGWriter

    level = check_compression_level(compression_level)
    version = check_format_version(format_version)
    writer = vtkSegmentationSVDAGWriter()
    writer.SetInputData(volume.dataobject)
    writer.WriteToOutputStringOn()
    writer.SetCompressionLevel(level)
    writer.SetFormatVersion(version)
    run_algorithm(writer, action="Write", error=ValueError, what="to_bytes")
    return vtk_to_numpy(writer.GetOutputBytes()).tobytes()


def dataobject_from_bytes(data):
    """The vtkSegmentationSVDAG of the bytes of a ``.svdag`` file (:func:`vtksvdag.from_bytes`
    wraps it in a SegmentationVolume).

    Raises TypeError when ``data`` is not bytes-like, OSError when the bytes are not a valid
    ``.svdag`` file (the message says which part is wrong).
    """
    from vtkmodules.util.numpy_support import numpy_to_vtk

    from .vtkSVDAGIO import vtkSegmentationVolumeReader

    try:
        array = np.frombuffer(data, dtype=np.uint8)
    except TypeError:
        raise TypeError(f"data must be bytes-like (the bytes of a .svdag file), not "
                        f"{type(data).__name__}") from None
    if array.size == 0:
        raise OSError("from_bytes: no bytes (an empty buffer is no .svdag file)")
    bytes_array = numpy_to_vtk(array, deep=False)
    reader = vtkSegmentationVolumeReader()
    reader.ReadFromInputStringOn()
    reader.SetInputArray(bytes_array)
    # The reader re-encodes a volume whose background is not the one it is given: give it the
    # file's own (header bytes 148..155, File.h; the header's crc32 is checked all the same).
    if array.size >= _BACKGROUND_OFFSET + 8:
        background = array[_BACKGROUND_OFFSET:_BACKGROUND_OFFSET + 8].view("<i8")[0]
        reader.SetBackgroundLabel(int(background))
    run_algorithm(reader, error=OSError, what="from_bytes")
    output = reader.GetOutput()
    if output is None or not output.HasVolume():
        raise OSError("from_bytes: the reader produced no volume")
    del array  # the VTK array borrowed it until the reader was done
    return output
