"""`webline linearize` (webline/src/webline/statespace.py, docs/linearize.md).

On a line with one idler between two spans, A is checked against the Jacobian of
physics.md's equations written here by hand, and the idler's mode against the
closed form omega^2 = (R^2/J) (EA/L1 + EA/L2); on the paper rewind line, the
modes a controls engineer found by hand, the files written, and A after a run
to a time in the pull roll's ramp. A loop's margins (`--loop`) against the plant and
its PI computed apart; the Bode and step-response files; a hidden unstable tuning
warned before a run's results (`growth`), and a run that runs away stopped at its
bound (`bound`).
"""

import json
import math
import re

import numpy as np
import pytest
from scipy.io import loadmat

from webline.cli import main
from webline.scene import load_scene, parse_scene
from webline.statespace import linearize

from .conftest import ROOT

CASES = ROOT / "webline" / "tests" / "cases"
IDLER = CASES / "idler_between_spans.json"
REWIND = CASES / "rewind_ramp.json"

# idler_between_spans.json's values
EA = 4.5e9 * 50e-6 * 1.0
L1, L2 = 1.0, 2.0
R, J, B = 0.05, 0.01, 0.001
V_FEED, V_TAKEOFF = 0.5, 0.5002222222


def hand_jacobian(x1, omega, x2):
    """d/d(x1, omega, x2) of physics.md [E2], [E5] and [R1] for source -> span -> idler -> span -> sink:
    x1' = v_feed - R omega x1/L1, x2' = R omega x1/L1 - v_takeoff x2/L2 (the web arrives with the
    first span's strain, 1 + eps1 = L1/x1), J omega' = R (T2 - T1) - b omega, T = EA (L/x - 1)."""
    return np.array([
        [-R * omega / L1, -R * x1 / L1, 0.0],
        [R * EA * L1 / (J * x1**2), -B / J, -R * EA * L2 / (J * x2**2)],
        [R * omega / L1, R * x1 / L1, -V_TAKEOFF / L2],
    ])


def test_idler_mode_and_jacobian_against_the_equations(fmus):
    ss = linearize(load_scene(IDLER), fmu_dir=fmus)
    free = ["first.unstretchedLength", "idler.omega", "second.unstretchedLength"]
    held = ["feed.omega", "takeoff.omega"]  # speeds the drives prescribe: states with zero rows and columns
    assert sorted(ss.states) == sorted(free + held)
    i = [ss.states.index(s) for s in free]
    h = [ss.states.index(s) for s in held]
    assert not np.any(ss.A[h]) and not np.any(ss.A[:, h])
    assert ss.moving() == []  # it starts in its steady state
    A = ss.A[np.ix_(i, i)]
    A_hand = hand_jacobian(*ss.x[i])
    # The Line's central differences are about 1e-7 relative (docs/line-fmu.md); 1e-5 as the issue asks.
    np.testing.assert_allclose(A, A_hand, rtol=1e-5, atol=0)
    # The motor torque drives the idler alone; the first span's tension follows its stretch.
    np.testing.assert_allclose(ss.B[i, ss.input_index("idler.tau_m")], [0.0, 1 / J, 0.0], rtol=1e-5, atol=0)
    x1 = ss.x[i[0]]
    assert ss.C[ss.output_index("first.T"), i[0]] == pytest.approx(-EA * L1 / x1**2, rel=1e-5)

    (mode,) = [m for m in ss.modes() if m.eigenvalue.imag > 0]
    assert mode.parts[0][0] == "idler"
    omega_closed = math.sqrt(R**2 / J * (EA / L1 + EA / L2))
    # Transport shifts it by about (v/L)^2/omega^2 (3e-6 here), the 1 + eps factors by about eps/2 (2.2e-4).
    assert mode.omega_n == pytest.approx(omega_closed, rel=1e-3)
    lam_hand = np.linalg.eigvals(A_hand)
    assert mode.omega_n == pytest.approx(np.max(np.abs(lam_hand)), rel=1e-6)
    assert mode.error < 1e-6 * mode.omega_n


