"""``vtksvdag info FILE``: statistics of a .svdag file or of any readable label volume."""
import os
import struct

from ._common import (
    add_input_options, add_output_options, file_bytes, load, print_json, print_table, stats_rows,
)

NAME = "info"
HELP = "print the statistics of a .svdag file or of a label volume compressed on the fly"


def add_arguments(parser):
    parser.add_argument("input", metavar="FILE", help=".svdag file, label volume file or chunked store (directory or URL)")
    add_input_options(parser)
    add_output_options(parser)


#: The .svdag file's signature and what each major version holds (IO/README.md).
_MAGIC = b"\x89SVDAG\r\n"
_FORMATS = {1: "the layout's sections", 2: "the layout's sections", 3: "the coded volume",
            4: "the DAG streams"}


def svdag_format(path):
    """The ``.svdag`` format version of a file as "major.minor", or None for another input."""
    if not os.path.isfile(path):
        return None
    with open(path, "rb") as f:
        head = f.read(12)
    if len(head) < 12 or head[:8] != _MAGIC:
        return None
    return "{}.{}".format(*struct.unpack_from("<HH", head, 8))


def run(args):
    volume = load(args, args.input)
    stats = volume.stats()
    stats.update(input=args.input, file_bytes=file_bytes(args.input),
                 file_format=svdag_format(args.input))
    if args.json:
        print_json(stats)
    else:
        size = "remote" if stats["file_bytes"] is None else f"{stats['file_bytes']:,} bytes"
        if stats["file_format"]:
            major = int(stats["file_format"].split(".")[0])
            size += f", .svdag {stats['file_format']}: {_FORMATS.get(major, 'a newer format')}"
        print_table([("input", f"{args.input}  ({size})")] + stats_rows(stats))
    return 0
