"""`pip install .`: the deflex Python module built by the project's own CMake (pyproject.toml).

build_ext configures the project for the interpreter pip runs under (tests and benchmarks off, the
module on) and builds only the module and the libraries it links, then copies the extension and its
typed stubs (.pyi, py.typed) into the package. Environment variables (docs/python.md, "Install"):

  DEFLEX_FROM_BUILD=DIR    an existing deflex build: its module when it was built for this ABI (a venv
                           of the interpreter that build used: nothing compiled), else only the module
                           compiled against that build's library and CMake package
  DEFLEX_REBUILD=1         with DEFLEX_FROM_BUILD: compile the module even when the ABI matches
  DEFLEX_BUILD_TYPE=T      CMake build type of what is compiled (Release unless told; None compiles
                           the module unoptimised, a sixth faster)
  CMAKE_ARGS="..."         more arguments to the configure (e.g. -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
  CMAKE_BUILD_PARALLEL_LEVEL=N  compile jobs (every core unless told)
"""

import os
import re
import shlex
import shutil
import subprocess
import sys
import sysconfig
from pathlib import Path

from setuptools import Extension, setup
from setuptools.command.build_ext import build_ext

ROOT = Path(__file__).resolve().parent
STUBS = ("__init__.pyi", "_deflex.pyi", "py.typed")


def project_version():
    """The version of CMakeLists.txt's project(), the one source of it."""
    text = (ROOT / "CMakeLists.txt").read_text(encoding="utf-8")
    match = re.search(r"project\(deflex VERSION ([0-9]+\.[0-9]+\.[0-9]+)", text)
    if not match:
        raise RuntimeError("CMakeLists.txt: no 'project(deflex VERSION X.Y.Z' line")
    return match.group(1)


def fail(message):
    """Stops the build with one line that says what the interpreter lacks."""
    sys.stderr.write(f"deflex: {message}\n")
    raise SystemExit(1)


def check_interpreter():
    """NumPy and the C headers of this interpreter: the module needs both to be built."""
    exe, version = sys.executable, sys.version.split()[0]
    try:
        import numpy  # noqa: F401  (the module returns NumPy arrays)
    except ImportError:
        fail(
            f"{exe} (Python {version}) cannot import NumPy, which the module returns its arrays in: install it "
            f"there ({exe} -m pip install numpy, or conda install numpy; Debian's python3: apt-get install "
            "python3-numpy; a venv sees Debian's when made with --system-site-packages)"
        )
    include = Path(sysconfig.get_paths()["include"])
    if not (include / "Python.h").is_file():
        minor = ".".join(version.split(".")[:2])
        fail(
            f"{exe} (Python {version}) has no C headers ({include}/Python.h is missing): Debian: apt-get install "
            f"python3-dev (python{minor}-dev)"
        )


def run(command, **kwargs):
    print("deflex: " + " ".join(shlex.quote(str(c)) for c in command), flush=True)
    subprocess.run([str(c) for c in command], check=True, **kwargs)


class CMakeBuild(build_ext):
    """Builds deflex._deflex with CMake instead of compiling sources itself."""

    def build_extension(self, ext):
        check_interpreter()
        module_dir = self.cmake_module()
        built = sorted(module_dir.glob("_deflex*" + sysconfig.get_config_var("EXT_SUFFIX")))
        if not built:
            fail(f"the build left no _deflex{sysconfig.get_config_var('EXT_SUFFIX')} in {module_dir}")
        target = Path(self.get_ext_fullpath(ext.name))
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(built[0], target)
        for name in STUBS:
            if (module_dir / name).is_file():
                shutil.copyfile(module_dir / name, target.parent / name)
            else:
                print(f"deflex: no {name} (mypy's stubgen is missing: Debian python3-mypy)", flush=True)

    def cmake_module(self):
        """The folder holding the built module and its stubs."""
        build_type = os.environ.get("DEFLEX_BUILD_TYPE", "Release")
        extra = shlex.split(os.environ.get("CMAKE_ARGS", ""))
        jobs = os.environ.get("CMAKE_BUILD_PARALLEL_LEVEL", str(os.cpu_count() or 1))
        suffix = sysconfig.get_config_var("EXT_SUFFIX")
        temp = Path(self.build_temp).resolve()
        common = [f"-DCMAKE_BUILD_TYPE={build_type}", f"-DPython3_EXECUTABLE={sys.executable}", *extra]
        from_build = os.environ.get("DEFLEX_FROM_BUILD", "")
        if from_build:
            build = Path(from_build).resolve()
            if not (build / "deflexConfig.cmake").is_file():
                fail(f"DEFLEX_FROM_BUILD={from_build} is no deflex build (no deflexConfig.cmake in it)")
            same_abi = list((build / "python" / "deflex").glob("_deflex" + suffix))
            if same_abi and os.environ.get("DEFLEX_REBUILD", "") in ("", "0"):
                print(f"deflex: the module {build} built for this ABI ({suffix})", flush=True)
                return build / "python" / "deflex"
            run(["cmake", "-S", ROOT / "python", "-B", temp, f"-Ddeflex_DIR={build}", *common])
        else:
            run(["cmake", "-S", ROOT, "-B", temp, "-DDEFLEX_PYTHON=ON", "-DDEFLEX_BUILD_TESTS=OFF",
                 "-DDEFLEX_BUILD_BENCHMARKS=OFF", *common])
        run(["cmake", "--build", temp, "--target", "deflex_python", "-j", jobs])
        return temp / "python" / "deflex"


setup(
    version=project_version(),
    ext_modules=[Extension("deflex._deflex", sources=[])],
    cmdclass={"build_ext": CMakeBuild},
    # Out of the CMake build folder (`build/`, the README's) and out of the sources.
    options={"build": {"build_base": "build-python/setuptools"}},
    zip_safe=False,
)
