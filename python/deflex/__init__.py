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
        f"deflex needs NumPy, which this interpreter ({sys.executable}) cannot import; use the python3 "
        "that has it (Debian: /usr/bin/python3 with python3-numpy), the one deflex was built for"
    ) from error

from ._deflex import *  # noqa: F401,F403
from ._deflex import __version__  # noqa: F401
