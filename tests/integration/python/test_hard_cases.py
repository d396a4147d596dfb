"""The hard-case catalogue through the packaged FMU (FMPy's FMU2Slave).

Every case is defined once in tests/hard_cases/catalogue.json. Its schedule,
its reference (mpmath closed forms, SciPy's Radau, the rk4/euler stability
polynomials: tests/hard_cases/reference.py, written from the physics, not
from the FMU's code) and each solver run's tolerance are stored in
tests/hard_cases/references.json; tests/hard_cases.rs replays the same file
through the model core. Here:

* `test_references_are_fresh`: references.json equals a fresh computation
  from the catalogue (bit for bit; where inputs move within steps, Radau's
  numbers to 1e-12 of their scale, far inside every tolerance, so that a
  SciPy release does not count as a change);
* `test_case`: each case and solver run through the FMU. At every point every
  output finite and the unstretched length > 0; each compared quantity within
  |FMU - ref| <= rel*|ref| + floor (+ the rk4/euler allowance), the rule and
  its reasons stated in the catalogue; a run the reference says must be
  refused answers fmi2Discard on that step with the catalogue's message,
  outputs unchanged and fmi2LastSuccessfulTime at the step's start; then the
  case's checks;
* two cases that only FMPy has: the input table through `simulate_fmu`;
* `test_case_fmi3`: each run again through the FMI 3.0 FMU (out/fmi3/), whose
  every output at every point must equal the FMI 2.0 run's bit for bit (so it
  passes the same checks); runs that set input derivatives are skipped there,
  FMI 3.0 has no fmi2SetRealInputDerivatives.

A summary of the worst error per solver ends the run.
"""

import importlib.util
import json
import math
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pytest
from fmpy import extract, read_model_description
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2Discard, fmi2LastSuccessfulTime
from fmpy.simulation import instantiate_fmu

from conftest import simulate_fmu  # (the FMI 2.0 FMU, then its FMI 3.0 twin: bit-identical)

ROOT = Path(__file__).resolve().parents[3]
# The oracle, beside the catalogue and the references it writes.
_spec = importlib.util.spec_from_file_location("hard_cases_reference", ROOT / "tests" / "hard_cases" / "reference.py")
R = sys.modules["hard_cases_reference"] = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(R)

STORED = json.loads(R.REFERENCES.read_text())
CATALOGUE = json.loads(R.CATALOGUE.read_text())
START, SOLVER_VALUES = R.model_description()
OUTPUTS = ("v", "T", "web_a.F", "web_b.F", "web_b.eps", "summary_Tension", "summary_Length",
           "summary_Strain", "summary_Stress", "m_web", "unstretchedLength")


# --------------------------------------------------------------------------
# The packaged FMU through FMPy


class Log:
    """Logger for FMPy's callback (messages arrive formatted by FMPy's proxy)."""

    def __init__(self):
        self.messages = []

    def __call__(self, component, instance, status, category, message):
        self.messages.append(message.decode())

    def text(self):
        return "\n".join(self.messages)


@dataclass
class Discard:
    step: int  # index of the refused step
    time: float  # its communication point
    before: dict  # outputs before the step
    after: dict  # outputs read after the refusal
    last_successful_time: float
    message: str


@dataclass
class Result:
    t: np.ndarray
    out: dict  # name -> array over the points (t = 0 and after each step)
    discard: Discard | None = None


