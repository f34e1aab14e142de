#!/usr/bin/env python3
"""A stand-in for an ABB controller in EGM path correction (EGMActMove + EGMMoveL/EGMMoveC), to try
`deflex online --link egm-path` without a robot. It behaves as the real controller does, never more
kindly:

- it runs its own program (here: the joint trajectory --program, as the RAPID program's path);
- every --period-ms (EGMActMove \\SampleRate) it sends an EgmRobot: feedback = where the arm is,
  planned = the programmed joints;
- each EgmSensorPathCorr carries the whole current offset (never an increment); the newest one is
  applied --dead-time-ms later. This script does not carry a robot model, so it reports the offsets it
  was sent (mm, in the correction frame) instead of moving joints; the arm follows the program.

  deflex online --link egm-path --period-ms 48 --egm-port 16511 \\
      --force-source csv:examples/online/force_replay.csv --loop &
  python3 examples/online/egm_path_correction_standin.py --port 16511 --program nominal.csv --seconds 5
"""
import argparse
import bisect
import csv
import math
import socket
import struct
import sys
import time

from egm_wire import egm_path_corr, egm_robot


def read_program(path):
    times, points = [], []
    with open(path, newline="") as f:
        rows = (r for r in csv.reader(f) if r and not r[0].startswith("#"))
        header = next(rows)
        cols = [header.index("q%d_deg" % j) for j in range(1, len(header))]
        t_col = header.index("t_s")
        for r in rows:
            times.append(float(r[t_col]))
            points.append([float(r[c]) for c in cols])
    return times, points


def sample(times, points, t):  # linear between the program's points: the controller's own path
    if t <= times[0]:
        return points[0]
    if t >= times[-1]:
        return points[-1]
    i = bisect.bisect_right(times, t) - 1
    u = (t - times[i]) / (times[i + 1] - times[i])
    return [a + u * (b - a) for a, b in zip(points[i], points[i + 1])]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--host", default="127.0.0.1", help="deflex's address")
    ap.add_argument("--port", type=int, default=6510, help="deflex's EGM port")
    ap.add_argument("--program", required=True, help="the controller's own program: a joint trajectory CSV")
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--period-ms", type=float, default=48.0, help="EGMActMove \\SampleRate")
    ap.add_argument("--dead-time-ms", type=float, default=48.0)
    args = ap.parse_args()
    times, points = read_program(args.program)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setblocking(False)
    deflex = (args.host, args.port)
    pending = []  # (due time, offset mm)
    active = (0.0, 0.0, 0.0)
    largest = 0.0
    sent = answers = ignored = 0
    start = time.monotonic()
    seq = 0
    next_t = start
    while time.monotonic() - start < args.seconds:
        now = time.monotonic()
        while True:
            try:
                data, _ = sock.recvfrom(4096)
            except BlockingIOError:
                break
            try:
                pos, _age = egm_path_corr(data)
            except (ValueError, IndexError, struct.error):
                ignored += 1
                continue
            answers += 1
            pending.append((now + args.dead_time_ms / 1000.0, pos))
        while pending and pending[0][0] <= now:
            active = pending.pop(0)[1]  # absolute: the newest replaces the last
            largest = max(largest, math.sqrt(sum(c * c for c in active)))
        planned = sample(times, points, now - start)
        seq += 1
        sock.sendto(egm_robot(seq, int((now - start) * 1000), planned, planned), deflex)
        sent += 1
        next_t += args.period_ms / 1000.0
        time.sleep(max(0.0, next_t - time.monotonic()))
    print("%d EgmRobot sent, %d path corrections taken, %d datagrams ignored" % (sent, answers, ignored))
    print("offset in force (mm, correction frame): %.4f %.4f %.4f; largest %.4f mm" % (active + (largest,)))
    return 0 if answers > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
