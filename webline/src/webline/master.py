"""The co-simulation master: runs a System, one FMU instance per component.

Every communication step [t, t+h] steps the components:

* Jacobi: every component gets the outputs of the others at t;
* Gauss–Seidel: in list order (rollers first, then spans in line order); a
  component whose source has stepped already gets that source's value at t+h.

Inputs are held (`hold`), or extrapolated (`extrapolate`, the default) from
the source's values at the last two communication points. A component that
accepts input derivatives (the span, canInterpolateInputs, unless its solver
is `exact`) gets the value at t and the slope over the step: after a
Gauss–Seidel source stepped, the slope to its value at t+h. A component that
holds its inputs (the Roller) gets the midpoint of that line, the best a
held input can do.

Profiles (speeds, torques, tensions, loads, timed parameter changes) live in
the FMUs, which split their steps at breakpoints themselves. With the `aligned`
grid the master also puts communication points on every breakpoint and
restarts extrapolation there; `uniform` uses multiples of the step only, as
other engines do; `fmpy` adds the step to the time as FMPy's simulate_ssp does.

Before a step the master saves every FMU's state (`rollback`); if an FMU
discards the step (fmi2Discard), all are rolled back and the step is retried
as two half steps. `zero_start` reproduces FMPy's simulate_ssp: every
connected input is 0.0 on the first step. A tension that oscillates ever more
stops the run (`Growth`): the coupling is unstable at the step.
"""

from __future__ import annotations

import hashlib
import math
import tempfile
import time as clock
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .bound import runaway
from .fmus import FmuError, FmuFile, Instance
from .names import scene_columns
from .result import Result
from .system import System, profile_text

ALGORITHMS = ("gauss-seidel", "jacobi")
COUPLINGS = ("extrapolate", "hold")
GRIDS = ("aligned", "uniform", "fmpy")
MAX_HALVINGS = 12
SETTLE_ROUNDS = 20


class CoSimulationError(RuntimeError):
    pass


@dataclass
class Options:
    algorithm: str = "gauss-seidel"
    coupling: str = "extrapolate"
    step: float | None = None  # None: the system's step
    rollback: bool = True
    grid: str = "aligned"
    zero_start: bool = False  # FMPy: every connected input 0.0 on the first step
    tolerance: float | None = 1e-12  # fmi2SetupExperiment's tolerance (None: not defined, as FMPy)
    progress: bool = False
    watch: bool = True  # stop a run whose tensions oscillate ever more (`Growth`); other engines do not watch
    bounds: dict | None = None  # {span component: N}: a run stops where |F| of a span passes it (bound.py)

    @staticmethod
    def engine(**kwargs) -> "Options":
        """The coupling other engines use (libcosim, FMPy): Jacobi, held inputs,
        a uniform grid, no rollback, no tolerance given."""
        base = dict(algorithm="jacobi", coupling="hold", rollback=False, grid="uniform", tolerance=None, watch=False)
        base.update(kwargs)
        return Options(**base)

    @staticmethod
    def fmpy(**kwargs) -> "Options":
        """FMPy's simulate_ssp, bit for bit: the engine coupling, its time
        accumulation, and 0.0 for every connected input on the first step."""
        return Options.engine(grid="fmpy", zero_start=True, **kwargs)


@dataclass
class Signal:
    """An output's values at the last two communication points."""

    now: float = 0.0
    t_now: float = 0.0
    prev: float = 0.0
    t_prev: float = 0.0
    has_prev: bool = False

    def push(self, t, x):
        self.prev, self.t_prev, self.has_prev = self.now, self.t_now, True
        self.now, self.t_now = x, t

    def slope(self):
        if not self.has_prev or self.t_now <= self.t_prev:
            return 0.0
        return (self.now - self.prev) / (self.t_now - self.t_prev)

    def copy(self):
        return Signal(self.now, self.t_now, self.prev, self.t_prev, self.has_prev)


