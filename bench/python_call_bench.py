#!/usr/bin/env python3
"""The cost of one call from Python: a single configuration through fk, jacobian, deflect and the
online step, i.e. the per-call overhead a batch call amortises (argument checks and conversion, the
result array, the GIL released around the C++), beside the C++ work itself (build/bench/model_bench:
BM_Deflex_FK about 0.09 us, BM_Deflex_FK_Jacobian 0.11 us). Target: a single fk within 1.5 us.

    PYTHONPATH=build/python python3 bench/python_call_bench.py [--repeat 7] [--number 20000]

Prints the median over the repeats of the time a call, us, and the fastest repeat.
"""
import argparse
import statistics
import timeit

import numpy as np

import deflex


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=7)
    parser.add_argument("--number", type=int, default=20000)
    args = parser.parse_args()
    robot = deflex.Robot.builtin()
    q = np.array([0.0, 0.5, 0.2, 0.0, 0.9, 0.0])
    q_list = q.tolist()
    w = np.array([0.0, 0.0, -500.0, 0.0, 0.0, 0.0])
    compensator = deflex.OnlineCompensator(robot)
    t = [0.0]

    def step():
        t[0] += 0.004
        return compensator.step(t[0], q)

    calls = {
        "fk(q) (ndarray)": lambda: robot.fk(q),
        "fk(q) (list)": lambda: robot.fk(q_list),
        "jacobian(q)": lambda: robot.jacobian(q),
        "deflect(q, w)": lambda: robot.deflect(q, w),
        "OnlineCompensator.step(t, q)": step,
    }
    print(f"deflex {deflex.__version__}: one call, us (median of {args.repeat} x {args.number} calls; fastest)")
    for name, call in calls.items():
        times = [s / args.number * 1e6 for s in timeit.repeat(call, number=args.number, repeat=args.repeat)]
        print(f"  {name:32s} {statistics.median(times):7.3f}   ({min(times):.3f})")


if __name__ == "__main__":
    main()
