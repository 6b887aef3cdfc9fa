"""Pieces shared by the subcommands: options, input loading, progress and output formatting."""
import argparse
import json
import math
import os
import sys

from .._labels import LabelRangeError
from ..fileio import read
from ..progress import ProgressBar
from ..stores import is_url

INT64_MIN = -(2**63)
UINT64_MAX = 2**64 - 1


class UsageError(Exception):
    """A bad option value found only once the input was read (a background that does not fit
    the file's dtype): reported like argparse's errors, with exit code 2."""


# -- option types: each names the range in its message; argparse adds "argument --name: " and
# exits with code 2.
def int_in(low, high):
    """An argparse type: an integer in low..high."""

    def parse(text):
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be an integer in {low}..{high}, got {text!r}") from None
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"must be in {low}..{high}, got {value}")
        return value

    parse.__name__ = f"integer in {low}..{high}"
    return parse


def finite_float(minimum=None, exclusive=False):
    """An argparse type: a finite number, optionally > minimum (exclusive) or >= minimum."""
    if minimum is None:
        wanted = "a finite number"
    else:
        wanted = f"a finite number {'>' if exclusive else '>='} {minimum:g}"

    def parse(text):
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"must be {wanted}, got {text!r}") from None
        ok = math.isfinite(value) and (
            minimum is None or (value > minimum if exclusive else value >= minimum)
        )
        if not ok:
            raise argparse.ArgumentTypeError(f"must be {wanted}, got {text}")
        return value

    parse.__name__ = wanted
    return parse


#: A label value: what fits int64 or uint64 (the volume's own dtype is checked after reading).
label_value = int_in(INT64_MIN, UINT64_MAX)


def output_path(suffixes, what):
    """An argparse type: a file name ending in one of ``suffixes`` (case-insensitive)."""

    def parse(text):
        if not text.lower().endswith(tuple(suffixes)):
            suffix = os.path.splitext(text)[1]
            found = f"suffix {suffix!r}" if suffix else "no suffix"
            raise argparse.ArgumentTypeError(
                f"{text!r} has {found}; {what} writes {' or '.join(suffixes)} files"
            )
        return text

    parse.__name__ = "output file"
    return parse


def add_output_options(parser):
    """--json and --no-progress, which every command has."""
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bar (it is shown only on a terminal)"
    )


def add_input_options(parser):
    """Options that decide what is read from a label volume file."""
    parser.add_argument(
        "--background", type=label_value, default=0, metavar="N",
        help="label that is not stored; it must fit the file's label type (default: 0)",
    )
    parser.add_argument(
        "--exclude", type=label_value, nargs="+", default=[], metavar="N",
        help="labels left out (they decode as background); each must fit the file's label type",
    )
    parser.add_argument(
        "--dataset", metavar="NAME",
        help="dataset name inside an HDF5 file, or array path inside a chunked store directory",
    )
    parser.add_argument(
        "--scale", type=int_in(0, 2**31 - 1), metavar="N",
        help="chunked stores (OME-Zarr, neuroglancer precomputed): scale index to read "
        "(default: 0, full resolution)",
    )
    parser.add_argument(
        "--cache-mib", type=int_in(0, 2**31 - 1), metavar="MIB",
        help="chunked stores: bound of tensorstore's chunk cache in MiB (default: none where "
        "the slabs read keep to the store's chunks, else 256)",
    )
    parser.add_argument(
        "--axis-order", choices=("zyx", "xyz"),
        help="chunked stores: order of the spatial dimensions (default: zyx for Zarr unless "
        "OME-Zarr axes say otherwise, xyz for N5 and precomputed)",
    )


def progress_bar(args, label):
    """A ProgressBar on stderr, or None when it would get in the way (no TTY, --json, --no-progress)."""
    if args.json or args.no_progress or not sys.stderr.isatty():
        return None
    return ProgressBar(label, stream=sys.stderr)


