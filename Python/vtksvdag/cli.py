"""The ``vtksvdag`` command line: compress, decompress and inspect segmentation volumes.

Exit codes: 0 success, 1 failure (unreadable file, bad data), 2 usage error. Errors are one
line ``vtksvdag: error: ...`` on stderr, never a traceback.
"""
import argparse
import sys

from . import __version__
from .commands import compress, decompress, info, render, view
from .commands._common import UsageError

#: Every subcommand, in the order ``--help`` lists them. A new command is a module in
#: ``vtksvdag/commands/`` plus one entry here.
COMMANDS = [compress, decompress, info, render, view]

PROG = "vtksvdag"


class _Parser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors are one line on stderr and exit code 2."""

    def error(self, message):
        self.exit(2, f"{PROG}: error: {message} (see '{self.prog} --help')\n")


def build_parser():
    """The argparse parser with one subparser per entry of :data:`COMMANDS`."""
    parser = _Parser(
        prog=PROG,
        description="Lossless SVDAG compression of segmentation (label) volumes.",
    )
    parser.add_argument("--version", action="version", version=f"{PROG} {__version__}")
    subparsers = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for command in COMMANDS:
        sub = subparsers.add_parser(command.NAME, help=command.HELP, description=command.HELP)
        command.add_arguments(sub)
        sub.set_defaults(run=command.run)
    return parser


def _describe(error):
    """One line for an exception raised by a command."""
    if isinstance(error, OSError) and error.filename is not None and error.strerror:
        return f"{error.filename}: {error.strerror}"
    if isinstance(error, KeyError) and error.args:
        return str(error.args[0])
    return str(error) or type(error).__name__


def main(argv=None):
    """Run the command line with ``argv`` (default: ``sys.argv[1:]``) and return the exit code.

    Examples
    --------
    >>> from vtksvdag.cli import main
    >>> main(["info", "segmentation.nrrd", "--json"])  # doctest: +SKIP
    0
    """
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as stop:  # --help, --version and usage errors
        return stop.code if isinstance(stop.code, int) else 2
    try:
        return args.run(args)
    except UsageError as error:  # an option that does not fit the input (found once read)
        print(f"{PROG}: error: {error} (see '{PROG} {args.command} --help')", file=sys.stderr)
        return 2
    except (OSError, ValueError, TypeError, KeyError, MemoryError, RuntimeError) as error:
        print(f"{PROG}: error: {_describe(error)}", file=sys.stderr)
        return 1
    except KeyboardInterrupt:
        print(f"{PROG}: interrupted", file=sys.stderr)
        return 130
    except Exception as error:  # noqa: BLE001 (a bug, but still one line and no traceback)
        print(f"{PROG}: error: internal error: {type(error).__name__}: {_describe(error)}",
              file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
