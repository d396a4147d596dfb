#!/usr/bin/env python3
"""Simulate the default scene with FMPy: a laminate span drawn and released.

    python fmu/demo.py out/ConvertingSpan.fmu --out out

PET film (strain 0.1 %) arrives at 5 m/s and is laminated with aluminium foil
into the span. At 0.2 s the downstream roller draws 0.1 % faster, so the span
strain rises towards 0.2 %; at 1.0 s the whole line slows to 2 m/s keeping the
draw (no change in tension: the steady strain depends only on the speed
ratio); at 1.5 s the draw is released and the tension relaxes with the
slower time constant L/v. Writes default_scene.csv and default_scene.png.
"""

import argparse
from pathlib import Path

import numpy as np
from fmpy import read_model_description, simulate_fmu
from fmpy.util import write_csv

OUTPUTS = ["web_a.v", "v", "T", "web_a.F", "web_b.F", "web_b.eps", "summary_Strain", "summary_Stress"]


# The inputs the scene drives; every other input of the FMU (the frame
# positions, used only with variableLength) is fed as a constant column at its
# start value from the model description: FMPy warns about any input that is
# missing from the input table.
DRIVEN = ["web_a.v", "web_a.eps", "web_b.v"]


def scene_inputs(fmu):
    """Piecewise-constant inputs; a repeated time is a step change."""
    rows = [
        # time, web_a.v, web_a.eps, web_b.v
        (0.0, 5.0, 1e-3, 5.0),
        (0.2, 5.0, 1e-3, 5.0),
        (0.2, 5.0, 1e-3, 5.005),
        (1.0, 5.0, 1e-3, 5.005),
        (1.0, 2.0, 1e-3, 2.002),
        (1.5, 2.0, 1e-3, 2.002),
        (1.5, 2.0, 1e-3, 2.0),
        (3.0, 2.0, 1e-3, 2.0),
    ]
    held = {v.name: float(v.start) for v in read_model_description(fmu).modelVariables
            if v.causality == "input" and v.name not in DRIVEN}
    dtype = [("time", np.float64)] + [(name, np.float64) for name in DRIVEN + list(held)]
    return np.array([row + tuple(held.values()) for row in rows], dtype=dtype)


def simulate(fmu, step=1e-3, stop=3.0):
    return simulate_fmu(
        fmu,
        fmi_type="CoSimulation",
        stop_time=stop,
        output_interval=step,
        input=scene_inputs(fmu),
        output=OUTPUTS,
    )


def plot(result, path):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (ax_t, ax_v) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    ax_t.plot(result["time"], result["T"], color="tab:red")
    ax_t.set_ylabel("span tension T [N]")
    ax_t.set_title("ConvertingSpan: PET film laminated with Al foil, 1 m span")
    ax_t.grid(True)
    ax_v.plot(result["time"], result["web_a.v"], color="tab:gray", linestyle="--", label="upstream roller web_a.v")
    ax_v.plot(result["time"], result["v"], color="tab:blue", label="web speed v (= web_b.v)")
    ax_v.set_ylabel("speed [m/s]")
    ax_v.set_xlabel("time [s]")
    ax_v.grid(True)
    # The 0.1 % draw is invisible at this scale: show it on its own axis.
    ax_d = ax_v.twinx()
    ax_d.plot(result["time"], 100 * (result["v"] / result["web_a.v"] - 1), color="tab:green", label="draw v_b/v_a - 1")
    ax_d.set_ylabel("draw [%]")
    lines = ax_v.get_lines() + ax_d.get_lines()
    ax_v.legend(lines, [line.get_label() for line in lines], loc="center right")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("fmu", type=Path)
    parser.add_argument("--out", type=Path, default=Path("out"))
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    result = simulate(str(args.fmu))
    csv, png = args.out / "default_scene.csv", args.out / "default_scene.png"
    write_csv(str(csv), result)
    plot(result, png)
    t = result["time"]
    for label, when in [("running", 0.2), ("drawn 0.1 %", 1.0), ("slowed, still drawn", 1.5), ("released", 3.0)]:
        i = int(np.searchsorted(t, when - 1e-9))
        print(f"t = {t[i]:5.3f} s  {label:22s} T = {result['T'][i]:8.2f} N  strain = {result['summary_Strain'][i]:.6f}")
    print(f"wrote {csv} and {png} ({len(t)} points)")


if __name__ == "__main__":
    main()
