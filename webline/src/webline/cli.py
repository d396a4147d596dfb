"""The `webline` command.

    webline run SCENE.json|LINE.ssp [--engine line|reference|parts|libcosim|fmpy] [--step 1ms] [--force] [--report]
                                    [--algorithm gauss-seidel|jacobi] [--coupling extrapolate|hold]
    webline export SCENE.json -o LINE.ssp
    webline export SCENE.json --fmu [-o Line.fmu] [--fmi3]
    webline check SCENE_OR_SSP ... [--method auto|derivatives|differences]
    webline linearize SCENE.json [--at TIME] [--loop NAME] [--bode INPUT:OUTPUT ...] [--step-response INPUT:OUTPUT ...]
                                 [-o MODEL.mat]
    webline reference SCENE.json
    webline convergence SCENE.json [--engine parts|line] [--steps 2ms,1ms,0.5ms]
    webline sweep SCENE.json --grid KEY=V1,V2 ... [--sample KEY=uniform(A, B) --n N] [--scheduler tcp://host:8786]
                             [--metric NAME=max(SIGNAL)] [--resume] [--max-failed N]
    webline scenes [--to scenes]
    webline draw SCENE.json [-o FILE.svg]
    webline --version

Outputs go to ./out of the current folder unless --out says otherwise; which FMUs webline
runs (the repository's out/ in a checkout, else the wheel's) is installation.py's choice.
"""

from __future__ import annotations

import argparse
import math
import re
import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from . import installation, units
from .bound import Runaway
from .names import ARCHIVE_ENGINES, ENGINES, engine_name
from .fmus import DEFAULT_FMU_DIR, FmuError
from .linear import StabilityError
from .master import ALGORITHMS, COUPLINGS, CoSimulationError, scene_grid
from .scene import SceneError, load_scene
from .ssp import SspError
from .linefmu import LineFmuError
from .journal import StudyError
from .summary import summary, system_summary, traction_columns
from .usermetric import FUNCTIONS

OUT = Path("out")  # of the current folder, wherever webline runs from


def time_arg(text: str) -> float:
    """A time on the command line: "1ms", "1 ms", "0.001" (seconds)."""
    t = text.strip()
    try:
        return float(t)
    except ValueError:
        pass
    for unit in ("ms", "us", "min", "s"):
        if t.endswith(unit):
            return units.parse_quantity(f"{t[: -len(unit)].strip()} {unit}", units.TIME)
    raise argparse.ArgumentTypeError(f"{text!r} is not a time (e.g. 1ms, 0.5 ms, 0.001)")


def engine_arg(text: str) -> str:
    try:
        return engine_name(text)
    except ValueError as e:
        raise argparse.ArgumentTypeError(str(e)) from None


def add_master_options(p):
    """The parts' master options; None where not given, so that another engine can refuse them."""
    p.add_argument("--step", type=time_arg, help="communication step (default: the scene's)")
    p.add_argument("--algorithm", choices=ALGORITHMS, help="parts: the master's algorithm (default gauss-seidel)")
    p.add_argument("--coupling", choices=COUPLINGS,
                   help="parts: extrapolate (the default): input extrapolation, input derivatives for the spans; "
                        "hold: zero-order hold")
    p.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR, help=f"where ConvertingSpan.fmu and Roller.fmu are (default: {DEFAULT_FMU_DIR})")
    p.add_argument("--no-rollback", action="store_true", help="parts: do not save FMU states; a discarded step is an error")


def master_options(args, engine: str, progress=False) -> dict:
    """The master's options for the parts; for another engine, an error if any was given."""
    given = [f"--{k.replace('_', '-')}" for k in ("algorithm", "coupling") if getattr(args, k, None)]
    given += ["--no-rollback"] if getattr(args, "no_rollback", False) else []
    if engine != "parts":
        if given:
            raise SceneError(f"{' and '.join(given)} set webline's co-simulation of the parts (--engine parts), "
                             f"not the {engine} engine")
        return {}
    return dict(algorithm=args.algorithm or ALGORITHMS[0], coupling=args.coupling or COUPLINGS[0],
                rollback=not getattr(args, "no_rollback", False), progress=progress)


