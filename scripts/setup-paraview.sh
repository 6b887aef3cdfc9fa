#!/usr/bin/env bash
# Builds the ParaView plugin vtkSVDAG against Debian 12's ParaView 5.11 (its own VTK 9.2) into
# build-paraview/, beside the main build against Debian's VTK 9.1 (scripts/setup.sh). Idempotent.
#
#   build-paraview/lib/paraview-5.11/plugins/vtkSVDAG/vtkSVDAG.so   the plugin
#   build-paraview/paraview-python/                                  ParaView's Python (see below)
#   build-paraview/env.sh                                            PYTHONPATH, PV_PLUGIN_PATH
#
# Debian's python3-paraview (pvpython and ParaView's Python modules) conflicts with python3-vtk9,
# which the main build needs: both ship /usr/lib/python3/dist-packages/vtkmodules. So it is never
# installed: its .deb is unpacked into build-paraview/paraview-python (pvbatch and pvserver come
# with the paraview package and find the modules through PYTHONPATH). ParaView's CMake package
# names those Python files by its own prefix, so CMake gets a view of /usr in which
# lib/python3 is the unpacked one (build-paraview/paraview-sdk, symbolic links and a copy of
# ParaView's CMake files).
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
OUT=$ROOT/build-paraview
SUDO=""; [ "$(id -u)" -eq 0 ] || SUDO="sudo"
export DEBIAN_FRONTEND=noninteractive

bash scripts/install-deps.sh

# paraview: pvbatch, pvserver, the GUI; paraview-dev: headers and CMake package (it also needs
# the MPI and other development packages below); qtbase5-dev, libqt5opengl5-dev: Qt's
# headers and CMake files for the GUI's label read-out in the plugin; mpi-default-bin: mpiexec.
PKGS=(paraview paraview-dev qtbase5-dev libqt5opengl5-dev mpi-default-dev mpi-default-bin xvfb xauth)
missing=()
for p in "${PKGS[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  $SUDO apt-get update -qq
  $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

PV_VERSION=$(dpkg-query -W -f='${Version}' paraview)
PYROOT=$OUT/paraview-python
if [ "$(cat "$PYROOT/.version" 2>/dev/null)" != "$PV_VERSION" ]; then
  rm -rf "$PYROOT" && mkdir -p "$PYROOT"
  (cd "$PYROOT" && apt-get download -qq "python3-paraview=$PV_VERSION" 2>/dev/null)
  dpkg-deb -x "$PYROOT"/python3-paraview_*.deb "$PYROOT"
  rm -f "$PYROOT"/python3-paraview_*.deb
  echo "$PV_VERSION" > "$PYROOT/.version"
fi

ARCHLIB=/usr/lib/x86_64-linux-gnu
SDK=$OUT/paraview-sdk/usr
if [ "$(cat "$SDK/.version" 2>/dev/null)" != "$PV_VERSION" ]; then
  rm -rf "$OUT/paraview-sdk"
  mkdir -p "$SDK/bin" "$SDK/lib/x86_64-linux-gnu/cmake"
  ln -s /usr/bin/* "$PYROOT"/usr/bin/* "$SDK/bin/"
  ln -s /usr/include "$SDK/include"
  ln -s /usr/share "$SDK/share"
  ln -s "$PYROOT/usr/lib/python3" "$SDK/lib/python3"
  # vtk/ holds the wrapping hierarchy files: ParaView's come with python3-paraview.
  ln -s "$PYROOT/usr/lib/x86_64-linux-gnu/vtk" "$SDK/lib/x86_64-linux-gnu/vtk"
  find "$ARCHLIB" -mindepth 1 -maxdepth 1 ! -name cmake ! -name vtk \
    -exec ln -s -t "$SDK/lib/x86_64-linux-gnu" {} +
  find "$ARCHLIB/cmake" -mindepth 1 -maxdepth 1 ! -name paraview-5.11 \
    -exec ln -s -t "$SDK/lib/x86_64-linux-gnu/cmake" {} +
  # A copy, not a link: the CMake files compute their prefix from where they are.
  cp -r "$ARCHLIB/cmake/paraview-5.11" "$SDK/lib/x86_64-linux-gnu/cmake/"
  echo "$PV_VERSION" > "$SDK/.version"
fi

cmake -S . -B "$OUT" -G Ninja -DCMAKE_BUILD_TYPE=Release -DVTKSVDAG_PARAVIEW=ON \
  -DParaView_DIR="$SDK/lib/x86_64-linux-gnu/cmake/paraview-5.11" >/dev/null
cmake --build "$OUT" -j2

PLUGIN_DIR=$OUT/lib/paraview-5.11/plugins/vtkSVDAG
cat > "$OUT/env.sh" <<ENV
# Source this for pvbatch, pvpython and pvserver with the vtkSVDAG plugin (scripts/setup-paraview.sh).
export PYTHONPATH="$PYROOT/usr/lib/python3/dist-packages\${PYTHONPATH:+:\$PYTHONPATH}"
export PV_PLUGIN_PATH="$PLUGIN_DIR"
export PATH="$PYROOT/usr/bin:\$PATH"
# ParaView's libraries through the view of /usr: pvpython then finds ParaView's vtkmodules next to
# them (it looks beside libvtkCommonCore), not Debian VTK 9.1's in /usr/lib/python3/dist-packages.
export LD_LIBRARY_PATH="$SDK/lib/x86_64-linux-gnu\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}"
ENV
echo "ParaView plugin: $PLUGIN_DIR/vtkSVDAG.so (environment: source build-paraview/env.sh)"
