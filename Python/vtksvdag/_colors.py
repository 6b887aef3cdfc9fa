"""Colors as the pyvista glue takes them (shared by ``plotting``, ``actor`` and ``slicing``)."""
import numpy as np


def to_rgb(color):
    """A color pyvista understands (name, hex, 0-1 floats or 0-255 ints) as 0-1 floats."""
    import pyvista as pv

    values = np.asarray(color) if isinstance(color, (tuple, list, np.ndarray)) else None
    if values is not None and values.dtype.kind == "f" and values.shape in ((3,), (4,)):
        # Floats are kept as given: pyvista.Color would round them to 8 bits.
        if not np.all((values >= 0) & (values <= 1)):
            raise ValueError(f"float colors must be in [0, 1], got {color!r}")
        return tuple(float(c) for c in values[:3])
    return tuple(float(c) for c in pv.Color(color).float_rgb)
