"""A line linearized at its start: A, B, C, D of each component from its FMU in Model Exchange.

Every component is instantiated in Model Exchange (FMPy's `FMU2Model`) with
its start values; connected inputs are then set from the outputs that feed
them until nothing changes (the operating point every engine starts from).
Each FMU gives its Jacobians with `fmi2GetDirectionalDerivative` when it
provides them, else by central differences of `fmi2GetDerivatives` and of its
outputs; `linearize(..., method=...)` forces either (the test compares them).
"""

from __future__ import annotations

import json
import shutil
import tempfile
from ctypes import c_double
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import FMU2Model

from .linear import Block, Line, StabilityError

METHODS = ("auto", "derivatives", "differences")
# Central differences: a step of 1e-6 of a variable's size (its value, at least its nominal)
# balances truncation (relative 1e-12) against rounding (1e-16/1e-6 = 1e-10).
RELATIVE_STEP = 1e-6


class ModelInstance:
    """One component in Model Exchange, initialized and in continuous-time mode."""

    def __init__(self, component, start_time: float, workdir: Path):
        self.name = component.name
        path = str(component.fmu)
        self.md = read_model_description(path)
        if self.md.modelExchange is None:
            raise StabilityError(
                f"{component.name}: {Path(path).name} has no Model Exchange interface: `webline check` linearizes "
                "the line through Model Exchange"
            )
        self.vars = {v.name: v for v in self.md.modelVariables}
        unzip = extract(path, unzipdir=tempfile.mkdtemp(prefix=f"check-{component.name}-", dir=workdir))
        self.fmu = FMU2Model(guid=self.md.guid, unzipDirectory=unzip,
                             modelIdentifier=self.md.modelExchange.modelIdentifier, instanceName=component.name)
        self.messages: list[str] = []
        self.fmu.instantiate(loggingOn=False)
        start, self.notes = model_exchange_start(component)
        if getattr(component, "profile", None) is not None and "profile" in self.vars:
            profile = Path(workdir) / f"{component.name}.profile.json"
            profile.write_text(json.dumps(component.profile))
            start["profile"] = str(profile)
        self._call("fmi2SetupExperiment", lambda: self.fmu.setupExperiment(startTime=start_time))
        self._set_start(start)
        self._call("fmi2EnterInitializationMode", self.fmu.enterInitializationMode)
        self._call("fmi2ExitInitializationMode", self.fmu.exitInitializationMode)
        while self.fmu.newDiscreteStates()[0]:
            pass
        self.fmu.enterContinuousTimeMode()
        self.n = self.md.numberOfContinuousStates
        self.state_vars = [d.variable.derivative for d in self.md.derivatives]
        self.derivative_vrs = [d.variable.valueReference for d in self.md.derivatives]

    def _call(self, what, f):
        try:
            return f()
        except FMICallException as e:
            raise StabilityError(f"{self.name}: {what} failed in Model Exchange (status {e.status})") from None

    def _set_start(self, start: dict):
        for name, value in start.items():
            v = self.vars.get(name)
            if v is None:
                raise StabilityError(f"{self.name}: the FMU has no variable {name!r}")
            if v.type == "Real":
                self._call(f"setting {name}", lambda: self.fmu.setReal([v.valueReference], [float(value)]))
            elif v.type == "Boolean":
                self._call(f"setting {name}", lambda: self.fmu.setBoolean([v.valueReference], [bool(value)]))
            elif v.type == "String":
                self._call(f"setting {name}", lambda: self.fmu.setString([v.valueReference], [str(value)]))
            else:
                self._call(f"setting {name}", lambda: self.fmu.setInteger([v.valueReference], [int(value)]))

    def vr(self, name):
        return self.vars[name].valueReference

    def get(self, names):
        return self.fmu.getReal([self.vr(n) for n in names]) if names else []

    def set(self, names, values):
        if names:
            self._call("fmi2SetReal", lambda: self.fmu.setReal([self.vr(n) for n in names], list(values)))

    def states(self):
        x = (c_double * self.n)()
        self.fmu.getContinuousStates(x, self.n)
        return np.array(x[:])

    def set_states(self, x):
        self._call("fmi2SetContinuousStates", lambda: self.fmu.setContinuousStates((c_double * self.n)(*x), self.n))

    def derivatives(self):
        dx = (c_double * self.n)()
        self._call("fmi2GetDerivatives", lambda: self.fmu.getDerivatives(dx, self.n))
        return np.array(dx[:])

    def provides_directional_derivative(self):
        return bool(self.md.modelExchange.providesDirectionalDerivative)

    def jacobians_by_derivatives(self, inputs, outputs):
        """[A B; C D] with fmi2GetDirectionalDerivative (`directional_jacobian`)."""
        known = [v.valueReference for v in self.state_vars] + [self.vr(u) for u in inputs]
        unknown = self.derivative_vrs + [self.vr(y) for y in outputs]
        return self._call("fmi2GetDirectionalDerivative", lambda: directional_jacobian(self.fmu, unknown, known))

    def jacobians_by_differences(self, inputs, outputs):
        """[A B; C D] by central differences of the derivatives and outputs."""
        x0 = self.states()
        u0 = np.array(self.get(inputs), dtype=float)
        nominal = [float(v.nominal or 1.0) if v.nominal is not None else 1.0 for v in self.state_vars]

        def f():
            return np.concatenate([self.derivatives(), np.array(self.get(outputs), dtype=float)])

        cols = []
        for j in range(self.n):
            d = RELATIVE_STEP * max(abs(x0[j]), nominal[j])
            x = x0.copy()
            x[j] = x0[j] + d
            self.set_states(x)
            fp = f()
            x[j] = x0[j] - d
            self.set_states(x)
            fm = f()
            cols.append((fp - fm) / (2 * d))
        self.set_states(x0)
        for j, name in enumerate(inputs):
            nom = self.vars[name].nominal
            d = RELATIVE_STEP * max(abs(u0[j]), float(nom) if nom else 1.0)
            self.set([name], [u0[j] + d])
            fp = f()
            self.set([name], [u0[j] - d])
            fm = f()
            self.set([name], [u0[j]])
            cols.append((fp - fm) / (2 * d))
        return np.array(cols).T if cols else np.zeros((self.n + len(outputs), 0))

    def free(self):
        try:
            self.fmu.terminate()
        except FMICallException:
            pass
        self.fmu.freeInstance()


