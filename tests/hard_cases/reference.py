"""The hard-case catalogue's reference: one place that expands every case of
tests/hard_cases/catalogue.json into its schedule and computes what the model
must produce.

    .venv/bin/python tests/hard_cases/reference.py --write   # rewrites references.json
    .venv/bin/python tests/hard_cases/reference.py --check   # fails if references.json is stale

tests/hard_cases/references.json holds, per case, the expanded schedule (the
inputs at t = 0 and every communication step: its size, the inputs set at its
start, the input derivatives given for it), the reference outputs at t = 0 and
after each step, and per solver run the tolerance (relative, and an absolute
floor per quantity), the rk4/euler truncation allowance, the step at which the
run must be refused, and the data of the case's checks. tests/hard_cases.rs
(the model core) and tests/integration/python/test_hard_cases.py (the FMU through FMPy)
replay it; pytest also checks that it equals a fresh computation.

The reference is written from the physics (docs/physics.md), not from
the model's code:

* held inputs: the closed form of the linear balance dx/dt = q - lambda*x over
  each step, evaluated with mpmath at 40 digits;
* inputs that move within a step (derivatives given): SciPy's Radau on the
  offset y = x - x_k of the step, rtol = 1e-12 and an absolute tolerance of
  1e-16 m, restarted at every communication point (the inputs have kinks
  there) and split where web_a.v changes sign (a kink of the balance); the
  state is accumulated in mpmath so that no rounding piles up;
* rk4/euler on held inputs: n substeps of the method on the linear balance
  are exactly x_inf + (x - x_inf) R(-lambda h/n)^n with R its stability
  polynomial: the prediction whose distance from the exact solution is the
  truncation error the method is allowed; a step with lambda*h/n beyond the
  method's stability limit (2.785, 2 on the negative real axis) must be
  refused.

Outputs after a step are formed with the inputs at the end of the step and,
for the damping and web-mass terms, the input rates the model documents: the
given derivatives, or else backward differences over the previous
communication step (0 after the first step).
"""

from __future__ import annotations

import argparse
import json
import math
import sys
import xml.etree.ElementTree as ET
from decimal import ROUND_FLOOR, Decimal
from dataclasses import dataclass
from pathlib import Path

import mpmath
import numpy as np
from mpmath import mpf

ROOT = Path(__file__).resolve().parents[2]
# The data stay beside the tests that replay them (tests/hard_cases.rs reads them too).
CATALOGUE = ROOT / "tests" / "hard_cases" / "catalogue.json"
REFERENCES = ROOT / "tests" / "hard_cases" / "references.json"
MODEL_DESCRIPTION = ROOT / "modelDescription.xml"
COMMAND = ".venv/bin/python tests/hard_cases/reference.py --write"

DPS = 40
EXPLICIT_LIMIT = {"rk4": 2.785, "euler": 2.0}  # stability limits on the negative real axis

INPUTS = ("web_a.v", "web_a.eps", "web_b.v", "frame_a.x", "frame_a.y", "frame_b.x", "frame_b.y")
DEFAULT_QUANTITIES = ("T", "summary_Strain")


# --------------------------------------------------------------------------
# The model description: start values and the solver enumeration


def model_description(path=MODEL_DESCRIPTION):
    """(start values of the parameters and inputs, {solver name: value}),
    read from modelDescription.xml."""
    root = ET.parse(path).getroot()
    start = {}
    for v in root.iter("ScalarVariable"):
        if v.get("causality") not in ("parameter", "input"):
            continue
        t = next(iter(v))
        s = t.get("start")
        if s is None:
            continue
        convert = {"Real": float, "Boolean": lambda x: x.lower() in ("true", "1"), "String": str}.get(t.tag, int)
        start[v.get("name")] = convert(s)
    solvers = None
    for st in root.iter("SimpleType"):
        if st.get("name") == "Solver":
            solvers = {item.get("name"): int(item.get("value")) for item in st.iter("Item")}
    assert solvers, "modelDescription.xml declares no Solver enumeration"
    return start, solvers


# --------------------------------------------------------------------------
# Schedules


