"""Makes this folder's tracker session from the simulated cell's base-frame runs one folder up: the runs
as Spatial Analyzer exports in a tracker's frame (metres, 3 um noise) on the tracker's own clock, and
six reference points measured in both frames (the tracker's with 5 um noise). The transform and the
clock offsets are known, so `deflex register` and `deflex evaluate --align-to` can be checked against
them: base_T_tracker = rotation of 120 deg about (0.1, 0.2, 1) then (4100, -2300, 350) mm; the
unloaded run's tracker clock is 812.25 s ahead, the loaded run's 903.5 s. Plain Python, no NumPy."""

import math
import random

AXIS = (0.1, 0.2, 1.0)
ANGLE = math.radians(120.0)
T_MM = (4100.0, -2300.0, 350.0)


def rotation():
    n = math.sqrt(sum(a * a for a in AXIS))
    x, y, z = (a / n for a in AXIS)
    c, s, C = math.cos(ANGLE), math.sin(ANGLE), 1 - math.cos(ANGLE)
    return [[c + x * x * C, x * y * C - z * s, x * z * C + y * s],
            [y * x * C + z * s, c + y * y * C, y * z * C - x * s],
            [z * x * C - y * s, z * y * C + x * s, c + z * z * C]]


R = rotation()


def to_tracker_m(p_mm):
    d = [p_mm[i] - T_MM[i] for i in range(3)]
    return [sum(R[k][i] * d[k] for k in range(3)) * 1e-3 for i in range(3)]


def export(name, clock_s, seed):
    rng = random.Random(seed)
    with open(f"../{name}.csv") as f, open(f"{name}.sa.txt", "w") as out:
        out.write("// SA Version: 2023.1\n// Working Frame: AT960 Tracker\n// Units: Meters\n"
                  "// Columns: Collection Group Target X Y Z Time\n")
        for k, line in enumerate(l for l in f if l[0].isdigit()):
            t, x, y, z = (float(v) for v in line.split(","))
            p = [v + rng.gauss(0.0, 3e-6) for v in to_tracker_m((x, y, z))]
            out.write(f"Session {name} P{k + 1:05d} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} {t + clock_s:.4f}\n")


POINTS_MM = [(1500, -500, 500), (2200, -400, 700), (1800, 600, 400), (2000, 0, 1500), (1600, 300, 1200),
             (2500, 500, 900)]


def points():
    rng = random.Random(3)
    with open("base_points.txt", "w") as out:
        out.write("// Working Frame: Robot Base\n// Units: Millimeters\n")
        for i, p in enumerate(POINTS_MM):
            out.write(f"REF{i + 1} {p[0]:.3f} {p[1]:.3f} {p[2]:.3f}\n")
    with open("tracker_points.txt", "w") as out:
        out.write("// SA Version: 2023.1\n// Working Frame: AT960 Tracker\n// Units: Meters\n")
        for i, p in enumerate(POINTS_MM):
            q = [v + rng.gauss(0.0, 5e-6) for v in to_tracker_m(p)]
            out.write(f"Session Reference REF{i + 1} {q[0]:.9f} {q[1]:.9f} {q[2]:.9f}\n")


if __name__ == "__main__":
    points()
    export("unloaded", 812.25, 1)
    export("loaded_uc", 903.5, 2)
