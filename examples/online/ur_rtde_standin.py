#!/usr/bin/env python3
"""A stand-in for a Universal Robots controller serving RTDE and playing deflex's servo program (the one
`deflex controller-setup --link ur-rtde` writes), to try `deflex online --link ur-rtde` without a robot.
It behaves as the real controller does, never more kindly (docs/online.md, "Universal Robots RTDE"):

- an RTDE server on --port (TCP, big-endian packages `uint16 size, uint8 type, payload`): protocol
  version 2 only; the URControl version of the series (--series e: 5.x, 500 Hz; cb3: 3.x, 125 Hz); an
  output frequency above the series' loop, an unknown field (NOT_FOUND) or a register in --in-use
  (IN_USE) and the start is refused; after the start one output package every loop cycle;
- the servo program: every cycle it takes the newest input registers (they keep their last value) and,
  while the mode register says servo (1), hands the six targets to servoj with the lookahead and gain
  the registers carry (outside 0.03..0.2 s and 100..2000 the program stops, as servoj raises an error);
  the end mode (2) holds the last target and ends the program; it echoes the counter in its output
  register;
- servoj's lookahead is a dead time of the lookahead, its gain a first-order lag of 1/gain s;
- a target moving a joint faster than --max-speed-deg-s is a protective stop (safety_mode 3, the
  program paused, the arm halted);
- the watchdog: deflex's counter unchanged for --watchdog-ms once the first target came stops the
  program (runtime_state 1) and the arm halts.

The arm starts at --program's first point. It prints what it did and exits 0 when targets were servoed
and the program was never stopped by a fault (the stream's own end is fine), 1 otherwise. Python
standard library only.

  deflex online --link ur-rtde --period-ms 8 --robot-host 127.0.0.1 --robot-port 30004 \\
      --program nominal.csv --force-source csv:examples/online/force_replay.csv --loop --duration-s 4 &
  python3 examples/online/ur_rtde_standin.py --port 30004 --series cb3 --program nominal.csv --seconds 6
"""
import argparse
import csv
import math
import re
import select
import socket
import struct
import sys
import time

OUTPUT_TYPES = {"timestamp": "DOUBLE", "actual_q": "VECTOR6D", "target_q": "VECTOR6D", "actual_qd": "VECTOR6D",
                "robot_mode": "INT32", "safety_mode": "INT32", "runtime_state": "UINT32"}
FORMAT = {"DOUBLE": "d", "VECTOR6D": "6d", "INT32": "i", "UINT32": "I"}


def first_point(path):
    """The first row's joints (rad) of a joint trajectory CSV (t_s,q1_deg..q6_deg)."""
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    header = rows[0]
    return [math.radians(float(rows[1][header.index("q%d_deg" % j)])) for j in range(1, 7)]


def field_type(name, output):
    if output:
        if name in OUTPUT_TYPES:
            return OUTPUT_TYPES[name]
        m = re.fullmatch(r"output_(int|double)_register_(\d{1,2})", name)
    else:
        m = re.fullmatch(r"input_(int|double)_register_(\d{1,2})", name)
    if not m or int(m.group(2)) > 47:
        return None
    return "INT32" if m.group(1) == "int" else "DOUBLE"


def package(kind, payload=b""):
    return struct.pack(">HB", 3 + len(payload), ord(kind)) + payload


