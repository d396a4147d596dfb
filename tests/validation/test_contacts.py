"""The contact laws of a roller the web may slip on (docs/physics.md, "Rollers that slip", "Contacts
that stick"), each against its closed form: the nip on either side of the wrap, the web's centripetal
force relieving the wrap, the air film at the entry tension; contacts that stick (the mass balance
through a roll or nip that holds, the user's pull roll and nip that hold and slide) and a brake that
holds a stopped line. In the Line FMU (FMI 2.0 and 3.0 Co-Simulation at 1 ms and 10 ms, FMI 2.0 Model
Exchange under FMPy's CVode at rtol 1e-10), in webline's reference, and for the brake in the Roller FMU
(the parts' co-simulation). The FMU engines skip, saying why, where the packaged Roller predates the
contact law that sticks (its traction.creep).

The sliding lines: a source at 5 m/s feeding a strain of 1e-3, a damped PET span (EA = 225 kN,
rho_l = 0.0695 kg/m), a roll driven at a speed clearly off the web's (so the web slides at |s| >= 50
v_slip, its grip at the kinetic limit), a second damped span and a sink. At steady state the mass
balance of the span after the roll, 1 + eps_b = (v_snk/v_src)(1 + eps_src), fixes T_b = EA eps_b; the
roll's law then fixes T_a, and the span before it carries the web to the roll at v_w = v_src (1 +
eps_a)/(1 + eps_src). They start given at that state (an equilibrium start holds the web to the roll).
Tolerance 1e-6 of the tension: the reference integrates at rtol 1e-10, the Line FMU at its default
tolerance (1e-9 on strains and speeds), so what is left is the integrators' error, far below it; the
web's mass on the wrap (m_w dv_w/dt) is 0 at steady state.
"""

import json
import math
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

from webline import linefmu
from webline.cli import main as webline_main
from webline.engines import run_scene
from webline.reference import reference
from webline.scene import SceneError, parse_scene

from .conftest import require_sticking_contacts

