"""Subcommands of the ``vtksvdag`` command line; each module is registered in ``cli.COMMANDS``.

A command module defines ``NAME``, ``HELP``, ``add_arguments(parser)`` and ``run(args) -> int``.
"""
