#!/usr/bin/env python3
"""Wall time and peak memory of deflex's long jobs at growing sizes (the whole program, as a user
runs it): offline compensation of an N-point line written to CSV, and stiffness identification from
N measurement rows. Usage: bench/scale_bench.py [--deflex build/bin/deflex] [--sizes 1000,100000,1000000]
[--offline-max 10000000]. Offline output goes to /dev/null unless --keep-output, so the disk is left
out; identification reads a file this script writes once (the shipped KR 210 measurements repeated,
in /tmp).

--identify-only [--repeat 5]: only the identification at the largest size, beside its anchor in the
same run (build/bench/identify_file_bench's one-pass streamed least squares over the same file, the
same reader and regressor, a whole program too), repetitions interleaved, medians printed."""
import argparse
import os
import statistics
import resource
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)


def run(cmd):
    """Runs cmd as a child; returns (wall s, user+sys CPU s, peak RSS MiB)."""
    start = time.monotonic()
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, err = proc.communicate()
    wall = time.monotonic() - start
    status = proc.returncode
    if status != 0:
        sys.exit(f"scale_bench: {' '.join(cmd)} failed ({status}):\n{err.decode()[-2000:]}")
    return wall


def measure(cmd):
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    wall = run(cmd)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    # ru_maxrss of the children is the largest of any child so far (KiB on Linux): run each size
    # in its own python process when exact peaks matter (see --one).
    return wall, cpu, after.ru_maxrss / 1024.0


def identify_file(n):
    path = f"/tmp/deflex_scale_identify_{n}.csv"
    if os.path.exists(path):
        return path
    src = os.path.join(ROOT, "examples", "identify", "kr210_synthetic_measurements.csv")
    with open(src) as f:
        lines = [l for l in f if l.strip() and not l.startswith("#")]
    header, rows = lines[0], lines[1:]
    with open(path, "w") as out:
        out.write(header)
        for i in range(n):
            out.write(rows[i % len(rows)])
    return path


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--deflex", default=os.path.join(ROOT, "build", "bin", "deflex"))
    ap.add_argument("--sizes", default="1000,100000,1000000")
    ap.add_argument("--offline-max", type=int, default=10000000, help="also run offline at this size (0: not)")
    ap.add_argument("--one", help="internal: run one job (offline:N or identify:N) and print its figures")
    ap.add_argument("--keep-output", action="store_true", help="write the offline CSV to /tmp instead of /dev/null")
    ap.add_argument("--identify-only", action="store_true",
                    help="the identification at the largest size beside its anchor, interleaved, medians")
    ap.add_argument("--repeat", type=int, default=5, help="repetitions for --identify-only")
    ap.add_argument("--anchor", default=os.path.join(ROOT, "build", "bench", "identify_file_bench"),
                    help="the anchor's program (Google Benchmark, BM_OnePassLeastSquaresAnchor)")
    a = ap.parse_args()

    if a.one:
        kind, n = a.one.split(":")
        n = int(n)
        if kind == "offline":
            out = f"/tmp/deflex_scale_offline_{n}.csv" if a.keep_output else "/dev/null"
            cmd = [a.deflex, "offline", "--line", f"start_mm=1400;-300;900,end_mm=1600;300;900,points={n}",
                   "--force", "constant:fx_N=120,fz_N=-450", "-o", out]
        elif kind == "anchor":
            cmd = [a.anchor, "--benchmark_filter=OnePassLeastSquaresAnchor"]
            os.environ["DEFLEX_IDENTIFY_DATA"] = identify_file(n)
        else:
            cmd = [a.deflex, "identify", "--robot", os.path.join(ROOT, "examples", "identify", "kr210_true_stiffness.yaml"),
                   "--data", identify_file(n)]
        wall, cpu, peak = measure(cmd)
        print(f"{kind},{n},{wall:.3f},{cpu:.3f},{peak:.1f}")
        return

    sizes = [int(s) for s in a.sizes.split(",")]
    if a.identify_only:
        n = max(sizes)
        identify_file(n)
        figures = {"identify": [], "anchor": []}
        for _ in range(a.repeat):
            for kind in figures:  # interleaved: both see the same load
                line = subprocess.run([sys.executable, __file__, "--deflex", a.deflex, "--anchor", a.anchor, "--one",
                                       f"{kind}:{n}"], check=True, capture_output=True, text=True).stdout.strip()
                _, _, wall, cpu, peak = line.split(",")
                figures[kind].append((float(wall), float(cpu), float(peak)))
        print(f"{'job':10} {'N':>10} {'wall s':>9} {'CPU s':>9} {'peak MiB':>9}   (medians of {a.repeat}; CPU min-max)")
        for kind, runs in figures.items():
            cpus = [r[1] for r in runs]
            print(f"{kind:10} {n:>10} {statistics.median(r[0] for r in runs):>9.2f} {statistics.median(cpus):>9.2f} "
                  f"{statistics.median(r[2] for r in runs):>9.1f}   ({min(cpus):.2f}-{max(cpus):.2f})", flush=True)
        print(f"load average: {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
        return
    jobs = [("offline", n) for n in sizes]
    if a.offline_max and a.offline_max not in sizes:
        jobs.append(("offline", a.offline_max))
    jobs += [("identify", n) for n in sizes]
    print(f"{'job':10} {'N':>10} {'wall s':>9} {'CPU s':>9} {'us/item':>9} {'peak MiB':>9}")
    for kind, n in jobs:
        if kind == "identify":
            identify_file(n)  # written outside the measured run
        line = subprocess.run([sys.executable, __file__, "--deflex", a.deflex, "--one", f"{kind}:{n}"] +
                              (["--keep-output"] if a.keep_output else []),
                              check=True, capture_output=True, text=True).stdout.strip()
        _, _, wall, cpu, peak = line.split(",")
        print(f"{kind:10} {n:>10} {float(wall):>9.2f} {float(cpu):>9.2f} {float(cpu) / n * 1e6:>9.2f} {float(peak):>9.1f}",
              flush=True)


if __name__ == "__main__":
    main()
