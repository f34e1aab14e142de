#!/usr/bin/env bash
# Builds the deflex Python module for a Python interpreter of your choice (a venv, pyenv or conda
# python, not only Debian's /usr/bin/python3) and installs it into that interpreter's own
# site-packages, then imports it from / to prove it.
#
#   scripts/python-module.sh                      the python3 first on PATH
#   scripts/python-module.sh --python PY          that interpreter (e.g. ~/venv/bin/python)
#   options: --build-dir DIR   where to build (default build-python/<the interpreter's ABI tag>)
#            --from-build DIR  use an existing deflex build (its library and CMake package): install
#                              its module when it was built for the same ABI (a venv of the
#                              interpreter that build used: no compiling), else compile only the
#                              module against that build (about a minute)
#            --rebuild         with --from-build: compile the module even when the ABI matches
#            --build-type T    CMake build type of what is compiled (default Release; None compiles
#                              the module unoptimised, a sixth faster, as the tests do)
#            --no-install      build only
#
# What the interpreter needs: NumPy (PY -m pip install numpy; conda install numpy; Debian:
# python3-numpy) and its C headers (Python.h: pyenv and conda builds have them; Debian: python3-dev).
# The C++ side needs what scripts/install-deps.sh installs. The library is built once a build
# directory (a few minutes on two cores); the module alone about a minute after that.
set -euo pipefail
cd "$(dirname "$0")/.."
python=python3
build_dir=""
from_build=""
rebuild=0
install=1
build_type=Release
while [ $# -gt 0 ]; do
  case "$1" in
    --python) python="$2"; shift 2 ;;
    --build-dir) build_dir="$2"; shift 2 ;;
    --from-build) from_build="$2"; shift 2 ;;
    --rebuild) rebuild=1; shift ;;
    --build-type) build_type="$2"; shift 2 ;;
    --no-install) install=0; shift ;;
    -h|--help) sed -n '2,21p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;;
    *) echo "python-module: unknown option '$1' (--help)" >&2; exit 2 ;;
  esac
done
say() { echo "python-module: $*" >&2; }
fail() { say "$*"; exit 1; }

exe=$(command -v "$python" || true)
[ -n "$exe" ] || fail "no interpreter '$python' (give --python PATH)"
exe=$("$exe" -c 'import sys; print(sys.executable)') || fail "$python does not run"
version=$("$exe" -c 'import sys; print("%d.%d.%d" % sys.version_info[:3])')
"$exe" -c 'import sys; sys.exit(0 if sys.version_info >= (3, 8) else 1)' ||
  fail "$exe is Python $version; deflex needs Python 3.8 or newer"
"$exe" -c 'import numpy' 2>/dev/null ||
  fail "$exe (Python $version) cannot import NumPy, which the module returns its arrays in: install it there ($exe -m pip install numpy, or conda install numpy; Debian's python3: apt-get install python3-numpy)"
include=$("$exe" -c 'import sysconfig; print(sysconfig.get_paths()["include"])')
[ -f "$include/Python.h" ] ||
  fail "$exe (Python $version) has no C headers ($include/Python.h is missing): Debian: apt-get install python3-dev (python$(echo "$version" | cut -d. -f1,2)-dev)"
soabi=$("$exe" -c 'import sysconfig; print(sysconfig.get_config_var("SOABI") or sysconfig.get_config_var("EXT_SUFFIX").strip("."))')
site=$("$exe" -c 'import sysconfig; print(sysconfig.get_paths()["platlib"])')
say "interpreter $exe (Python $version, $soabi); installs into $site"

if [ -n "$from_build" ] && [ "$rebuild" -eq 0 ] && ls "$from_build"/python/deflex/_deflex."$soabi".so >/dev/null 2>&1; then
  module_dir="$from_build/python/deflex"
  say "using the module $from_build built for the same ABI"
elif [ -n "$from_build" ]; then
  [ -f "$from_build/deflexConfig.cmake" ] ||
    fail "$from_build is no deflex build (no deflexConfig.cmake): build deflex there first (README), or drop --from-build"
  build_dir=${build_dir:-build-python/$soabi}
  say "compiling the module for $soabi in $build_dir against the library of $from_build"
  cmake -S python -B "$build_dir" -DCMAKE_BUILD_TYPE="$build_type" -Ddeflex_DIR="$(cd "$from_build" && pwd)" \
    -DPython3_EXECUTABLE="$exe" >/dev/null
  cmake --build "$build_dir" -j"$(nproc)" --target deflex_python
  module_dir="$build_dir/python/deflex"
else
  build_dir=${build_dir:-build-python/$soabi}
  say "building in $build_dir"
  cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE="$build_type" -DPython3_EXECUTABLE="$exe" -DDEFLEX_PYTHON=ON \
    -DDEFLEX_BUILD_TESTS=OFF -DDEFLEX_BUILD_BENCHMARKS=OFF >/dev/null
  cmake --build "$build_dir" -j"$(nproc)" --target deflex_python
  module_dir="$build_dir/python/deflex"
fi
[ "$install" -eq 1 ] || { say "built in $module_dir (not installed: --no-install)"; exit 0; }

# Into the interpreter's site-packages: a folder of our own, written beside and renamed into place.
# A deflex folder there that this script did not make (no deflex module in it) is left alone.
target="$site/deflex"
if [ -e "$target" ] && ! ls "$target"/_deflex.*.so >/dev/null 2>&1; then
  fail "$target exists and is not a deflex module this script installed: remove or move it yourself"
fi
mkdir -p "$site"
staging=$(mktemp -d "$site/.deflex-install.XXXXXX")
trap 'rm -rf "$staging"' EXIT
cp "$module_dir"/__init__.py "$module_dir"/_deflex."$soabi".so "$staging"/
for f in __init__.pyi _deflex.pyi py.typed; do
  if [ -f "$module_dir/$f" ]; then cp "$module_dir/$f" "$staging/"; fi
done
old=""
if [ -e "$target" ]; then old="$site/.deflex-old.$$"; mv "$target" "$old"; fi
mv "$staging" "$target"
trap - EXIT
if [ -n "$old" ]; then rm -rf "$old"; fi
(cd / && PYTHONPATH= "$exe" -c 'import deflex; print("python-module: import deflex:", deflex.__file__, deflex.__version__)')
