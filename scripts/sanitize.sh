#!/usr/bin/env bash
# Every test under AddressSanitizer + UndefinedBehaviorSanitizer (CI runs the untrusted-input and
# real-time modules' tests only: the whole tree takes about 40 min to build on two cores, see
# .ci/run). Run before landing a change to memory handling anywhere. Usage: scripts/sanitize.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
dir=${1:-build-asan}
cmake -S . -B "$dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
  -DDEFLEX_SANITIZE=ON -DDEFLEX_WERROR=ON -DDEFLEX_BUILD_BENCHMARKS=OFF >/dev/null
cmake --build "$dir" -j"$(nproc)"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
  ctest --test-dir "$dir" --output-on-failure -j"$(nproc)" --timeout 900
