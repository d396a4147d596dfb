"""The co-simulation master: one FMU instance per component of a scene.

Every communication step [t, t+h]:

1. Rollers (Roller FMU) and dancer carriages step first: they have no
   direct feedthrough, and take the spans' forces at t — held (`hold`), or
   extrapolated linearly to the middle of the step from the last two
   communication points (`extrapolate`, the default; the Roller holds its
   inputs, so the midpoint value is what a held input can do best).
2. Spans step next, in line order. With Gauss–Seidel (the default) they see
   the rollers' speeds and the upstream span's strain at t+h: the span FMU
   accepts input derivatives, so it gets the value at t and the slope to
   t+h (`extrapolate`: the inputs move linearly over the step), or the new
   value held (`hold`). With Jacobi every span sees values at t only
   (`extrapolate`: value and slope extrapolated from the last two points).
3. Profiles (source speeds, torques, tensions, loads) are known functions
   of time: `extrapolate` gives each FMU the exact start value and slope
   (spans) or the exact average over the step (rollers); `hold` holds the
   value at t, as a plain importer would.

Communication points fall on every profile breakpoint and event, and the
extrapolation history starts afresh there. Before a step the master saves
every FMU's state; if an FMU discards the step (fmi2Discard), all FMUs are
rolled back and the step is retried as two half steps.

Events change fixed parameters (a splice: new web properties, a new roll):
the component's FMU instance is replaced by a new one, started from the old
one's state (the span's strain; the roller's surface speed).
"""

from __future__ import annotations

import math
import time as clock
from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import expm

from .fmus import DEFAULT_FMU_DIR, ROLLER_FMU, SPAN_FMU, FmuError, FmuFile, Instance
from .result import Result
from .scene import Dancer, Prescribed, Roller, Scene, Span

ALGORITHMS = ("gauss-seidel", "jacobi")
COUPLINGS = ("extrapolate", "hold")
SPAN_INPUTS = ["web_a.v", "web_a.eps", "web_b.v", "frame_a.x", "frame_a.y", "frame_b.x", "frame_b.y"]
SPAN_OUTPUTS = ["summary_Tension", "web_a.F", "web_b.F", "web_b.eps", "summary_Length"]
ROLLER_INPUTS = ["F_up", "F_down", "tau_m"]
ROLLER_OUTPUTS = ["v", "omega"]
MAX_HALVINGS = 12


class CoSimulationError(RuntimeError):
    pass


@dataclass
class Signal:
    """A coupling signal's values at the last two communication points."""

    now: float = 0.0
    t_now: float = 0.0
    prev: float = 0.0
    t_prev: float = 0.0
    has_prev: bool = False

    def push(self, t, x):
        self.prev, self.t_prev, self.has_prev = self.now, self.t_now, True
        self.now, self.t_now = x, t

    def reset(self, t, x):
        self.now, self.t_now, self.has_prev = x, t, False

    def slope(self):
        if not self.has_prev or self.t_now <= self.t_prev:
            return 0.0
        return (self.now - self.prev) / (self.t_now - self.t_prev)

    def copy(self):
        return Signal(self.now, self.t_now, self.prev, self.t_prev, self.has_prev)


def span_frames(scene: Scene, span: Span, y: float, R_dancer: float):
    """Frame positions of a span hanging from a dancer: vertical spans of length y."""
    up, down = scene.upstream(span), scene.downstream(span)
    if isinstance(down, Dancer):  # the dancer is at b
        return (0.0, 0.0, 0.0, -y)
    if isinstance(up, Dancer):  # the dancer is at a
        w = 2.0 * R_dancer
        return (w, -y, w, 0.0)
    return (0.0, 0.0, 1.0, 0.0)


WEB_FIELDS = ("E", "thickness", "width", "density", "d_r")


def web_values(side: str, web, web_library=None) -> dict:
    """The span FMU's parameters for one web ("wp1" or "wp2"): the record's
    name, which the FMU looks up itself, or the values one by one."""
    if web.record:
        values = {f"{side}.record": web.record}
        if web_library:
            values["webLibrary"] = web_library
        return values
    return {f"{side}.record": "", **{f"{side}.{k}": getattr(web, k) for k in WEB_FIELDS}}


