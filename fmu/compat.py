#!/usr/bin/env python3
"""Write the FMI cross-check compatibility files next to each packaged FMU.

    .venv/bin/python fmu/compat.py out

For ConvertingSpan.fmu and Roller.fmu in the folder: <Model>_in.csv (every
input, a repeated time is a step), <Model>_ref.csv (at most 10 variables,
simulated here with FMPy), <Model>_ref.opt (StartTime, StopTime, StepSize,
RelTol) and one ReadMe.txt for both, in the formats of the FMI cross-check
rules (modelica/fmi-cross-check, FMI-CROSS-CHECK-RULES.md, appendix B).
"""

import argparse
import textwrap
from pathlib import Path

import fmpy
import numpy as np
from fmpy import read_model_description, simulate_fmu
from fmpy.util import write_csv

from demo import scene_inputs

# With one inlet and one outlet and no loop in the drive, these inputs are not read.
ROLLER_EXTRA_PORTS = [f"web_a{k}.{q}" for k in (2, 3, 4) for q in ("F", "eps")] + [f"web_b{j}.F" for j in (2, 3, 4)] + ["loop.measured", "dancer.y"]

# The span's default scene is fmu/demo.py's; the Roller's is a motor torque
# pulse under equal tensions: omega rises from 100 to 110 rad/s and holds.
SCENES = {
    "ConvertingSpan": {
        "stop": 3.0,
        "step": 1e-3,
        "inputs": scene_inputs,
        "outputs": ["v", "T", "web_a.F", "web_b.F", "web_b.eps", "summary_Tension", "summary_Length",
                    "summary_Strain", "summary_Stress", "m_web"],
        "story": "PET film at 0.1 % strain enters at 5 m/s and leaves as a PET/Al laminate; at 0.2 s "
                 "roller b draws 0.1 % faster, at 1.0 s the line slows to 2 m/s keeping the draw, at "
                 "1.5 s the draw is released (fmu/demo.py).",
    },
    "Roller": {
        "stop": 2.0,
        "step": 1e-3,
        # The extra inlets' and outlets' inputs and the loops' measures at 0: not read here.
        "inputs": lambda fmu: table(
            ["web_a.F", "web_b.F", "web_a.eps", "tau_m", "F_load"] + ROLLER_EXTRA_PORTS,
            [row + (0.0,) * len(ROLLER_EXTRA_PORTS) for row in
             [(0.0, 844.0, 844.0, 1e-3, 0.0, 0.0), (0.5, 844.0, 844.0, 1e-3, 0.0, 0.0), (0.5, 844.0, 844.0, 1e-3, 0.5, 0.0),
              (1.5, 844.0, 844.0, 1e-3, 0.5, 0.0), (1.5, 844.0, 844.0, 1e-3, 0.0, 0.0), (2.0, 844.0, 844.0, 1e-3, 0.0, 0.0)]],
        ),
        "outputs": ["web_a.v", "omega"],
        "story": "A roller at 100 rad/s (5 m/s) between two spans at 844 N; the motor gives 0.5 N.m "
                 "from 0.5 s to 1.5 s, so omega rises at 10 rad/s2 to 110 rad/s and holds.",
    },
}
# The FMUs' default `tolerance` parameter; the default solver steps exactly
# with held inputs, so it only matters to a Model Exchange importer.
REL_TOL = 1e-8


def table(names, rows):
    return np.array(rows, dtype=[("time", np.float64)] + [(n, np.float64) for n in names])


def write_files(folder, model):
    scene = SCENES[model]
    fmu = str(folder / f"{model}.fmu")
    inputs = scene["inputs"](fmu)
    declared = [v.name for v in read_model_description(fmu).modelVariables if v.causality == "input"]
    assert sorted(inputs.dtype.names[1:]) == sorted(declared), f"{model}: the scene must feed every input"
    result = simulate_fmu(fmu, stop_time=scene["stop"], output_interval=scene["step"],
                          relative_tolerance=REL_TOL, input=inputs, output=scene["outputs"])
    write_csv(folder / f"{model}_in.csv", inputs)
    write_csv(folder / f"{model}_ref.csv", result)
    (folder / f"{model}_ref.opt").write_text(
        f"StartTime, 0.0\nStopTime, {scene['stop']}\nStepSize, {scene['step']}\nRelTol, {REL_TOL}\n")
    return f"""{model}.fmu (FMI 2.0 Co-Simulation and Model Exchange)
  {model}_in.csv   every input; a repeated time is a step change, held in between
  {model}_ref.csv  {", ".join(scene["outputs"])}
  {model}_ref.opt  start {0.0} s, stop {scene['stop']} s, step {scene['step']} s, RelTol {REL_TOL}
{textwrap.fill("Scene: " + scene["story"], 96, initial_indent="  ", subsequent_indent="    ")}
"""


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("folder", type=Path, help="the folder with the packaged FMUs (out)")
    folder = parser.parse_args().folder
    parts = [write_files(folder, model) for model in SCENES]
    (folder / "ReadMe.txt").write_text(
        "Compatibility files of the ConvertingSpan FMUs, in the formats of the FMI cross-check rules.\n"
        f"The reference results were computed with FMPy {fmpy.__version__} (Co-Simulation, inputs held\n"
        "between communication points, output every StepSize) by fmu/compat.py. Linux x86-64.\n\n"
        + "\n".join(parts)
        + "\nReproduce a reference: fmpy.simulate_fmu(fmu, stop_time=StopTime, output_interval=StepSize,\n"
        "input=fmpy.util.read_csv(<Model>_in.csv)); every variable not in _in.csv keeps its start value.\n"
    )
    print(f"compat.py: wrote the compatibility files of {', '.join(SCENES)} in {folder}")


if __name__ == "__main__":
    main()
