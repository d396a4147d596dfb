"""Rollers that slip, nips that hold (docs/physics.md, "Rollers that slip"): the closed forms in the
monolithic reference and the Line FMU (FMI 2.0 Co-Simulation at 1 and 10 ms, Model Exchange, and
FMI 3.0), the scene keys and their refusals, and what `webline run` reports.

The closed forms hold where the web slides at |s| >= 50 v_slip (tanh(50) is 1 to the last bit), to
1e-6 of each quantity's scale: the reference integrates at rtol 1e-10 and the Line FMU at its
default tolerance, 1e-9 on strains and speeds; the web's mass on the wrap adds m_w dv_w/dt, of
order 1e-9 of the tension in these steady lines.
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

from .conftest import SCENES

PET = {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3", "d_r": "1 ms"}
EA = 4.5e9 * 50e-6
RHO_L = 1390.0 * 50e-6 * 1.0  # the web's mass per length: its centripetal force rho_l v^2 relieves the wrap
MU, WRAP, MU_NIP, LOAD, V_SLIP = 0.3, math.radians(90.0), 0.5, 200.0, 1e-3
DAMPED = {"web": "PET", "effects": ["includeDamping"]}


def scene(line, record, start="equilibrium", stop="0.3 s"):
    return parse_scene(json.dumps({"name": "traction", "stop_time": stop, "step": "1 ms", "start": start,
                                   "webs": {"PET": PET}, "line": line, "record": record}), "traction.json")


def sliding_line(nip_side=None):
    """A drag roll (a wrap) and a nip roll, both driven slower than the web, which slides over both."""
    return scene([
        {"type": "source", "name": "src", "speed": "5 m/s", "strain": 1e-3},
        {"type": "span", "name": "a", "L": "1 m", **DAMPED},
        {"type": "roller", "name": "drag", "R": "0.1 m", "wrap": "90 deg", "drive": {"speed": "4.5 m/s"},
         "traction": {"mu": MU}},
        {"type": "span", "name": "b", "L": "1 m", **DAMPED},
        {"type": "roller", "name": "nip", "R": "0.1 m", "drive": {"speed": "4.4 m/s"},
         "nip": {"load": f"{LOAD} N", "mu": MU_NIP, **({"side": nip_side} if nip_side else {})}},
        {"type": "span", "name": "c", "L": "1 m", **DAMPED},
        {"type": "sink", "name": "snk", "speed": "5.005 m/s"},
    ], ["a.T", "b.T", "c.T", "drag.v_web", "drag.slip", "drag.traction", "nip.v_web", "nip.slip", "nip.traction"])


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


def check_sliding(result, engine):
    for key, value in expected_sliding().items():
        x = result.column(key)
        assert np.max(np.abs(x - value)) <= 1e-6 * abs(value), f"{engine}: {key} {x.min()}..{x.max()} vs {value}"
    for roll in ("drag", "nip"):
        assert result.column(f"{roll}.slip").min() >= 50 * V_SLIP, engine
        assert result.column(f"{roll}.traction").min() >= 0.99, engine


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
    assert (fmus / linefmu.TEMPLATE / "fmi2" / "binaries").is_dir()
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


def test_webline_run_says_when_the_idler_slid(line_dir, tmp_path, capsys):
    """The shipped scene: the idler skids on the steep ramp and holds on the gentle one."""
    assert webline_main(["run", str(SCENES / "idler_skid.json"), "--out", str(tmp_path), "--fmu-dir", str(line_dir)]) == 0
    out = capsys.readouterr().out
    said = next(line for line in out.splitlines() if line.strip().startswith("idler:"))
    assert "100 % of its traction at most" in said and "it slid from t = 0.22" in said, said
    table = np.genfromtxt(tmp_path / "idler_skid.csv", delimiter=",", names=True)
    used = table["idlertraction_1"]
    gentle = table["time_s"] > 2.5
    assert used[gentle].max() < 0.7, "the gentle ramp leaves it a third of its traction"
