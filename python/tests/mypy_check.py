#!/usr/bin/env python3
"""mypy on the Python a user copies: every ```python block of README.md and docs/python.md that is a
program (it imports deflex; the others are fragments of the text around them) and every example under
examples/python/, checked against the module's stubs (deflex/_deflex.pyi, py.typed) as a researcher's
editor or CI would check their own code. Any error fails, in the stubs themselves too (they are found
through MYPYPATH, as the user's own code is).

    mypy_check.py SOURCE_DIR MODULE_DIR WORK_DIR
"""
import pathlib
import re
import subprocess
import sys


def python_blocks(markdown):
    """The text of each ```python block, in order."""
    return re.findall(r"^```python\n(.*?)^```$", markdown, re.MULTILINE | re.DOTALL)


def main():
    source, module, work = (pathlib.Path(a).resolve() for a in sys.argv[1:4])
    work.mkdir(parents=True, exist_ok=True)
    files = []
    for doc in ("README.md", "docs/python.md"):
        for i, block in enumerate(python_blocks((source / doc).read_text(encoding="utf-8"))):
            if not re.search(r"^import .*\bdeflex\b", block, re.MULTILINE):
                continue
            name = work / f"{doc.replace('/', '_').replace('.md', '')}_block{i + 1}.py"
            name.write_text(block, encoding="utf-8")
            files.append(name)
    files += sorted((source / "examples" / "python").glob("*.py"))
    # A canary: mypy must see the stubs (a module it cannot find would be Any, and nothing would fail).
    canary = work / "canary.py"
    canary.write_text("import deflex\nreveal_type(deflex.Robot.builtin())\n", encoding="utf-8")
    files.append(canary)
    # Third-party modules without stubs (matplotlib, optional in the examples) are Any; deflex never is.
    config = work / "mypy.ini"
    config.write_text("[mypy]\n[mypy-matplotlib.*]\nignore_missing_imports = True\n", encoding="utf-8")
    if not (module / "deflex" / "_deflex.pyi").is_file():
        sys.exit(f"mypy_check: {module}/deflex/_deflex.pyi is missing (mypy's stubgen did not run)")
    command = [sys.executable, "-m", "mypy", "--config-file", str(config), "--no-incremental", "--cache-dir",
               str(work / "cache"), "--check-untyped-defs", "--python-version",
               f"{sys.version_info.major}.{sys.version_info.minor}", *map(str, files)]
    env = {"MYPYPATH": str(module), "PATH": "/usr/bin:/bin"}
    result = subprocess.run(command, capture_output=True, text=True, env=env, cwd=work)
    print(result.stdout, end="")
    print(result.stderr, end="", file=sys.stderr)
    print(f"mypy_check: {len(files)} files ({', '.join(f.name for f in files)})")
    if 'Revealed type is "deflex._deflex.Robot"' not in result.stdout:
        sys.exit("mypy_check: mypy did not read deflex's stubs (the canary's type is not deflex._deflex.Robot)")
    sys.exit(result.returncode)


if __name__ == "__main__":
    main()
