"""The fault table of docs/online.md, measured: every fault a cell has (silence, a stalled PC, restarts,
a controller that stops, a stale force, a slow consumer), for each link it applies to, run against the
in-memory stand-in of that link's controller (deflex.StandIn: the real controller's behaviour, dead time
included), on the issue's load case: a 50 mm/s circle of the paper's size and a constant
(300, 200, -1000) N at the TCP. What went on the wire is read back from the stand-in, decoded with the
wire's own codec, and measured here against the session's two stated limits:

  bound:  |command - nominal| per joint (joint links), |offset| at the TCP (egm-path)
  step:   |command(k) - command(k-1)| per joint or at the TCP, between consecutive commands

Run (from the repository, after building): PYTHONPATH=build/python python3 examples/python/02_fault_table.py [OUTDIR] (example-out/ and the script's name when omitted)
It prints one row a fault and writes fault_table.csv (and fault_outage.png when matplotlib is there)
into OUTDIR. Units: m, rad, N, s inside; mm, deg and ms in the printed figures, and said.
"""

import csv
import pathlib
import sys
from typing import Callable

import deflex  # first: on an interpreter without NumPy its message says what to do
import numpy as np

out_dir = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "example-out/02_fault_table")
out_dir.mkdir(parents=True, exist_ok=True)
robot = deflex.Robot.builtin()
FORCE_N = [300.0, 200.0, -1000.0]

# %% 1. The program: the paper's circle (radius 129.9 mm about (1800, 0, 900) mm, tool pointing down),
#    at 50 mm/s after 0.5 s at rest, from the robot's IK. egm-joint and simple message stream it; for
#    egm-path and rsi it is the controller's own program.
circle = deflex.Circle(centre_m=[1.8, 0.0, 0.9], radius_m=0.1299, points=161)
q_path, _ = deflex.solve_path_ik(robot, circle.poses((0.0, 0.0, 1.0, 0.0)))
arc = np.concatenate([[0.0], np.cumsum(np.linalg.norm(np.diff(robot.fk(q_path)[:, :3, 3], axis=0), axis=1))])
t_prog = np.concatenate([[0.0], 0.5 + arc / 0.050])
q_prog = np.vstack([q_path[:1], q_path])
program = (t_prog, q_prog)
print(f"program: {len(t_prog)} points, {t_prog[-1]:.1f} s, {arc[-1] * 1e3:.0f} mm of circle at 50 mm/s")


def tcp_positions(q):
    return robot.fk(q)[:, :3, 3]


def measure(link, name, faults, settle_s=3.0, after_s=3.0, **settings):
    """One stand-in session: `settle_s` of steady compensation, the fault, `after_s` more (or until the
    session ends). Returns one row of the table and the stand-in."""
    s = deflex.StandIn(robot, link, program, force_base_N=FORCE_N, **settings)
    s.run_for(settle_s)
    t_fault = s.time_s
    faults(s)
    s.run_for(after_s)
    t_end = s.time_s
    wire = s.wire
    log = s.cycle_log()
    summary = s.finish()
    inv = summary["invariants"]
    # The steps from the fault on, on the wire: consecutive commands of one controller session. At a
    # restart after a silence the controller takes a new reference (the arm, or zero offset) and deflex's
    # first command of the new session is measured from it (the log's step at that cycle), not from the
    # last command of the old session, which the controller no longer holds. A restart without a silence
    # is not excepted: the controller may still hold the last command.
    t_wire = wire["t_s"]
    starts = log["t_s"][(log["session_start"] == 1.0) & (log["t_s"] > t_fault)]
    starts = [t0 for t0 in starts if t_wire[np.searchsorted(t_wire, t0) - 1] < t0 - 0.1]
    pairs = np.arange(1, len(t_wire))
    pairs = pairs[t_wire[pairs] > t_fault]
    for t0 in starts:
        first = np.searchsorted(t_wire, t0)
        pairs = pairs[pairs != first]
    row = {"link": link, "fault": name, "commands": len(t_wire)}
    if link == "egm-path":
        steps_mm = np.linalg.norm(np.diff(wire["offset_m"], axis=0), axis=1) * 1e3
        row["step_after_fault_deg"] = float("nan")
        row["step_after_fault_mm"] = float(steps_mm[pairs - 1].max()) if len(pairs) else 0.0
    else:
        joints = wire["joints_rad"]
        steps = np.abs(np.diff(joints, axis=0))[pairs - 1]
        row["step_after_fault_deg"] = float(np.degrees(steps.max())) if len(pairs) else 0.0
        if link in ("egm-joint", "simple-message") and len(pairs):
            # Absolute targets: the TCP's step between two commands, the program's own motion included
            # (50 mm/s: 0.2 mm a 4 ms cycle, 5 mm a 100 ms point).
            tcp = tcp_positions(joints)
            row["step_after_fault_mm"] = float(np.linalg.norm(tcp[pairs] - tcp[pairs - 1], axis=1).max() * 1e3)
        else:
            row["step_after_fault_mm"] = float("nan")
    after = (log["t_s"] > t_fault) & (log["replied"] == 1.0)
    row["step_fraction_after_fault"] = float(log["step_fraction"][after].max()) if after.any() else 0.0
    row["step_fraction_whole_run"] = inv["max_step_fraction"]
    if link == "egm-path":
        row["bound_fraction"] = inv["max_tcp_correction_mm"] / inv["tcp_bound_mm"]
    else:
        row["bound_fraction"] = inv["max_deviation_deg"] / inv["joint_bound_deg"]
    row["silences"] = summary["counters"]["silences"]
    row["longest_silence_s"] = summary["counters"]["longest_silence_s"]
    row["restarts"] = summary["counters"]["restarts"]
    row["end"] = summary["stop_reason"]
    row["exit_code"] = summary["exit_code"]
    row["ended_after_fault_s"] = (t_end - t_fault) if summary["stop_reason"] != "user-stop" else float("nan")
    row["reason"] = summary["reason"]
    return row, s


