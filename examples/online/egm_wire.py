"""ABB EGM messages by hand, for the stand-in controllers (Python standard library only).

Field numbers from ABB's EGM schema (deflex's src/deflex/wire/egm.proto and the reference notes):
EgmRobot {header 1, feedBack 2, planned 3}, EgmHeader {seqno 1, tm 2, mtype 3},
EgmFeedBack/EgmPlanned {joints 1: EgmJoints {repeated double joints = 1}},
EgmSensor {header 1, planned 2, speedRef 3 {joints 1}}, EgmSensorPathCorr {header 1, pathCorr 2
{pos 1 {x 1, y 2, z 3}, age 2}}. Repeated doubles are written unpacked, as the controller does, and
read packed or unpacked.
"""
import struct


def varint(v):
    out = bytearray()
    while v >= 0x80:
        out.append((v & 0x7F) | 0x80)
        v >>= 7
    out.append(v)
    return bytes(out)


def field_len(number, body):
    return varint(number << 3 | 2) + varint(len(body)) + body


def joints(values):
    return b"".join(varint(1 << 3 | 1) + struct.pack("<d", v) for v in values)


def egm_robot(seqno, tm_ms, feedback_deg, planned_deg):
    header = varint(1 << 3) + varint(seqno) + varint(2 << 3) + varint(tm_ms & 0xFFFFFFFF) + varint(3 << 3) + varint(2)
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


def fields(buf):
    i = 0
    while i < len(buf):
        key, i = read_varint(buf, i)
        wire = key & 7
        if wire == 0:
            value, i = read_varint(buf, i)
        elif wire == 1:
            value, i = buf[i:i + 8], i + 8
        elif wire == 2:
            n, i = read_varint(buf, i)
            value, i = buf[i:i + n], i + n
        elif wire == 5:
            value, i = buf[i:i + 4], i + 4
        else:
            raise ValueError("bad wire type")
        yield key >> 3, wire, value


def doubles(buf):
    out = []
    for number, wire, v in fields(buf):
        if number == 1 and wire == 1:
            out.append(struct.unpack("<d", v)[0])
        elif number == 1 and wire == 2:  # packed
            out.extend(struct.unpack("<%dd" % (len(v) // 8), v))
    return out


def egm_sensor(buf):
    """(planned joints deg, speed reference deg/s or None) of an EgmSensor; ValueError if it is not one."""
    planned = speed = None
    for number, wire, value in fields(buf):
        if wire != 2:
            continue
        if number == 2:
            for n2, _, js in fields(value):
                if n2 == 1:
                    planned = doubles(js)
        elif number == 3:
            for n2, _, js in fields(value):
                if n2 == 1:
                    speed = doubles(js)
    if not planned:
        raise ValueError("not an EgmSensor with planned joints")
    return planned, speed


def egm_path_corr(buf):
    """(x, y, z) mm and age (ms) of an EgmSensorPathCorr; ValueError if it is not one."""
    for number, wire, value in fields(buf):
        if number == 2 and wire == 2:
            pos, age = None, None
            for n2, w2, v2 in fields(value):
                if n2 == 1 and w2 == 2:
                    xyz = {n3: struct.unpack("<d", v3)[0] for n3, w3, v3 in fields(v2) if w3 == 1}
                    pos = (xyz.get(1), xyz.get(2), xyz.get(3))
                elif n2 == 2 and w2 == 0:
                    age = v2
            if pos is None or None in pos or age is None:
                raise ValueError("pathCorr without pos or age")
            return pos, age
    raise ValueError("not an EgmSensorPathCorr")
