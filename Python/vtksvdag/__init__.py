"""vtksvdag: lossless SVDAG compression of segmentation volumes for VTK and pyvista.

The compiled VTK modules (``vtksvdag.vtkSVDAGCore``, ...) are built by CMake into another
directory; ``extend_path`` merges it into this package.
"""
from pkgutil import extend_path

__path__ = extend_path(__path__, __name__)

__version__ = "0.1.0"
