#!/usr/bin/env python3
"""A stand-in for an ABB controller running a RAPID streaming server of the ROS-Industrial simple
message protocol, to try `deflex online --link simple-message` without a robot. It behaves as the real
server does, never more kindly (the same behaviour as deflex's simulated cell, src/deflex/cell/
simple_message_server.hpp):

- motion server (--motion-port, 11000): each JOINT_TRAJ_PT service request with a sequence >= 0 is an
  absolute joint target (radians) and a duration (s); it is queued in a small buffer (--buffer-points)
  and answered SUCCESS with the header only (as ABB's RAPID server answers), or FAILURE when the buffer
  is full or the point is refused (non-finite, duration <= 0). STOP_TRAJECTORY (-4) stops the arm as
  soon as possible and empties the buffer; the download sequences (-1, -3) are answered FAILURE. A frame
  of another type or too short is skipped without a reply; a LENGTH that cannot be a frame closes the
  connection. The queue keeps running when the client goes.
- the motion task runs the queue as joint moves over their durations (MoveAbsJ \\T) with a zone: it blends
  into the next point only if that point was known --latency-ms before the blend had to begin (over the
  last --zone-fraction of the move, half by default: RAPID's z10 covers half of a 100 ms move up to
  200 mm/s); otherwise it stops at the point ("corner path failure") and starts again from rest.
- state server (--state-port, 11002): every --state-period-ms (ABB: 100) a JOINT_POSITION topic with the
  arm's joints (sequence 0), then a ROBOT_STATUS topic.

The arm starts at rest at --start-deg or at the first row of --program. With port 0 the system picks
free ports; --port-file writes "MOTION STATE" there once listening. At the end it prints what it saw.
Python standard library only.

  deflex offline --circle default --force ldbb:phi_deg=30,force_N=400 --nominal-trajectory nominal.csv
  python3 examples/online/simple_message_standin.py --program nominal.csv --seconds 30 &
  deflex online --link simple-message --robot-host 127.0.0.1 --program nominal.csv --period-ms 100 \\
      --force-source csv:examples/online/force_replay.csv --loop
"""
import argparse
import csv
import math
import socket
import struct
import sys
import time

JOINT_POSITION, JOINT_TRAJ_PT, ROBOT_STATUS = 10, 11, 13
TOPIC, SERVICE_REQUEST, SERVICE_REPLY = 1, 2, 3
SUCCESS, FAILURE = 1, 2
STOP_TRAJECTORY = -4
MAX_FRAME = 1024


def first_row(path):
    with open(path, newline="") as f:
        rows = (r for r in csv.reader(f) if r and not r[0].startswith("#"))
        header = next(rows)
        values = next(rows)
    return [float(values[header.index("q%d_deg" % j)]) for j in range(1, len(header))]


class Frames:
    """Whole frames out of a byte stream (LENGTH, MSG_TYPE, COMM_TYPE, REPLY_CODE, data)."""

    def __init__(self, order):
        self.order, self.buf = order, b""

    def feed(self, data):
        self.buf += data

    def next(self):
        if len(self.buf) < 4:
            return None
        (length,) = struct.unpack(self.order + "i", self.buf[:4])
        if length < 12 or length > MAX_FRAME:
            raise ValueError("frame LENGTH %d: out of step" % length)
        if len(self.buf) < 4 + length:
            return None
        frame, self.buf = self.buf[4:4 + length], self.buf[4 + length:]
        msg_type, comm, reply = struct.unpack(self.order + "3i", frame[:12])
        return msg_type, comm, reply, frame[12:]


