#!/usr/bin/env bash
# Sets up a fresh machine for vtkSVDAG: Debian packages, the .venv, the build. Idempotent.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD

bash scripts/install-deps.sh

# Debian's VTK is built for Debian's Python; the venv sees it through system site packages.
if [ ! -x .venv/bin/python ]; then
  /usr/bin/python3 -m venv --system-site-packages .venv
fi
PIP=(.venv/bin/python -m pip install -q --disable-pip-version-check -c Python/constraints.txt)
"${PIP[@]}" -r Python/requirements.txt
"${PIP[@]}" --no-deps pyvista==0.46.5
# pytest-pyvista's verify_image_cache (image regression); --no-deps for the same reason.
"${PIP[@]}" --no-deps pytest-pyvista==0.3.3
# The package's metadata and console script `vtksvdag` from pyproject.toml, editable and without
# its CMake build (the build below is the development one, in build/).
"${PIP[@]}" --no-deps -e . --config-settings=wheel.cmake=false

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build build

# The wrapped modules live in build/python/vtksvdag; the package's extend_path merges every
# vtksvdag directory on sys.path, so both go there (a PYTHONPATH before them, as
# scripts/sanitize.sh sets, takes precedence for the wrapped modules).
SITE=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
printf '%s\n' "$ROOT/Python" "$ROOT/build/python" > "$SITE/vtksvdag-build.pth"
echo "vtkSVDAG is set up: .venv/bin/vtksvdag --help"
