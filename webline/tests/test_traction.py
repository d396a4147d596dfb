"""Rollers that slip, nips that hold (docs/physics.md, "Rollers that slip", "Contacts that stick"):
the closed forms in the monolithic reference and the Line FMU (FMI 2.0 Co-Simulation at 1 and 10 ms,
Model Exchange, and FMI 3.0), the scene keys and their refusals, and what `webline run` reports.

The closed forms hold where the web slides (its grip at the kinetic limit, g = 1), to 1e-6 of each
quantity's scale: the reference integrates at rtol 1e-10 and the Line FMU at its default tolerance,
1e-9 on strains and speeds; the web's mass on the wrap adds m_w dv_w/dt, of order 1e-9 of the
tension in these steady lines. The Line FMU's tests skip, saying so, where the packaged Roller
predates the contact law that sticks (its traction.creep).
"""

import json
import math

import numpy as np
import pytest
from fmpy import simulate_fmu

from webline import linefmu
from webline.cli import main as webline_main
from webline.reference import reference
from webline.scene import SceneError, parse_scene

from .conftest import SCENES, require_sticking_contacts

PET = {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3", "d_r": "1 ms"}
EA = 4.5e9 * 50e-6
RHO_L = 1390.0 * 50e-6 * 1.0  # the web's mass per length: its centripetal force rho_l v^2 relieves the wrap
MU, WRAP, MU_NIP, LOAD, V_SLIP = 0.3, math.radians(90.0), 0.5, 200.0, 1e-3
DAMPED = {"web": "PET", "effects": ["includeDamping"]}


def scene(line, record, start="equilibrium", stop="0.3 s"):
    return parse_scene(json.dumps({"name": "traction", "stop_time": stop, "step": "1 ms", "start": start,
                                   "webs": {"PET": PET}, "line": line, "record": record}), "traction.json")


def sliding_line(nip_side=None):
    """A drag roll (a wrap) and a nip roll, both driven slower than the web, which slides over both: a
    given start at the steady slide (`expected_sliding`; an equilibrium start holds the web to the
    rolls, which cannot hold it here), which the grips reach from 0 within microseconds; the web over
    the nip (which has no slip_start: that is the wrap's traction's) starts at its surface's speed."""
    x = expected_sliding()
    return scene([
        {"type": "source", "name": "src", "speed": "5 m/s", "strain": 1e-3},
        {"type": "span", "name": "a", "L": "1 m", "T_start": f"{x['a.T']!r} N", **DAMPED},
        {"type": "roller", "name": "drag", "R": "0.1 m", "wrap": "90 deg", "drive": {"speed": "4.5 m/s"},
         "traction": {"mu": MU, "slip_start": f"{x['drag.v_web'] - 4.5!r} m/s"}},
        {"type": "span", "name": "b", "L": "1 m", "T_start": f"{x['b.T']!r} N", **DAMPED},
        {"type": "roller", "name": "nip", "R": "0.1 m", "drive": {"speed": "4.4 m/s"},
         "nip": {"load": f"{LOAD} N", "mu": MU_NIP, **({"side": nip_side} if nip_side else {})}},
        {"type": "span", "name": "c", "L": "1 m", "T_start": f"{x['c.T']!r} N", **DAMPED},
        {"type": "sink", "name": "snk", "speed": "5.005 m/s"},
    ], ["a.T", "b.T", "c.T", "drag.v_web", "drag.slip", "drag.traction", "nip.v_web", "nip.slip", "nip.traction"],
        start="given", stop="4 s")


def expected_sliding():
    """The mass balance span by span (1 + eps_out = (v_out/v_in)(1 + eps_in)) gives c's strain from the
    source and sink alone; the nip passes mu N below it, the wrap divides T - rho_l v^2 by exp(mu theta)
    below that (v the web's speed over the drag roll, which follows from a's strain: solved by
    iteration, each step shrinking the error by 2 rho_l v^2 / EA), and each roll's web speed follows
    from the strain before it."""
    eps_c = 5.005 / 5.0 * 1.001 - 1.0
    eps_b = eps_c - MU_NIP * LOAD / EA
    eps_a = eps_b
    for _ in range(10):
        relief = RHO_L * (5.0 * (1.0 + eps_a) / 1.001) ** 2
        eps_a = (relief + (EA * eps_b - relief) * math.exp(-MU * WRAP)) / EA
    return {"a.T": EA * eps_a, "b.T": EA * eps_b, "c.T": EA * eps_c,
            "drag.v_web": 5.0 * (1.0 + eps_a) / 1.001, "nip.v_web": 5.0 * (1.0 + eps_b) / 1.001}


# Where the start's kick (the grips' microseconds at 0) has left less than 1e-7 of each tension: the
# spans' mass balances return it at about v/(L (1 + 1/e^(mu theta))) = 3/s (tests/validation/test_contacts.py).
SETTLED = 3.5


def check_sliding(result, engine):
    settled = result.time >= SETTLED
    for key, value in expected_sliding().items():
        x = result.column(key)[settled]
        assert np.max(np.abs(x - value)) <= 1e-6 * abs(value), f"{engine}: {key} {x.min()}..{x.max()} vs {value}"
    for roll in ("drag", "nip"):
        assert result.column(f"{roll}.slip")[settled].min() >= 50 * V_SLIP, engine
        assert np.max(np.abs(result.column(f"{roll}.traction")[settled] - 1.0)) <= 1e-9, engine


def spin_up_line():
    """An idler at rest on a running line (the web crosses it at the line's speed), a given start."""
    return scene([
        {"type": "source", "name": "src", "speed": "5 m/s", "strain": 1e-3},
        {"type": "span", "name": "a", "L": "1 m", "eps_start": 1e-3, **DAMPED},
        {"type": "roller", "name": "idler", "J": "0.01 kg.m2", "R": "0.05 m", "v_start": "0 m/s", "wrap": "90 deg",
         "traction": {"mu": MU, "slip_start": "5 m/s"}},
        {"type": "span", "name": "b", "L": "1 m", "eps_start": 2e-3, **DAMPED},
        {"type": "sink", "name": "snk", "speed": "5.005 m/s"},
    ], ["a.T", "idler.v", "idler.v_web", "idler.slip", "idler.traction"], start="given", stop="0.4 s")


def check_spin_up(t, acceleration, tension, v_web, slip, used, engine):
    """While it slides (after the sudden start's transient, a few ms), the surface accelerates at
    R^2 (T_a - rho_l v_w^2)(exp(mu theta) - 1)/J; while it sticks with at most 90 % of its traction,
    |s| <= 5 v_slip."""
    sliding = (slip > 50 * V_SLIP) & (t > 0.02)
    expected = 0.05 ** 2 * (tension - RHO_L * v_web ** 2) * (math.exp(MU * WRAP) - 1.0) / 0.01
    assert sliding.sum() >= 8, engine  # a tenth of the run at least, at 10 ms too
    assert np.max(np.abs(acceleration[sliding] / expected[sliding] - 1.0)) < 1e-6, engine
    sticking = (slip <= 50 * V_SLIP) & (used <= 0.9)
    assert sticking.sum() >= 8 and np.max(np.abs(slip[sticking])) <= 5 * V_SLIP, engine


@pytest.fixture(scope="module")
def line_dir(fmus):
    """The packaged FMUs with the Line FMU's libraries, whose Roller has the contact law that sticks."""
    assert (fmus / linefmu.TEMPLATE / "fmi2" / "binaries").is_dir()
    require_sticking_contacts(fmus)
    return fmus


def test_the_closed_forms_hold_in_the_reference():
    check_sliding(reference(sliding_line()), "reference")
    s = spin_up_line()
    from webline.reference import LineODE

    ode = LineODE(s)
    r = reference(s)
    i = ode.i_omega["idler"]
    t = r.time
    # The reference's own rates at its recorded states: the surface's acceleration R * domega/dt.
    states = _reference_states(s, t)
    accel = np.array([0.05 * ode.rhs(tk, z)[i] for tk, z in zip(t, states)])
    check_spin_up(t, accel, r.column("a.T"), r.column("idler.v_web"), r.column("idler.slip"), r.column("idler.traction"),
                  "reference")


def _reference_states(s, times):
    """The reference's state at each time (its dense output, integrated again here)."""
    from scipy.integrate import solve_ivp

    from webline.reference import RTOL, LineODE, atol_of

    ode = LineODE(s)
    z0 = ode.initial_state()
    sol = solve_ivp(ode.rhs, (0.0, s.stop_time), z0, method="Radau", rtol=RTOL, atol=atol_of(ode, z0), dense_output=True)
    return [sol.sol(t) for t in times]


@pytest.mark.parametrize("how", ["cs 1 ms", "cs 10 ms", "me", "fmi3"])
def test_the_closed_forms_hold_in_the_line_fmu(how, line_dir, tmp_path):
    s = sliding_line()
    fmu = linefmu.export(s, tmp_path / "sliding.fmu", line_dir, fmi3=how == "fmi3")
    result = linefmu.simulate(s, fmu, 1e-2 if how == "cs 10 ms" else 1e-3, model_exchange=how == "me")
    check_sliding(result, how)
    s = spin_up_line()
    fmu = linefmu.export(s, tmp_path / "spin.fmu", line_dir, fmi3=how == "fmi3")
    names = ["a.T", "idler.v_web", "idler.slip", "idler.traction", "der(idler.omega)"]
    h = 1e-2 if how == "cs 10 ms" else 1e-3
    out = simulate_fmu(str(fmu), stop_time=s.stop_time, step_size=h, output_interval=h, output=names,
                       fmi_type="ModelExchange" if how == "me" else "CoSimulation")
    check_spin_up(out["time"], 0.05 * out["der(idler.omega)"], out["a.T"], out["idler.v_web"], out["idler.slip"],
                  out["idler.traction"], how)


def test_the_line_fmu_reports_what_a_roller_with_traction_has(line_dir, tmp_path):
    from fmpy import read_model_description

    s = sliding_line()
    md = read_model_description(str(linefmu.export(s, tmp_path / "l.fmu", line_dir)))
    names = {v.name for v in md.modelVariables}
    for q in ("v", "v_web", "slip", "traction", "mu_eff"):
        assert f"drag.{q}" in names and f"nip.{q}" in names
    assert "drag.h_air" not in names, "h_air only with an air film"
    assert "drag.includeTraction" not in names, "the line's structure is the scene's"


@pytest.mark.parametrize("edit, says", [
    (lambda line: line[2]["traction"].update(static=0.8), "roller 'idler': traction: static 0.8: .* must be >= 1"),
    (lambda line: line[2]["traction"].update(creep="-5 nm"), "roller 'idler': traction: creep"),
    (lambda line: line[2]["traction"].update(slip_start="1 m/s"),
     "roller 'idler': traction: slip_start is the web's slip at a given start; with \"start\": \"equilibrium\""),
    (lambda line: line[2].update(drive={"brake": "-5 N.m"}) or line[2].pop("traction"),
     "roller 'idler': drive.brake: -5 N.m at t = 0 s: a brake's rated torque is >= 0"),
    (lambda line: line[2].update(drive={"brake": {"torque": "5 N.m", "creep": "1 um", "v_slip": "1 mm/s"}}) or line[2].pop("traction"),
     "v_slip"),
    (lambda line: line[4].update(type="winder", J="1 kg.m2", R="0.1 m", drive={"tension": "100 N"}, wrap="90 deg",
                                 traction={"mu": 0.3}) or line[4].pop("speed"),
     "traction or a nip on a winder is not modelled"),
    (lambda line: line[2]["traction"].update(mu=0.3) or line[2].pop("wrap"), "give the roller a \"wrap\""),
    (lambda line: line[1].update(effects=[]), "needs the effect includeDamping"),
    (lambda line: line[2].update(nip={"load": "100 N", "mu": 0.5, "side": "middle"}),
     "roller 'idler': nip: side 'middle' is not one of 'entry', 'exit'"),
    (lambda line: line[0].update(type="unwinder", J="1 kg.m2", R="0.1 m", drive={"tension": "100 N"}, strain=0.0)
     or line[0].pop("speed") or line[2].update(type="roller"), None),
])
def test_scene_keys_are_checked_by_name(edit, says):
    line = [
        {"type": "source", "name": "src", "speed": "5 m/s", "strain": 1e-3},
        {"type": "span", "name": "a", "L": "1 m", **DAMPED},
        {"type": "roller", "name": "idler", "J": "0.01 kg.m2", "R": "0.05 m", "wrap": "90 deg", "traction": {"mu": MU}},
        {"type": "span", "name": "b", "L": "1 m", **DAMPED},
        {"type": "sink", "name": "snk", "speed": "5 m/s"},
    ]
    edit(line)
    text = json.dumps({"name": "t", "stop_time": "1 s", "step": "1 ms", "webs": {"PET": PET}, "line": line})
    if says is None:
        parse_scene(text, "t.json")  # an unwinder feeding the idler: fine
        return
    with pytest.raises(SceneError, match=says):
        parse_scene(text, "t.json")


@pytest.mark.parametrize("side, value", [(None, 0), ("entry", 0), ("exit", 1)])
def test_the_nips_side_reaches_the_roller(side, value, line_dir):
    """A scene's nip side is the Roller's nip.side in the Line's parts (entry by default)."""
    part = next(p for p in linefmu.line_spec(sliding_line(side), line_dir)["parts"] if p["name"] == "nip")
    assert part["start"]["nip.side"] == value


def test_the_contact_keys_reach_the_roller(fmus):
    """traction.static and traction.creep, and a brake's creep, are the Roller's parameters of the same
    names in the compiled parts (the Line FMU's and the co-simulation's); their defaults the reference's
    constants."""
    from webline.compiler import compile_scene
    from webline.scene import BRAKE_CREEP, TRACTION_CREEP

    line = [
        {"type": "unwinder", "name": "unwind", "J": "1 kg.m2", "R": "0.2 m", "strain": 0.0,
         "drive": {"brake": {"torque": "20 N.m", "creep": "20 nm"}}},
        {"type": "span", "name": "a", "L": "1 m", **DAMPED},
        {"type": "roller", "name": "idler", "J": "0.01 kg.m2", "R": "0.05 m", "wrap": "90 deg",
         "traction": {"mu": MU, "static": 1.2, "creep": "50 nm"}},
        {"type": "span", "name": "b", "L": "1 m", **DAMPED},
        {"type": "roller", "name": "plain", "J": "0.01 kg.m2", "R": "0.05 m", "wrap": "90 deg", "traction": {"mu": MU}},
        {"type": "span", "name": "c", "L": "1 m", **DAMPED},
        {"type": "winder", "name": "rewind", "J": "1 kg.m2", "R": "0.2 m", "drive": {"tension": "100 N"}},
    ]
    parts = {c.name: c.start for c in compile_scene(scene(line, ["a.T"], start="given"), fmus, settle=False).components}
    assert parts["idler"]["traction.static"] == 1.2 and parts["idler"]["traction.creep"] == pytest.approx(5e-8, rel=1e-12)
    assert parts["plain"]["traction.static"] == 1.0 and parts["plain"]["traction.creep"] == TRACTION_CREEP
    assert parts["unwind"]["brake.creep"] == pytest.approx(2e-8, rel=1e-12) and (BRAKE_CREEP, TRACTION_CREEP) == (1e-6, 5e-8)


def test_traction_is_refused_where_it_is_not_modelled():
    unwinder = {"type": "unwinder", "name": "u", "J": "1 kg.m2", "R": "0.1 m", "strain": 0.0,
                "drive": {"tension": "100 N"}, "wrap": "90 deg", "traction": {"mu": 0.3}}
    line = [unwinder, {"type": "span", "name": "a", "L": "1 m", **DAMPED}, {"type": "sink", "name": "snk", "speed": "5 m/s"}]
    text = json.dumps({"name": "t", "stop_time": "1 s", "step": "1 ms", "webs": {"PET": PET}, "line": line})
    with pytest.raises(SceneError, match="traction or a nip on an unwinder is not modelled"):
        parse_scene(text, "t.json")


def test_the_parts_refuse_traction_by_name(fmus, tmp_path, capsys):
    code = webline_main(["run", str(SCENES / "idler_skid.json"), "--engine", "parts", "--out", str(tmp_path)])
    assert code != 0
    err = capsys.readouterr().err
    assert "roller 'idler' has traction" in err and "Line FMU" in err


@pytest.mark.parametrize("engine", ["reference", "line"])
def test_webline_run_says_when_the_idler_slid(engine, fmus, tmp_path, capsys):
    """The shipped scene: the idler skids on the steep ramp (from 0.22 s, where the ramp's J a/R^2
    passes what its wrap holds) and holds on the gentle one."""
    if engine == "line":
        require_sticking_contacts(fmus)
    assert webline_main(["run", str(SCENES / "idler_skid.json"), "--engine", engine, "--out", str(tmp_path),
                         "--fmu-dir", str(fmus)]) == 0
    out = capsys.readouterr().out
    said = next(line for line in out.splitlines() if line.strip().startswith("idler:"))
    assert "it slid from t = 0.22" in said and "m of web slid over it" in said, said
    table = np.genfromtxt(tmp_path / "idler_skid.csv", delimiter=",", names=True)
    used = table["idlertraction_1"]
    gentle = table["time_s"] > 2.5
    assert used[gentle].max() < 0.7, "the gentle ramp leaves it a third of its traction"


CASES = SCENES.parent / "tests" / "cases"


def run_reference(path, tmp_path, capsys):
    """`webline run --engine reference` on a scene: its exit code and what it printed (out, err)."""
    code = webline_main(["run", str(path), "--engine", "reference", "--out", str(tmp_path)])
    out = capsys.readouterr()
    return code, out.out, out.err


def test_webline_run_reports_the_share_a_holding_pull_roll_uses(tmp_path, capsys):
    """The user's pull roll holds 100 N against 200 N (mu 0.3, 180 deg): the friction it needs over the
    kinetic limit, ln(2)/(0.3 pi) = 0.7355, is 74 %; it never slid. The PNG's title keeps the
    description's "0.2 m/s" (its first sentence has no full stop before its end)."""
    code, out, _ = run_reference(CASES / "pull_roll_sticks_slow.json", tmp_path, capsys)
    assert code == 0
    said = next(line.strip() for line in out.splitlines() if line.strip().startswith("pull:"))
    assert said.startswith("pull: 74 % of its traction at most while it held") and said.endswith("it never slid"), said
    from webline.cli import first_sentence

    assert first_sentence("case 1: pull roll at 0.2 m/s, 20 N.m. Second.") == "case 1: pull roll at 0.2 m/s, 20 N.m"


def test_webline_run_reports_a_slide_with_when_how_fast_and_how_much_web(tmp_path, capsys):
    """The pull roll against 300 N, started given: it slides (the capstan limit is 256.6 N). The summary
    says when, how fast at most and how much web slid over it: the integral of |slip| over the samples
    it slid at, computed here from the CSV the run wrote (to the 3 digits printed)."""
    scene = json.loads((CASES / "pull_roll_slides_slow.json").read_text())
    scene.update(start="given")
    for part in scene["line"]:
        if part["name"] in ("up", "down"):
            part["T_start"] = "100 N" if part["name"] == "up" else "300 N"
    path = tmp_path / "pull_roll_slides_slow.json"
    path.write_text(json.dumps(scene))
    code, out, _ = run_reference(path, tmp_path, capsys)
    assert code == 0
    said = next(line.strip() for line in out.splitlines() if line.strip().startswith("pull:"))
    table = np.genfromtxt(tmp_path / "pull_roll_slides_slow.csv", delimiter=",", names=True)
    slip, used, t = table["pullslip_ms"], table["pulltraction_1"], table["time_s"]
    sliding = (used >= 1.0 - 1e-6) | (np.abs(slip) > V_SLIP)
    slid = np.trapezoid(np.where(sliding, np.abs(slip), 0.0), t)
    assert f"it slid from t = {t[sliding][0]:.3g} s to {t[sliding][-1]:.3g} s" in said, said
    assert f"at up to {np.max(np.abs(slip[sliding])):.3g} m/s, {slid:.3g} m of web slid over it" in said, said


@pytest.mark.parametrize("case, says", [
    ("pull_roll_slides_slow", "pull: needs 300 N downstream, its capstan limit is 256.6 N (mu 0.3, 180 deg): "
                              "the web slides from the start; use \"start\": \"given\""),
    ("nip_slides", "nip: needs 300 N downstream, its nip limit is 200 N (nip mu 0.5, 200 N): the web slides from the "
                   "start; use \"start\": \"given\""),
])
def test_an_equilibrium_start_past_a_contacts_limit_is_refused_in_plain_words(case, says, tmp_path, capsys):
    """An equilibrium start holds every web to its rollers (zero slip); where a contact cannot carry
    what the steady line asks of it, the run stops before any engine, saying what it needs and its
    limit: 100 N e^(0.3 pi) = 256.6 N against 300 N; 100 N + 0.5 * 200 N = 200 N against 300 N."""
    code, out, err = run_reference(CASES / f"{case}.json", tmp_path, capsys)
    assert code != 0 and says in err, err
    assert "not making good progress" not in err


def test_webline_run_says_an_idler_rides_on_air_not_a_share_over_its_limit(tmp_path, capsys):
    """An idler whose air film grows with the line's ramp (1 to 10 m/s; roughness 12 um): mu_eff falls to
    0 where Knox and Sweeney's film reaches 3 roughnesses, h = 0.643 R (12 eta V/T_w)^(2/3) = 36 um,
    at V = 6.1 m/s (T_w = 100 N/m). From there the summary says it rides on air, from the web's speed
    where it began (the speed recorded at the first sample with mu_eff = 0)."""
    code, out, _ = run_reference(CASES / "idler_rides_on_air.json", tmp_path, capsys)
    assert code == 0
    said = next(line.strip() for line in out.splitlines() if line.strip().startswith("idler:"))
    table = np.genfromtxt(tmp_path / "idler_rides_on_air.csv", delimiter=",", names=True)
    first = int(np.argmax(table["idlermu_eff_1"] == 0.0))
    assert table["idlermu_eff_1"][first] == 0.0
    assert f"it rides on air from {table['idlerv_web_ms'][first]:.4g} m/s" in said, said
    assert 5.5 < table["idlerv_web_ms"][first] < 7.0, "near where the film reaches 3 roughnesses"


def test_a_huge_mu_is_refused_by_name_and_the_largest_runs_without_runtime_warnings(tmp_path, capsys):
    """mu = 1e6 on the pull roll is refused by name with the range the Roller takes (0 to 10), before any
    engine runs; mu = 10, the largest, where a trial state's sinh(mu theta g/2) grows fastest,
    runs cleanly with no NumPy RuntimeWarning at the sticking line's 100 N."""
    import warnings

    scene = json.loads((CASES / "pull_roll_sticks_slow.json").read_text())
    scene["stop_time"] = "0.2 s"
    path = tmp_path / "mu.json"
    for mu in (1e6, 10.0):
        scene["line"][2]["traction"]["mu"] = mu
        path.write_text(json.dumps(scene))
        with warnings.catch_warnings():
            warnings.simplefilter("error", RuntimeWarning)
            code, out, err = run_reference(path, tmp_path, capsys)
        assert "RuntimeWarning" not in err, err
        if mu > 10.0:
            assert code != 0 and "traction: mu = 1e+06: a friction coefficient is 0 to 10" in err, err
        else:
            assert code == 0, err
    table = np.genfromtxt(tmp_path / "pull_roll_sticks_slow.csv", delimiter=",", names=True)
    assert np.max(np.abs(table["upT_N"] / 100.0 - 1.0)) < 1e-5


def test_idlers_that_stick_side_by_side_on_damped_spans_start_steady_in_the_reference():
    """Two idlers with traction next to each other, their spans damped (a damped span's tension reads the
    web's speed at both ends): the reference's equilibrium start sets every web to its roller's surface
    before it solves any grip, so the line starts steady (each grip solved against the final tensions;
    solved one by one with the next web still at its start speed, idler0 was left 6.7e-9 of its scale
    off steady and the start refused). Over 0.2 s the tensions stay at the start's to 1e-9 relative."""
    web = {"paper": {"E": "5 GPa", "thickness": "100 um", "width": "1.2 m", "density": "800 kg/m3", "d_r": "0.5 ms"}}
    idler = {"type": "roller", "J": "0.05 kg.m2", "R": "0.08 m", "b": "0.002 N.m.s", "v_start": "10 m/s",
             "wrap": "90 deg", "traction": {"mu": 0.3}}
    line = [{"type": "unwinder", "name": "unwind", "J": "8 kg.m2", "R": "0.5 m", "b": "0.1 N.m.s",
             "drive": {"tension": "400 N"}, "strain": 0.0, "v_start": "10 m/s"}]
    for i in range(3):
        line.append({"type": "span", "name": f"s{i}", "L": f"{1.0 + 0.25 * i} m", "web": "paper", "effects": ["includeDamping"]})
        line.append({**idler, "name": f"idler{i}"} if i < 2 else {"type": "sink", "name": "pull", "speed": "10 m/s"})
    s = parse_scene(json.dumps({"name": "idlers", "stop_time": "0.2 s", "step": "1 ms", "start": "equilibrium", "webs": web,
                                "line": line, "record": ["s0.T", "s1.T", "s2.T"]}), "idlers.json")
    r = reference(s)
    for name in ("s0.T [N]", "s1.T [N]", "s2.T [N]"):
        T = r.column(name)
        assert np.max(np.abs(T / T[0] - 1.0)) < 1e-9, name
