#!/usr/bin/env python3
"""A stand-in for a FANUC controller streaming with Stream Motion (option J519, protocol version 1), to
try `deflex online --link fanuc-j519` without a robot. It behaves as the real controller does, never
more kindly (docs/online.md, "FANUC Stream Motion"):

- before a stream it answers threshold requests (type 3, 16 bytes) with the 184-byte table of the
  joint and kind asked, every one of its 20 speed columns, with and without payload, at the limit it
  enforces (a real table allows more at low speed; this one is as strict as its own check);
- it listens on --port; nothing is sent until a start packet (type 0, version 1, 8 bytes) comes, then a
  132-byte status every --interval-ms to its sender, numbered from 1, big-endian: the ready bit once the
  TP program waits in IBGN, the joints (degrees) where the arm is;
- each 64-byte command must carry the next sequence number in turn (else MOTN-601); commands queue
  (10 at most), motion starts once --start-buffer are queued, and from then on one is taken every
  interval: an empty queue is MOTN-603 (receiving interval over);
- every target taken is checked as the controller does: each joint's velocity, acceleration and jerk
  by finite differences at the interval against --limits VEL,ACC,JERK (deg/s, deg/s^2, deg/s^3); one
  over is MOTN-609/610/611. An alarm stops the stream: the ready bit clears, statuses go on;
- a command flagged last-data ends the session (the TP program leaves IBGN); a stop packet ends the
  status output.

It starts the arm at --program's first point. It prints what it took and the peaks it measured, and
exits 0 when the session ended on last-data without an alarm, 1 otherwise. Python standard library only.

  deflex online --link fanuc-j519 --robot-host 127.0.0.1 --robot-port 60015 --program nominal.csv \\
      --force-source csv:examples/online/force_replay.csv --loop --duration-s 4 &
  python3 examples/online/fanuc_j519_standin.py --port 60015 --program nominal.csv --seconds 6
"""
import argparse
import csv
import select
import socket
import struct
import sys
import time

STATUS = struct.Struct(">IIIBBHHHI9f9f9f")  # 132 bytes
COMMAND = struct.Struct(">IIIBBHHBBHHHH9f")  # 64 bytes
THRESHOLD_REQUEST = struct.Struct(">IIII")  # 16 bytes: type 3, version, axis 1..9, kind 0..2
THRESHOLD_REPLY = struct.Struct(">IIIIII20f20f")  # 184 bytes


def first_point(path):
    """The first row's joints (deg) of a joint trajectory CSV (t_s,q1_deg..q6_deg)."""
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    header = rows[0]
    return [float(rows[1][header.index("q%d_deg" % j)]) for j in range(1, 7)]


