"""Draws docs/img/tracker_session.svg: a tracker run taken through deflex register and deflex evaluate
--align-to, in the robot's base frame against the commanded path. Reads the frame file deflex register
wrote and the offset deflex evaluate printed; plain Python, no NumPy.

    deflex register --tracker tracker_points.txt --base base_points.txt -o /tmp/frame.yaml
    deflex evaluate --json --tracker-frame /tmp/frame.yaml --unloaded unloaded.sa.txt \\
        --loaded loaded_uc.sa.txt --align-to ../unloaded.csv > /tmp/eval.json
    python3 plot_session.py /tmp/frame.yaml /tmp/eval.json ../../../docs/img/tracker_session.svg
"""

import json
import math
import re
import sys


def frame(path):
    text = open(path).read()
    p = [float(v) for v in re.search(r"position: \[([^\]]*)\]", text).group(1).split(",")]
    w, x, y, z = (float(v) for v in re.search(r"quaternion_wxyz: \[([^\]]*)\]", text).group(1).split(","))
    r = [[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
         [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
         [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]]
    return lambda q: [sum(r[i][k] * q[k] for k in range(3)) + p[i] for i in range(3)]


def sa_points(path):
    out = []
    for line in open(path):
        if line.startswith("//") or not line.strip():
            continue
        f = line.split()
        out.append((float(f[6]), [float(f[3]), float(f[4]), float(f[5])]))
    return out


def commanded(path):
    rows = [l.strip().split(",") for l in open(path) if l[0].isdigit()]
    return [(float(r[0]), [float(v) * 1e-3 for v in r[1:4]]) for r in rows]


def at(cmd, t):
    lo, hi = 0, len(cmd) - 1
    if t <= cmd[0][0] or t >= cmd[-1][0]:
        return None
    while hi - lo > 1:
        mid = (lo + hi) // 2
        lo, hi = (mid, hi) if cmd[mid][0] <= t else (lo, mid)
    (t0, a), (t1, b) = cmd[lo], cmd[hi]
    s = (t - t0) / (t1 - t0)
    return [a[i] + s * (b[i] - a[i]) for i in range(3)]


def main(frame_path, eval_path, out_path):
    to_base = frame(frame_path)
    doc = json.load(open(eval_path))
    offset = next(r["offset_s"] for r in doc["alignment"]["runs"] if r["file"].endswith("loaded_uc.sa.txt"))
    cmd = commanded("../unloaded.csv")
    run = [(t + offset, to_base(p)) for t, p in sa_points("loaded_uc.sa.txt")]
    pairs = [(t, p, at(cmd, t)) for t, p in run]
    pairs = [(t, p, c) for t, p, c in pairs if c is not None]
    W, H = 900, 420
    svg = [f'<svg xmlns="http://www.w3.org/2000/svg" width="{W}" height="{H}" font-family="sans-serif" font-size="12">',
           '<rect width="100%" height="100%" fill="white"/>']
    # Left: the path in the base xy plane, the measured deviation from the command magnified.
    mag = 40.0
    xs = [c[0] for _, _, c in pairs]
    ys = [c[1] for _, _, c in pairs]
    cx, cy = (max(xs) + min(xs)) / 2, (max(ys) + min(ys)) / 2
    span = max(max(xs) - min(xs), max(ys) - min(ys)) * 1.7
    def px(x, y):
        return 40 + (x - cx + span / 2) / span * 340, 40 + (cy - y + span / 2) / span * 340
    cmd_pts = " ".join("{:.1f},{:.1f}".format(*px(c[0], c[1])) for _, _, c in pairs[::4])
    meas_pts = " ".join("{:.1f},{:.1f}".format(*px(c[0] + mag * (p[0] - c[0]), c[1] + mag * (p[1] - c[1])))
                        for _, p, c in pairs[::4])
    svg.append(f'<polyline points="{cmd_pts}" fill="none" stroke="#444" stroke-width="1.5"/>')
    svg.append(f'<polyline points="{meas_pts}" fill="none" stroke="#d62728" stroke-width="1"/>')
    svg.append('<text x="40" y="24" font-weight="bold">Base frame, xy plane: command (grey), registered tracker run (red)</text>')
    svg.append(f'<text x="40" y="400">deviation from the command at the same program time drawn x{mag:.0f}</text>')
    # Right: the deviation's components against program time.
    x0, y0, w, h = 470, 50, 400, 320
    ts = [t for t, _, _ in pairs]
    t_min, t_max = min(ts), max(ts)
    devs = [[(p[i] - c[i]) * 1e3 for i in range(3)] for _, p, c in pairs]
    lim = max(abs(v) for d in devs for v in d) * 1.1
    def q(t, v):
        return x0 + (t - t_min) / (t_max - t_min) * w, y0 + h / 2 - v / lim * h / 2
    svg.append(f'<rect x="{x0}" y="{y0}" width="{w}" height="{h}" fill="none" stroke="#999"/>')
    svg.append(f'<line x1="{x0}" y1="{y0 + h / 2}" x2="{x0 + w}" y2="{y0 + h / 2}" stroke="#ccc"/>')
    for i, (name, colour) in enumerate((("x", "#1f77b4"), ("y", "#2ca02c"), ("z", "#ff7f0e"))):
        pts = " ".join("{:.1f},{:.1f}".format(*q(t, d[i])) for (t, _, _), d in list(zip(pairs, devs))[::2])
        svg.append(f'<polyline points="{pts}" fill="none" stroke="{colour}" stroke-width="1"/>')
        svg.append(f'<text x="{x0 + 10 + 40 * i}" y="{y0 + 16}" fill="{colour}">d{name}</text>')
    svg.append(f'<text x="{x0}" y="24" font-weight="bold">Measured minus commanded at the same program time, mm</text>')
    svg.append(f'<text x="{x0 - 4}" y="{y0 + 4}" text-anchor="end">{lim:+.2f}</text>')
    svg.append(f'<text x="{x0 - 4}" y="{y0 + h}" text-anchor="end">{-lim:+.2f}</text>')
    svg.append(f'<text x="{x0}" y="{y0 + h + 18}">{t_min:.1f} s</text>')
    svg.append(f'<text x="{x0 + w}" y="{y0 + h + 18}" text-anchor="end">program time {t_max:.1f} s</text>')
    svg.append(f'<text x="{x0}" y="{y0 + h + 36}">offset {offset:+.4f} s from the tracker clock; 625 N push, uncompensated</text>')
    svg.append("</svg>")
    open(out_path, "w").write("\n".join(svg) + "\n")


if __name__ == "__main__":
    main(*sys.argv[1:4])
