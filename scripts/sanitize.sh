#!/usr/bin/env bash
# Tests under AddressSanitizer + UndefinedBehaviorSanitizer, at -O1 -g1 (2.5x Release's compile
# time; -O2 -g is 6.5x).
#   scripts/sanitize.sh [BUILD_DIR]                 every test (about 40 min to build on two cores)
#   scripts/sanitize.sh BUILD_DIR MODULE [MODULE..]  only those modules' test programs (what CI runs)
# DEFLEX_SANITIZE_EXCEPT="m1;m2" in the environment compiles those modules without the sanitizers.
# DEFLEX_SANITIZE_DEBUG=-g0 leaves out the line tables (CI does: -g1 costs 46 % more compile time under
# the sanitizers; a report then names functions without lines, and a run here with the default gives them).
# Run every test before landing a change to memory handling anywhere.
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build-asan}
shift || true
# Ninja when the directory is new: unlike make it compiles a target's sources while the modules it
# links are still building, so both cores stay busy (a directory made by make keeps make).
generator=()
if [ ! -f "$dir/CMakeCache.txt" ] && command -v ninja >/dev/null; then
  generator=(-G Ninja)
fi
cmake -S . -B "$dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 ${DEFLEX_SANITIZE_DEBUG:--g1} -DNDEBUG" \
  -DDEFLEX_SANITIZE=ON "-DDEFLEX_SANITIZE_EXCEPT=${DEFLEX_SANITIZE_EXCEPT:-}" -DDEFLEX_WERROR=ON \
  -DDEFLEX_BUILD_BENCHMARKS=OFF >/dev/null
targets=()
labels=()
for m in "$@"; do
  targets+=(--target "deflex_${m}_tests")
  labels+=("$m")
done
cmake --build "$dir" -j"$(nproc)" "${targets[@]}"
select=()
if [ ${#labels[@]} -gt 0 ]; then
  select=(-L "^($(IFS='|'; echo "${labels[*]}"))\$")
fi
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir "$dir" --output-on-failure -j"$(nproc)" --timeout 900 "${select[@]}"
