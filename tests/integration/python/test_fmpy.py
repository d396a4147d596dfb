"""The packaged FMU through FMPy: archive, exports, co-simulation against the
exact solution, sensor units, FMU state, parameter checks and the defaults."""

import html
import re
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import mpmath
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException
from fmpy.fmi2 import fmi2Error, fmi2LastSuccessfulTime
from fmpy.simulation import instantiate_fmu
from fmpy.validation import validate_fmu
from mpmath import mpf

from conftest import simulate_fmu, ROOT, ABS_STRAIN, INPUTS, compare, exact_solution, input_pieces, step_table, tension

sys.path.insert(0, str(ROOT / "fmu"))
from package import FMI3_FUNCTIONS  # noqa: E402

# --------------------------------------------------------------------------
# (a) validation, (b) archive, (c) exported symbols


def test_fmpy_validation_finds_no_problem(fmu_path):
    assert validate_fmu(str(fmu_path)) == []


def test_archive_holds_exactly_its_files_with_clean_paths(fmu_path):
    with zipfile.ZipFile(fmu_path) as zf:
        names = zf.namelist()
        assert zf.testzip() is None, "a member of the FMU is corrupted"
    assert sorted(names) == sorted(
        ["modelDescription.xml", "binaries/linux64/ConvertingSpan.so", "binaries/win64/ConvertingSpan.dll",
         "binaries/aarch64-linux/ConvertingSpan.so", "documentation/index.html", "resources/webs.json"]
    )
    for name in names:
        assert "\\" not in name, f"{name!r} uses a backslash separator"
        assert not name.startswith(("./", "/")), f"{name!r} is not a plain relative path"
        assert "/./" not in name and "//" not in name, name


def test_documentation_lists_every_variable_and_the_guid(fmu_path, model_description):
    with zipfile.ZipFile(fmu_path) as zf:
        doc = zf.read("documentation/index.html").decode("utf-8")
    missing = [v.name for v in model_description.modelVariables if f"<code>{html.escape(v.name)}</code>" not in doc]
    assert not missing, f"the documentation does not name the variables {missing}"
    assert model_description.guid in doc
    for placeholder in ("<!-- VARIABLES -->", "<!-- UNIT_CHOICES -->", "<!-- GUID -->", "<!-- VERSION -->", "<!-- WEBS -->"):
        assert placeholder not in doc, f"the placeholder {placeholder} was not filled in"


FMI2_FUNCTIONS = sorted(
    """
    fmi2GetTypesPlatform fmi2GetVersion fmi2SetDebugLogging fmi2Instantiate fmi2FreeInstance
    fmi2SetupExperiment fmi2EnterInitializationMode fmi2ExitInitializationMode fmi2Terminate fmi2Reset
    fmi2GetReal fmi2GetInteger fmi2GetBoolean fmi2GetString
    fmi2SetReal fmi2SetInteger fmi2SetBoolean fmi2SetString
    fmi2GetFMUstate fmi2SetFMUstate fmi2FreeFMUstate fmi2SerializedFMUstateSize fmi2SerializeFMUstate
    fmi2DeSerializeFMUstate fmi2GetDirectionalDerivative
    fmi2EnterEventMode fmi2NewDiscreteStates fmi2EnterContinuousTimeMode fmi2CompletedIntegratorStep
    fmi2SetTime fmi2SetContinuousStates fmi2GetDerivatives fmi2GetEventIndicators fmi2GetContinuousStates
    fmi2GetNominalsOfContinuousStates
    fmi2SetRealInputDerivatives fmi2GetRealOutputDerivatives fmi2DoStep fmi2CancelStep
    fmi2GetStatus fmi2GetRealStatus fmi2GetIntegerStatus fmi2GetBooleanStatus fmi2GetStringStatus
    """.split()
)


