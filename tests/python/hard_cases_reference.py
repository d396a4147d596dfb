"""Driver and independent references for the hard-case tests (test_hard_cases.py).

A case is a *schedule*: the inputs at t = 0 (set before initialization) and a
list of communication steps, each with its size, the inputs the importer sets
at its start and, optionally, the input derivatives it gives for it
(fmi2SetRealInputDerivatives). The same schedule drives the packaged FMU
(`run_fmu`, through FMPy's FMU2Slave) and the reference (`reference`), which
is written from the physics (shared/docs/physics.md and the issue), not from
the FMU's code:

* held inputs: the closed form of the linear balance dx/dt = q - lambda*x over
  each step, evaluated with mpmath at 40 digits;
* inputs that move within a step (derivatives given): SciPy's Radau on the
  offset y = x - x_k of the step, rtol = 1e-12 and an absolute tolerance of
  1e-16 m, restarted at every communication point (the inputs have kinks there)
  and split where web_a.v changes sign (a kink of the balance); the state is
  accumulated in mpmath so that no rounding piles up over many steps.

Outputs after a step are formed with the inputs at the end of the step and,
for the damping and web-mass terms, the input rates the issue documents: the
given derivatives, or else backward differences over the previous
communication step (0 after the first step).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import mpmath
import numpy as np
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2Discard, fmi2LastSuccessfulTime
from fmpy.simulation import instantiate_fmu
from mpmath import mpf

DPS = 40

SOLVERS = {"auto": 1, "exact": 2, "rosenbrock": 3, "dopri5": 4, "rk4": 5, "euler": 6}
SOLVER_NAMES = {v: k for k, v in SOLVERS.items()}
EXPLICIT_LIMIT = {"rk4": 2.785, "euler": 2.0}  # stability limits on the negative real axis

INPUTS = ("web_a.v", "web_a.eps", "web_b.v", "frame_a.x", "frame_a.y", "frame_b.x", "frame_b.y")
OUTPUTS = (
    "v", "T", "web_a.F", "web_b.F", "web_b.eps", "summary_Tension", "summary_Length",
    "summary_Strain", "summary_Stress", "m_web", "unstretchedLength",
)


# --------------------------------------------------------------------------
# Schedules


@dataclass
class Step:
    h: float
    u: dict  # every input over the step (at its start)
    du: dict | None = None  # derivatives given for the step; None: inputs held


@dataclass
class Schedule:
    initial: dict  # every input at t = 0
    steps: list = field(default_factory=list)

    def times(self):
        t = [0.0]
        for s in self.steps:
            t.append(t[-1] + s.h)
        return np.array(t)


def resolve(name, names):
    """A variable name written as a Python identifier, one '_' standing for the
    '.' (web_a_v -> web_a.v, wp2_d_r -> wp2.d_r)."""
    if name in names:
        return name
    found = [c for i, ch in enumerate(name) if ch == "_" for c in [name[:i] + "." + name[i + 1:]] if c in names]
    assert len(found) == 1, f"{name}: no single variable of that name"
    return found[0]


def inputs(defaults, **changes):
    """All seven inputs: the start values, with `changes`."""
    u = {n: float(defaults[n]) for n in INPUTS}
    for k, v in changes.items():
        u[resolve(k, u)] = float(v)
    return u


def held(initial, segments):
    """A schedule of held inputs: segments = [(n_steps, h, {name: value}), ...];
    each segment's changes apply from its first step on."""
    s = Schedule(dict(initial))
    u = dict(initial)
    for n, h, change in segments:
        u = {**u, **change}
        s.steps += [Step(float(h), dict(u)) for _ in range(int(n))]
    return s


def ramped(initial, segments):
    """Inputs that ramp linearly, given to the FMU as input derivatives:
    segments = [(n_steps, h, {name: slope}), ...], each ramping on from where
    the last one ended; an empty dict holds the inputs (no derivatives given).
    A segment may carry a fourth element, {name: value}, set at its start."""
    s = Schedule(dict(initial))
    u = dict(initial)
    for seg in segments:
        n, h, slopes = seg[:3]
        if len(seg) > 3:
            u = {**u, **seg[3]}
        for _ in range(int(n)):
            s.steps.append(Step(float(h), dict(u), dict(slopes) if slopes else None))
            # the FMU's inputs at the end of the step: u + slope*h
            u = {name: u[name] + slopes.get(name, 0.0) * float(h) for name in INPUTS}
    return s


