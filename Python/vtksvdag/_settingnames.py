"""The names of the render settings' values (LOD, shading, backend), as the C++ settings class
defines them (vtkSegmentationSVDAGRenderSettings.GetNumberOfLODs, GetLODName, ...): the pyvista
glue and the command line keep no copies. (The defaults are what a new settings object holds.)

``setting`` is the C++ name: ``"LOD"``, ``"Shading"`` or ``"Backend"``. Importing the rendering
module is left to the calls (the package works where it cannot load).
"""


def _settings_class():
    from .vtkSVDAGRendering import vtkSegmentationSVDAGRenderSettings

    return vtkSegmentationSVDAGRenderSettings


def names(setting):
    """The names of the setting's values, in the order of their enum values."""
    cls = _settings_class()
    count = getattr(cls, f"GetNumberOf{setting}s")()
    return tuple(getattr(cls, f"Get{setting}Name")(i) for i in range(count))


def set_by_name(settings, setting, value, option):
    """Sets the setting through its C++ string setter (``SetLOD("auto")``); ValueError naming
    ``option`` and the valid names for any other value (the C++ setter would only report it)."""
    valid = names(setting)
    if not isinstance(value, str) or value not in valid:
        raise ValueError(f"{option} must be one of {list(valid)}, got {value!r}")
    getattr(settings, f"Set{setting}")(value)
