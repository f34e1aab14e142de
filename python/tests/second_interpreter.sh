#!/usr/bin/env bash
# The module in a second interpreter, as a user with a venv has it: scripts/python-module.sh compiles
# the module for a fresh venv's python against this build's library (its CMake package, no library
# rebuilt) and installs it into the venv (PyPI is out of reach here, so the venv sees the system's
# NumPy through --system-site-packages), and the paper's workflow example runs under that venv's
# python alone (no PYTHONPATH), from another folder. A venv without NumPy is refused by
# the script with the command that fixes it, and importing deflex there says the same. The module is
# compiled unoptimised (--build-type None: 45 s of compiler time against 54 s; the library it calls is the build's).
# The venvs are made without pip (nothing is installed with it; with pip each took 5 s to make).
#   second_interpreter.sh PYTHON3 SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail
python3=$1 source_dir=$2 build_dir=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
unset PYTHONPATH
"$python3" -m venv --without-pip --system-site-packages "$work/venv"
"$source_dir/scripts/python-module.sh" --python "$work/venv/bin/python" --from-build "$build_dir" --rebuild \
  --build-type None --build-dir "$work/module-build"
test -f "$work/module-build/python/deflex/_deflex.pyi"  # compiled here, stubs and all
site=$("$work/venv/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["platlib"])')
test -f "$site/deflex/__init__.py"
(cd "$work" && PYTHONDONTWRITEBYTECODE=1 "$work/venv/bin/python" -c \
  "import deflex, sys; assert deflex.__file__.startswith('$site'), deflex.__file__; assert sys.prefix == '$work/venv'")
mkdir -p "$work/out"
(cd "$work/out" && PYTHONDONTWRITEBYTECODE=1 "$work/venv/bin/python" "$source_dir/examples/python/03_paper_workflow.py" .)
test -s "$work/out/paper_workflow.csv"
# Installed again over its own earlier install (the build's own module this time): replaced, not refused.
"$source_dir/scripts/python-module.sh" --python "$work/venv/bin/python" --from-build "$build_dir" >/dev/null
# An interpreter without NumPy: refused by name, and nothing installed.
"$python3" -m venv --without-pip "$work/bare"
if "$source_dir/scripts/python-module.sh" --python "$work/bare/bin/python" --from-build "$build_dir" 2>"$work/bare.err"; then
  echo "FAIL: an interpreter without NumPy was accepted" >&2
  exit 1
fi
grep -q "cannot import NumPy" "$work/bare.err"
grep -q "pip install numpy" "$work/bare.err"
bare_site=$("$work/bare/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["platlib"])')
test ! -e "$bare_site/deflex"
# A deflex folder the script did not make is left alone.
mkdir -p "$bare_site/deflex" && echo "mine" > "$bare_site/deflex/notes.txt"
"$python3" -m venv --without-pip --system-site-packages "$work/other"
other_site=$("$work/other/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["platlib"])')
mkdir -p "$other_site/deflex" && echo "mine" > "$other_site/deflex/notes.txt"
if "$source_dir/scripts/python-module.sh" --python "$work/other/bin/python" --from-build "$build_dir" 2>"$work/other.err"; then
  echo "FAIL: a user's deflex folder was replaced" >&2
  exit 1
fi
grep -q "is not a deflex module this script installed" "$work/other.err"
test "$(cat "$other_site/deflex/notes.txt")" = mine
echo "second interpreter: ok ($work/venv/bin/python)"