# --------------------------------------------------------------------------
# The packaged FMU through FMPy


class Log:
    """Logger for FMPy's callback (messages arrive formatted by FMPy's proxy)."""

    def __init__(self):
        self.messages = []

    def __call__(self, component, instance, status, category, message):
        self.messages.append((status, category.decode(), message.decode()))

    def text(self):
        return "\n".join(m for _, _, m in self.messages)


@dataclass
class Discard:
    step: int  # index of the refused step
    time: float  # its communication point
    h: float
    before: dict  # outputs before the step
    after: dict  # outputs read after the refusal
    last_successful_time: float
    message: str


@dataclass
class Result:
    t: np.ndarray
    out: dict  # name -> array over the points (t = 0 and after each step)
    discard: Discard | None
    log: str


class Fmu:
    """The packaged FMU: model description, unzipped directory, value references."""

    def __init__(self, md, unzipdir):
        self.md = md
        self.unzipdir = unzipdir
        self.var = {v.name: v for v in md.modelVariables}
        self.vr = {name: v.valueReference for name, v in self.var.items()}
        self.defaults = {}
        for v in md.modelVariables:
            if v.start is None:
                continue
            if v.type == "Real":
                self.defaults[v.name] = float(v.start)
            elif v.type == "Boolean":
                self.defaults[v.name] = str(v.start).lower() in ("true", "1")
            else:
                self.defaults[v.name] = int(v.start)

    def params(self, **overrides):
        """Every parameter: the start values with overrides (see `resolve`)."""
        p = {n: v for n, v in self.defaults.items() if self.var[n].causality == "parameter"}
        for k, v in overrides.items():
            p[resolve(k, p)] = v
        return p

    def inputs(self, **changes):
        return inputs(self.defaults, **changes)

    def _set(self, fmu, values):
        groups = {"Real": ([], []), "Integer": ([], []), "Enumeration": ([], []), "Boolean": ([], [])}
        for name, value in values.items():
            vrs, vals = groups[self.var[name].type]
            vrs.append(self.vr[name])
            vals.append(value)
        if groups["Real"][0]:
            fmu.setReal(*groups["Real"])
        ints = (groups["Integer"][0] + groups["Enumeration"][0], groups["Integer"][1] + groups["Enumeration"][1])
        if ints[0]:
            fmu.setInteger(ints[0], [int(x) for x in ints[1]])
        if groups["Boolean"][0]:
            fmu.setBoolean(groups["Boolean"][0], [bool(x) for x in groups["Boolean"][1]])

    def run(self, params, schedule, experiment_tolerance=None):
        """Runs the schedule; every output at t = 0 and after each step. A step
        refused with fmi2Discard ends the run (recorded in `discard`); any other
        failure raises."""
        log = Log()
        fmu = instantiate_fmu(self.unzipdir, self.md, "CoSimulation", logger=log)
        out_vrs = [self.vr[n] for n in OUTPUTS]
        in_vrs = [self.vr[n] for n in INPUTS]
        rows, times, discard = [], [0.0], None
        try:
            fmu.setupExperiment(tolerance=experiment_tolerance, startTime=0.0)
            self._set(fmu, params)
            fmu.setReal(in_vrs, [schedule.initial[n] for n in INPUTS])
            fmu.enterInitializationMode()
            fmu.exitInitializationMode()
            rows.append(fmu.getReal(out_vrs))
            t = 0.0
            previous = dict(schedule.initial)
            for k, s in enumerate(schedule.steps):
                changed = [n for n in INPUTS if s.u[n] != previous[n]]
                if changed:
                    fmu.setReal([self.vr[n] for n in changed], [s.u[n] for n in changed])
                if s.du is not None:
                    names = list(s.du)
                    fmu.setRealInputDerivatives([self.vr[n] for n in names], [1] * len(names), [s.du[n] for n in names])
                try:
                    fmu.doStep(t, s.h)
                except FMICallException as e:
                    if e.status != fmi2Discard:
                        raise AssertionError(f"step {k} at t = {t} with h = {s.h}: status {e.status}\n{log.text()}") from e
                    discard = Discard(
                        step=k, time=t, h=s.h,
                        before=dict(zip(OUTPUTS, rows[-1])),
                        after=dict(zip(OUTPUTS, fmu.getReal(out_vrs))),
                        last_successful_time=fmu.getRealStatus(fmi2LastSuccessfulTime),
                        message=log.text(),
                    )
                    break
                t += s.h
                times.append(t)
                rows.append(fmu.getReal(out_vrs))
                # what the FMU now holds: with derivatives, its inputs moved along the ramp
                previous = {n: s.u[n] + (s.du or {}).get(n, 0.0) * s.h for n in INPUTS}
        finally:
            fmu.freeInstance()
        arr = np.array(rows, dtype=float)
        return Result(np.array(times), {n: arr[:, i] for i, n in enumerate(OUTPUTS)}, discard, log.text())


