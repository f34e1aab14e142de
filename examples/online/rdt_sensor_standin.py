#!/usr/bin/env python3
"""A stand-in for a force/torque sensor that streams over RDT (ATI Net F/T and Ethernet Axia, Schunk
FTN-Axia, OnRobot HEX through its Compute Box), to try `deflex online --force-source rdt:HOST[:PORT]`
without a sensor. It behaves as the real one does, never more kindly:

- requests are 8 bytes, big-endian: uint16 0x1234, uint16 command, uint32 sample_count; anything else
  is ignored (as the sensor does). 0x0002 starts real-time streaming (one record a datagram), 0x0003
  buffered streaming (--buffer records a datagram, the sensor's "RDT buffer size"), 0x0000 stops,
  0x0042 sets the sensor's own bias (the current reading becomes its zero, for every client);
  a sample_count above 0 stops after that many records;
- it answers the LAST requester only, at the address and port the request came from: a second client
  that asks takes the stream, and the first one sees silence;
- records are 36 bytes, big-endian: uint32 rdt_sequence (1 at each request, +1 a record), uint32
  ft_sequence (the internal sample counter since power-up, not reset by a request; it moves by
  --internal-rate / --rate a record), uint32 status, int32 Fx Fy Fz Tx Ty Tz in counts
  (--counts-per-force a --force-unit, --counts-per-torque a --torque-unit); both sequences wrap at
  2^32 (--ft-start puts the counter near the wrap);
- it serves its calibration page, netftapi2.xml, over HTTP on --http-port (cfgcpf, cfgcpt, scfgfu,
  scfgtu, comrdtrate, comrdtbsiz, runrate), as the sensor's web server does on port 80.

Faults for tests, each counted in the summary it prints on exit (a JSON line on stderr):
--drop-every K / --loss PCT (records never sent), --duplicate-every K (a datagram sent twice),
--reorder-every K (a datagram held back behind the next), --saturate-every K (Fx at the int32 limit),
--status-every K with --status-word (a status bit set), --stall-at T --stall-s S (the network goes
quiet: records and requests in that time are lost), --restart-at T (a power cycle: silent for
--restart-s, then the ft counter starts again from 0 and nothing streams until asked again),
--max-records N (never send more than N records in all, then stay silent).

Python standard library only. Example:

  python3 examples/online/rdt_sensor_standin.py --port 49152 --http-port 8080 --rate 1000 &
  deflex online --link egm-joint ... --force-source rdt:127.0.0.1 \
      --rdt-calibration http://127.0.0.1:8080/netftapi2.xml
"""
import argparse
import http.server
import json
import random
import select
import signal
import socket
import struct
import sys
import threading
import time

HEADER = 0x1234
STOP, REALTIME, BUFFERED, BIAS = 0x0000, 0x0002, 0x0003, 0x0042
INT32_MAX, INT32_MIN = 2**31 - 1, -(2**31)


def netftapi2_xml(a):
    """The calibration page a Net F/T serves (the fields deflex reads, and a few beside them)."""
    return (
        '<?xml version="1.0"?>\n<netft>\n'
        "<prodname>deflex RDT stand-in</prodname>\n"
        "<runstat>0x00000000</runstat>\n"
        f"<runrate>{a.internal_rate:g}</runrate>\n"
        "<cfgnam>stand-in</cfgnam>\n<cfgcalsel>0</cfgcalsel>\n<cfgcalsn>SI-0000</cfgcalsn>\n"
        f"<scfgfu>{a.force_unit}</scfgfu>\n<scfgtu>{a.torque_unit}</scfgtu>\n"
        f"<cfgcpf>{a.counts_per_force:g}</cfgcpf>\n<cfgcpt>{a.counts_per_torque:g}</cfgcpt>\n"
        "<comrdte>Enabled</comrdte>\n"
        f"<comrdtrate>{a.rate:g}</comrdtrate>\n<comrdtbsiz>{a.buffer}</comrdtbsiz>\n"
        "</netft>\n"
    )