def cmd_export(args):
    from .ssp import write_ssp
    from .stability import export_step
    from .compiler import compile_scene

    scene = load_scene(args.scene, fmu_dir=args.fmu_dir)
    if args.fmu:
        from . import linefmu

        path = linefmu.export(scene, args.output or Path(args.out) / f"{scene.name}.fmu", args.fmu_dir, fmi3=args.fmi3)
        print(f"{scene.name}: {len(scene.line)} parts as one FMU ({'FMI 3.0' if args.fmi3 else 'FMI 2.0'}, "
              f"start: {linefmu.run_start(scene)}); wrote {path}")
        return 0
    if args.fmi3:
        raise SceneError("--fmi3 goes with --fmu (an SSP archive carries the FMI 2.0 FMUs)")
    from .engines import refuse_for_parts

    refuse_for_parts(scene)
    system = compile_scene(scene, args.fmu_dir)
    system.step = args.step or export_step(system)
    path = write_ssp(system, args.output or Path(args.out) / f"{scene.name}.ssp")
    print(f"{scene.name}: {len(system.components)} FMU components, {len(system.connections)} connections, "
          f"step {system.step * 1e3:g} ms, stop {system.stop_time:g} s; wrote {path}")
    names = [c.name for c in system.components]
    for a, b in ((a, b) for a in names for b in names if a != b and b.startswith(a)):
        print(f"webline export: warning: part '{a}' begins the name of part '{b}': FMPy 0.3's simulate_ssp "
              f"gives {b}'s parameters to {a} and stops; rename one of them (docs/ssp.md)", file=sys.stderr)
    return 0


def cmd_run(args):
    progress = sys.stderr.isatty() if args.progress is None else args.progress
    if args.scene.endswith(".ssp"):
        from .engines import run_archive

        engine = args.engine or "parts"
        if args.reference:
            raise SspError(f"{args.scene}: --reference needs a scene (the monolithic reference is computed from it)")
        if args.report:
            raise SspError(f"{args.scene}: --report needs a scene (.json): its page shows the scene and its parts' tables")
        if engine not in ARCHIVE_ENGINES:
            raise SspError(f"{args.scene}: the {engine} engine runs a scene (.json); an SSP archive runs as "
                           f"{', '.join(ARCHIVE_ENGINES)} (parts by default)")
        result = run_archive(Path(args.scene), engine, args.step, force=args.force, **master_options(args, engine, progress))
        return report_run(args, None, result.scene, result)
    from .engines import run_scene

    scene = load_scene(args.scene, fmu_dir=args.fmu_dir)
    # Every roller the web may slip on reports its traction (the summary's "will it slip?") and where
    # the web's speed leaves it none.
    scene.record += list(dict.fromkeys(q for c in scene.parts if getattr(c, "traction", None) is not None
                                       for q in traction_columns(scene, c) if q not in scene.record))
    # Every lay-on roller reports where its nip let go (the summary's separations, a warning).
    scene.record += [(c.name, "layon.N") for c in scene.parts if getattr(c, "layon", None) is not None
                     and (c.name, "layon.N") not in scene.record]
    engine = args.engine
    if args.reference and engine == "reference":
        raise SceneError("--reference compares an engine with the reference; --engine reference is the reference itself")
    if args.force and engine != "parts":
        raise SceneError("--force runs the parts' co-simulation above its predicted stable step; it goes with --engine parts")
    from .growth import check

    growing = check(scene, args.fmu_dir)
    for warning in growing:  # before the run: a loop that grows is never silent
        print(f"webline run: warning: {warning}", flush=True)
    result = run_scene(scene, engine, args.fmu_dir, args.step, force=args.force,
                       **master_options(args, engine or "line", progress))
    return report_run(args, scene, scene.name, result, growing)


