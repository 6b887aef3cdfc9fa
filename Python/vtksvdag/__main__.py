"""``python -m vtksvdag``: the command line (see :mod:`vtksvdag.cli`)."""
import sys

from .cli import main

sys.exit(main())
