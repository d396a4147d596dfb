"""The engines that run a line, by one set of names (`webline run`, `convergence`, `sweep`):

- `line`: the scene as one Line FMU in FMPy, exact at any step (the default; `fmpy-line` is its old name);
  where the Line FMU cannot run a scene, the monolithic reference runs it and the result says so;
- `reference`: the monolithic SciPy reference (`reference.py`);
- `parts`: webline's co-simulation of the part FMUs (`master.py`), refused above its coupling's
  predicted stable step unless forced (`stability.refuse_unstable`); an SSP archive runs as parts;
- `libcosim`, `fmpy`: an SSP archive (a scene exported to one first) in DNV's libcosim or FMPy's
  simulate_ssp, both Jacobi with held inputs at a fixed step.

Every engine's Result names its columns as the scene does ("span.T [N]", "roller.v [m/s]"), an SSP
archive's too (`scene_columns`). `run_libcosim` and `run_fmpy` return the values after each step, on
the communication points start + k*h, k = 1..n.
"""

from __future__ import annotations

import tempfile
import time as clock
from unittest import mock
from pathlib import Path

import numpy as np

from . import names
from .bound import check_result
from .fmus import DEFAULT_FMU_DIR, ROLLER_FMU, SPAN_FMU, identity
from .names import ARCHIVE_ENGINES, DEFAULT, engine_name
from .result import Result
from .scene import SceneError
from .scene.types import profiles_of
from .ssp import SSD, SspError, _variables
from .system import System


def refuse_traction(scene):
    """A web that may slip is refused by the parts' co-simulation and its SSP: while it sticks, friction
    holds the web on its wrap so stiffly that explicit coupling is stable only at steps of some ten
    microseconds (`webline check` predicts them), which change as it sticks and slides."""
    slips = [c for c in scene.nodes if getattr(c, "traction", None) is not None]
    if slips:
        c = slips[0]
        raise SceneError(f"{c.where}: {c.type} {c.name!r} has traction: explicit coupling of parts follows a web that "
                         "may slip only at steps of some ten microseconds (see `webline check`), so the parts' "
                         "co-simulation and its SSP export refuse it; run the scene as one Line FMU (webline run's "
                         "default engine) or with --engine reference")


def refuse_loops(scene):
    """A drive's loop reads a span's tension as an input the line wires inside its equations; the
    parts' co-simulation and its SSP export do not wire it (nor predict its stable step)."""
    looped = [c for c in scene.nodes if getattr(getattr(c, "drive", None), "loop", None) is not None]
    if looped:
        c = looped[0]
        raise SceneError(f"{c.where}: {c.type} {c.name!r} has a loop in its drive (\"pi\"): the parts' co-simulation and "
                         "its SSP export do not wire what a loop measures; run the scene as one Line FMU (webline run's "
                         "default engine) or with --engine reference")


def refuse_slack_laminates(scene):
    """A laminate with preventNegativeTension is slack only as a whole, when the sum of its layers'
    tensions is (docs/merge-split.md, [M6]): the parts' co-simulation steps each layer in an FMU of its
    own, which cannot clamp on a sum it does not see."""
    slack = [sp for sp in scene.spans if sp.layered and "preventNegativeTension" in sp.effects]
    if slack:
        sp = slack[0]
        raise SceneError(f"{sp.where}: span {sp.name!r} is a laminate with preventNegativeTension, which goes slack only "
                         "as a whole (when the sum of its layers' tensions is not positive): the parts' co-simulation and "
                         "its SSP export step each layer in an FMU of its own and cannot clamp on that sum; run the scene "
                         "as one Line FMU (webline run's default engine) or with --engine reference")


ONE_LINE = "run the scene as one Line FMU (webline run's default engine) or with --engine reference"


def refuse_first(parts, why: str):
    """The first of `parts` refused by name: `why` the parts' co-simulation and its SSP export do not run it."""
    if parts:
        c = parts[0]
        raise SceneError(f"{c.where}: {c.type} {c.name!r} {why}; {ONE_LINE}")