def run_with_progress(args, label, task):
    """Call ``task(progress)`` with a progress bar callback (or None) and close the bar after."""
    bar = progress_bar(args, label)
    try:
        return task(bar)
    finally:
        if bar is not None:
            bar.close()


_OPTION_OF = {"background": "--background", "excluded label": "--exclude"}


def load(args, path, reader=read):
    """Read ``path`` (a label volume or a .svdag file) with the input options of ``args``,
    through ``reader`` (vtksvdag.read or a function with its keyword arguments).

    Raises UsageError when --background or --exclude does not fit the file's label dtype.
    """
    try:
        return run_with_progress(
            args,
            "read",
            lambda progress: reader(
                path,
                background=getattr(args, "background", 0),
                exclude=getattr(args, "exclude", ()),
                dataset=getattr(args, "dataset", None),
                progress=progress,
                scale=getattr(args, "scale", None),
                axis_order=getattr(args, "axis_order", None),
                cache_bytes=None if getattr(args, "cache_mib", None) is None else args.cache_mib << 20,
            ),
        )
    except LabelRangeError as e:
        option = _OPTION_OF.get(e.what, e.what)
        raise UsageError(
            f"argument {option}: {e.value} is out of range for the labels of {path} "
            f"({e.type_name}: {e.low}..{e.high})"
        ) from None


def file_bytes(path):
    """Size of a file in bytes; of all files under a directory (a chunked store); None for a
    URL (a remote store is not listed)."""
    if is_url(path):
        return None
    if os.path.isdir(path):
        return sum(os.path.getsize(os.path.join(root, name))
                   for root, _, names in os.walk(path) for name in names)
    return os.path.getsize(path)


def _number(value):
    return f"{value:,}" if isinstance(value, int) else str(value)


def stats_rows(stats):
    """(name, text) rows describing a volume's statistics for the human-readable table."""
    dims = " x ".join(str(d) for d in stats["dims"])
    rows = [
        ("dimensions", f"{dims}  ({_number(stats['voxels'])} voxels, {stats['dtype']})"),
        ("spacing", " ".join(f"{v:g}" for v in stats["spacing"])),
        ("origin", " ".join(f"{v:g}" for v in stats["origin"])),
        ("labels", f"{_number(stats['labels'])}  (background {stats['background']} not stored)"),
        ("blocks", _number(stats["blocks"])),
        (
            "DAG nodes",
            f"{_number(stats['dag_nodes'])}  (roots {_number(stats['root_nodes'])}, "
            f"mids {_number(stats['mid_nodes'])}, leaves {_number(stats['leaves'])})",
        ),
        ("bytes: blocks", _number(stats["bytes_blocks"])),
        ("bytes: DAG", _number(stats["bytes_dag"])),
        ("bytes: labels", _number(stats["bytes_labels"])),
        ("bytes: total", _number(stats["bytes_total"])),
        ("bits per voxel", f"{stats['bits_per_voxel']:.4f}"),
    ]
    if stats.get("compression_ratio_32"):
        rows.append(("32-bit raw", f"{_number(stats['raw_bytes_32'])} bytes "
                     f"({stats['compression_ratio_32']:.1f}x the compressed size)"))
    if stats.get("build_seconds") is not None:
        rows.append(("build time", f"{stats['build_seconds']:.3f} s"))
    if stats.get("load_seconds") is not None:
        rows.append(("load time", f"{stats['load_seconds']:.3f} s"))
    return rows


def print_table(rows, stream=None):
    """Print (name, text) rows as two aligned columns."""
    stream = stream if stream is not None else sys.stdout
    width = max(len(name) for name, _ in rows)
    for name, text in rows:
        print(f"{name:<{width}}  {text}", file=stream)


def print_json(obj, stream=None):
    """Print one JSON object on one line."""
    print(json.dumps(obj, sort_keys=True), file=stream if stream is not None else sys.stdout)