def test_rewind_line_modes_and_files(fmus, tmp_path, capsys):
    """The modes found by hand on this line: the dancer at 71.2 Hz, the unwinder at 3.1 Hz with damping 0.036."""
    assert main(["linearize", str(REWIND), "--bode", "unwind.tau_m:entry.T", "--out", str(tmp_path),
                 "--fmu-dir", str(fmus)]) == 0
    text = capsys.readouterr().out
    rows = {float(r.split()[0]): r for r in text.splitlines() if re.match(r"\s+\d+\.\d+\s+\S+\s+0\.\d{4}\s", r)}
    dancer = min(rows, key=lambda f: abs(f - 71.2))
    unwind = min(rows, key=lambda f: abs(f - 3.1))
    assert dancer == pytest.approx(71.2, abs=0.05) and "dancer 98 % (y, y_dot)" in rows[dancer]
    assert unwind == pytest.approx(3.1, abs=0.05) and re.search(r"\s0\.03[56]\d\s.*unwind \d+ %", rows[unwind])

    m = loadmat(tmp_path / "rewind_ramp_linear.mat", squeeze_me=True)
    n = len(m["states"])
    assert m["A"].shape == (n, n) and m["B"].shape == (n, len(m["inputs"])) and m["C"].shape == (len(m["outputs"]), n)
    assert "dancer.F_load" in list(m["inputs"]) and "entry.T" in list(m["outputs"]) and "dancer.y" in list(m["states"])
    lam = np.linalg.eigvals(m["A"])
    unwinder = lam[np.argmin(np.abs(np.abs(lam) / (2 * math.pi) - 3.1))]
    assert -unwinder.real / abs(unwinder) == pytest.approx(0.036, abs=0.0005)
    assert (tmp_path / "rewind_ramp_bode_unwind.tau_m_entry.T.png").stat().st_size > 10_000


def test_linearized_at_a_time_in_the_ramp(fmus):
    """At 2 s the pull roll runs at 6 m/s (5 -> 7 m/s from 1 s to 3 s): the feed span's own entry of A is
    -v_pull/L (physics.md [E2]), which the run to that time in Model Exchange must have reached; the
    line is not steady there, and says so, the pull roll accelerating at 1 m/s2."""
    ss = linearize(load_scene(REWIND), at=2.0, fmu_dir=fmus)
    k = ss.states.index("feed.unstretchedLength")
    v, omega = (ss.y[ss.outputs.index(f"pull.{q}")] for q in ("v", "omega"))
    assert v == pytest.approx(6.0, rel=1e-9)
    assert ss.A[k, k] == pytest.approx(-6.0 / 1.2, rel=1e-6)
    assert dict(ss.moving())["pull.omega"] * v / omega == pytest.approx(1.0, rel=1e-9)


def test_an_unknown_signal_is_refused_by_name(fmus, tmp_path, capsys):
    assert main(["linearize", str(IDLER), "--bode", "idler.tau_m:nothing.T", "--out", str(tmp_path),
                 "--fmu-dir", str(fmus)]) == 2
    err = capsys.readouterr().err
    assert "no output 'nothing.T'" in err and "second.T" in err
    assert not list(tmp_path.iterdir())


# ------------------------------------------------------------------ a loop as a controls engineer reads it

LOOP = ROOT / "webline" / "scenes" / "rewind_ramp_loop.json"
PET = {"E": "4.5 GPa", "thickness": "50 um", "width": "1 m", "density": "1390 kg/m3", "d_r": "1 ms"}