def refuse_runout(scene):
    """A roll with runout [R15] moves its span's length with its angle; the parts' co-simulation and its
    SSP export are not checked against the reference for it (nor is its stable step predicted)."""
    refuse_first([c for c in scene.nodes if getattr(c, "runout", None) is not None],
                 "has runout: the parts' co-simulation and its SSP export do not run a roll with runout")


def refuse_layon(scene):
    """A lay-on roller [R18] presses on its winder through a stiff nip that lets go; the parts' co-simulation and
    its SSP export do not run it (the Roller's co-simulation step is not checked against the reference for it)."""
    refuse_first([c for c in scene.nodes if getattr(c, "layon", None) is not None],
                 "has a lay-on roller (layon): the parts' co-simulation and its SSP export do not run it")


def refuse_stepwise(scene):
    """A stepwise radius [R17] moves the radius the web meets by a layer within a few degrees of a turn; the
    Roller FMU's co-simulation step holds the radius over a piece, so it refuses it (docs/physics.md)."""
    refuse_first([c for c in scene.nodes if getattr(getattr(c, "wound", None), "merge", 0.0)],
                 "has a stepwise radius (wound.stepwise): the Roller FMU's co-simulation step holds its radius over a "
                 "piece, so the parts' co-simulation and its SSP export refuse it")


def refuse_scurves(scene):
    """An S-curve's jerk phases are quadratic pieces; the Roller FMU's co-simulation step takes a table as
    linear over a piece, and the master passes a profile's value and slope at a step's start."""
    for c in scene.parts:
        for p in profiles_of(c):
            if p.is_curved():
                raise SceneError(f"{c.where}: {c.type} {c.name!r} has an S-curve profile (\"scurve\"): the parts' co-simulation "
                                 "and its SSP export take profiles as linear within a step; run the scene as one Line FMU "
                                 "(webline run's default engine) or with --engine reference")


def refuse_for_parts(scene):
    """What a line of part FMUs cannot run (the parts' co-simulation and its SSP export): a web that may
    slip, a drive's loop, a laminate that may go slack, a roll with runout, a lay-on roller, a stepwise radius,
    an S-curve."""
    refuse_layon(scene)
    refuse_runout(scene)
    refuse_traction(scene)
    refuse_loops(scene)
    refuse_slack_laminates(scene)
    refuse_stepwise(scene)
    refuse_scurves(scene)


def run_scene(scene, engine: str | None = None, fmu_dir=None, step: float | None = None, force: bool = False,
              **options) -> Result:
    """A scene run by an engine (None: `line`, or `reference` where the Line FMU cannot run it), its
    columns as the scene names them. info["engine"] says which ran, info["warnings"] what the user must
    see. `options`: the parts' master options (algorithm, coupling, rollback, progress)."""
    engine = engine_name(engine or DEFAULT)
    warnings = []
    used = []  # the FMUs that ran, by identity (fmus.identity)
    if engine == "line":
        from . import linefmu
        from .compiler import TooManyWebs
        from .linefmu import LineFmuError

        try:
            with tempfile.TemporaryDirectory(prefix="webline-line-") as tmp:
                path = linefmu.export(scene, Path(tmp) / f"{scene.name}.fmu", fmu_dir)
                result = linefmu.simulate(scene, path, step)
                used = [identity(path)]
        except (LineFmuError, TooManyWebs) as e:
            if isinstance(e, LineFmuError) and not e.cannot_export:
                raise
            warnings.append(f"the Line FMU cannot run this scene ({e}): the monolithic reference ran it")
            engine = "reference"
        else:
            warnings += [f"the Line FMU: {m}" for m in result.info["messages"].warnings]
    if engine == "reference":
        from .master import scene_grid
        from .reference import reference

        result = reference(scene, times=scene_grid(scene, step))
        result.info["step"] = step or scene.step
    elif engine == "parts":
        from .compiler import run_scene as run_parts

        refuse_for_parts(scene)
        from .stability import operating_lines

        warnings += check_step(lambda: operating_lines(scene, fmu_dir), scene.name, step or scene.step, force,
                               scene.part_type, **options)
        result = run_parts(scene, fmu_dir=fmu_dir, step=step, **options)
    elif engine in ("libcosim", "fmpy"):
        from .compiler import compile_scene
        from .ssp import write_ssp
        from .stability import export_step

        refuse_for_parts(scene)
        with tempfile.TemporaryDirectory(prefix="webline-ssp-") as tmp:
            system = compile_scene(scene, fmu_dir)
            system.step = export_step(system)
            result = run_archive(write_ssp(system, Path(tmp) / f"{scene.name}.ssp"), engine, step, Path(tmp))
        result.scene = scene.name
    if engine in ("parts", "libcosim", "fmpy"):
        used = [identity(Path(fmu_dir or DEFAULT_FMU_DIR) / name) for name in (SPAN_FMU, ROLLER_FMU)]
    result.info["engine"] = engine
    result.info["warnings"] = warnings + result.info.get("warnings", [])
    result.info["fmus"] = used
    check_result(scene, result)  # the engines webline does not step: their recorded tensions
    return result


