#!/usr/bin/env python3
"""A stand-in for a KUKA controller in RSI axis correction (KRL: RSI_ON(#ABSOLUTE, #IPO_FAST) around
the program's own motion), to try `deflex online --link rsi` without a robot. It behaves as the real
controller does, never more kindly:

- every --cycle-ms (4 ms, IPO_FAST) it sends <Rob Type="KUKA"> with AIPos (the axes: program plus
  offset), ASPos (the program), RIst/RSol (zeros here), Delay (late answers so far) and the IPOC, a
  millisecond time stamp that grows by the cycle;
- a cycle's answer must be a <Sen> of the configured Type (SENTYPE) carrying that cycle's IPOC, from
  deflex's address, and must arrive before the next cycle starts; anything else (no answer, an old
  IPOC, another Type, a document it cannot read) counts the cycle late. The count is never reset; at
  --timeout late answers RSI stops, and with it the program and the arm;
- the AK values are whole offsets from where RSI started (absolute mode), each axis clamped to
  +-limit (AXISCORR LowerLimAi/UpperLimAi), applied after --dead-time-ms; an axis beyond --max-deg
  (AXISCORRMON MaxAi) stops RSI.

--setup DIR reads the port, SENTYPE, Timeout and limits from the files `deflex controller-setup --link
rsi` wrote, as the controller would. Python standard library only.

  deflex controller-setup --link rsi --sensor-ip 127.0.0.1 --rsi-port 49152 -o rsi-setup
  deflex online --link rsi --rsi-port 49152 --force-source csv:examples/online/force_replay.csv --loop &
  python3 examples/online/rsi_standin.py --setup rsi-setup --seconds 5
"""
import argparse
import csv
import math
import os
import select
import socket
import sys
import time
import xml.etree.ElementTree as ET


def read_setup(directory, context):
    """Port, SENTYPE, Timeout, AXISCORR limit and AXISCORRMON maximum from deflex's generated files."""
    ethernet = ET.parse(os.path.join(directory, context + "_ethernet.xml")).getroot()
    rsi = ET.parse(os.path.join(directory, context + ".rsi.xml")).getroot()
    params = {}
    for obj in rsi.iter("RSIObject"):
        for p in obj.iter("Parameter"):
            params[(obj.get("ObjType"), p.get("Name"))] = p.get("ParamValue")
    upper = float(params[("AXISCORR", "UpperLimA1")])
    lower = float(params[("AXISCORR", "LowerLimA1")])
    return {
        "port": int(ethernet.find("CONFIG/PORT").text),
        "sentype": ethernet.find("CONFIG/SENTYPE").text,
        "timeout": int(params[("ETHERNET", "Timeout")]),
        "limit": min(upper, -lower),
        "max": float(params[("AXISCORRMON", "MaxA1")]),
    }


def read_program(path):
    """(t_s, [q_deg]) rows of a joint trajectory CSV (t_s,q1_deg..)."""
    with open(path, newline="") as f:
        rows = [r for r in csv.reader(f) if r and not r[0].startswith("#")]
    header = rows[0]
    cols = [header.index("q%d_deg" % j) for j in range(1, 7)]
    return [(float(r[header.index("t_s")]), [float(r[c]) for c in cols]) for r in rows[1:]]


def sample(program, t):
    if t <= program[0][0]:
        return list(program[0][1])
    for (t0, q0), (t1, q1) in zip(program, program[1:]):
        if t <= t1:
            u = (t - t0) / (t1 - t0) if t1 > t0 else 1.0
            return [a + u * (b - a) for a, b in zip(q0, q1)]
    return list(program[-1][1])


def rob(ipoc, actual, setpoint, late, decimals):
    axes = lambda q: " ".join('A%d="%.*f"' % (i + 1, decimals, v) for i, v in enumerate(q))
    pose = " ".join('%s="%.*f"' % (k, decimals, 0.0) for k in "XYZABC")
    return ('<Rob Type="KUKA"><RIst %s/><RSol %s/><AIPos %s/><ASPos %s/><Delay D="%d"/><IPOC>%d</IPOC></Rob>'
            % (pose, pose, axes(actual), axes(setpoint), late, ipoc)).encode("ascii")