# --------------------------------------------------------------------------
# The reference


def _length(p, u):
    if p["variableLength"]:
        return mpmath.hypot(mpf(u["frame_b.x"]) - mpf(u["frame_a.x"]), mpf(u["frame_b.y"]) - mpf(u["frame_a.y"]))
    return mpf(p["L"])


def _length_rate(p, u, du):
    """dL/dt = (d . d')/|d| for the roller-to-roller vector d."""
    if not p["variableLength"] or du is None:
        return mpf(0)
    dx = mpf(u["frame_b.x"]) - mpf(u["frame_a.x"])
    dy = mpf(u["frame_b.y"]) - mpf(u["frame_a.y"])
    rx = mpf(du.get("frame_b.x", 0.0)) - mpf(du.get("frame_a.x", 0.0))
    ry = mpf(du.get("frame_b.y", 0.0)) - mpf(du.get("frame_a.y", 0.0))
    return (dx * rx + dy * ry) / mpmath.hypot(dx, dy)


def _web(p, prefix):
    E, th, w, rho = (mpf(p[f"{prefix}.{k}"]) for k in ("E", "thickness", "width", "density"))
    return {"EA": E * th * w, "A": th * w, "rho_l": rho * th * w, "d_r": mpf(p[f"{prefix}.d_r"])}


def _fluxes(u, x, L):
    """(q_a, dx/dt): entry flux (unstretched length per second) and the balance.
    Web entering at a carries eps_a; web leaving through a (v_a < 0) carries the
    span's strain, as does all web passing b: flux v*x/L."""
    va, ea, vb = mpf(u["web_a.v"]), mpf(u["web_a.eps"]), mpf(u["web_b.v"])
    qa = va / (1 + ea) if va >= 0 else va * x / L
    return qa, qa - vb * x / L


def _held_step(u, L, x, h, method=None):
    """Closed form over h with held inputs; with method = (name, n) the result
    of n sub-steps of that explicit method instead (its stability function
    R(z) applied to the linear balance: x_inf + (x - x_inf) R(-lambda h/n)^n)."""
    va, ea, vb = mpf(u["web_a.v"]), mpf(u["web_a.eps"]), mpf(u["web_b.v"])
    q = va / (1 + ea) if va >= 0 else mpf(0)
    lam = (vb - min(va, 0)) / L
    h = mpf(h)
    if method is None:
        if lam == 0:
            return x + q * h
        x_inf = q / lam
        return x_inf + (x - x_inf) * mpmath.exp(-lam * h)
    name, n = method
    z = -lam * h / n
    R = 1 + z if name == "euler" else 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
    if lam == 0:
        return x + q * h
    x_inf = q / lam
    return x_inf + (x - x_inf) * R**n


def _moving_step(p, u, du, x, h):
    """Radau over one step with inputs moving linearly; x in mpmath, the
    integration on the offset y = x(t) - x (float)."""
    from scipy.integrate import solve_ivp

    names = INPUTS
    u0 = {n: float(u[n]) for n in names}
    r = {n: float(du.get(n, 0.0)) for n in names}
    xf = float(x)
    lo = float(x - mpf(xf))  # what float(x) leaves out; carried in y

    def at(t):
        return {n: u0[n] + r[n] * t for n in names}

    def length(v):
        if p["variableLength"]:
            return math.hypot(v["frame_b.x"] - v["frame_a.x"], v["frame_b.y"] - v["frame_a.y"])
        return float(p["L"])

    def f(t, y):
        v = at(t)
        L = length(v)
        va, ea, vb = v["web_a.v"], v["web_a.eps"], v["web_b.v"]
        if va >= 0:
            # (q - vb*xf/L) first: the small rate near equilibrium, then the offset
            return [(va / (1 + ea) - vb * xf / L) - vb * y[0] / L]
        return [(va - vb) * (xf + y[0]) / L]

    def jac(t, y):
        v = at(t)
        return [[-(v["web_b.v"] - min(v["web_a.v"], 0.0)) / length(v)]]

    # split where web_a.v changes sign (the balance has a kink there)
    cuts = [0.0, h]
    if r["web_a.v"] != 0.0:
        tc = -u0["web_a.v"] / r["web_a.v"]
        if 0.0 < tc < h:
            cuts = [0.0, tc, h]
    y = lo
    for a, b in zip(cuts[:-1], cuts[1:]):
        sol = solve_ivp(f, (a, b), [y], method="Radau", rtol=1e-12, atol=1e-16, jac=jac)
        assert sol.success, sol.message
        y = float(sol.y[0, -1])
    return mpf(xf) + mpf(y)