def check_step(lines, name: str, step: float, force: bool, kind_of, algorithm="gauss-seidel", coupling="extrapolate",
               **_) -> list[str]:
    """Before the parts run: their coupling's limit over the run (`lines()`: the line linearized at its
    operating points), refused above it (stability.UnstableStep); forced, a warning for the summary."""
    from .stability import refuse_unstable

    if force:
        return [f"forced: a step of {step * 1e3:g} ms was not checked against the stable step of the {algorithm}/"
                f"{coupling} coupling; the run may be wrong (`webline check` predicts that step)"]
    refuse_unstable(lines(), name, step, algorithm, coupling, kind_of)
    return []


def run_archive(archive: Path, engine: str = "parts", step: float | None = None, workdir=None, force=False,
                **options) -> Result:
    """An SSP archive run by `parts` (webline's master; `options` are its own; refused above the
    coupling's stable step at the start unless `force`), `libcosim` or `fmpy`."""
    from .master import run_system
    from .ssp import read_ssp

    engine = engine_name(engine)
    if engine not in ARCHIVE_ENGINES:
        raise SspError(f"{archive}: the {engine} engine runs a scene (.json), not an SSP archive "
                       f"(engines for an archive: {', '.join(ARCHIVE_ENGINES)})")
    with tempfile.TemporaryDirectory(prefix="webline-ssp-") as tmp:
        folder = Path(workdir or tmp) / "extracted"
        system = read_ssp(archive, folder)
        if engine == "libcosim":
            result = run_libcosim(folder, system, step)
        elif engine == "fmpy":
            result = run_fmpy(archive, system, step)
        else:
            from .linearization import linearize

            warnings = check_step(lambda: [(system.start_time, linearize(system))], system.name, step or system.step,
                                  force, lambda name: system.component(name).kind, **options)
            result = run_system(system, step=step, **options)
            result.info["warnings"] = warnings
    result.info["engine"] = engine
    return result


def scene_columns(system: System) -> list[str]:
    """The recorded variables of a System (an archive's) named as a scene names them (`names.scene_columns`)."""
    return names.scene_columns(system, {c.name: _variables(Path(c.fmu))[1] for c in system.components})


def steps_of(system: System, step: float | None) -> tuple[float, int]:
    h = step or system.step
    n = int(round((system.stop_time - system.start_time) / h))
    return h, n


