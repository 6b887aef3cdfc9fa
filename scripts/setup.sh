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
# The pure-Python package, editable, with its console script `vtksvdag`.
"${PIP[@]}" --no-deps -e Python

cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
cmake --build build

# The wrapped modules live in build/python/vtksvdag; the package merges both directories.
# Python/ goes on sys.path too (before build/python): setuptools' editable finder runs after the
# path finder, which would otherwise take build/python/vtksvdag alone as a namespace package and
# never import Python/vtksvdag/__init__.py.
SITE=$(.venv/bin/python -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')
printf '%s\n' "$ROOT/Python" "$ROOT/build/python" > "$SITE/vtksvdag-build.pth"
echo "vtkSVDAG is set up: .venv/bin/vtksvdag --help"