def unwinder_line(drive):
    """An unwinder (8 kg.m2, 0.5 m) with `drive`, a 2 m span, a pull roll at 10 m/s (a sink)."""
    return parse_scene(json.dumps({
        "name": "loop", "stop_time": "1 s", "step": "10 ms", "start": "equilibrium", "webs": {"PET": PET},
        "line": [
            {"type": "unwinder", "name": "unwind", "J": "8 kg.m2", "R": "0.5 m", "b": "0.1 N.m.s", "strain": 0.0,
             "v_start": "10 m/s", "drive": drive},
            {"type": "span", "name": "entry", "L": "2 m", "web": "PET", "effects": ["includeDamping"]},
            {"type": "sink", "name": "pull", "speed": "10 m/s"},
        ],
        "record": ["entry.T"]}), "loop.json")


def crossings(hz, L):
    """The margins read off L on a fine grid, by linear interpolation between its points (this test's own
    reading): [(Hz, gain margin dB)] where arg L = -180 deg, [(Hz, phase margin deg)] where |L| = 1."""
    db, deg = 20 * np.log10(np.abs(L)), np.degrees(np.angle(-L))  # arg(-L): 0 where arg L = -180
    lf = np.log10(hz)
    gain, phase = [], []
    for j in np.nonzero(np.sign(deg[:-1]) != np.sign(deg[1:]))[0]:
        if abs(deg[j] - deg[j + 1]) < 90:  # a crossing of 0, not the jump at +-180
            s = deg[j] / (deg[j] - deg[j + 1])
            gain.append((10 ** (lf[j] + s * (lf[j + 1] - lf[j])), -(db[j] + s * (db[j + 1] - db[j]))))
    for j in np.nonzero(np.sign(db[:-1]) != np.sign(db[1:]))[0]:
        s = db[j] / (db[j] - db[j + 1])
        phase.append((10 ** (lf[j] + s * (lf[j + 1] - lf[j])), deg[j] + s * (deg[j + 1] - deg[j])))
    return gain, phase


@pytest.mark.parametrize("gains", [{"kp": 0.2, "ki": 2.0}, {"kp": 2.0, "ki": 20.0, "lag": "20 ms"}])
def test_loop_margins_match_the_plant_and_the_pi_computed_apart(fmus, gains):
    """`--loop` breaks the loop inside the Line FMU at its torque (margins.OpenLoop). Independently: the
    plant alone (the same line with a torque drive holding the loop's steady torque, linearized on its own),
    the PI C(s) = kp + ki/s in closed form and the motor's lag 1/(1 + s T_m), L = sign C(s) P(s) / (1 + s T_m) on a
    grid of 20000 points a decade, its crossings interpolated: the margins agree to 0.5 deg and 0.1 dB, the
    crossover frequencies to 1e-3 (the grid's spacing is 1.2e-4 of a frequency; the two linearizations
    differ only by the derivatives' 1e-7)."""
    from webline.margins import OpenLoop

    pi = {"measure": "entry.T", "set": "400 N", **gains}
    looped = unwinder_line({"pi": pi})
    ss = linearize(looped, fmu_dir=fmus)
    m = OpenLoop(ss, "unwind").margins()
    assert m.phase, "a crossover of |L| = 1"

    torque = float(ss.y[ss.output_index("unwind.tau")])
    plant = linearize(unwinder_line({"torque": f"{torque!r} N.m"}), fmu_dir=fmus)
    assert plant.y[plant.output_index("entry.T")] == pytest.approx(400.0, rel=1e-9), "the same operating point"
    A, b = plant.A, plant.B[:, plant.input_index("unwind.tau_m")]
    c, d = plant.C[plant.output_index("entry.T")], plant.D[plant.output_index("entry.T"), plant.input_index("unwind.tau_m")]
    sign = looped.component("unwind").drive.loop.sign
    lag = looped.component("unwind").drive.loop.lag
    hz = np.geomspace(1e-2, 1e3, 5 * 20000)
    s = 2j * np.pi * hz
    n = A.shape[0]
    P = np.array([c @ np.linalg.solve(si * np.eye(n) - A, b) + d for si in s])
    # The loop's torque c = -sign C(s) T and T = P (c + d): c = -L (c + d) with L = sign C P.
    L = sign * (gains["kp"] + gains["ki"] / s) * P / (1 + s * lag)
    gain, phase = crossings(hz, L)
    print(f"margins: {m}; apart: gain {gain}, phase {phase}")
    assert len(phase) == len(m.phase) and len(gain) == len(m.gain)
    for (f, pm), c_ in zip(phase, m.phase):
        assert c_.margin == pytest.approx(pm, abs=0.5) and c_.frequency == pytest.approx(f, rel=1e-3)
    for (f, gm), c_ in zip(gain, m.gain):
        assert c_.margin == pytest.approx(gm, abs=0.1) and c_.frequency == pytest.approx(f, rel=1e-3)


