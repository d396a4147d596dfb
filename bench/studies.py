#!/usr/bin/env python3
"""Studies measured: what a point of `webline sweep` costs beyond its simulation, and points per
second per worker through the Line FMU and through the parts, side by side in one run. Writes the
measured part of docs/studies.md.

    .venv/bin/python bench/studies.py [--workers 2] [--quick] [--out docs/studies.md]

Needs out/ from `bash fmu/main.sh`. The splice scene (webline/scenes/splice.json, at its own
0.5 ms step) with the issue's design: idler inertia uniform in [0.01, 0.05] kg m2, first span
length normal around 1.5 m (sd 0.05 m), a Latin hypercube of seed 7. --quick shortens every run
(a smoke test of the script; nothing written).

  overhead  the simulation itself is FMPy's efficient loop in this process, with no Dask and no
            webline: one instance of the exported FMU, for each point fmi2Reset, then simulate_fmu
            with the point's parameters (the lesser of 2 rounds over 120 points). Against it, studies
            of 20 and 120 of those points on a local cluster of one worker, each timed from the
            cluster being up to the last row: the 100 more points' wall time is what a point costs
            (the export, sending the FMU and the first instance are paid once per study, and cancel).
            Beside it what the worker spends per point outside simulate_fmu (finding the instance,
            the metrics), the client's planning per point, and a point as `webline run --engine
            fmpy-line` runs it (export, extract, instantiate).
  rate      1,000 points through the Line FMU and 20 through the parts (the co-simulation of the
            scene's FMUs, `--engine parts`), each a study on a local cluster of --workers workers:
            points per second per worker, from the cluster being up to the last row.

Times are for people to read: other processes on the machine move them (the machine these
numbers came from has two cores, shared); the ratios measured side by side in one run hold better.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time as clock
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "webline" / "src"))

from webline import linefmu  # noqa: E402
from webline.linestudy import Planner  # noqa: E402
from webline.sampling import Design, design, parse_sample  # noqa: E402
from webline.scene import load_scene  # noqa: E402
from webline.sweep import run_sweep  # noqa: E402

OUT = ROOT / "out"
SCENE = ROOT / "webline" / "scenes" / "splice.json"
DOC = ROOT / "docs" / "studies.md"
BEGIN, END = "<!-- MEASURED (bench/studies.py) -->", "<!-- /MEASURED -->"
SAMPLES = ["line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)", "line.first.L=normal(1.5 m, 0.05 m)"]


def plain_loop(points) -> float:
    """Seconds per point of FMPy's efficient loop (reset, simulate_fmu) on the exported FMU."""
    from fmpy import extract, read_model_description, simulate_fmu
    from fmpy.simulation import instantiate_fmu

    planner = Planner(SCENE, OUT)
    tasks = [planner.plan(p) for p in points]
    (structure,) = planner.structures
    with tempfile.TemporaryDirectory() as tmp:
        fmu = Path(tmp) / "Line.fmu"
        fmu.write_bytes(structure.fmu)
        folder = extract(str(fmu))
        description = read_model_description(folder)
        instance = instantiate_fmu(folder, description, "CoSimulation")
        rounds = []
        for _ in range(2):
            t0 = clock.perf_counter()
            for _, task in tasks:
                instance.reset()
                simulate_fmu(folder, model_description=description, fmu_instance=instance, fmi_type="CoSimulation",
                             stop_time=task.stop_time, step_size=task.step, output_interval=task.step,
                             output=task.outputs, start_values=task.parameters)
            rounds.append((clock.perf_counter() - t0) / len(tasks))
        instance.freeInstance()
    return min(rounds)