class Controller:
    def __init__(self, args, start):
        self.e_series = args.series == "e"
        self.period = 0.002 if self.e_series else 0.008
        self.max_step = math.radians(args.max_speed_deg_s) * self.period
        self.watchdog = args.watchdog_ms * 1e-3
        self.in_use = {int(r) for r in args.in_use.split(",") if r}
        self.offset = args.register_offset
        self.position = list(start)
        self.target = list(start)
        self.delayed = []  # (due time, target) in order: servoj's lookahead as dead time
        self.gain = 0.0
        self.outputs = self.inputs = None  # field names of the recipes
        self.started = False
        self.registers = None  # the newest input package's values
        self.counter = None
        self.counter_at = 0.0
        self.echo = 0
        self.safety_mode, self.runtime_state = 1, 2
        self.end_at = None
        self.stopped = ""
        self.servoed = self.packages_in = self.rejected = 0

    def halt(self, why, runtime_state):
        if not self.stopped:
            self.stopped = why
        self.runtime_state = runtime_state
        self.target = list(self.position)
        self.delayed = []

    def setup(self, payload, output):
        frequency = 0.0
        if output:
            frequency = struct.unpack(">d", payload[:8])[0]
            payload = payload[8:]
        names = payload.decode("ascii").split(",")
        words, ok = [], True
        for n in names:
            t = field_type(n, output)
            reg = re.fullmatch(r"input_(?:int|double)_register_(\d+)", n)
            if t is None:
                words.append("NOT_FOUND")
                ok = False
            elif not output and reg and int(reg.group(1)) in self.in_use:
                words.append("IN_USE")
                ok = False
            else:
                words.append(t)
        rate_ok = not output or frequency <= 1.0 / self.period + 1e-9
        recipe = [(n, w) for n, w in zip(names, words)] if ok and rate_ok else None
        if output:
            self.outputs = recipe
        else:
            self.inputs = recipe
        return package("O" if output else "I", bytes([1 if output else 2]) + ",".join(words).encode("ascii"))

    def handle(self, kind, payload):
        """One package from the client: the reply to send, or b""."""
        if kind == "V":
            return package("V", bytes([1 if struct.unpack(">H", payload)[0] == 2 else 0]))
        if kind == "v":
            return package("v", struct.pack(">IIII", 5 if self.e_series else 3, 11 if self.e_series else 15, 0, 0))
        if kind in "OI":
            return self.setup(payload, kind == "O")
        if kind == "S":
            self.started = self.outputs is not None and self.inputs is not None
            return package("S", bytes([1 if self.started else 0]))
        if kind == "P":
            self.started = False
            return package("P", bytes([1]))
        if kind == "U" and self.inputs and payload[:1] == b"\x02":
            fmt = ">" + "".join(FORMAT[t] for _, t in self.inputs)
            if struct.calcsize(fmt) == len(payload) - 1:
                self.registers = dict(zip((n for n, _ in self.inputs), struct.unpack(fmt, payload[1:])))
                self.packages_in += 1
                return b""
        self.rejected += 1
        return b""

    def servo(self, now):
        if self.runtime_state != 2 or self.registers is None:
            self.counter_at = now
            return
        if self.end_at is not None and now >= self.end_at:
            self.halt("the program ended (the stream's end)", 1)
            return
        r, o = self.registers, self.offset
        counter = r.get("input_int_register_%d" % o, 0)
        if counter != self.counter:
            self.counter, self.counter_at = counter, now
        elif now - self.counter_at > self.watchdog:
            self.halt("the RTDE watchdog: input_int_register_%d did not change" % o, 1)
            return
        mode = r.get("input_int_register_%d" % (o + 1), 0)
        if mode not in (1, 2):
            return
        q = [r.get("input_double_register_%d" % (o + j), 0.0) for j in range(6)]
        lookahead = r.get("input_double_register_%d" % (o + 6), 0.0)
        gain = r.get("input_double_register_%d" % (o + 7), 0.0)
        if not (0.03 <= lookahead <= 0.2 and 100 <= gain <= 2000):
            self.halt("servoj: lookahead_time or gain out of range", 1)
            return
        self.gain, self.echo = gain, counter
        if mode == 2 and self.end_at is None:
            self.end_at = now + min(2 * lookahead, 0.5 * self.watchdog)
        self.delayed.append((now + lookahead, q))
        self.servoed += 1

    def move(self, now):
        while self.delayed and self.delayed[0][0] <= now + 1e-9:
            self.target = self.delayed.pop(0)[1]
        share = 1.0 - math.exp(-self.period * self.gain)
        step = [share * (t - p) for t, p in zip(self.target, self.position)]
        if self.runtime_state == 2 and max(abs(s) for s in step) > self.max_step:
            self.safety_mode = 3
            self.halt("protective stop: a joint's speed limit was exceeded", 4)
            return
        self.position = [p + s for p, s in zip(self.position, step)]

    def output_package(self, now):
        values = {"timestamp": now, "actual_q": self.position, "target_q": self.position,
                  "actual_qd": [0.0] * 6, "robot_mode": 7, "safety_mode": self.safety_mode,
                  "runtime_state": self.runtime_state, "output_int_register_%d" % self.offset: self.echo}
        fmt, flat = ">B", [1]
        for n, t in self.outputs:
            fmt += FORMAT[t]
            v = values.get(n, [0.0] * 6 if t == "VECTOR6D" else 0)
            flat += list(v) if t == "VECTOR6D" else [v]
        return package("U", struct.pack(fmt, *flat))