class Fmu:
    """The packaged FMU, unzipped; runs a stored schedule."""

    def __init__(self, fmu_path, unzipdir):
        self.md = read_model_description(str(fmu_path))
        self.unzipdir = unzipdir
        self.var = {v.name: v for v in self.md.modelVariables}

    def _set(self, fmu, values):
        for name, value in values.items():
            v = self.var[name]
            if v.type == "Real":
                fmu.setReal([v.valueReference], [float(value)])
            elif v.type == "Boolean":
                fmu.setBoolean([v.valueReference], [bool(value)])
            else:
                fmu.setInteger([v.valueReference], [int(value)])

    def run(self, parameters, initial, entries):
        """Every output at t = 0 and after each step. A step refused with
        fmi2Discard ends the run (recorded in `discard`); any other failure raises."""
        log = Log()
        fmu = instantiate_fmu(self.unzipdir, self.md, "CoSimulation", logger=log)
        out_vrs = [self.var[n].valueReference for n in OUTPUTS]
        rows, times, discard, last = [], [0.0], None, None
        try:
            fmu.setupExperiment(startTime=0.0)
            self._set(fmu, parameters)
            self._set(fmu, initial)
            fmu.enterInitializationMode()
            fmu.exitInitializationMode()
            rows.append(fmu.getReal(out_vrs))
            t, k = 0.0, 0
            for s in (e for e in entries for _ in range(e.get("n", 1))):
                # the inputs that change at the entry's first step (none along a held segment)
                self._set(fmu, s.get("set", {}) if s is not last else {})
                last = s
                if "du" in s:
                    names = list(s["du"])
                    fmu.setRealInputDerivatives([self.var[n].valueReference for n in names], [1] * len(names),
                                                [s["du"][n] for n in names])
                try:
                    fmu.doStep(t, s["h"])
                except FMICallException as e:
                    if e.status != fmi2Discard:
                        raise AssertionError(f"step {k} at t = {t} with h = {s['h']}: status {e.status}\n{log.text()}") from e
                    discard = Discard(k, t, dict(zip(OUTPUTS, rows[-1])), dict(zip(OUTPUTS, fmu.getReal(out_vrs))),
                                      fmu.getRealStatus(fmi2LastSuccessfulTime), log.text())
                    break
                t += s["h"]
                k += 1
                times.append(t)
                rows.append(fmu.getReal(out_vrs))
        finally:
            fmu.freeInstance()
        arr = np.array(rows, dtype=float)
        return Result(np.array(times), {n: arr[:, i] for i, n in enumerate(OUTPUTS)}, discard)


class Fmu3(Fmu):
    """The FMI 3.0 FMU: the same schedule through FMPy's FMU3Slave."""

    def _set(self, fmu, values):
        for name, value in values.items():
            v = self.var[name]
            setter = {"Float64": fmu.setFloat64, "Boolean": fmu.setBoolean, "Enumeration": fmu.setInt64,
                      "Int32": fmu.setInt32}[v.type]
            setter([v.valueReference], [bool(value) if v.type == "Boolean" else value if v.type == "Float64" else int(value)])

    def run(self, parameters, initial, entries):
        messages = []
        fmu = instantiate_fmu(self.unzipdir, self.md, "CoSimulation",
                              logger=lambda env, status, category, message: messages.append(message.decode()))
        out_vrs = [self.var[n].valueReference for n in OUTPUTS]
        time_vr = self.var["time"].valueReference
        rows, times, discard, last = [], [0.0], None, None
        try:
            self._set(fmu, parameters)
            self._set(fmu, initial)
            fmu.enterInitializationMode(startTime=0.0)
            fmu.exitInitializationMode()
            rows.append(fmu.getFloat64(out_vrs))
            t, k = 0.0, 0
            for s in (e for e in entries for _ in range(e.get("n", 1))):
                self._set(fmu, s.get("set", {}) if s is not last else {})
                last = s
                try:
                    fmu.doStep(t, s["h"])
                except FMICallException as e:
                    if e.status != FMI3_DISCARD:
                        raise AssertionError(f"step {k} at t = {t}: status {e.status}\n" + "\n".join(messages)) from e
                    discard = Discard(k, t, dict(zip(OUTPUTS, rows[-1])), dict(zip(OUTPUTS, fmu.getFloat64(out_vrs))),
                                      fmu.getFloat64([time_vr])[0], "\n".join(messages))
                    break
                t += s["h"]
                k += 1
                times.append(t)
                rows.append(fmu.getFloat64(out_vrs))
        finally:
            fmu.freeInstance()
        arr = np.array(rows, dtype=float)
        return Result(np.array(times), {n: arr[:, i] for i, n in enumerate(OUTPUTS)}, discard)


