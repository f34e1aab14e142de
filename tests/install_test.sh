#!/bin/sh
# Installs the build into a scratch prefix and runs the installed deflex from an unrelated directory
# with nothing but the prefix's bin and the system directories on the PATH.
#   install_test.sh BUILD_DIR PREFIX
set -eu
build=$1
prefix=$2
rm -rf "$prefix"
cmake --install "$build" --prefix "$prefix" >/dev/null
test -x "$prefix/bin/deflex"
test -f "$prefix/share/deflex/data/robots/abb_irb6700_300_270.yaml"
test -f "$prefix/share/deflex/examples/robots/kuka_kr210_r2700.yaml"
cd /
out=$(PATH="$prefix/bin:/usr/bin:/bin" deflex fk --joints-deg "0,30,10,0,50,0")
echo "$out"
echo "$out" | grep -q "TCP position (mm, base frame): 1949.886 0.000 895.428"
# The installed examples are usable as they are.
PATH="$prefix/bin:/usr/bin:/bin" deflex deflect --robot "$prefix/share/deflex/examples/robots/kuka_kr210_r2700.yaml" \
  --joints-deg "0,10,10,0,40,0" --wrench "0,0,-500,0,0,0" | grep -q "TCP deflection"
echo "installed deflex runs from $(pwd) on the PATH"