class Motion:
    """The motion task: a queue of joint moves with zones, closed forms in time (joint_move_queue.hpp)."""

    def __init__(self, q, args):
        self.n = len(q)
        self.latency, self.ramp, self.stop_time = args.latency_ms / 1e3, 0.1, 0.1
        self.zone = args.zone_fraction
        self.vmax = math.radians(args.max_speed_deg_s) if args.max_speed_deg_s > 0 else None
        self.queue = []  # (known_s, target, duration)
        self.phase, self.rest_x, self.rest_since = "rest", list(q), 0.0
        self.x, self.v = list(q), [0.0] * self.n
        self.corner_failures = 0

    def take(self, start):
        _, target, duration = self.queue.pop(0)
        if self.vmax:
            duration = max(duration, max(abs(b - a) for a, b in zip(start, target)) / self.vmax)
        self.a, self.b, self.T = list(start), list(target), duration
        self.sv = [(b - a) / duration for a, b in zip(start, target)]

    def half_time(self, T):
        return T * min(self.zone, 0.5) if self.zone > 0 else 0.5 * min(T, self.ramp)

    def blend(self, t0, tb, x0, vin, vout, to_line):
        self.bt0, self.btb, self.bx0, self.bvin, self.bvout, self.to_line = t0, tb, x0, vin, vout, to_line
        self.phase = "blend"

    def advance(self, t):
        while True:
            if self.phase == "rest":
                if self.queue:
                    start = max(self.rest_since, self.queue[0][0] + self.latency)
                    if start <= t:
                        self.take(self.rest_x)
                        tb = 0.5 * min(self.T, self.ramp)
                        self.s = start + tb
                        self.blend(start, tb, list(self.rest_x), [0.0] * self.n, self.sv, True)
                        continue
                self.x, self.v = list(self.rest_x), [0.0] * self.n
                return self.x
            if self.phase == "blend":
                end = self.bt0 + 2 * self.btb
                if t >= end:
                    if self.to_line:
                        self.phase = "line"
                    else:
                        self.phase, self.rest_x, self.rest_since = "rest", list(self.b), end
                    continue
                tau = t - self.bt0
                if tau < 0:
                    self.x = [x0 + tau * vi for x0, vi in zip(self.bx0, self.bvin)]
                    self.v = list(self.bvin)
                else:
                    k = tau * tau / (4 * self.btb)
                    self.x = [x0 + tau * vi + k * (vo - vi) for x0, vi, vo in zip(self.bx0, self.bvin, self.bvout)]
                    self.v = [vi + tau / (2 * self.btb) * (vo - vi) for vi, vo in zip(self.bvin, self.bvout)]
                return self.x
            if self.phase == "line":
                tb_in = self.half_time(self.T)
                decision = self.s + self.T - tb_in
                if t >= decision:
                    vin = list(self.sv)
                    if self.zone > 0 and self.queue and self.queue[0][0] + self.latency <= decision:
                        frm, s_next = list(self.b), self.s + self.T
                        self.take(frm)
                        tb = min(tb_in, self.half_time(self.T))
                        self.s = s_next
                        self.blend(s_next - tb, tb, [b - tb * v for b, v in zip(frm, vin)], vin, self.sv, True)
                    else:
                        tb = tb_in
                        if self.zone > 0:
                            self.corner_failures += 1
                        self.blend(self.s + self.T - tb, tb, [b - tb * v for b, v in zip(self.b, vin)], vin,
                                   [0.0] * self.n, False)
                    continue
                self.x = [a + (t - self.s) * v for a, v in zip(self.a, self.sv)]
                self.v = list(self.sv)
                return self.x
            if self.phase == "stopping":
                tau = t - self.st0
                if tau >= self.stop_time:
                    self.phase = "rest"
                    self.rest_x = [x + 0.5 * self.stop_time * v for x, v in zip(self.sx0, self.sv0)]
                    self.rest_since = self.st0 + self.stop_time
                    continue
                k = tau - tau * tau / (2 * self.stop_time)
                self.x = [x + k * v for x, v in zip(self.sx0, self.sv0)]
                self.v = [(1 - tau / self.stop_time) * v for v in self.sv0]
                return self.x

    def stop(self, t):
        self.advance(t)
        self.queue = []
        if self.phase in ("rest", "stopping"):
            return
        self.phase, self.st0, self.sx0, self.sv0 = "stopping", t, list(self.x), list(self.v)


