"""A PI tension controller closing the loop around a whole line in one FMU.

The plant is the lamination scene (webline/scenes/lamination.json) exported
as Line.fmu: a tension-driven unwinder feeds PET film to a laminating nip
that takes the line from standstill to 5 m/s. The unwinder's roll (2 kg.m2)
resists the acceleration, so with its tension drive alone the film tension
rises far above its 150 N.

The controller runs every 2 ms, as a PLC task would, through FMPy's
low-level API: it reads the film tension `film.T`, and sets the unwinder's
extra motor torque `unwind.tau_m` to

    tau_m = J/R * a_ref  +  Kp * e  +  Ki * integral(e),   e = T - T_set,

the first term the roll's inertia compensation from the line's speed
reference (the nip's speed table), the others a PI on the tension error
(positive tau_m unwinds faster, which lowers the tension).

    python examples/pi_tension_control.py [--fmu Line.fmu] [--out out/]

writes out/pi_tension_control.csv and .png, and prints the tension error's band
with the controller and its largest error without it. The same loop inside the scene:
examples/pi_tension_control_in_scene.py.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "webline" / "scenes" / "lamination.json"

T_SET = 150.0  # N, the film tension the unwinder's drive is set to
H = 2e-3  # s, the controller's period and the communication step
KP = 0.2  # N.m per N
KI = 2.0  # N.m per N.s
J, R = 2.0, 0.2  # the unwinder roll's inertia (kg.m2) and radius (m), as in the scene


def export(fmu: Path, fmu_dir: Path) -> Path:
    """The lamination scene as Line.fmu (webline export --fmu)."""
    from webline import linefmu
    from webline.scene import load_scene

    return linefmu.export(load_scene(SCENE, fmu_dir=fmu_dir), fmu, fmu_dir)


def speed_reference(fmu_dir: Path):
    """The line's speed reference: the nip's speed table, as a function of time giving its slope."""
    from webline.scene import load_scene

    scene = load_scene(SCENE, fmu_dir=fmu_dir)
    return scene.speed_profile(scene.component("nip")).slope


def run(fmu: Path, acceleration, kp: float, ki: float, compensate: bool, stop: float = 3.5) -> np.ndarray:
    """Rows of (t, film.T, unwind.tau_m) at every controller period."""
    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    slave = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu)), modelIdentifier="Line", instanceName="line")
    slave.instantiate()
    slave.setupExperiment(startTime=0.0, stopTime=stop)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    t, integral, rows = 0.0, 0.0, []
    for _ in range(int(round(stop / H))):
        tension = slave.getReal([vr["film.T"]])[0]
        error = tension - T_SET
        integral += error * H
        tau = (J / R * acceleration(t) if compensate else 0.0) + kp * error + ki * integral
        slave.setReal([vr["unwind.tau_m"]], [tau])
        slave.doStep(currentCommunicationPoint=t, communicationStepSize=H)
        t += H
        rows.append((t, slave.getReal([vr["film.T"]])[0], tau))
    slave.terminate()
    slave.freeInstance()
    return np.array(rows)


def main(argv=None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--fmu", type=Path, help="a Line.fmu of the lamination scene (default: exported to OUT/lamination_line.fmu)")
    p.add_argument("--fmu-dir", type=Path, default=ROOT / "out", help="where webline finds the FMUs and the Line libraries")
    p.add_argument("--out", type=Path, default=ROOT / "out")
    args = p.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    fmu = args.fmu or export(args.out / "lamination_line.fmu", args.fmu_dir)
    acceleration = speed_reference(args.fmu_dir)
    closed = run(fmu, acceleration, KP, KI, compensate=True)
    drive_only = run(fmu, acceleration, 0.0, 0.0, compensate=False)
    settled = closed[:, 0] > 0.1
    worst = {"closed_loop": float(np.max(np.abs(closed[settled, 1] - T_SET))),
             "tension_drive_only": float(np.max(np.abs(drive_only[settled, 1] - T_SET)))}
    band = (float(np.min(closed[settled, 1] - T_SET)), float(np.max(closed[settled, 1] - T_SET)))
    with open(args.out / "pi_tension_control.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time [s]", "film.T closed loop [N]", "unwind.tau_m [N.m]", "film.T tension drive only [N]"])
        for a, b in zip(closed, drive_only):
            w.writerow([f"{a[0]:.6g}", f"{a[1]:.9g}", f"{a[2]:.9g}", f"{b[1]:.9g}"])
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax1, ax2, ax3) = plt.subplots(3, 1, sharex=True, figsize=(8, 8))
    ax1.plot(drive_only[:, 0], drive_only[:, 1], label="tension drive only")
    ax1.plot(closed[:, 0], closed[:, 1], label=f"PI (Kp {KP}, Ki {KI}) + inertia compensation, every {H * 1e3:g} ms")
    ax1.axhline(T_SET, color="grey", lw=0.8, ls="--")
    ax1.set_ylabel("film.T [N]")
    ax1.legend(loc="upper right", fontsize=8)
    ax2.plot(closed[:, 0], closed[:, 1] - T_SET, color="C1")
    ax2.set_ylabel("closed loop: T - T_set [N]")
    ax3.plot(closed[:, 0], closed[:, 2], color="C1")
    ax3.set_ylabel("unwind.tau_m [N.m]")
    ax3.set_xlabel("time [s]")
    fig.suptitle("Lamination line as one FMU: film tension through the start-up")
    fig.tight_layout()
    fig.savefig(args.out / "pi_tension_control.png", dpi=110)
    print(f"film tension error after 0.1 s with the loop around the FMU: {band[0]:+.3f} .. {band[1]:+.3f} N")
    print(f"largest film tension error after 0.1 s: {worst['closed_loop']:.3f} N with the controller, "
          f"{worst['tension_drive_only']:.1f} N with the tension drive alone; "
          f"wrote {args.out / 'pi_tension_control.csv'}, {args.out / 'pi_tension_control.png'}")
    return worst


if __name__ == "__main__":
    main()
