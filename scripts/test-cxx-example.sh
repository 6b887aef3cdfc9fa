#!/usr/bin/env bash
# Builds and tests examples/cxx out of tree against an installed vtkSVDAG:
#
#   bash scripts/test-cxx-example.sh PREFIX      # PREFIX from `cmake --install build --prefix PREFIX`
#
# In a fresh temporary directory: copies the prefix to another path (it must be relocatable),
# copies examples/cxx and the data file it needs (nothing else of this tree), configures with
# only -DCMAKE_PREFIX_PATH=<copied prefix>, builds, checks that the viewer loads vtkSVDAG's
# libraries from the copied prefix (ldd) and runs ctest under xvfb-run. Prints ctest's summary;
# exits non-zero on any failure. Needs an X server or xvfb-run, and a Vulkan device (lavapipe).
set -euo pipefail

if [[ $# -ne 1 || ! -f "$1/lib/cmake/vtkSVDAG/vtkSVDAGConfig.cmake" ]]; then
  echo "usage: $0 PREFIX   (an installed vtkSVDAG: PREFIX/lib/cmake/vtkSVDAG/vtkSVDAGConfig.cmake)" >&2
  exit 2
fi
prefix=$(cd "$1" && pwd)
tree=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

cp -a "$prefix" "$work/moved-prefix"
# Relocatable: nothing in the package's CMake files names the original prefix.
if grep -r -l -F "$prefix" "$work/moved-prefix/lib/cmake"; then
  echo "error: the CMake files above name the original prefix $prefix" >&2
  exit 1
fi
mkdir -p "$work/src/data"
cp -a "$tree/examples/cxx" "$work/src/cxx"
cp "$tree/examples/data/cells.nrrd" "$work/src/data/"

start=$SECONDS
generator=()
command -v ninja >/dev/null && generator=(-G Ninja)
cmake -S "$work/src/cxx" -B "$work/build" "${generator[@]}" \
  -DCMAKE_PREFIX_PATH="$work/moved-prefix" >"$work/configure.log" 2>&1 ||
  { cat "$work/configure.log"; exit 1; }
cmake --build "$work/build" >"$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }

# Every vtkSVDAG library the viewer loads comes from the copied prefix.
libraries=$(ldd "$work/build/SegmentationViewer" | grep -i svdag || true)
echo "$libraries"
if [[ -z "$libraries" ]] || grep -v -q -F "$work/moved-prefix/lib/" <<<"$libraries"; then
  echo "error: the viewer does not load vtkSVDAG from $work/moved-prefix/lib" >&2
  exit 1
fi

run=()
[[ -z "${DISPLAY:-}" ]] && run=(xvfb-run -a -s "-screen 0 1024x768x24")
status=0
"${run[@]}" ctest --test-dir "$work/build" --output-on-failure >"$work/ctest.log" 2>&1 || status=$?
if [[ $status -ne 0 ]]; then
  cat "$work/ctest.log"
else
  grep -E "tests passed|Total Test time" "$work/ctest.log"
fi
echo "examples/cxx: configure + build + ctest took $((SECONDS - start)) s"
exit $status