def read_packages(conn, buffer):
    """The whole packages waiting (kind, payload) and the rest of the bytes; None when the client left."""
    try:
        data = conn.recv(65536)
    except OSError:  # reset: the client closed with bytes unread
        data = b""
    if not data:
        return None, buffer
    buffer += data
    out = []
    while len(buffer) >= 3:
        size, kind = struct.unpack(">HB", buffer[:3])
        if size < 3:
            return None, b""
        if len(buffer) < size:
            break
        out.append((chr(kind), buffer[3:size]))
        buffer = buffer[size:]
    return out, buffer


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--port", type=int, default=30004, help="TCP port of the RTDE server")
    p.add_argument("--program", required=True, help="the joint trajectory CSV deflex streams (the arm starts at its start)")
    p.add_argument("--seconds", type=float, default=6.0, help="how long to run, s")
    p.add_argument("--series", choices=["e", "cb3"], default="e", help="e-Series (500 Hz) or CB3 (125 Hz)")
    p.add_argument("--register-offset", type=int, default=24, help="the servo program's first register")
    p.add_argument("--max-speed-deg-s", type=float, default=180.0, help="the joint speed limit, deg/s")
    p.add_argument("--watchdog-ms", type=float, default=100.0, help="rtde_set_watchdog's period, ms")
    p.add_argument("--in-use", default="", help="input registers another writer holds, comma separated")
    p.add_argument("--ready-file", default="", help="a file written once the server listens")
    args = p.parse_args()
    c = Controller(args, first_point(args.program))
    server = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
    server.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
    server.bind(("127.0.0.1", args.port))
    server.listen(1)
    if args.ready_file:
        with open(args.ready_file, "w") as f:
            f.write("%d\n" % args.port)
    server.settimeout(args.seconds)
    conn, _ = server.accept()
    conn.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    start = time.monotonic()
    next_cycle, buffer, connected = 0.0, b"", True
    while time.monotonic() - start < args.seconds:
        now = time.monotonic() - start
        if now < next_cycle:
            time.sleep(next_cycle - now)
            continue
        t = next_cycle
        next_cycle += c.period
        while connected and select.select([conn], [], [], 0.0)[0]:
            packages, buffer = read_packages(conn, buffer)
            if packages is None:
                connected = False
                break
            for kind, payload in packages:
                reply = c.handle(kind, payload)
                if reply:
                    conn.sendall(reply)
        c.servo(t)
        c.move(t)
        if connected and c.started:
            try:
                conn.sendall(c.output_package(t))
            except OSError:
                connected = False
    print("stand-in: %d targets servoed, %d input packages, %d rejected; safety_mode %d; %s"
          % (c.servoed, c.packages_in, c.rejected, c.safety_mode,
             ("program stopped: " + c.stopped) if c.stopped else "program playing"))
    fault = c.stopped and c.stopped != "the program ended (the stream's end)"
    return 0 if c.servoed > 0 and not fault else 1


if __name__ == "__main__":
    sys.exit(main())