def outage(seconds):
    return lambda s: s.outage(seconds)


def stall(seconds):
    def f(s):
        s.stall(True)
        s.run_for(seconds)
        s.stall(False)
    return f


def sensor_gap(seconds):
    def f(s):
        s.sensor_silent(True)
        s.run_for(seconds)
        s.sensor_silent(False)
    return f


def silence_then_restart(silence_s):
    def f(s):
        s.outage(silence_s)
        s.run_for(silence_s + 0.5)
        s.restart(True)
    return f


def restart_behind_outage(outage_s):
    def f(s):
        s.restart(True)
        s.outage(outage_s)
    return f


# %% 2. The faults, link by link.
rows = []
cases: list[tuple[str, str, Callable[[deflex.StandIn], object], dict[str, float]]] = [
    ("egm-joint", "outage 0.02 s", outage(0.02), {}),
    ("egm-joint", "outage 0.1 s", outage(0.1), {}),
    ("egm-joint", "outage 0.45 s", outage(0.45), {}),
    ("egm-joint", "outage 2 s", outage(2.0), {"comm_timeout_s": 3.0}),
    ("egm-joint", "outage 2 s, CommTimeout 1 s", outage(2.0), {"after_s": 6.0}),
    ("egm-joint", "deflex stalled 0.45 s", stall(0.45), {}),
    ("egm-joint", "restart after 1.2 s silence", silence_then_restart(1.2), {}),
    ("egm-joint", "restart, no silence, reference kept", lambda s: s.restart(False), {}),
    ("egm-joint", "restart, no silence, onto the arm", lambda s: s.restart(True), {}),
    ("egm-joint", "3 datagrams overtaken", lambda s: s.reorder(3), {}),
    ("egm-joint", "stop request while moving", lambda s: s.stop(), {}),
    ("egm-joint", "EGM stopped early", lambda s: s.end_session(2), {}),
    ("egm-joint", "motors off", lambda s: s.motors_off(), {}),
    ("egm-joint", "silent for good", outage(100.0), {"after_s": 4.0}),
    ("egm-joint", "force stale 1 s", sensor_gap(1.0), {}),
    ("egm-path", "outage 0.45 s", outage(0.45), {}),
    ("egm-path", "restart behind a 1 s outage", restart_behind_outage(1.0), {}),
    ("egm-path", "restart, no silence", lambda s: s.restart(True), {}),
    ("egm-path", "force stale 1 s", sensor_gap(1.0), {}),
    ("rsi", "outage 0.2 s", outage(0.2), {}),
    ("rsi", "deflex stalled 1 s (RSI Timeout)", stall(1.0), {}),
    ("rsi", "RSI_OFF 0.3 s, RSI_ON", lambda s: s.restart(True, 0.3), {}),
    ("rsi", "stop request", lambda s: s.stop(), {}),
    ("rsi", "force stale 1 s", sensor_gap(1.0), {}),
    ("simple-message", "force stale 1 s", sensor_gap(1.0), {}),
]
for link, name, fault, extra in cases:
    row, _ = measure(link, name, fault, **extra)
    rows.append(row)
