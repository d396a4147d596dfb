"""Shared fixtures (the packaged FMUs from fmu/packaged.py) and the exact reference solution
for the FMU tests.

The reference is computed with mpmath at 40 significant digits from the
closed-form solution of the span's material balance with piecewise-constant
inputs. It is written from the physics (documentation, equations [E1]-[E8]),
not from the FMU's code: it integrates the input table piece by piece and
evaluates the state at any time, independently of the communication steps
the importer takes.
"""

import sys
from dataclasses import dataclass
from pathlib import Path

import mpmath
import numpy as np
import pytest
from mpmath import mpf


# FMPy 0.3.32 routes every logger through one process-wide C proxy that
# simulate_fmu(..., logger=f) and instantiate_fmu(..., logger=f) re-point at a
# ctypes thunk they create and then drop; once it is freed, the next FMU that
# logs through FMPy's default callbacks crashes the process. Keep every thunk
# alive for the test session.
import fmpy.simulation as _fmpy_simulation

_KEPT_LOGGERS = []
_make_logger = _fmpy_simulation.fmi2CallbackLoggerTYPE


def _kept_logger(function):
    thunk = _make_logger(function)
    _KEPT_LOGGERS.append(thunk)
    return thunk


_fmpy_simulation.fmi2CallbackLoggerTYPE = _kept_logger

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "fmu"))
from packaged import FMU, fmu_path, fmus, packaged  # noqa: E402, F401 (fmu_path and fmus are fixtures)

INPUTS = ("web_a.v", "web_a.eps", "web_b.v")
DPS = 40

# --------------------------------------------------------------------------
# Fixtures


@pytest.fixture(scope="session")
def model_description(fmu_path):
    from fmpy import read_model_description

    return read_model_description(str(fmu_path))


@pytest.fixture(scope="session")
def unzipdir(fmu_path, tmp_path_factory):
    """The FMU extracted once; simulate_fmu and FMU2Slave both accept it."""
    from fmpy import extract

    return extract(str(fmu_path), unzipdir=str(tmp_path_factory.mktemp("fmu")))


@pytest.fixture(scope="session")
def defaults(model_description):
    """Start values of every variable from the model description, as Python values."""
    return start_values(model_description)


def start_values(model_description):
    values = {}
    for v in model_description.modelVariables:
        if v.start is None:
            continue
        if v.type == "Real":
            values[v.name] = float(v.start)
        elif v.type == "Boolean":
            values[v.name] = str(v.start).lower() in ("true", "1")
        elif v.type == "String":
            values[v.name] = v.start
        else:
            values[v.name] = int(v.start)
    return values


# --------------------------------------------------------------------------
# Every scene twice: the FMI 2.0 FMU and its FMI 3.0 twin (out/fmi3/)

_FMI3_UNZIPPED = {}


def fmi3_twin(fmi2):
    """The unzipped FMI 3.0 FMU of the FMI 2.0 FMU (a .fmu or its unzipped folder) `fmi2`."""
    import xml.etree.ElementTree as ET
    from fmpy import extract

    path = Path(fmi2)
    name = ET.parse(path / "modelDescription.xml").getroot().get("modelName") if path.is_dir() else path.stem
    if name not in _FMI3_UNZIPPED:
        _FMI3_UNZIPPED[name] = extract(str(packaged(ROOT / "out" / "fmi3" / f"{name}.fmu")))
    return _FMI3_UNZIPPED[name]


def simulate_fmu(filename, **kw):
    """FMPy's simulate_fmu on the FMI 2.0 FMU, then the same call on its FMI
    3.0 twin: every recorded value must be bit-identical (the same model code
    behind both APIs), and a call the FMI 2.0 FMU refuses the twin refuses
    too. Returns the FMI 2.0 result."""
    from fmpy import simulate_fmu as fmpy_simulate

    twin_kw = dict(kw)
    # FMI 3.0's logger takes other arguments; the twin's messages are kept apart.
    twin_log = []
    twin_kw["logger"] = lambda env, status, category, message: twin_log.append(message.decode())
    try:
        two = fmpy_simulate(filename, **kw)
    except Exception as refused:
        with pytest.raises(type(refused)):
            fmpy_simulate(fmi3_twin(filename), **twin_kw)
        raise
    three = fmpy_simulate(fmi3_twin(filename), **twin_kw)
    assert two.dtype.names == three.dtype.names
    for name in two.dtype.names:
        assert two[name].tobytes() == three[name].tobytes(), (
            f"FMI 3.0 differs from FMI 2.0 in {name}: first at row "
            f"{int(np.argmax(two[name] != three[name]))} of {len(two)}\n" + "\n".join(twin_log[-5:])
        )
    return two


