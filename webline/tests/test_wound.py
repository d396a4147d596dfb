"""Rolls that change in scenes ([R3] of docs/physics.md): an unwinder's or winder's `wound` web moves
its radius and inertia in every engine, against closed forms.

- The radius: d(r^2)/dt = s h v/(pi (1 + eps)), the roll counting the web's unstretched length (eps
  the strain of the web at the roll: the unwinder's given 0, the winder's arriving span's), so
  r(t)^2 = r0^2 + s (h/pi) * (the integral of v/(1 + eps)). The integral is the trapezoid of the
  recorded values at 1 ms; they barely move, so the rule's error is far below the 1e-9 of r0 allowed
  (the Line FMU's tolerance is 1e-9). Winding the stretched length instead would put the winder 3e-6
  of r0 off (its strain is 1e-4).
- The inertia: [R1] balances J domega/dt with J(r) = J0 + (pi/2) rho w (r^4 - r0^4) (the web leaving
  carries off the angular momentum J' omega itself), so an unwinder under tension control pulls
  T = T_set + (J omega' + b omega)/r. J is the closed form; omega' is the run's own, by central
  differences (error O(dt^2 omega''')), hence 1e-7 of T. The old law's J' omega would be 6 % off.
"""

import json

import numpy as np
import pytest

from webline import engines
from webline.scene import SceneError, parse_scene

BOARD = {"E": "3 GPa", "thickness": "1 mm", "width": "1 m", "density": "700 kg/m3", "d_r": "1 ms"}
J0, R0, B, H, RHO, WIDTH, T_SET, V = 8.0, 0.4, 0.1, 1e-3, 700.0, 1.0, 300.0, 5.0


def scene(roll, stop="1.5 s"):
    """An unwinder (or a winder) of 1 mm board, exaggerated so that its radius moves within the run."""
    unwinder = {"type": "unwinder", "name": "unwind", "J": f"{J0} kg.m2", "R": f"{R0} m", "b": f"{B} N.m.s",
                "drive": {"tension": f"{T_SET} N"}, "strain": 0, "v_start": f"{V} m/s", **roll.get("unwind", {})}
    winder = {"type": "winder", "name": "rewind", "J": "4 kg.m2", "R": "0.2 m", "b": "0.05 N.m.s",
              "drive": {"tension": "300 N"}, "v_start": f"{V} m/s", **roll.get("rewind", {})}
    return parse_scene(json.dumps({
        "name": "wound", "stop_time": stop, "step": "1 ms", "webs": {"board": BOARD},
        "line": [unwinder, {"type": "span", "name": "entry", "L": "2 m", "web": "board", "effects": ["includeDamping"]},
                 {"type": "roller", "name": "pull", "drive": {"speed": f"{V} m/s"}},
                 {"type": "span", "name": "exit", "L": "1 m", "web": "board", "effects": ["includeDamping"]}, winder],
        "record": ["entry.T", "unwind.r", "unwind.omega", "unwind.v", "rewind.r", "rewind.v", "exit.eps"]}), "wound.json")


WOUND = {"unwind": {"wound": {"thickness": "1 mm"}}, "rewind": {"wound": {"thickness": "1 mm", "density": "700 kg/m3"}}}


@pytest.fixture(scope="module")
def runs(fmus):
    s = scene(WOUND)
    return {e: engines.run_scene(s, e, fmu_dir=fmus) for e in ("line", "reference", "parts")}


# The parts' Roller moves r and J after each piece of its step, by the web wound at the piece's mean speed
# and radius (second order in the step: 3e-12 of r0 at 1 ms here).
@pytest.mark.parametrize("engine,tol", [("line", 1e-9), ("reference", 1e-9), ("parts", 1e-9)])
def test_the_radius_follows_the_web_wound_off_and_on(runs, engine, tol):
    r = runs[engine]
    t = r.time
    for roll, sign, r0, eps in (("unwind", -1.0, R0, 0.0), ("rewind", 1.0, 0.2, r.column("exit.eps"))):
        q = r.column(f"{roll}.v") / (1.0 + eps)  # the web's unstretched flow at the roll
        wound = np.concatenate([[0.0], np.cumsum(0.5 * (q[1:] + q[:-1]) * np.diff(t))])
        exact = np.sqrt(r0**2 + sign * H / np.pi * wound)
        err = np.max(np.abs(r.column(f"{roll}.r") - exact)) / r0
        print(f"{engine}: {roll}.r against the closed form {err:.1e} of r0 (moved {abs(exact[-1] - r0) * 1e3:.2f} mm)")
        assert err < tol
        assert abs(exact[-1] - r0) > 2e-3  # the radius did move


