#!/usr/bin/env bash
# Runs every test: the C++ suites (ctest) and the Python suites (pytest), headless under Xvfb.
# Sets the machine up first (idempotent), so it also works on a fresh clone.
set -uo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh || { echo "setup failed"; exit 1; }

status=0
# In CI (CI=true), or when asked: the ASan+UBSan build and its tests (about 8 minutes on 2 cores),
# first, so that the output ends with the main suites' summaries.
if [ "${CI:-}" = true ] || [ -n "${VTKSVDAG_SANITIZE_TESTS:-}" ]; then
  bash scripts/sanitize.sh || status=1
fi
# The installs a user makes (CMake package, out-of-tree example, pip into a fresh venv), before
# the main suites so that the output ends with their summaries.
xvfb-run -a -s "-screen 0 1024x768x24" bash scripts/test-install.sh || status=1
# The ParaView plugin (build-paraview/); its tests are Testing/Python/test_paraview*.py, which
# skip without it.
bash scripts/setup-paraview.sh || { echo "setup-paraview failed"; status=1; }
xvfb-run -a -s "-screen 0 1024x768x24" ctest --test-dir build --output-on-failure -j2 || status=1
xvfb-run -a -s "-screen 0 1024x768x24" .venv/bin/python -m pytest -q Testing/Python || status=1
exit $status