# --------------------------------------------------------------------------
# Input tables


def step_table(stop, initial, steps=()):
    """A piecewise-constant input table in FMPy's format.

    initial: {input name: value} at t = 0 (all three inputs);
    steps:   [(time, {input name: new value}), ...], in time order.
    A step is two rows at the same time (old value, new value), which FMPy
    treats as an event and makes a communication point.
    """
    assert set(initial) == set(INPUTS)
    current = dict(initial)
    rows = [(0.0, *[current[n] for n in INPUTS])]
    for t, change in steps:
        rows.append((float(t), *[current[n] for n in INPUTS]))
        current.update(change)
        rows.append((float(t), *[current[n] for n in INPUTS]))
    rows.append((float(stop), *[current[n] for n in INPUTS]))
    dtype = [("time", np.float64)] + [(n, np.float64) for n in INPUTS]
    return np.array(rows, dtype=dtype)


@dataclass
class Piece:
    """Inputs held over [start, end)."""

    start: mpf
    end: mpf
    va: mpf
    ea: mpf
    vb: mpf


def input_pieces(table, fallback):
    """The pieces of a piecewise-constant table (rows with the same time are a
    step; between different times the values must be equal, or the table is
    not held and this reference does not apply). Inputs missing from the
    table take `fallback` (their start values)."""
    inf = mpmath.inf
    if table is None:
        return [Piece(-inf, inf, *[mpf(fallback[n]) for n in INPUTS])]
    t = table["time"]
    cols = [table[n] if n in table.dtype.names else np.full(len(t), fallback[n]) for n in INPUTS]
    rows = [tuple(float(c[i]) for c in cols) for i in range(len(t))]
    pieces = [Piece(-inf, mpf(float(t[0])), *map(mpf, rows[0]))]
    for i in range(len(t) - 1):
        if t[i + 1] == t[i]:
            continue  # a step: the next row starts the next piece
        assert t[i + 1] > t[i], "input table times must not decrease"
        assert rows[i] == rows[i + 1], f"inputs are not held between t = {t[i]} and {t[i + 1]}"
        pieces.append(Piece(mpf(float(t[i])), mpf(float(t[i + 1])), *map(mpf, rows[i])))
    pieces.append(Piece(mpf(float(t[-1])), inf, *map(mpf, rows[-1])))
    return pieces


# --------------------------------------------------------------------------
# The exact solution


def _piece_at(pieces, t):
    """The piece whose inputs are held at time t (t in [start, end))."""
    for p in pieces:
        if p.start <= t < p.end:
            return p
    return pieces[-1]


def _advance(L, piece, x, dt):
    """Closed form of dx/dt = v_a/(1+eps_a) - v_b*x/L over dt with held inputs
    (v_a >= 0: web enters at a with the upstream strain)."""
    assert piece.va >= 0, "the reference covers v_a >= 0 only"
    q = piece.va / (1 + piece.ea)
    lam = piece.vb / L
    if lam == 0:
        return x + q * dt
    x_inf = q / lam  # = L*v_a/(v_b*(1+eps_a))
    return x_inf + (x - x_inf) * mpmath.exp(-lam * dt)


def tension(p, x, piece):
    """Span tension [E5] for the unstretched length x and the inputs of `piece`."""
    L = mpf(p["L"])
    EA = mpf(p["wp2.E"]) * mpf(p["wp2.width"]) * mpf(p["wp2.thickness"])
    eps = L / x - 1
    effective = eps
    if p["includeDamping"]:
        dxdt = piece.va / (1 + piece.ea) - piece.vb * x / L
        deps_dt = -(L / x**2) * dxdt
        effective = eps + mpf(p["wp2.d_r"]) * deps_dt
    T = EA * effective
    if p["preventNegativeTension"] and T < 0:
        T = mpf(0)
    return T


def initial_strain(p, piece):
    """Start strain [E6]: steady state of the initial inputs, or eps_start."""
    if not p["startAtEquilibrium"]:
        return mpf(p["eps_start"])
    if piece.va == 0:
        return piece.ea
    return (piece.vb / piece.va) * (1 + piece.ea) - 1


