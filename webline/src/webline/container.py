"""The same line with FMPy's own tools: an FMPy container FMU, simulated by FMPy.

The container holds one ConvertingSpan or Roller component per component of
the scene, wired as the runner wires them (roller speeds to the spans,
span forces to the rollers, each span's exit strain to the next span); the
profiles (prescribed speeds, the arriving strain, motor torques) become the
container's inputs, fed by `fmpy.simulate_fmu` from tables, and the
parameters its start values. FMPy's container steps every component with the
inputs of the start of the step and then copies the outputs (Jacobi, inputs
held), so it is compared with the runner's `--algorithm jacobi --coupling
hold`, and both with the monolithic reference.

Scenes with a dancer (a carriage the runner integrates itself) or events
(which replace FMU instances) cannot be put in a container.
"""

from __future__ import annotations

import copy
import shutil
import tempfile
import time as clock
import uuid
from pathlib import Path

import numpy as np

from .fmus import DEFAULT_FMU_DIR, ROLLER_FMU, SPAN_FMU, enumeration
from .master import CoSimulation, Options, span_start_values
from .result import Result
from .scene import Dancer, Prescribed, Roller, Scene, Span


class ContainerError(ValueError):
    pass


def _variable(name, vr, type_, causality, variability, start=None, description=None):
    from fmpy.model_description import ModelVariable

    v = ModelVariable(name=name, valueReference=vr, type=type_, causality=causality, variability=variability)
    v.description = description
    if start is not None:
        v.start = start
    if causality == "output":
        v.initial = "calculated"
    elif causality == "parameter":
        v.initial = "exact"
    return v


def _literal(x):
    if isinstance(x, bool):
        return "true" if x else "false"
    return repr(x) if isinstance(x, float) else str(x)


