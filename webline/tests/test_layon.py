"""A winder's lay-on roller ([R18], docs/physics.md "A lay-on roller"): a roller on a carriage of mass m
pressed against the roll by a load F through a nip (a spring k and damper c that only push), turned by
the nip's traction.

- The steady nip: on a round roll, after the load steps from 100 N to 200 N, the carriage settles where
  the nip carries the load, N = F to 1e-6 N (its balance m X'' = N - F with X'' = 0), compressed by F/k, in the
  reference and the Line FMU, from a given and an equilibrium start.
- The bounce: webline/scenes/rewind_layon.json ramps the line through the speed at which the load can no
  longer hold the carriage on a roll running out by e, omega_c of `bounce_omega` (the rigid nip's
  sqrt(F/(m e)) less the nip's own compression F/k); the nip lets go first at a speed within 5 % of it.
  Before it the nip never let go; the summary counts the separations and warns.
  The Line FMU lets go at the same sample and agrees with the reference before it to 1e-6 of N's scale.
- Every lay-on quantity (N, delta, x, v, omega) of the Line FMU agrees with the reference's to 1e-6 of its scale
  on a roll running out, at three angles of the carriage's line; at an equilibrium start on a growing roll both
  hold the carriage at rest with N = F, its damper taking c r'.
- The separations are counted from the output samples against a known signal; the compiler's parameters.
- The scene's keys: a lay-on anywhere but on a winder, on a stepwise radius, with a negative load and in
  the parts' engine are refused by name.
"""

import json
import math

import numpy as np
import pytest

from webline import engines
from webline.accuracy import errors
from webline.reference import bounce_omega, reference
from webline.scene import LayOn, SceneError, load_scene, parse_scene
from webline.profiles import Profile
from webline.summary import separations, summary

from .conftest import SCENES

