"""vtksvdag: lossless SVDAG compression of segmentation volumes for VTK and pyvista.

The compiled VTK modules (``vtksvdag.vtkSVDAGCore``, ``vtksvdag.vtkSVDAGIO``, ...) are built by
CMake into another directory; ``extend_path`` merges it into this package.

Examples
--------
>>> import numpy as np
>>> import vtksvdag
>>> labels = np.zeros((64, 64, 64), dtype=np.uint32)
>>> labels[10:50, 20:40, 5:60] = 3
>>> volume = vtksvdag.from_numpy(labels)
>>> volume.stats()["labels"]
1
>>> np.array_equal(volume.to_numpy(), labels)
True
"""
from pkgutil import extend_path

__path__ = extend_path(__path__, __name__)

__version__ = "0.1.0"

from .build import from_image, from_numpy  # noqa: E402 (needs the extended __path__)
from .distributed import build_distributed  # noqa: E402
from .fileio import from_bytes, read  # noqa: E402
from .labelmeta import read_label_table  # noqa: E402
from .plotting import add_segmentation, pick, refine  # noqa: E402
from .slicing import add_segmentation_slice  # noqa: E402
from .streaming import Builder  # noqa: E402
from .volume import SegmentationVolume  # noqa: E402



def __getattr__(name):
    # The legend module imports pyvista; the rest of the package works without it.
    if name == "add_label_legend":
        from .legend import add_label_legend

        return add_label_legend
    # The viewer needs the optional extra "viewer" (trame).
    if name == "view":
        from .viewer import view

        return view
    raise AttributeError(f"module 'vtksvdag' has no attribute {name!r}")


__all__ = [
    "Builder",
    "SegmentationVolume",
    "add_label_legend",
    "add_segmentation",
    "add_segmentation_slice",
    "build_distributed",
    "from_bytes",
    "from_image",
    "from_numpy",
    "pick",
    "read",
    "read_label_table",
    "refine",
    "view",
    "__version__",
]
