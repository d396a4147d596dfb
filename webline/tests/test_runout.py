"""A roll with runout ([R15], docs/physics.md "A roll with runout"): an unwinder's surface, a circle of
radius r, turns about an axis e off its centre; the web leaves along the tangent towards its span's far
end, pulls with the arm p and is paid out at omega*p + dL/dt.

- The ripple: a speed-driven roll without `wound`, a span of L with no damping, a sink at the roll's
  surface speed and the web at the strain it leaves with (no draw): the span's first-order lag driven
  by the payout omega*e*cos(psi) gives T a ripple at the roll's rotation frequency of amplitude
  EA (e/L)(1 + eps0)/sqrt(1 + (r/L)^2). At e/L = 1e-5 the terms left out are of order e/L: the
  amplitude to 1e-4 (least squares over whole turns, after 20 time constants L/v) and the ripple's
  period against the turn to 1e-4 (zero crossings), in the reference and in the Line FMU.
- An oval roll (the support function's second harmonic, a = 1e-5 m, no eccentricity) ripples at twice
  the turn's frequency by EA (a/(2L))(1 + eps0)/sqrt(1 + (r/(2L))^2) (docs/physics.md, "An out-of-round
  roll"), to 1e-4 in both engines; its period half a turn.
- The scene's keys: runout on a roller, a harmonic of order 1 or of a concave roll, an equilibrium start
  and the parts' engine are refused by name.
"""

import json

import numpy as np
import pytest

from webline import engines
from webline.scene import SceneError, parse_scene

E, R, L, V, EPS = 1e-5, 0.5, 1.0, 10.0, 1e-3
EA = 4.5e9 * 50e-6
TURN = 2 * np.pi * R / V
SETTLE = 2.0  # s: 20 time constants L/v


def scene(runout=None, start="given", extra=None, stop=SETTLE + 5 * TURN):
    unwind = {"type": "unwinder", "name": "unwind", "R": f"{R} m", "drive": {"speed": f"{V} m/s"}, "strain": EPS,
              "runout": runout or {"eccentricity": f"{E} m", "phase": "30 deg"}, **(extra or {})}
    return parse_scene(json.dumps({
        "name": "runout", "stop_time": f"{stop} s", "step": "1 ms", "start": start,
        "webs": {"PET": {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3"}},
        "line": [unwind, {"type": "span", "name": "film", "L": f"{L} m", "web": "PET"},
                 {"type": "sink", "name": "pull", "speed": f"{V} m/s"}],
        "record": ["film.T"]}), "runout.json")


def ripple(result, order=1):
    """(mean, amplitude at `order` times the roll's frequency, period of the ripple) of film.T over the
    whole turns after SETTLE."""
    t, T = np.asarray(result.time), np.asarray(result.data)[:, 0]
    n = int(round(5 * TURN / 1e-3))
    t, T = t[-n:] - t[-n], T[-n:]
    omega = 2 * np.pi * order / TURN
    # Least squares on (1, cos, sin): exact for a sinusoid whatever the window's last part-sample.
    basis = np.column_stack([np.ones_like(t), np.cos(omega * t), np.sin(omega * t)])
    (mean, a, b), *_ = np.linalg.lstsq(basis, T, rcond=None)
    up = np.flatnonzero((T[:-1] < mean) & (T[1:] >= mean))
    crossings = t[up] + (mean - T[up]) / (T[up + 1] - T[up]) * (t[up + 1] - t[up])
    return mean, float(np.hypot(a, b)), (crossings[-1] - crossings[0]) / (len(crossings) - 1)


@pytest.mark.parametrize("engine", ["reference", "line"])
def test_the_ripple_is_the_first_order_lag_at_the_roll_frequency(engine, fmus):
    mean, amplitude, period = ripple(engines.run_scene(scene(), engine, fmu_dir=fmus))
    expected = EA * (E / L) * (1 + EPS) / np.sqrt(1 + (R / L) ** 2)
    assert abs(amplitude / expected - 1) < 1e-4, (amplitude, expected)
    assert abs(mean / (EA * EPS) - 1) < 1e-4, mean
    assert abs(period / TURN - 1) < 1e-4, (period, TURN)


@pytest.mark.parametrize("engine", ["reference", "line"])
def test_an_oval_roll_ripples_twice_a_turn(engine, fmus):
    oval = {"eccentricity": "0 m", "harmonics": [{"order": 2, "amplitude": f"{E} m", "phase": "40 deg"}]}
    result = engines.run_scene(scene(runout=oval), engine, fmu_dir=fmus)
    mean, amplitude, period = ripple(result, order=2)
    expected = EA * (E / (2 * L)) * (1 + EPS) / np.sqrt(1 + (R / (2 * L)) ** 2)
    assert abs(amplitude / expected - 1) < 1e-4, (amplitude, expected)
    assert abs(period / (TURN / 2) - 1) < 1e-4, (period, TURN)
    assert ripple(result)[1] < 1e-3 * expected, "an oval without eccentricity must not ripple at the turn"


@pytest.mark.parametrize("change, words", [
    ({"runout": {"eccentricity": "1 mm", "harmonics": [{"order": 1, "amplitude": "0.1 mm"}]}}, "a whole number from 2"),
    ({"runout": {"eccentricity": "1 mm", "harmonics": [{"order": 8, "amplitude": "10 mm"}]}}, "must stay convex"),
    ({"start": "equilibrium"}, "holds no steady state"),
    ({"runout": {"eccentricity": "0.6 m"}}, "too short"),
])
def test_a_runout_that_cannot_be_is_refused_by_name(change, words):
    with pytest.raises(SceneError, match=words):
        scene(runout=change.get("runout"), start=change.get("start", "given"))


def test_runout_is_a_rolls_and_the_parts_refuse_it(fmus):
    text = json.dumps({
        "name": "x", "stop_time": "0.1 s", "step": "1 ms",
        "webs": {"PET": {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3"}},
        "line": [{"type": "source", "name": "in", "speed": "5 m/s", "strain": 0.001},
                 {"type": "span", "name": "a", "L": "1 m", "web": "PET"},
                 {"type": "roller", "name": "idler", "J": "0.01 kg.m2", "R": "0.05 m", "runout": {"eccentricity": "1 mm"}},
                 {"type": "span", "name": "b", "L": "1 m", "web": "PET"},
                 {"type": "sink", "name": "out", "speed": "5 m/s"}]})
    with pytest.raises(SceneError, match="runout is a roll's"):
        parse_scene(text, "x.json")
    with pytest.raises(SceneError, match="has runout"):
        engines.run_scene(scene(stop=0.01), "parts", fmu_dir=fmus)
