"""``vtksvdag decompress IN.svdag -o OUT``: decode a .svdag file into a label volume file."""
import argparse
import time

from ..export import LABEL_VOLUME_SUFFIXES, label_volume_suffix, write_label_volume
from ._common import add_output_options, file_bytes, load, print_json, print_table, run_with_progress

NAME = "decompress"
HELP = ("decode a .svdag file into NRRD (.nrrd/.nhdr), VTK XML (.vti), numpy (.npy, [x, y, z]) or "
        "an OME-Zarr store (.zarr, Zarr v2, (z, y, x))")


def _output_path(text):
    try:
        label_volume_suffix(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None
    return text


def add_arguments(parser):
    parser.add_argument("input", metavar="IN.svdag", help=".svdag file (or any readable label volume)")
    parser.add_argument(
        "-o", "--output", required=True, type=_output_path, metavar="OUT",
        help=f"output file; its suffix picks the format ({', '.join(LABEL_VOLUME_SUFFIXES)}). "
        ".npy arrays are indexed [x, y, z]; a .zarr store is a new OME-Zarr 0.4 directory "
        "(Zarr v2 array '0', (z, y, x), x fastest, spacing/origin as its scale/translation)",
    )
    add_output_options(parser)


def run(args):
    volume = load(args, args.input)
    start = time.perf_counter()
    run_with_progress(args, "write", lambda progress: write_label_volume(volume, args.output, progress))
    seconds = time.perf_counter() - start
    result = {
        "input": args.input,
        "output": args.output,
        "file_bytes": file_bytes(args.output),
        "dims": list(volume.dims),
        "voxels": volume.n_voxels,
        "dtype": volume.dtype.name,
        "labels": int(volume.labels.size),
        "decode_seconds": seconds,
    }
    if args.json:
        print_json(result)
    else:
        print_table(
            [
                ("input", args.input),
                ("output", f"{args.output}  ({result['file_bytes']:,} bytes)"),
                ("dimensions", " x ".join(str(d) for d in result["dims"]) + f"  ({result['dtype']})"),
                ("labels", f"{result['labels']:,}"),
                ("decode+write", f"{seconds:.3f} s"),
            ]
        )
    return 0
