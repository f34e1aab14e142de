#!/usr/bin/env bash
# examples/consumer with deflex as a subproject (add_subdirectory): the configure succeeds, deflex's
# targets are there under deflex::, its tests, benchmarks and Python module are off, and it writes no
# build type into the consumer's cache. (Building it compiles the library again, which the installed-
# package test does not need to repeat.)
#   check_subdirectory.sh CMAKE SOURCE_DIR WORK_DIR
set -euo pipefail
cmake=$1 source_dir=$2 work=$3
rm -rf "$work"
mkdir -p "$(dirname "$work")"
"$cmake" -S "$source_dir/examples/consumer" -B "$work" -DDEFLEX_SOURCE_DIR="$source_dir" >"$work.log" 2>&1 ||
  { cat "$work.log"; exit 1; }
cache="$work/CMakeCache.txt"
if grep -q '^CMAKE_BUILD_TYPE:STRING=Release' "$cache"; then
  echo "FAIL: deflex forced a build type into the consumer's cache" >&2
  exit 1
fi
grep -q '^DEFLEX_BUILD_TESTS:BOOL=OFF' "$cache"
grep -q '^DEFLEX_BUILD_BENCHMARKS:BOOL=OFF' "$cache"
if grep -q '^DEFLEX_PYTHON:BOOL=ON' "$cache"; then echo "FAIL: the Python module is on in a subproject" >&2; exit 1; fi
targets=$("$cmake" --build "$work" --target help)
for t in deflex_consumer deflex_model deflex_offline deflex_online deflex_runtime deflex_standin; do
  echo "$targets" | grep -q "$t" || { echo "FAIL: no target $t" >&2; exit 1; }
done
echo "add_subdirectory: ok"
