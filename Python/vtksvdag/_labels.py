"""Label dtypes and label values: checks shared by every way of building a volume.

The C++ classes take label values (background, excluded labels) as 64-bit signed integers that
they reinterpret in the volume's scalar type. Python callers pass plain integers in the volume's
own type (a uint64 label above 2**63 included); this module checks them and converts them to
that 64-bit pattern.
"""
import numbers

import numpy as np
from vtkmodules.util.numpy_support import get_numpy_array_type

_INT64 = np.iinfo(np.int64)
_UINT64 = np.iinfo(np.uint64)


def check_label_dtype(dtype, what="label array"):
    """Return the integer dtype labels are stored as, or raise TypeError.

    ``bool`` is accepted and stored as ``uint8`` (a mask is a volume with the single label 1).
    """
    dtype = np.dtype(dtype)
    if dtype == np.bool_:
        return np.dtype(np.uint8)
    if dtype.kind not in "iu":
        hint = (
            " Convert a label map stored as floats with array.astype(np.int32) (or another"
            " integer type) after checking that it holds whole numbers."
            if dtype.kind == "f"
            else ""
        )
        raise TypeError(
            f"the {what} has dtype {dtype}; segmentation labels must be integers "
            f"(int8..int64, uint8..uint64 or bool).{hint}"
        )
    return dtype


def numpy_dtype_of_vtk_type(vtk_type):
    """The numpy dtype of a VTK scalar type id; TypeError for types numpy cannot hold (bits)."""
    try:
        return np.dtype(get_numpy_array_type(vtk_type))
    except KeyError:
        raise TypeError(f"VTK scalar type {vtk_type} has no numpy equivalent") from None


def label_pattern(value, dtype, what="label"):
    """Check that ``value`` is a label of ``dtype`` and return it as the C++ classes take it.

    Parameters
    ----------
    value : int
        A label value (Python or numpy integer; bool counts as 0/1).
    dtype : numpy.dtype or None
        The volume's label dtype; None when unknown (a file not read yet): then any value
        that fits int64 or uint64 is accepted.
    what : str
        The argument's name, for error messages.

    Returns
    -------
    int
        The value's bit pattern as a signed 64-bit integer.
    """
    if not isinstance(value, (numbers.Integral, np.integer)):
        raise TypeError(f"{what} must be an integer, not {type(value).__name__} ({value!r})")
    value = int(value)
    if dtype is None:
        low, high = _INT64.min, _UINT64.max
        type_name = "a 64-bit integer"
    else:
        info = np.iinfo(dtype)
        low, high = info.min, info.max
        type_name = f"dtype {np.dtype(dtype)}"
    if not low <= value <= high:
        raise ValueError(f"{what} {value} is out of range for {type_name} [{low}, {high}]")
    return value - (1 << 64) if value > _INT64.max else value


def label_patterns(values, dtype, what="excluded label"):
    """:func:`label_pattern` for each of ``values`` (an iterable of integers, or one integer)."""
    if isinstance(values, (numbers.Integral, np.integer)):
        values = [values]
    return [label_pattern(v, dtype, what) for v in np.asarray(values, dtype=object).ravel()]
