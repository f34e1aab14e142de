#!/usr/bin/env bash
# deflex as an installed library, as an integrator uses it: cmake --install into a scratch prefix, then
# examples/consumer built against it with find_package(deflex) and run on a ROS-Industrial URDF, and a
# program built with nothing but the compiler and pkg-config's flags for deflex.pc.
#   check_installed.sh CMAKE SOURCE_DIR BUILD_DIR WORK_DIR
set -euo pipefail
cmake=$1 source_dir=$2 build_dir=$3 work=$4
rm -rf "$work" && mkdir -p "$work"
"$cmake" --install "$build_dir" --prefix "$work/prefix" >/dev/null
test -f "$work/prefix/include/deflex/deflex.hpp" && test -f "$work/prefix/include/deflex/version.hpp"
if ls "$work"/prefix/include/deflex/*/detail >/dev/null 2>&1; then
  echo "FAIL: a module's detail/ headers were installed" >&2
  exit 1
fi
"$cmake" -S "$source_dir/examples/consumer" -B "$work/build" -DCMAKE_PREFIX_PATH="$work/prefix" \
  -DCMAKE_BUILD_TYPE=Release >/dev/null
"$cmake" --build "$work/build" -j2
"$work/build/deflex_consumer" "$source_dir/examples/robots/ros-industrial/kuka_kr120r2500pro.urdf"
# pkg-config: the flags of deflex.pc alone build and link a program on the model.
cat > "$work/fk.cpp" <<'CPP'
#include <cstdio>
#include "deflex/model/kinematics.hpp"
#include "deflex/robotfile/robot_io.hpp"
int main() {
  const deflex::RobotModel robot = deflex::builtin_irb6700();
  deflex::Workspace ws(robot);
  const double x = deflex::tcp_pose(robot, ws, deflex::JointVector::Zero(6)).translation().x();
  std::printf("%.3f\n", x);
  return x > 1.0 && x < 3.0 ? 0 : 1;
}
CPP
pc=$(find "$work/prefix" -name deflex.pc -path '*pkgconfig*' | head -n 1)
test -n "$pc"
libdir=$(dirname "$pc")
# shellcheck disable=SC2046
c++ "$work/fk.cpp" -o "$work/fk" $(PKG_CONFIG_PATH="$libdir" pkg-config --cflags --libs deflex)
"$work/fk"
echo "installed package: ok"