def build_container(scene: Scene, step: float, path: Path, fmu_dir=DEFAULT_FMU_DIR):
    """Writes the container FMU; returns (input names -> profile, output names ->
    (component, quantity), Boolean parameters -> value to set at the start)."""
    from fmpy import read_model_description
    from fmpy.container_fmu import Configuration
    from fmpy.container_fmu.cli import create_container_fmu
    from fmpy.container_fmu.config import Component, Connection
    from fmpy.model_description import CoSimulation as CS, DefaultExperiment, ModelDescription

    if any(isinstance(c, Dancer) for c in scene.line) or scene.events:
        raise ContainerError(f"{scene.name}: a container holds FMUs only: scenes with a dancer or events are not supported")
    fmu_dir = Path(fmu_dir)
    files = {"span": fmu_dir / SPAN_FMU, "roller": fmu_dir / ROLLER_FMU}
    mds = {k: read_model_description(str(f)) for k, f in files.items()}
    var = {k: {v.name: v for v in md.modelVariables} for k, md in mds.items()}

    components = {}
    for c in scene.line:
        if isinstance(c, Span):
            components[c.name] = Component(name=c.name, filename=files["span"], modelDescription=mds["span"])
        elif isinstance(c, Roller) and c.has_fmu:
            components[c.name] = Component(name=c.name, filename=files["roller"], modelDescription=mds["roller"])
    kind = {n: ("span" if isinstance(scene.component(n), Span) else "roller") for n in components}

    md = ModelDescription()
    md.fmiVersion = "2.0"
    md.modelName = f"WebLine_{scene.name}"
    md.instantiationToken = "{" + str(uuid.uuid4()) + "}"
    md.description = f"The {scene.name} line as an FMPy container of ConvertingSpan and Roller FMUs"
    md.coSimulation = CS(modelIdentifier="container_fmu")
    md.coSimulation.fixedInternalStepSize = step
    md.coSimulation.canHandleVariableCommunicationStepSize = True
    md.defaultExperiment = DefaultExperiment(startTime="0", stopTime=str(scene.stop_time), stepSize=str(step))

    mappings = {}
    # The container answers value reference 0 with its time and maps value
    # reference k to the k-th variable mapping: "time" comes first.
    variables = [_variable("time", 0, "Real", "independent", "continuous")]

    def add(name, causality, variability, type_, start, targets):
        v = _variable(name, len(variables), type_, causality, variability, start)
        variables.append(v)
        mappings[v] = [(components[c], var[kind[c]][n]) for c, n in targets]
        return v

    # Parameters as start values of the container's variables.
    booleans = {}
    for c in scene.line:
        if c.name not in components:
            continue
        if isinstance(c, Span):
            values = span_start_values(c, enumeration(mds["span"], "solver"), web_library=scene.web_library)
        else:
            values = {"J": c.J, "R": c.R, "b": c.b, "omega_start": scene.initial_speed(c) / c.R}
        for pname, x in values.items():
            t = var[kind[c.name]][pname].type
            t = "Integer" if t == "Enumeration" else t  # set through fmi2SetInteger
            if t == "Boolean":
                # FMPy 0.3.32's container passes Boolean start values from its
                # configuration as false: these are set through simulate_fmu.
                add(f"{c.name}.{pname}", "parameter", "fixed", t, _literal(x), [(c.name, pname)]).start = None
                booleans[f"{c.name}.{pname}"] = bool(x)
            else:
                add(f"{c.name}.{pname}", "parameter", "fixed", t, _literal(x), [(c.name, pname)])

    # The container copies its connections once when initialization ends, in
    # connection order, so a span may be read while its other inputs still
    # hold their FMU start values (with damping the tension feeds through).
    # The spans' inputs therefore start at the line's initial values.
    for sp in scene.spans:
        up, down = scene.upstream(sp), scene.downstream(sp)
        eps_a = scene.line[0].strain.value(0.0) if sp.index == 1 else None
        start = {"web_a.v": scene.initial_speed(up), "web_b.v": scene.initial_speed(down)}
        if eps_a is not None:
            start["web_a.eps"] = eps_a
        for n, x in start.items():
            add(f"{sp.name}.{n}.start", "parameter", "fixed", "Real", _literal(x), [(sp.name, n)])

    # Inputs: profiles, each mapped to every component input it drives.
    inputs = {}
    for c in scene.line:
        if isinstance(c, Span):
            continue
        speed = scene.speed_profile(c)
        if speed is not None:
            targets = []
            before, after = scene.span_before(c), scene.span_after(c)
            if before is not None:
                targets.append((before.name, "web_b.v"))
            if after is not None:
                targets.append((after.name, "web_a.v"))
            add(f"{c.name}.v", "input", "continuous", "Real", _literal(speed.value(0.0)), targets)
            inputs[f"{c.name}.v"] = speed
        if c.name in components:
            tau = scene.torque_profile(c)
            add(f"{c.name}.tau_m", "input", "continuous", "Real", _literal(tau.value(0.0)), [(c.name, "tau_m")])
            inputs[f"{c.name}.tau_m"] = tau
    first = scene.line[1]
    strain = scene.line[0].strain
    add("source.eps", "input", "continuous", "Real", _literal(strain.value(0.0)), [(first.name, "web_a.eps")])
    inputs["source.eps"] = strain

    # Outputs: the recorded quantities the FMUs give.
    outputs = {}
    span_out = {"T": "summary_Tension", "eps": "web_b.eps", "L": "summary_Length", "F_a": "web_a.F", "F_b": "web_b.F"}
    for cname, q in scene.record:
        c = scene.component(cname)
        if isinstance(c, Span):
            n = span_out[q]
        elif cname in components and q in ("v", "omega"):
            n = q
        else:
            continue
        add(f"{cname}.{q}", "output", "continuous", "Real", None, [(cname, n)])
        outputs[f"{cname}.{q}"] = (cname, q)

    # Connections.
    connections = []

    def as_float64(v):
        # FMPy 0.3.32 writes a connection's type as the FMI 2 name ("Real"), which
        # its container binary does not read: hand it a copy typed "Float64".
        c = copy.copy(v)
        c.type = "Float64"
        return c

    def connect(src, src_var, dst, dst_var):
        connections.append(
            Connection(
                startElement=components[src],
                startConnectors=[as_float64(var[kind[src]][src_var])],
                endElement=components[dst],
                endConnectors=[as_float64(var[kind[dst]][dst_var])],
            )
        )

    for sp in scene.spans:
        up, down = scene.upstream(sp), scene.downstream(sp)
        if up.name in components:
            connect(up.name, "v", sp.name, "web_a.v")
            connect(sp.name, "web_a.F", up.name, "F_down")
        if down.name in components:
            connect(down.name, "v", sp.name, "web_b.v")
            connect(sp.name, "web_b.F", down.name, "F_up")
        if sp.index > 1:
            connect(scene.line[sp.index - 2].name, "web_b.eps", sp.name, "web_a.eps")

    md.modelVariables = variables
    config = Configuration(
        parallelDoStep=False,
        modelDescription=md,
        components=list(components.values()),
        connections=connections,
        variableMappings=mappings,
    )
    work = Path(tempfile.mkdtemp(prefix="webline-container-"))
    try:
        create_container_fmu(config, work, Path(path))
    finally:
        shutil.rmtree(work, ignore_errors=True)
    return inputs, outputs, booleans


