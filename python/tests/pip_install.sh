#!/usr/bin/env bash
# `pip install .` and a wheel, as a researcher with a venv does it, without network (PyPI is out of
# reach here): the venvs see the system's NumPy, setuptools and wheel through --system-site-packages,
# and the builds use them (--no-build-isolation).
#   1. pip install from a copy of the checkout into a fresh venv: the module compiled by the project's
#      CMake for that venv's python, against this build's library (DEFLEX_FROM_BUILD, DEFLEX_REBUILD;
#      unoptimised, as the tests compile it); stubs and py.typed installed beside it; the paper's
#      workflow example run under that venv alone from another folder;
#   2. a wheel built by `python3 -m build --no-isolation` (Debian's python3-build; `pip wheel` where it
#      is missing) and installed into another fresh venv, imported there from /;
#   3. an interpreter without NumPy refused by setup.py with the command that fixes it.
#   pip_install.sh PYTHON3 SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail
python3=$1 source_dir=$2 build_dir=$3 work=$4
rm -rf "$work" && mkdir -p "$work/src"
unset PYTHONPATH
export PYTHONDONTWRITEBYTECODE=1 PIP_DISABLE_PIP_VERSION_CHECK=1 PIP_NO_INDEX=1
# The checkout without its build folders: what pip sees of a fresh clone.
tar -C "$source_dir" --exclude='./build*' --exclude=./.git --exclude='./out*' --exclude='*.egg-info' -cf - . |
  tar -C "$work/src" -xf -
site_of() { "$1" -c 'import sysconfig; print(sysconfig.get_paths()["platlib"])'; }
check_installed() {  # PYTHON: deflex imports from that interpreter's site-packages, stubs beside it
  local site
  site=$(site_of "$1")
  (cd / && "$1" -c "import deflex, sys; assert deflex.__file__.startswith('$site/'), deflex.__file__; \
assert deflex.__version__ == '$version', deflex.__version__; print('import deflex:', deflex.__file__)")
  for f in __init__.py _deflex.pyi __init__.pyi py.typed; do
    test -f "$site/deflex/$f" || { echo "FAIL: $site/deflex/$f is missing" >&2; exit 1; }
  done
}
version=$(sed -n 's/^project(deflex VERSION \([0-9.]*\).*/\1/p' "$source_dir/CMakeLists.txt")

# 1. pip install . (compiling the module for this venv; -v shows the build's commands, checked below).
"$python3" -m venv --system-site-packages "$work/venv"
(cd "$work/src" && DEFLEX_FROM_BUILD="$build_dir" DEFLEX_REBUILD=1 DEFLEX_BUILD_TYPE=None \
  "$work/venv/bin/python" -m pip install -v --no-build-isolation . >"$work/pip.log" 2>&1) ||
  { cat "$work/pip.log" >&2; exit 1; }
grep -q "cmake --build" "$work/pip.log" || { echo "FAIL: pip did not compile the module" >&2; exit 1; }
check_installed "$work/venv/bin/python"
mkdir -p "$work/out"
(cd "$work/out" && "$work/venv/bin/python" "$source_dir/examples/python/03_paper_workflow.py" .)
test -s "$work/out/paper_workflow.csv"

# 2. A wheel, installed into a fresh venv (the build's own module: the same interpreter's ABI).
if "$python3" -c 'import build' 2>/dev/null; then
  (cd "$work/src" && DEFLEX_FROM_BUILD="$build_dir" "$python3" -m build --no-isolation --wheel --outdir "$work/dist" . \
    >"$work/wheel.log" 2>&1) || { cat "$work/wheel.log" >&2; exit 1; }
else
  (cd "$work/src" && DEFLEX_FROM_BUILD="$build_dir" "$python3" -m pip wheel --no-build-isolation --no-deps \
    -w "$work/dist" . >"$work/wheel.log" 2>&1) || { cat "$work/wheel.log" >&2; exit 1; }
fi
wheel=$(ls "$work"/dist/deflex-"$version"-*.whl)
"$python3" -m venv --system-site-packages "$work/wheel-venv"
"$work/wheel-venv/bin/python" -m pip install "$wheel" >"$work/wheel-install.log" 2>&1 ||
  { cat "$work/wheel-install.log" >&2; exit 1; }
check_installed "$work/wheel-venv/bin/python"
(cd / && "$work/wheel-venv/bin/python" -c "import deflex; print(deflex.Robot.builtin().fk([0, 0.5, 0.2, 0, 0.9, 0]))")

# 3. No NumPy: refused before anything is compiled, naming the fix.
"$python3" -m venv "$work/bare"
if (cd "$work/src" && "$work/bare/bin/python" setup.py -q build_ext 2>"$work/bare.err"); then
  echo "FAIL: an interpreter without NumPy was accepted" >&2
  exit 1
fi
grep -q "cannot import NumPy" "$work/bare.err" && grep -q "pip install numpy" "$work/bare.err" ||
  { cat "$work/bare.err" >&2; exit 1; }
echo "pip install and wheel: ok ($wheel)"
