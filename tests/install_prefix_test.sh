#!/bin/sh
# `cmake --install --prefix P` as a user who owns P and nothing else: run as root (CI), the install runs
# as `nobody` into a scratch prefix that user owns, so a file meant for anywhere else fails it; the
# top level of / is listed before and after, and nothing may appear there; the Python package (module,
# stubs, py.typed) must be inside P and import from there.
#   install_prefix_test.sh CMAKE BUILD_DIR WORK_DIR [PYTHON PYTHON_SITE_RELATIVE]
set -eu
cmake=$1 build=$2 work=$3 python=${4:-} site=${5:-}
rm -rf "$work"
mkdir -p "$work"
prefix="$work/prefix"
mkdir "$prefix"
as_user=""
if [ "$(id -u)" -eq 0 ]; then
  # The manifest cmake --install writes into the build tree: a file that user may write, and nothing
  # else of the build tree.
  touch "$build/install_manifest.txt"
  chown nobody "$build/install_manifest.txt" "$prefix"
  chmod 755 "$work"
  as_user="setpriv --reuid=nobody --regid=nogroup --clear-groups --"
fi
ls -A / | sort >"$work/root-before.txt"
touch "$work/stamp"
sleep 1
# shellcheck disable=SC2086
if ! $as_user env HOME="$prefix" "$cmake" --install "$build" --prefix "$prefix" >"$work/install.log" 2>&1; then
  cat "$work/install.log" >&2
  echo "FAIL: cmake --install into $prefix as ${as_user:+nobody}${as_user:-$(id -un)} failed" >&2
  exit 1
fi
ls -A / | sort >"$work/root-after.txt"
if ! cmp -s "$work/root-before.txt" "$work/root-after.txt"; then
  echo "FAIL: new entries at the top of the file system:" >&2
  comm -13 "$work/root-before.txt" "$work/root-after.txt" >&2
  exit 1
fi
# Every path the install reported is inside the prefix.
outside=$(grep -E '^-- (Installing|Up-to-date):' "$work/install.log" | sed 's/^-- [A-Za-z-]*: //' | grep -v "^$prefix/" || true)
if [ -n "$outside" ]; then
  echo "FAIL: installed outside $prefix:" >&2
  echo "$outside" >&2
  exit 1
fi
# Nothing new in the places any user may write, but the prefix (and the manifest handed to the user
# above, which lies there when the build tree does, as in a clone under /tmp).
for d in /tmp /var/tmp /dev/shm; do
  [ -d "$d" ] || continue
  new=$(find "$d" -xdev -newer "$work/stamp" -user nobody 2>/dev/null | grep -v "^$work" |
    grep -vxF "$build/install_manifest.txt" || true)
  if [ -n "$new" ] && [ -n "$as_user" ]; then
    echo "FAIL: written outside the prefix:" >&2
    echo "$new" >&2
    exit 1
  fi
done
test -x "$prefix/bin/deflex"
test -f "$prefix/include/deflex/deflex.hpp"
if [ -n "$python" ]; then
  pkg="$prefix/$site/deflex"
  for f in __init__.py py.typed _deflex.pyi __init__.pyi; do
    test -f "$pkg/$f" || { echo "FAIL: $pkg/$f is missing" >&2; exit 1; }
  done
  ls "$pkg"/_deflex*.so >/dev/null
  cd /
  # shellcheck disable=SC2046,SC2086
  $as_user env PYTHONDONTWRITEBYTECODE=1 PYTHONPATH="$prefix/$site" "$python" -c \
    "import deflex, sys; assert deflex.__file__.startswith('$prefix/'), deflex.__file__; print(deflex.__file__)"
fi
echo "installed into $prefix only: ok"
