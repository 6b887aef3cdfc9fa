"""``vtksvdag compress INPUT -o OUT.svdag``: compress a label volume file into a .svdag file."""
import argparse
import functools

from .._svdagfile import COMPRESSION_LEVELS, DEFAULT_FORMAT_VERSION, FORMAT_VERSIONS
from ..distributed import build_distributed
from ..fileio import read
from ._common import (
    UsageError, add_input_options, add_output_options, file_bytes, int_in, load, output_path, print_json,
    print_table, run_with_progress, stats_rows,
)

NAME = "compress"
HELP = ("compress a label volume file (NRRD, MetaImage, VTI, NIfTI, TIFF, HDF5, .npy) or chunked "
        "store (Zarr, OME-Zarr, N5, neuroglancer precomputed) to .svdag")


def add_arguments(parser):
    parser.add_argument("input", metavar="INPUT", help="label volume file, or chunked store directory or URL")
    parser.add_argument(
        "-o", "--output", required=True, type=output_path((".svdag",), "compress"),
        metavar="OUT.svdag", help="output file (.svdag)",
    )
    add_input_options(parser)
    low, high = COMPRESSION_LEVELS.start, COMPRESSION_LEVELS.stop - 1
    parser.add_argument(
        "--level", type=int_in(low, high), default=3, metavar="L",
        help=f"with --format-version 2: zstd compression level of the file, {low + 1}..{high}; "
        f"{low} stores it uncompressed (default: 3)",
    )
    parser.add_argument(
        "--format-version", type=int, choices=FORMAT_VERSIONS, default=DEFAULT_FORMAT_VERSION,
        metavar="V", help="4: the DAG as byte streams, smaller than CSGV's files and fast to load "
        "(default); 3: the smallest file, about a build's time to load; 2: the in-memory "
        "sections under zstd, read by vtksvdag before format 3",
    )
    parser.add_argument(
        "--dask", metavar="CLUSTER",
        help="chunked stores: compress on Dask, 'local:N' (N local worker processes) or a "
        "scheduler address such as tcp://scheduler:8786; the output is the same byte for byte",
    )
    parser.add_argument(
        "--slab", type=slab_slices, default=None, metavar="N",
        help="with --dask: z-slices a task reads at a time, a multiple of 16 (default: about "
        "64 MiB, kept to the store's chunks)",
    )
    parser.add_argument(
        "--partitions", type=int_in(1, 2**31 - 1), default=None, metavar="N",
        help="with --dask: tasks that read the store (default: one per worker thread)",
    )
    add_output_options(parser)


def slab_slices(text):
    value = int_in(16, 2**31 - 1)(text)
    if value % 16:
        raise argparse.ArgumentTypeError(f"must be a multiple of 16, not {value}")
    return value


def run(args):
    for option, value in (("--slab", args.slab), ("--partitions", args.partitions)):
        if value is not None and not args.dask:
            raise UsageError(f"argument {option}: only with --dask")
    reader = read
    if args.dask:
        reader = functools.partial(build_distributed, client=args.dask, slab=args.slab,
                                   partitions=args.partitions)
    volume = load(args, args.input, reader=reader)
    run_with_progress(
        args, "write", lambda progress: volume.save(
            args.output, compression_level=args.level, progress=progress, format_version=args.format_version
        )
    )
    stats = volume.stats()
    stats.update(input=args.input, output=args.output, file_bytes=file_bytes(args.output))
    if args.json:
        print_json(stats)
    else:
        print_table(
            [("input", args.input)]
            + stats_rows(stats)
            + [("output", f"{args.output}  ({stats['file_bytes']:,} bytes)")]
        )
    return 0
