#!/usr/bin/env bash
# Installs what deflex needs to build and test, from Debian 12's packages only. Safe to run again:
# apt-get skips what is already installed. Run as root (or with sudo available).
#   scripts/install-deps.sh           what the build and the main job need
#   scripts/install-deps.sh --tests   and what only the tests use (headless Chromium, about 100 MB)
#   scripts/install-deps.sh --lint    and clang-format and clang-tidy (scripts/lint.sh; CI)
set -euo pipefail
tests=0
lint=0
for arg in "$@"; do
  case "$arg" in
    --tests) tests=1 ;;
    --lint) lint=1 ;;
    *) echo "install-deps: unknown option $arg (--tests, --lint)" >&2; exit 2 ;;
  esac
done
packages=(
  build-essential cmake pkg-config
  # ninja: scripts/sanitize.sh builds with it (it compiles a module's tests while other modules build)
  ninja-build
  libeigen3-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev libfmt-dev
  protobuf-compiler libprotobuf-dev liburdfdom-dev libtinyxml-dev
  libgtest-dev libgmock-dev libbenchmark-dev liborocos-kdl-dev libboost-dev
  libspdlog-dev libxml2-dev
  # libcurl: an RDT force sensor's calibration page (netftapi2.xml) fetched from the sensor over HTTP
  libcurl4-openssl-dev
  # cpp-httplib: the live monitor page's server (deflex online --monitor, deflex monitor)
  libcpp-httplib-dev
  # dygraphs: the monitor page's charts, embedded in the program at build time (the page needs no network)
  libjs-dygraphs
  python3 python3-dev python3-numpy python3-pytest pybind11-dev
  # `pip install .` (pyproject.toml: setuptools' build_ext drives the CMake) into a venv that sees them
  # (--system-site-packages): setuptools and wheel build it, venv makes the environment
  python3-setuptools python3-wheel python3-venv
)
# chromium: the tests open the live monitor page in headless Chromium and read what it shows;
# python3-yaml: the Python tests give the case study a case as a dict read from the case file;
# python3-build: the wheel test builds one with `python3 -m build --no-isolation`; python3-mypy: the
# README's and the examples' Python are type-checked against the module's stubs;
# locales: a comma-decimal locale (de_DE.UTF-8, generated below) for the test that numbers parse the same
# whatever the process locale (it skips, saying so, where the locale is missing)
if [ "$tests" -eq 1 ]; then packages+=(chromium python3-yaml python3-build python3-mypy locales); fi
if [ "$lint" -eq 1 ]; then packages+=(clang-format clang-tidy); fi
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
sudo=""
if [ "$(id -u)" -ne 0 ]; then sudo=sudo; fi
if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#packages[@]} packages present" >&2
else
  echo "install-deps: installing ${missing[*]}" >&2
  export DEBIAN_FRONTEND=noninteractive
  $sudo apt-get update -qq
  $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}" >/dev/null
  echo "install-deps: done" >&2
fi
if [ "$tests" -eq 1 ] && ! locale -a 2>/dev/null | grep -qi '^de_DE\.utf-\?8$'; then
  echo "install-deps: generating the de_DE.UTF-8 locale (a test parses numbers under it)" >&2
  $sudo sed -i 's/^# *\(de_DE.UTF-8 UTF-8\)/\1/' /etc/locale.gen
  grep -q '^de_DE.UTF-8 UTF-8' /etc/locale.gen || echo 'de_DE.UTF-8 UTF-8' | $sudo tee -a /etc/locale.gen >/dev/null
  $sudo locale-gen >/dev/null
fi