def initial_state(p, u):
    L = _length(p, u)
    va, ea, vb = mpf(u["web_a.v"]), mpf(u["web_a.eps"]), mpf(u["web_b.v"])
    if p["startAtEquilibrium"]:
        eps = ea if va == 0 else (vb / va) * (1 + ea) - 1
    else:
        eps = mpf(p["eps_start"])
    return L / (1 + eps)


def outputs(p, u, x, rates):
    """Every output for state x, inputs u and input rates {'vb': dv_b/dt, 'L': dL/dt}."""
    L = _length(p, u)
    w2, w1 = _web(p, "wp2"), _web(p, "wp1")
    eps = L / x - 1
    qa, dxdt = _fluxes(u, x, L)
    eff = eps
    if p["includeDamping"]:
        deps = rates["L"] / x - (1 + eps) ** 2 / L * dxdt
        eff = eps + w2["d_r"] * deps
    T = w2["EA"] * eff
    if p["preventNegativeTension"] and T < 0:
        T = mpf(0)
    Fb = T
    va, vb = mpf(u["web_a.v"]), mpf(u["web_b.v"])
    m = w2["rho_l"] * x
    if p["includeMass"]:
        rho_in = w1["rho_l"] if va >= 0 else w2["rho_l"]
        Fb = T + qa * (w2["rho_l"] * vb - rho_in * va) + m * rates["vb"]
    return {
        "v": vb, "T": T, "web_a.F": T, "web_b.F": Fb, "web_b.eps": eps, "summary_Tension": T,
        "summary_Length": L, "summary_Strain": eps, "summary_Stress": T / w2["A"], "m_web": m,
        "unstretchedLength": x,
    }


def reference(p, schedule, method=None, n_points=None):
    """Reference outputs at t = 0 and after each step (lists of mpf).
    method: None (exact), or ("rk4"|"euler", substeps) for the prediction of that
    fixed-step method on held inputs (its stability function, see _held_step)."""
    with mpmath.workdps(DPS):
        u = schedule.initial
        x = initial_state(p, u)
        ref = {n: [] for n in OUTPUTS}

        def record(u, x, rates):
            for n, v in outputs(p, u, x, rates).items():
                ref[n].append(v)

        record(u, x, {"vb": mpf(0), "L": mpf(0)})
        prev = None  # (inputs at the start of the previous step, its size)
        steps = schedule.steps if n_points is None else schedule.steps[: n_points - 1]
        for s in steps:
            u = s.u
            moving = s.du is not None and any(v != 0.0 for v in s.du.values())
            if moving:
                assert method is None, "the fixed-step prediction covers held inputs only"
                x = _moving_step(p, u, s.du, x, s.h)
            else:
                x = _held_step(u, _length(p, u), x, s.h, method)
            end = {n: u[n] + (s.du or {}).get(n, 0.0) * s.h for n in INPUTS}
            if s.du is not None:
                rates = {"vb": mpf(s.du.get("web_b.v", 0.0)), "L": _length_rate(p, end, s.du)}
            elif prev is not None:
                pu, ph = prev
                rates = {
                    "vb": (mpf(u["web_b.v"]) - mpf(pu["web_b.v"])) / mpf(ph),
                    "L": (_length(p, u) - _length(p, pu)) / mpf(ph),
                }
            else:
                rates = {"vb": mpf(0), "L": mpf(0)}
            prev = (u, s.h)
            record(end, x, rates)
        return ref


# --------------------------------------------------------------------------
# Checks and the record of errors


WORST = {}  # solver -> {"err": worst relative error, "case": where}


def check_physical(result, what=""):
    """Every output finite at every point, the unstretched length > 0."""
    for name, values in result.out.items():
        bad = np.flatnonzero(~np.isfinite(values))
        assert bad.size == 0, f"{what}: {name} is not finite at t = {result.t[bad[0]]!r}: {values[bad[0]]!r}"
    x = result.out["unstretchedLength"]
    assert np.all(x > 0), f"{what}: unstretched length {x.min()} <= 0"