class Controller:
    def __init__(self, args, start_deg):
        self.interval = args.interval_ms * 1e-3
        self.start_buffer = args.start_buffer
        vel, acc, jerk = (float(x) for x in args.limits.split(","))
        self.limits = (vel, acc, jerk)
        self.position = list(start_deg)
        self.history = [list(start_deg)] * 3  # the last three targets, newest first (at rest)
        self.peak = [0.0, 0.0, 0.0]
        self.pc = None
        self.status_seq = 0
        self.expected = 0
        self.queue = []
        self.moving = False
        self.ended = False
        self.alarm = ""
        self.taken = 0
        self.ready_at = None

    def threshold_reply(self, data):
        """The table a threshold request asks for, or None (not one, or a stream runs)."""
        kind, version, axis, limit_kind = THRESHOLD_REQUEST.unpack(data)
        if kind != 3 or not 1 <= axis <= 9 or limit_kind > 2 or self.pc is not None:
            return None
        value = self.limits[limit_kind]
        # axis, kind, $MAX_SPD (mm/s), the interval (ms), then no payload and full payload at 5..100 %
        return THRESHOLD_REPLY.pack(3, version, axis, limit_kind, 2000, int(round(self.interval * 1e3)),
                                    *([value] * 20), *([value] * 20))

    def receive(self, data, sender, now):
        """Takes a datagram; returns the bytes to answer it with at once (a threshold table), or None."""
        if len(data) == THRESHOLD_REQUEST.size:
            return self.threshold_reply(data)
        if len(data) == 8:
            kind, version = struct.unpack(">II", data)
            if kind == 0 and self.pc is None:
                self.pc, self.ready_at = sender, now + 0.05
            elif kind == 2:
                self.pc = None
            return
        if len(data) != COMMAND.size or sender != self.pc or self.alarm or self.ended:
            return
        fields = COMMAND.unpack(data)
        kind, version, seq, last = fields[0], fields[1], fields[2], fields[3]
        if kind != 1 or version != 1:
            self.alarm = "MOTN-607 ST: Protocol version mismatch"
            return
        in_turn = (1 <= seq <= self.status_seq) if self.expected == 0 else seq == self.expected <= self.status_seq
        if not in_turn:
            self.alarm = "MOTN-601 ST: Sequence No. error"
            return
        self.expected = seq + 1
        self.queue.append((list(fields[13:19]), last == 1))
        if len(self.queue) > 10:
            self.alarm = "MOTN-603 ST: command buffer overflow"

    def take(self):
        if not self.moving:
            if len(self.queue) < self.start_buffer:
                return
            self.moving = True
        if not self.queue:
            self.alarm = "MOTN-603 ST: Receiving interval over"
            return
        target, last = self.queue.pop(0)
        t = self.interval
        p1, p2, p3 = self.history
        for j in range(6):
            v = (target[j] - p1[j]) / t
            a = (target[j] - 2 * p1[j] + p2[j]) / t**2
            k = (target[j] - 3 * p1[j] + 3 * p2[j] - p3[j]) / t**3
            for i, (value, code) in enumerate(((v, "MOTN-609"), (a, "MOTN-610"), (k, "MOTN-611"))):
                self.peak[i] = max(self.peak[i], abs(value))
                if abs(value) > self.limits[i] and not self.alarm:
                    self.alarm = "%s ST: joint %d limit exceeded (%.1f)" % (code, j + 1, abs(value))
        if self.alarm:
            return
        self.history = [target, p1, p2]
        self.position = target  # the arm follows (no dead time modelled here)
        self.taken += 1
        if last:
            self.ended, self.moving = True, False

    def status(self, now, scheduled):
        self.status_seq += 1
        ready = not self.alarm and not self.ended and now >= self.ready_at
        bits = (1 if ready else 0) | 4 | (8 if self.moving else 0)
        stamp = int(round(scheduled * 500.0)) * 2 & 0xFFFFFFFF  # the controller's own clock, 2 ms resolution
        return STATUS.pack(0, 1, self.status_seq, bits, 0, 0, 0, 0, stamp, *([0.0] * 9),
                           *(self.position + [0.0] * 3), *([0.0] * 9))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--port", type=int, default=60015, help="UDP port the controller listens on")
    p.add_argument("--program", required=True, help="the joint trajectory CSV deflex streams (the arm starts at its start)")
    p.add_argument("--seconds", type=float, default=6.0, help="how long to run, s")
    p.add_argument("--interval-ms", type=float, default=8.0, help="$STMO.$COM_INT, ms")
    p.add_argument("--start-buffer", type=int, default=4,
                   help="commands queued before motion starts (a spare against this PC's scheduling)")
    p.add_argument("--limits", default="120,265,1240", help="VEL,ACC,JERK: deg/s, deg/s^2, deg/s^3")
    args = p.parse_args()
    c = Controller(args, first_point(args.program))
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("127.0.0.1", args.port))
    start = time.monotonic()
    next_status = None
    while True:
        now = time.monotonic() - start
        if now > args.seconds:
            break
        wait = 0.001 if next_status is None else max(0.0, next_status - now)
        readable, _, _ = select.select([sock], [], [], wait)
        if readable:
            data, sender = sock.recvfrom(2048)
            reply = c.receive(data, sender, now)
            if reply is not None:
                sock.sendto(reply, sender)
            if c.pc is not None and next_status is None:
                next_status = now
            continue
        if c.pc is not None and next_status is not None and now >= next_status:
            scheduled = next_status
            next_status += c.interval
            if not c.alarm and not c.ended:
                c.take()
            sock.sendto(c.status(now, scheduled), c.pc)
    print("stand-in: %d statuses, %d targets taken, peaks %.2f deg/s, %.2f deg/s^2, %.1f deg/s^3; %s"
          % (c.status_seq, c.taken, c.peak[0], c.peak[1], c.peak[2],
             ("alarm " + c.alarm) if c.alarm else ("ended on last-data" if c.ended else "still streaming")))
    return 0 if c.ended and not c.alarm else 1


if __name__ == "__main__":
    sys.exit(main())
