#!/usr/bin/env bash
# Checks the installs a user makes, outside this checkout (scripts/test.sh runs it; CI too):
#   cmake-package  `cmake --install build` into a prefix that is then moved (it must be
#                  relocatable and name neither the source nor the build tree); Testing/Install,
#                  a downstream project, finds it with find_package alone, compiles every
#                  installed header on its own and runs a program using all three modules
#   cxx-example    examples/cxx built against that moved prefix from a copy of its own, with its
#                  regression test (scripts/test-cxx-example.sh)
#   pip-install    README.md's "Install into your own environment" commands, run as they are in a
#                  temporary directory beside a fresh clone of this repository (HEAD: commit first)
# Each check prints its time; the last line is "install: N passed, N failed". Needs the build
# (scripts/setup.sh) and an X display for the example (scripts/test.sh runs it under Xvfb).
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
WORK=$(mktemp -d "${TMPDIR:-/tmp}/vtksvdag-install.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
passed=0
failed=0

run_check() { # name command...
  local name=$1 start status
  shift
  echo "== install check: $name"
  start=$(date +%s)
  ("$@") && status=0 || status=1
  echo "== install check: $name $([ $status = 0 ] && echo passed || echo FAILED) in $(( $(date +%s) - start )) s"
  if [ $status = 0 ]; then passed=$((passed + 1)); else failed=$((failed + 1)); fi
}

cmake_package() {
  set -e
  cmake --install build --prefix "$WORK/staging" >/dev/null
  mv "$WORK/staging" "$WORK/prefix"
  if grep -rIl -e "$ROOT" "$WORK/prefix/lib/cmake"; then
    echo "the installed CMake files name the source or build tree"; return 1
  fi
  if readelf -d "$WORK"/prefix/lib/*.so "$WORK"/prefix/bin/* | grep -E "R(UN)?PATH" | grep -F "$ROOT"; then
    echo "an installed binary's RUNPATH names the build tree"; return 1
  fi
  cmake -S Testing/Install -B "$WORK/install-check" -G Ninja -DCMAKE_BUILD_TYPE=Release \
    -DCMAKE_PREFIX_PATH="$WORK/prefix" >/dev/null
  cmake --build "$WORK/install-check" >/dev/null
  "$WORK/install-check/install_check"
}

cxx_example() {
  set -e
  [ -d "$WORK/prefix" ] || { echo "no installed prefix (cmake-package failed)"; return 1; }
  bash scripts/test-cxx-example.sh "$WORK/prefix"
}

pip_install() {
  set -e
  mkdir "$WORK/pip"
  git clone --quiet "$ROOT" "$WORK/pip/vtkSVDAG"
  # The first bash block after the section's heading, as the README shows it.
  local commands
  commands=$(awk '/^## Install into your own environment/ {section = 1; next}
                  section && /^```bash/ {block = 1; next}
                  block && /^```/ {exit}
                  block {print}' README.md)
  [ -n "$commands" ] || { echo "README.md has no install commands"; return 1; }
  (cd "$WORK/pip" && bash -euo pipefail -c "$commands")
  # Debian's VTK and pandas are built against Debian's numpy: a newer one that pip put into the
  # environment (a dependency asking for it) would shadow it.
  "$WORK/pip/svdag-env/bin/python" -c "import numpy, sys
if not numpy.__file__.startswith('/usr/lib/python3/'):
    sys.exit('the environment has its own numpy ' + numpy.__version__ + ' (' + numpy.__file__ + '), not Debian\'s')"
}

run_check cmake-package cmake_package
if [ -f scripts/test-cxx-example.sh ]; then
  run_check cxx-example cxx_example
fi
run_check pip-install pip_install
echo "install: $passed passed, $failed failed"
[ $failed = 0 ]