def test_bode_and_step_response_files(fmus, tmp_path, capsys):
    """--bode writes (Hz, dB, deg) beside its PNG, over the line's modes (a decade around them, not down to
    a roll's radius), --step-response a CSV and PNG whose end is the response at 0 Hz (its modes settled),
    --loop prints the margins."""
    assert main(["linearize", str(LOOP), "--loop", "unwind", "--bode", "unwind.tau_m:entry.T", "--step-response",
                 "unwind.tau_m:entry.T", "--out", str(tmp_path), "--fmu-dir", str(fmus)]) == 0
    text = capsys.readouterr().out
    assert re.search(r"phase margin +\d+\.\d+ deg at the gain crossover \d", text), text
    ss = linearize(load_scene(LOOP), fmu_dir=fmus)
    bode = np.loadtxt(tmp_path / "rewind_ramp_loop_bode_unwind.tau_m_entry.T.csv", delimiter=",", skiprows=1)
    header = (tmp_path / "rewind_ramp_loop_bode_unwind.tau_m_entry.T.csv").read_text().splitlines()[0]
    assert header == "frequency [Hz],magnitude [dB],phase [deg]"
    h = ss.response("unwind.tau_m", "entry.T", bode[:, 0])
    np.testing.assert_allclose(bode[:, 1], 20 * np.log10(np.abs(h)), atol=1e-6)
    np.testing.assert_allclose(np.cos(np.radians(bode[:, 2])), np.cos(np.angle(h)), atol=1e-6)
    assert 1e-3 < bode[0, 0] < 0.1 and 100 < bode[-1, 0] < 2000, "a decade beyond the line's modes"
    step = np.loadtxt(tmp_path / "rewind_ramp_loop_step_unwind.tau_m_entry.T.csv", delimiter=",", skiprows=1)
    dc = ss.response("unwind.tau_m", "entry.T", [1e-7])[0].real
    assert step[-1, 1] == pytest.approx(dc, abs=0.01 * np.max(np.abs(step[:, 1]))), "settled at the 0 Hz gain"
    assert step[0, 1] == 0.0
    for name in ("bode_unwind.tau_m_entry.T", "step_unwind.tau_m_entry.T", "loop_unwind"):
        assert (tmp_path / f"rewind_ramp_loop_{name}.png").stat().st_size > 10_000


def unstable(stop="4 s"):
    """rewind_ramp_loop.json, its unwinder wound and its loop tuned kp 0.5, ki 5, no ramp: a mode near 4.6 Hz
    grows; a set point 0.01 N up at 0.1 s starts it."""
    d = json.loads(LOOP.read_text())
    d["stop_time"] = stop
    for c in d["line"]:
        if c["name"] == "unwind":
            c["wound"] = {"thickness": "80 um"}
            c["drive"]["pi"].update(kp=0.5, ki=5.0, set={"table": [["0 s", "400 N"], ["0.1 s", "400 N"], ["0.1 s", "400.01 N"]]})
        if c["name"] == "pull":
            c["drive"] = {"speed": "5 m/s"}
    return d