WEB = {"PET": {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3", "d_r": "1 ms"}}
LOAD = {"step": {"time": "0.05 s", "from": "100 N", "to": "200 N"}}


def scene(layon=None, winder=None, start="given", stop="0.5 s"):
    """A source, a 2 m span and a winder pressed by a lay-on; `layon` changes its keys (None drops one)."""
    keys = {"mass": "20 kg", "stiffness": "1e7 N/m", "damping": "5000 N.s/m", "radius": "0.1 m", "load": LOAD, **(layon or {})}
    wind = {"type": "winder", "name": "wind", "J": "1 kg.m2", "R": "0.2 m", "drive": {"tension": "112.5 N"},
            "layon": {k: v for k, v in keys.items() if v is not None}, **(winder or {})}
    wind = {k: v for k, v in wind.items() if v is not None}
    return parse_scene(json.dumps({
        "name": "layon", "stop_time": stop, "step": "1 ms", "start": start, "webs": WEB,
        "line": [{"type": "source", "name": "in", "speed": "5 m/s", "strain": 0.0005},
                 {"type": "span", "name": "film", "L": "2 m", "web": "PET", "effects": ["includeDamping"]}, wind],
        "record": ["wind.layon.N", "wind.layon.delta"]}), "layon.json")


@pytest.mark.parametrize("start", ["given", "equilibrium"])
@pytest.mark.parametrize("engine", ["reference", "line"])
def test_the_steady_nip_carries_the_load(engine, start, fmus):
    result = engines.run_scene(scene(start=start), engine, fmu_dir=fmus)
    assert result.info["engine"] == engine
    N, delta = result.column("wind.layon.N"), result.column("wind.layon.delta")
    print(f"{engine}, {start}: N - F = {N[0] - 100.0:.3g} N at the start, {N[-1] - 200.0:.3g} N at the end")
    assert abs(N[0] - 100.0) < 1e-6, N[0]  # it starts pressed by F/k at rest
    assert abs(N[-1] - 200.0) < 1e-6, N[-1]
    assert abs(delta[-1] - 200.0 / 1e7) < 1e-12, delta[-1]  # the nip's static compression F/k
    assert N.max() > 200.0 and N.min() > 0.0  # it overshot the new load and never let go


@pytest.mark.parametrize("engine", ["reference", "line"])
def test_a_growing_roll_starts_steady_with_the_nip_carrying_the_load(engine, fmus):
    """At an equilibrium start on a roll that grows (r' = h v/(2 pi r), 2e-4 m/s) the carriage is at rest, its balance
    N = F: the nip's damper, pressed at r', takes c r' of it (1 N), the spring the rest."""
    grown = scene(layon={"load": "150 N"}, winder={"wound": {"thickness": "50 um"}}, start="equilibrium", stop="0.01 s")
    result = engines.run_scene(grown, engine, fmu_dir=fmus)
    assert result.info["engine"] == engine
    N, delta = result.column("wind.layon.N")[0], result.column("wind.layon.delta")[0]
    r_rate = 50e-6 * 5.0 / (2 * math.pi * 0.2 * (1 + 0.0005))  # [R3] at the arriving strain
    assert abs(N - 150.0) < 1e-6, N
    assert abs(delta - (150.0 - 5000.0 * r_rate) / 1e7) < 1e-12, delta


@pytest.fixture(scope="module")
def shipped():
    scene = load_scene(SCENES / "rewind_layon.json")
    return scene, engines.run_scene(scene, "reference")


@pytest.mark.parametrize("engine", ["reference", "line"])
def test_the_shipped_scene_lets_go_at_the_derived_speed(engine, shipped, fmus):
    scene, ref = shipped
    result = ref if engine == "reference" else engines.run_scene(scene, engine, fmu_dir=fmus)
    assert result.info["engine"] == engine
    winder = scene.component("rewind")
    layon, e = winder.layon, winder.runout.eccentricity
    load = layon.load.value(0.0)
    omega_c = bounce_omega(layon, load, e)
    N, omega, r = (result.column(f"rewind.{q}") for q in ("layon.N", "omega", "r"))
    first = int(np.argmax(N <= 0.0))
    assert N[first] <= 0.0 and np.all(N[:first] > 0.0)
    v, v_c = r[first] * omega[first], r[first] * omega_c
    print(f"{engine}: first separation at t = {result.time[first]:.4g} s, v = {v:.4g} m/s; derived v_c = {v_c:.4g} m/s "
          f"({v / v_c - 1:+.2%}); rigid {r[first] * math.sqrt(load / (layon.mass * e)):.4g} m/s")
    assert abs(v / v_c - 1.0) < 0.05, (v, v_c)
    warning = next(w for w in summary(scene, result).warnings if w.startswith("lay-on at rewind lost contact"))
    assert f"first at t = {result.time[first]:.4g} s" in warning, warning
    if engine != "reference":
        # Up to the first separation the nip's force is smooth: the engine agrees with the reference to 1e-6 of its scale.
        N_ref = ref.column("rewind.layon.N")
        assert first == int(np.argmax(N_ref <= 0.0)), "the engine lets go at another sample than the reference"
        assert np.max(np.abs(N[:first] - N_ref[:first])) < 1e-6 * np.max(np.abs(N_ref)), engine


@pytest.mark.parametrize("angle, drive", [("0 deg", "tension"), ("50 deg", "tension"), ("-120 deg", "tension"), ("20 deg", "speed")])
def test_the_line_fmu_gives_every_layon_quantity_the_reference_gives(angle, drive, fmus):
    """The lay-on on a roll running out by 0.2 mm at phase 30 deg, its carriage's line at `angle` from the web's side:
    the nip's force swings once a turn (below its bounce speed), and every quantity it records agrees with the
    reference's, written apart from the Roller's, to 1e-6 of its scale (their conventions for the angles alike), on
    a winder driven by tension and on one that follows its speed profile."""
    winder = {"runout": {"eccentricity": "0.2 mm", "phase": "30 deg"}}
    if drive == "speed":
        winder.update(drive={"speed": "5 m/s"}, J=None)
    turning = scene(layon={"angle": angle}, winder=winder, stop="0.3 s")
    turning.record = [("wind", q) for q in ("layon.N", "layon.delta", "layon.x", "layon.v", "layon.omega")]
    if drive == "tension":  # (the reference records no omega of a speed-driven roll)
        turning.record.append(("wind", "omega"))
    line = engines.run_scene(turning, "line", fmu_dir=fmus)
    assert line.info["engine"] == "line"
    errs = errors(line, reference(turning, times=line.time))
    print(angle, {k: f"{e:.1e}" for k, e in errs.items()})
    assert max(errs.values()) < 1e-6, errs
    N = line.column("wind.layon.N")
    # The runout moves the nip: at 25 rad/s it swings N by m e omega^2 = 2.5 N each way (an angle off by a few
    # degrees shifts that swing's phase by as much: 0.1 N, 5e-4 of the scale).
    assert np.ptp(N[line.time > 0.1]) > 4.5


def test_the_bounce_speed_is_the_undamped_closed_form_without_damping():
    layon = LayOn(mass=25.0, stiffness=1e7, damping=0.0, radius=0.1, load=Profile.constant(50.0))
    e, F = 5e-4, 50.0
    assert abs(bounce_omega(layon, F, e) / math.sqrt(F / (layon.mass * (e + F / layon.stiffness))) - 1.0) < 1e-12
    # Damped (zeta 0.16), the swing at the nip's resonance is 1.7e4 N: no speed below it lets go of 1e5 N.
    damped = LayOn(mass=25.0, stiffness=1e7, damping=5000.0, radius=0.1, load=Profile.constant(1e5))
    assert bounce_omega(damped, 1e5, e) is None


def test_separations_are_counted_and_timed():
    # Apart over the last 0.4 s of each second, sampled every 10 ms for 2.8 s: three separations, the first at
    # 0.6 s, 0.4 s each but the last, still open at the end (0.2 s).
    t = np.arange(281) * 0.01
    apart = separations(t, np.where(np.arange(281) % 100 >= 60, 0.0, 50.0))
    assert (apart.count, apart.first) == (3, 0.6)
    assert abs(apart.longest - 0.4) < 1e-12 and abs(apart.total - 1.0) < 1e-12, apart
    assert separations(t, np.full(281, 1.0)).count == 0


@pytest.mark.parametrize("layon, winder, words", [
    ({}, {"wound": {"thickness": "50 um", "stepwise": {"merge": "30 deg"}}}, "stepwise"),
    ({}, {"runout": {"eccentricity": "1 mm", "harmonics": [{"order": 2, "amplitude": "0.1 mm"}]}}, "out-of-round"),
    ({"load": "-5 N"}, {}, "load >= 0"),
    ({"mu": 20}, {}, "friction coefficient"),
    ({"mass": None}, {}, "mass"),
])
def test_a_layon_that_cannot_be_is_refused_by_name(layon, winder, words):
    with pytest.raises(SceneError, match=words):
        scene(layon=layon, winder=winder)


def test_a_new_roll_under_a_layon_is_refused_by_name():
    """A set event of R (a new roll) would move the roll's surface under the carriage: refused; J and b may change."""
    base = json.loads(json.dumps({"name": "layon", "stop_time": "0.5 s", "step": "1 ms", "webs": WEB,
                                  "line": [{"type": "source", "name": "in", "speed": "5 m/s", "strain": 0.0005},
                                           {"type": "span", "name": "film", "L": "2 m", "web": "PET"},
                                           {"type": "winder", "name": "wind", "J": "1 kg.m2", "R": "0.2 m", "drive": {"tension": "100 N"},
                                            "layon": {"mass": "20 kg", "stiffness": "1e7 N/m", "damping": "5000 N.s/m",
                                                      "radius": "0.1 m", "load": "100 N"}}]}))
    for change, refused in [({"R": "0.3 m"}, True), ({"J": "2 kg.m2"}, False)]:
        base["events"] = [{"time": "0.2 s", "component": "wind", "set": change}]
        if refused:
            with pytest.raises(SceneError, match="a new roll .set R. would move its surface"):
                parse_scene(json.dumps(base), "layon.json")
        else:
            parse_scene(json.dumps(base), "layon.json")


def test_a_layon_is_a_winders_and_the_parts_refuse_it(fmus):
    text = json.dumps({
        "name": "x", "stop_time": "0.1 s", "step": "1 ms", "webs": WEB,
        "line": [{"type": "unwinder", "name": "unwind", "J": "1 kg.m2", "R": "0.2 m", "strain": 0.001,
                  "layon": {"mass": "20 kg", "stiffness": "1e7 N/m", "damping": "5000 N.s/m", "radius": "0.1 m", "load": "100 N"}},
                 {"type": "span", "name": "a", "L": "1 m", "web": "PET"},
                 {"type": "sink", "name": "out", "speed": "5 m/s"}]})
    with pytest.raises(SceneError, match="put it on a winder"):
        parse_scene(text, "x.json")
    with pytest.raises(SceneError, match="has a lay-on roller"):
        engines.run_scene(scene(stop="0.01 s"), "parts", fmu_dir=fmus)


def test_the_compiler_gives_the_roller_its_layon_parameters(fmus):
    """The Roller's parameters by the names of the spec (a constant load as layon.F, a profile as the table "layon")."""
    from webline.compiler import compile_scene

    wind = compile_scene(scene(layon={"angle": "30 deg", "mu": 0.4}), fmus, settle=False).component("wind")
    assert {k: v for k, v in wind.start.items() if k.startswith("layon")} == {
        "layon": True, "layon.m": 20.0, "layon.k": 1e7, "layon.c": 5000.0, "layon.r": 0.1, "layon.J": 0.05, "layon.b": 1e-3,
        "layon.mu": 0.4, "layon.v_slip": 1e-3, "layon.angle": pytest.approx(math.radians(30.0), abs=1e-15)}
    assert wind.profile["layon"] == [[0.05, 100.0], [0.05, 200.0]]
    steady = compile_scene(scene(layon={"load": "150 N"}), fmus, settle=False).component("wind")
    assert steady.start["layon.F"] == 150.0 and "layon" not in steady.profile