@dataclass
class Step:
    h: float
    u: dict  # every input over the step (at its start)
    du: dict | None = None  # derivatives given for the step; None: inputs held


def _advance(u, du, h):
    """The inputs at the end of a step along its ramp."""
    return {n: u[n] + du.get(n, 0.0) * h for n in INPUTS}


def _lambda(p, u):
    """lambda = (v_b - min(v_a, 0))/L: the decay rate of the balance."""
    L = math.hypot(u["frame_b.x"] - u["frame_a.x"], u["frame_b.y"] - u["frame_a.y"]) if p["variableLength"] else p["L"]
    return (u["web_b.v"] - min(u["web_a.v"], 0.0)) / L


def _step_size(h, p, u):
    if isinstance(h, dict):
        solver = h["of_stability_limit"]
        return EXPLICIT_LIMIT[solver] * p["substeps"] / _lambda(p, u) * h["fraction"]
    return float(h)


def six_decades(u, seed, derivatives):
    """300 steps with sizes log-uniform in [1e-6, 1] s (seeded). Held: the
    inputs jump at random steps (draws, eps_a, line speed). With derivatives:
    the speeds ramp, the slopes changing at random steps (the inputs stay
    continuous)."""
    rng = np.random.default_rng(seed)
    steps = []
    slope = {"web_a.v": 0.0, "web_b.v": 0.0}
    for _ in range(300):
        if rng.random() < 0.1:
            va = 5.0 + rng.uniform(-0.5, 0.5)
            if derivatives:
                a = rng.uniform(-0.5, 0.5)
                slope = {"web_a.v": a, "web_b.v": a * (1 + rng.uniform(-5e-4, 3e-3)) + rng.uniform(-0.01, 0.01)}
            else:
                u = {**u, "web_a.v": va, "web_b.v": va * (1 + rng.uniform(-5e-4, 3e-3)), "web_a.eps": rng.uniform(0, 2e-3)}
        h = float(10 ** rng.uniform(-6, 0))
        steps.append(Step(h, dict(u), dict(slope) if derivatives else None))
        if derivatives:
            u = _advance(u, slope, h)
    hs = [s.h for s in steps]
    assert min(hs) < 3e-6 and max(hs) > 0.3
    return steps, u


GENERATORS = {"six decades": six_decades}


def expand_steps(segments, p, initial, h_default=None):
    """The catalogue's segments as a list of Steps (see catalogue.json's `about`)."""
    u = dict(initial)
    t = 0.0
    steps = []
    for seg in segments:
        u = {**u, **seg.get("set", {})}
        h = seg.get("h", h_default)
        if "hold" in seg:
            h = _step_size(h, p, u)
            steps += [Step(h, dict(u)) for _ in range(seg["hold"])]
            t += seg["hold"] * h
        elif "ramp" in seg:
            h = _step_size(h, p, u)
            rate = seg.get("rate") or {n: c / h for n, c in seg["change"].items()}
            for _ in range(seg["ramp"]):
                steps.append(Step(h, dict(u), dict(rate)))
                u = _advance(u, rate, h)
                t += h
        elif "sample" in seg:
            start = dict(u)
            for k in range(seg["sample"]):
                u = {**start, **{n: start[n] + r * k * h for n, r in seg["rate"].items()}}
                steps.append(Step(h, dict(u)))
                t += h
        elif "oscillate" in seg:
            w = 2 * math.pi * seg["frequency"]

            def at(time):
                return {n: f.get("mean", 0.0) + f.get("sin", 0.0) * math.sin(w * time) + f.get("cos", 0.0) * math.cos(w * time)
                        for n, f in seg["inputs"].items()}

            for k in range(seg["oscillate"]):
                a, b = at(t + k * h), at(t + (k + 1) * h)
                u = {**u, **a}
                steps.append(Step(h, dict(u), {n: (b[n] - a[n]) / h for n in a} if seg["derivatives"] else None))
            t += seg["oscillate"] * h
            if seg["derivatives"]:
                u = _advance(u, steps[-1].du, h)
        elif "generate" in seg:
            more, u = GENERATORS[seg["generate"]](u, seg["seed"], seg["derivatives"])
            steps += more
            t += sum(s.h for s in more)
        else:
            raise ValueError(f"unknown segment {seg}")
    return steps


