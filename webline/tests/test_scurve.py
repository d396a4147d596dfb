"""S-curve ramps in profiles (`{"scurve": {"start", "from", "to", "jerk", "duration"}}`): jerk-limited,
their jerk phases quadratic pieces of the profile, which keeps a profile's contract (value, left value,
slope, exact average, breakpoints).

- The profile: its jerk never exceeds the limit (second differences of its value at 1 ms: within 1e-6
  of the limit, rounding), it reaches its end value at its end time exactly, its slope is its value's
  derivative and its average the exact integral (Simpson on each piece; checked against a fine trapezoid).
- The engines: a source's S-curve speed and a winder's S-curve tension reach the line as given: the
  source's recorded v is the profile to 1e-12, the winder's tau/r is its tension to 1e-9.
"""

import json

import numpy as np
import pytest

from webline import engines
from webline.profiles import Profile
from webline.scene import SceneError, parse_scene

BOARD = {"E": "3 GPa", "thickness": "1 mm", "width": "1 m", "density": "700 kg/m3", "d_r": "1 ms"}


@pytest.mark.parametrize("jerk,duration", [(10.0, 2.0), (10.0, None), (None, 2.0), (40.0, 3.0)])
def test_an_scurve_keeps_its_jerk_limit_and_ends_at_its_end_value(jerk, duration):
    p = Profile.scurve(1.0, 2.0, 7.0, jerk, duration)
    limit = jerk if jerk is not None else 4.0 * 5.0 / duration**2
    end = 1.0 + (duration if duration is not None else 2.0 * np.sqrt(5.0 / jerk))
    assert p.value(end) == 7.0 and p.value_left(end) == pytest.approx(7.0, abs=1e-12)
    assert p.value(end - 1e-3) < 7.0 and p.slope(end) == 0.0 and abs(p.slope(1.0)) < 1e-12
    dt = 1e-3
    t = np.arange(0.5, end + 0.5, dt)
    v = np.array([p.value(x) for x in t])
    jerks = np.diff(v, 2) / dt**2  # the jerk of a speed is its second derivative: the pieces' curvature
    print(f"jerk {limit}: the largest second difference {np.max(np.abs(jerks)):.9g}")
    assert np.max(np.abs(jerks)) <= limit * (1.0 + 1e-6)
    assert np.max(np.abs(jerks)) >= limit * (1.0 - 1e-3)  # it reaches the limit
    slopes = np.array([p.slope(x) for x in t])
    # Central differences: exact on a quadratic, off by up to (the jerk's jump)*dt/4 across a knot: at most
    # 2*jerk there (+jerk to -jerk where the ramp has no constant acceleration), so jerk*dt/2.
    assert np.max(np.abs(np.gradient(v, dt)[1:-1] - slopes[1:-1])) < 0.51 * limit * dt
    a, b = 1.1, end - 0.3
    fine = np.linspace(a, b, 200001)
    exact = np.trapezoid([p.value(x) for x in fine], fine) / (b - a)
    assert abs(p.average(a, b) - exact) < 1e-9
    assert p.breakpoints()[0] == 1.0 and p.breakpoints()[-1] == pytest.approx(end, abs=1e-15)


def scene(speed, tension, engine_refused=False):
    return parse_scene(json.dumps({
        "name": "scurve", "stop_time": "4 s", "step": "10 ms", "webs": {"board": BOARD},
        "line": [{"type": "source", "name": "feed", "speed": speed, "strain": 0.0},
                 {"type": "span", "name": "exit", "L": "1 m", "web": "board", "effects": ["includeDamping"]},
                 {"type": "winder", "name": "rewind", "J": "2 kg.m2", "R": "0.2 m", "b": "0.05 N.m.s",
                  "drive": {"tension": tension}, "v_start": "2 m/s"}],
        "record": ["feed.v", "exit.T", "rewind.tau", "rewind.r"]}), "scurve.json")


SPEED = {"scurve": {"start": "1 s", "from": "2 m/s", "to": "5 m/s", "jerk": 6.0, "duration": "2 s"}}
TENSION = {"scurve": {"start": "0.5 s", "from": "300 N", "to": "200 N", "jerk": 400.0}}


@pytest.mark.parametrize("engine", ["line", "reference"])
def test_an_scurve_reaches_the_line_as_given(fmus, engine):
    s = scene(SPEED, TENSION)
    r = engines.run_scene(s, engine, fmu_dir=fmus)
    t = r.time
    speed, tension = s.component("feed").speed, s.component("rewind").drive.profile
    v_err = np.max(np.abs(r.column("feed.v") - [speed.value(x) for x in t]))
    T = np.array([tension.value(x) for x in t])
    tau_err = np.max(np.abs(r.column("rewind.tau") / r.column("rewind.r") - T) / T)
    print(f"{engine}: feed.v off its S-curve by {v_err:.1e} m/s, tau/r off its tension by {tau_err:.1e}")
    assert v_err < 1e-12 and tau_err < 1e-9
    assert r.column("feed.v")[np.searchsorted(t, 3.0)] == 5.0


def test_an_inconsistent_scurve_is_refused_with_the_numbers(fmus):
    with pytest.raises(SceneError, match=r"a jerk of 1 per s\^2 takes at least 3.4641 s from 2 to 5, longer than the duration 2 s"):
        scene({"scurve": {"start": "1 s", "from": "2 m/s", "to": "5 m/s", "jerk": 1.0, "duration": "2 s"}}, "300 N")
    with pytest.raises(SceneError, match="needs a jerk, a duration or both"):
        scene({"scurve": {"start": "1 s", "from": "2 m/s", "to": "5 m/s"}}, "300 N")
    with pytest.raises(SceneError, match="has an S-curve profile"):
        engines.run_scene(scene(SPEED, "300 N"), "parts", fmu_dir=fmus)
