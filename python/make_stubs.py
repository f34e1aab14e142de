#!/usr/bin/env python3
"""Typed stubs of the deflex module (deflex/_deflex.pyi, deflex/__init__.pyi, py.typed), written from the
signatures pybind11 puts in every docstring of the built module, so that a type checker sees what the
module takes and gives: static methods as static methods, each overload, the ArrayLike an array
property takes beside the array it gives, NumPy's NDArray for arrays, str or os.PathLike for paths.
Run by the build after every link of the module (python/CMakeLists.txt) and by setup.py's build.

    make_stubs.py PACKAGE_DIR      (the folder holding __init__.py and the built _deflex module)
"""
import importlib
import pathlib
import re
import sys

HEADER = '''"""Typed signatures of deflex's extension module (written by python/make_stubs.py from the module)."""
import os
import typing
from typing import Any, Dict, List, Optional, Tuple, Union, overload

import numpy
import numpy.typing

'''

SIGNATURE = re.compile(r"^(?:\d+\. )?(\w*)\((.*)\) -> (.+)$")


def python_type(text):
    """A pybind11 type name as the stubs write it."""
    text = text.replace("deflex._deflex.", "")
    text = re.sub(r"numpy\.ndarray\[bool\]", "numpy.typing.NDArray[numpy.bool_]", text)
    text = re.sub(r"numpy\.ndarray\[([\w.]+)\]", r"numpy.typing.NDArray[\1]", text)
    text = re.sub(r"\bhandle\b", "Any", text)
    return text


def split_top(text):
    """Splits at the commas outside brackets and quotes."""
    parts, depth, quote, current = [], 0, "", ""
    for ch in text:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "'\"":
            quote = ch
        elif ch in "([{":
            depth += 1
        elif ch in ")]}":
            depth -= 1
        if ch == "," and depth == 0 and not quote:
            parts.append(current.strip())
            current = ""
        else:
            current += ch
    if current.strip():
        parts.append(current.strip())
    return parts


def parameters(text, method):
    """The parameter list of a signature's text, `self` first for a method."""
    out = []
    for i, p in enumerate(split_top(text)):
        if p in ("*", "/") or p.startswith("*"):
            out.append(p.split(":")[0])
            continue
        name, _, rest = p.partition(":")
        annotation, eq, _default = rest.partition("=")
        name = name.strip()
        if method and i == 0:
            out.append("self")
            continue
        if re.fullmatch(r"arg\d+", name):
            name = f"__{name}"  # positional only in pybind11's own sense: no keyword
        item = f"{name}: {python_type(annotation.strip())}" if annotation.strip() else name
        out.append(item + (" = ..." if eq else ""))
    return ", ".join(out)


def signatures(doc, name):
    """(parameters text, return text) of every signature of a pybind11 docstring for `name` ("" for a
    property's accessor): its first line, or the numbered lines of an overloaded function."""
    lines = (doc or "").splitlines()
    if len(lines) > 1 and lines[1].strip() == "Overloaded function.":
        candidates = [line for line in lines[2:] if re.match(r"^\d+\. ", line)]
    else:
        candidates = lines[:1]
    found = []
    for line in candidates:
        m = SIGNATURE.match(line.strip())
        if m and m.group(1) == name:
            found.append((m.group(2), m.group(3)))
    return found


def return_type(text):
    """A result's type: pybind11's `object` (a py::object result: a dict, a list, ...) is Any, so that it
    can be indexed without a cast."""
    t = python_type(text)
    return "Any" if t == "object" else t


def function_lines(name, doc, indent="", method=False, static=False):
    sigs = signatures(doc, name)
    if not sigs:
        return []
    lines = []
    for params, ret in sigs:
        if len(sigs) > 1:
            lines.append(f"{indent}@overload")
        if static:
            lines.append(f"{indent}@staticmethod")
        lines.append(f"{indent}def {name}({parameters(params, method and not static)}) -> {return_type(ret)}: ...")
    return lines


def property_lines(name, prop, indent):
    getter = signatures(prop.fget.__doc__, "")
    ret = return_type(getter[0][1]) if getter else "Any"
    lines = [f"{indent}@property", f"{indent}def {name}(self) -> {ret}: ..."]
    if prop.fset is not None:
        setter = signatures(prop.fset.__doc__, "")
        value = "Any"
        if setter:
            args = split_top(setter[0][0])
            value = python_type(args[-1].partition(":")[2].strip()) if len(args) > 1 else "Any"
        if value == "Any" and "NDArray" in ret:
            value = "numpy.typing.ArrayLike"  # every array property is set from any array-like
        lines += [f"{indent}@{name}.setter", f"{indent}def {name}(self, value: {value}) -> None: ..."]
    return lines


def class_lines(cls):
    if issubclass(cls, BaseException):
        bases = ", ".join(b.__name__ for b in cls.__bases__)
        return [f"class {cls.__name__}({bases}): ...", ""]
    body = []
    for name, value in sorted(vars(cls).items()):
        kind = type(value).__name__
        if name.startswith("__") and name not in ("__init__", "__iter__", "__len__", "__getitem__"):
            continue
        if kind == "staticmethod":
            body += function_lines(name, value.__func__.__doc__, "    ", static=True)
        elif kind == "instancemethod":
            body += function_lines(name, value.__func__.__doc__, "    ", method=True)
        elif kind == "property":
            body += property_lines(name, value, "    ")
    return [f"class {cls.__name__}:"] + (body or ["    ..."]) + [""]


def main():
    package = pathlib.Path(sys.argv[1]).resolve()
    sys.path.insert(0, str(package.parent))
    module = importlib.import_module(f"{package.name}._deflex")
    out = [HEADER]
    functions = []
    for name, value in sorted(vars(module).items()):
        if name.startswith("_"):
            continue
        if isinstance(value, type):
            out += class_lines(value)
        elif callable(value):
            functions += function_lines(name, value.__doc__)
    out += functions
    out += ["", "__version__: str", ""]
    (package / "_deflex.pyi").write_text("\n".join(out), encoding="utf-8")
    (package / "__init__.pyi").write_text(
        '"""deflex: see _deflex.pyi."""\nfrom ._deflex import *\nfrom ._deflex import __version__ as __version__\n',
        encoding="utf-8")
    (package / "py.typed").write_text("", encoding="utf-8")


if __name__ == "__main__":
    main()
