"""The paper's workflow from Python, notebook style, identification to evaluation: plan a stiffness
calibration, measure it (here on a synthetic "true" arm whose stiffness the model does not know,
with tracker noise), identify the joint stiffness, compensate the paper's loaded circle offline for
its three loads, replay a recorded force log through the online cycle, and judge both by the
paper's figure of merit (mean distance of the loaded path from the unloaded one). The true arm here
differs from the model only in its stiffness, so compensation comes out near complete; the
simulated cell of `deflex case-study` (run_case_study) is harder than the model, as a real cell is.

Run (after building): PYTHONPATH=build/python python3 examples/python/03_paper_workflow.py [OUTDIR] (example-out/ and the script's name when omitted)
or, with the module installed into an interpreter (`pip install .`), that interpreter alone.
Each block is a notebook cell. Units: m, rad, N, Nm inside; mm only in printed figures, and said.
"""

import pathlib
import sys

import deflex  # first: on an interpreter without NumPy its message says what to do
import numpy as np

out_dir = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "example-out/03_paper_workflow")
out_dir.mkdir(parents=True, exist_ok=True)
rng = np.random.default_rng(7)

# %% 1. The model (the robot file's nominal stiffness) and the arm it stands for. The "true" arm is
#    the same kinematics with each joint 10-25 % softer or stiffer: what a calibration is for.
model = deflex.Robot.builtin()
nominal_k = model.stiffness
assert nominal_k is not None  # the built-in robot's file gives one (a bare URDF's is None)
truth = model.with_stiffness(nominal_k * np.array([0.85, 1.10, 0.80, 1.20, 0.90, 1.15]), "the synthetic truth")
truth_k = truth.stiffness
assert truth_k is not None
print(f"robot: {model.name}; nominal stiffness {np.array2string(nominal_k / 1e6, precision=3)} MNm/rad")

# %% 2. Plan the calibration in a box around the work (m, base frame): poses and load directions that
#    make every joint's compliance observable (the operator's sheet: plan.write_csv()).
plan = deflex.plan_calibration(model, [1.5, -0.4, 0.7], [2.1, 0.4, 1.2], load_n=800, poses=12, loads_per_pose=3)
plan.write_csv(out_dir / "calibration_plan.csv")
print(f"calibration plan: {len(plan.q)} loads at {len(set(plan.pose))} poses, condition number {plan.condition_number:.1f}")
# An infinite condition number means some joint's stiffness cannot be told from the planned positions
# at all (its predicted error is inf too); the plan's warnings say which joint and what to do.
for warning in plan.warnings:
    print(f"  plan warning: {warning}")

# %% 3. "Measure": the true arm under each planned load, seen by a 6-DoF tracker probe: the TCP's
#    displacement dp (m) with 10 um noise a coordinate and its rotation drot (rad) with 20 urad. This
#    arm's TCP lies on joint 6's axis, so joint 6 turning never moves it: only the orientation sees it
#    (the plan says so: its predicted error for joint 6 is infinite from positions alone).
def rotation_vector(R):
    angle = np.arccos(np.clip((np.trace(R) - 1.0) / 2.0, -1.0, 1.0))
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]]) / 2.0
    return w if angle < 1e-12 else w * angle / np.sin(angle)


loaded, unloaded = truth.fk(truth.deflected_configuration(plan.q, plan.wrench)), truth.fk(plan.q)
dp = loaded[:, :3, 3] - unloaded[:, :3, 3] + rng.normal(0.0, 10e-6, size=(len(plan.q), 3))
drot = np.array([rotation_vector(a[:3, :3] @ b[:3, :3].T) for a, b in zip(loaded, unloaded)])
drot += rng.normal(0.0, 20e-6, size=drot.shape)

# %% 4. Identify the joint stiffness from those arrays (a measurement CSV's path works the same way).
estimate = deflex.identify_stiffness(model, q=plan.q, wrench=plan.wrench, dp=dp, drot=drot)
identified = model.with_stiffness(estimate.stiffness_nm_per_rad, "identified in 03_paper_workflow.py")
error_pct = 100 * (estimate.stiffness_nm_per_rad / truth_k - 1)
print(f"identified: residual RMS {estimate.residual_rms_m * 1e3:.4f} mm; stiffness error against the truth "
      f"{np.array2string(error_pct, precision=1)} %")

# %% 5. The paper's circle (centre 1800, 0, 900 mm, the LDBB inclined 30 deg) and its three loads,
#    compensated offline with the identified model: one result a load.
circle = deflex.Circle(centre_m=[1.8, 0.0, 0.9], radius_m=0.13, points=81)
loads_spec = "ldbb:phi_deg=30,force_N=125;375;625"
results = deflex.compensate_loads(identified, circle, loads_spec)
forces = deflex.force_along_path(identified, circle, loads_spec)  # the wrench at each point, base frame, at the WAP