def record_error(solver, case, err, ratio=0.0):
    w = WORST.setdefault(solver, {"err": 0.0, "case": "", "ratio": 0.0, "ratio_case": "", "cases": 0})
    w["cases"] += 1
    if err >= w["err"]:
        w["err"], w["case"] = err, case
    if ratio >= w["ratio"]:
        w["ratio"], w["ratio_case"] = ratio, case


def compare(case, solver, p, result, ref, quantities=("T", "summary_Strain"), rel=1e-12, abs_strain=1e-15,
            allowance=None, record_as=None, floor_factor=None):
    """Asserts |FMU - reference| <= rel*|ref| + floor (+ allowance) for each
    quantity at every point, and records for the solver the worst relative
    error of the tension and the strain (at points where the reference is at
    least 1 % of its largest magnitude in the run: near a zero crossing a
    relative error says nothing) and the worst ratio error/tolerance.

    floor: abs_strain for strains, abs_strain*E2*A2 for forces,
    abs_strain*rho_l2*L for the web mass, abs_strain*L for lengths.
    allowance: {quantity: array} added to the tolerance point by point (the
    truncation error a fixed-step method is known to make).
    floor_factor: {quantity: factor} multiplies that quantity's floor.
    """
    with mpmath.workdps(DPS):
        w2 = _web(p, "wp2")
        scale = {
            "T": w2["EA"], "web_a.F": w2["EA"], "web_b.F": w2["EA"], "summary_Tension": w2["EA"],
            "summary_Stress": w2["EA"] / w2["A"], "web_b.eps": 1, "summary_Strain": 1,
            "m_web": w2["rho_l"] * mpf(p["L"]), "unstretchedLength": mpf(p["L"]),
            "summary_Length": mpf(p["L"]), "v": 1,
        }
        n = len(result.t)
        failures = []
        worst_rel, worst_ratio = 0.0, 0.0
        for q in quantities:
            got = result.out[q]
            floor = mpf(abs_strain) * scale[q] * (floor_factor or {}).get(q, 1)
            significant = max(abs(r) for r in ref[q][:n]) / 100
            for i in range(n):
                r = ref[q][i]
                err = abs(mpf(float(got[i])) - r)
                tol = mpf(rel) * abs(r) + floor
                if allowance is not None and q in allowance:
                    tol += mpf(allowance[q][i])
                ratio = float(err / tol) if tol > 0 else (0.0 if err == 0 else math.inf)
                worst_ratio = max(worst_ratio, ratio)
                if q in ("T", "summary_Strain") and abs(r) >= significant and abs(r) > floor:
                    worst_rel = max(worst_rel, float(err / abs(r)))
                if not err <= tol:
                    failures.append(
                        f"{q} at t = {result.t[i]!r}: FMU {float(got[i])!r}, reference {mpmath.nstr(r, 17)}, "
                        f"error {float(err):.3e} > tolerance {float(tol):.3e}"
                    )
        record_error(record_as or solver, case, worst_rel, worst_ratio)
        assert not failures, f"{case} [{solver}]: {len(failures)} points out of tolerance:\n" + "\n".join(failures[:8])
        return worst_rel


def method_allowance(ref_exact, ref_method, quantities, factor=1.01):
    """The truncation error of a fixed-step method, |method - exact| point by
    point, times `factor`: the tolerance of rk4/euler against the exact solution."""
    return {q: [factor * abs(a - b) for a, b in zip(ref_exact[q], ref_method[q])] for q in quantities}


def summary_lines():
    """The worst errors per solver: relative error of T and strain (points at
    >= 1 % of the run's largest value) and error/tolerance, with the cases."""
    names = list(SOLVERS) + sorted(set(WORST) - set(SOLVERS))
    width = max(len(n) for n in names)
    lines = [
        "worst relative error of T and strain (points >= 1 % of the run's largest), and worst error/tolerance",
        f"{'solver':{width}s} {'runs':>5s} {'rel. error':>10s}  {'case':44s} {'err/tol':>8s}  case",
    ]
    for name in names:
        if name in WORST:
            w = WORST[name]
            lines.append(f"{name:{width}s} {w['cases']:5d} {w['err']:10.2e}  {w['case'][:44]:44s} {w['ratio']:8.2e}  {w['ratio_case']}")
        else:
            lines.append(f"{name:{width}s} {'(not run)':>16s}")
    return lines
