"""A winder's tapered tension and stepwise radius ([R16], [R17] of docs/physics.md).

- `"drive": {"tension": T0, "taper": k}` holds T(r) = T0 (1 - k (1 - R/r)) as the roll grows, in every
  engine. The law is algebraic in the roll's radius and the profile's tension, so the drive's recorded
  torque over the recorded radius equals it to rounding: 1e-9 relative is asked (1e-15 is what rounding
  leaves). The roll grows more than 20 % (2 mm per lap, exaggerated so that it does within the run).
- `"wound": {"stepwise": {"merge": "30 deg"}}`: the radius the web meets, v/omega, steps by a layer over
  the last 30 degrees of each layer, and is the smooth radius r where each merge ends; r itself keeps
  the mass balance of [R3].
"""

import json

import numpy as np
import pytest

from webline import engines
from webline.scene import SceneError, parse_scene

BOARD = {"E": "3 GPa", "thickness": "1 mm", "width": "1 m", "density": "700 kg/m3", "d_r": "1 ms"}
K, R0 = 0.3, 0.2


def scene(drive, kind="winder", wound=None):
    roll = {"type": kind, "name": "rewind", "J": "2 kg.m2", "R": f"{R0} m", "b": "0.05 N.m.s", "drive": drive,
            "v_start": "5 m/s", "wound": wound or {"thickness": "2 mm"}}
    if kind == "unwinder":
        roll["strain"] = 0
    span = {"type": "span", "name": "exit", "L": "1 m", "web": "board", "effects": ["includeDamping"]}
    line = [{"type": "source", "name": "feed", "speed": "5 m/s", "strain": 0.0}, span, roll]
    if kind == "unwinder":
        line = [roll, span, {"type": "sink", "name": "pull", "speed": "5 m/s"}]
    return parse_scene(json.dumps({
        "name": "taper", "stop_time": "6 s", "step": "10 ms", "webs": {"board": BOARD}, "line": line,
        "record": ["exit.T", "exit.eps", "rewind.tau", "rewind.r", "rewind.v", "rewind.omega"]}), "winding.json")


def tension_given(t):
    """T0 of the scene's profile: 300 N, ramped to 360 N over 1-3 s."""
    return 300.0 + 60.0 * np.clip((t - 1.0) / 2.0, 0.0, 1.0)


TAPERED = {"tension": {"table": [["0 s", "300 N"], ["1 s", "300 N"], ["3 s", "360 N"]]}, "taper": K}


@pytest.mark.parametrize("engine", ["line", "reference", "parts"])
def test_a_tapered_winders_torque_over_its_radius_is_the_hyperbolic_law(fmus, engine):
    # The parts' explicit coupling is stable up to 4.7 ms here (webline check): they step at 2 ms.
    r = engines.run_scene(scene(TAPERED), engine, fmu_dir=fmus, step=2e-3 if engine == "parts" else None)
    t, radius = r.time, r.column("rewind.r")
    expected = tension_given(t) * (1.0 - K * (1.0 - R0 / radius))
    err = np.max(np.abs(r.column("rewind.tau") / radius - expected) / expected)
    print(f"{engine}: tau/r against T(r) {err:.1e}; r grew {radius[-1] / R0 - 1:.0%}")
    assert radius[-1] > 1.2 * R0
    assert err < 1e-9
    # The span follows the tapered tension once the ramp is over, less the bearing's b omega/r and the roll's
    # J omega'/r (about 1 % here): within 2 %.
    late = t > 4.0
    T = r.column("exit.T")[late]
    assert np.max(np.abs(T - expected[late]) / expected[late]) < 0.02
    assert T[-1] < 0.97 * 360.0, "the taper must lower the tension (360 N and more without it)"


def test_a_taper_is_a_winders_and_between_0_and_1():
    with pytest.raises(SceneError, match="taper = 1.5: a taper is 0 to 1"):
        scene({"tension": "300 N", "taper": 1.5})
    with pytest.raises(SceneError, match="drive.taper = 0.3: a taper is a winder's"):
        scene({"tension": "300 N", "taper": 0.3}, kind="unwinder")
    plain = scene({"tension": "300 N"})
    assert plain.component("rewind").drive.taper == 0.0


STEPWISE = {"thickness": "2 mm", "stepwise": {"merge": "30 deg"}}
H, M = 2e-3, 30.0 / 360.0


def stepwise(r):
    """The stepwise law [R17], written out for this winder."""
    u = (r - R0) / H
    n = np.floor(u)
    return R0 + H * (n + np.maximum(0.0, (u - n - (1.0 - M)) / M))


@pytest.mark.parametrize("engine", ["line", "reference"])
def test_a_stepwise_radius_holds_each_layer_and_merges_to_the_next(fmus, engine):
    """v/omega is the stepwise law of r at every sample (rounding apart: 1e-12), within a layer below r, and
    holds every layer's radius R + n h in turn; r keeps [R3]'s balance: r^2 - R^2 = (h/pi) times the
    unstretched web wound, the integral of v/(1 + eps), to 1e-6 of R (the trapezoid of 10 ms samples
    across the merges' kinks in v: 2e-7 here)."""
    r = engines.run_scene(scene({"tension": "300 N"}, wound=STEPWISE), engine, fmu_dir=fmus)
    t, radius, v, omega = r.time, r.column("rewind.r"), r.column("rewind.v"), r.column("rewind.omega")
    contact = v / omega
    err = np.max(np.abs(contact - stepwise(radius)) / radius)
    print(f"{engine}: v/omega against the stepwise law {err:.1e}")
    assert err < 1e-12
    assert np.all(contact <= radius + 1e-12) and np.all(contact > radius - H)
    layers = (contact - R0) / H
    seen = set(np.round(layers[np.abs(layers - np.round(layers)) < 1e-9]).astype(int))
    wound = int(np.floor((radius[-1] - R0) / H))
    assert wound >= 20 and seen == set(range(wound + 1)), (wound, sorted(seen))
    q = v / (1.0 + r.column("exit.eps"))
    flow = np.concatenate([[0.0], np.cumsum(0.5 * (q[1:] + q[:-1]) * np.diff(t))])
    balance = np.max(np.abs(np.sqrt(R0**2 + H / np.pi * flow) - radius)) / R0
    print(f"{engine}: r against the web wound {balance:.1e} of R")
    assert balance < 1e-6


def test_a_stepwise_radius_is_refused_by_the_parts_and_beyond_a_turn(fmus):
    with pytest.raises(SceneError, match="has a stepwise radius"):
        engines.run_scene(scene({"tension": "300 N"}, wound=STEPWISE), "parts", fmu_dir=fmus)
    with pytest.raises(SceneError, match="merge = 400 degrees: a merge is at most a turn"):
        scene({"tension": "300 N"}, wound={"thickness": "2 mm", "stepwise": {"merge": "400 deg"}})