def first_sentence(text: str) -> str:
    """Up to the full stop that ends the first sentence: one before a space or the end ("0.2 m/s" and
    "N.m" keep their points)."""
    return re.split(r"[.](?:\s|$)", text, maxsplit=1)[0]


def report_run(args, scene, name, result, growing=()):
    """CSV, the summary (with the reference's errors when asked), the PNG and, with --report, the page of a
    run; `growing`: the warnings of the loops that grow, said before the run."""
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    csv_path = out / f"{name}.csv"
    result.write_csv(csv_path)
    ref = None
    if args.reference:
        from .reference import reference
        from .accuracy import errors

        ref = reference(scene, times=result.time)
        errs = errors(result, ref)
    said = summary(scene, result) if scene is not None else None
    print(said.text() if said is not None else system_summary(result))
    if ref is not None:
        worst = max(errs.items(), key=lambda kv: kv[1])
        against = (f"against the monolithic reference ({ref.info['method']}, {ref.info['wall_time']:.1f} s): "
                   f"largest error {worst[1]:.2e} of the column's range ({worst[0]}); "
                   + ", ".join(f"{k} {e:.1e}" for k, e in errs.items()))
        print(f"  {against}")
        said.findings.append(against)
    written = [str(csv_path)]
    title = f"{name}: {first_sentence(scene.description)}" if scene is not None and scene.description else None
    if not args.no_plot:
        from .plot import plot

        png = out / f"{name}.png"
        plot(result, png, title=title, reference=ref)
        written.append(str(png))
    if args.report:
        from .report import write_report

        written.append(str(write_report(out / f"{name}.html", scene, Path(args.scene), said, list(growing), result, ref, title)))
    print("wrote " + ", ".join(written))
    return 0


def cmd_check(args):
    """Describe each scene (read strictly), then linearize its line and predict the stable steps: the
    four couplings' at the start, webline's own and a plain importer's over the run's operating points."""
    from .stability import PLAIN, StabilityError, analyse, coupling_limits, operating_lines, report

    status = 0
    for path in args.scenes:
        if str(path).endswith(".ssp"):
            from .linearization import linearize
            from .ssp import read_ssp

            system = read_ssp(Path(path), Path(tempfile.mkdtemp(prefix="webline-check-")))
            print(f"{path}: {system.name}: {len(system.components)} components, step {system.step * 1e3:g} ms")
            lines = lambda system=system: [(system.start_time, linearize(system, method=args.method))]  # noqa: E731
            kind_of = lambda name, system=system: system.component(name).kind  # noqa: E731
        else:
            from .compiler import compile_scene

            scene = load_scene(path)
            chain = " -> ".join(f"{c.name} ({c.type})" for c in scene.line)
            effects = sorted({e for c in scene.spans for e in c.effects})
            print(f"{path}: {scene.name}: {chain}; effects: {', '.join(effects) or 'none'}; "
                  f"{len(scene.events)} events; step {scene.step * 1e3:g} ms, stop {scene.stop_time:g} s")
            for b in scene.branches:
                side = " -> ".join(f"{c.name} ({c.type})" for c in b.parts)
                print(f"  {b.kind} at {b.node}: " + (f"{side} -> {b.node}" if b.kind == "merge" else f"{b.node} -> {side}"))
            if args.describe_only:
                continue
            system = compile_scene(scene, args.fmu_dir, settle=False)
            lines = lambda scene=scene: operating_lines(scene, args.fmu_dir, args.method)  # noqa: E731
            kind_of = scene.part_type
        try:
            points = lines()
            limits = coupling_limits(points, (("gauss-seidel", "extrapolate"), PLAIN), kind_of)
            print(report(system, analyse(system, line=points[0][1]), limits))
        except StabilityError as e:
            print(f"  stability: {e}")
            status = 2
    return status


