"""One owner per render option: the LOD, shading and backend names and every default come from the
C++ settings class (the Python glue and both command lines keep no copies), and add_segmentation
takes every option as a documented keyword argument (no hidden ``**kwargs``; misspelled options
are a TypeError with suggestions).

References: the C++ enum values (``LOD_*``, ``SHADING_*``, ``BACKEND_*`` of the wrapped class) for
the names, a new settings object for the defaults, and the docstring's own Parameters section for
the documentation check.
"""
import argparse
import inspect
import json
import pathlib
import re
import subprocess
import sys

import numpy as np
import pytest

import vtksvdag
from vtksvdag import plotting
from vtksvdag.commands import render as render_command
from vtksvdag.vtkSVDAGRendering import (vtkSegmentationSVDAGRenderer,
                                        vtkSegmentationSVDAGRenderSettings as S)

# Each setting: (C++ name, its enum constants by name).
SETTINGS = {
    "LOD": {"block": S.LOD_BLOCK, "leaf": S.LOD_LEAF, "voxel": S.LOD_VOXEL, "auto": S.LOD_AUTO},
    "Shading": {"voxel": S.SHADING_VOXEL, "smooth": S.SHADING_SMOOTH},
    "Backend": {"auto": S.BACKEND_AUTO, "rt": S.BACKEND_RT, "compute": S.BACKEND_COMPUTE},
}


@pytest.mark.parametrize("setting", sorted(SETTINGS))
def test_names_are_the_enum_values(setting):
    count = getattr(S, f"GetNumberOf{setting}s")()
    names = [getattr(S, f"Get{setting}Name")(i) for i in range(count)]
    assert dict(zip(names, range(count))) == SETTINGS[setting]
    assert getattr(S, f"Get{setting}Name")(count) is None
    assert getattr(S, f"Get{setting}Name")(-1) is None
    settings = S()
    for name, value in SETTINGS[setting].items():
        getattr(settings, f"Set{setting}")(name)  # the string setter
        assert getattr(settings, f"Get{setting}")() == value
        assert getattr(settings, f"Get{setting}AsString")() == name


def test_unknown_lod_name_is_an_error_and_changes_nothing():
    from conftest import capture_errors

    settings = S()
    errors = capture_errors(settings)
    settings.SetLOD("leaf")
    settings.SetLOD("fine")
    assert settings.GetLODAsString() == "leaf"
    assert len(errors) == 1 and "unknown LOD 'fine' (block, leaf, voxel or auto)" in errors[0]
    settings.SetLOD(17)  # ints clamp like the other enumerations
    assert settings.GetLOD() == S.LOD_AUTO


def test_python_keeps_no_copies_of_the_names():
    # The former copies are gone: the glue reads the C++ class.
    for module, names in ((plotting, ("_LODS", "_SHADINGS", "_BACKENDS", "_EXTRA_OPTIONS")),
                          (render_command, ("LODS", "SHADINGS", "BACKENDS"))):
        assert not [n for n in names if hasattr(module, n)]
    parser = argparse.ArgumentParser()
    render_command.add_arguments(parser)
    actions = {a.dest: a for a in parser._actions}
    defaults = S()
    for dest, setting in (("lod", "LOD"), ("shading", "Shading"), ("backend", "Backend")):
        assert list(actions[dest].choices) == list(SETTINGS[setting])
        assert actions[dest].default == getattr(defaults, f"Get{setting}AsString")()
    assert actions["bounces"].default == defaults.GetMaximumBounces()
    assert actions["seed"].default == defaults.GetSeed()