class Growth:
    """Watches a run for an oscillation its coupling makes grow: the tensions' second difference over three
    communication points (what a smooth signal keeps near zero, and an oscillation at the step's scale does
    not), its peak over windows of WINDOW steps. The run stops when that peak, already FLOOR of the
    tension's scale (its largest magnitude so far, at least 1 N) when first seen, has not fallen in
    GROWING windows in a row and has grown RATIO times over them: a physical transient (a jump, a snatch,
    a ring-down) peaks once and decays, and a transient's onset starts below the floor. It sees growth of
    2.3 % per step and more (RATIO ** (1 / (GROWING * WINDOW)))."""

    WINDOW = 20
    RATIO = 10.0
    GROWING = 5
    FLOOR = 1e-4

    def __init__(self, names):
        self.names = list(names)
        n = len(self.names)
        self.last = np.full((2, n), np.nan)  # the values at the last two points
        self.scale = np.ones(n)
        self.peak = np.zeros(n)  # this window's
        self.peaks = []  # the last GROWING + 1 windows'
        self.count = 0

    def see(self, t, values):
        """The tensions at the next communication point; a message when the run must stop, else None."""
        x = np.asarray(values, dtype=float)
        self.scale = np.maximum(self.scale, np.abs(x))
        if not np.isnan(self.last).any():
            self.peak = np.maximum(self.peak, np.abs(x - 2.0 * self.last[1] + self.last[0]))
        self.last = np.vstack([self.last[1], x])
        self.count += 1
        if self.count % self.WINDOW:
            return None
        self.peaks = (self.peaks + [self.peak])[-(self.GROWING + 1):]
        self.peak = np.zeros_like(self.peak)
        if len(self.peaks) <= self.GROWING:
            return None
        p = np.array(self.peaks)
        growing = np.all(p[1:] >= p[:-1], axis=0) & (p[0] >= self.FLOOR * self.scale) & (p[-1] >= self.RATIO * p[0])
        if not growing.any():
            return None
        k = int(np.argmax(np.where(growing, p[-1] / self.scale, -1.0)))
        rate = (p[-1, k] / p[0, k]) ** (1.0 / (self.GROWING * self.WINDOW))
        return (f"{self.names[k]} oscillates ever more at t = {t:g} s: its step-to-step swing grew {p[-1, k] / p[0, k]:.3g} "
                f"times in {self.GROWING * self.WINDOW} steps ({rate:.3g} per step) to {p[-1, k]:.3g} N: the coupling is "
                "unstable at this step (docs/line-coupling.md, 'Stability: the longest step'); take a smaller step, "
                "or --engine line")


def communication_points(start, stop, h, breakpoints=(), mode="aligned"):
    """The communication points: multiples of h from `start` and the stop time;
    `aligned` adds the breakpoints (points closer than 1e-6*h merge, the
    breakpoint kept); `fmpy` adds h again and again while t < stop, as FMPy does."""
    steps = steps_of(start, stop, h, breakpoints, mode)
    return [t for t, _ in steps] + [steps[-1][0] + steps[-1][1] if mode == "fmpy" else stop]


def steps_of(start, stop, h, breakpoints=(), mode="aligned"):
    """The communication steps (t, step size). `uniform` and `fmpy` pass h
    itself as other engines do, not a difference of two points (the last
    uniform step ends at the stop time)."""
    if mode == "fmpy":
        out, t = [], start
        while t < stop:
            out.append((t, h))
            t += h
        return out
    n = max(1, int(math.ceil((stop - start) / h - 1e-9)))
    points = [min(start + k * h, stop) for k in range(n + 1)]
    points[-1] = stop
    if mode == "uniform":
        return [(t, h if k < n - 1 else stop - t) for k, t in enumerate(points[:-1])]
    bset = set(breakpoints)
    out = []
    for t in sorted(set(points) | bset):
        if out and t - out[-1] < 1e-6 * h:
            if t in bset:
                out[-1] = t
            continue
        out.append(t)
    out[-1] = stop
    return [(a, b - a) for a, b in zip(out[:-1], out[1:])]


def profile_file(profile: dict) -> str:
    """The profile JSON in a file (named by its content) for the String parameter `profile`."""
    text = profile_text(profile)
    d = Path(tempfile.gettempdir()) / "webline-profiles"
    d.mkdir(exist_ok=True)
    path = d / f"{hashlib.sha256(text.encode()).hexdigest()[:20]}.json"
    if not path.exists():
        tmp = path.with_suffix(f".{id(text)}.part")
        tmp.write_text(text)
        tmp.replace(path)
    return str(path)