def bode_arg(text: str) -> tuple[str, str]:
    """--bode INPUT:OUTPUT, e.g. unwind.tau_m:entry.T."""
    if text.count(":") != 1 or not all(text.split(":")):
        raise argparse.ArgumentTypeError(f"{text!r} is not INPUT:OUTPUT (e.g. unwind.tau_m:entry.T)")
    return tuple(text.split(":"))


def cmd_linearize(args):
    """The scene's Line FMU linearized at --at: the state-space model as a .mat, the modes, the loops'
    margins, Bode plots and step responses (each a CSV and a PNG)."""
    from dataclasses import replace

    from . import margins
    from .statespace import bode, bode_plot, frequencies, linearize, report, step_plot

    scene = load_scene(args.scene, fmu_dir=args.fmu_dir)
    ss = linearize(scene, args.at, args.fmu_dir)
    for pair in (args.bode or []) + (args.step_response or []):  # every name checked before anything is written
        ss.input_index(pair[0]), ss.output_index(pair[1])
    loops = [margins.OpenLoop(ss, name) for name in args.loop or []]
    modes = ss.modes()
    print(report(ss, modes))
    out = Path(args.out)
    written = [str(ss.write_mat(args.output or out / f"{scene.name}_linear.mat"))]
    for loop in loops:
        m = loop.margins()
        print(margins.report(m))
        opened = replace(ss, A=loop.A).modes()  # L's resonances are the open loop's
        hz = np.unique(np.concatenate([frequencies(opened)] + [[c.frequency] for c in m.gain + m.phase]))
        marks = [(c.frequency, f"gain margin {c.margin:.1f} dB") for c in [m.gain_margin] if c]
        marks += [(c.frequency, f"phase margin {c.margin:.1f} deg") for c in [m.phase_margin] if c]
        written += map(str, bode_plot(hz, loop.response(hz), out / f"{scene.name}_loop_{loop.name}.png",
                                      f"{ss.scene}: loop {loop.name} broken at its torque, L(j omega), at t = {ss.time:g} s",
                                      "|L| [dB]", opened, marks))
    for i, o in args.bode or []:
        written += map(str, bode(ss, i, o, out / f"{scene.name}_bode_{i}_{o}.png", modes))
    for i, o in args.step_response or []:
        written += map(str, step_plot(ss, i, o, out / f"{scene.name}_step_{i}_{o}.png", modes))
    print("wrote " + ", ".join(written))
    return 0


def cmd_reference(args):
    from .reference import reference

    scene = load_scene(args.scene)
    ref = reference(scene, times=scene_grid(scene, args.step))
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    path = out / f"{scene.name}_reference.csv"
    ref.write_csv(path)
    print(f"{scene.name}: {ref.info['method']}, {ref.info['rhs_evaluations']} right-hand sides, {ref.info['wall_time']:.1f} s; wrote {path}")
    return 0


def cmd_convergence(args):
    from .accuracy import convergence, observed_orders

    scene = load_scene(args.scene, fmu_dir=args.fmu_dir)
    steps = [time_arg(s) for s in args.steps.split(",")]
    options = master_options(args, args.engine)
    rows, _ = convergence(scene, steps, engine=args.engine, fmu_dir=args.fmu_dir, **options)
    orders = observed_orders(rows)
    how = f"co-simulation of the parts ({options['algorithm']}, {options['coupling']})" if options else "the Line FMU"
    print(f"{scene.name}: {how} against the monolithic reference")
    print(f"  {'step':>10}{'tension error':>15}{'speed error':>13}{'order':>7}{'wall time':>11}")
    for i, r in enumerate(rows):
        order = f"{orders[i - 1]:.2f}" if i > 0 and not math.isnan(orders[i - 1]) else ""
        if r.failed:
            print(f"  {r.step * 1e3:>8g}ms   unstable: {r.failed}")
        else:
            print(f"  {r.step * 1e3:>8g}ms{r.error:>15.3e}{r.speed_error:>13.3e}{order:>7}{r.wall_time:>10.2f}s")
    return 0


