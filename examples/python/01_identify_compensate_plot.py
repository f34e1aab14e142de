"""deflex from Python, notebook style: identify a robot's joint stiffness from measured deflections,
compensate a path for a process force with the identified model, and plot the deflection along it.

Run (from the repository, after building): PYTHONPATH=build/python python3 examples/python/01_identify_compensate_plot.py [OUTDIR] (example-out/ and the script's name when omitted)
Each block below is a notebook cell. Units: m, rad, N, Nm (mm only in printed figures, and said).
"""

import pathlib
import sys

import deflex  # first: on an interpreter without NumPy its message says what to do
import numpy as np

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parent.parent
out_dir = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else "example-out/01_identify_compensate_plot")
out_dir.mkdir(parents=True, exist_ok=True)

# %% 1. The robot as its file describes it: kinematics and an assumed (nominal) joint stiffness.
nominal = deflex.Robot.from_file(str(ROOT / "examples" / "robots" / "kuka_kr210_r2700.yaml"))
assert nominal.stiffness is not None  # this file gives one (a bare URDF's is None)
print(f"robot: {nominal.name}, nominal stiffness (Nm/rad): {np.array2string(nominal.stiffness, precision=3)}")

# %% 2. Identify the stiffness from the shipped calibration measurements (examples/identify/: a
#    planned experiment, 60 loads of 800 N, TCP displacements measured with 0.01 mm noise).
measurements = ROOT / "examples" / "identify" / "kr210_synthetic_measurements.csv"
estimate = deflex.identify_stiffness(nominal, str(measurements))
print(f"identified from {estimate.measurements} measurements, residual RMS {estimate.residual_rms_m * 1e3:.4f} mm, "
      f"condition number {estimate.condition_number:.2f}")
for j, (k, se) in enumerate(zip(estimate.stiffness_nm_per_rad, estimate.std_error_nm_per_rad), start=1):
    print(f"  joint {j}: k = {k:12.4g} Nm/rad  +- {se:.3g} ({100 * se / k:.2f} %)")
for warning in estimate.warnings:
    print("  warning:", warning)
if estimate.unidentifiable_joints:
    sys.exit(f"joints {estimate.unidentifiable_joints} are not identifiable from these data")
robot = nominal.with_stiffness(estimate.stiffness_nm_per_rad, f"identified from {measurements.name}")

# %% 3. Plan the task path inside the calibrated region (local calibration): a circle of 100 mm radius,
#    tool pointing down, solved by IK with one arm configuration kept.
circle = deflex.Circle(centre_m=[1.6, 0.0, 0.8], radius_m=0.1)
q_path, configuration = deflex.solve_path_ik(robot, circle)
print(f"path: {len(q_path)} points, arm configuration (cf1, cf4, cf6, cfx) = {configuration}")

# %% 4. Compensate it for the LDBB's bar force (the paper's load: 400 N pushing along the bar, which is
#    inclined 30 deg to the circle's plane), and check the compensation against the model.
result = deflex.compensate_path(robot, circle, "ldbb:phi_deg=30,force_N=400")
print(result.summary(), end="")
deflection_mm = np.linalg.norm(result.predicted_deflection[:, :3], axis=1) * 1e3
correction_mm = np.linalg.norm(result.tcp_command[:, :3, 3] - result.tcp_desired[:, :3, 3], axis=1) * 1e3
assert result.max_residual_m < 1e-9, "the compensated command must cancel the model's own deflection"
result.write_csv(str(out_dir / "compensated_circle.csv"))
print(f"wrote {out_dir / 'compensated_circle.csv'}")

# %% 5. The same deflection from the batch call (all points in one call, GIL released), as a check.
batch = robot.deflect(result.q_desired, result.wrench)
first_order_mm = np.linalg.norm(batch.tcp_deflection[:, :3], axis=1) * 1e3
print(f"first-order deflection (J K^-1 J^T W): mean {first_order_mm.mean():.4f} mm, exact fixed point "
      f"{deflection_mm.mean():.4f} mm")

# %% 6. Plot the deflection along the path (matplotlib when installed; skipped cleanly otherwise).
try:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
except ImportError:
    print("matplotlib is not installed: the plot is skipped (Debian: python3-matplotlib)")
else:
    angle_deg = np.linspace(0.0, 360.0, len(deflection_mm))
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(angle_deg, deflection_mm, label="predicted TCP deflection, uncompensated")
    ax.plot(angle_deg, correction_mm, "--", label="compensation offset of the TCP target")
    ax.set_xlabel("position on the circle (deg)")
    ax.set_ylabel("mm")
    ax.set_title(f"{robot.name}: LDBB 400 N push, identified stiffness")
    ax.legend()
    fig.tight_layout()
    fig.savefig(out_dir / "deflection_along_path.png", dpi=120)
    print(f"wrote {out_dir / 'deflection_along_path.png'}")
