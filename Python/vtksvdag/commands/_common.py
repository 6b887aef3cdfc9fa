"""Pieces shared by the subcommands: options, input loading, progress and output formatting."""
import json
import os
import sys

from ..fileio import read
from ..progress import ProgressBar


def add_output_options(parser):
    """--json and --no-progress, which every command has."""
    parser.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    parser.add_argument(
        "--no-progress", action="store_true", help="no progress bar (it is shown only on a terminal)"
    )


def add_input_options(parser):
    """Options that decide what is read from a label volume file."""
    parser.add_argument(
        "--background", type=int, default=0, metavar="N", help="label that is not stored (default: 0)"
    )
    parser.add_argument(
        "--exclude", type=int, nargs="+", default=[], metavar="N",
        help="labels left out (they decode as background)",
    )
    parser.add_argument("--dataset", metavar="NAME", help="dataset name inside an HDF5 file")


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


def load(args, path):
    """Read ``path`` (a label volume or a .svdag file) with the input options of ``args``."""
    return run_with_progress(
        args,
        "read",
        lambda progress: read(
            path,
            background=getattr(args, "background", 0),
            exclude=getattr(args, "exclude", ()),
            dataset=getattr(args, "dataset", None),
            progress=progress,
        ),
    )


def file_bytes(path):
    """Size of a file in bytes."""
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
