"""Where scripts/setup-paraview.sh puts ParaView and the plugin, and the environment its
build-paraview/env.sh sets (ParaView's Python and libraries), for the ParaView benchmarks."""
import os
import pathlib

REPO = pathlib.Path(__file__).resolve().parents[1]
BUILD = REPO / "build-paraview"
PLUGIN = BUILD / "lib" / "paraview-5.11" / "plugins" / "vtkSVDAG" / "vtkSVDAG.so"


def paraview_env():
    """os.environ with build-paraview/env.sh's variables."""
    env = os.environ.copy()
    env["PYTHONPATH"] = str(BUILD / "paraview-python" / "usr" / "lib" / "python3" / "dist-packages")
    env["LD_LIBRARY_PATH"] = str(BUILD / "paraview-sdk" / "usr" / "lib" / "x86_64-linux-gnu")
    return env