def test_the_library_exports_the_44_fmi2_and_75_fmi3_functions_and_nothing_else(unzipdir):
    assert len(FMI2_FUNCTIONS) == 44 and len(set(FMI2_FUNCTIONS)) == 44
    nm = shutil.which("nm")
    assert nm, "nm (binutils) is needed"
    so = Path(unzipdir) / "binaries" / "linux64" / "ConvertingSpan.so"
    out = subprocess.run([nm, "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True).stdout
    symbols = [line.split()[-1] for line in out.splitlines() if line.strip()]
    types = {line.split()[-1]: line.split()[-2] for line in out.splitlines() if line.strip()}
    # The same library serves the FMI 3.0 FMU (fmi/abi): its functions are exported too.
    expected = sorted(set(FMI2_FUNCTIONS) | FMI3_FUNCTIONS)
    assert sorted(symbols) == expected, (
        f"extra: {sorted(set(symbols) - set(expected))}, missing: {sorted(set(expected) - set(symbols))}"
    )
    assert all(types[s] == "T" for s in symbols), "every export must be a function in the text section"


# --------------------------------------------------------------------------
# (d) co-simulation against the exact solution

REAL_OUTPUTS = [
    "v", "T", "web_a.F", "web_b.F", "web_b.eps",
    "summary_Tension", "summary_Length", "summary_Strain", "summary_Stress", "unstretchedLength",
]
BASE = {"web_a.v": 5.0, "web_a.eps": 1e-3, "web_b.v": 5.0}


def simulate(unzipdir, params, table, stop, h, outputs=REAL_OUTPUTS, **kw):
    """FMPy co-simulation; params are start values (parameters and the inputs' start values)."""
    return simulate_fmu(
        unzipdir, fmi_type="CoSimulation", start_values=params, input=table, output=outputs,
        stop_time=stop, output_interval=h, **kw,
    )


def check_exact(scenario, result, defaults, params, table):
    """Every output at every communication point against the exact solution."""
    p = dict(defaults)
    p.update(params)
    times = list(result["time"])
    ref = exact_solution(p, table, times)
    EA = p["wp2.E"] * p["wp2.width"] * p["wp2.thickness"]
    A = p["wp2.width"] * p["wp2.thickness"]
    force_floor = ABS_STRAIN * EA
    assert p["toUnitV"] == 1 and p["toUnitF"] == 1 and p["useSensor"]
    for name in ("T", "web_a.F", "web_b.F", "summary_Tension"):
        compare(scenario, name, result[name], ref["tension"], force_floor, times=times)
    compare(scenario, "summary_Stress", result["summary_Stress"], [T / mpf(A) for T in ref["tension"]],
            ABS_STRAIN * p["wp2.E"], times=times)
    for name in ("summary_Strain", "web_b.eps"):
        compare(scenario, name, result[name], ref["strain"], ABS_STRAIN, times=times)
    compare(scenario, "unstretchedLength", result["unstretchedLength"], ref["x"], ABS_STRAIN * p["L"], times=times)
    compare(scenario, "v", result["v"], ref["v"], 0.0, times=times)
    assert np.all(result["summary_Length"] == p["L"])
    return ref


# Each input steps at its own time; 0.55 and 1.25 are not on the 0.1 s or
# 1 s grids, so FMPy must insert them as communication points.
STEPS = [
    (0.2, {"web_b.v": 5.005}),
    (0.55, {"web_a.eps": 2e-3}),
    (0.8, {"web_a.v": 4.99}),
    (1.25, {"web_a.v": 2.0, "web_b.v": 2.002}),
    (1.6, {"web_b.v": 2.0, "web_a.eps": 5e-4}),
]


@pytest.mark.parametrize("h", [1e-3, 0.1, 1.0])
def test_step_changes_in_each_input_are_exact_for_any_communication_step(unzipdir, defaults, h):
    table = step_table(6.0, BASE, STEPS)
    result = simulate(unzipdir, {}, table, 6.0, h)
    times = result["time"]
    for t, _ in STEPS:
        assert np.any(np.isclose(times, t, rtol=0, atol=1e-12)), f"no communication point at the step t = {t}"
    check_exact(f"input steps, h = {h:g}", result, defaults, {}, table)
    # the steps did something: the strain settles at the last speed ratio and
    # arriving strain (time constant L/v_b = 0.5 s at 2 m/s)
    eps_end = result["summary_Strain"][-1]
    assert abs(eps_end - 5e-4) < 1e-6


def test_communication_step_1e_5_short_run(unzipdir, defaults):
    table = step_table(0.05, BASE, [(0.01, {"web_b.v": 5.005}), (0.03, {"web_a.eps": 2e-3})])
    result = simulate(unzipdir, {}, table, 0.05, 1e-5)
    assert len(result) >= 5001
    check_exact("input steps, h = 1e-5 (5000 steps)", result, defaults, {}, table)


def test_speeds_near_zero(unzipdir, defaults):
    """Stopped line, creeping line (1e-9 m/s) fed from one end or from both:
    lambda = 1e-9/s, so the strain moves by parts in 1e7 over the run."""
    initial = {"web_a.v": 0.0, "web_a.eps": 1e-3, "web_b.v": 0.0}
    steps = [
        (100.0, {"web_b.v": 1e-9}),  # drawn out at b only: x decays with lambda = 1e-9
        (300.0, {"web_a.v": 1e-9, "web_b.v": 0.0}),  # fed in at a only: x grows linearly
        (500.0, {"web_b.v": 1e-9}),  # both ends at 1e-9
        (700.0, {"web_a.v": 0.0}),
        (900.0, {"web_b.v": 0.0}),  # stopped again
    ]
    table = step_table(1000.0, initial, steps)
    result = simulate(unzipdir, {}, table, 1000.0, 1.0)
    ref = check_exact("speeds near zero (0 and 1e-9 m/s), h = 1 s", result, defaults, {}, table)
    T = result["T"]
    i100, i300, i900 = (int(np.searchsorted(result["time"], t)) for t in (100.0, 300.0, 900.0))
    assert np.all(T[: i100 + 1] == T[0]), "a stopped line must keep its tension exactly"
    assert T[i300] > T[i100] + 0.1, "drawing at 1e-9 m/s for 200 s raises T by ~0.17 N"
    assert np.all(T[i900:] == T[i900]), "stopped again: constant tension"
    assert float(ref["tension"][i300] - ref["tension"][i100]) > 0.1


@pytest.mark.parametrize("h", [0.01, 0.1, 1.0])
def test_very_short_fast_span_with_large_steps(unzipdir, defaults, h):
    """L = 5 mm at 30 m/s: lambda = 6000/s, lambda*h = 60 ... 6000."""
    params = {"L": 5e-3}
    base = {"web_a.v": 30.0, "web_a.eps": 1e-3, "web_b.v": 30.0}
    table = step_table(5.0, base, [(0.05, {"web_b.v": 30.03}), (2.5, {"web_b.v": 30.0, "web_a.eps": 2e-3})])
    result = simulate(unzipdir, params, table, 5.0, h)
    check_exact(f"L = 5 mm at 30 m/s, h = {h:g} (lambda*h = {6000 * h:g})", result, defaults, params, table)
    assert np.all(np.isfinite(result["T"]))


@pytest.mark.parametrize("h", [1e-3, 0.1])
def test_start_away_from_equilibrium(unzipdir, defaults, h):
    params = {"startAtEquilibrium": False, "eps_start": 3e-3}
    table = step_table(2.0, BASE, [])
    result = simulate(unzipdir, params, table, 2.0, h)
    assert result["summary_Strain"][0] == pytest.approx(3e-3, rel=1e-15)
    check_exact(f"start at eps_start = 3e-3, h = {h:g}", result, defaults, params, table)
    # relaxes towards eps_a = 1e-3 with time constant L/v_b = 0.2 s (10 time constants)
    assert 1e-3 < result["summary_Strain"][-1] < 1e-3 + 1e-7


@pytest.mark.parametrize("va, ea, vb", [(5.0, 2e-3, 5.005), (30.0, 1e-3, 29.99), (1e-9, 1e-3, 1.5e-9), (0.0, 3e-3, 2.0)])
def test_start_at_equilibrium_with_a_draw_stays_steady(unzipdir, defaults, va, ea, vb):
    """(1+eps_b) = (v_b/v_a)(1+eps_a) (eps_b = eps_a for v_a = 0): with the
    inputs held, the span starts and stays there (except v_a = 0: it is then
    drawn empty from eps_a on)."""
    table = step_table(1.0, {"web_a.v": va, "web_a.eps": ea, "web_b.v": vb}, [])
    result = simulate(unzipdir, {}, table, 1.0, 0.01)
    check_exact(f"start at equilibrium, v_a = {va:g}, eps_a = {ea:g}, v_b = {vb:g}", result, defaults, {}, table)
    expected = ea if va == 0 else (vb / va) * (1 + ea) - 1
    assert result["summary_Strain"][0] == pytest.approx(expected, rel=1e-12)
    if va > 0:
        assert np.allclose(result["summary_Strain"], expected, rtol=1e-12, atol=0)


def test_damping_makes_tension_feed_through_from_the_inputs(unzipdir, defaults):
    params = {"includeDamping": True, "wp2.d_r": 0.01}
    steps = [(0.2, {"web_b.v": 5.005}), (0.5, {"web_a.eps": 2e-3}), (0.7, {"web_a.v": 4.99})]
    table = step_table(1.0, BASE, steps)
    result = simulate(unzipdir, params, table, 1.0, 1e-3)
    check_exact("damping on (d_r = 0.01 s), input steps, h = 1e-3", result, defaults, params, table)
    # At the sample after the speed step T jumps by E2*A2*d_r*dv_b/x (~42 N),
    # much more than the elastic change over one step (~4 N).
    i = int(np.searchsorted(result["time"], 0.2))
    assert result["time"][i] == pytest.approx(0.2)
    assert result["T"][i + 1] - result["T"][i] > 30


def test_damping_feedthrough_without_a_step(unzipdir, model_description, defaults):
    """Setting an input changes T at once (before any fmi2DoStep) by the damping term."""
    vr = {v.name: v.valueReference for v in model_description.modelVariables}
    fmu = instantiate_fmu(unzipdir, model_description, "CoSimulation")
    try:
        fmu.setupExperiment(startTime=0.0)
        fmu.setBoolean([vr["includeDamping"]], [True])
        fmu.setReal([vr["wp2.d_r"]], [0.01])
        fmu.enterInitializationMode()
        fmu.exitInitializationMode()
        T0 = fmu.getReal([vr["T"]])[0]
        results = {}
        for name, value in (("web_b.v", 5.005), ("web_a.eps", 2e-3), ("web_a.v", 4.99)):
            fmu.setReal([vr[n] for n in INPUTS], [BASE[n] for n in INPUTS])
            assert fmu.getReal([vr["T"]])[0] == T0
            fmu.setReal([vr[name]], [value])
            results[name] = fmu.getReal([vr["T"]])[0]
    finally:
        fmu.terminate()
        fmu.freeInstance()
    p = dict(defaults)
    p.update({"includeDamping": True, "wp2.d_r": 0.01})
    EA = p["wp2.E"] * p["wp2.width"] * p["wp2.thickness"]
    with mpmath.workdps(40):
        x = mpf(1) / (1 + mpf(1e-3))
        for name, value in (("web_b.v", 5.005), ("web_a.eps", 2e-3), ("web_a.v", 4.99)):
            inputs = dict(BASE)
            inputs[name] = value
            piece = input_pieces(None, inputs)[0]
            compare("damping feedthrough at t = 0 (FMU2Slave)", f"T after setting {name}",
                    [results[name]], [tension(p, x, piece)], ABS_STRAIN * EA)
            assert abs(results[name] - T0) > 1, f"T does not feed through from {name}"


@pytest.mark.parametrize("damping", [False, True])
def test_prevent_negative_tension_slack_phase_and_retension(unzipdir, defaults, damping):
    params = {"preventNegativeTension": True, "includeDamping": damping, "wp2.d_r": 0.01}
    steps = [(0.2, {"web_b.v": 4.99}), (1.5, {"web_b.v": 5.01})]
    table = step_table(3.0, BASE, steps)
    result = simulate(unzipdir, params, table, 3.0, 1e-3)
    check_exact(f"preventNegativeTension, slack and re-tension, damping {damping}", result, defaults, params, table)
    t, eps, T = result["time"], result["summary_Strain"], result["T"]
    slack = eps < 0
    assert slack.sum() > 500, "the web must go slack (negative strain) for a while"
    # While the strain falls (before the re-tensioning step at 1.5 s) a slack
    # web carries no tension at all. (After it, with damping, the rising
    # strain adds d_r*deps/dt > 0, so T may be > 0 while eps is still < 0;
    # the exact comparison above covers those points.)
    falling = slack & (t <= 1.5)
    assert falling.sum() > 500
    assert np.all(T[falling] == 0.0), "a slack web carries no tension"
    assert np.all(T >= 0.0)
    assert T[-1] > 1000, "the web re-tensions when the strain returns above zero"


def test_negative_tension_without_the_clamp(unzipdir, defaults):
    """The same slack phase without preventNegativeTension: T < 0 (so the clamp test can fail)."""
    table = step_table(1.0, BASE, [(0.2, {"web_b.v": 4.99})])
    result = simulate(unzipdir, {}, table, 1.0, 1e-3)
    check_exact("compression without preventNegativeTension", result, defaults, {}, table)
    assert result["T"][-1] < -500


# --------------------------------------------------------------------------
# (e) sensor units

LBF = mpf("4.4482216152605")
KGF = mpf("9.80665")
FT = mpf("0.3048")
INCH = mpf("0.0254")
WIDTH = 1.3


def hand_computed():
    """v and T of the steady span (v_b = 5 m/s, eps = 1e-3, wp2.width = 1.3 m)."""
    with mpmath.workdps(40):
        vb = mpf(5)
        T = mpf(1.43e10) * mpf(WIDTH) * mpf(59e-6) * mpf(1e-3)  # N
        v = {1: vb, 2: vb * 60, 3: vb * 1000, 4: vb / FT, 5: vb * 60 / FT, 6: vb / INCH}
        F = {1: T, 2: T / 1000, 3: T / LBF, 4: T / KGF, 5: T / mpf(WIDTH), 6: T / LBF * INCH / mpf(WIDTH)}
        return v, F


@pytest.mark.parametrize("unit", [1, 2, 3, 4, 5, 6])
def test_sensor_units(unzipdir, unit):
    v_exact, F_exact = hand_computed()
    params = {"wp2.width": WIDTH, "toUnitV": unit, "toUnitF": unit}
    result = simulate(unzipdir, params, None, 0.01, 0.01, outputs=["v", "T", "summary_Tension"])
    for row in result:
        # a unit factor written to 16 digits and one product: a few ulps
        assert abs(mpf(float(row["v"])) - v_exact[unit]) <= 1e-15 * abs(v_exact[unit]), (unit, row["v"], v_exact[unit])
        assert abs(mpf(float(row["T"])) - F_exact[unit]) <= 1e-14 * abs(F_exact[unit]), (unit, row["T"], F_exact[unit])
        assert abs(mpf(float(row["summary_Tension"])) - F_exact[1]) <= 1e-14 * F_exact[1]


def test_sensor_off_gives_zero_while_summary_stays(unzipdir):
    params = {"wp2.width": WIDTH, "useSensor": False, "toUnitV": 3, "toUnitF": 6}
    result = simulate(unzipdir, params, None, 0.1, 0.01, outputs=["v", "T", "summary_Tension", "web_b.F"])
    assert np.all(result["v"] == 0.0)
    assert np.all(result["T"] == 0.0)
    _, F = hand_computed()
    assert np.allclose(result["summary_Tension"], float(F[1]), rtol=1e-14, atol=0)
    assert np.allclose(result["web_b.F"], float(F[1]), rtol=1e-14, atol=0)


# --------------------------------------------------------------------------
# (f) FMU state through FMPy's FMU2Slave API


class Log:
    """A logger for FMPy's callback (messages arrive formatted by FMPy's proxy)."""

    def __init__(self):
        self.messages = []

    def __call__(self, component, instance, status, category, message):
        self.messages.append((status, category.decode(), message.decode()))

    def text(self):
        return "\n".join(m for _, _, m in self.messages)


def _slave(unzipdir, md, log):
    return instantiate_fmu(unzipdir, md, "CoSimulation", logger=log)


def _run(fmu, vr, t, n, h=1e-3):
    """n steps from t with an input schedule; every output after each step."""
    out_vrs = [vr[n_] for n_ in ("T", "summary_Strain", "unstretchedLength", "web_b.F", "v")]
    rows = []
    for i in range(n):
        if i == n // 3:
            fmu.setReal([vr["web_b.v"]], [5.01])
        if i == 2 * n // 3:
            fmu.setReal([vr["web_a.eps"], vr["web_a.v"]], [2e-3, 4.995])
        fmu.doStep(t + i * h, h)
        rows.append(tuple(fmu.getReal(out_vrs)))
    return rows, fmu.getRealStatus(fmi2LastSuccessfulTime)


def test_fmu_state_save_restore_serialize_deserialize(unzipdir, model_description):
    md = model_description
    vr = {v.name: v.valueReference for v in md.modelVariables}
    log_a, log_b = Log(), Log()
    a = _slave(unzipdir, md, log_a)
    b = _slave(unzipdir, md, log_b)
    try:
        a.setupExperiment(startTime=0.0)
        a.setBoolean([vr["includeDamping"]], [True])
        a.enterInitializationMode()
        a.exitInitializationMode()
        a.setReal([vr["web_b.v"]], [5.005])
        warmup, t = _run(a, vr, 0.0, 50)
        assert t == pytest.approx(0.05)

        state = a.getFMUstate()
        at_save = a.getReal([vr["T"], vr["summary_Strain"]])
        first, t1 = _run(a, vr, t, 90)
        assert first[-1] != first[0], "the continuation must change the outputs"

        # restore: the same outputs at once, and the same continuation, bit for bit
        a.setFMUstate(state)
        assert a.getRealStatus(fmi2LastSuccessfulTime) == t
        assert a.getReal([vr["T"], vr["summary_Strain"]]) == at_save
        second, t2 = _run(a, vr, t, 90)
        assert second == first and t2 == t1

        # serialize, deserialize into a fresh instance, continue there
        data = a.serializeFMUstate(state)
        assert isinstance(data, bytes) and len(data) > 32
        state_b = b.deSerializeFMUstate(data)
        assert b.serializeFMUstate(state_b) == data, "serialization must round-trip"
        b.setFMUstate(state_b)
        assert b.getRealStatus(fmi2LastSuccessfulTime) == t
        third, t3 = _run(b, vr, t, 90)
        assert third == first and t3 == t1

        # a state from another instance and a freed state are refused
        with pytest.raises(FMICallException) as e:
            b.setFMUstate(state)
        assert e.value.status == fmi2Error
        a.freeFMUstate(state)
        with pytest.raises(FMICallException):
            a.setFMUstate(state)  # FMPy's freeFMUstate set the handle to NULL

        # corrupted, truncated and foreign bytes are refused with a reason
        corrupted = bytearray(data)
        corrupted[len(data) // 2] ^= 0x01
        for bad, why in [
            (bytes(corrupted), r"checksum|corrupt"),
            (data[:-1], r"truncated|short|bytes"),
            (b"X" + data[1:], r"magic|not an FMU state"),
            (b"", r"short|empty|bytes"),
        ]:
            n_before = len(log_b.messages)
            with pytest.raises(FMICallException) as e:
                b.deSerializeFMUstate(bad)
            assert e.value.status == fmi2Error
            new = "\n".join(m for _, _, m in log_b.messages[n_before:])
            assert re.search(why, new), f"no reason logged for bad state bytes: {new!r}"
        b.freeFMUstate(state_b)
    finally:
        a.freeInstance()
        b.freeInstance()


# --------------------------------------------------------------------------
# (g) parameter checks with a message naming the variable, value and range

BAD = [
    ({"L": -1.0}, "L", "-1", [r"\[0\.000001, 100000\]"]),
    ({"wp2.E": 0.0}, "wp2.E", "0", [r"\[1000, 10000000000000\]"]),
    ({"eps_start": -1.0}, "eps_start", "-1", [r"\(-1, 10\]"]),
    ({"eps_start": -1.0, "startAtEquilibrium": False}, "eps_start", "-1", [r"\(-1, 10\]"]),
    ({"toUnitF": 7}, "toUnitF", "7", [r"1\s*\.\.\s*6", r"\[1, 6\]"]),
    ({"toUnitV": 0}, "toUnitV", "0", [r"1\s*\.\.\s*6", r"\[1, 6\]"]),
    ({"web_a.eps": -1.0}, "web_a.eps", "-1", [r"\(-1, 10\]"]),
    ({"wp2.d_r": -1.0}, "wp2.d_r", "-1", [r"\[0, 1000\]"]),
    ({"web_b.v": 2e3}, "web_b.v", "2000", [r"\[-1000, 1000\]"]),
    ({"wp2.thickness": 2.0}, "wp2.thickness", "2", [r"\[0\.000000001, 1\]"]),
]


@pytest.mark.parametrize("start_values, name, value, ranges", BAD, ids=[str(b[0]) for b in BAD])
def test_bad_parameters_are_refused_with_a_message(unzipdir, start_values, name, value, ranges):
    log = Log()
    with pytest.raises(FMICallException) as e:
        simulate_fmu(unzipdir, fmi_type="CoSimulation", start_values=start_values, stop_time=0.01, logger=log)
    assert e.value.status == fmi2Error
    errors = [m for status, cat, m in log.messages if status == fmi2Error]
    assert errors, "the refusal must be logged with status fmi2Error"
    text = "\n".join(errors)
    assert re.search(rf"(?<![\w.]){re.escape(name)} = {re.escape(value)}\b", text), f"name and value missing: {text!r}"
    assert any(re.search(r, text) for r in ranges), f"allowed range missing: {text!r}"


def test_good_parameters_at_the_bounds_are_accepted(unzipdir):
    """The inclusive bound wp2.d_r = 0 and values just inside the strict bounds pass."""
    result = simulate_fmu(unzipdir, fmi_type="CoSimulation", stop_time=0.01,
                          start_values={"wp2.d_r": 0.0, "eps_start": -0.5, "startAtEquilibrium": False, "L": 1e-3})
    assert len(result) > 1


# --------------------------------------------------------------------------
# (h) the defaults


def test_defaults_give_the_steady_tension_over_the_default_experiment(unzipdir, defaults, model_description):
    """startAtEquilibrium with equal speeds: eps_b = eps_a = 1e-3, so
    T = 1.43e10 Pa * 59e-6 m * 1 m * 1e-3 = 843.7 N for the whole run."""
    result = simulate_fmu(unzipdir, fmi_type="CoSimulation", output=REAL_OUTPUTS)
    exp = model_description.defaultExperiment
    assert result["time"][0] == float(exp.startTime)
    assert result["time"][-1] == pytest.approx(float(exp.stopTime), abs=1e-12)
    assert len(result) > 100
    check_exact("defaults, no inputs, DefaultExperiment", result, defaults, {}, None)
    assert np.allclose(result["T"], 843.7, rtol=1e-12, atol=0)
    assert np.allclose(result["summary_Strain"], 1e-3, rtol=1e-12, atol=0)
    assert np.all(result["v"] == 5.0)
