#!/usr/bin/env bash
# What a program of one's own gets from the installed package, against a scratch install:
#   - the previous release's consumer example (tests/install/consumer-0.1.0: examples/consumer as
#     released with deflex 0.1.0) builds and runs against 0.2; the one change a 0.1 consumer makes is the
#     version it asks find_package for (SameMinorVersion: a 0.1 request does not accept 0.2, and says so);
#   - the headers that moved in 0.2.0 still compile by their 0.1 paths, each with a deprecation warning
#     (silenced by DEFLEX_NO_DEPRECATED_HEADER_WARNINGS);
#   - the model compiles as C++17 for a C++17 program (its targets ask for C++17, not C++20);
#   - no private define of deflex's own dependencies (cpp-httplib's CPPHTTPLIB_*) reaches a consumer,
#     neither through the CMake targets nor through deflex.pc.
#   interface_test.sh CMAKE SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail
cmake=$1 source_dir=$2 build_dir=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
"$cmake" --install "$build_dir" --prefix "$work/prefix" >/dev/null
fail() { echo "FAIL: $*" >&2; exit 1; }

# The 0.1.0 example asks for 0.1: refused by the version rule, naming the version found.
cp -r "$source_dir/tests/install/consumer-0.1.0" "$work/consumer-0.1"
if "$cmake" -S "$work/consumer-0.1" -B "$work/consumer-0.1-refused" -DCMAKE_PREFIX_PATH="$work/prefix" \
  >"$work/refused.log" 2>&1; then
  fail "find_package(deflex 0.1) accepted deflex 0.2 (the version file is SameMinorVersion)"
fi
grep -q "0.2.0" "$work/refused.log" || fail "the refusal does not name the version found: $(cat "$work/refused.log")"
sed -i 's/find_package(deflex 0.1 /find_package(deflex 0.2 /' "$work/consumer-0.1/CMakeLists.txt"
"$cmake" -S "$work/consumer-0.1" -B "$work/consumer-0.1-build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
"$cmake" --build "$work/consumer-0.1-build" -j2 >/dev/null
"$work/consumer-0.1-build/deflex_consumer" "$source_dir/examples/robots/ros-industrial/kuka_kr120r2500pro.urdf"

# The interface checks: model17, old_headers, everything.
"$cmake" -S "$source_dir/tests/install/interface" -B "$work/interface" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
"$cmake" --build "$work/interface" -j2 >"$work/interface.log" 2>&1 || { cat "$work/interface.log" >&2; exit 1; }
"$work/interface/model17"
"$work/interface/old_headers"
"$work/interface/everything"
model17=$(grep -o '"command": "[^"]*model17.cpp[^"]*"' "$work/interface/compile_commands.json")
echo "$model17" | grep -q -- '-std=c++17' || fail "model17 is not compiled as C++17: $model17"
echo "$model17" | grep -q -- '-std=c++20' && fail "deflex::model forced C++20 on a C++17 consumer: $model17"
warned=$(grep -c "warning: deflex/.* is deprecated: include deflex/" "$work/interface.log" || true)
moved=$(find "$source_dir/src/compat/deflex" -name '*.hpp' | wc -l)
[ "$warned" -eq "$moved" ] || fail "$warned deprecation warnings for $moved moved headers: $(cat "$work/interface.log")"
grep -q CPPHTTPLIB "$work/interface/compile_commands.json" && fail "a CPPHTTPLIB define reached a consumer's compile line"
pc_dir=$(dirname "$(find "$work/prefix" -name deflex.pc | head -n 1)")
cflags=$(PKG_CONFIG_PATH="$pc_dir" pkg-config --cflags deflex)
case "$cflags" in *CPPHTTPLIB*) fail "deflex.pc hands its users cpp-httplib's defines: $cflags" ;; esac
# Silenced on request.
# shellcheck disable=SC2086
c++ -fsyntax-only -DDEFLEX_NO_DEPRECATED_HEADER_WARNINGS $cflags "$source_dir/tests/install/interface/old_headers.cpp" \
  2>"$work/silenced.log"
grep -q "deprecated" "$work/silenced.log" && fail "DEFLEX_NO_DEPRECATED_HEADER_WARNINGS did not silence: $(cat "$work/silenced.log")"
echo "consumer interface: ok"