class Master:
    def __init__(self, system: System, options: Options | None = None):
        self.system = system
        self.opt = options or Options()
        if self.opt.algorithm not in ALGORITHMS:
            raise ValueError(f"algorithm must be one of {ALGORITHMS}")
        if self.opt.coupling not in COUPLINGS:
            raise ValueError(f"coupling must be one of {COUPLINGS}")
        if self.opt.grid not in GRIDS:
            raise ValueError(f"grid must be one of {GRIDS}")
        self.h = self.opt.step or system.step
        self.files = {c.name: FmuFile.load(c.fmu) for c in system.components}
        self.inputs = {c.name: system.inputs_of(c.name) for c in system.components}
        # The outputs read from each component: those connected, then those recorded.
        self.outputs = {c.name: [] for c in system.components}
        for name, var in [c.source for c in system.connections] + list(system.record):
            if var not in self.outputs[name]:
                self.outputs[name].append(var)
        self.inst: dict[str, Instance] = {}
        self.sig: dict[tuple, Signal] = {}
        self.first = True
        self.steps = self.rollbacks = 0

    # ------------------------------------------------------------ set-up

    def accepts_derivatives(self, comp) -> bool:
        f = self.files[comp.name]
        if not f.can_interpolate_inputs():
            return False
        if "solver" in comp.start and "solver" in f.variables:
            return comp.start["solver"] != f.enumeration("solver").get("exact")
        return True

    def start_values(self, comp) -> dict:
        values = dict(comp.start)
        if comp.profile:
            values["profile"] = profile_file(comp.profile)
        return values

    def instantiate(self):
        t0 = self.system.start_time
        stop = self.system.stop_time if self.opt.tolerance is not None else None
        for comp in self.system.components:
            inst = Instance(self.files[comp.name], comp.name, [c.target[1] for c in self.inputs[comp.name]], self.outputs[comp.name])
            self.inst[comp.name] = inst
            inst.begin(self.start_values(comp), self.opt.tolerance, t0, stop)
        for inst in self.inst.values():
            inst.end_initialization()
        for comp in self.system.components:
            for var, x in zip(self.outputs[comp.name], self.inst[comp.name].outputs()):
                self.sig[(comp.name, var)] = Signal(now=x, t_now=t0)
        self.derivatives = {c.name: self.accepts_derivatives(c) for c in self.system.components}

    def free(self):
        for inst in self.inst.values():
            inst.free()

    # ------------------------------------------------------------ a step

    def input_values(self, comp, t, h, at_break=False):
        """(values, slopes or None) of a component's connected inputs over [t, t+h].
        `at_break`: the step ends at a profile breakpoint, where a source's new value
        may already be after a jump or kink: its old trend is used instead."""
        conns = self.inputs[comp.name]
        if self.first and self.opt.zero_start:
            return [0.0] * len(conns), None
        ex = self.opt.coupling == "extrapolate"
        ders = self.derivatives[comp.name] and ex
        t1 = t + h
        values, slopes = [], []
        for c in conns:
            s = self.before[c.source] if at_break else self.sig[c.source]
            stepped = s.t_now == t1 and t1 != t
            if not ex:
                values.append(s.now)
                continue
            if stepped:
                x0, dx = s.prev, (s.now - s.prev) / h
            else:
                x0, dx = s.now, s.slope()
            if ders:
                values.append(x0)
                slopes.append(dx)
            else:
                values.append(x0 + 0.5 * h * dx)
        return values, (slopes if ders and any(slopes) else None)

    def step_component(self, comp, t, h, at_break=False):
        """Sets the inputs, steps, reads the outputs: the outputs, or None if discarded."""
        inst = self.inst[comp.name]
        if self.inputs[comp.name]:
            values, slopes = self.input_values(comp, t, h, at_break)
            inst.set_inputs(values)
            if slopes is not None:
                inst.set_input_derivatives(slopes)
        if not inst.do_step(t, h):
            return None
        out = inst.outputs()
        if not all(map(math.isfinite, out)):
            raise CoSimulationError(
                f"{comp.name!r} gave non-finite outputs {dict(zip(self.outputs[comp.name], out))} at t = {t + h}: the "
                "co-simulation diverged; the coupling is unstable at this communication step "
                "(docs/line-coupling.md, 'Stability: the longest step'): take a smaller step"
            )
        return out

    def try_step(self, t, h, at_break=False) -> bool:
        t1 = t + h
        gs = self.opt.algorithm == "gauss-seidel"
        if at_break:  # the signals as they were at t
            self.before = {k: s.copy() for k, s in self.sig.items()}
        new = {}
        for comp in self.system.components:
            out = self.step_component(comp, t, h, at_break)
            if out is None:
                return False
            if gs:
                for var, x in zip(self.outputs[comp.name], out):
                    self.sig[(comp.name, var)].push(t1, x)
            else:
                new[comp.name] = out
        for name, out in new.items():
            for var, x in zip(self.outputs[name], out):
                self.sig[(name, var)].push(t1, x)
        self.first = False
        return True

    def step(self, t, h, at_break=False, depth=0):
        if not self.opt.rollback:
            if not self.try_step(t, h, at_break):
                raise CoSimulationError(f"a component discarded the step at t = {t} ({self.last_messages()}); rollback is off")
            self.steps += 1
            return
        for inst in self.inst.values():
            inst.save()
        saved = {k: s.copy() for k, s in self.sig.items()}
        first = self.first
        if self.try_step(t, h, at_break):
            self.steps += 1
            return
        for inst in self.inst.values():
            inst.restore()
        self.sig, self.first = saved, first
        self.rollbacks += 1
        if depth >= MAX_HALVINGS:
            raise CoSimulationError(f"step at t = {t} discarded after {MAX_HALVINGS} halvings: {self.last_messages()}")
        half = 0.5 * h
        self.step(t, half, False, depth + 1)
        self.step(t + half, h - half, at_break, depth + 1)

    def last_messages(self):
        return "; ".join(f"{n}: {i.messages[-1]}" for n, i in self.inst.items() if i.messages) or "no message"

    # ------------------------------------------------------------ run

    def record(self):
        return [self.sig[key].now for key in self.system.record]

    def columns(self):
        return scene_columns(self.system, {name: f.variables for name, f in self.files.items()})

    def run(self) -> Result:
        start = clock.perf_counter()
        s = self.system
        breaks = s.breakpoints() if self.opt.grid == "aligned" else []
        steps = steps_of(s.start_time, s.stop_time, self.h, breaks, self.opt.grid)
        bset = set(breaks)
        bar = None
        try:
            self.instantiate()
            times, rows = [s.start_time], [self.record()]
            if self.opt.progress:
                from tqdm import tqdm

                bar = tqdm(total=len(steps), unit="step", desc=s.name, leave=False)
            ends = [t for t, _ in steps[1:]] + [steps[-1][0] + steps[-1][1] if self.opt.grid == "fmpy" else s.stop_time]
            watched = [k for k in self.sig if k[1].endswith(".F") and self.system.component(k[0]).kind == "span"]
            growth = Growth(f"the tension of span {c!r}" for c, v in watched) if self.opt.watch and watched else None
            for (t, h), t1 in zip(steps, ends):
                self.step(t, h, t1 in bset)
                if growth is not None:
                    stop = growth.see(t1, [self.sig[k].now for k in watched])
                    if stop:
                        raise CoSimulationError(f"{s.name}: {stop}")
                for c, v in watched if self.opt.bounds else ():
                    if abs(self.sig[(c, v)].now) > self.opt.bounds[c]:
                        raise runaway(s.name, c, self.sig[(c, v)].now, self.opt.bounds[c], t1)
                if t1 in bset:  # a kink or jump: extrapolate afresh
                    for sg in self.sig.values():
                        sg.has_prev = False
                times.append(t1)
                rows.append(self.record())
                if bar is not None:
                    bar.update(1)
        finally:
            if bar is not None:
                bar.close()
            self.free()
        events = [(e["time"], c.name, ", ".join(k for k in e if k != "time")) for c in s.components for e in (c.profile or {}).get("set", [])]
        return Result(
            scene=s.name,
            columns=self.columns(),
            time=np.array(times),
            data=s.combine(np.array(rows, dtype=float).reshape(len(times), len(s.record))),
            info={
                "method": f"co-simulation ({self.opt.algorithm}, {self.opt.coupling})",
                "step": self.h,
                "steps": self.steps,
                "rollbacks": self.rollbacks,
                "instances": len(s.components),
                "wall_time": clock.perf_counter() - start,
                "events": sorted(events),
            },
        )


def run_system(system: System, algorithm="gauss-seidel", coupling="extrapolate", step=None, **options) -> Result:
    return Master(system, Options(algorithm=algorithm, coupling=coupling, step=step, **options)).run()


def settle_start_values(system: System):
    """Connected inputs start at the initial outputs feeding them: the FMUs are
    initialized, their outputs copied to the inputs' start values, until nothing
    changes (a span's forces depend on its speeds; strains pass along the line)."""
    for _ in range(SETTLE_ROUNDS):
        m = Master(system, Options(tolerance=None))
        try:
            m.instantiate()
            changed = False
            for c in system.connections:
                x = m.sig[c.source].now
                comp = system.component(c.target[0])
                if comp.start.get(c.target[1]) != x:
                    comp.start[c.target[1]] = x
                    changed = True
        finally:
            m.free()
        if not changed:
            return system
    raise CoSimulationError(f"{system.name}: the start values of the connected inputs do not settle in {SETTLE_ROUNDS} rounds")


def scene_grid(scene, h=None):
    """The aligned communication points of a scene at step h (default: its own)."""
    return communication_points(0.0, scene.stop_time, h or scene.step, scene.breakpoints())