def span_start_values(span: Span, solvers: dict, length_default=1.0, web_library=None):
    """The span FMU's parameters for `span`; `solvers` maps solver names to the
    values of the FMU's Enumeration `solver` (`FmuFile.enumeration`)."""
    values = {
        "L": span.length if span.length is not None else length_default,
        **web_values("wp1", span.wp1, web_library),
        **web_values("wp2", span.wp2, web_library),
        "includeDamping": "includeDamping" in span.effects,
        "preventNegativeTension": "preventNegativeTension" in span.effects,
        "includeMass": "includeMass" in span.effects,
        "variableLength": "variableLength" in span.effects,
        "startAtEquilibrium": span.eps_start is None,
        "solver": solvers[span.solver],
    }
    if span.eps_start is not None:
        values["eps_start"] = span.eps_start
    if span.tolerance is not None:
        values["tolerance"] = span.tolerance
    if span.substeps is not None:
        values["substeps"] = span.substeps
    return values


class Carriage:
    """A dancer's carriage, m*y'' = F - c*y' - k*(y - y0), stepped exactly
    with the force held over the step: s(t+h) = Phi*s + Gamma*g, where
    Phi = exp(A h) and Gamma = integral of exp(A s) ds, cached per step size."""

    def __init__(self, d: Dancer):
        self.d = d
        self.y = d.y_start
        self.ydot = 0.0
        self.A = np.array([[0.0, 1.0], [-d.stiffness / d.mass, -d.damping / d.mass]])
        self._cache = {}

    def _matrices(self, h):
        if h not in self._cache:
            M = np.zeros((4, 4))
            M[:2, :2] = self.A * h
            M[:2, 2:] = np.eye(2) * h
            E = expm(M)
            if len(self._cache) > 64:
                self._cache.clear()
            self._cache[h] = (E[:2, :2], E[:2, 2:])
        return self._cache[h]

    def step(self, force: float, h: float):
        d = self.d
        phi, gamma = self._matrices(h)
        g = np.array([0.0, (force + d.stiffness * d.y_start) / d.mass])
        s = phi @ np.array([self.y, self.ydot]) + gamma @ g
        self.y, self.ydot = float(s[0]), float(s[1])


@dataclass
class Options:
    algorithm: str = "gauss-seidel"
    coupling: str = "extrapolate"
    step: float | None = None  # None: the scene's step
    fmu_tolerance: float = 1e-12
    rollback: bool = True
    fmu_dir: object = DEFAULT_FMU_DIR
    progress: bool = False


@dataclass
class Stats:
    steps: int = 0
    rollbacks: int = 0
    instances: int = 0
    replaced: int = 0
    wall_time: float = 0.0
    events: list = field(default_factory=list)