def cmd_sweep(args):
    """Exit status: 0 when every point is ok (a warning is ok), 1 when some failed or were not run,
    2 when the study was refused before it ran, 130 when it was interrupted."""
    import secrets

    from .journal import Journal
    from .sampling import DesignError, design, parse_grid, parse_sample
    from .sweep import engine_name, outputs, run_sweep
    from .sweepplot import output_column
    from .usermetric import parse_metric

    out = Path(args.out)
    seed = args.seed
    if args.sample and seed is None and args.resume:
        seed = Journal.seed_of(out)
    if args.sample and seed is None:  # a study that can be repeated: say which seed it drew
        seed = secrets.randbelow(2**32)
        print(f"seed {seed} (give --seed {seed} to draw the same points)")
    try:
        points = design(parse_grid(args.grid or []), [parse_sample(s) for s in args.sample or []], args.n, seed)
    except DesignError as e:
        raise SceneError(str(e)) from None
    if args.max_failed is not None and args.max_failed < 0:
        raise SceneError(f"--max-failed {args.max_failed}: give a number of points >= 0")
    scene = load_scene(args.scene, fmu_dir=args.fmu_dir)
    column = None
    try:  # the metrics' signals and the output to plot are known before the run: refused now, not after it
        user = [parse_metric(m, scene) for m in args.metric or []]
        twice = sorted({m.name for m in user if [u.name for u in user].count(m.name) > 1})
        if twice:
            raise SceneError(f"--metric {twice[0]!r} is given twice")
        if args.plot is not None:
            column = output_column(outputs(scene, engine_name(args.engine), user), args.plot)
    except ValueError as e:
        raise SceneError(str(e)) from None
    out.parent.mkdir(parents=True, exist_ok=True)
    if args.series:
        Path(args.series).parent.mkdir(parents=True, exist_ok=True)
    table = run_sweep(args.scene, points, engine=args.engine, scheduler=args.scheduler, workers=args.workers,
                      step=args.step, fmu_dir=args.fmu_dir, progress=sys.stderr.isatty(), series=args.series,
                      envelope=args.plot is not None, out=out, resume=args.resume, max_failed=args.max_failed,
                      connect_timeout=args.connect_timeout, worker_timeout=args.worker_timeout, user=user)
    table.write(out)
    print(table.format())
    written = [str(out)] + ([str(args.series)] if args.series else [])
    if args.plot is not None:
        from .sweepplot import plot_envelope, plot_scatter

        title = Path(args.scene).stem
        band = table.info["envelope"]
        if band.points:
            written.append(str(plot_envelope(band, out.with_name(f"{out.stem}_envelope.png"), title)))
        written.append(str(plot_scatter(table, column, out.with_name(f"{out.stem}_scatter.png"), title)))
    print("wrote " + ", ".join(written))
    if table.info["stopped"] and table.info["stopped"].startswith("interrupted"):
        return 130
    return 1 if table.failed() or table.info["missing"] else 0


def cmd_scenes(args):
    """The shipped scenes copied into a folder of the user's, to run and change; a file there is kept."""
    folder = Path(args.to)
    folder.mkdir(parents=True, exist_ok=True)
    copied, kept = [], []
    for scene in sorted(installation.SCENES.glob("*.json")):
        target = folder / scene.name
        if target.exists():
            kept.append(target.name)
        else:
            shutil.copyfile(scene, target)
            copied.append(target.name)
    print(f"copied {len(copied)} scenes into {folder}: {', '.join(copied) or 'none'}"
          + (f"; kept your {', '.join(kept)}" if kept else ""))
    if copied:
        print(f"run one: webline run {folder / copied[0]}")
    return 0