def run_libcosim(ssd_dir: Path, system: System, step: float | None = None) -> Result:
    """libcosim on an extracted archive (read_ssp's target folder: libcosim never unpacks an untrusted zip)."""
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    h, n = steps_of(system, step)
    ns = int(round(h * 1e9))  # libcosim counts time in nanoseconds
    if abs(ns - h * 1e9) > 1e-6 * h * 1e9:
        raise SspError(f"{system.name}: step {h} s is not a whole number of nanoseconds (libcosim's time unit)")
    log_output_level(CosimLogLevel.ERROR)
    t0 = clock.perf_counter()
    try:
        execution = CosimExecution.from_ssp_file(str(Path(ssd_dir)), step_size=ns)
    except AssertionError:
        raise SspError(f"{ssd_dir}: libcosim could not load {SSD} (see its log above)") from None
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    reads, order = [], []  # (slave index, value references) per component; the record's order of the values read
    for comp in dict.fromkeys(c for c, _ in system.record):
        index = execution.slave_index_from_instance_name(comp)
        vr = {v.name.decode(): v.reference for v in execution.slave_variables(index)}
        picked = [i for i, (c, _) in enumerate(system.record) if c == comp]
        reads.append((index, [vr[system.record[i][1]] for i in picked]))
        order += picked
    columns = scene_columns(system)
    rows = np.empty((n, len(system.record)))
    for k in range(n):
        if not execution.step():
            raise SspError(f"{system.name}: libcosim failed at step {k} (t = {system.start_time + k * h} s)")
        rows[k, order] = [x for index, vrs in reads for x in observer.last_real_values(index, vrs)]
    wall = clock.perf_counter() - t0
    times = system.start_time + h * np.arange(1, n + 1)
    return Result(scene=system.name, columns=columns, time=times, data=system.combine(rows),
                  info={"method": f"libcosim, fixed step {h * 1e3:g} ms", "step": h, "steps": n, "wall_time": wall})


def fmpy_parameter_set(archive: Path, system_root=None):
    """The archive's own parameter sets as one FMPy ParameterSet: names prefixed with the component,
    Boolean literals converted (FMPy sets a Boolean as `value != 0.0`, so the text 'false' would be True)."""
    from fmpy.ssp.ssd import ParameterSet, read_ssd, read_ssv

    ssd = read_ssd(str(archive))
    merged = ParameterSet(name="start values")
    for comp in ssd.system.elements:
        for binding in comp.parameterBindings:
            sets = [read_ssv(str(archive), resource=binding.source)] if binding.source else binding.parameterValues
            for ps in sets:
                for p in ps.parameters:
                    if p.type in ("String", "Enumeration", "Binary"):
                        raise SspError(f"{archive}: {comp.name}.{p.name}: FMPy's SSP simulation cannot set a {p.type}")
                    if p.type == "Boolean":
                        p.value = {"true": 1.0, "false": 0.0, "1": 1.0, "0": 0.0}[p.value.strip()]
                    p.name = f"{comp.name}.{p.name}"
                    merged.parameters.append(p)
    return merged


def _fmpy_set_parameters(component, parameter_set):
    """FMPy's `set_parameters` (fmpy.ssp.simulation, 0.3.x) with one fix: a parameter belongs to a
    component when its name starts with the component's path *and a dot*. FMPy tests the path alone,
    so component `film` takes `film_unwind.J` as its variable `unwind.J` and fails (a KeyError); the
    laminator's and the slitter's names (film/film_unwind, lane_c/lane_c2) do this. Otherwise the same."""
    from fmpy.ssp.simulation import set_value

    path, parent = component.name, component.parent
    while parent.parent is not None:
        path = parent.name + "." + path
        parent = parent.parent
    for parameter in parameter_set.parameters:
        if parameter.name.startswith(path + "."):
            set_value(component, parameter.name[len(path) + 1:], parameter.value)


def run_fmpy(archive: Path, system: System, step: float | None = None) -> Result:
    """FMPy's simulate_ssp on a (checked) archive. FMPy labels its rows t but they hold the values at t + h,
    and its first step uses 0.0 for every connected input; the times here are the true ones
    (master.Options.fmpy() reproduces this run)."""
    from fmpy.ssp.simulation import simulate_ssp

    h, n = steps_of(system, step)
    t0 = clock.perf_counter()
    # As a user calls it: FMPy adds h to its time while time < stop (n or n + 1 steps).
    # FMPy's own prefix test of parameter names mistakes `film_unwind.J` for component `film`'s: its fix.
    with mock.patch("fmpy.ssp.simulation.set_parameters", _fmpy_set_parameters):
        out = simulate_ssp(str(archive), start_time=system.start_time, stop_time=system.stop_time,
                           step_size=h, parameter_set=fmpy_parameter_set(archive))
    wall = clock.perf_counter() - t0
    keys = [f"{c}.{v}" for c, v in system.record]
    missing = [k for k in keys if k not in out.dtype.names]
    if missing:
        raise SspError(f"{archive}: FMPy recorded no {', '.join(missing)} (it records connectors only)")
    data = system.combine(np.column_stack([out[k].astype(float) for k in keys]))
    return Result(scene=system.name, columns=scene_columns(system), time=out["time"] + h, data=data,
                  info={"method": f"FMPy simulate_ssp, fixed step {h * 1e3:g} ms", "step": h, "steps": len(out), "wall_time": wall})