def answer(data, sentype):
    """(ipoc, [AK deg]) of a <Sen> of this Type with six finite AK values; ValueError otherwise."""
    try:
        root = ET.fromstring(data)
    except ET.ParseError as e:
        raise ValueError(str(e))
    if root.tag != "Sen" or root.get("Type") != sentype:
        raise ValueError("not a <Sen Type=%r>" % sentype)
    ak, ipoc = root.find("AK"), root.find("IPOC")
    if ak is None or ipoc is None or ipoc.text is None:
        raise ValueError("no AK or IPOC")
    values = [float(ak.get("A%d" % i)) for i in range(1, 7)]
    if not all(math.isfinite(v) for v in values):
        raise ValueError("non-finite AK")
    return int(ipoc.text.strip()), values


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--host", default="127.0.0.1", help="deflex's address")
    ap.add_argument("--port", type=int, help="deflex's RSI port (the Ethernet config's PORT)")
    ap.add_argument("--setup", help="read port, SENTYPE, Timeout and limits from this deflex controller-setup directory")
    ap.add_argument("--context", default="deflex_rsi", help="base name of the setup files")
    ap.add_argument("--sentype", default="ImFree")
    ap.add_argument("--timeout", type=int, default=100, help="ETHERNET Timeout: late answers that stop RSI")
    ap.add_argument("--limit-deg", type=float, default=0.5, help="AXISCORR: each axis's offset within +-this")
    ap.add_argument("--max-deg", type=float, help="AXISCORRMON MaxAi (default 1.2 x the limit)")
    ap.add_argument("--cycle-ms", type=float, default=4.0, help="4 (IPO_FAST) or 12 (IPO)")
    ap.add_argument("--dead-time-ms", type=float, default=8.0, help="from an answer taken to the axes moving")
    ap.add_argument("--precision", type=int, default=4, help="decimals of the values sent (ETHERNET Precision)")
    ap.add_argument("--start-deg", default="0,20,10,0,60,0", help="the axes when RSI starts (no --program)")
    ap.add_argument("--program", help="the KRL program's motion: a joint trajectory CSV (t_s,q1_deg..q6_deg)")
    ap.add_argument("--first-ipoc", type=int, default=4208163628)
    ap.add_argument("--seconds", type=float, default=5.0)
    ap.add_argument("--log", help="CSV of every cycle: t_s, ipoc, late, axes, offsets (degrees)")
    args = ap.parse_args()
    if args.setup:
        s = read_setup(args.setup, args.context)
        args.port = args.port or s["port"]
        args.sentype, args.timeout, args.limit_deg, args.max_deg = s["sentype"], s["timeout"], s["limit"], s["max"]
    if not args.port:
        ap.error("give --port or --setup")
    max_deg = args.max_deg if args.max_deg is not None else 1.2 * args.limit_deg
    program = read_program(args.program) if args.program else [(0.0, [float(v) for v in args.start_deg.split(",")])]

    deflex = (socket.gethostbyname(args.host), args.port)
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.bind(("0.0.0.0", 0))
    cycle = args.cycle_ms / 1000.0
    offset = [0.0] * 6
    pending = []  # (due time, offsets)
    late = answers = stale = ignored = clamped = sent = 0
    stopped = None
    ipoc = args.first_ipoc
    log = open(args.log, "w") if args.log else None
    if log:
        log.write("t_s,ipoc,late," + ",".join("q%d_deg" % j for j in range(1, 7)) + ","
                  + ",".join("offset%d_deg" % j for j in range(1, 7)) + "\n")
    start = time.monotonic()
    cycle_start = start
    program_t = 0.0
    while stopped is None and cycle_start - start < args.seconds:
        setpoint = sample(program, program_t)
        axes = [q + o for q, o in zip(setpoint, offset)]
        sock.sendto(rob(ipoc, axes, setpoint, late, args.precision), deflex)
        sent += 1
        if log:
            log.write("%.4f,%d,%d,%s,%s\n" % (cycle_start - start, ipoc, late, ",".join("%.6f" % q for q in axes),
                                             ",".join("%.6f" % o for o in offset)))
        answered = False
        deadline = cycle_start + cycle
        while True:  # the answers that arrive within this cycle
            remaining = deadline - time.monotonic()
            if remaining <= 0 or not select.select([sock], [], [], remaining)[0]:
                break
            data, sender = sock.recvfrom(65535)
            try:
                if sender != deflex:
                    raise ValueError("another sender")
                got_ipoc, values = answer(data, args.sentype)
            except ValueError:
                ignored += 1
                continue
            if got_ipoc != ipoc or answered:
                stale += 1
                continue
            answered = True
            answers += 1
            limited = [min(max(v, -args.limit_deg), args.limit_deg) for v in values]
            clamped += limited != values
            pending.append((time.monotonic() + args.dead_time_ms / 1000.0, limited))
        # The cycle is over: was it answered in time?
        if not answered:
            late += 1
            if late >= args.timeout:
                stopped = "RSI stopped: %d late answers reached the ETHERNET Timeout" % late
        now = time.monotonic()
        while pending and pending[0][0] <= now:
            offset = pending.pop(0)[1]  # absolute: the newest replaces the one before
        if any(abs(o) > max_deg for o in offset):
            stopped = "RSI stopped: AXISCORRMON MaxA exceeded"
        cycle_start = deadline
        program_t += cycle
        ipoc += int(round(args.cycle_ms))
    if log:
        log.close()
    print("%d <Rob> sent, %d answers taken in time, %d late (Timeout %d), %d stale, %d ignored, %d clamped%s"
          % (sent, answers, late, args.timeout, stale, ignored, clamped, "; " + stopped if stopped else ""))
    print("axis offsets now (mdeg):", " ".join("%.3f" % (o * 1000.0) for o in offset))
    return 0 if answers > 0 and stopped is None else 1


if __name__ == "__main__":
    sys.exit(main())