def cmd_draw(args):
    """The line as an SVG, a PNG beside it and NAME.layout.json: the geometry drawn (docs/scenes.md)."""
    import json

    from matplotlib import rc_context

    from .drawing import figure, layout_dict

    scene = load_scene(args.scene)
    svg = args.output or Path(args.out) / f"{scene.name}.svg"
    if svg.suffix.lower() != ".svg":
        raise SceneError(f"-o {svg}: the drawing is an SVG; give FILE.svg (FILE.png and FILE.layout.json go beside it)")
    svg.parent.mkdir(parents=True, exist_ok=True)
    fig, layout = figure(scene)
    for warning in layout.warnings:
        print(f"webline draw: warning: {warning}", file=sys.stderr)
    png, geometry = svg.with_suffix(".png"), svg.with_name(f"{svg.stem}.layout.json")
    with rc_context({"svg.hashsalt": scene.name}):  # the same scene, the same file
        fig.savefig(svg, metadata={"Date": None})
    fig.savefig(png, dpi=150)
    geometry.write_text(json.dumps(layout_dict(layout), indent=1) + "\n", encoding="utf-8")
    print(f"{scene.name}: {len(layout.rollers)} parts, {len(layout.spans)} spans ({layout.placement} placement); "
          f"wrote {svg}, {png}, {geometry}")
    return 0


# The commands that need no FMU library of this platform.
WITHOUT_LIBRARIES = ("scenes", "reference", "draw")