class CoSimulation:
    def __init__(self, scene: Scene, options: Options | None = None):
        self.scene = scene
        self.opt = options or Options()
        if self.opt.algorithm not in ALGORITHMS:
            raise ValueError(f"algorithm must be one of {ALGORITHMS}")
        if self.opt.coupling not in COUPLINGS:
            raise ValueError(f"coupling must be one of {COUPLINGS}")
        from pathlib import Path

        d = Path(self.opt.fmu_dir)
        self.span_file = FmuFile.load(d / SPAN_FMU)
        self.roller_file = FmuFile.load(d / ROLLER_FMU)
        self.stats = Stats()
        self.inst: dict[str, Instance] = {}
        self.carriage: dict[str, Carriage] = {}
        # Coupling signals, keyed (component name, quantity).
        self.sig: dict[tuple, Signal] = {}
        self.params: dict[str, dict] = {}  # current parameters of each FMU component
        self.torque = {}

    # ------------------------------------------------------------ helpers

    def nodes_with_fmu(self):
        return [c for c in self.scene.nodes if isinstance(c, (Roller, Dancer)) and c.has_fmu]

    def node_speed_profile(self, node):
        return self.scene.speed_profile(node)

    def accepts_derivatives(self, span):
        """The span FMU takes input derivatives (canInterpolateInputs), unless
        its solver is `exact`, which holds the inputs over a step."""
        return self.span_file.can_interpolate_inputs() and span.solver != "exact"

    def torque_profile(self, node):
        """The motor torque of a Roller-FMU node; a tension drive's torque uses
        the radius in force now (a splice may have changed it)."""
        if not isinstance(node, Roller):
            return None
        d = node.drive
        if d.kind == "tension":
            R = self.params.get(node.name, {}).get("R", node.R)
            return d.profile.scaled((-1.0 if node.type == "unwinder" else 1.0) * R)
        return self.scene.torque_profile(node)

    def strain_profile(self, span):
        up = self.scene.upstream(span)
        if isinstance(up, Prescribed):
            return up.strain
        if isinstance(up, Roller) and up.type == "unwinder":
            return up.strain
        return None

    def grid(self):
        return self.grid_of(self.scene, self.opt.step or self.scene.step)

    @staticmethod
    def grid_of(scene, h):
        """Communication points: multiples of h, every breakpoint and event
        time, and the stop time (points closer than 1e-6*h are merged, the
        breakpoint kept)."""
        n = max(1, int(math.ceil(scene.stop_time / h - 1e-9)))
        points = [min(k * h, scene.stop_time) for k in range(n + 1)]
        breaks = scene.breakpoints()
        bset = set(breaks)
        out = []
        tol = 1e-6 * h
        for t in sorted(set(points) | bset):
            if out and t - out[-1] < tol:
                if t in bset:
                    out[-1] = t
                continue
            out.append(t)
        out[-1] = scene.stop_time
        return out, bset

    # ------------------------------------------------------------ set-up

    def _new_span_instance(self, span: Span, values: dict, inputs: list, t: float):
        inst = Instance(self.span_file, span.name, SPAN_INPUTS, SPAN_OUTPUTS)
        inst.begin(values, self.opt.fmu_tolerance, t, self.scene.stop_time)
        inst.set_inputs(inputs)
        self.stats.instances += 1
        return inst

    def _new_roller_instance(self, node, values: dict, inputs: list, t: float):
        inst = Instance(self.roller_file, node.name, ROLLER_INPUTS, ROLLER_OUTPUTS)
        inst.begin(values, self.opt.fmu_tolerance, t, self.scene.stop_time)
        inst.set_inputs(inputs)
        self.stats.instances += 1
        return inst

    def setup(self):
        s = self.scene
        self.t0 = 0.0
        t = self.t0
        # Node speeds at the start.
        for node in s.nodes:
            v0 = s.initial_speed(node)
            self.sig[(node.name, "v")] = Signal(now=v0, t_now=t)
            if isinstance(node, Dancer):
                self.carriage[node.name] = Carriage(node)
                self.sig[(node.name, "y")] = Signal(now=node.y_start, t_now=t)
        # Spans in line order: each one's start strain feeds the next.
        for span in s.spans:
            values = span_start_values(span, self.span_file.enumeration("solver"), web_library=self.scene.web_library)
            self.params[span.name] = values
            inputs = self.span_inputs_at(span, t)
            self.inst[span.name] = self._new_span_instance(span, values, inputs, t)
            out = self.inst[span.name].outputs()
            self._store_span(span, t, out, reset=True)
        for node in self.nodes_with_fmu():
            values = {"J": node.J, "R": node.R, "b": node.b, "omega_start": s.initial_speed(node) / node.R}
            self.params[node.name] = values
            inputs = self.roller_inputs_at(node, t, t)
            self.inst[node.name] = self._new_roller_instance(node, values, inputs, t)
        for inst in self.inst.values():
            inst.end_initialization()
        for span in s.spans:
            self._store_span(span, t, self.inst[span.name].outputs(), reset=True)
        for node in self.nodes_with_fmu():
            v, omega = self.inst[node.name].outputs()
            self.sig[(node.name, "v")].reset(t, v)
            self.sig[(node.name, "omega")] = Signal(now=omega, t_now=t)

    def _store_span(self, span, t, out, reset):
        T, Fa, Fb, eps, L = out
        for q, x in (("T", T), ("F_a", Fa), ("F_b", Fb), ("eps", eps), ("L", L)):
            key = (span.name, q)
            if reset or key not in self.sig:
                self.sig[key] = Signal(now=x, t_now=t)
            else:
                self.sig[key].push(t, x)

    # ------------------------------------------------------------ inputs

    def span_inputs_at(self, span, t):
        """Span inputs from the current signal values (used at the start and for a new instance)."""
        s = self.scene
        up, down = s.upstream(span), s.downstream(span)
        va = self._speed_now(up, t)
        vb = self._speed_now(down, t)
        eps_a = self._strain_in_now(span, t)
        frames = self._frames_now(span)
        return [va, eps_a, vb, *frames]

    def _speed_now(self, node, t):
        p = self.node_speed_profile(node)
        return p.value(t) if p is not None else self.sig[(node.name, "v")].now

    def _strain_in_now(self, span, t):
        p = self.strain_profile(span)
        if p is not None:
            return p.value(t)
        return self.sig[(self.scene.line[span.index - 2].name, "eps")].now

    def _frames_now(self, span):
        s = self.scene
        for d in (s.upstream(span), s.downstream(span)):
            if isinstance(d, Dancer):
                return span_frames(s, span, self.sig[(d.name, "y")].now, d.R)
        return (0.0, 0.0, 1.0, 0.0)

    def roller_inputs_at(self, node, t0, t1):
        """F_up, F_down, tau_m for a roller's step over [t0, t1] (held inputs)."""
        s = self.scene
        before, after = s.span_before(node), s.span_after(node)
        mid = self.opt.coupling == "extrapolate"
        h = t1 - t0

        def force(span, q):
            if span is None:
                return 0.0
            sg = self.sig[(span.name, q)]
            return sg.now + (0.5 * h * sg.slope() if mid else 0.0)

        F_up = force(before, "F_b")
        F_down = force(after, "F_a")
        tau_profile = self.torque_profile(node)
        if tau_profile is None:
            tau = 0.0
        elif mid and t1 > t0:
            tau = tau_profile.average(t0, t1)
        else:
            tau = tau_profile.value(t0)
        return [F_up, F_down, tau]

    def _moving_input(self, t, h, profile=None, signal=None, stepped=False):
        """(value at t, slope over the step) of a span input, by the coupling rules."""
        ex = self.opt.coupling == "extrapolate"
        if profile is not None:
            return (profile.value(t), profile.slope(t) if ex else 0.0)
        if stepped:  # Gauss–Seidel: the source has stepped to t+h already
            if ex:
                return (signal.prev, (signal.now - signal.prev) / h)
            return (signal.now, 0.0)
        if ex:
            return (signal.now, signal.slope())
        return (signal.now, 0.0)

    # ------------------------------------------------------------ stepping

    def _save(self):
        for inst in self.inst.values():
            inst.save()
        return (
            {k: v.copy() for k, v in self.sig.items()},
            {k: (c.y, c.ydot) for k, c in self.carriage.items()},
        )

    def _restore(self, saved):
        for inst in self.inst.values():
            inst.restore()
        sigs, carriages = saved
        self.sig = {k: v.copy() for k, v in sigs.items()}
        for k, (y, ydot) in carriages.items():
            self.carriage[k].y, self.carriage[k].ydot = y, ydot

    def step(self, t, h, reset_after):
        """One communication step, with rollback and halving on a discard."""
        saved = self._save() if self.opt.rollback else None
        if self._try_step(t, h, reset_after):
            self.stats.steps += 1
            return
        if not self.opt.rollback:
            raise CoSimulationError(f"an FMU discarded the step at t = {t} with h = {h} and rollback is off")
        depth = 0
        self._restore(saved)
        self.stats.rollbacks += 1
        self._retry(t, h, reset_after, depth + 1)

    def _retry(self, t, h, reset_after, depth):
        if depth > MAX_HALVINGS:
            raise CoSimulationError(
                f"the step at t = {t} was discarded even at h = {h}: {self._last_messages()}. "
                "The coupling is probably unstable at this communication step (docs/line-coupling.md: 'Stability: the longest step'): "
                "take a smaller step, or --algorithm gauss-seidel --coupling extrapolate"
            )
        half = 0.5 * h
        for k, (a, hh) in enumerate(((t, half), (t + half, h - half))):
            saved = self._save()
            if self._try_step(a, hh, reset_after and k == 1):
                self.stats.steps += 1
                continue
            self._restore(saved)
            self.stats.rollbacks += 1
            self._retry(a, hh, reset_after and k == 1, depth + 1)

    def _last_messages(self):
        return "; ".join(f"{n}: {i.messages[-1]}" for n, i in self.inst.items() if i.messages)

    def _try_step(self, t, h, reset_after) -> bool:
        s = self.scene
        t1 = t + h
        gs = self.opt.algorithm == "gauss-seidel"
        ok = True
        # 1. rollers and carriages
        new_node = {}
        for node in self.nodes_with_fmu():
            inst = self.inst[node.name]
            inputs = self.roller_inputs_at(node, t, t1)
            inst.set_inputs(inputs)
            if not inst.do_step(t, h):
                return False
            if isinstance(node, Dancer):
                F_up, F_down, _ = inputs
                load = node.load.average(t, t1) if self.opt.coupling == "extrapolate" else node.load.value(t)
                self.carriage[node.name].step(load - F_up - F_down, h)
            new_node[node.name] = inst.outputs()
        if gs:
            for name, (v, omega) in new_node.items():
                self.sig[(name, "v")].push(t1, v)
                if name in self.carriage:
                    self.sig[(name, "y")].push(t1, self.carriage[name].y)
        # 2. spans, in line order
        new_span = {}
        for span in s.spans:
            up, down = s.upstream(span), s.downstream(span)
            values, slopes = [], []
            v, dv = self._moving_input(t, h, self.node_speed_profile(up), self.sig.get((up.name, "v")), stepped=gs)
            values.append(v)
            slopes.append(dv)
            p = self.strain_profile(span)
            if p is not None:
                e, de = self._moving_input(t, h, profile=p)
            else:
                e, de = self._moving_input(t, h, signal=self.sig[(s.line[span.index - 2].name, "eps")], stepped=gs)
            values.append(e)
            slopes.append(de)
            v, dv = self._moving_input(t, h, self.node_speed_profile(down), self.sig.get((down.name, "v")), stepped=gs)
            values.append(v)
            slopes.append(dv)
            dancer = up if isinstance(up, Dancer) else down if isinstance(down, Dancer) else None
            if dancer is not None:
                y, dy = self._moving_input(t, h, signal=self.sig[(dancer.name, "y")], stepped=gs)
                f0 = span_frames(s, span, y, dancer.R)
                f1 = span_frames(s, span, y + dy * h, dancer.R)
                values += list(f0)
                slopes += [(b - a) / h for a, b in zip(f0, f1)]
            else:
                values += [0.0, 0.0, 1.0, 0.0]
                slopes += [0.0, 0.0, 0.0, 0.0]
            inst = self.inst[span.name]
            if not self.accepts_derivatives(span):
                # Held inputs only (solver exact): the midpoint of the linear input.
                values = [x + 0.5 * h * dx for x, dx in zip(values, slopes)]
                slopes = [0.0] * len(slopes)
            inst.set_inputs(values)
            if any(slopes):
                inst.set_input_derivatives(slopes)
            if not inst.do_step(t, h):
                return False
            out = inst.outputs()
            if not all(map(math.isfinite, out)):
                raise CoSimulationError(
                    f"span {span.name!r} gave non-finite outputs {out} at t = {t1} (inputs {values}): the co-simulation "
                    "diverged; the coupling is unstable at this communication step (docs/line-coupling.md: 'Stability: the longest step'): "
                    "take a smaller step, or --algorithm gauss-seidel --coupling extrapolate"
                )
            new_span[span.name] = out
            if gs:
                self.sig[(span.name, "eps")].push(t1, out[3])
        # 3. commit the new values
        for span in s.spans:
            T, Fa, Fb, eps, L = new_span[span.name]
            for q, x in (("T", T), ("F_a", Fa), ("F_b", Fb), ("L", L)):
                self.sig[(span.name, q)].push(t1, x)
            if not gs:
                self.sig[(span.name, "eps")].push(t1, eps)
        for name, (v, omega) in new_node.items():
            if not gs:
                self.sig[(name, "v")].push(t1, v)
                if name in self.carriage:
                    self.sig[(name, "y")].push(t1, self.carriage[name].y)
            self.sig[(name, "omega")].push(t1, omega)
        if reset_after:
            for sg in self.sig.values():
                sg.has_prev = False
        return ok

    # ------------------------------------------------------------ events

    def apply_events(self, t, events):
        s = self.scene
        for ev in events:
            comp = s.component(ev.component)
            old = self.inst[comp.name]
            if isinstance(comp, Span):
                values = dict(self.params[comp.name])
                webs = dict(ev.changes)
                if "web" in webs:
                    webs["wp1"] = webs["wp2"] = webs.pop("web")
                for side, web in webs.items():
                    # The old web's values go: a record may not meet values set one by one.
                    values = {k: x for k, x in values.items() if not k.startswith(f"{side}.")}
                    values.update(web_values(side, web, s.web_library))
                # Continue from the old instance's state: its strain.
                values["startAtEquilibrium"] = False
                values["eps_start"] = self.sig[(comp.name, "eps")].now
                inputs = self.span_inputs_at(comp, t)
                old.free()
                new = self._new_span_instance(comp, values, inputs, t)
                new.end_initialization()
                self.inst[comp.name] = new
                self._store_span(comp, t, new.outputs(), reset=True)
            else:
                values = dict(self.params[comp.name])
                v = self.sig[(comp.name, "v")].now
                values.update(ev.changes)
                # A new roll or roller at the same surface speed.
                values["omega_start"] = v / values["R"]
                self.params[comp.name] = values  # the tension drive's torque follows the new radius
                inputs = self.roller_inputs_at(comp, t, t)
                old.free()
                new = self._new_roller_instance(comp, values, inputs, t)
                new.end_initialization()
                self.inst[comp.name] = new
                vnew, omega = new.outputs()
                self.sig[(comp.name, "v")].reset(t, vnew)
                self.sig[(comp.name, "omega")].reset(t, omega)
            self.params[comp.name] = values
            self.stats.replaced += 1
            self.stats.events.append((t, comp.name, ", ".join(ev.changes)))

    # ------------------------------------------------------------ recording

    def record(self, t):
        s = self.scene
        row = []
        for cname, q in s.record:
            c = s.component(cname)
            if isinstance(c, Span):
                row.append(self.sig[(cname, q)].now)
            elif q == "v":
                p = self.node_speed_profile(c)
                # At a jump, the value the step that ends here used: the left limit.
                row.append(self.sig[(cname, "v")].now if p is None else p.value_left(t) if t > 0 else p.value(t))
            elif q == "eps":
                row.append(c.strain.value_left(t) if t > 0 else c.strain.value(t))
            elif q == "omega":
                row.append(self.sig[(cname, "omega")].now)
            elif q == "tau":
                p = self.torque_profile(c)
                row.append(p.value_left(t) if t > 0 else p.value(t))
            elif q == "y":
                row.append(self.carriage[cname].y)
            elif q == "y_dot":
                row.append(self.carriage[cname].ydot)
        return row

    # ------------------------------------------------------------ run

    def run(self) -> Result:
        start = clock.perf_counter()
        s = self.scene
        grid, breaks = self.grid()
        events_at = {}
        for ev in s.events:
            events_at.setdefault(ev.time, []).append(ev)
        # Event times are breakpoints and so grid points; map them exactly.
        try:
            self.setup()
            times = [grid[0]]
            rows = [self.record(grid[0])]
            bar = None
            if self.opt.progress:
                from tqdm import tqdm

                bar = tqdm(total=len(grid) - 1, unit="step", desc=s.name, leave=False)
            for t, t1 in zip(grid[:-1], grid[1:]):
                if t in events_at:
                    self.apply_events(t, events_at[t])
                self.step(t, t1 - t, reset_after=t1 in breaks)
                times.append(t1)
                rows.append(self.record(t1))
                if bar is not None:
                    bar.update(1)
            if bar is not None:
                bar.close()
        finally:
            for inst in self.inst.values():
                inst.free()
        self.stats.wall_time = clock.perf_counter() - start
        return Result(
            scene=s.name,
            columns=s.columns(),
            time=np.array(times),
            data=np.array(rows),
            info={
                "method": f"co-simulation ({self.opt.algorithm}, {self.opt.coupling})",
                "step": self.opt.step or s.step,
                "steps": self.stats.steps,
                "rollbacks": self.stats.rollbacks,
                "instances": self.stats.instances,
                "replaced": self.stats.replaced,
                "wall_time": self.stats.wall_time,
                "events": self.stats.events,
            },
        )


def run_scene(scene: Scene, **kwargs) -> Result:
    return CoSimulation(scene, Options(**kwargs)).run()