def serve_http(a, host):
    page = netftapi2_xml(a).encode("ascii")

    class Handler(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            if self.path.split("?")[0] != "/netftapi2.xml":
                self.send_response(404)
                self.end_headers()
                return
            self.send_response(200)
            self.send_header("Content-Type", "text/xml")
            self.send_header("Content-Length", str(len(page)))
            self.end_headers()
            self.wfile.write(page)

        def log_message(self, *args):
            pass

    server = http.server.ThreadingHTTPServer((host, a.http_port), Handler)
    threading.Thread(target=server.serve_forever, daemon=True).start()
    return server


class Sensor:
    def __init__(self, a):
        self.a = a
        self.step = max(1, round(a.internal_rate / a.rate))  # ft counts a record
        self.power_up = time.monotonic()
        self.ft0 = a.ft_start
        self.powered = True
        self.target = None
        self.mode = REALTIME
        self.rdt = 0
        self.remaining = 0
        self.next_record = None  # index of the next record due (records since power-up)
        self.bias = [0] * 6
        self.pending = []  # records of a buffered datagram not yet full
        self.held = None  # a datagram held back (reorder)
        self.k = 0  # records generated for clients so far (the fault schedule counts these)
        self.datagrams = 0
        self.rng = random.Random(a.seed)
        self.counts_per = [a.counts_per_force] * 3 + [a.counts_per_torque] * 3
        self.s = {"sent": 0, "dropped": 0, "duplicated": 0, "reordered": 0, "saturated": 0, "flagged": 0,
                  "requests": 0, "stops": 0, "biases": 0, "bad_requests": 0, "clients": 0, "stall_lost": 0,
                  "restarts": 0}
        self.clients = set()

    def index_now(self, now):
        return int((now - self.power_up) * self.a.rate)

    def counts(self, i):
        """The raw reading of internal sample i: the wrench in counts, noise, less the sensor's bias."""
        w = self.a.wrench
        noise = self.a.noise
        raw = []
        for axis in range(6):
            value = w[axis] + (self.rng.gauss(0.0, noise if axis < 3 else noise / 10.0) if noise > 0 else 0.0)
            raw.append(int(round(value * self.counts_per[axis])))
        return raw

    def request(self, data, addr, now):
        if len(data) != 8:
            self.s["bad_requests"] += 1
            return
        header, command, count = struct.unpack(">HHI", data)
        if header != HEADER:
            self.s["bad_requests"] += 1
            return
        if command in (REALTIME, BUFFERED):
            self.s["requests"] += 1
            if addr not in self.clients:
                self.clients.add(addr)
                self.s["clients"] = len(self.clients)
            self.flush()
            self.target = addr  # the last requester takes the stream
            self.mode = command
            self.rdt = 0
            self.remaining = count
            self.pending = []
            self.next_record = self.index_now(now) + 1
        elif command == STOP:
            self.s["stops"] += 1
            self.flush()
            self.target = None
        elif command == BIAS:
            self.s["biases"] += 1
            raw = self.counts(self.index_now(now))
            self.bias = [r + b for r, b in zip(raw, self.bias)]

    def every(self, k, n):
        return n > 0 and k % n == n - 1

    def record(self, i):
        """Record for internal sample i, and which faults it carries (saturated, flagged)."""
        self.rdt = (self.rdt + 1) & 0xFFFFFFFF
        ft = (self.ft0 + i * self.step) & 0xFFFFFFFF
        c = [r - b for r, b in zip(self.counts(i), self.bias)]
        status = 0
        a = self.a
        saturated = self.every(self.k, a.saturate_every)
        flagged = self.every(self.k, a.status_every)
        if saturated:
            c[0] = INT32_MAX
        if flagged:
            status = a.status_word
        c = [max(INT32_MIN, min(INT32_MAX, v)) for v in c]
        return struct.pack(">III6i", self.rdt, ft, status, *c), saturated, flagged

    def send(self, sock, datagram):
        self.datagrams += 1
        a = self.a
        if self.every(self.datagrams, a.reorder_every) and self.held is None:
            self.held = datagram
            self.s["reordered"] += 1
            return
        self.out(sock, datagram)
        if self.every(self.datagrams, a.duplicate_every):
            self.out(sock, datagram)
            self.s["duplicated"] += 1
        if self.held is not None:
            self.out(sock, self.held)
            self.held = None

    def out(self, sock, datagram):
        try:
            sock.sendto(datagram, self.target)
        except OSError:
            pass

    def flush(self):
        self.pending = []
        self.held = None

    def tick(self, sock, now, quiet):
        if self.target is None or self.next_record is None:
            return
        due = self.index_now(now)
        a = self.a
        while self.next_record <= due and self.target is not None:
            i = self.next_record
            self.next_record += 1
            if a.max_records > 0 and self.s["sent"] >= a.max_records:
                self.target = None
                return
            rec, saturated, flagged = self.record(i)
            k = self.k
            self.k += 1
            last = False
            if self.remaining > 0:  # a request for a given number of records
                self.remaining -= 1
                last = self.remaining == 0
            if quiet:
                self.s["stall_lost"] += 1
            elif self.every(k, a.drop_every) or (a.loss > 0 and self.rng.random() * 100.0 < a.loss):
                self.s["dropped"] += 1
            else:
                self.s["sent"] += 1
                self.s["saturated"] += saturated  # counted as sent, so a test can match them
                self.s["flagged"] += flagged
                if self.mode == BUFFERED:
                    self.pending.append(rec)
                    if len(self.pending) >= a.buffer:
                        self.send(sock, b"".join(self.pending))
                        self.pending = []
                else:
                    self.send(sock, rec)
            if last:
                self.target = None


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--port", type=int, default=49152, help="RDT port (0: any free one, printed at start)")
    p.add_argument("--http-port", type=int, default=-1, help="serve netftapi2.xml here (0: any free port; -1: off)")
    p.add_argument("--rate", type=float, default=1000.0, help="RDT output rate, records a second (comrdtrate)")
    p.add_argument("--internal-rate", type=float, default=0.0, help="internal sample rate (runrate; default: --rate)")
    p.add_argument("--buffer", type=int, default=10, help="records a datagram in buffered mode, 1..40 (comrdtbsiz)")
    p.add_argument("--counts-per-force", type=float, default=1000000.0)
    p.add_argument("--counts-per-torque", type=float, default=1000000.0)
    p.add_argument("--force-unit", default="N")
    p.add_argument("--torque-unit", default="Nm")
    p.add_argument("--wrench", default="0,0,-50,0,0,0",
                   help="Fx,Fy,Fz,Tx,Ty,Tz in --force-unit and --torque-unit (default: 50 units down)")
    p.add_argument("--noise", type=float, default=0.0, help="force noise, standard deviation in force units")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--ft-start", type=lambda s: int(s, 0), default=0, help="ft_sequence at power-up (near 2**32: wrap)")
    p.add_argument("--seconds", type=float, default=0.0, help="exit after this long (0: until SIGINT/SIGTERM)")
    p.add_argument("--max-records", type=int, default=0)
    p.add_argument("--drop-every", type=int, default=0)
    p.add_argument("--loss", type=float, default=0.0, help="percent of records lost at random (seeded)")
    p.add_argument("--duplicate-every", type=int, default=0)
    p.add_argument("--reorder-every", type=int, default=0)
    p.add_argument("--saturate-every", type=int, default=0)
    p.add_argument("--status-every", type=int, default=0)
    p.add_argument("--status-word", type=lambda s: int(s, 0), default=0x00010000)
    p.add_argument("--stall-at", type=float, default=-1.0)
    p.add_argument("--stall-s", type=float, default=0.0)
    p.add_argument("--restart-at", type=float, default=-1.0)
    p.add_argument("--restart-s", type=float, default=1.0)
    a = p.parse_args()
    if a.internal_rate <= 0:
        a.internal_rate = a.rate
    a.wrench = [float(v) for v in a.wrench.split(",")]
    if len(a.wrench) != 6 or not 1 <= a.buffer <= 40 or a.rate <= 0:
        p.error("--wrench takes 6 values, --buffer 1..40, --rate > 0")

    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind((a.host, a.port))
    sock.setblocking(False)
    http_port = -1
    if a.http_port >= 0:
        http_port = serve_http(a, a.host).server_address[1]
    sys.stderr.write(f"rdt_sensor_standin: RDT on {a.host}:{sock.getsockname()[1]}; HTTP on {a.host}:{http_port}; "
                     f"rate {a.rate:g} Hz; buffer {a.buffer};\n")
    sys.stderr.flush()

    stop = []
    signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
    signal.signal(signal.SIGINT, lambda *_: stop.append(1))
    sensor = Sensor(a)
    start = time.monotonic()
    restarted = False
    while not stop:
        now = time.monotonic()
        t = now - start
        if a.seconds > 0 and t >= a.seconds:
            break
        if not restarted and 0 <= a.restart_at <= t:
            if t < a.restart_at + a.restart_s:
                sensor.powered = False  # off: nothing heard, nothing sent
            else:
                restarted = True
                fresh = Sensor(a)
                fresh.s = sensor.s
                fresh.s["restarts"] += 1
                fresh.clients = sensor.clients
                fresh.ft0 = 0  # the counter starts again at power-up
                sensor = fresh
        quiet = a.stall_at >= 0 and a.stall_at <= t < a.stall_at + a.stall_s
        readable, _, _ = select.select([sock], [], [], 0.0005)
        if readable:
            while True:
                try:
                    data, addr = sock.recvfrom(2048)
                except BlockingIOError:
                    break
                if sensor.powered and not quiet:
                    sensor.request(data, addr, time.monotonic())
        if sensor.powered:
            sensor.tick(sock, time.monotonic(), quiet)
    sys.stderr.write("summary: " + json.dumps(sensor.s, sort_keys=True) + "\n")
    sys.stderr.flush()


if __name__ == "__main__":
    main()