def test_one_default_everywhere(tmp_path):
    """The LOD default is auto in the C++ settings, the image renderer, the pyvista glue, the
    Python command line and the C++ command line alike."""
    import pyvista as pv

    assert S().GetLODAsString() == "auto"
    assert vtkSegmentationSVDAGRenderer().GetSettings().GetLODAsString() == "auto"
    labels = np.zeros((8, 8, 8), np.uint8)
    labels[2:6, 2:6, 2:6] = 3
    plotter = pv.Plotter(off_screen=True, window_size=(32, 32))
    try:
        actor = vtksvdag.add_segmentation(plotter, labels)
        settings = actor.GetMapper().GetSettings()
        fresh = S()
        for getter in ("GetLODAsString", "GetShadingAsString", "GetBackendAsString",
                       "GetMaximumBounces", "GetSeed", "GetSamplesPerPixel", "GetExposure",
                       "GetNextEventEstimation"):
            assert getattr(settings, getter)() == getattr(fresh, getter)(), getter
    finally:
        plotter.close()

    volume = vtksvdag.from_numpy(labels)
    path = tmp_path / "cube.svdag"
    volume.save(path)
    result = subprocess.run([sys.executable, "-m", "vtksvdag", "render", str(path), "-o",
                             str(tmp_path / "a.png"), "--width", "16", "--height", "16", "--spp",
                             "1", "--json"], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    report = json.loads(result.stdout)
    assert (report["lod"], report["shading"], report["bounces"], report["seed"]) == (
        "auto", "voxel", S().GetMaximumBounces(), S().GetSeed())

    import vtksvdag.vtkSVDAGRendering as module

    tool = pathlib.Path(module.__file__).resolve().parents[2] / "bin" / "vtksvdag-render"
    assert tool.is_file(), f"the command line renderer was not built: {tool}"
    run = subprocess.run([str(tool), str(path), str(tmp_path / "b.png"), "--width", "16",
                          "--height", "16"], capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert json.loads(run.stdout)["lod"] == "auto"
    usage = subprocess.run([str(tool)], capture_output=True, text=True, timeout=60)
    assert "--lod block|leaf|voxel|auto" in usage.stderr and "auto|rt|compute" in usage.stderr


def documented_parameters(function):
    """The names of the numpydoc Parameters section of function's docstring."""
    doc = inspect.getdoc(function)
    section = doc.split("Parameters\n----------\n", 1)[1].split("\n\n", 1)[0]
    section = re.split(r"\n(?:Returns|Raises|Examples)\n-+\n", section)[0]
    names = []
    for line in section.splitlines():
        match = re.match(r"^(\w+(?:, \w+)*) :", line)
        if match:
            names += match.group(1).split(", ")
    return names


def test_add_segmentation_options_are_named_and_documented():
    signature = inspect.signature(vtksvdag.add_segmentation)
    kinds = {p.kind for p in signature.parameters.values()}
    assert inspect.Parameter.VAR_KEYWORD not in kinds and inspect.Parameter.VAR_POSITIONAL not in kinds
    assert documented_parameters(vtksvdag.add_segmentation) == list(signature.parameters)
    # Every option name add_segmentation took before, named or through **kwargs, still works.
    former = {"colors", "cmap", "opacity", "hidden_labels", "attributes", "color_by", "query",
              "highlight", "dim", "lod", "shading", "backend", "spp", "bounces", "sun",
              "environment", "clipping_planes", "crop", "name", "reset_camera", "exposure", "seed",
              "next_event_estimation", "write_depth", "error_target", "auto_adjust",
              "samples_per_pass", "clim", "nan_color", "highlight_color", "highlight_intensity",
              "others_opacity"}
    assert former <= set(signature.parameters)


def test_misspelled_option_is_a_type_error_with_a_suggestion():
    import pyvista as pv

    plotter = pv.Plotter(off_screen=True, window_size=(32, 32))
    try:
        with pytest.raises(TypeError, match=r"'exposre' \(did you mean 'exposure'\?\)"):
            vtksvdag.add_segmentation(plotter, np.ones((4, 4, 4), np.uint8), exposre=2.0)
        with pytest.raises(TypeError, match=r"unknown options: 'frobnicate'$"):
            vtksvdag.add_segmentation(plotter, np.ones((4, 4, 4), np.uint8), frobnicate=1)
        with pytest.raises(ValueError, match=r"lod must be one of \['block', 'leaf', 'voxel', 'auto'\]"):
            vtksvdag.add_segmentation(plotter, np.ones((4, 4, 4), np.uint8), lod="fine")
    finally:
        plotter.close()


def test_options_reach_the_mapper():
    """The options that were **kwargs set the mapper and its settings as documented."""
    import pyvista as pv

    labels = np.zeros((8, 8, 8), np.uint8)
    labels[2:6, 2:6, 2:6] = 3
    plotter = pv.Plotter(off_screen=True, window_size=(32, 32))
    try:
        actor = vtksvdag.add_segmentation(
            plotter, labels, lod="leaf", shading="smooth", backend="compute", spp=5,
            samples_per_pass=2, bounces=7, seed=11, next_event_estimation=False, exposure=2.5,
            write_depth=False, auto_adjust=False, error_target=0.01)
        mapper = actor.GetMapper()
        s = mapper.GetSettings()
        assert (s.GetLODAsString(), s.GetShadingAsString(), s.GetBackendAsString()) == (
            "leaf", "smooth", "compute")
        assert (s.GetSamplesPerPixel(), s.GetMaximumBounces(), s.GetSeed()) == (2, 7, 11)
        assert not s.GetNextEventEstimation() and s.GetExposure() == 2.5
        assert mapper.GetTargetSamplesPerPixel() == 5 and mapper.GetErrorTarget() == 0.01
        assert not mapper.GetWriteDepth() and not mapper.GetAutoAdjustToRenderTime()
    finally:
        plotter.close()
