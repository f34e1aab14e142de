#!/usr/bin/env python3
"""A stand-in for an ABB controller in EGM position guidance (EGMActJoint + EGMRunJoint), to try
`deflex online --link egm-joint` without a robot. It behaves as the real controller does, never more
kindly:

- every --period-ms it sends an EgmRobot: feedback = where the arm is (motor side), planned = the
  target it is following, i.e. the sensor's own last target;
- it takes each EgmSensor's joints as the absolute target (and its speed reference), filters them
  (--lowpass-hz, the controller's \\LpFilter), and after --dead-time-ms its servo follows with
  speed = gain * (target - position) + speed reference;
- with no answer for --comm-timeout-s it stops EGM: the arm holds and no more messages go out.

The arm starts at rest at --start-deg (or the first row of --program). At the end it prints what it
saw; --log writes every cycle (time, feedback, target). Python standard library only.

  deflex offline --circle default --force ldbb:phi_deg=30,force_N=400 --nominal-trajectory nominal.csv
  deflex online --link egm-joint --program nominal.csv --egm-port 16510 \\
      --force-source csv:examples/online/force_replay.csv --loop &
  python3 examples/online/egm_position_guidance_standin.py --port 16510 --program nominal.csv --seconds 5
"""
import argparse
import csv
import math
import socket
import struct
import sys
import time

from egm_wire import egm_robot, egm_sensor


def first_row(path):
    with open(path, newline="") as f:
        rows = (r for r in csv.reader(f) if r and not r[0].startswith("#"))
        header = next(rows)
        values = next(rows)
    return [float(values[header.index("q%d_deg" % j)]) for j in range(1, len(header))]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--host", default="127.0.0.1", help="deflex's address")
    ap.add_argument("--port", type=int, default=6510, help="deflex's EGM port")
    ap.add_argument("--start-deg", help="the arm's joints at the start, degrees, comma-separated")
    ap.add_argument("--program", help="take the start from the first row of this joint trajectory CSV")
    ap.add_argument("--seconds", type=float, default=5.0, help="how long to run, s")
    ap.add_argument("--period-ms", type=float, default=4.0)
    ap.add_argument("--dead-time-ms", type=float, default=48.0, help="reference to motion (abb_libegm #111: ~50 ms)")
    ap.add_argument("--lowpass-hz", type=float, default=20.0)
    ap.add_argument("--gain", type=float, default=5.0, help="position gain k, 1/s")
    ap.add_argument("--comm-timeout-s", type=float, default=1.0)
    ap.add_argument("--log", help="CSV of every cycle: t_s, feedback and target joints in degrees")
    args = ap.parse_args()
    if args.program:
        q = first_row(args.program)
    elif args.start_deg:
        q = [float(v) for v in args.start_deg.split(",")]
    else:
        ap.error("give --start-deg or --program")
    n = len(q)
    period = args.period_ms / 1000.0
    target, speed = list(q), [0.0] * n
    filt_t, filt_s = list(q), [0.0] * n
    position = list(q)
    delay = [(list(q), [0.0] * n)] * (max(0, round(args.dead_time_ms / args.period_ms)) + 1)
    head = 0
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.setblocking(False)
    deflex = (args.host, args.port)
    log = open(args.log, "w") if args.log else None
    if log:
        log.write("t_s," + ",".join("fb%d_deg" % (j + 1) for j in range(n)) + ","
                  + ",".join("target%d_deg" % (j + 1) for j in range(n)) + "\n")
    sent = answers = ignored = 0
    stopped = False
    start = time.monotonic()
    last_answer = start
    seq = 0
    next_t = start
    while time.monotonic() - start < args.seconds:
        now = time.monotonic()
        while True:  # every answer that has arrived; the newest is the target
            try:
                data, sender = sock.recvfrom(4096)
            except BlockingIOError:
                break
            try:
                planned, speed_ref = egm_sensor(data)
                if len(planned) != n:
                    raise ValueError("joint count")
            except (ValueError, IndexError, struct.error):
                ignored += 1
                continue
            answers += 1
            last_answer = now
            target = planned
            speed = speed_ref if speed_ref and len(speed_ref) == n else [0.0] * n
        if not stopped and now - last_answer > args.comm_timeout_s:
            stopped = True
            print("EGM stopped: no answer for %.1f s (the arm holds)" % args.comm_timeout_s, file=sys.stderr)
        if not stopped:
            a = 1.0 - math.exp(-2.0 * math.pi * args.lowpass_hz * period) if args.lowpass_hz > 0 else 1.0
            filt_t = [f + a * (t - f) for f, t in zip(filt_t, target)]
            filt_s = [f + a * (s - f) for f, s in zip(filt_s, speed)]
            delay[head] = (filt_t, filt_s)
            head = (head + 1) % len(delay)
            r, v = delay[head]
            position = [p + period * (args.gain * (rj - p) + vj) for p, rj, vj in zip(position, r, v)]
            seq += 1
            sock.sendto(egm_robot(seq, int((now - start) * 1000), position, target), deflex)
            sent += 1
            if log:
                log.write("%.4f,%s,%s\n" % (now - start, ",".join("%.9f" % p for p in position),
                                            ",".join("%.9f" % t for t in target)))
        next_t += period
        time.sleep(max(0.0, next_t - time.monotonic()))
    if log:
        log.close()
    print("%d EgmRobot sent, %d answers taken, %d datagrams ignored%s" %
          (sent, answers, ignored, ", EGM stopped (timeout)" if stopped else ""))
    print("arm at (deg):       ", " ".join("%.5f" % p for p in position))
    print("moved from start (mdeg):", " ".join("%.3f" % ((p - s) * 1000) for p, s in zip(position, q)))
    return 0 if answers > 0 and not stopped else 1


if __name__ == "__main__":
    sys.exit(main())
