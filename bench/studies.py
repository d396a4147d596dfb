#!/usr/bin/env python3
"""Studies measured: what a point of `webline sweep` costs beyond its simulation, and points per
second per worker through the Line FMU and through the parts, side by side in one run. Writes the
measured part of docs/studies.md.

    .venv/bin/python bench/studies.py [--workers 2] [--quick] [--out docs/studies.md]

Needs out/ from `bash fmu/main.sh`. The splice scene (webline/scenes/splice.json, at its own
0.5 ms step) with the issue's design: idler inertia uniform in [0.01, 0.05] kg m2, first span
length normal around 1.5 m (sd 0.05 m), a Latin hypercube of seed 7. --quick shortens every run
(a smoke test of the script; nothing written).

  overhead  200 points as one study on a local cluster of one worker. The simulation is the time
            the worker spends in fmi2Reset and simulate_fmu; a point's cost is the worker's time from
            the end of its first task to the end of its last, divided by the points after the first:
            whatever Dask and webline add per point shows there (the gaps between tasks included),
            measured in the same run and under the same load as the simulation. Apart: what is paid
            once per study before the first point runs (reading the scene, the export, sending the
            FMU) and once per worker (its first task extracts the FMU and makes the instance), the
            study end to end, FMPy's efficient loop (reset, simulate_fmu) in this process with no
            Dask, and a point as `webline run --engine fmpy-line` runs it (export, extract,
            instantiate, run).
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
from measured import publish  # bench/, the script's folder

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "webline" / "src"))

from webline import linefmu  # noqa: E402
from webline.linestudy import Planner  # noqa: E402
from webline.sampling import design, parse_sample  # noqa: E402
from webline.scene import load_scene  # noqa: E402
from webline.sweep import run_sweep  # noqa: E402

OUT = ROOT / "out"
SCENE = ROOT / "webline" / "scenes" / "splice.json"
DOC = ROOT / "docs" / "studies.md"
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
        t0 = clock.perf_counter()
        for _, task in tasks:
            instance.reset()
            simulate_fmu(folder, model_description=description, fmu_instance=instance, fmi_type="CoSimulation",
                         stop_time=task.stop_time, step_size=task.step, output_interval=task.step,
                         output=task.outputs, start_values=task.parameters)
        seconds = (clock.perf_counter() - t0) / len(tasks)
        instance.freeInstance()
    return seconds


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
    n_loop, n_line, n_parts = (24, 40, 4) if args.quick else (200, 1000, 20)

    # What a point costs beyond its simulation, measured within one study on one worker: the time from
    # its first task's start to its last task's end against the time the runs themselves took.
    few = design([], samples, n_loop, 7)
    study = run_sweep(SCENE, few, workers=1, fmu_dir=OUT)
    assert not study.failed(), study.failed()[:1]
    started, ended, sim = (np.array(x) for x in zip(*study.info["tasks"]))
    order = np.argsort(started)
    started, ended, sim = started[order], ended[order], sim[order]
    first = ended[0] - started[0] - sim[0]  # the worker's first task extracts the FMU and makes the instance
    steady = ended[-1] - ended[0]  # the other points, from the first task's end to the last's
    cost = steady / (len(sim) - 1)
    mean = sim[1:].mean()
    gaps = started[1:] - ended[:-1]
    outside = np.median(ended - started - sim)
    fixed = started[0] - study.info["started"]
    loop = plain_loop(few.points)
    one = alone(few.points[:5])
    n = len(few.points)
    lines = ["### What a point costs beyond its simulation", "",
             f"The splice scene at 0.5 ms (5,000 steps), {n} points of the design as one study on a local cluster of one "
             "worker. The simulation is what the worker spent in fmi2Reset and simulate_fmu. A point's cost is the "
             "worker's time from the end of its first task to the end of its last, per point: all that Dask and webline "
             "add per point (the task to the worker, finding the instance, setting the parameters, the row, the result "
             "back, the next task) shows there, measured in the same run and under the same load as the simulation. "
             "What is paid once is apart.", "",
             "| | seconds | of the simulation |", "|---|---:|---:|",
             f"| the simulation of a point (mean) | {mean:.4f} | |",
             f"| a point on the worker, all included | {cost:.4f} | {cost / mean:.1%} |",
             f"| **the cost per point beyond the simulation** | **{cost - mean:+.4f}** | **{cost / mean - 1:+.1%}** |",
             f"| of which inside the task, outside the simulation (median) | {outside:.5f} | {outside / mean:.2%} |",
             f"| of which between points: Dask hands over a task every few points (median, mean) | {np.median(gaps):.4f}, {gaps.mean():.4f} | "
             f"{gaps.mean() / mean:.1%} |",
             f"| once per study, before the first point runs: reading the scene, the export, the FMU to the worker | {fixed:.2f} | |",
             f"| once per worker, in its first task: extracting the FMU, the instance | {first:.2f} | |",
             f"| the study end to end (from the cluster being up), per point | {study.info['wall_time'] / n:.4f} | "
             f"{study.info['wall_time'] / n / mean:.1%} |",
             f"| FMPy's efficient loop in this process (no Dask, no webline), per point | {loop:.4f} | {loop / mean:.1%} |",
             f"| a point as `webline run --engine fmpy-line` runs it (export, extract, instantiate, run) | {one:.4f} | "
             f"{one / mean:.0%} |", ""]

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
        on_worker = np.median([b - a for a, b, _ in t.info["tasks"]])
        lines.append(f"| {name} | {len(t.rows)} | {len(t.failed())} | {wall:.1f} | {rates[name]:.2f} | {on_worker:.3f} |")
    lines += ["", f"The Line FMU runs {rates['line (the Line FMU)'] / rates['parts (co-simulation of the FMUs)']:.1f}× "
              "as many points per second per worker as the parts.", ""]

    text = "\n".join(lines)
    print(text)
    if not args.quick:
        publish(args.out, "bench/studies.py", text)


if __name__ == "__main__":
    main()