def exact_solution(params, table, times, start_time=0.0):
    """The exact outputs at the communication points `times`.

    params: every parameter and input start value (e.g. `defaults` updated
    with the test's values); table: the input table (or None for the start
    values); times: the recorded communication points, in order, starting at
    start_time.

    The state is continuous: it is integrated piece by piece from the table.
    Outputs that feed through from the inputs (v; T with damping) use the
    inputs the importer held over the step that ends at the point (the inputs
    are applied at each step's start and read after the step), i.e. the piece
    containing the middle of the preceding interval; at the start point the
    initial inputs.

    Returns {"x", "strain", "tension", "v"} as lists of mpf (SI units).
    """
    with mpmath.workdps(DPS):
        pieces = input_pieces(table, params)
        L = mpf(params["L"])
        t0 = mpf(float(start_time))
        first = _piece_at(pieces, t0)
        x = L / (1 + initial_strain(params, first))
        t = t0
        out = {"x": [], "strain": [], "tension": [], "v": []}
        prev = None
        for tk in times:
            tk = mpf(float(tk))
            assert tk >= t, "output times must not decrease"
            # integrate piece by piece from t to tk
            while t < tk:
                piece = _piece_at(pieces, t)
                t_next = min(piece.end, tk)
                x = _advance(L, piece, x, t_next - t)
                t = t_next
            held = first if prev is None else _piece_at(pieces, (prev + tk) / 2)
            out["x"].append(x)
            out["strain"].append(L / x - 1)
            out["tension"].append(tension(params, x, held))
            out["v"].append(held.vb)
            prev = tk
        return out


# --------------------------------------------------------------------------
# Comparison with the tolerance, and a record of the errors seen

# Tolerance against the exact solution: 1e-12 relative plus an absolute floor.
# Why: the FMU's step is the closed-form solution for held inputs, so the
# only errors are floating-point roundings (a few ulps per step in the state,
# which the FMU carries as a compensated sum). The strain L/x - 1 amplifies a
# relative error of x by (1+eps)/eps, i.e. by 1e3 at eps = 1e-3, so an
# x accurate to ~1e-16 gives a strain accurate to ~1e-13; 1e-12 leaves a
# factor 10 for accumulation over up to 1e5 steps and for FMPy's linear
# interpolation of held inputs (w0*v + w1*v may differ from v by one ulp).
# Where the strain or the tension passes through zero a relative bound means
# nothing, so an absolute floor of 1e-15 in strain (about 5 ulps of x = L),
# i.e. 1e-15*E2*A2 in tension, is added.
REL_TOL = 1e-12
ABS_STRAIN = 1e-15

ERRORS = {}  # scenario -> {"max_rel": float, "max_ratio": float, "points": int}


def compare(scenario, name, got, ref, abs_floor, rel=REL_TOL, times=None):
    """Asserts |got - ref| <= rel*|ref| + abs_floor at every point and records
    the largest relative error (over points where |ref| > abs_floor)."""
    got = np.asarray(got, dtype=float)
    assert len(got) == len(ref), f"{scenario} {name}: {len(got)} points, reference has {len(ref)}"
    worst_rel = 0.0
    worst_ratio = 0.0
    failures = []
    with mpmath.workdps(DPS):
        for i, (g, r) in enumerate(zip(got, ref)):
            err = abs(mpf(float(g)) - r)
            tol = rel * abs(r) + mpf(abs_floor)
            ratio = float(err / tol) if tol > 0 else (0.0 if err == 0 else float("inf"))
            worst_ratio = max(worst_ratio, ratio)
            if abs(r) > abs_floor:
                worst_rel = max(worst_rel, float(err / abs(r)))
            if not err <= tol:
                at = f"t = {times[i]!r}" if times is not None else f"point {i}"
                failures.append(f"{at}: FMU {float(g)!r}, exact {mpmath.nstr(r, 20)}, error {float(err):.3e} > tol {float(tol):.3e}")
    rec = ERRORS.setdefault(scenario, {"max_rel": 0.0, "max_ratio": 0.0, "points": 0, "quantities": set()})
    rec["max_rel"] = max(rec["max_rel"], worst_rel)
    rec["max_ratio"] = max(rec["max_ratio"], worst_ratio)
    rec["points"] += len(got)
    rec["quantities"].add(name)
    assert not failures, f"{scenario}: {name} differs from the exact solution at {len(failures)} of {len(got)} points:\n" + "\n".join(failures[:10])
    return worst_rel


def pytest_terminal_summary(terminalreporter):
    if not ERRORS:
        return
    tr = terminalreporter
    tr.section("error against the exact solution (mpmath, 40 digits)")
    tr.write_line(f"tolerance: {REL_TOL:g} relative + {ABS_STRAIN:g} strain (x E2*A2 for forces)")
    tr.write_line(f"{'scenario':58s} {'points':>7s} {'max rel err':>12s} {'max err/tol':>12s}")
    for name, rec in ERRORS.items():
        tr.write_line(f"{name:58s} {rec['points']:7d} {rec['max_rel']:12.3e} {rec['max_ratio']:12.3e}")