def main(argv=None):
    # Raw: the version's lines (installation.describe) print as they are.
    parser = argparse.ArgumentParser(prog="webline", description="Co-simulate web lines of ConvertingSpan and Roller FMUs.",
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=installation.describe(),
                        help="webline's version, and which FMUs it uses and why")
    sub = parser.add_subparsers(dest="command", required=True)

    p = sub.add_parser("run", help="run a scene (the Line FMU by default) or an SSP archive: CSV, PNG and a summary")
    p.add_argument("scene", help="a scene (.json) or an SSP archive (.ssp)")
    add_master_options(p)
    p.add_argument("--engine", type=engine_arg, metavar="{" + ",".join(ENGINES) + "}",
                   help="line (the default for a scene): the scene as one Line FMU in FMPy, exact at any --step (where "
                        "it cannot run a scene, the monolithic reference does, and the summary says so); reference: the "
                        "monolithic SciPy reference; parts (the default for an SSP archive): webline's co-simulation of "
                        "the part FMUs (--algorithm and --coupling apply), refused above its predicted stable step; "
                        "libcosim or fmpy: the SSP archive in those (Jacobi, held inputs; a scene is exported first)")
    p.add_argument("--force", action="store_true",
                   help="parts: run above the predicted stable step anyway (the summary warns)")
    p.add_argument("--out", default=str(OUT), help="output folder (default: ./out)")
    p.add_argument("--no-plot", action="store_true")
    p.add_argument("--report", action="store_true",
                   help="also OUT/SCENE.html: one self-contained page (viewable offline) with the summary, the warnings, "
                        "a plot per quantity, the scene and the versions of webline and the FMUs")
    p.add_argument("--reference", action="store_true", help="also compute the monolithic reference and print the error")
    g = p.add_mutually_exclusive_group()
    g.add_argument("--progress", dest="progress", action="store_true", default=None, help="show a progress bar")
    g.add_argument("--no-progress", dest="progress", action="store_false")
    p.set_defaults(func=cmd_run)

    p = sub.add_parser("export", help="a scene as an SSP 1.0 archive of parts (FMUs, parameter sets, step) for libcosim, "
                                      "FMPy, ...; or with --fmu as one Line FMU")
    p.add_argument("scene")
    p.add_argument("-o", "--output", type=Path, help="the archive (default: OUT/SCENE.ssp; OUT/SCENE.fmu with --fmu)")
    p.add_argument("--fmu", action="store_true", help="the whole line as one FMU (Line.fmu), solved implicitly inside")
    p.add_argument("--fmi3", action="store_true", help="with --fmu: FMI 3.0 instead of 2.0")
    p.add_argument("--step", type=time_arg, help="the step the archive carries (default: the predicted stable step, "
                                                   "or the scene's if smaller)")
    p.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR)
    p.add_argument("--out", default=str(OUT))
    p.set_defaults(func=cmd_export)

    p = sub.add_parser("check", help="describe scenes or SSP archives; predict the line's largest stable step")
    p.add_argument("scenes", nargs="+", metavar="SCENE_OR_SSP")
    p.add_argument("--describe-only", action="store_true", help="only read the scenes strictly and describe them")
    p.add_argument("--method", choices=("auto", "derivatives", "differences"), default="auto",
                   help="Jacobians from fmi2GetDirectionalDerivative or central differences (auto: the former when the FMU provides it)")
    p.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR)
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("linearize", help="the scene's Line FMU linearized at a time: A, B, C, D with names (.mat), "
                                         "its modes and the parts that move in each, Bode plots")
    p.add_argument("scene")
    p.add_argument("--at", type=time_arg, default=0.0, help="the time to linearize at (default 0: the start)")
    p.add_argument("--bode", type=bode_arg, action="append", metavar="INPUT:OUTPUT",
                   help="a Bode plot from a Line input to a Line output, e.g. unwind.tau_m:entry.T, as a CSV (Hz, dB, deg) "
                        "and a PNG (repeat for more)")
    p.add_argument("--step-response", type=bode_arg, action="append", metavar="INPUT:OUTPUT",
                   help="the response of a Line output to a unit step of a Line input, as a CSV and a PNG (repeat for more)")
    p.add_argument("--loop", action="append", metavar="NAME",
                   help="break roller NAME's drive loop at its torque output: the loop's gain and phase margins, their "
                        "crossover frequencies, and its Bode plot (repeat for more)")
    p.add_argument("-o", "--output", type=Path, help="the model (default: OUT/SCENE_linear.mat)")
    p.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR)
    p.add_argument("--out", default=str(OUT), help="output folder (default: ./out)")
    p.set_defaults(func=cmd_linearize)

    p = sub.add_parser("reference", help="the monolithic SciPy reference of a scene, as CSV")
    p.add_argument("scene")
    p.add_argument("--step", type=time_arg)
    p.add_argument("--out", default=str(OUT))
    p.set_defaults(func=cmd_reference)

    p = sub.add_parser("convergence", help="error against the reference as the communication step shrinks")
    p.add_argument("scene")
    p.add_argument("--steps", default="2ms,1ms,0.5ms,0.25ms")
    p.add_argument("--engine", type=engine_arg, default="parts", metavar="{parts,line}",
                   help="parts (the default: the coupling's error, every step run, an unstable one reported) or line")
    p.add_argument("--algorithm", choices=ALGORITHMS, help="parts: default gauss-seidel")
    p.add_argument("--coupling", choices=COUPLINGS, help="parts: default extrapolate")
    p.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR)
    p.set_defaults(func=cmd_convergence)

    p = sub.add_parser("sweep", help="run a scene over a grid or random samples of its values, on Dask")
    p.add_argument("scene")
    p.add_argument("--grid", action="append", metavar="KEY=V1,V2,...",
                   help='a scene value and its values, e.g. "line.film.L=1 m,2 m" (repeat for more dimensions)')
    p.add_argument("--sample", action="append", metavar="KEY=DISTRIBUTION",
                   help='a scene value drawn from uniform(LOW, HIGH) or normal(MEAN, SD), e.g. '
                        '"line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)" (a Latin hypercube over all of them)')
    p.add_argument("--n", type=int, help="with --sample: how many points to draw")
    p.add_argument("--seed", type=int, help="with --sample: the seed (the same seed, the same points)")
    p.add_argument("--engine", default="line", choices=("line", "fmpy-line", "parts", "reference"),
                   help="line (default): the scene as one Line FMU, exported once per structure, a point's steps "
                        "in one call; fmpy-line: the same in FMPy's loop (the same numbers); parts: the "
                        "co-simulation of its FMUs; reference: the monolithic SciPy reference")
    p.add_argument("--scheduler", help="address of a running Dask scheduler (default: a local cluster)")
    p.add_argument("--workers", type=int, default=2, help="workers of the local cluster")
    p.add_argument("--step", type=time_arg)
    p.add_argument("--fmu-dir", type=Path, default=DEFAULT_FMU_DIR)
    p.add_argument("--out", default=str(OUT / "sweep.csv"), help="the table (default: ./out/sweep.csv)")
    p.add_argument("--series", metavar="FILE.parquet", help="also every point's recorded signals, in one Parquet file")
    p.add_argument("--plot", nargs="?", const="", metavar="OUTPUT",
                   help="PNGs next to the table: each recorded tension's band over the points, and OUTPUT "
                        "(a column of the table, default the first span's T_max) against each swept key")
    p.add_argument("--metric", action="append", metavar="NAME=FUNCTION(SIGNAL[, FROM[, TO]])",
                   help='a scalar of your own per point, e.g. "peak=max(first.T)" or "late=mean(idler.v, 2.0, 2.5)" '
                        f"(functions: {', '.join(FUNCTIONS)}; FROM, TO in s; docs/studies.md)")
    p.add_argument("--resume", action="store_true",
                   help="finish the unfinished study whose table is --out: run only its missing and failed points")
    p.add_argument("--max-failed", type=int, metavar="N", help="stop the study once more than N points have failed")
    p.add_argument("--connect-timeout", type=time_arg, default=10.0, metavar="SECONDS",
                   help="how long the --scheduler has to answer (default 10 s)")
    p.add_argument("--worker-timeout", type=time_arg, default=300.0, metavar="SECONDS",
                   help="how long a study whose workers are all gone waits for one (default 300 s)")
    p.set_defaults(func=cmd_sweep)

    p = sub.add_parser("scenes", help="copy the shipped scenes (lamination, laminator, slitter, ...) into a folder")
    p.add_argument("--to", default="scenes", help="the folder (default: ./scenes); a scene already there is kept")
    p.set_defaults(func=cmd_scenes)

    p = sub.add_parser("draw", help="draw the line to scale: an SVG, a PNG beside it and NAME.layout.json (the "
                                    "geometry drawn, in metres)",
                       description="Draws the scene's line to scale: rollers as circles of their radius, spans as the "
                                   "web's tangents labelled with name, length and web, drives, loops, brakes, nips, "
                                   "traction, load cells and dancers marked. Parts go where the scene's \"at\" puts "
                                   "them, else a left-to-right layout keeps every wrap the scene states; positions that "
                                   "contradict a wrap are refused (exit 2). docs/scenes.md, \"Drawing a line\".")
    p.add_argument("scene")
    p.add_argument("-o", "--output", type=Path, metavar="FILE.svg",
                   help="the drawing (default: OUT/SCENE.svg); FILE.png and FILE.layout.json go beside it")
    p.add_argument("--out", default=str(OUT), help="output folder (default: ./out)")
    p.set_defaults(func=cmd_draw)

    args = parser.parse_args(argv)
    try:
        if args.command not in WITHOUT_LIBRARIES:
            installation.require_platform(getattr(args, "fmu_dir", None))
        return args.func(args)
    except (SceneError, CoSimulationError, FmuError, SspError, FileNotFoundError, LineFmuError, StabilityError,
            StudyError, installation.PlatformError, Runaway) as e:
        print(f"webline: {e}", file=sys.stderr)
        return 2
    except ModuleNotFoundError as e:
        extra = installation.missing_extra(e)
        if extra is None:
            raise
        print(f"webline {args.command}: needs the {extra} extra ({e.name} is not installed): "
              f"pip install 'webline[{extra}]'", file=sys.stderr)
        return 2


if __name__ == "__main__":
    raise SystemExit(main())
