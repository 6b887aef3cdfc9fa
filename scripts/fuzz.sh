#!/usr/bin/env bash
# Long fuzzing campaign over every volume reader and the .svdag loader (Testing/fuzz/).
#
#   bash scripts/fuzz.sh                    # 1 hour in all, every target
#   bash scripts/fuzz.sh 600 nrrd_gzip svdag_fixcrc      # 600 s for each target named
#   FUZZ_ASAN=1 bash scripts/fuzz.sh 1800   # against build-asan/ (scripts/sanitize.sh builds it)
#
# The test suite runs the same harness for about 60 s (Testing/Python/test_fuzz.py). Findings
# (crashes, hangs, unexpected exceptions, silently wrong volumes) land in
# bench/out/fuzz/findings/ with their logs; copy each into Testing/fuzz/crashes/ as
# <target>--<what-it-is>.<ext> so that test_fuzz replays it from then on. The corpus grows in
# bench/out/fuzz/corpus/ and is reused by the next campaign. Exit status 1 when anything was found.
set -uo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
SECONDS_ARG=${1:-3600}
shift || true
PER_TARGET=()
[ $# -gt 0 ] && PER_TARGET=(--per-target)
OUT=${FUZZ_OUT:-$ROOT/bench/out/fuzz}
PY=${FUZZ_PYTHON:-$ROOT/.venv/bin/python}

if [ -n "${FUZZ_ASAN:-}" ]; then
  BUILD=${SANITIZE_BUILD_DIR:-$ROOT/build-asan}
  [ -d "$BUILD/python/vtksvdag" ] || { echo "fuzz.sh: no $BUILD: run scripts/sanitize.sh first"; exit 1; }
  export LD_PRELOAD="$(gcc -print-file-name=libasan.so) $(gcc -print-file-name=libubsan.so)"
  export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0:halt_on_error=1:abort_on_error=1:max_allocation_size_mb=4096:allocator_may_return_null=1}
  export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
  export PYTHONPATH="$ROOT/Python:$BUILD/python${PYTHONPATH:+:$PYTHONPATH}"
  OUT=${FUZZ_OUT:-$ROOT/bench/out/fuzz-asan}
fi
mkdir -p "$OUT"
exec "$PY" Testing/fuzz/campaign.py --seconds "$SECONDS_ARG" "${PER_TARGET[@]}" --out "$OUT" "$@"