def directional_jacobian(fmu, unknowns: list, knowns: list) -> np.ndarray:
    """d unknowns / d knowns (value references) of an FMI 2.0 instance, column by column with
    fmi2GetDirectionalDerivative (seed: one known at a time)."""
    J = np.zeros((len(unknowns), len(knowns)))
    for c, known in enumerate(knowns):
        J[:, c] = fmu.getDirectionalDerivative(unknowns, [known], [1.0])
    return J


def model_exchange_start(component):
    """The component's start values for Model Exchange, and notes on what had to change.

    The span refuses, in Model Exchange, effects that need input rates:
    includeMass (dv_b/dt) and includeDamping with variableLength (dL/dt). The
    line is linearized without them, and the notes say so."""
    start = dict(component.start)
    notes = []
    if component.kind == "span":
        if start.get("includeMass"):
            start["includeMass"] = False
            notes.append(f"{component.name}: linearized without includeMass (the web's inertia; Model Exchange gives no dv_b/dt)")
        if start.get("includeDamping") and start.get("variableLength"):
            start["includeDamping"] = False
            notes.append(f"{component.name}: linearized without includeDamping (with variableLength it needs dL/dt)")
    if start.get("loop.sample"):  # held in Model Exchange, a sampled loop's torque would not feed back at all
        start["loop.sample"], start["loop.delay"] = 0.0, 0.0
        notes.append(f"{component.name}: its sampled loop linearized continuous (the hold's lag, T/2 + delay, left out)")
    return start, notes


def interpolates(component, md) -> bool:
    """Whether the master gives this component input derivatives: it can interpolate inputs,
    and (the span) its solver is not `exact`, which holds inputs."""
    if md.coSimulation is None or not md.coSimulation.canInterpolateInputs:
        return False
    solver = next((v for v in md.modelVariables if v.name == "solver"), None)
    if solver is not None and solver.declaredType is not None and "solver" in component.start:
        exact = {i.name: int(i.value) for i in solver.declaredType.items}.get("exact")
        return int(component.start["solver"]) != exact
    return True


def linearize(system, method: str = "auto", settle_passes: int | None = None) -> Line:
    """The Line of `system` at its start time."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS}")
    names = [c.name for c in system.components]
    index = {n: i for i, n in enumerate(names)}
    inputs = {n: [] for n in names}
    outputs = {n: [] for n in names}
    for conn in system.connections:
        inputs[conn.target[0]].append(conn)
        if conn.source[1] not in outputs[conn.source[0]]:
            outputs[conn.source[0]].append(conn.source[1])
    workdir = Path(tempfile.mkdtemp(prefix="webline-check-"))
    insts: list[ModelInstance] = []
    try:
        for c in system.components:
            insts.append(ModelInstance(c, system.start_time, workdir))
        # The operating point: connected inputs from the outputs feeding them, to a fixed point
        # (feedthrough chains, such as the strain from span to span, need one pass per link).
        for _ in range(settle_passes or len(insts) + 1):
            changed = False
            for conn in system.connections:
                src, dst = insts[index[conn.source[0]]], insts[index[conn.target[0]]]
                y = src.get([conn.source[1]])[0]
                if dst.get([conn.target[1]])[0] != y:
                    dst.set([conn.target[1]], [y])
                    changed = True
            if not changed:
                break
        blocks, sources = [], []
        for c, inst in zip(system.components, insts):
            ins = [conn.target[1] for conn in inputs[c.name]]
            outs = outputs[c.name]
            use = method
            if method == "auto":
                use = "derivatives" if inst.provides_directional_derivative() else "differences"
            J = inst.jacobians_by_derivatives(ins, outs) if use == "derivatives" else inst.jacobians_by_differences(ins, outs)
            n = inst.n
            states = [v.name for v in inst.state_vars]
            # A roll's radius is held: it moves over the roll's life, and its slow drift (an unwinder
            # turns faster as it empties, a mode growing at h*v/(2*pi*r^2)) is the line's, not the coupling's.
            keep = [i for i, name in enumerate(states) if not (c.kind == "roller" and name == "r")]
            rows = keep + list(range(n, J.shape[0]))
            cols = keep + list(range(n, J.shape[1]))
            J = J[np.ix_(rows, cols)]
            n = len(keep)
            blocks.append(Block(
                name=c.name, A=J[:n, :n], B=J[:n, n:], C=J[n:, :n], D=J[n:, n:],
                states=[states[i] for i in keep], inputs=ins, outputs=outs,
                interpolates=interpolates(c, inst.md), method=use,
            ))
            sources.append([(index[conn.source[0]], outputs[conn.source[0]].index(conn.source[1])) for conn in inputs[c.name]])
        return Line(blocks, sources, notes=[n for inst in insts for n in inst.notes])
    finally:
        for inst in insts:
            inst.free()
        shutil.rmtree(workdir, ignore_errors=True)