# %% 6. Evaluate on the true arm: commanded to the desired joints (UC) and to the compensated ones (C),
#    where does the loaded TCP go? The figure of merit is the mean distance from the unloaded path.
def loaded_path(q_command, wrench):
    return truth.fk(truth.deflected_configuration(q_command, wrench))[:, :3, 3]


print("offline compensation on the true arm (mean distance from the unloaded path, mm):")
print("  load N    UC mm    C mm   compensation")
rows = []
for res, load, force_n in zip(results, forces, (125, 375, 625)):
    unloaded = truth.fk(res.q_desired)[:, :3, 3]
    uc = deflex.mean_distance_to_path_m(loaded_path(res.q_desired, load["wrench"]), unloaded)
    c = deflex.mean_distance_to_path_m(loaded_path(res.q_command, load["wrench"]), unloaded)
    rows.append((force_n, uc, c))
    print(f"  {force_n:6.0f}  {uc * 1e3:7.4f}  {c * 1e3:7.4f}   {100 * deflex.compensation_ratio(uc, c):5.1f} %")
assert all(c < 0.35 * uc for _, uc, c in rows), "offline compensation should remove most of the deflection"

# %% 7. Online: the circle run at 10 mm/s (about 82 s) on a 4 ms cycle, and a recorded force log of
#    it (1 kHz, the 625 N load with 5 N of noise, in the frame of a 3-component sensor at the flange)
#    replayed through the cycle: replay() consumes every sample, in time order, none dropped.
res = results[-1]
t_points, q_points = res.joint_trajectory(identified, speed_mm_s=10.0, nominal=True)
t_cycle = np.arange(0.004, t_points[-1], 0.004)
q_cycle = np.column_stack([np.interp(t_cycle, t_points, q_points[:, j]) for j in range(model.dof)])
t_force = np.arange(0.0, t_points[-1], 1e-3)
w_points = forces[-1]["wrench"]
f_base = np.column_stack([np.interp(t_force, t_points, w_points[:, j]) for j in range(3)])
f_base += rng.normal(0.0, 5.0, size=f_base.shape)
q_force = np.column_stack([np.interp(t_force, t_points, q_points[:, j]) for j in range(model.dof)])
R_sensor = identified.fk(q_force, point="flange")[:, :3, :3]  # base_R_sensor: the sensor at the flange
f_sensor = np.einsum("nji,nj->ni", R_sensor, f_base)  # R^T f
sensor = deflex.SensorConfig()
sensor.components = 3
sensor.lowpass_cutoff_hz = 20.0
online = deflex.OnlineCompensator(identified, sensor)
cycles = online.replay(t_force, np.hstack([f_sensor, np.zeros_like(f_sensor)]), t_cycle, q_cycle)
assert online.counters["samples_dropped"] == 0
ok = np.asarray(cycles["usable"])
w_cycle = np.column_stack([np.interp(t_cycle, t_points, w_points[:, j]) for j in range(6)])
unloaded_online = truth.fk(q_cycle)[:, :3, 3]
uc_online = deflex.mean_distance_to_path_m(loaded_path(q_cycle[ok], w_cycle[ok]), unloaded_online)
c_online = deflex.mean_distance_to_path_m(loaded_path(cycles["q_command"][ok], w_cycle[ok]), unloaded_online)
print(f"online at 625 N ({len(t_force)} force samples replayed, {ok.sum()} of {len(t_cycle)} cycles usable): UC "
      f"{uc_online * 1e3:.4f} mm, C {c_online * 1e3:.4f} mm, compensation "
      f"{100 * deflex.compensation_ratio(uc_online, c_online):.1f} %")
assert c_online < 0.35 * uc_online, "online compensation should remove most of the deflection"

# %% 8. A plot of the deflection along the circle, when matplotlib is there; the table as CSV always.
np.savetxt(out_dir / "paper_workflow.csv", np.array([[f, uc * 1e3, c * 1e3] for f, uc, c in rows]), delimiter=",",
           header="load_N,uc_mm,c_mm", comments="")
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print(f"wrote {out_dir / 'paper_workflow.csv'} (matplotlib is not installed: no plot)")
else:
    fig, ax = plt.subplots(figsize=(6, 3.5))
    angle = np.degrees(np.arctan2(res.tcp_desired[:, 1, 3] - 0.0, res.tcp_desired[:, 0, 3] - 1.8))
    order = np.argsort(angle)  # about the centre, from -180 to 180 deg (the closed circle's ends meet there)
    for (force_n, _, _), r in zip(rows, results):
        deflection = np.linalg.norm(r.predicted_deflection[:, :3], axis=1) * 1e3
        ax.plot(angle[order], deflection[order], label=f"{force_n:.0f} N")
    ax.set_xlabel("angle on the circle, deg")
    ax.set_ylabel("predicted TCP deflection, mm")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out_dir / "paper_workflow.png", dpi=120)
    print(f"wrote {out_dir / 'paper_workflow.csv'} and {out_dir / 'paper_workflow.png'}")