FMI3_DISCARD = 2


@pytest.fixture(scope="module")
def span3(tmp_path_factory):
    from conftest import packaged

    fmu3 = packaged(ROOT / "out" / "fmi3" / "ConvertingSpan.fmu")
    return Fmu3(fmu3, extract(str(fmu3), unzipdir=str(tmp_path_factory.mktemp("hard_cases3"))))


@pytest.fixture(scope="module")
def span(fmu_path, tmp_path_factory):
    """The packaged FMU (conftest's fmu_path), unzipped once for this module."""
    return Fmu(fmu_path, extract(str(fmu_path), unzipdir=str(tmp_path_factory.mktemp("hard_cases"))))


# --------------------------------------------------------------------------
# Comparison, checks and the record of errors


WORST = {}  # row -> {"err", "case", "ratio", "ratio_case", "runs"}


def record(row, case, err, ratio):
    w = WORST.setdefault(row, {"err": 0.0, "case": "", "ratio": 0.0, "ratio_case": "", "runs": 0})
    w["runs"] += 1
    if err >= w["err"]:
        w["err"], w["case"] = err, case
    if ratio >= w["ratio"]:
        w["ratio"], w["ratio_case"] = ratio, case


def check_physical(res, what):
    """Every output finite at every point, the unstretched length > 0."""
    for name, values in res.out.items():
        bad = np.flatnonzero(~np.isfinite(values))
        assert bad.size == 0, f"{what}: {name} is not finite at t = {res.t[bad[0]]!r}: {values[bad[0]]!r}"
    x = res.out["unstretchedLength"]
    assert np.all(x > 0), f"{what}: unstretched length {x.min()} <= 0"


def compare(what, res, reference, quantities, rel, floor, allowance=None):
    """|FMU - ref| <= rel*|ref| + floor[q] (+ allowance[q]) at every point;
    returns the worst relative error of T and strain (points >= 1 % of the
    run's largest value) and the worst error/tolerance."""
    failures, worst, ratio = [], 0.0, 0.0
    for q in quantities:
        got, ref = res.out[q], np.array(reference[q])
        assert len(got) == len(ref), f"{what}: {len(got)} points, the reference has {len(ref)}"
        err = np.abs(got - ref)
        tol = rel * np.abs(ref) + floor[q] + (np.array(allowance[q]) if allowance else 0.0)
        ratio = max(ratio, float(np.max(np.where(tol > 0, err / np.where(tol > 0, tol, 1), np.where(err > 0, np.inf, 0)))))
        for i in np.flatnonzero(~(err <= tol)):
            failures.append(f"{q} at t = {res.t[i]!r}: FMU {got[i]!r}, reference {ref[i]!r}, "
                            f"error {err[i]:.3e} > tolerance {tol[i]:.3e}")
        if q in ("T", "summary_Strain"):
            big = (np.abs(ref) >= np.max(np.abs(ref)) / 100) & (np.abs(ref) > floor[q])
            if big.any():
                worst = max(worst, float(np.max(err[big] / np.abs(ref[big]))))
    assert not failures, f"{what}: {len(failures)} points out of tolerance:\n" + "\n".join(failures[:8])
    return worst, ratio


