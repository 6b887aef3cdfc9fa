#!/usr/bin/env bash
# Builds vtkSVDAG with AddressSanitizer + UndefinedBehaviorSanitizer in build-asan/ and runs the
# C++ tests (ctest) and the Python reader and file tests (pytest) against that build.
#
#   bash scripts/sanitize.sh            # configure, build, ctest, pytest
#   SANITIZE_PYTESTS="Testing/Python/test_api.py" bash scripts/sanitize.sh   # other Python tests
#   SANITIZE_SKIP_BUILD=1 bash scripts/sanitize.sh                          # reuse the build
#
# Needs the .venv that scripts/setup.sh makes (pytest, h5py, nibabel, ...). A full build takes
# about half an hour on 2 cores; the tests a few minutes. Any sanitizer report fails the run:
# UBSan aborts (-fno-sanitize-recover), ASan aborts on the first error.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
BUILD=${SANITIZE_BUILD_DIR:-$ROOT/build-asan}
JOBS=${SANITIZE_JOBS:-2}
PY=${SANITIZE_PYTHON:-$ROOT/.venv/bin/python}
PYTESTS=${SANITIZE_PYTESTS:-"Testing/Python/test_reader_formats.py Testing/Python/test_reader_pieces.py Testing/Python/test_svdag_file.py Testing/Python/test_svdag_format1.py Testing/Python/test_fuzz.py"}

[ -x "$PY" ] || { echo "sanitize.sh: $PY missing: run scripts/setup.sh first"; exit 1; }
t0=$(date +%s)
if [ -z "${SANITIZE_SKIP_BUILD:-}" ]; then
  cmake -S . -B "$BUILD" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DVTKSVDAG_SANITIZE=ON \
    -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null || { echo "sanitize.sh: configure failed"; exit 1; }
  cmake --build "$BUILD" -j "$JOBS" || { echo "sanitize.sh: build failed"; exit 1; }
fi
t1=$(date +%s)

# halt_on_error: the first report fails the test. detect_leaks=0: Python and VTK's singletons
# keep memory until exit by design. Vulkan/Mesa and python3 itself are not instrumented.
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:halt_on_error=1:abort_on_error=1:max_allocation_size_mb=4096:allocator_may_return_null=1:detect_stack_use_after_return=0}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}

status=0
echo "== ctest (ASan+UBSan) in $BUILD"
xvfb-run -a -s "-screen 0 1024x768x24" ctest --test-dir "$BUILD" --output-on-failure -j "$JOBS" \
  | tee "$BUILD/sanitize-ctest.log" || status=1
t2=$(date +%s)

# python3 is not instrumented: the ASan runtime has to be loaded first, by LD_PRELOAD. The wrapped
# modules come from $BUILD/python (PYTHONPATH before the .venv's .pth that names build/python);
# test_fuzz's own check below makes sure of it.
LIBASAN=$(gcc -print-file-name=libasan.so)
LIBUBSAN=$(gcc -print-file-name=libubsan.so)
export LD_PRELOAD="$LIBASAN $LIBUBSAN"
export PYTHONPATH="$ROOT/Python:$BUILD/python${PYTHONPATH:+:$PYTHONPATH}"
export VTKSVDAG_EXPECT_BUILD="$BUILD"
echo "== pytest (ASan+UBSan) against $BUILD/python"
where=$("$PY" -c 'import vtksvdag.vtkSVDAGIO as m, vtksvdag.vtkSVDAGCore as c; print(m.__file__); print(c.__file__)') \
  || { echo "sanitize.sh: the sanitized modules do not import"; exit 1; }
echo "$where"
if printf '%s\n' "$where" | grep -qv "^$BUILD/python/"; then
  echo "sanitize.sh: vtksvdag's wrapped modules do not come from $BUILD"; exit 1
fi
# shellcheck disable=SC2086
"$PY" -m pytest -q $PYTESTS | tee "$BUILD/sanitize-pytest.log" || status=1
t3=$(date +%s)
echo "sanitize.sh: build $((t1 - t0)) s, ctest $((t2 - t1)) s, pytest $((t3 - t2)) s; status $status"
# The summary bench/stability.py puts into docs/stability.md.
{
  echo "$(date -u '+%Y-%m-%d %H:%M UTC'), ASan+UBSan ($BUILD), status $status"
  grep -E "tests passed|tests failed" "$BUILD/sanitize-ctest.log" | tail -1
  tail -1 "$BUILD/sanitize-pytest.log"
  echo "build $((t1 - t0)) s, ctest $((t2 - t1)) s, pytest $((t3 - t2)) s"
} > "$BUILD/sanitize-summary.txt"
exit $status
