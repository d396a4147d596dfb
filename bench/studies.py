#!/usr/bin/env python3
"""Studies measured: what a point of `webline sweep` costs against the Line FMU's own stepping, through
the native loop (`--engine line`) and FMPy's (`--engine fmpy-line`), and points per second per worker
through both and through the parts, side by side in one run. Writes the measured part of docs/studies.md.

    .venv/bin/python bench/studies.py [--workers 2] [--quick] [--out docs/studies.md]

Needs out/ from `bash fmu/main.sh`. The splice scene (webline/scenes/splice.json, at its own
0.5 ms step) with the issue's design: idler inertia uniform in [0.01, 0.05] kg m2, first span
length normal around 1.5 m (sd 0.05 m), a Latin hypercube of seed 7. --quick shortens every run
(a smoke test of the script; nothing written).

  cost      In this process, for each point of 200, interleaved: the FMU's own stepping (its 5,000
            fmi2DoStep in one call of convertingSpanDoSteps, no outputs read, after the reset and
            the initialization, which are not counted), the native loop (webline.native.simulate:
            reset, initialization, steps, outputs, the array) and FMPy's (reset, simulate_fmu), and
            for the first 20 the parts' co-simulation as a worker runs it (`--engine parts`). Then
            the same 200 points as one study on a local cluster of one worker, once per loop, and
            the stepping again on the native study's worker right after its study: a point's cost on its worker is the worker's time from the end of its first task to the
            end of its last, per point, so whatever Dask and webline add per point shows there (the
            gaps between tasks included). Apart: what is paid once per study before the first
            point runs (reading the scene, the export, sending the FMU) and once per worker (its
            first task extracts the FMU and makes the instance), and a point as `webline run
            --engine fmpy-line` runs it (export, extract, instantiate, run).
  rate      1,000 points through the Line FMU by either loop and 20 through the parts (the
            co-simulation of the scene's FMUs, `--engine parts`), each a study on a local cluster
            of --workers workers: points per second per worker, from the cluster being up to the
            last row.

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

from webline import linefmu, native  # noqa: E402
from webline.linestudy import Planner  # noqa: E402
from webline.sampling import design, parse_sample  # noqa: E402
from webline.scene import load_scene  # noqa: E402
from webline.sweep import dask_client, run_sweep  # noqa: E402

OUT = ROOT / "out"
SCENE = ROOT / "webline" / "scenes" / "splice.json"
DOC = ROOT / "docs" / "studies.md"
NATIVE_PARTS, STEPPING_PARTS = "native (the parts' points)", "stepping (the parts' points)"
SAMPLES = ["line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)", "line.first.L=normal(1.5 m, 0.05 m)"]


def in_process(fmu_bytes: bytes, tasks: list, loops=True, parts=()) -> dict:
    """Seconds per point in this process (a worker's, when a Dask task), each point of `tasks`
    (linestudy.LineTask) interleaved: the FMU's own stepping (one call, no outputs), with `loops` the
    native loop and FMPy's (both reset the instance first), and for the first points, `parts` (their
    overrides), the co-simulation of the parts as a worker runs it (`--engine parts`)."""
    from fmpy import extract, read_model_description, simulate_fmu
    from fmpy.simulation import instantiate_fmu
    from webline.engines import run_scene
    from webline.points import metric_record

    seconds = {"stepping": [], "native": [], "fmpy": [], "parts": [], NATIVE_PARTS: [], STEPPING_PARTS: []}
    with tempfile.TemporaryDirectory() as tmp:
        fmu = Path(tmp) / "Line.fmu"
        fmu.write_bytes(fmu_bytes)
        folder = extract(str(fmu))
        description = read_model_description(folder)
        instance = instantiate_fmu(folder, description, "CoSimulation")
        run, nothing = native.entry(instance), np.array([], dtype=np.uint32)
        for k, task in enumerate(tasks):
            instance.reset()
            begin = native.start(instance, description, task.stop_time, task.parameters)
            times = native.communication_points(begin, task.stop_time, task.step, True)
            t0 = clock.perf_counter()
            status, _, _ = native.steps(run, instance, times, nothing, np.empty((len(times), 0)))
            seconds["stepping"].append(clock.perf_counter() - t0)
            assert status == native.OK, status
            instance.terminate()
            for name, simulate in (("native", native.simulate), ("fmpy", simulate_fmu)) if loops else ():
                t0 = clock.perf_counter()
                instance.reset()
                simulate(folder, model_description=description, fmu_instance=instance, fmi_type="CoSimulation",
                         stop_time=task.stop_time, step_size=task.step, output_interval=task.step,
                         output=task.outputs, start_values=task.parameters)
                seconds[name].append(clock.perf_counter() - t0)
            if k < len(parts):
                scene = load_scene(SCENE, parts[k], OUT)
                scene.record = metric_record(scene)
                t0 = clock.perf_counter()
                run_scene(scene, "parts", fmu_dir=OUT)
                seconds["parts"].append(clock.perf_counter() - t0)
                seconds[NATIVE_PARTS].append(seconds["native"][-1])
                seconds[STEPPING_PARTS].append(seconds["stepping"][-1])
        instance.freeInstance()
    return {k: float(np.mean(v)) for k, v in seconds.items() if v}


def on_worker(study) -> dict:
    """What a study of one worker says about its points: the mean run (fmi2Reset and the loop), a point
    all included (from the end of the worker's first task to the end of its last, per point), what is
    paid once per study and once per worker."""
    assert not study.failed(), study.failed()[:1]
    started, ended, sim = (np.array(x) for x in zip(*study.info["tasks"]))
    order = np.argsort(started)
    started, ended, sim = started[order], ended[order], sim[order]
    return {"run": float(sim[1:].mean()), "point": float((ended[-1] - ended[0]) / (len(sim) - 1)),
            "study": float(started[0] - study.info["started"]), "worker": float(ended[0] - started[0] - sim[0]),
            "planning": float(study.info["planning"]), "wall": float(study.info["wall_time"])}


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

    # What a point costs against the FMU's own stepping: in this process, and on a worker in a study.
    few = design([], samples, n_loop, 7)
    planner = Planner(SCENE, OUT)
    tasks = [planner.plan(p)[1] for p in few.points]
    fmu = planner.structures[0].fmu
    here = in_process(fmu, tasks, parts=few.points[:n_parts])
    studies = {}
    with dask_client(None, 1) as (client, _):  # the stepping on the worker that ran the study, right after it
        studies["line"] = on_worker(run_sweep(SCENE, few, engine="line", client=client, fmu_dir=OUT))
        worker_step = client.submit(in_process, fmu, tasks, False, pure=False).result()["stepping"]
    studies["fmpy-line"] = on_worker(run_sweep(SCENE, few, engine="fmpy-line", workers=1, fmu_dir=OUT))
    one = alone(few.points[:5])
    step = here["stepping"]
    n = len(few.points)
    line, fmpy = studies["line"], studies["fmpy-line"]
    lines = ["### What a point costs against the FMU's own stepping", "",
             f"The splice scene at 0.5 ms (5,000 steps), {n} points of the design. The FMU's own stepping is its 5,000 "
             "fmi2DoStep of a point in one call of `convertingSpanDoSteps` with no outputs read, after the point's reset and "
             "initialization. In this process it is measured for each point interleaved with the point by each loop. On a "
             "worker: the same points as one study on a local cluster of one worker, once per loop, and the stepping of "
             "each point on the native study's worker right after it; a point there is the worker's time from the end of "
             "its first task to the end of its last, per point: all that Dask and webline add per point (the task to the "
             "worker, the parameters, the row, the result back, the next task) shows there. What is paid once is apart.", "",
             "| | native loop (`--engine line`) [s] | of the stepping | FMPy's loop (`--engine fmpy-line`) [s] | of the stepping |",
             "|---|---:|---:|---:|---:|",
             f"| the FMU's own stepping of a point, in this process (mean) | {step:.4f} | 100% | {step:.4f} | 100% |",
             f"| a point in this process: reset, set-up, steps, outputs (mean) | {here['native']:.4f} | {here['native'] / step:.0%} | "
             f"{here['fmpy']:.4f} | {here['fmpy'] / step:.0%} |",
             f"| the FMU's own stepping of a point, on the worker (mean) | {worker_step:.4f} | 100% | {worker_step:.4f} | 100% |",
             f"| a point's run on the worker: reset and the loop (mean) | {line['run']:.4f} | {line['run'] / worker_step:.0%} | "
             f"{fmpy['run']:.4f} | {fmpy['run'] / worker_step:.0%} |",
             f"| **a point on the worker, all included** | **{line['point']:.4f}** | **{line['point'] / worker_step:.0%}** | "
             f"{fmpy['point']:.4f} | {fmpy['point'] / worker_step:.0%} |",
             f"| once per study, before the first point runs: reading the scene, the export, the FMU to the worker | "
             f"{line['study']:.2f} | | {fmpy['study']:.2f} | |",
             f"| once per worker, in its first task: extracting the FMU, the instance | {line['worker']:.2f} | | {fmpy['worker']:.2f} | |",
             f"| meanwhile on the client: reading each point's scene, compiling its line, submitting it (all points, the "
             f"export included), of the study's {line['wall']:.1f} s and {fmpy['wall']:.1f} s | {line['planning']:.2f} | | "
             f"{fmpy['planning']:.2f} | |",
             f"| a point as `webline run --engine fmpy-line` runs it (export, extract, instantiate, run) | | | {one:.4f} | {one / step:.0%} |",
             "", f"A point on its worker costs {line['point'] / worker_step:.2f}× the FMU's own stepping through the native loop, "
             f"{fmpy['point'] / worker_step:.2f}× through FMPy's; in this process {here['native'] / step:.2f}× and "
             f"{here['fmpy'] / step:.2f}×.", ""]

    # Points per second per worker, every engine.
    many = design([], samples, n_line, 7)
    runs = {"line (the Line FMU, native loop)": run_sweep(SCENE, many, engine="line", workers=args.workers, fmu_dir=OUT),
            "fmpy-line (the Line FMU, FMPy's loop)": run_sweep(SCENE, many, engine="fmpy-line", workers=args.workers, fmu_dir=OUT),
            "parts (co-simulation of the FMUs)": run_sweep(SCENE, design([], samples, n_parts, 7), engine="parts",
                                                           workers=args.workers, fmu_dir=OUT)}
    lines += ["### Points per second per worker", "",
              f"A local cluster of {args.workers} workers; the same design, the first {n_parts} points of it for the parts.", "",
              "| engine | points | failed | wall time [s] | points/s per worker | per task on its worker (median) [s] |",
              "|---|---:|---:|---:|---:|---:|"]
    rates = {}
    for name, t in runs.items():
        wall = t.info["wall_time"]
        rates[name] = len(t.rows) / wall / t.info["workers"]
        on_worker_s = np.median([b - a for a, b, _ in t.info["tasks"]])
        lines.append(f"| {name} | {len(t.rows)} | {len(t.failed())} | {wall:.1f} | {rates[name]:.2f} | {on_worker_s:.3f} |")
    native_rate, fmpy_rate, parts_rate = rates.values()
    planning = runs["line (the Line FMU, native loop)"].info["planning"]
    lines += ["", f"Per worker, the Line FMU runs {native_rate / parts_rate:.0f}× as many points per second as the parts through "
              f"the native loop, {fmpy_rate / parts_rate:.1f}× through FMPy's. Here the client, which reads each point's "
              f"scene, compiles its line and submits it ({planning:.1f} s for the {n_line} points, the export included), and "
              "Dask's scheduler share the machine's cores with the workers.", "",
              f"Point for point, in this process and interleaved (the first {n_parts} points of the design): the parts' "
              f"co-simulation of a point takes {here['parts']:.3f} s, the Line FMU's native loop {here[NATIVE_PARTS]:.4f} s "
              f"({here['parts'] / here[NATIVE_PARTS]:.0f}×), and the Line FMU's own stepping {here[STEPPING_PARTS]:.4f} s "
              f"({here['parts'] / here[STEPPING_PARTS]:.0f}×): no loop around the Line FMU can make the factor larger than "
              "that.", ""]

    text = "\n".join(lines)
    print(text)
    if not args.quick:
        publish(args.out, "bench/studies.py", text)


if __name__ == "__main__":
    main()
