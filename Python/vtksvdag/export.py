"""Write a decoded SegmentationVolume as an ordinary label volume file (NRRD, VTI or .npy)."""
import os

import numpy as np

from ._vtkrun import run_algorithm

#: Output suffixes :func:`write_label_volume` understands.
LABEL_VOLUME_SUFFIXES = (".nrrd", ".nhdr", ".vti", ".npy", ".zarr")


def label_volume_suffix(path):
    """The suffix of ``path`` that selects its format; ValueError for unsupported ones."""
    lower = os.fsdecode(path).lower().rstrip("/" + os.sep)  # a .zarr store may be "out.zarr/"
    for suffix in LABEL_VOLUME_SUFFIXES:
        if lower.endswith(suffix):
            return suffix
    raise ValueError(
        f"cannot write {os.fsdecode(path)!r}: unsupported format "
        f"(use one of {', '.join(LABEL_VOLUME_SUFFIXES)})"
    )


def _write_nrrd(volume, path):
    import nrrd

    # NRRD's "space directions" holds one vector per axis: column a of the direction
    # matrix scaled by that axis' spacing.
    directions = (volume.direction * np.asarray(volume.spacing)).T
    header = {
        "encoding": "gzip",
        "kinds": ["domain", "domain", "domain"],
        "space dimension": 3,
        "space directions": directions,
        "space origin": np.asarray(volume.origin, dtype=float),
    }
    # pynrrd writes .nhdr as a detached header next to its gzip-compressed data file.
    nrrd.write(path, volume.to_numpy("xyz"), header=header, index_order="F")


def _write_vti(volume, path, progress):
    from vtkmodules.vtkIOXML import vtkXMLImageDataWriter

    writer = vtkXMLImageDataWriter()
    writer.SetInputData(volume.to_image())
    writer.SetFileName(path)
    writer.SetDataModeToAppended()
    writer.EncodeAppendedDataOff()  # raw bytes, zlib-compressed; not base64
    writer.SetCompressorTypeToZLib()
    run_algorithm(writer, action="Write", progress=progress, error=OSError, what=path)


def write_label_volume(volume, path, progress=None):
    """Decode ``volume`` and write it to ``path``; the suffix picks the format.

    Parameters
    ----------
    volume : SegmentationVolume
        The compressed volume.
    path : str, bytes or os.PathLike
        ``.nrrd`` (gzip encoding, space directions and origin), ``.nhdr`` (detached NRRD
        header plus gzip data file), ``.vti`` (VTK XML image data, zlib) or ``.npy`` (numpy
        array indexed ``[x, y, z]``, Fortran order, the original dtype; no geometry) or
        ``.zarr`` (a new OME-Zarr 0.4 / Zarr v2 store directory, (z, y, x), written slab by
        slab with tensorstore: :func:`vtksvdag.stores.write_zarr`).
    progress : callable, optional
        Called with the writing progress in [0, 1] (VTI and Zarr only).

    Raises
    ------
    ValueError
        Unsupported suffix.
    OSError
        The file cannot be written.

    Examples
    --------
    >>> import numpy as np, vtksvdag
    >>> from vtksvdag.export import write_label_volume
    >>> volume = vtksvdag.from_numpy(np.ones((4, 4, 4), dtype=np.uint8))
    >>> write_label_volume(volume, "labels.nrrd")  # doctest: +SKIP
    """
    path = os.fsdecode(path)
    suffix = label_volume_suffix(path)
    if suffix in (".nrrd", ".nhdr"):
        _write_nrrd(volume, path)
    elif suffix == ".vti":
        _write_vti(volume, path, progress)
    elif suffix == ".zarr":
        from .stores import write_zarr

        write_zarr(volume, path, progress=progress)
    else:
        np.save(path, volume.to_numpy("xyz"), allow_pickle=False)
