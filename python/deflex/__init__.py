"""deflex from Python: the elastic deflection of industrial robots, predicted and compensated.

NumPy arrays in and out, SI units (m, rad, N, Nm, s), the names of the C++ API. See docs/python.md.

    import deflex
    robot = deflex.Robot.builtin()
    robot.fk([0, 0.5, 0.2, 0, 0.9, 0])   # 4x4 base_T_tcp, m
"""

import sys

try:
    import numpy  # noqa: F401  (the module returns NumPy arrays)
except ImportError as error:  # pragma: no cover - depends on the interpreter
    raise ImportError(
        f"deflex needs NumPy, which this interpreter ({sys.executable}) cannot import: install it there "
        f"({sys.executable} -m pip install numpy; Debian's python3: apt-get install python3-numpy; a venv sees "
        "Debian's when made with --system-site-packages), or install deflex into the python3 that has it "
        "(docs/python.md)"
    ) from error

try:
    from ._deflex import *  # noqa: F401,F403
    from ._deflex import __version__  # noqa: F401
    from . import _deflex
except ImportError as error:  # pragma: no cover - depends on the interpreter
    raise ImportError(
        f"deflex's extension module was built for another Python than this one ({sys.executable}, "
        f"{sys.version.split()[0]}): {error}. Build it for this interpreter from deflex's checkout: "
        f"{sys.executable} -m pip install --no-build-isolation . (docs/python.md)"
    ) from error


def _scalar_repr(self):
    """A repr that shows the object's scalar fields (numbers, strings, flags), for the classes that
    have none of their own."""
    fields = []
    for name in dir(type(self)):
        if name.startswith("_") or not isinstance(getattr(type(self), name), property):
            continue
        try:
            value = getattr(self, name)
        except Exception:  # noqa: BLE001  (a field that cannot be read now is left out)
            continue
        if isinstance(value, (bool, int, float, str)):
            fields.append(f"{name}={value!r}")
    return f"<deflex.{type(self).__name__} " + ", ".join(fields) + ">"


for _name in dir(_deflex):
    _cls = getattr(_deflex, _name)
    if isinstance(_cls, type) and _cls.__module__.startswith("deflex") and _cls.__repr__ is object.__repr__:
        _cls.__repr__ = _scalar_repr
del _name, _cls