def simulate_container(scene: Scene, step: float, fmu_dir=DEFAULT_FMU_DIR, path=None) -> Result:
    """Builds the container and simulates it with `fmpy.simulate_fmu`."""
    from fmpy import simulate_fmu

    start = clock.perf_counter()
    path = Path(path or tempfile.mkdtemp(prefix="webline-") + f"/{scene.name}_container.fmu")
    inputs, outputs, booleans = build_container(scene, step, path, fmu_dir)
    times, _ = CoSimulation.grid_of(scene, step)
    if len(set(np.round(np.diff(times) / step, 9))) > 1:
        raise ContainerError(f"{scene.name}: the container steps with a fixed step; a breakpoint is not on the {step} s grid")
    # Input tables: FMPy holds each input at its value at the start of a step.
    names = list(inputs)
    table = np.array(
        [tuple([t] + [inputs[n].value(t) for n in names]) for t in times],
        dtype=[("time", float)] + [(n, float) for n in names],
    )
    res = simulate_fmu(
        str(path),
        stop_time=scene.stop_time,
        output_interval=step,
        input=table,
        output=list(outputs),
        start_values=booleans,
        validate=False,
    )
    cols = [c for c in scene.columns() if c.split(" [")[0] in outputs]
    data = np.column_stack([res[c.split(" [")[0]] for c in cols])
    return Result(
        scene=scene.name,
        columns=cols,
        time=np.asarray(res["time"], dtype=float),
        data=data,
        info={"method": "FMPy container FMU (Jacobi, inputs held)", "step": step, "wall_time": clock.perf_counter() - start, "path": str(path)},
    )


def compare_container(scene: Scene, step=None, fmu_dir=DEFAULT_FMU_DIR, out=None):
    """Container vs runner (Jacobi, hold) vs reference: a printable report."""
    from .reference import reference
    from .study import errors

    h = step or scene.step
    fmu_path = (Path(out) / f"{scene.name}_container.fmu") if out else None
    if fmu_path:
        fmu_path.parent.mkdir(parents=True, exist_ok=True)
    cont = simulate_container(scene, h, fmu_dir, fmu_path)
    runner = CoSimulation(scene, Options(step=h, algorithm="jacobi", coupling="hold", fmu_dir=fmu_dir)).run()
    keys = [k for k in cont.keys()]
    diff = {k: float(np.max(np.abs(cont.column(k) - runner.column(k)))) / (float(np.max(np.abs(runner.column(k)))) or 1.0) for k in keys}
    ref = reference(scene, times=runner.time)
    e_cont = errors(cont, ref)
    e_run = errors(runner, ref)
    lines = [
        f"{scene.name}: FMPy container FMU ({cont.info['path']}) at a {h * 1e3:g} ms step, {cont.info['wall_time']:.2f} s",
        f"  container vs runner (jacobi, hold): largest difference {max(diff.values()):.2e} of the column's range",
        f"  container vs monolithic reference:  largest error {max(e_cont.values()):.2e}",
        f"  runner (jacobi, hold) vs reference:  largest error {max(e_run.values()):.2e}",
    ]
    return "\n".join(lines)