def run_check(c, res, ref, solver):
    """One of the catalogue's checks (resolved in references.json)."""
    o = res.out
    kind = c["check"]
    if kind == "constant":
        for q in c["quantities"]:
            v = o[q][c["from"]: c["to"] + 1]
            assert np.all(v == v[0]), f"{q} moved over points {c['from']}..{c['to']}"
    elif kind == "value":
        v = o[c["quantity"]][c["point"]]
        assert abs(v - c["equals"]) <= c["rel"] * abs(c["equals"]), f"{c['quantity']} at point {c['point']} = {v}"
    elif kind == "extremes":
        v = o[c["quantity"]]
        if "min_below" in c:
            assert v.min() < c["min_below"], f"{c['quantity']}: smallest {v.min()}"
        if "max_above" in c:
            assert v.max() > c["max_above"], f"{c['quantity']}: largest {v.max()}"
        if "last_above" in c:
            assert v[-1] > c["last_above"], f"{c['quantity']}: last {v[-1]}"
    elif kind == "at_least":
        assert np.all(o[c["quantity"]] >= c["value"]), f"{c['quantity']} below {c['value']}"
    elif kind == "zero_at":
        assert np.all(o[c["quantity"]][c["points"]] == 0.0), f"{c['quantity']} not 0 where the reference is well slack"
    elif kind == "some_point":
        hit = np.ones(len(res.t), dtype=bool)
        for q, a in c["above"].items():
            hit &= o[q] > a
        for q, b in c["below"].items():
            hit &= o[q] < b
        assert hit.any(), f"no point above {c['above']} and below {c['below']}"
    elif kind == "difference_above":
        a, b = c["quantities"]
        d = abs(o[a][c["point"]] - o[b][c["point"]])
        assert d > c["above"], f"|{a} - {b}| = {d} at point {c['point']}, not above {c['above']}"
    elif kind == "inertia":
        for k, flux in zip(c["points"], c["flux"]):
            inertia = o["web_b.F"][k] - o["T"][k] - flux
            want = o["m_web"][k] * c["slope"]
            assert abs(inertia - want) <= c["rel"] * abs(want), f"point {k}: inertia {inertia}, m dv/dt {want}"
    elif kind == "damping_dominates":
        T, eps, EA = o["T"][c["point"]], o["summary_Strain"][c["point"]], c["EA"]
        assert abs(T - EA * eps) > c["factor"] * abs(EA * (eps - c["strain_a"])), "the damping term does not dominate"
    elif kind == "damping_term":
        if solver in c["solvers"]:
            got = o["T"] - c["EA"] * o["summary_Strain"]
            for i in range(1, len(got)):
                term = c["term"][i]
                assert abs(got[i] - term) <= c["rel"] * abs(term) + c["of_T"] * abs(o["T"][i]), (i, got[i], term)
    else:
        raise AssertionError(f"unknown check {kind}")


# --------------------------------------------------------------------------
# The catalogue


RUNS = [(case, run) for case in STORED["cases"] for run in case["runs"]]


@pytest.mark.parametrize("case, run", RUNS, ids=[f"{c['name']} [{r['solver']}]" for c, r in RUNS])
def test_case(span, case, run):
    what = f"{case['name']} [{run['solver']}]"
    res = span.run({**case["parameters"], **run["parameters"]}, case["initial"], case["steps"])
    check_physical(res, what)
    if "refused_at" in run:
        d = res.discard
        assert d is not None, f"{what}: step {run['refused_at']} must be refused, was accepted"
        assert d.step == run["refused_at"], f"{what}: step {d.step} refused, expected {run['refused_at']}"
        for name in ("unstretchedLength", "summary_Strain", "T", "m_web", "summary_Length"):
            assert d.after[name] == d.before[name], f"{name} changed by a refused step: {d.before[name]} -> {d.after[name]}"
        assert d.last_successful_time == d.time
        assert run["message"] in d.message, d.message
        return
    assert res.discard is None, f"{what}: step {res.discard.step} refused: {res.discard.message}"
    worst, ratio = compare(what, res, case["reference"], case["quantities"], run["rel"], run["floor"], run.get("allowance"))
    record(case.get("report_as", run["solver"]), case["name"], worst, ratio)
    for c in case.get("checks", []):
        run_check(c, res, case["reference"], run["solver"])


