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


class LabelRangeError(ValueError):
    """A label value (background, excluded label) that the volume's dtype cannot hold.

    Attributes
    ----------
    what : str
        The argument's name ("background", "excluded label").
    value : int
        The value given.
    low, high : int
        The range of the dtype.
    type_name : str
        "dtype uint8" (or "a 64-bit integer" when the dtype is not known yet).
    where : str
        Appended to the message, e.g. " (the labels of x.nrrd)".
    """

    def __init__(self, what, value, low, high, type_name, where=""):
        self.what, self.value, self.low, self.high = what, value, low, high
        self.type_name, self.where = type_name, where
        super().__init__(f"{what} {value} is out of range for {type_name} [{low}, {high}]{where}")


def check_label_dtype(dtype, what="label array"):
    """Return the integer dtype labels are stored as, or raise TypeError.

    ``bool`` is accepted and stored as ``uint8`` (a mask is a volume with the single label 1).
    The dtype returned is in native byte order (``>u2`` gives ``uint16``): VTK arrays hold
    native values, so a big-endian array must be converted, never reinterpreted.
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
    return dtype.newbyteorder("=")


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
        raise LabelRangeError(what, value, low, high, type_name)
    return value - (1 << 64) if value > _INT64.max else value


def label_list(values, what="excluded label"):
    """``values`` (one integer, or any iterable of them: list, set, range, array, generator) as
    a list; TypeError for a string or a non-iterable. The items are checked by
    :func:`label_pattern`."""
    if values is None:
        return []
    if isinstance(values, (numbers.Integral, np.integer)):
        return [values]
    if isinstance(values, np.ndarray):
        return values.ravel().tolist() if values.dtype.kind in "iub" else list(values.ravel())
    if isinstance(values, (str, bytes)):
        raise TypeError(f"{what}s must be integers, not {type(values).__name__} ({values!r})")
    try:
        return list(values)
    except TypeError:
        raise TypeError(
            f"{what}s must be an integer or an iterable of integers, not "
            f"{type(values).__name__} ({values!r})"
        ) from None


def label_patterns(values, dtype, what="excluded label"):
    """:func:`label_pattern` for each of ``values`` (an iterable of integers, or one integer)."""
    return [label_pattern(v, dtype, what) for v in label_list(values, what)]