def test_the_unwinders_torque_balances_its_changing_inertia(runs):
    r = runs["line"]
    t, T, rr, w = r.time, r.column("entry.T"), r.column("unwind.r"), r.column("unwind.omega")
    v = r.column("unwind.v")
    J = J0 + 0.5 * np.pi * RHO * WIDTH * (rr**4 - R0**4)
    r_rate = -H * v / (2 * np.pi * rr)
    J_rate = 2 * np.pi * RHO * WIDTH * rr**3 * r_rate
    w_rate = np.gradient(w, t)
    late = t > 0.5  # the start's transient (the 27 Hz mode, damping 0.09) has died away
    expected = T_SET + (J * w_rate + B * w) / rr
    err = np.max(np.abs(T - expected)[late]) / T_SET
    old_law = np.max(np.abs(T - (expected + J_rate * w / rr))[late]) / T_SET
    print(f"entry.T against the unwinder's balance: {err:.1e} (the old law's J' omega: {old_law:.1e})")
    assert err < 1e-7
    assert old_law > 1e-2


def test_the_line_fmu_and_the_reference_agree(runs):
    a, b = runs["line"], runs["reference"]
    for k in a.keys():
        x, y = a.column(k), b.column(k)
        assert np.max(np.abs(x - y)) <= 1e-8 * np.max(np.abs(y)), k


def test_without_wound_the_radius_stays(fmus):
    r = engines.run_scene(scene({}, stop="0.2 s"), "line", fmu_dir=fmus)
    assert np.all(r.column("unwind.r") == R0) and np.all(r.column("rewind.r") == 0.2)


def short_line(first, middle=(), events=()):
    """A scene of `first`, a span of board, the `middle` parts (roller, span), and a sink."""
    line = [first, {"type": "span", "name": "entry", "L": "2 m", "web": "board"}, *middle,
            {"type": "sink", "name": "pull", "speed": "5 m/s"}]
    return json.dumps({"name": "w", "stop_time": "1 s", "step": "1 ms", "webs": {"board": BOARD}, "line": line,
                       "events": list(events)})


WOUND_UNWINDER = {"type": "unwinder", "name": "unwind", "J": "8 kg.m2", "R": "0.4 m", "strain": 0,
                  "drive": {"tension": "300 N"}, "wound": {"thickness": "1 mm"}}


@pytest.mark.parametrize("roll,message", [
    ({"unwind": {"wound": {"density": "700 kg/m3"}}}, "needs the key 'thickness'"),
    ({"unwind": {"wound": {"thickness": "-1 mm"}}}, "thickness"),
])
def test_a_wound_roll_that_cannot_be_is_refused(roll, message):
    with pytest.raises(SceneError, match=message):
        scene(roll)


def test_a_speed_driven_roll_winds_nothing():
    # A speed-driven unwinder takes no J, b or v_start.
    unwinder = {"type": "unwinder", "name": "unwind", "strain": 0, "drive": {"speed": "5 m/s"}, "wound": {"thickness": "1 mm"}}
    with pytest.raises(SceneError, match="a speed-driven roll does not use"):
        parse_scene(short_line(unwinder), "w.json")


def test_wound_belongs_to_a_roll_and_its_radius_moves_by_no_event():
    idler = {"type": "roller", "name": "idler", "J": "0.1 kg.m2", "R": "0.1 m", "wound": {"thickness": "1 mm"}}
    source = {"type": "source", "name": "src", "speed": "5 m/s", "strain": 0}
    with pytest.raises(SceneError, match="wound is a roll's"):
        parse_scene(short_line(source, (idler, {"type": "span", "name": "exit", "L": "1 m", "web": "board"})), "w.json")
    base = scene(WOUND)
    assert base.component("unwind").wound.density == 700.0 and base.component("unwind").wound.width == 1.0
    with pytest.raises(SceneError, match=r"unknown key 'R'.*allowed: b"):
        parse_scene(short_line(WOUND_UNWINDER, events=[{"time": "0.5 s", "component": "unwind", "set": {"R": "0.3 m"}}]), "w.json")