@pytest.mark.parametrize("case, run", RUNS, ids=[f"{c['name']} [{r['solver']}]" for c, r in RUNS])
def test_case_fmi3(span, span3, case, run):
    if any("du" in s for s in case["steps"]):
        pytest.skip("sets input derivatives, which FMI 3.0 does not have")
    parameters = {**case["parameters"], **run["parameters"]}
    two = span.run(parameters, case["initial"], case["steps"])
    three = span3.run(parameters, case["initial"], case["steps"])
    assert three.t.tobytes() == two.t.tobytes()
    for name in OUTPUTS:
        assert three.out[name].tobytes() == two.out[name].tobytes(), name
    assert (three.discard is None) == (two.discard is None)
    if two.discard is not None:
        d2, d3 = two.discard, three.discard
        assert (d3.step, d3.time, d3.before, d3.after, d3.last_successful_time) == (
            d2.step, d2.time, d2.before, d2.after, d2.last_successful_time)
        assert run["message"] in d3.message and "fmi3DoStep" in d3.message, d3.message


def _same(a, b, loose, path="", scale=None):
    """a == b; with `loose`, numbers may differ by 1e-12 of their scale (the
    largest magnitude in their list)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), f"{path}: keys {sorted(a)} vs {sorted(b)}"
        for k in a:
            _same(a[k], b[k], loose, f"{path}.{k}")
    elif isinstance(a, list):
        assert isinstance(b, list) and len(a) == len(b), f"{path}: lengths differ"
        s = max((abs(x) for x in a if isinstance(x, float)), default=None)
        for i, (x, y) in enumerate(zip(a, b)):
            _same(x, y, loose, f"{path}[{i}]", s)
    elif isinstance(a, float) and loose:
        s = max(abs(a), scale or 0.0)
        assert abs(a - b) <= 1e-12 * s, f"{path}: stored {a!r}, fresh {b!r}"
    else:
        assert a == b, f"{path}: stored {a!r}, fresh {b!r}"


def test_references_are_fresh():
    """references.json is what the catalogue and the reference module give
    now: run the command in `generated_by` after changing either."""
    fresh = R.compute()
    assert [c["name"] for c in STORED["cases"]] == [c["name"] for c in fresh["cases"]], f"stale: run {R.COMMAND}"
    for stored, new in zip(STORED["cases"], fresh["cases"]):
        loose = any("du" in e for e in stored["steps"])
        _same(stored, new, loose, stored["name"])


# --------------------------------------------------------------------------
# Only through FMPy: input tables through simulate_fmu


def _catalogue_case(name):
    return next(c for c in CATALOGUE["cases"] if c["name"] == name)


def _parameters(*sets, **more):
    p = {}
    for s in sets:
        p.update(CATALOGUE["parameter_sets"][s])
    return {**p, **more, "tolerance": CATALOGUE["tolerance_parameter"]}


def _simulate(fmu_path, p, table, stop, interval):
    start = {k: v for k, v in p.items() if v != START.get(k)}
    return simulate_fmu(str(fmu_path), stop_time=stop, output_interval=interval, start_values=start, input=table,
                        output=list(OUTPUTS))


def _reference_for(p, initial, steps, result, quantities, rel, floor_strain, what):
    res = Result(result["time"], {n: result[n] for n in OUTPUTS})
    check_physical(res, what)
    full = {**START, **p}
    ref = R.reference(full, initial, steps)
    units = R.floor_units(full)
    reference = {q: [float(v) for v in ref[q]] for q in quantities}
    worst, ratio = compare(what, res, reference, quantities, rel, {q: floor_strain * units[q] for q in quantities})
    record("auto", what, worst, ratio)


def test_web_mass_held_ramp_through_simulate_fmu(fmu_path):
    """The web-mass acceleration as an input table through fmpy.simulate_fmu:
    FMPy interpolates the table at each communication point and holds the
    value over the step, so web_b.F takes dv_b/dt from the backward
    differences. (FMPy 0.3.32's set_input_derivatives=True cannot drive this
    FMU: its Input class allocates derivative buffers for exactly 9 inputs and
    raises ValueError for 7; input derivatives go through FMU2Slave in the
    catalogue.) Reference: closed form with the values FMPy sets (its own
    interpolation formula); tolerance 1e-12 + 1e-15 of strain (exact step)."""
    p = _parameters("mass")
    v0, v1 = (2.0, 1e-3, 2.004), (6.0, 1e-3, 6.012)
    names = ("web_a.v", "web_a.eps", "web_b.v")
    frames = {n: START[n] for n in R.INPUTS if n.startswith("frame")}
    table = np.array([(0.0, *v0, *frames.values()), (1.0, *v1, *frames.values())],
                     dtype=[("time", float)] + [(n, float) for n in names + tuple(frames)])
    result = _simulate(fmu_path, p, table, 1.0, 0.01)
    t = result["time"]
    u0 = {**{n: START[n] for n in R.INPUTS}, **dict(zip(names, v0))}
    steps = []
    for a, b in zip(t[:-1], t[1:]):
        w0 = (1.0 - a) / 1.0
        w1 = 1 - w0
        steps.append(R.Step(float(b - a), {**u0, **{n: w0 * x0 + w1 * x1 for n, x0, x1 in zip(names, v0, v1)}}))
    _reference_for(p, u0, steps, result, ("T", "summary_Strain", "web_b.F", "m_web"), 1e-12, 1e-15,
                   "web mass, held ramp via simulate_fmu")


def test_large_step_change_in_every_input_through_simulate_fmu(fmu_path):
    """The catalogue's step in every input as an input table (a repeated time
    is a step) through fmpy.simulate_fmu, solver auto: FMPy makes the step
    times communication points and holds the inputs. Tolerance 1e-12 + 2e-15
    of strain (exact step)."""
    case = _catalogue_case("a step in every input at once")
    p = _parameters("mass", includeDamping=True, variableLength=True)
    u0 = {**{n: START[n] for n in R.INPUTS}, **case["initial"]}
    u1 = {**u0, **case["steps"][1]["set"]}
    u2 = {**u1, **case["steps"][2]["set"]}
    rows = [(0.0, *[u0[n] for n in R.INPUTS]), (0.1, *[u0[n] for n in R.INPUTS]),
            (0.1, *[u1[n] for n in R.INPUTS]), (0.5, *[u1[n] for n in R.INPUTS]),
            (0.5, *[u2[n] for n in R.INPUTS]), (0.9, *[u2[n] for n in R.INPUTS])]
    table = np.array(rows, dtype=[("time", float)] + [(n, float) for n in R.INPUTS])
    result = _simulate(fmu_path, p, table, 0.9, 2e-3)
    t = result["time"]
    steps = [R.Step(float(b - a), dict(u0 if a < 0.1 - 1e-9 else (u1 if a < 0.5 - 1e-9 else u2)))
             for a, b in zip(t[:-1], t[1:])]
    _reference_for(p, u0, steps, result, ("T", "summary_Strain", "web_b.F", "m_web", "summary_Length"), 1e-12, 2e-15,
                   "step in every input (simulate_fmu)")


# --------------------------------------------------------------------------
# The summary (a terminal section at the end of the run)


def summary_lines():
    names = list(SOLVER_VALUES) + sorted(set(WORST) - set(SOLVER_VALUES))
    width = max(len(n) for n in names)
    lines = [
        "worst relative error of T and strain (points >= 1 % of the run's largest), and worst error/tolerance",
        f"{'solver':{width}s} {'runs':>5s} {'rel. error':>10s}  {'case':44s} {'err/tol':>8s}  case",
    ]
    for name in names:
        if name in WORST:
            w = WORST[name]
            lines.append(f"{name:{width}s} {w['runs']:5d} {w['err']:10.2e}  {w['case'][:44]:44s} {w['ratio']:8.2e}  {w['ratio_case']}")
        else:
            lines.append(f"{name:{width}s} {'(not run)':>16s}")
    return lines


class _Summary:
    def pytest_terminal_summary(self, terminalreporter):
        if WORST:
            terminalreporter.section("hard cases: worst relative error of T and strain per solver")
            for line in summary_lines():
                terminalreporter.write_line(line)


@pytest.fixture(scope="module", autouse=True)
def _print_worst_errors(request):
    pm = request.config.pluginmanager
    if not pm.has_plugin("hard_cases_summary"):
        pm.register(_Summary(), "hard_cases_summary")
    yield