def test_a_growing_loop_is_warned_before_the_results(fmus, tmp_path, capsys):
    """`webline run` linearizes the line first and names the growing mode, its frequency to 4 digits, before
    the run's summary; the run's own oscillation, its zero crossings over the last 2 s, has that frequency
    to 1 %. `linearize` marks it."""
    scene = tmp_path / "unstable.json"
    scene.write_text(json.dumps(unstable()))
    assert main(["run", str(scene), "--out", str(tmp_path), "--no-plot", "--fmu-dir", str(fmus)]) == 0
    text = capsys.readouterr().out
    warning = re.search(r"warning: the line is unstable at the start: an oscillation at ([\d.]+) Hz .*damping ratio (-[\d.]+).*"
                        r"the states it moves most: (.*?);", text)
    assert warning, text
    assert text.index("warning: the line is unstable") < text.index("rewind_ramp_loop: engine"), "before the results"
    assert "unwind.omega" in warning.group(3) and "unwind.loop.I" in warning.group(3)
    csv = np.genfromtxt(tmp_path / "rewind_ramp_loop.csv", delimiter=",", names=True)
    t, T = csv["time_s"], csv["entryT_N"] - 400.0
    late = t > t[-1] - 2.0
    zero = t[late][1:][np.sign(T[late][1:]) != np.sign(T[late][:-1])]
    measured = (len(zero) - 1) / (2 * (zero[-1] - zero[0]))
    print(f"warned {warning.group(1)} Hz, damping {warning.group(2)}; the run oscillates at {measured:.4g} Hz")
    assert float(warning.group(1)) == pytest.approx(measured, rel=0.01)
    assert np.max(np.abs(T[late])) > 100 * np.max(np.abs(T[(t > 0.1) & (t < 0.6)])), "it grows"

    assert main(["linearize", str(scene), "--out", str(tmp_path), "--fmu-dir", str(fmus)]) == 0
    grows = [r for r in capsys.readouterr().out.splitlines() if "GROWS" in r]
    assert len(grows) == 1 and float(grows[0].split()[0]) == pytest.approx(4.6, abs=0.1)


def test_a_stable_loop_runs_without_a_warning(fmus, tmp_path, capsys):
    """The shipped loop's line at its own tuning: no mode grows, nothing is said; a wound roll's radius
    drifts, which is not a loop's growth."""
    d = json.loads(LOOP.read_text())
    d["stop_time"] = "0.5 s"
    d["line"][0]["wound"] = {"thickness": "80 um"}
    scene = tmp_path / "stable.json"
    scene.write_text(json.dumps(d))
    assert main(["run", str(scene), "--out", str(tmp_path), "--no-plot", "--fmu-dir", str(fmus)]) == 0
    assert "warning" not in capsys.readouterr().out


@pytest.mark.parametrize("engine", ["line", "reference"])
def test_a_run_whose_tension_runs_away_stops_at_the_bound(fmus, tmp_path, capsys, engine):
    """The unstable tuning without the motor's torque limit (which holds it to a limit cycle of about 2 kN)
    grows until the entry span's tension passes 10 % of its EA (48 kN on 80 um paper, 1.2 m wide): the
    run stops there with exit code 2 and a message naming the span, the value, the time and the bound, in
    the Line FMU's run and in the reference alike (bound.py)."""
    d = unstable("12 s")
    del d["line"][0]["drive"]["pi"]["limit"]
    scene = tmp_path / "runaway.json"
    scene.write_text(json.dumps(d))
    assert main(["run", str(scene), "--engine", engine, "--out", str(tmp_path), "--no-plot", "--fmu-dir", str(fmus)]) == 2
    err = capsys.readouterr().err
    found = re.search(r"the tension of span '(entry|feed)' reached (-?[\d.e+]+) N at t = ([\d.]+) s, past the bound of "
                      r"4\.8e\+04 N \(10 % of its web's EA", err)
    assert found, err
    assert abs(float(found.group(2))) == pytest.approx(48_000, rel=0.02) and 8.0 < float(found.group(3)) < 11.0
    assert not (tmp_path / "rewind_ramp_loop.csv").exists()
