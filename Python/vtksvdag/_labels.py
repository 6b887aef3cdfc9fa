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


class FloatLabelsError(ValueError, TypeError):
    """Float labels without ``cast="exact"``.

    A ValueError, as the documentation of the readers promises (the values are the problem:
    integer-valued floats are accepted with ``cast="exact"``), and a TypeError, which a float
    array was before ``cast`` existed.
    """


#: The values of the ``cast=`` option of read, from_numpy, from_image and add_segmentation.
#: None: integer labels only; "exact": floats too when every value is a whole number that an
#: integer type holds.
CASTS = (None, "exact")


def check_cast(cast):
    """``cast`` itself; ValueError naming the option and its values for anything else."""
    if not (cast is None or (isinstance(cast, str) and cast in CASTS)):
        raise ValueError(f"cast must be one of {list(CASTS)}, got {cast!r}")
    return cast


def _smallest_integer_dtype(low, high):
    """The narrowest integer dtype holding [low, high] (unsigned when low >= 0), or None."""
    kinds = ("uint8", "uint16", "uint32", "uint64") if low >= 0 else ("int8", "int16", "int32", "int64")
    for name in kinds:
        info = np.iinfo(name)
        # Python ints: a float64 bound such as 2**64 must not round to the dtype's maximum.
        if int(info.min) <= low and high <= int(info.max):
            return np.dtype(name)
    return None


def float_labels_error(dtype, what):
    """The FloatLabelsError for float labels without ``cast``."""
    return FloatLabelsError(
        f"the {what} has dtype {dtype}; segmentation labels must be integers "
        f"(int8..int64, uint8..uint64 or bool); cast='exact' accepts floats that are whole "
        f"numbers")


#: The ending of every message refusing a value with ``cast="exact"``, here and in the C++
#: readers (svdagExactCastSlabSource::RefusalEnding), which vtksvdag.read recognises it by.
EXACT_CAST_REFUSAL = "only whole numbers that an integer type holds are accepted"


class ExactCast:
    """``cast="exact"`` for a float array seen in pieces (the slabs of a store), never whole:
    :meth:`check` every piece, then :meth:`dtype`, then :meth:`convert` each piece again.
    :func:`cast_labels` is the case of one piece; svdagExactCastSlabSource (IO/) applies the
    same rule to float files.

    The rule: every value finite and whole, stored as the narrowest integer dtype holding all
    of them (unsigned when none is negative). A refusal names the first offending value in C
    order of the whole array (pieces may come in any order) and its index.
    """

    # Powers of two, exact as floats (float(2**63 - 1) would round up to 2**63).
    _BOUNDS = (-2.0**63, 2.0**63, 2.0**64)

    def __init__(self, dtype, what="label array"):
        self.float_dtype, self.what = np.dtype(dtype), what
        self.low = self.high = None
        self.not_whole = None  # (index, value): the first value not finite or not whole
        # The first value below -2**63, from 2**63 on, from 2**64 on: offenders once the range
        # says which of them no integer type holds.
        self.beyond = [None, None, None]

    @staticmethod
    def _first(current, mask, piece, offset):
        """The earlier (in C order) of ``current`` and the first True of ``mask``, if any."""
        if not mask.any():
            return current
        local = np.unravel_index(int(np.argmax(mask)), mask.shape)
        index = tuple(int(i) + int(o) for i, o in zip(local, offset))
        if current is not None and current[0] <= index:
            return current
        return index, piece[local]

    def check(self, piece, offset=None):
        """Check ``piece``, the part of the array from index ``offset`` on (default: 0s)."""
        piece = np.asarray(piece)
        offset = (0,) * piece.ndim if offset is None else offset
        if not piece.size:
            return
        # trunc of nan/inf is nan/inf: the finite mask keeps them out of `whole`.
        bad = ~(np.isfinite(piece) & (np.trunc(piece) == piece))
        self.not_whole = self._first(self.not_whole, bad, piece, offset)
        if self.not_whole is not None:
            return  # refused whatever the range: the range is not needed any more
        low, high = piece.min(), piece.max()
        self.low = low if self.low is None else min(self.low, low)
        self.high = high if self.high is None else max(self.high, high)
        below, from63, from64 = self._BOUNDS
        if low < below:
            self.beyond[0] = self._first(self.beyond[0], piece < below, piece, offset)
        if high >= from63:
            self.beyond[1] = self._first(self.beyond[1], piece >= from63, piece, offset)
            self.beyond[2] = self._first(self.beyond[2], piece >= from64, piece, offset)

    def dtype(self):
        """The integer dtype of the labels; FloatLabelsError naming the first value refused."""
        if self.not_whole is not None:
            index, value = self.not_whole
            reason = "not finite" if not np.isfinite(value) else "not a whole number"
        elif self.low is None:
            return np.dtype(np.uint8)  # an empty array
        else:
            low = int(self.low)
            dtype = _smallest_integer_dtype(low, int(self.high))
            if dtype is not None:
                return dtype
            # Below -2**63 or from 2**64 on, or, with negative values (int64 then), from 2**63 on.
            candidates = self.beyond[:2] if low < 0 else self.beyond[2:]
            index, value = min((c for c in candidates if c is not None), key=lambda c: c[0])
            reason = "outside every integer type (with the other values)"
        raise FloatLabelsError(
            f"cast='exact': the {self.what} ({self.float_dtype}) holds {value!r} at index "
            f"{index}, {reason}; {EXACT_CAST_REFUSAL}")

    def convert(self, piece):
        """``piece`` as labels of :meth:`dtype`; ValueError where a value is not one the check
        saw (the data changed in between)."""
        labels = np.asarray(piece).astype(self.dtype())
        if not np.array_equal(labels, piece):
            raise ValueError(f"the {self.what} changed while it was read: a piece holds values "
                             f"the check did not find")
        return labels


def cast_labels(array, cast, what="label array"):
    """``array`` as integer labels following ``cast`` (see CASTS): integer and bool arrays are
    returned as they are; a float array with ``cast="exact"`` becomes the narrowest integer
    dtype holding its values (unsigned when none is negative), value for value (see
    :class:`ExactCast`).

    Raises FloatLabelsError for a float array without ``cast``, and for ``cast="exact"`` when a
    value is not finite, not whole, or outside every integer type, naming the first such value
    (in C order) and its index.
    """
    check_cast(cast)
    array = np.asarray(array)
    if array.dtype.kind != "f":
        return array
    if cast is None:
        raise float_labels_error(array.dtype, what)
    checker = ExactCast(array.dtype, what)
    checker.check(array)
    return array.astype(checker.dtype())


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
            " A label map stored as whole-number floats is accepted with cast='exact'"
            " (read, from_numpy, from_image, add_segmentation), or convert it with"
            " array.astype(np.int32) (or another integer type) after checking it."
            if dtype.kind == "f"
            else ""
        )
        error = FloatLabelsError if dtype.kind == "f" else TypeError
        raise error(
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
