#!/usr/bin/env python3
"""A stand-in for a Yaskawa controller running MotoROS2's real-time motion mode (joint increments), to
try `deflex online --link motoros2-rt` without a robot. It behaves as the real controller does, never
more kindly (docs/online.md, "Yaskawa MotoROS2 real-time"):

- the session is open from the start (as after the ROS 2 service start_rt_mode); it listens on --port;
  the first command's sender is the only commander and its first command must carry number 0;
- a 620-byte little-endian command (version 1, type 0: joint increments in radians, 8 groups of 8
  axes) is taken at most once an interpolation period (--period-ms): its increment is added to the
  command position at the clock and answered with one 2053-byte reply (feedback, command position,
  the safety unit's truncation flag) to the command's source; every other datagram queued by then is
  discarded;
- a command whose number is not ahead of the last taken is answered with the previous reply and not
  applied; one more than --max-sequence-gap ahead drops the session ("Missed too many command
  packets"); a datagram of another size, version or type, a second sender, or an increment above
  --max-speed-deg-s times the period drops it; so does no command for --timeout-ms;
- with --fsu-speed-deg-s, increments beyond it are truncated and the next reply carries the flag;
- the arm's feedback trails the command position by three periods. A dropped session answers nothing.

It starts the arm at --program's first point. It prints what it took and exits 0 when the session was
never dropped and commands were taken, 1 otherwise. Python standard library only.

  deflex online --link motoros2-rt --robot-host 127.0.0.1 --robot-port 22000 --program nominal.csv \\
      --force-source csv:examples/online/force_replay.csv --loop --duration-s 4 &
  python3 examples/online/motoros2_rt_standin.py --port 22000 --program nominal.csv --seconds 6
"""
import argparse
import csv
import math
import select
import socket
import struct
import sys
import time

COMMAND = struct.Struct("<iiI64d8i64s")  # 620 bytes
REPLY = struct.Struct("<I256d?")  # 2053 bytes


def first_point(path):
    """The first row's joints (rad) of a joint trajectory CSV (t_s,q1_deg..q6_deg)."""
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    header = rows[0]
    return [math.radians(float(rows[1][header.index("q%d_deg" % j)])) for j in range(1, 7)]


class Controller:
    def __init__(self, args, start_rad):
        self.period = args.period_ms * 1e-3
        self.max_gap = args.max_sequence_gap
        self.timeout = args.timeout_ms * 1e-3
        self.max_inc = math.radians(args.max_speed_deg_s) * self.period
        self.fsu_inc = math.radians(args.fsu_speed_deg_s) * self.period if args.fsu_speed_deg_s > 0 else math.inf
        self.command = list(start_rad)
        self.feedback = [list(start_rad)] * 3  # the command positions of the last periods, oldest first
        self.pc = None
        self.last_seq = None
        self.last_reply = None
        self.last_command_at = 0.0
        self.truncated_last = False
        self.dropped = ""
        self.taken = self.duplicates = self.truncated = self.purged = 0
        self.largest_increment = 0.0

    def drop(self, why):
        if not self.dropped:
            self.dropped = why

    def handle(self, data, sender, sock, now):
        """One datagram at the clock; True when a command was taken."""
        if self.pc is not None and sender != self.pc:
            self.drop("a command from a second sender")
            return False
        if len(data) != COMMAND.size:
            self.drop("a datagram of %d bytes, not %d" % (len(data), COMMAND.size))
            return False
        fields = COMMAND.unpack(data)
        version, kind, seq = fields[0], fields[1], fields[2]
        if version != 1 or kind != 0:
            self.drop("version %d, type %d: not the activated joint mode" % (version, kind))
            return False
        self.pc = sender
        self.last_command_at = now
        if self.last_seq is None:
            if seq != 0:
                self.drop("the session's first command is not number 0")
                return False
        else:
            ahead = (seq - self.last_seq + 2**31) % 2**32 - 2**31
            if ahead <= 0:
                self.duplicates += 1
                if self.last_reply is not None:
                    sock.sendto(self.last_reply, sender)
                return False
            if ahead > self.max_gap:
                self.drop("Missed too many command packets")
                return False
        increments = fields[3:9]  # group 0, axes S L U R B T
        if any(not math.isfinite(d) or abs(d) > self.max_inc for d in increments):
            self.drop("an increment above an axis' maximum increment per interpolation cycle")
            return False
        self.last_seq = seq
        shortfall = [0.0] * 6
        truncated = False
        for j, d in enumerate(increments):
            applied = max(-self.fsu_inc, min(self.fsu_inc, d))
            truncated = truncated or applied != d
            shortfall[j] = d - applied
            self.command[j] += applied
            self.largest_increment = max(self.largest_increment, abs(d))
        self.truncated += 1 if truncated else 0
        self.taken += 1
        self.feedback = self.feedback[1:] + [list(self.command)]
        axes = [0.0] * 256
        for j in range(6):
            axes[j] = self.feedback[0][j]  # feedback joints, group 0
            axes[128 + j] = self.command[j] + shortfall[j]  # command position: the truncation shows next time
        self.last_reply = REPLY.pack(seq, *axes, self.truncated_last)
        self.truncated_last = truncated
        sock.sendto(self.last_reply, sender)
        return True

    def clock(self, sock, now):
        """The interpolation clock: the first command queued is taken, the rest discarded."""
        taken = False
        while select.select([sock], [], [], 0.0)[0]:
            data, sender = sock.recvfrom(8192)
            if self.dropped:
                continue
            if taken:
                self.purged += 1
                continue
            taken = self.handle(data, sender, sock, now)
        if not self.dropped and self.timeout >= 0 and now - self.last_command_at > self.timeout:
            self.drop("no command for timeout_for_rt_msg")


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--port", type=int, default=22000, help="UDP port the controller listens on")
    p.add_argument("--program", required=True, help="the joint trajectory CSV deflex streams (the arm starts at its start)")
    p.add_argument("--seconds", type=float, default=6.0, help="how long to run, s")
    p.add_argument("--period-ms", type=float, default=4.0, help="the interpolation period, ms")
    p.add_argument("--max-sequence-gap", type=int, default=3, help="max_sequence_diff_for_rt_msg")
    p.add_argument("--timeout-ms", type=float, default=5000.0, help="timeout_for_rt_msg, ms (-1: never)")
    p.add_argument("--max-speed-deg-s", type=float, default=150.0, help="every axis' maximum speed, deg/s")
    p.add_argument("--fsu-speed-deg-s", type=float, default=0.0, help="the FSU's speed limit, deg/s (0: none)")
    args = p.parse_args()
    c = Controller(args, first_point(args.program))
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", args.port))
    start = time.monotonic()
    next_clock = 0.0
    while True:
        now = time.monotonic() - start
        if now > args.seconds:
            break
        if now < next_clock:
            time.sleep(next_clock - now)
            continue
        next_clock += c.period
        c.clock(sock, now)
    print("stand-in: %d increments taken (largest %.5f deg), %d answered again, %d discarded, %d truncated; %s"
          % (c.taken, math.degrees(c.largest_increment), c.duplicates, c.purged, c.truncated,
             ("session dropped: " + c.dropped) if c.dropped else "session kept"))
    return 0 if c.taken > 0 and not c.dropped else 1


if __name__ == "__main__":
    sys.exit(main())