def compress(initial, steps):
    """The schedule as stored: {n, h, set, du}, `set` the inputs that differ
    from the previous step's start (set at the entry's first step), `du` the
    derivatives given for each of its steps; n omitted where 1."""
    out = []
    prev = initial
    for s in steps:
        changed = {n: s.u[n] for n in INPUTS if s.u[n] != prev[n]}
        last = out[-1] if out else None
        if last and not changed and s.du is None and "du" not in last and last["h"] == s.h:
            last["n"] = last.get("n", 1) + 1
        else:
            e = {"h": s.h}
            if changed:
                e["set"] = changed
            if s.du is not None:
                e["du"] = dict(s.du)
            out.append(e)
        prev = s.u
    return out


def decompress(initial, entries):
    """The Steps of a stored schedule (the inverse of `compress`)."""
    u = dict(initial)
    steps = []
    for e in entries:
        u = {**u, **e.get("set", {})}
        steps += [Step(e["h"], dict(u), e.get("du")) for _ in range(e.get("n", 1))]
    return steps


# --------------------------------------------------------------------------
# The reference solution


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
    return {"E": E, "EA": E * th * w, "A": th * w, "rho_l": rho * th * w, "d_r": mpf(p[f"{prefix}.d_r"])}


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
    if lam == 0:
        return x + q * h
    x_inf = q / lam
    if method is None:
        return x_inf + (x - x_inf) * mpmath.exp(-lam * h)
    name, n = method
    z = -lam * h / n
    R = 1 + z if name == "euler" else 1 + z + z**2 / 2 + z**3 / 6 + z**4 / 24
    return x_inf + (x - x_inf) * R**n


def _moving_step(p, u, du, x, h):
    """Radau over one step with inputs moving linearly; x in mpmath, the
    integration on the offset y = x(t) - x (float)."""
    from scipy.integrate import solve_ivp

    u0 = {n: float(u[n]) for n in INPUTS}
    r = {n: float(du.get(n, 0.0)) for n in INPUTS}
    xf = float(x)
    lo = float(x - mpf(xf))  # what float(x) leaves out; carried in y

    def at(t):
        return {n: u0[n] + r[n] * t for n in INPUTS}

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


def reference(p, initial, steps, method=None):
    """Reference outputs at t = 0 and after each step (lists of mpf).
    method: None (exact), or ("rk4"|"euler", substeps) for the prediction of that
    fixed-step method on held inputs (its stability function, see _held_step)."""
    with mpmath.workdps(DPS):
        x = initial_state(p, initial)
        ref = {}

        def record(u, x, rates):
            for n, v in outputs(p, u, x, rates).items():
                ref.setdefault(n, []).append(v)

        record(initial, x, {"vb": mpf(0), "L": mpf(0)})
        prev = None  # (inputs at the start of the previous step, its size)
        for s in steps:
            u = s.u
            moving = s.du is not None and any(v != 0.0 for v in s.du.values())
            if moving:
                assert method is None, "the fixed-step prediction covers held inputs only"
                x = _moving_step(p, u, s.du, x, s.h)
            else:
                x = _held_step(u, _length(p, u), x, s.h, method)
            end = _advance(u, s.du or {}, s.h)
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


def refused_step(p, solver, steps):
    """The first step a fixed-step explicit method must refuse (lambda*h/substeps
    beyond its stability limit anywhere in the step), or None."""
    if solver not in EXPLICIT_LIMIT:
        return None
    for k, s in enumerate(steps):
        if s.du is None:
            lam = _lambda(p, s.u)
        else:
            lam = max(_lambda(p, _advance(s.u, s.du, t)) for t in np.linspace(0.0, s.h, 1001))
        if lam * s.h / p["substeps"] > EXPLICIT_LIMIT[solver]:
            return k
    return None


# --------------------------------------------------------------------------
# The catalogue, its tolerances and checks


