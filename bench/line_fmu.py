#!/usr/bin/env python3
"""The Line FMU measured: what a step costs natively, what accuracy costs in
time, and a line as one FMU against the same line as an SSP of parts, side
by side in FMPy and in libcosim. Writes the measured part of docs/line-fmu.md.

    .venv/bin/python bench/line_fmu.py [--quick] [--out docs/line-fmu.md]

Needs out/ from `bash fmu/main.sh` (the span's and the Roller's FMUs and the
Line's libraries). --quick shortens every run (a smoke test of the script).

  native    bench/line_cost.c drives the FMU's library from C: set a motor
            torque, fmi2DoStep, get one output, as a 1 kHz or 100 Hz control
            loop would; CPU time of the thread per step, the least of 7
            rounds (each round instantiates the line afresh; the machine's
            other load only adds to a round). Lines of 1, 3
            and 10 spans (an unwinder, idlers, a pull roll, a winder: `long_line`).
  accuracy  the splice scene at 1 ms for the `tolerance` parameter from 1e-7
            to 1e-11: the largest error of any recorded signal against the
            monolithic reference (relative to the signal's largest magnitude)
            and the native cost per step.
  engines   the splice scene (whole) and the 10-span line (its first second):
            the parts as an SSP at the step `webline export` picks for them,
            run by FMPy's simulate_ssp and by libcosim, beside the Line FMU at
            1 ms and 10 ms run by the same two; wall time and the largest error
            against the monolithic reference.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

import numpy as np
from measured import publish  # bench/, the script's folder

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "webline" / "src"))

from webline import linefmu  # noqa: E402
from webline.accuracy import errors  # noqa: E402
from webline.reference import reference  # noqa: E402
from webline.result import Result  # noqa: E402
from webline.scene import load_scene, parse_scene  # noqa: E402

OUT = ROOT / "out"
DOC = ROOT / "docs" / "line-fmu.md"


def long_line(spans: int, stop: float = 2.0, traction: bool = False) -> str:
    """A paper line of `spans` spans: tension-driven unwinder, idlers, a pull
    roll that sets the speed (10 m/s, 2 % slower from 0.5 s), a tension-driven winder.
    `traction`: the web may slip on every idler (90 degrees of wrap, mu 0.3)."""
    web = {"paper": {"E": "5 GPa", "thickness": "100 um", "width": "1.2 m", "density": "800 kg/m3", "d_r": "0.5 ms"}}
    line = [{"type": "unwinder", "name": "unwind", "J": "8 kg.m2", "R": "0.5 m", "b": "0.1 N.m.s",
             "drive": {"tension": "400 N"}, "strain": 0.0, "v_start": "10 m/s"}]
    for i in range(spans):
        line.append({"type": "span", "name": f"s{i}", "L": f"{1.0 + 0.25 * (i % 4)} m", "web": "paper", "effects": ["includeDamping"]})
        if i == spans - 1:
            break
        if i == spans - 2 or spans == 1:
            line.append({"type": "roller", "name": "pull",
                         "drive": {"speed": {"table": [["0 s", "10 m/s"], ["0.5 s", "10 m/s"], ["0.6 s", "9.8 m/s"]]}}})
        else:
            line.append({"type": "roller", "name": f"idler{i}", "J": "0.05 kg.m2", "R": "0.08 m", "b": "0.002 N.m.s", "v_start": "10 m/s",
                         **({"wrap": "90 deg", "traction": {"mu": 0.3}} if traction else {})})
    if spans == 1:
        line.append({"type": "sink", "name": "pull", "speed": {"table": [["0 s", "10 m/s"], ["0.5 s", "10 m/s"], ["0.6 s", "9.8 m/s"]]}})
    else:
        line.append({"type": "winder", "name": "rewind", "J": "6 kg.m2", "R": "0.4 m", "b": "0.1 N.m.s",
                     "drive": {"tension": "400 N"}, "v_start": "10 m/s"})
    record = [f"s{i}.T" for i in range(spans)]
    name = f"line{spans}" + ("_traction" if traction else "")
    return json.dumps({"name": name, "description": f"a paper line of {spans} spans", "stop_time": f"{stop} s",
                       "step": "1 ms", "start": "equilibrium", "webs": web, "line": line, "record": record})


def harness(folder: Path) -> Path:
    import fmpy

    exe = folder / "line_cost"
    subprocess.run(["gcc", "-O2", "-Wall", "-Wextra", "-Werror", f"-I{Path(fmpy.__file__).parent / 'c-code'}",
                    f"-I{ROOT / 'tests' / 'integration' / 'c_importer'}", str(ROOT / "bench" / "line_cost.c"), "-o", str(exe), "-ldl"], check=True)
    return exe


def unpacked(fmu: Path, folder: Path):
    """The FMU extracted: its linux64 library, GUID, resources URI and value references."""
    with zipfile.ZipFile(fmu) as z:
        z.extractall(folder)
    from fmpy import read_model_description

    md = read_model_description(str(fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    return folder / "binaries" / "linux64" / "Line.so", md.guid, (folder / "resources").as_uri() + "/", vr, md


def native(exe: Path, fmu: Path, folder: Path, torque: str, output: str, h: float, steps: int, tol=None, rounds=7) -> float:
    """ns per step, the least over the rounds."""
    lib, guid, uri, vr, _ = unpacked(fmu, folder)
    args = [str(exe), str(lib), guid, uri, str(vr[torque]), str(vr[output]), repr(h), str(steps), str(rounds)]
    if tol is not None:
        args += [str(vr["tolerance"]), repr(tol)]
    run = subprocess.run(args, capture_output=True, text=True, check=True)
    per_round = [float(x) for x in run.stdout.split()[:rounds]]
    return min(per_round)


def line_in_libcosim(fmu: Path, scene, h: float) -> Result:
    names = [linefmu.output(c, q) for c, q in scene.record]
    time_, rows, wall = linefmu.run_libcosim(fmu, names, h, scene.stop_time)
    return Result(scene.name, scene.columns(), time_, rows, {"method": "Line FMU in libcosim", "step": h, "wall_time": wall})


def parts(source: str, stop: float, folder: str):
    """The scene (a file or a scene's text) as an SSP of parts at its exported step, run by
    FMPy and by libcosim: the step, and each engine's wall time and largest error.

    Runs in a process of its own: FMPy's C logger proxy keeps the logger of the last
    simulate_fmu call after that call returns, so a later SSP that logs a warning in the
    same process calls freed memory."""
    from webline.compiler import compile_scene
    from webline.engines import run_fmpy, run_libcosim
    from webline.ssp import read_ssp, write_ssp
    from webline.stability import export_step

    folder = Path(folder)
    scene = load_scene(Path(source), fmu_dir=OUT) if source.endswith(".json") else parse_scene(source, source="line", fmu_dir=OUT)
    scene.stop_time = stop
    system = compile_scene(scene, OUT)
    system.step = export_step(system)
    archive = write_ssp(system, folder / f"{scene.name}.ssp")
    system = read_ssp(archive, folder / "extracted")
    measured = {}
    for engine, r in (("libcosim", run_libcosim(folder / "extracted", system)), ("FMPy", run_fmpy(archive, system))):
        r.columns = scene.columns()  # the SSP names columns by variable; compare by the scene's names
        measured[engine] = (r.info["wall_time"], worst(r, scene))
    return system.step, measured


def worst(result: Result, scene) -> float:
    within = result.time <= scene.stop_time + 1e-9
    trimmed = Result(result.scene, result.columns, result.time[within], result.data[within], result.info)
    return max(errors(trimmed, reference(scene, times=trimmed.time)).values())


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--quick", action="store_true")
    p.add_argument("--out", type=Path, default=DOC)
    args = p.parse_args()
    quick = args.quick
    tmp = Path(tempfile.mkdtemp(prefix="line-bench-"))
    exe = harness(tmp)
    lines = []

    # Native cost per step.
    lines += ["### What a step costs natively", "",
              "| line | states | ns per step at 1 ms | ns per step at 10 ms |", "|---|---:|---:|---:|"]
    for spans in (1, 3, 10):
        scene = parse_scene(long_line(spans), source=f"line{spans}", fmu_dir=OUT)
        fmu = linefmu.export(scene, tmp / f"line{spans}.fmu", OUT)
        from fmpy import read_model_description

        n = len(read_model_description(str(fmu)).derivatives)
        torque = "idler0.tau_m" if spans > 2 else "unwind.tau_m"
        costs = [native(exe, fmu, tmp / f"u{spans}-{h}", torque, "s0.T", h, 200 if quick else int(2.0 / h)) for h in (1e-3, 1e-2)]
        lines.append(f"| {spans} span{'s' if spans > 1 else ''} | {n} | {costs[0]:,.0f} | {costs[1]:,.0f} |")
    lines.append("")

    # What traction costs: the 10-span line with the web free to slip on every idler, beside it without.
    lines += ["### What traction costs (the 10-span line at 1 ms)", "",
              "| line | states | ns per step | largest error over 2 s, of scale |", "|---|---:|---:|---:|"]
    for traction in (False, True):
        scene = parse_scene(long_line(10, stop=0.7 if quick else 2.0, traction=traction), source="line10", fmu_dir=OUT)
        fmu = linefmu.export(scene, tmp / f"{scene.name}.fmu", OUT)
        from fmpy import read_model_description

        n = len(read_model_description(str(fmu)).derivatives)
        cost = native(exe, fmu, tmp / f"u-{scene.name}", "idler0.tau_m", "s0.T", 1e-3, 200 if quick else 2000)
        what = "traction on its 8 idlers" if traction else "no slip"
        lines.append(f"| 10 spans, {what} | {n} | {cost:,.0f} | {worst(linefmu.run(scene, OUT, step=1e-3), scene):.1e} |")
    lines.append("")

    # Accuracy against time.
    splice = load_scene(ROOT / "webline" / "scenes" / "splice.json", fmu_dir=OUT)
    if quick:
        splice.stop_time = 0.5
    lines += ["### What accuracy costs (the splice scene at 1 ms)", "",
              "| tolerance | largest error, of scale | ns per step |", "|---:|---:|---:|"]
    fmu = linefmu.export(splice, tmp / "splice.fmu", OUT, start="given")
    from fmpy import simulate_fmu

    names = [linefmu.output(c, q) for c, q in splice.record]
    for tol in (1e-7, 1e-8, 1e-9, 1e-10, 1e-11):
        out = simulate_fmu(str(fmu), stop_time=splice.stop_time, step_size=1e-3, output_interval=1e-3, output=names,
                           start_values={"tolerance": tol}, relative_tolerance=tol)
        result = Result(splice.name, splice.columns(), out["time"], np.column_stack([out[x] for x in names]), {})
        cost = native(exe, fmu, tmp / f"tol{tol}", "unwind.tau_m" if "unwind.tau_m" in names else "idler.tau_m", "first.T", 1e-3,
                      200 if quick else 2500, tol=tol)
        lines.append(f"| {tol:.0e} | {worst(result, splice):.1e} | {cost:,.0f} |")
    lines.append("")

    # One FMU against the SSP of parts, in the same engines.
    lines += ["### A line as one FMU against its SSP of parts", "",
              "| scene | run | step | engine | wall time [s] | faster than the SSP in this engine | largest error, of scale |",
              "|---|---|---:|---|---:|---:|---:|"]
    ten_text = long_line(10, stop=0.7 if quick else 1.0)  # through the pull roll's slow-down at 0.5-0.6 s
    ten = parse_scene(ten_text, source="line10", fmu_dir=OUT)
    spawn = multiprocessing.get_context("spawn")
    for scene, source in ((splice, str(ROOT / "webline" / "scenes" / "splice.json")), (ten, ten_text)):
        with spawn.Pool(1) as pool:
            step, runs = pool.apply(parts, (source, scene.stop_time, str(tmp / f"ssp-{scene.name}")))
        for engine, (wall, err) in runs.items():
            lines.append(f"| {scene.name} | SSP of {len(scene.line)} parts | {step * 1e3:g} ms | {engine} | {wall:.2f} | | {err:.1e} |")
        for h in (1e-3, 1e-2):
            fmu = linefmu.export(scene, tmp / f"{scene.name}-{h}.fmu", OUT, start=linefmu.run_start(scene))
            a = linefmu.run(scene, OUT, step=h)
            b = line_in_libcosim(fmu, scene, h)
            for engine, r in (("FMPy", a), ("libcosim", b)):
                wall = r.info["wall_time"]
                lines.append(f"| {scene.name} | Line FMU | {h * 1e3:g} ms | {engine} | {wall:.2f} | {runs[engine][0] / wall:.0f}× | {worst(r, scene):.1e} |")
    lines.append("")

    text = "\n".join(lines)
    print(text)
    if not quick:
        publish(args.out, "bench/line_fmu.py", text)


if __name__ == "__main__":
    main()