def alone(points) -> float:
    """Seconds per point as `webline run --engine fmpy-line` runs one: export, extract, instantiate, run."""
    t0 = clock.perf_counter()
    for p in points:
        linefmu.run(load_scene(SCENE, p, OUT), OUT)
    return (clock.perf_counter() - t0) / len(points)


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--workers", type=int, default=2)
    p.add_argument("--quick", action="store_true")
    p.add_argument("--out", type=Path, default=DOC)
    args = p.parse_args()
    samples = [parse_sample(s) for s in SAMPLES]
    n_loop, n_line, n_parts = (24, 40, 4) if args.quick else (120, 1000, 20)

    # What a point costs beyond its simulation: the study's wall time per point added, against the loop's.
    big = design([], samples, n_loop, 7)
    small = Design(big.keys, big.points[: n_loop // 6], big.values[: n_loop // 6], big.seed)
    loop = plain_loop(big.points)
    studies = [run_sweep(SCENE, d, workers=1, fmu_dir=OUT) for d in (small, big)]
    for t in studies:
        assert not t.failed(), t.failed()[:1]
    walls = [t.info["wall_time"] for t in studies]
    per_point = (walls[1] - walls[0]) / (len(big.points) - len(small.points))
    fixed = walls[1] - per_point * len(big.points)
    inside = np.array(studies[1].info["seconds"]) - np.array(studies[1].info["simulation"])
    planning = (studies[1].info["planning"] - studies[0].info["planning"]) / (len(big.points) - len(small.points))
    one = alone(big.points[:5])
    lines = ["### What a point costs beyond its simulation", "",
             f"The splice scene at 0.5 ms (5,000 steps). Studies of {len(small.points)} and {len(big.points)} points on a "
             "local cluster of one worker, each timed from the cluster being up to the last row: a point's cost is what "
             f"the {len(big.points) - len(small.points)} more points added, the rest is paid once per study.", "",
             "| | seconds | of the simulation |", "|---|---:|---:|",
             f"| the simulation itself: FMPy's efficient loop (reset, simulate_fmu), per point | {loop:.4f} | |",
             f"| a point of `webline sweep` | {per_point:.4f} | {per_point / loop:.1%} |",
             f"| the cost per point beyond the simulation | {per_point - loop:+.4f} | **{per_point / loop - 1:+.1%}** |",
             f"| in the worker outside simulate_fmu, per point (median) | {np.median(inside):.5f} | {np.median(inside) / loop:.2%} |",
             f"| planning on the client, per point (beside the worker) | {planning:.5f} | {planning / loop:.2%} |",
             f"| once per study: the export, the FMU to the worker, its instance | {fixed:.2f} | |",
             f"| a point as `webline run --engine fmpy-line` runs it (export, extract, instantiate, run) | {one:.4f} | "
             f"{one / loop:.0%} |", ""]

    # Points per second per worker, both engines.
    many = design([], samples, n_line, 7)
    line = run_sweep(SCENE, many, workers=args.workers, fmu_dir=OUT)
    parts = run_sweep(SCENE, design([], samples, n_parts, 7), engine="parts", workers=args.workers, fmu_dir=OUT)
    lines += ["### Points per second per worker", "",
              f"A local cluster of {args.workers} workers; the same design, the first {n_parts} points of it for the parts.", "",
              "| engine | points | failed | wall time [s] | points/s per worker | per point on its worker [s] |",
              "|---|---:|---:|---:|---:|---:|"]
    rates = {}
    for name, t in (("line (the Line FMU)", line), ("parts (co-simulation of the FMUs)", parts)):
        wall = t.info["wall_time"]
        rates[name] = len(t.rows) / wall / t.info["workers"]
        lines.append(f"| {name} | {len(t.rows)} | {len(t.failed())} | {wall:.1f} | {rates[name]:.2f} | "
                     f"{np.median(t.info['seconds']):.3f} |")
    lines += ["", f"The Line FMU runs {rates['line (the Line FMU)'] / rates['parts (co-simulation of the FMUs)']:.1f}× "
              "as many points per second per worker as the parts.", ""]

    text = "\n".join(lines)
    print(text)
    if not args.quick:
        doc = args.out.read_text()
        head, rest = doc.split(BEGIN, 1)
        _, tail = rest.split(END, 1)
        args.out.write_text(f"{head}{BEGIN}\n\n{text}\n{END}{tail}")
        print(f"written: {args.out}")


if __name__ == "__main__":
    main()
