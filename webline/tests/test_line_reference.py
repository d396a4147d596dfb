"""Co-simulation against the monolithic reference (webline/src/webline/reference.py:
the whole line as one ODE, SciPy's Radau at rtol 1e-10).

* The reference itself against a closed form (a span between two prescribed
  speeds: the strain relaxes exponentially), to 1e-8.
* Every shipped scene at its default step within its stated tolerance. The
  error is the largest deviation of a span tension over the run relative to
  that tension's largest value. Measured (this machine): lamination 2.6e-4,
  emergency stop 1.0e-3, dancer 1.7e-3, splice 8.5e-3, stiff line 3.5e-5; the bounds are about
  three times that, so that they fail on a real change, not on rounding.
* Convergence: with extrapolation and input derivatives (the default) the
  error falls at second order as the step halves; with inputs held, at first.
  Asserted as observed orders in [1.7, 2.5] and [0.8, 1.3].
"""

import math

import numpy as np
import pytest
from webline.compiler import run_scene
from webline.reference import reference
from webline.scene import load_scene, parse_scene
from webline.accuracy import convergence, errors, observed_orders, stability_limit, tension_error, union_grid

from .conftest import SCENES


DEFAULT_STEP_TOLERANCE = {"lamination": 1e-3, "emergency_stop": 3e-3, "dancer": 5e-3, "splice": 2.5e-2, "stiff_line": 1e-4}


@pytest.fixture(scope="module")
def lamination():
    return load_scene(SCENES / "lamination.json")


@pytest.fixture(scope="module")
def lamination_reference(lamination):
    """One reference for every lamination test, on the union of their grids."""
    return reference(lamination, times=union_grid(lamination, [2e-3, 1e-3, 5e-4, 2.5e-4]))


def test_reference_against_a_closed_form():
    """Source at v_a, strain eps_a; sink steps from v_a to v_b at t0: the span's
    unstretched length x relaxes as x_inf + (x0 - x_inf) exp(-v_b (t - t0)/L)."""
    text = """{
      "name": "relax", "stop_time": "1 s", "step": "10 ms",
      "webs": {"PET": {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3"}},
      "line": [
        {"type": "source", "name": "in", "speed": "5 m/s", "strain": 0.001},
        {"type": "span", "name": "s", "L": "0.8 m", "web": "PET"},
        {"type": "sink", "name": "out", "speed": {"step": {"time": "0.2 s", "from": "5 m/s", "to": "5.01 m/s"}}}
      ]
    }"""
    s = parse_scene(text, "relax.json")
    ref = reference(s)
    L, va, ea, vb, t0 = 0.8, 5.0, 0.001, 5.01, 0.2
    x0 = L / (1 + ea)  # equilibrium at the start: eps = eps_a
    x_inf = va / (1 + ea) * L / vb
    t = ref.time
    x = np.where(t <= t0, x0, x_inf + (x0 - x_inf) * np.exp(-vb * (t - t0) / L))
    T = 4.5e9 * 50e-6 * (L / x - 1)
    assert np.max(np.abs(ref.column("s.T") - T)) / np.max(T) < 1e-8


@pytest.mark.parametrize("name", list(DEFAULT_STEP_TOLERANCE))
def test_each_scene_at_its_default_step_is_within_its_tolerance(fmus, name, lamination_reference):
    s = load_scene(SCENES / f"{name}.json")
    r = run_scene(s, fmu_dir=fmus)
    ref = lamination_reference if name == "lamination" else reference(s, times=r.time)
    e = errors(r, ref)
    assert tension_error(e) < DEFAULT_STEP_TOLERANCE[name], e
    # Speeds are far closer than tensions (they integrate the forces).
    assert max(v for k, v in e.items() if k.endswith(".v")) < DEFAULT_STEP_TOLERANCE[name] / 3, e


def test_second_order_with_extrapolation_and_input_derivatives(fmus, lamination, lamination_reference):
    rows, _ = convergence(lamination, [2e-3, 1e-3, 5e-4], ref=lamination_reference, fmu_dir=fmus)
    orders = observed_orders(rows)
    assert all(1.7 <= p <= 2.5 for p in orders), [(r.step, r.error) for r in rows]
    assert rows[1].error < DEFAULT_STEP_TOLERANCE["lamination"]


def test_first_order_with_held_inputs(fmus, lamination, lamination_reference):
    rows, _ = convergence(lamination, [2e-3, 1e-3, 5e-4], ref=lamination_reference, fmu_dir=fmus, coupling="hold")
    orders = observed_orders(rows)
    assert all(0.8 <= p <= 1.3 for p in orders), [(r.step, r.error) for r in rows]


def test_second_order_through_slack_and_snatch(fmus):
    s = load_scene(SCENES / "emergency_stop.json")
    rows, _ = convergence(s, [2e-3, 1e-3, 5e-4], fmu_dir=fmus)
    orders = observed_orders(rows)
    assert all(1.5 <= p <= 2.5 for p in orders), [(r.step, r.error) for r in rows]


def test_stability_limit_of_a_stiff_line(fmus):
    """Heavy board in two 0.2 m spans around a light idler (about 4500 rad/s), Kelvin–Voigt damped:
    held inputs stay stable at 0.25 ms and diverge at 0.35 ms; extrapolation with input derivatives
    stays stable to 0.35 ms and diverges at 0.5 ms, and it is more accurate."""
    s = load_scene(SCENES / "stiff_line.json")
    steps = [5e-4, 3.5e-4, 2.5e-4, 1.25e-4]
    ref = reference(s, times=union_grid(s, steps))
    held, _ = convergence(s, steps, ref=ref, coupling="hold", fmu_dir=fmus)
    moving, _ = convergence(s, steps, ref=ref, fmu_dir=fmus)
    assert stability_limit(held) == (2.5e-4, 3.5e-4)
    assert stability_limit(moving) == (3.5e-4, 5e-4)
    assert moving[-1].error < held[-1].error  # where both are stable, derivatives are more accurate