def floor_units(p):
    """What one unit of strain floor is for each quantity (see the catalogue's `floor`)."""
    with mpmath.workdps(DPS):
        w2 = _web(p, "wp2")
        L = mpf(p["L"])
        units = {"T": w2["EA"], "web_a.F": w2["EA"], "web_b.F": w2["EA"], "summary_Tension": w2["EA"],
                 "summary_Stress": w2["E"], "web_b.eps": 1, "summary_Strain": 1, "m_web": w2["rho_l"] * L,
                 "unstretchedLength": L, "summary_Length": L, "v": 1}
        return {q: float(u) for q, u in units.items()}


def _resolve_check(check, ref, p, steps, n_points):
    """A catalogue check with what it needs from the reference filled in."""
    c = dict(check)
    kind = c["check"]
    if kind == "constant" and c["to"] < 0:
        c["to"] += n_points
    elif kind == "zero_where_slack":
        slack = [i for i in range(1, n_points) if ref[c["quantity"]][i] == 0]
        assert slack, "the reference goes slack"
        below = c["strain_below"]
        c = {"check": "zero_at", "quantity": c["quantity"],
             "points": [i for i in slack if ref["summary_Strain"][i] < below]}
    elif kind == "difference_above":
        a = c["above"]
        c["above"] = float(ref[a["reference"]][c["point"]] * mpf(a["times"]))
    elif kind == "inertia":
        with mpmath.workdps(DPS):
            rho1, rho2 = _web(p, "wp1")["rho_l"], _web(p, "wp2")["rho_l"]
            flux = []
            for k in c["points"]:
                u = steps[k - 1].u  # held over the step that ends at point k
                va, ea, vb = mpf(u["web_a.v"]), mpf(u["web_a.eps"]), mpf(u["web_b.v"])
                flux.append(float(va / (1 + ea) * (rho2 * vb - rho1 * va)))
        c["flux"] = flux
    elif kind in ("damping_dominates", "damping_term"):
        EA = p["wp2.E"] * p["wp2.thickness"] * p["wp2.width"]
        c["EA"] = EA
        if kind == "damping_term":
            with mpmath.workdps(DPS):
                term = [t - mpf(EA) * e for t, e in zip(ref["T"], ref["summary_Strain"])]
                assert max(abs(t) for t in term) > c.pop("at_least_of_T") * max(abs(t) for t in ref["T"]), \
                    "the damping term must be far above the tolerance"
                c["term"] = [float(t) for t in term]
    return c


def expand_catalogue(catalogue, start, solvers):
    """The cases of the catalogue, one per step size where a case has `for_each_h`."""
    for case in catalogue["cases"]:
        for h in case.get("for_each_h", [None]):
            c = dict(case)
            c.pop("for_each_h", None)
            if h is not None:
                c["name"] = f"{case['name']}, h = {h:g}"
            c["h"] = h
            yield c


def compute_case(case, catalogue, start, solver_values):
    tol_param = catalogue["tolerance_parameter"]
    overrides = {}
    for k, v in case.get("parameters", {}).items():
        if k == "$set":
            overrides.update(catalogue["parameter_sets"][v])
        else:
            overrides[k] = v
    overrides["tolerance"] = tol_param
    p = {**start, **overrides}
    initial = {n: float(start[n]) for n in INPUTS}
    initial.update(case.get("initial", {}))
    steps = expand_steps(case["steps"], p, initial, case["h"])
    quantities = case.get("quantities", list(DEFAULT_QUANTITIES))
    ref = reference(p, initial, steps)
    n_points = len(steps) + 1
    moving = any(s.du is not None for s in steps)
    units = floor_units(p)
    with mpmath.workdps(DPS):
        largest_strain = float(max(abs(e) for e in ref["summary_Strain"]))
    solvers = case["solvers"]
    if isinstance(solvers, str):
        solvers = catalogue["solver_sets"][solvers]
    runs = []
    for solver in solvers:
        ps = {**p, **case.get("solver_parameters", {}).get(solver, {}), "solver": solver_values[solver]}
        run = {"solver": solver, "parameters": {**case.get("solver_parameters", {}).get(solver, {}),
                                                 "solver": solver_values[solver]}}
        refused = case.get("refused", {}).get(solver, refused_step(ps, solver, steps))
        if refused is not None:
            run["refused_at"] = refused
            run["message"] = catalogue["refusal_message"][solver]
            runs.append(run)
            continue
        rule = catalogue["tolerances"]["moving" if moving else "held"][solver]
        floor = rule.get("floor", 0.0) + rule.get("floor_of_largest_strain", 0.0) * largest_strain
        run["rel"] = rule["rel"]
        run["floor"] = {q: floor * units[q] * case.get("floor_factor", {}).get(q, 1) for q in quantities}
        if "method_error_factor" in rule:
            predicted = reference(ps, initial, steps, method=(solver, ps["substeps"]))
            with mpmath.workdps(DPS):
                run["allowance"] = {q: [_down(rule["method_error_factor"] * abs(a - b)) for a, b in zip(ref[q], predicted[q])]
                                    for q in quantities}
        runs.append(run)
    checks = [_resolve_check(c, ref, p, steps, n_points) for c in case.get("checks", [])]
    out = {
        "name": case["name"],
        "group": case["group"],
        "parameters": overrides,
        "initial": initial,
        "steps": compress(initial, steps),
        "quantities": quantities,
        "reference": {q: [float(v) for v in ref[q]] for q in quantities},
        "runs": runs,
    }
    if checks:
        out["checks"] = checks
    if "report_as" in case:
        out["report_as"] = case["report_as"]
    return out


