#!/usr/bin/env python3
"""A stand-in for an ABB controller's EGM link, to try `deflex online` without a robot.

Sends EgmRobot messages (header, feedback and planned joints in degrees) every 4 ms to the sensor's
address, waits for each EgmSensor reply and prints the correction it carried. Python standard
library only: the protobuf wire format is written by hand (field numbers from egm.proto).

  deflex online --egm-port 6510 --force-source csv:examples/online/force_replay.csv --loop &
  python3 examples/online/egm_fake_controller.py --port 6510 --cycles 500
"""
import argparse
import socket
import struct
import time


def varint(v):
    out = bytearray()
    while v >= 0x80:
        out.append((v & 0x7F) | 0x80)
        v >>= 7
    out.append(v)
    return bytes(out)


def field_len(number, body):
    return varint(number << 3 | 2) + varint(len(body)) + body


def joints(values):  # EgmJoints: repeated double joints = 1, unpacked like the controller sends
    return b"".join(varint(1 << 3 | 1) + struct.pack("<d", v) for v in values)


def egm_robot(seqno, tm_ms, feedback_deg, planned_deg):
    header = varint(1 << 3) + varint(seqno) + varint(2 << 3) + varint(tm_ms) + varint(3 << 3) + varint(2)
    return (field_len(1, header) + field_len(2, field_len(1, joints(feedback_deg)))
            + field_len(3, field_len(1, joints(planned_deg))))


def read_varint(buf, i):
    shift = value = 0
    while True:
        b = buf[i]
        i += 1
        value |= (b & 0x7F) << shift
        shift += 7
        if b < 0x80:
            return value, i


def skip_or_read(buf, i, wire):
    if wire == 0:
        return read_varint(buf, i)
    if wire == 1:
        return buf[i:i + 8], i + 8
    if wire == 2:
        n, i = read_varint(buf, i)
        return buf[i:i + n], i + n
    if wire == 5:
        return buf[i:i + 4], i + 4
    raise ValueError("bad wire type")


def fields(buf):
    i = 0
    while i < len(buf):
        key, i = read_varint(buf, i)
        value, i = skip_or_read(buf, i, key & 7)
        yield key >> 3, key & 7, value


def planned_joints(egm_sensor):
    for number, _, planned in fields(egm_sensor):
        if number == 2:
            for n2, _, js in fields(planned):
                if n2 == 1:
                    out = []
                    for n3, wire, v in fields(js):
                        if n3 == 1 and wire == 1:
                            out.append(struct.unpack("<d", v)[0])
                        elif n3 == 1 and wire == 2:  # packed
                            out.extend(struct.unpack("<%dd" % (len(v) // 8), v))
                    return out
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=6510)
    ap.add_argument("--cycles", type=int, default=250)
    ap.add_argument("--period-ms", type=float, default=4.0)
    ap.add_argument("--joints-deg", default="0,20,10,0,60,0", help="planned = feedback joints, degrees")
    args = ap.parse_args()
    q = [float(v) for v in args.joints_deg.split(",")]
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sock.settimeout(0.5)
    answered = 0
    last = None
    for k in range(1, args.cycles + 1):
        sock.sendto(egm_robot(k, int(k * args.period_ms), q, q), (args.host, args.port))
        try:
            reply, _ = sock.recvfrom(2048)
            last = planned_joints(reply)
            answered += 1
        except socket.timeout:
            pass
        time.sleep(args.period_ms / 1000.0)
    print(f"{answered}/{args.cycles} cycles answered")
    if last:
        print("last command (deg):", " ".join(f"{v:.5f}" for v in last))
        print("correction (mdeg):  ", " ".join(f"{(a - b) * 1000:.3f}" for a, b in zip(q, last)))


if __name__ == "__main__":
    main()
