#!/usr/bin/env python3
"""Runs the README's and the docs' examples as they are written, so they cannot drift from the program.

Every ```sh block of README.md and of each --doc file must be preceded by a marker line:
  <!-- readme-test: run -->            the block is run with bash -eu (deflex on the PATH is this
                                       build's program) and must exit 0
  <!-- readme-test: skip REASON -->    not run, for the reason given (needs a robot, takes minutes)
  <!-- test-command -->                the build-and-test command CI itself runs
A ```console block whose lines start with "$ " is a transcript: each command is run and its output
must match the lines that follow it (numbers to 1e-9 absolute or 1e-4 relative, text exactly).
Each file's blocks run in order, in a fresh scratch directory of their own (a file's later blocks use
what its earlier blocks wrote, as a reader pasting them in order would). Commands run in a scratch directory holding links to the repository's examples/, data/ and docs/
and build/bin/ pointing at this build's programs, so README paths work unchanged.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys

NUMBER = re.compile(r"[-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?")


def blocks(readme):
    """(language, marker, first line number, text) of each fenced block."""
    lines = readme.splitlines()
    out = []
    i = 0
    while i < len(lines):
        m = re.match(r"^```(\w*)\s*$", lines[i])
        if not m or not m.group(1):
            i += 1
            continue
        lang = m.group(1)
        marker = ""
        for back in (i - 1, i - 2):
            if back >= 0 and lines[back].startswith("<!--"):
                marker = lines[back].strip()
                break
        j = i + 1
        while j < len(lines) and lines[j].strip() != "```":
            j += 1
        out.append((lang, marker, i + 1, "\n".join(lines[i + 1:j])))
        i = j + 1
    return out


def same_line(expected, actual):
    if NUMBER.sub("#", expected) != NUMBER.sub("#", actual):
        return False
    for e, a in zip(NUMBER.findall(expected), NUMBER.findall(actual)):
        x, y = float(e), float(a)
        if abs(x - y) > 1e-9 + 1e-4 * max(abs(x), abs(y)):
            return False
    return True


def run(cmd, work, env, timeout):
    return subprocess.run(["bash", "-euo", "pipefail", "-c", cmd], cwd=work, env=env, capture_output=True,
                          text=True, timeout=timeout)


def scratch(repo, work, bin_dir):
    """A scratch directory with the repository's examples/, data/, docs/ and build/bin/ linked in."""
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(os.path.join(work, "build"))
    for d in ("examples", "data", "docs"):
        os.symlink(os.path.join(repo, d), os.path.join(work, d))
    os.symlink(os.path.abspath(bin_dir), os.path.join(work, "build", "bin"))
    env = dict(os.environ)
    env["PATH"] = os.path.abspath(bin_dir) + os.pathsep + env.get("PATH", "")
    return env


def check_file(path, repo, work, bin_dir, failures, counts):
    """Runs one Markdown file's blocks in order in its own scratch directory."""
    env = scratch(repo, work, bin_dir)
    with open(path, encoding="utf-8") as f:
        text_of_file = f.read()
    name = os.path.relpath(os.path.abspath(path), repo)
    for lang, marker, line, text in blocks(text_of_file):
        where = f"{name}:{line}"
        if lang == "sh":
            if marker == "<!-- test-command -->" or marker.startswith("<!-- readme-test: skip "):
                counts[2] += 1
                continue
            if marker != "<!-- readme-test: run -->":
                failures.append(f"{where}: a sh block without a readme-test marker (run, or skip with a reason)")
                continue
            r = run(text, work, env, 240)
            counts[0] += 1
            print(f"{where}: exit {r.returncode}")
            if r.returncode != 0:
                failures.append(f"{where}: exit {r.returncode}\n{text}\n--- stdout\n{r.stdout}\n--- stderr\n{r.stderr}")
        elif lang == "console" and text.startswith("$ "):
            # Transcript: "$ command" lines, each followed by its expected output.
            steps = []
            for l in text.splitlines():
                if l.startswith("$ "):
                    steps.append([l[2:], []])
                elif steps and l.strip():
                    steps[-1][1].append(l)
            for cmd, expected in steps:
                counts[1] += 1
                r = run(cmd, work, env, 120)
                actual = [l for l in r.stdout.splitlines() if l.strip()]
                ok = r.returncode == 0 and len(actual) == len(expected) and all(
                    same_line(e, a) for e, a in zip(expected, actual))
                print(f"{where}: $ {cmd}: {'matches' if ok else 'DIFFERS'}")
                if not ok:
                    failures.append(f"{where}: $ {cmd}\nexit {r.returncode}\n--- the file says\n" + "\n".join(expected) +
                                    "\n--- the program says\n" + r.stdout + "\n--- stderr\n" + r.stderr)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--readme", required=True)
    ap.add_argument("--doc", action="append", default=[], help="a further Markdown file whose blocks run")
    ap.add_argument("--bin-dir", required=True)
    ap.add_argument("--work", required=True)
    args = ap.parse_args()
    repo = os.path.dirname(os.path.abspath(args.readme))
    failures = []
    counts = [0, 0, 0]  # sh blocks run, transcript commands checked, blocks skipped
    for index, path in enumerate([args.readme] + args.doc):
        work = os.path.join(os.path.abspath(args.work), str(index))
        check_file(path, repo, work, args.bin_dir, failures, counts)
    ran, transcripts, skipped = counts
    print(f"{ran} sh blocks run, {transcripts} transcript commands checked, {skipped} blocks skipped by their marker")
    if ran == 0 or transcripts == 0:
        failures.append("no runnable example found: the markers are missing")
    for f in failures:
        print("FAIL " + f, file=sys.stderr)
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