row, _ = measure("simple-message", "server takes a point every 150 ms", lambda s: None, settle_s=0.0, after_s=10.0,
                 server_read_period_s=0.15)
rows.append(row)


# %% 3. The table.
def f(v, fmt):
    return "-" if v != v else format(v, fmt)


print()
print(f"{'link':<15} {'fault':<34} {'step deg':>9} {'step mm':>8} {'% limit':>8} {'% bound':>8}  end (exit code)")
for r in rows:
    end = f"{r['end']} ({r['exit_code']})"
    if r["ended_after_fault_s"] == r["ended_after_fault_s"]:
        end += f" {r['ended_after_fault_s'] * 1e3:.0f} ms after the fault"
    print(f"{r['link']:<15} {r['fault']:<34} {f(r['step_after_fault_deg'], '9.4f')} {f(r['step_after_fault_mm'], '8.3f')} "
          f"{r['step_fraction_after_fault'] * 100:8.0f} {r['bound_fraction'] * 100:8.1f}  {end}")
print("From the fault on: step deg, the largest change of any joint between two consecutive commands on the wire;")
print("step mm, the TCP's (egm-joint and simple message send absolute targets: the program's own motion is included,")
print("0.2 mm a 4 ms cycle and 5 mm a 100 ms point at 50 mm/s; egm-path, the offset's); % limit, the largest step of")
print("a cycle over the per-cycle step limit the session stated. % bound: over the whole run, the largest")
print("|command - nominal| over its bound (egm-path: |offset| over the TCP bound).")

with open(out_dir / "fault_table.csv", "w", newline="") as fh:
    w = csv.DictWriter(fh, fieldnames=list(rows[0].keys()))
    w.writeheader()
    w.writerows(rows)
print(f"wrote {out_dir / 'fault_table.csv'}")

# The two invariants, on the wire, in every fault: the example fails if one breaks.
for r in rows:
    assert r["step_fraction_whole_run"] <= 1.0 + 1e-9, r
    assert r["bound_fraction"] <= 1.0 + 1e-9, r
expected_end = {"EGM stopped early": 6, "motors off": 6, "silent for good": 5, "deflex stalled 1 s (RSI Timeout)": 6,
                "outage 2 s, CommTimeout 1 s": 5, "restart, no silence, onto the arm": 6, "restart, no silence": 6,
                "server takes a point every 150 ms": 8}
for r in rows:
    assert r["exit_code"] == expected_end.get(r["fault"], 0), r

# %% 4. A picture of the 0.45 s outage on egm-joint: the TCP of the commands on the wire.
try:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    plt = None
if plt is not None:
    _, s = measure("egm-joint", "outage 0.45 s", outage(0.45), after_s=1.5)
    wire = s.wire
    p = tcp_positions(wire["joints_rad"]) * 1e3
    step = np.concatenate([[0.0], np.linalg.norm(np.diff(p, axis=0), axis=1)])
    fig, ax = plt.subplots(2, 1, figsize=(8, 5), sharex=True)
    ax[0].plot(wire["t_s"], step, ".", ms=2)
    ax[0].set_ylabel("TCP step between\ncommands (mm)")
    ax[0].set_title("egm-joint, 0.45 s outage at t = 3 s: the command goes on from where it stopped")
    ax[1].plot(wire["t_s"], p[:, 0] - p[0, 0], label="x")
    ax[1].plot(wire["t_s"], p[:, 1] - p[0, 1], label="y")
    ax[1].set_ylabel("TCP of the command,\nfrom the start (mm)")
    ax[1].set_xlabel("stand-in clock (s)")
    ax[1].legend()
    fig.tight_layout()
    fig.savefig(out_dir / "fault_outage.png", dpi=110)
    print(f"wrote {out_dir / 'fault_outage.png'}")