def _down(x):
    """x rounded down to 4 significant digits: a stored allowance is never
    larger than the one computed (at most 0.1 % smaller), and short."""
    if x == 0:
        return 0.0
    d = Decimal(mpmath.nstr(x, 20, strip_zeros=False, min_fixed=1, max_fixed=0))
    e = d.adjusted() - 3
    y = float(d.quantize(Decimal(1).scaleb(e), rounding=ROUND_FLOOR))
    return y if y <= x else math.nextafter(y, 0.0)


def check_tolerance_rule(catalogue):
    """The catalogue's numbers are the rule its `why` states."""
    tol = catalogue["tolerance_parameter"]
    g = tol ** (2 / 3)
    t = catalogue["tolerances"]
    for solver in ("rosenbrock",):
        assert t["held"][solver]["rel"] == g == t["held"][solver]["floor_of_largest_strain"]
    for solver in ("auto", "rosenbrock"):
        assert t["moving"][solver]["rel"] == g == t["moving"][solver]["floor_of_largest_strain"]
    for kind in ("held", "moving"):
        assert t[kind]["dopri5"]["rel"] == 100 * tol == t[kind]["dopri5"]["floor_of_largest_strain"]


def compute(catalogue_path=CATALOGUE, only=None):
    """Every case's stored form (see the module docstring); `only`: a set of names."""
    catalogue = json.loads(Path(catalogue_path).read_text())
    check_tolerance_rule(catalogue)
    start, solver_values = model_description()
    cases = []
    for case in expand_catalogue(catalogue, start, solver_values):
        if only is None or case["name"] in only:
            cases.append(compute_case(case, catalogue, start, solver_values))
    return {"generated_by": COMMAND, "cases": cases}


def dumps(data):
    """One case per line group: readable diffs, small file."""
    lines = ['{"generated_by": ' + json.dumps(data["generated_by"]) + ', "cases": [']
    for i, c in enumerate(data["cases"]):
        lines.append(json.dumps(c, separators=(",", ":")) + ("," if i + 1 < len(data["cases"]) else ""))
    lines.append("]}")
    return "\n".join(lines) + "\n"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", action="store_true", help="rewrite references.json")
    ap.add_argument("--check", action="store_true", help="fail if references.json differs from a fresh computation")
    args = ap.parse_args()
    data = compute()
    text = dumps(data)
    if args.write:
        REFERENCES.write_text(text)
        print(f"wrote {REFERENCES} ({len(text) / 1e6:.2f} MB, {len(data['cases'])} cases, "
              f"{sum(len(c['runs']) for c in data['cases'])} runs)")
    if args.check:
        if REFERENCES.read_text() != text:
            sys.exit(f"{REFERENCES} is stale: run {COMMAND}")
        print("references.json is up to date")


if __name__ == "__main__":
    main()
