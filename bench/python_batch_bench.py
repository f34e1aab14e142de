#!/usr/bin/env python3
"""Throughput of the Python module's batch calls (fk, jacobian, deflect over 100,000 IRB6700
configurations in one call each) against the C++ loop doing the same work (build/bench/batch_bench).

Run from the repository after building:
    PYTHONPATH=build/python python3 bench/python_batch_bench.py [--repetitions 5] [--cpp build/bench/batch_bench]
Prints per call the median time (wall and CPU) of each side and Python's throughput as a share of
C++'s (CPU time: the machine is shared). Exit status 1 with --check when a share is below 80 %.
"""

import argparse
import json
import statistics
import subprocess
import sys
import time

import numpy as np

import deflex

N = 100_000


def time_python(call, repetitions):
    wall, cpu = [], []
    call()  # warm up (first touch of the output pages)
    for _ in range(repetitions):
        w0, c0 = time.perf_counter(), time.process_time()
        call()
        wall.append(time.perf_counter() - w0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall), statistics.median(cpu)


def time_cpp(binary, repetitions):
    out = subprocess.run([binary, f"--benchmark_repetitions={repetitions}", "--benchmark_report_aggregates_only=true",
                          "--benchmark_format=json"], capture_output=True, text=True, check=True).stdout
    figures = {}
    for b in json.loads(out)["benchmarks"]:
        if b.get("aggregate_name") == "median":
            scale = {"ms": 1e-3, "us": 1e-6, "ns": 1e-9, "s": 1.0}[b["time_unit"]]
            figures[b["run_name"].replace("BM_Batch100k_", "")] = (b["real_time"] * scale, b["cpu_time"] * scale)
    return figures


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--repetitions", type=int, default=5)
    parser.add_argument("--cpp", default="build/bench/batch_bench")
    parser.add_argument("--check", action="store_true", help="exit 1 if Python reaches less than 80%% of C++")
    args = parser.parse_args()

    robot = deflex.Robot.builtin()
    rng = np.random.default_rng(1)
    lo, hi = robot.lower_limits, robot.upper_limits
    q = lo + (hi - lo) * rng.random((N, robot.dof))
    wrench = np.array([400.0, -300.0, -650.0, 0.0, 0.0, 0.0])
    calls = {"FK": lambda: robot.fk(q), "Jacobian": lambda: robot.jacobian(q), "Deflect": lambda: robot.deflect(q, wrench)}

    cpp = time_cpp(args.cpp, args.repetitions)
    print(f"{N} configurations a call, median of {args.repetitions}; ms per call (wall / CPU)")
    print(f"{'call':<10} {'C++ loop':>18} {'Python batch':>18} {'Python/C++ throughput (CPU)':>30}")
    worst = float("inf")
    for name, call in calls.items():
        py_wall, py_cpu = time_python(call, args.repetitions)
        cpp_wall, cpp_cpu = cpp[name]
        share = cpp_cpu / py_cpu
        worst = min(worst, share)
        print(f"{name:<10} {cpp_wall * 1e3:8.2f} / {cpp_cpu * 1e3:7.2f} {py_wall * 1e3:8.2f} / {py_cpu * 1e3:7.2f} "
              f"{100 * share:29.0f}%")
    if args.check and worst < 0.8:
        print(f"Python reaches {100 * worst:.0f}% of the C++ loop's throughput, below 80%", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