def listen(host, port):
    s = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    s.bind((host, port))
    s.listen(1)
    s.setblocking(False)
    return s


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--host", default="127.0.0.1", help="address to listen on")
    ap.add_argument("--motion-port", type=int, default=11000)
    ap.add_argument("--state-port", type=int, default=11002)
    ap.add_argument("--port-file", help="write 'MOTION STATE' (the ports listened on) here")
    ap.add_argument("--byte-order", choices=["little", "big"], default="little", help="ABB RAPID: little")
    ap.add_argument("--start-deg", help="the arm's joints at the start, degrees, comma-separated")
    ap.add_argument("--program", help="take the start from the first row of this joint trajectory CSV")
    ap.add_argument("--seconds", type=float, default=30.0, help="how long to run, s")
    ap.add_argument("--buffer-points", type=int, default=4, help="the server's queue of points")
    ap.add_argument("--state-period-ms", type=float, default=100.0, help="ROS_stateServer's update rate")
    ap.add_argument("--latency-ms", type=float, default=50.0, help="a point must be known this long before use")
    ap.add_argument("--zone-fraction", type=float, default=0.5, help="share of a move the zone covers (0: fine)")
    ap.add_argument("--max-speed-deg-s", type=float, default=0.0, help="joint speed limit (0: none)")
    ap.add_argument("--log", help="CSV of the arm: t_s and joints in degrees, every 4 ms")
    args = ap.parse_args()
    if args.program:
        q = [math.radians(v) for v in first_row(args.program)]
    elif args.start_deg:
        q = [math.radians(float(v)) for v in args.start_deg.split(",")]
    else:
        ap.error("give --start-deg or --program")
    order = "<" if args.byte_order == "little" else ">"
    n = len(q)
    motion_server, state_server = listen(args.host, args.motion_port), listen(args.host, args.state_port)
    if args.port_file:
        with open(args.port_file, "w") as f:
            f.write("%d %d\n" % (motion_server.getsockname()[1], state_server.getsockname()[1]))
    arm = Motion(q, args)
    frames = Frames(order)
    motion = state = None
    motion_out = state_out = b""
    accepted = failures = stops = skipped = published = 0
    last_sequence = None
    log = open(args.log, "w") if args.log else None
    if log:
        log.write("t_s," + ",".join("q%d_deg" % (j + 1) for j in range(n)) + "\n")
    start = time.monotonic()
    next_tick, next_state = start, 0.0
    while True:
        now = time.monotonic()
        t = now - start
        if t > args.seconds:
            break
        for which in ("motion", "state"):
            server = motion_server if which == "motion" else state_server
            if (motion if which == "motion" else state) is None:
                try:
                    conn, _ = server.accept()
                    conn.setblocking(False)
                    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
                    if which == "motion":
                        motion = conn
                    else:
                        state = conn
                except BlockingIOError:
                    pass
        x = arm.advance(t)
        if motion is not None:
            try:
                data = motion.recv(4096)
                if not data:
                    motion.close()
                    motion = None  # the client left: the queue keeps running
                else:
                    frames.feed(data)
            except BlockingIOError:
                pass
            try:
                while motion is not None:
                    f = frames.next()
                    if f is None:
                        break
                    msg_type, comm, _, data = f
                    if msg_type != JOINT_TRAJ_PT or len(data) < 52:
                        skipped += 1
                        continue
                    values = struct.unpack(order + "i10f2f", data[:52])
                    seq, joints, duration = values[0], list(values[1:1 + n]), values[12]
                    code = SUCCESS
                    if seq == STOP_TRAJECTORY:
                        arm.stop(t)
                        stops += 1
                    elif seq < 0 or not all(map(math.isfinite, joints)) or not duration > 0:
                        code = FAILURE
                        failures += 1
                    elif len(arm.queue) >= args.buffer_points:
                        code = FAILURE
                        failures += 1
                    else:
                        arm.queue.append((t, joints, duration))
                        accepted += 1
                        last_sequence = seq
                    if comm == SERVICE_REQUEST:
                        motion_out += struct.pack(order + "4i", 12, JOINT_TRAJ_PT, SERVICE_REPLY, code)
            except ValueError as e:
                print("motion connection: %s; closing it" % e, file=sys.stderr)
                motion.close()
                motion = None
            if motion is not None and motion_out:
                try:
                    motion_out = motion_out[motion.send(motion_out):]
                except BlockingIOError:
                    pass
                except OSError:
                    motion.close()
                    motion = None
        if state is not None and t >= next_state:
            next_state += args.state_period_ms / 1e3
            joints = [float(v) for v in x] + [0.0] * (10 - n)
            moving = 0 if arm.phase == "rest" else 1
            msg = struct.pack(order + "4i i10f", 56, JOINT_POSITION, TOPIC, 0, 0, *joints)
            msg += struct.pack(order + "4i 7i", 40, ROBOT_STATUS, TOPIC, 0, 1, 0, 0, 0, moving, 2, 1)
            state_out += msg
            published += 1
        if state is not None and state_out:
            try:
                state_out = state_out[state.send(state_out):]
            except BlockingIOError:
                pass
            except OSError:
                state.close()
                state = None  # the client left: nothing more goes out
        if log:
            log.write("%.4f,%s\n" % (t, ",".join("%.9f" % math.degrees(v) for v in x)))
        next_tick += 0.004
        time.sleep(max(0.0, next_tick - time.monotonic()))
    if log:
        log.close()
    print("%d points accepted (last sequence %s), %d FAILURE replies, %d STOP_TRAJECTORY, %d frames skipped, "
          "%d JOINT_POSITION published, %d corner path failures" %
          (accepted, last_sequence, failures, stops, skipped, published, arm.corner_failures))
    print("arm at (deg):", " ".join("%.5f" % math.degrees(v) for v in arm.x))
    return 0 if accepted > 0 else 1


if __name__ == "__main__":
    sys.exit(main())