EA = 4.5e9 * 50e-6
RHO_L = 1390.0 * 50e-6 * 1.0
MU, WRAP, MU_NIP, LOAD, V_SLIP = 0.3, math.radians(90.0), 0.5, 200.0, 1e-3
E = math.exp(MU * WRAP)
NIP = MU_NIP * LOAD
PET = {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3", "d_r": "1 ms"}
DAMPED = {"web": "PET", "effects": ["includeDamping"]}
# Where a sliding start's kick has died out: the web's mass on the wrap (a millisecond's mode) after
# LAW_FROM; the spans' strains after SETTLED. Sliding ties T_a to T_b (dT_a = dT_b/E braking, E dT_b
# driving), so the two spans' mass balances, L deps_a/dt = dv_w - v deps_a and L deps_b/dt = -dv_w
# - v (deps_b - deps_a), return their sum at v/(L (1 + 1/E)) = 3.1/s braking, v/(L (1 + E)) = 1.9/s
# driving: the kick's 0.02 N is below 1e-7 of T after 3.5 s.
LAW_FROM, SETTLED, STOP = 0.05, 3.5, "4 s"
HOW = ["fmi2 cs 1 ms", "fmi2 cs 10 ms", "fmi3 cs 1 ms", "fmi3 cs 10 ms", "fmi2 me", "reference"]
# A web that slides at a slip below v_slip crosses the grip's kink at every swing of the winder's mode:
# FMPy's CVode then takes more than its 500 steps per output interval (at rtol 1e-10 and 1e-8), so the
# sliding cases run in Co-Simulation, where the Line FMU's own integrator steps over the kink.
SLIDING_HOW = [h for h in HOW if not h.endswith("me")]


def line(name, roll, v_sink, record=(), start=None, stop="0.3 s"):
    """src (5 m/s, strain 1e-3) - a - roll (`roll`'s keys, a 90 degree wrap) - b - snk (v_sink). A web
    that slides from the start starts given (an equilibrium start is a sticking one): `start` =
    (eps_a, eps_b, slip), the steady sliding state, which the contact's grip reaches from 0 within
    microseconds (at the rate |s|/creep): the force it lacks meanwhile kicks the web's mass on the wrap
    (a mode damped in about a millisecond) and moves the spans' strains by about 1e-4 of the tension,
    which the spans' mass balance returns (`SETTLED`)."""
    spans = [{}, {}]
    if start is not None:
        eps_a, eps_b, slip = start
        spans = [{"eps_start": eps_a}, {"eps_start": eps_b}]
        roll = {**roll, "traction": {**roll["traction"], "slip_start": f"{slip!r} m/s"}}
    return parse_scene(json.dumps({
        "name": name, "stop_time": stop, "step": "1 ms", "start": "equilibrium" if start is None else "given",
        "webs": {"PET": PET},
        "line": [
            {"type": "source", "name": "src", "speed": "5 m/s", "strain": 1e-3},
            {"type": "span", "name": "a", "L": "1 m", **DAMPED, **spans[0]},
            {"type": "roller", "name": "roll", "R": "0.1 m", "wrap": "90 deg", **roll},
            {"type": "span", "name": "b", "L": "1 m", **DAMPED, **spans[1]},
            {"type": "sink", "name": "snk", "speed": f"{v_sink} m/s"},
        ],
        "record": ["a.T", "b.T", "roll.v_web", "roll.slip", *record]}), f"{name}.json")


def run(scene, how, where):
    """The scene's recorded columns, {name: array}, in one engine."""
    fmus, tmp_path = where
    names = [f"{c}.{q}" for c, q in scene.record]
    if how == "reference":
        r = reference(scene)
        return {"time": r.time, **{n: r.column(n) for n in names}}
    require_sticking_contacts(fmus)
    if how == "parts":  # the Roller and span FMUs co-simulated at the scene's step
        r = run_scene(scene, "parts", fmus)
        return {"time": r.time, **{n: r.column(n) for n in names}}
    fmu = linefmu.export(scene, tmp_path / f"{scene.name}.fmu", fmus, fmi3=how.startswith("fmi3"))
    if how.endswith("me"):
        out = simulate_fmu(str(fmu), fmi_type="ModelExchange", stop_time=scene.stop_time, output_interval=1e-3,
                           relative_tolerance=1e-10, output=names)
    else:
        step = 1e-2 if how.endswith("10 ms") else 1e-3
        out = simulate_fmu(str(fmu), fmi_type="CoSimulation", stop_time=scene.stop_time, step_size=step,
                           output_interval=step, output=names)
    return {"time": np.asarray(out["time"], dtype=float), **{n: np.asarray(out[n], dtype=float) for n in names}}


@pytest.fixture
def where(fmus, tmp_path):
    """The packaged FMUs and a folder for the Line FMUs exported from them."""
    return fmus, tmp_path


def steady_a(eps_b, law):
    """eps_a from T_b = EA eps_b through the roll's `law` T_a(T_b, relief), with v_w from eps_a: a fixed
    point whose map contracts by 2 rho_l v^2 / EA (1e-5 here), so 20 steps reach the last bit."""
    eps_a = eps_b
    for _ in range(20):
        v_w = 5.0 * (1.0 + eps_a) / 1.001
        eps_a = law(EA * eps_b, RHO_L * v_w * v_w) / EA
    return eps_a, 5.0 * (1.0 + eps_a) / 1.001


# The four cases: the nip at the wrap's entry or exit (in the direction of travel, src to snk), the
# roll braking the web (driven at 4.5 m/s: the web slides faster, s > 0, so the tension rises to
# T_b) or driving it (at 5.5 m/s: s < 0, the tension falls to T_b). Braking, the entry is the
# low-tension side; driving, the high one. With the nip on the wrap's low side the wrap multiplies
# what the nip adds, T'_high = (T'_low + mu_nip N) e^(mu theta); on its high side the nip adds after
# it, T'_high = T'_low e^(mu theta) + mu_nip N; T' = T - rho_l v_w^2 on the wrap (the nip's jump is
# the same in T and T'). Each law solved for T_a given T_b (the span after the roll fixes T_b):
CASES = {
    # braking, nip at the entry = on the low side: T'_b = (T'_a + nN) E
    "entry, braking": (4.5, "entry", 5.005, lambda tb, m: m + (tb - m) / E - NIP, True),
    # braking, nip at the exit = on the high side: T'_b = T'_a E + nN
    "exit, braking": (4.5, "exit", 5.005, lambda tb, m: m + (tb - m - NIP) / E, False),
    # driving, nip at the entry = on the high side: T'_a = T'_b E + nN
    "entry, driving": (5.5, "entry", 5.0, lambda tb, m: m + (tb - m) * E + NIP, False),
    # driving, nip at the exit = on the low side: T'_a = (T'_b + nN) E
    "exit, driving": (5.5, "exit", 5.0, lambda tb, m: m + (tb - m + NIP) * E, True),
}


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize("case", list(CASES))
def test_a_sliding_roll_with_a_wrap_and_a_nip_gives_the_law_of_the_nips_side(case, how, where):
    """A roll with a 90 degree wrap (mu 0.3) and a nip (mu_nip 0.5, N = 200 N), speed-driven clearly
    off the web's speed so the web slides: with the nip on the wrap's low-tension side,
    T_high - rho_l v^2 = (T_low - rho_l v^2 + mu_nip N) e^(mu theta); on its high-tension side,
    T_high - rho_l v^2 = (T_low - rho_l v^2) e^(mu theta) + mu_nip N (the wrap multiplies what
    reaches it; the two differ by mu_nip N (e^(mu theta) - 1) = 60 N). The law is checked on the
    engine's own tensions and web speed at every point, and the tensions against the steady state
    the mass balance and the law give (module docstring), each to 1e-6 of the high tension (the
    integrators' error is far below it; see the module docstring)."""
    v_roll, side, v_snk, law, nip_low = CASES[case]
    eps_b = v_snk / 5.0 * 1.001 - 1.0
    eps_a, v_expected = steady_a(eps_b, law)
    scene = line("contact", {"drive": {"speed": f"{v_roll} m/s"}, "traction": {"mu": MU},
                             "nip": {"load": f"{LOAD} N", "mu": MU_NIP, "side": side}}, v_snk,
                 start=(eps_a, eps_b, v_expected - v_roll), stop=STOP)
    r = run(scene, how, where)
    law, steady = r["time"] >= LAW_FROM, r["time"] >= SETTLED
    t_a, t_b, v_w = r["a.T"][law], r["b.T"][law], r["roll.v_web"][law]
    braking = v_roll < 5.0
    low, high = (t_a, t_b) if braking else (t_b, t_a)
    m = RHO_L * v_w ** 2
    expected = m + ((low - m + NIP) * E if nip_low else (low - m) * E + NIP)
    assert np.max(np.abs(high - expected) / high) <= 1e-6, f"{how}: {np.max(np.abs(high - expected) / high):.2e}"
    assert np.min(np.abs(r["roll.slip"])) >= 50 * V_SLIP, how
    for name, value in (("a.T", EA * eps_a), ("b.T", EA * eps_b)):
        x = r[name][steady]
        assert np.max(np.abs(x - value)) <= 1e-6 * np.max(high), f"{how}: {name} {x.min()}..{x.max()} vs {value}"
    assert np.max(np.abs(r["roll.v_web"][steady] - v_expected)) <= 1e-6 * 5.0, how


# A board heavy enough that its centripetal force takes all its tension off the wrap at 20 m/s:
# 0.5 mm, 1000 kg/m3, 1 m wide: rho_l = 0.5 kg/m, rho_l v^2 = 200 N at 20 m/s.
BOARD = {"BOARD": {"E": "5 GPa", "thickness": "0.5 mm", "width": "1 m", "density": "1000 kg/m3", "d_r": "1 ms"}}


def floating_line(stop, record):
    """The board from a source at 20 m/s (strain 1e-5: 25 N) over a roll driven at 15 m/s to a sink at 20 m/s,
    starting given where it is steady: the web crosses the roll at 20 m/s (an equilibrium start would
    hold it to the roll's surface)."""
    return {
        "name": "floating", "stop_time": stop, "step": "1 ms", "start": "given", "webs": BOARD,
        "line": [
            {"type": "source", "name": "src", "speed": "20 m/s", "strain": 1e-5},
            {"type": "span", "name": "a", "L": "1 m", "web": "BOARD", "effects": ["includeDamping"], "eps_start": 1e-5},
            {"type": "roller", "name": "roll", "R": "0.1 m", "wrap": "90 deg", "drive": {"speed": "15 m/s"},
             "traction": {"mu": MU, "slip_start": "5 m/s"}},
            {"type": "span", "name": "b", "L": "1 m", "web": "BOARD", "effects": ["includeDamping"], "eps_start": 1e-5},
            {"type": "sink", "name": "snk", "speed": "20 m/s"},
        ],
        "record": record}


@pytest.mark.parametrize("how", HOW)
def test_a_web_whose_speed_takes_its_tension_off_the_wrap_has_no_traction(how, where):
    """T - rho_l v^2 <= 0: the pressure p R = T - rho_l v^2 of the capstan derivation is none, so the
    wrap transmits no friction whatever the slip. A board at 20 m/s (rho_l v^2 = 200 N) under about
    25 N (strain 1e-5: EA = 2.5 MN) over a roll driven at 15 m/s: with f = 0 the roll passes the
    web on untouched, so at steady state T_a = T_b (m_w dv_w/dt = T_b - T_a + f = 0), both spans
    carry the strain the mass balance gives between source and sink at the same speed (eps_a =
    eps_b = the source's 1e-5), and the web crosses the roll at the sink's speed. The tensions to
    1e-6 of T, T_a = T_b to 1e-9 of T (the spans' tensions differ only by the integrators' error),
    the web's speed to 1e-9; the speed drive's reaction torque, the roll's friction times its
    radius (b = 0, J domega/dt = 0 at a constant speed), exactly 0."""
    scene = parse_scene(json.dumps(floating_line("0.2 s", ["a.T", "b.T", "roll.v_web", "roll.slip", "roll.tau"])),
                        "floating.json")
    r = run(scene, how, where)
    t = 5e9 * 0.5e-3 * 1e-5
    assert np.max(np.abs(r["a.T"] - t)) <= 1e-6 * t and np.max(np.abs(r["b.T"] - t)) <= 1e-6 * t, how
    assert np.max(np.abs(r["a.T"] - r["b.T"])) <= 1e-9 * t, how
    assert np.max(np.abs(r["roll.v_web"] - 20.0)) <= 1e-9 * 20.0, how
    assert np.min(r["roll.slip"]) >= 4.9, how
    assert np.all(r["roll.tau"] == 0.0), f"{how}: friction torque {np.max(np.abs(r['roll.tau']))}"


def test_webline_run_names_the_roller_and_the_speed_where_the_wrap_has_no_traction(fmus, tmp_path, capsys):
    """The same board line run by `webline run`: its summary says that the roll has no traction on
    its wrap, at v_web = 20 m/s (the sink's speed: the web passes the roll untouched), where the
    centripetal force rho_l v^2 = 0.5 * 20^2 = 200 N exceeds the tension 25 N."""
    require_sticking_contacts(fmus)  # the Line FMU runs it
    scene = floating_line("0.05 s", ["a.T"])
    path = tmp_path / "floating.json"
    path.write_text(json.dumps(scene))
    assert webline_main(["run", str(path), "--out", str(tmp_path), "--fmu-dir", str(fmus)]) == 0
    said = [line for line in capsys.readouterr().out.splitlines() if "no traction" in line]
    assert len(said) == 1, said
    assert said[0].strip().startswith("roll: no traction on its wrap") and "v_web = 20 m/s" in said[0], said[0]
    assert "rho_l v^2 = 200 N" in said[0] and "tension 25 N" in said[0], said[0]


@pytest.mark.parametrize("how", HOW)
def test_the_air_film_is_knox_and_sweeneys_at_the_entry_tension(how, where):
    """Knox and Sweeney: h = 0.643 R (12 eta V / T_w)^(2/3), V the mean of the web's and the surface's
    speeds, T_w the tension per width where the film forms: the inlet, where the web arrives (T_a,
    running forward). The braking roll with its nip at the entry (first case above) has
    T_b/T_a = 450 N / 182 N = 2.5, so the mean tension would give a film 31 % thinner: the check
    tells them apart. Its roughness (1 mm) is far above the film (about 20 um here), so mu_eff = mu
    and the tensions are the first case's closed forms; h to 1e-6 relative (it goes as T_a^(-2/3)
    and V^(2/3), both known to 1e-6 or better once the sliding start has settled, `SETTLED`)."""
    eps_b = 5.005 / 5.0 * 1.001 - 1.0
    eps_a, v_w = steady_a(eps_b, CASES["entry, braking"][3])
    scene = line("film", {"drive": {"speed": "4.5 m/s"}, "traction": {"mu": MU, "air": {"roughness": "1 mm"}},
                          "nip": {"load": f"{LOAD} N", "mu": MU_NIP}}, 5.005, record=("roll.h_air", "roll.mu_eff"),
                 start=(eps_a, eps_b, v_w - 4.5), stop=STOP)
    r = run(scene, how, where)
    t_a, t_b = EA * eps_a, EA * eps_b
    film = lambda t: 0.643 * 0.1 * (12.0 * 1.81e-5 * (v_w + 4.5) / 2.0 / (t / 1.0)) ** (2.0 / 3.0)
    h = r["roll.h_air"][r["time"] >= SETTLED]
    assert np.max(np.abs(h / film(t_a) - 1.0)) <= 1e-6, f"{how}: {h.min()}..{h.max()} vs {film(t_a)}"
    assert abs(film((t_a + t_b) / 2.0) / film(t_a) - 1.0) > 0.2  # the mean tension's film is another
    assert np.all(r["roll.mu_eff"] == MU), how


# Contacts that stick (docs/physics.md, "Contacts that stick"): each contact's grip is a bristle whose
# steady sticking slip is exactly 0, so the mass balance holds through a contact that holds.


def draw_line(v, contact):
    """A source at v (strain 0), a 0.1 m damped span, a roll speed-driven at v (1 + 5e-4) with a
    180 degree wrap (mu 0.3) or a nip (500 N, mu 0.5), a second 0.1 m span and a sink at
    v (1 + 5e-4)^2; both spans start unstretched (a given start), so the draws fill them."""
    v2, v3 = v * (1.0 + 5e-4), v * (1.0 + 5e-4) ** 2
    roll = {"wrap": "180 deg", "traction": {"mu": MU}} if contact == "roll" else {"nip": {"load": "500 N", "mu": MU_NIP}}
    span = {"L": "0.1 m", "eps_start": 0.0, **DAMPED}
    return parse_scene(json.dumps({
        "name": "draw", "stop_time": f"{2.5 / v!r} s", "step": "1 ms", "start": "given", "webs": {"PET": PET},
        "line": [
            {"type": "source", "name": "src", "speed": f"{v!r} m/s", "strain": 0.0},
            {"type": "span", "name": "a", **span},
            {"type": "roller", "name": "roll", "R": "0.1 m", "drive": {"speed": f"{v2!r} m/s"}, **roll},
            {"type": "span", "name": "b", **span},
            {"type": "sink", "name": "snk", "speed": f"{v3!r} m/s"},
        ],
        "record": ["a.T", "b.T", "roll.slip", "roll.traction"]}), "draw.json"), v2, v3


@pytest.mark.parametrize("how", HOW)
@pytest.mark.parametrize("v", [0.1, 1.0, 10.0])
@pytest.mark.parametrize("contact", ["roll", "nip"])
def test_a_sticking_contact_between_speed_drives_gives_the_mass_balances_tensions(contact, v, how, where):
    """Mass balance through a contact that holds: the web crosses it at its surface's speed, so each
    span carries its draw, 1 + eps_a = (v_roll/v_src)(1 + 0) and 1 + eps_b = (v_snk/v_roll)(1 + eps_a):
    T_a = EA eps_a = 112.5 N, T_b = EA eps_b = 225 N, at 0.1, 1 and 10 m/s alike. The roll holds them
    (T_b/T_a = 2 < e^(0.3 pi) = 2.57; the nip's T_b - T_a = 112.5 N < 250 N). The regularized law of
    before needed a slip v_slip artanh(share) for it, a draw error EA s/v of some 1000 N at 0.1 m/s.
    Both spans fill from 0 at the rate v/L of their mass balance: the run lasts 25 L/v, where what is
    left of the start is e^-25 = 1e-11 of T. Tolerance 1e-6 of each tension at the end: the
    integrators' error (rtol 1e-10 in the reference, 1e-9 on the Line FMU's states) is far below."""
    scene, v2, v3 = draw_line(v, contact)
    r = run(scene, how, where)
    eps_a = v2 / v - 1.0
    eps_b = v3 / v2 * (1.0 + eps_a) - 1.0
    for name, value in (("a.T", EA * eps_a), ("b.T", EA * eps_b)):
        assert abs(r[name][-1] / value - 1.0) <= 1e-6, f"{how}: {name} {r[name][-1]!r} N vs {value!r} N"
    assert r["roll.traction"][-1] < 1.0, how


# The user's scenes (PET 50 um, 0.2 and 2 m/s), with what they must give.
USER_CASES = Path(__file__).resolve().parents[2] / "webline" / "tests" / "cases"
EXP = math.exp(MU * math.pi)  # a 180 degree wrap, mu 0.3: e^(0.3 pi) = 2.566


def user_case(name, **edits):
    """A scene of webline/tests/cases, its top-level keys replaced by `edits`; spans' T_start by `T_start`."""
    scene = json.loads((USER_CASES / f"{name}.json").read_text())
    for span, value in edits.pop("T_start", {}).items():
        next(p for p in scene["line"] if p["name"] == span)["T_start"] = value
    scene.update(edits)
    return parse_scene(json.dumps(scene), f"{name}.json")


@pytest.mark.parametrize("how", HOW)
def test_a_pull_roll_that_holds_gives_the_sources_draw_and_its_share(how, where):
    """pull_roll_sticks_slow: a source at 0.19991115 m/s (strain 0) and a pull roll speed-driven at
    0.2 m/s (mu 0.3, 180 degrees), a winder holding 200 N. The web sticks, so span up carries the draw
    EA (0.2/0.19991115 - 1) = 100.0 N, span down the winder's 200 N, and the share in use is the g of
    T_b - m = (T_a - m) e^(mu pi g), m = rho_l v^2 = 0.0028 N: g = ln((200 - m)/(100 - m))/(0.3 pi) =
    0.7355. Both to 1e-6 (the integrators' error is far below; the line starts steady)."""
    r = run(user_case("pull_roll_sticks_slow"), how, where)
    m = RHO_L * 0.2 ** 2
    t_a = EA * (0.2 / 0.19991115059973347 - 1.0)
    share = math.log((200.0 - m) / (t_a - m)) / (MU * math.pi)
    assert np.max(np.abs(r["up.T"] / t_a - 1.0)) <= 1e-6, how
    assert np.max(np.abs(r["pull.traction"] - share)) <= 1e-6, f"{how}: {r['pull.traction'].max()} vs {share}"
    assert abs(share - 0.7355) < 5e-5


@pytest.mark.parametrize("how", SLIDING_HOW)
def test_a_pull_roll_past_its_capstan_limit_slides_at_it(how, where):
    """pull_roll_slides_slow, started given with up at 100 N and down at the winder's 300 N (its
    equilibrium start is refused: webline/tests/test_traction.py): 300 N is above the capstan limit
    100 e^(0.3 pi) = 256.6 N, so the web slides, and while it slides at the kinetic limit (g = 1)
    T_a - m = (T_b - m) e^(-0.3 pi), m = rho_l v_w^2, to 1e-6 of T_a on the engine's own tensions
    (the web's mass on the wrap, m_w dv_w/dt, is below 1e-8 of it there). It ends steady on the
    slide: T_a = m + (300 - m)/2.566 = 116.9 N; to 1e-4, the swing the winder's mode (100 rad/s,
    damped by the span's d_r only) keeps at 4 s."""
    r = run(user_case("pull_roll_slides_slow", start="given", stop_time="4 s", T_start={"up": "100 N", "down": "300 N"}),
            how, where)
    m = RHO_L * r["pull.v_web"] ** 2
    sliding = (r["pull.traction"] >= 1.0 - 1e-9) & (r["pull.slip"] > 0.0) & (r["time"] > 1.5)
    assert sliding.sum() > len(sliding) / 4, how
    expected = m + (r["down.T"] - m) / EXP
    assert np.max(np.abs(r["up.T"][sliding] / expected[sliding] - 1.0)) <= 1e-6, how
    limit = RHO_L * 0.2 ** 2 + (300.0 - RHO_L * 0.2 ** 2) / EXP
    assert abs(r["up.T"][-1] / limit - 1.0) <= 1e-4, f"{how}: {r['up.T'][-1]} N vs {limit} N"
    assert abs(limit - 116.9) < 0.05


@pytest.mark.parametrize("how", HOW)
def test_a_nip_that_holds_gives_the_sources_draw_and_its_share(how, where):
    """nip_holds: a source at 1.9991115 m/s (strain 0), a nip roll speed-driven at 2 m/s (500 N, mu 0.5),
    a winder holding 300 N. The nip holds (it needs 300 - 100 = 200 N of mu N = 250 N), so span up
    carries the draw EA (2/1.9991115 - 1) = 100.0 N and the share is (300 - T_a)/250 = 0.8. To 1e-6."""
    r = run(user_case("nip_holds"), how, where)
    t_a = EA * (2.0 / 1.9991115059973346 - 1.0)
    assert np.max(np.abs(r["up.T"] / t_a - 1.0)) <= 1e-6, how
    assert np.max(np.abs(r["nip.traction"] - (300.0 - t_a) / 250.0)) <= 1e-6, how


@pytest.mark.parametrize("how", SLIDING_HOW)
def test_a_nip_past_its_limit_slides_at_it(how, where):
    """nip_slides (200 N, mu 0.5: 100 N of friction), started given with up at 100 N and down at the
    winder's 300 N: it needs 200 N, so it slides, and sliding T_a = T_b - mu N. It ends at
    300 - 100 = 200 N; to 1e-4, the winder's swing at 4 s (see the pull roll's)."""
    r = run(user_case("nip_slides", start="given", stop_time="4 s", T_start={"up": "100 N", "down": "300 N"}), how, where)
    sliding = (r["nip.traction"] >= 1.0 - 1e-9) & (r["nip.slip"] > 0.0) & (r["time"] > 1.5)
    assert sliding.sum() > len(sliding) / 4, how
    assert np.max(np.abs(r["up.T"][sliding] / (r["down.T"][sliding] - 100.0) - 1.0)) <= 1e-6, how
    assert abs(r["up.T"][-1] / 200.0 - 1.0) <= 1e-4, f"{how}: {r['up.T'][-1]} N"


@pytest.mark.parametrize("how", [*HOW, "parts"])
def test_a_braked_stopped_line_holds_its_tension(how, where):
    """brake_stopped_line: an unwinder braked by 20 N.m (R 0.2 m) feeds a pull roll that stops from
    2 m/s between 0.5 and 1.5 s; the line then stands for 10 s. A powder brake holds up to its rating
    at rest: the stopped roll's grip carries the film's R T < 20 N.m with no motion, so from 1 s to
    10 s after the stop the film's tension stays put (to 1e-6 relative: a brake that turned, as the
    old -B tanh(v/v_slip) did, lets it fall to 0 within a second), and the brake's torque never
    exceeds its rating (to 1e-9 of it: the integrators' error). In the Line FMU and the reference,
    and in the Roller FMU (the parts' co-simulation)."""
    r = run(user_case("brake_stopped_line", stop_time="11.5 s"), how, where)
    stood = r["time"] >= 2.5 - 1e-9
    T = r["film.T"][stood]
    assert T[0] > 10.0, f"{how}: {T[0]} N at 1 s after the stop"
    assert np.max(np.abs(T / T[0] - 1.0)) < 1e-6, f"{how}: {T.min()}..{T.max()} N"
    assert np.max(np.abs(r["unwind.tau"])) <= 20.0 * (1.0 + 1e-9), how


@pytest.mark.parametrize("how", HOW)
def test_static_friction_holds_past_the_kinetic_limit_up_to_mu_s(how, where):
    """The pull roll with "static": 1.2 (mu_s = 1.2 mu) against a winder holding T_b = m + (100 - m)
    e^(1.1 mu pi), m = rho_l v^2: holding it needs g = 1.1, past the kinetic limit but within the
    static one psi(0) = 1.2, so the web sticks (zero slip: span up keeps the source's 100 N draw) and
    the share in use is 1.1; to 1e-6 (the integrators' error is far below; the line starts steady).
    Without "static" (1) the same line asks more than its limit, and the start is refused."""
    m = RHO_L * 0.2 ** 2
    t_a = EA * (0.2 / 0.19991115059973347 - 1.0)
    t_b = m + (t_a - m) * math.exp(1.1 * MU * math.pi)
    scene = json.loads((USER_CASES / "pull_roll_sticks_slow.json").read_text())
    scene["line"][4]["drive"] = {"tension": f"{t_b!r} N"}
    scene["line"][2]["traction"]["static"] = 1.2
    r = run(parse_scene(json.dumps(scene), "static.json"), how, where)
    assert np.max(np.abs(r["up.T"] / t_a - 1.0)) <= 1e-6, how
    assert np.max(np.abs(r["pull.traction"] - 1.1)) <= 1e-6, f"{how}: {r['pull.traction'].max()}"
    assert np.max(np.abs(r["pull.slip"])) <= 1e-9, how
    del scene["line"][2]["traction"]["static"]
    with pytest.raises(SceneError, match="pull: needs .* N downstream, its capstan limit is"):
        run(parse_scene(json.dumps(scene), "kinetic.json"), how, where)


def test_a_sticking_contacts_own_mode_is_overdamped_as_its_closed_form_says():
    """A contact that sticks is a spring F'/delta in parallel with a damper F'/v_slip between the web's
    mass on the wrap m_w = rho_l R theta and the roll, F' = df/dg the friction's slope in the grip; its
    mode's roots m_w s^2 + (F'/v_slip) s + F'/delta = 0 are real where zeta = sqrt(F' delta/m_w)/(2 v_slip)
    > 1. The user's pull roll holding 100 N against 200 N (wrap: F' = sqrt(T'_a T'_b) mu theta
    cosh(mu theta g/2) = 141 N, m_w = 0.0218 kg, delta = 50 nm, v_slip = 1 mm/s): zeta = 9.0, roots
    -6.46e6 /s and -1.99e4 /s. The reference's Jacobian at its steady state (central differences, which
    take |s|'s slope at s = 0 as 0, as the closed form does) has both, real, to 1 %: the spans in series
    add their stiffness 2 EA/L (1.6e-4 of F'/delta) and damping 2 d_r EA/L (0.3 % of F'/v_slip)."""
    from webline.reference import LineODE
    from webline.scene import TRACTION_CREEP

    ode = LineODE(user_case("pull_roll_sticks_slow"))
    z = ode.initial_state()
    steps = np.maximum(np.abs(z), 1e-3) * 1e-7
    steps[ode.i_vw["pull"]] = 1e-9
    jacobian = np.column_stack([(ode.rhs(0.0, z + np.eye(ode.n)[j] * h) - ode.rhs(0.0, z - np.eye(ode.n)[j] * h)) / (2 * h)
                                for j, h in enumerate(steps)])
    roots = sorted(np.linalg.eigvals(jacobian), key=lambda x: x.real)[:2]
    contact = ode.evaluate(0.0, z)[1]["pull"]
    m = RHO_L * 0.2 ** 2
    a, b, w, g = 100.0 - m, 200.0 - m, MU * math.pi, contact["traction"]
    slope = math.sqrt(a * b) * w * math.cosh(w * g / 2.0)
    m_w, delta = contact["m_w"], TRACTION_CREEP
    zeta = math.sqrt(slope * delta / m_w) / (2.0 * V_SLIP)
    c, k = slope / V_SLIP, slope / delta
    expected = sorted([(-c - math.sqrt(c * c - 4 * m_w * k)) / (2 * m_w), (-c + math.sqrt(c * c - 4 * m_w * k)) / (2 * m_w)])
    assert zeta > 1.0 and abs(zeta - 9.0) < 0.05, zeta
    for got, want in zip(roots, expected):
        assert abs(got.imag) == 0.0 and abs(got.real / want - 1.0) < 1e-2, f"{got} vs {want}"