def relative_difference(a: Result, b: Result) -> dict:
    """Per recorded column, the largest difference of `a` from `b` at their common communication points,
    relative to the column's largest magnitude in `b` (so a strain of 1e-4 and a tension of 300 N compare alike)."""
    h = b.info.get("step") or a.info.get("step")
    ia, ib = [], []
    j = 0
    for i, t in enumerate(a.time):  # both grids sorted: a merge on times equal to within 1e-6 h
        while j < len(b.time) and b.time[j] < t - 1e-6 * h:
            j += 1
        if j < len(b.time) and abs(b.time[j] - t) <= 1e-6 * h:
            ia.append(i)
            ib.append(j)
    if len(ia) < 2:
        raise ValueError(f"{a.scene}: the two runs share no communication points")
    out = {}
    for key in b.keys():
        xa, xb = a.column(key)[ia], b.column(key)[ib]
        out[key] = float(np.max(np.abs(xa - xb)) / (np.max(np.abs(xb)) or 1.0))
    return out


def agreement(scene_path, fmu_dir, workdir: Path, stop_time: float | None = None) -> dict:
    """A shipped scene exported (at the step the export predicts) and run by libcosim and FMPy, each against
    webline's master on the same coupling (libcosim: Options.engine(); FMPy: Options.fmpy()) and against the
    monolithic reference. `stop_time` shortens the exported run. Returns the largest relative differences
    over the recorded columns (docs/ssp.md, tests)."""
    from .master import Master, Options
    from .reference import reference
    from .scene import load_scene
    from .ssp import read_ssp, write_ssp
    from .stability import export_step
    from .accuracy import errors
    from .compiler import compile_scene

    scene = load_scene(scene_path, fmu_dir=fmu_dir)
    if stop_time is not None:
        scene.stop_time = stop_time
    refuse_for_parts(scene)
    exported = compile_scene(scene, fmu_dir)
    exported.step = export_step(exported)
    archive = write_ssp(exported, Path(workdir) / f"{scene.name}.ssp")
    system = read_ssp(archive, Path(workdir) / scene.name)
    runs = {
        "libcosim": run_libcosim(Path(workdir) / scene.name, system),
        "fmpy": run_fmpy(archive, system),
        "webline_engine": Master(system, Options.engine()).run(),
        "webline_fmpy": Master(system, Options.fmpy()).run(),
    }
    ref = reference(scene, times=runs["webline_engine"].time)

    def versus_reference(result):  # every engine names its columns as the scene does
        within = result.time <= ref.time[-1] + 1e-6 * system.step  # FMPy may step once past the stop time
        trimmed = Result(result.scene, result.columns, result.time[within], result.data[within], result.info)
        return max(errors(trimmed, ref).values())

    return {
        "scene": scene.name,
        "step": system.step,
        "steps": runs["libcosim"].info["steps"],
        "libcosim_vs_webline": max(relative_difference(runs["libcosim"], runs["webline_engine"]).values()),
        "fmpy_vs_webline": max(relative_difference(runs["fmpy"], runs["webline_fmpy"]).values()),
        "libcosim_vs_reference": versus_reference(runs["libcosim"]),
        "fmpy_vs_reference": versus_reference(runs["fmpy"]),
        "webline_vs_reference": versus_reference(runs["webline_engine"]),
        "wall_time": {k: r.info["wall_time"] for k, r in runs.items()},
    }
