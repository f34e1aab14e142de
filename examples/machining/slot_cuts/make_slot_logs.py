#!/usr/bin/env python3
"""Simulated force logs of four full-slot cuts, for `deflex cutting-coefficients` (docs/machining.md).

A 10 mm, 3-flute end mill in Al7075-T6 (the published set of data/machining/al7075-t6.yaml), 9000 rpm,
ap 4 mm, feeds 900, 1800, 2700 and 3600 mm/min (fz 0.033 to 0.133 mm), M3. The per-tooth formulas of
the linear edge-force model summed over the teeth, sampled at 5 kHz (not locked to the 450 Hz tooth
passing, as a sensor's clock is not) for 0.1 s of air (spindle on: the spindle's weight on the sensor)
then 0.4 s of cut, with 8 N of noise. The log's axes are the cut frame's: x along the feed, y normal to
it (tool axis x feed), z along the tool axis from the tip into the spindle; forces on the tool.
Run it to write slot_900.csv ... slot_3600.csv beside it.
"""
import math
import os
import random

KTC, KRC, KAC, KTE, KRE, KAE = 767.0, 168.8, 222.0, 27.7, 26.6, 0.7  # N/mm^2, N/mm
FLUTES, AP_MM, RPM, RATE_HZ = 3, 4.0, 9000.0, 5000.0
BIAS_N = (3.0, -1.5, -42.0)  # the spindle's weight and the sensor's offset, seen in air and in the cut


def slot_force(fz_mm, angle):
    fx = fy = fz = 0.0
    for j in range(FLUTES):
        phi = (angle + 2 * math.pi * j / FLUTES) % (2 * math.pi)
        if phi > math.pi:
            continue
        h = fz_mm * math.sin(phi)
        ft, fr, fa = AP_MM * (KTC * h + KTE), AP_MM * (KRC * h + KRE), AP_MM * (KAC * h + KAE)
        fx += -ft * math.cos(phi) - fr * math.sin(phi)
        fy += ft * math.sin(phi) - fr * math.cos(phi)
        fz += -fa
    return fx, fy, fz


def main():
    rng = random.Random(44)
    here = os.path.dirname(os.path.abspath(__file__))
    for feed in (900, 1800, 2700, 3600):
        fz_mm = feed / (RPM * FLUTES)
        phase = rng.uniform(0, 2 * math.pi)
        with open(os.path.join(here, f"slot_{feed}.csv"), "w") as f:
            f.write(f"# simulated full-slot cut: F {feed} mm/min, S 9000 rpm, ap 4 mm, 10 mm 3-flute end mill, "
                    "Al7075-T6; air 0..0.1 s, cut 0.1..0.5 s (make_slot_logs.py)\n")
            f.write("t_s,fx_N,fy_N,fz_N\n")
            for i in range(int(0.5 * RATE_HZ)):
                t = i / RATE_HZ
                force = slot_force(fz_mm, phase + 2 * math.pi * RPM / 60 * t) if t >= 0.1 else (0.0, 0.0, 0.0)
                cells = [force[k] + BIAS_N[k] + rng.gauss(0.0, 8.0) for k in range(3)]
                f.write(f"{t:.4f},{cells[0]:.2f},{cells[1]:.2f},{cells[2]:.2f}\n")


if __name__ == "__main__":
    main()
