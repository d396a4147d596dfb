"""The same PI tension loop as examples/pi_tension_control.py, inside the scene instead of around it.

The plant is again the lamination scene (webline/scenes/lamination.json): a tension-driven unwinder
feeds PET film to a laminating nip that takes the line from standstill to 5 m/s. Here the unwinder's
drive is a loop of the scene itself,

    "drive": {"pi": {"measure": "film.T", "set": "150 N", "kp": 0.2, "ki": 2.0, "feedforward": "inertia"}}

with the same gains and the same inertia compensation (J/R times the nip's acceleration). The Line
FMU solves the loop with the line's equations (its integrator is a state of the unwinder), so FMPy
only steps it; nothing is sampled every 2 ms, and the equilibrium start puts the drive's torque in
the integrator.

    python examples/pi_tension_control_in_scene.py [--out out/]

prints the film tension's error band with the loop in the scene, and writes
out/pi_tension_control_in_scene.csv.
"""

from __future__ import annotations

import argparse
import csv
import json
from pathlib import Path

import numpy as np
from fmpy import simulate_fmu

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "webline" / "scenes" / "lamination.json"
T_SET = 150.0  # N
H = 2e-3  # s, the communication step (the loop itself runs inside the FMU's implicit steps)
LOOP = {"measure": "film.T", "set": f"{T_SET} N", "kp": 0.2, "ki": 2.0, "feedforward": "inertia"}


def export(fmu: Path, fmu_dir: Path) -> Path:
    """The lamination scene with its unwinder's drive a loop, as Line.fmu."""
    from webline import linefmu
    from webline.scene import parse_scene

    scene = json.loads(SCENE.read_text())
    unwind = next(part for part in scene["line"] if part["name"] == "unwind")
    unwind["drive"] = {"pi": LOOP}
    return linefmu.export(parse_scene(json.dumps(scene), str(SCENE), fmu_dir=fmu_dir), fmu, fmu_dir)


def main(argv=None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--fmu-dir", type=Path, default=ROOT / "out", help="where webline finds the FMUs and the Line libraries")
    p.add_argument("--out", type=Path, default=ROOT / "out")
    args = p.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    fmu = export(args.out / "lamination_loop_line.fmu", args.fmu_dir)
    out = simulate_fmu(str(fmu), stop_time=3.5, step_size=H, output_interval=H, output=["film.T", "unwind.tau"])
    t, tension = out["time"], out["film.T"]
    settled = t > 0.1
    band = (float(np.min(tension[settled] - T_SET)), float(np.max(tension[settled] - T_SET)))
    with open(args.out / "pi_tension_control_in_scene.csv", "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["time [s]", "film.T [N]", "unwind.tau [N.m]"])
        for row in zip(t, tension, out["unwind.tau"]):
            w.writerow([f"{x:.9g}" for x in row])
    print(f"film tension error after 0.1 s with the loop in the scene: {band[0]:+.3f} .. {band[1]:+.3f} N; "
          f"wrote {args.out / 'pi_tension_control_in_scene.csv'}")
    return {"loop_in_scene": band}


if __name__ == "__main__":
    main()
