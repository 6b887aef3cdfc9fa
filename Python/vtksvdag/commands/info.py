"""``vtksvdag info FILE``: statistics of a .svdag file or of any readable label volume."""
from ._common import (
    add_input_options, add_output_options, file_bytes, load, print_json, print_table, stats_rows,
)

NAME = "info"
HELP = "print the statistics of a .svdag file or of a label volume compressed on the fly"


def add_arguments(parser):
    parser.add_argument("input", metavar="FILE", help=".svdag file, label volume file or chunked store (directory or URL)")
    add_input_options(parser)
    add_output_options(parser)


def run(args):
    volume = load(args, args.input)
    stats = volume.stats()
    stats.update(input=args.input, file_bytes=file_bytes(args.input))
    if args.json:
        print_json(stats)
    else:
        size = "remote" if stats["file_bytes"] is None else f"{stats['file_bytes']:,} bytes"
        print_table([("input", f"{args.input}  ({size})")] + stats_rows(stats))
    return 0
