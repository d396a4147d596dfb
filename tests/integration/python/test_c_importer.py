"""The FMU's binary driven by a plain C importer (tests/integration/c_importer/importer.c).

The importer is compiled here with gcc -Wall -Werror against FMPy's copy of
the FMI 2.0 headers, dlopen()s binaries/linux64/ConvertingSpan.so from the
FMU and looks every function up with dlsym, typed with the header's
fmi2...TYPE. The GUID and every value reference are read from the model
description here and passed on the command line.
"""

import re
import shutil
import subprocess
from pathlib import Path

import fmpy
import mpmath
import pytest
from mpmath import mpf

from conftest import ABS_STRAIN, compare, exact_solution, step_table, tension, _piece_at, input_pieces

SOURCE = Path(__file__).resolve().parents[1] / "c_importer" / "importer.c"
HEADERS = Path(fmpy.__file__).resolve().parent / "c-code"

# The variables the importer touches (it finds their value references in argv).
NAMES = [
    "L", "wp2.width", "wp2.d_r", "includeDamping", "toUnitV",
    "web_a.v", "web_a.eps", "web_b.v",
    "T", "summary_Strain", "unstretchedLength", "v",
]

# The scene importer.c runs; checked against the param lines it prints.
SCENE = {
    "L": 2.0,
    "wp2.width": 1.3,
    "wp2.d_r": 0.01,
    "includeDamping": True,
    "toUnitV": 2,  # m/min: v = 60 * web_b.v
    "web_a.v": 5.0,
    "web_a.eps": 1e-3,
    "web_b.v": 5.0,
}
H = 1e-3
N_STEPS = 1000
HALFWAY_VB = 5.005  # set before step 500 (t = 0.5)
CONT_VB = 4.999  # set halfway through each 100-step continuation from t = 1.0
N_CONT = 100
FMI2_OK, FMI2_ERROR = 0, 3


@pytest.fixture(scope="module")
def importer(tmp_path_factory):
    gcc = shutil.which("gcc")
    assert gcc, "gcc is needed to build the C importer"
    out = tmp_path_factory.mktemp("c_importer") / "importer"
    build = subprocess.run(
        [gcc, "-Wall", "-Werror", "-O1", "-I", str(HEADERS), str(SOURCE), "-o", str(out), "-ldl"],
        capture_output=True, text=True,
    )
    assert build.returncode == 0, f"importer.c does not compile cleanly:\n{build.stderr}"
    assert build.stderr == "", f"gcc printed diagnostics:\n{build.stderr}"
    return out


@pytest.fixture(scope="module")
def run(importer, unzipdir, model_description):
    md = model_description
    library = Path(unzipdir) / "binaries" / "linux64" / f"{md.coSimulation.modelIdentifier}.so"
    assert library.is_file()
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    args = [str(importer), str(library), md.guid] + [f"{n}={vrs[n]}" for n in NAMES]
    proc = subprocess.run(args, capture_output=True, text=True, timeout=60)
    lines = [line.split(",") for line in proc.stdout.splitlines()]
    return proc, lines


def records(lines, kind):
    return [line[1:] for line in lines if line[0] == kind]


def test_importer_exits_0_and_every_legal_call_returns_fmi2OK(run):
    proc, lines = run
    assert proc.returncode == 0, f"importer exit code {proc.returncode}\n{proc.stdout[-2000:]}\n{proc.stderr[-2000:]}"
    statuses = records(lines, "status")
    assert len(statuses) > 20
    bad = [(label, s) for label, s in statuses if int(s) != FMI2_OK]
    assert not bad, f"calls that must succeed failed: {bad}"
    checks = dict(records(lines, "check"))
    failed = [name for name, ok in checks.items() if ok != "1"]
    assert not failed, f"checks in importer.c failed: {failed}"
    info = dict(records(lines, "info"))
    assert info["version"] == "2.0"
    assert info["platform"] == "default"


def test_illegal_calls_return_fmi2Error_and_are_logged(run):
    proc, lines = run
    illegal = dict(records(lines, "illegal"))
    expected = {
        "doStep before init",
        "exitInitializationMode before enter",
        "getReal before init",
        "setReal output T",
        "doStep in initialization mode",
        "doStep at the wrong time",
        "doStep after terminate",
        "deSerializeFMUstate corrupted",
        "doStep on a model exchange instance",
    }
    assert set(illegal) == expected
    wrong = {k: v for k, v in illegal.items() if int(v) != FMI2_ERROR}
    assert not wrong, f"illegal calls that did not return fmi2Error (3): {wrong}"
    checks = dict(records(lines, "check"))
    for name in ("wrong GUID gives NULL", "model exchange instantiates", "percent GUID gives NULL", "corrupted gives no state"):
        assert checks.get(name) == "1", name
    log = proc.stderr
    # every refusal is explained through the importer's logger, with status fmi2Error
    assert "log,illegal,3,logStatusError,fmi2DoStep: illegal call sequence" in log
    assert "log,illegal,3,logStatusError,fmi2ExitInitializationMode: illegal call sequence" in log
    assert "log,illegal,3,logStatusError,fmi2GetReal: illegal call sequence" in log
    assert re.search(r"log,illegal,3,logStatusError,fmi2SetReal: .*\bT\b.*", log)
    assert "is not the current time" in log
    assert re.search(r"log,copy,3,logStatusError,fmi2DeSerializeFMUstate: .*(checksum|corrupt)", log)
    assert re.search(r"log,illegal,3,logStatusError,fmi2Instantiate: .*GUID", log)


def test_logger_is_variadic_and_percent_signs_survive_vsnprintf(run):
    """The FMU passes its messages as printf formats: a '%' in a quoted GUID
    must arrive as '%' after the importer's vsnprintf (the FMU escapes it)."""
    proc, _ = run
    src = SOURCE.read_text()
    assert re.search(r"static void logger\([^)]*fmi2String message, \.\.\.\)", src)
    assert "vsnprintf(" in src
    assert "{100%-wrong-%s-%d-guid}" in proc.stderr
    # loggingOn = fmi2True for the scene instance: its lifecycle is logged
    assert "log,scene,0,logEvents,instantiated" in proc.stderr


def _params(defaults, lines):
    params = dict(defaults)
    params.update(SCENE)
    printed = {name: value for name, value in records(lines, "param")}
    for name, value in SCENE.items():
        assert float(printed[name]) == float(value), f"importer.c set {name} = {printed[name]}, the test expects {value}"
    assert float(printed["web_b.v@500"]) == HALFWAY_VB
    return params


def _table():
    initial = {n: SCENE[n] for n in ("web_a.v", "web_a.eps", "web_b.v")}
    return step_table(2.0, initial, [(0.5, {"web_b.v": HALFWAY_VB}), (N_STEPS * H + (N_CONT // 2) * H, {"web_b.v": CONT_VB})])


def test_scene_matches_the_exact_solution(run, defaults):
    """1000 steps of 1 ms with damping on and a web_b.v step halfway: T, strain,
    unstretched length and v (in m/min) at every step against the exact solution."""
    _, lines = run
    params = _params(defaults, lines)
    rows = records(lines, "row")
    assert [int(r[0]) for r in rows] == list(range(N_STEPS + 1))
    times = [float(r[1]) for r in rows]
    ref = exact_solution(params, _table(), times)
    EA = params["wp2.E"] * params["wp2.width"] * params["wp2.thickness"]
    scenario = "C importer: damping, web_b.v step, h = 1e-3"
    compare(scenario, "T", [float(r[2]) for r in rows], ref["tension"], ABS_STRAIN * EA, times=times)
    compare(scenario, "summary_Strain", [float(r[3]) for r in rows], ref["strain"], ABS_STRAIN, times=times)
    compare(scenario, "unstretchedLength", [float(r[4]) for r in rows], ref["x"], ABS_STRAIN * params["L"], times=times)
    compare(scenario, "v [m/min]", [float(r[5]) for r in rows], [60 * v for v in ref["v"]], 0.0, times=times)
    # the step is visible: the tension rises after it
    assert float(rows[-1][2]) > float(rows[500][2]) + 100


def test_tension_feeds_through_from_web_b_v_with_damping(run, defaults):
    """Setting web_b.v changes T at once (no step) by E2*A2*d_r*deps/dt."""
    _, lines = run
    params = _params(defaults, lines)
    (k, before, after), = records(lines, "feedthrough")
    k = int(k)
    t = [float(r[1]) for r in records(lines, "row")][k]
    ref = exact_solution(params, _table(), [0.0, t])
    with mpmath.workdps(40):
        pieces = input_pieces(_table(), params)
        new_inputs = _piece_at(pieces, mpf(0.75))
        T_after = tension(params, ref["x"][-1], new_inputs)
    EA = params["wp2.E"] * params["wp2.width"] * params["wp2.thickness"]
    scenario = "C importer: damping, web_b.v step, h = 1e-3"
    compare(scenario, "T before the input change", [float(before)], [ref["tension"][-1]], ABS_STRAIN * EA)
    compare(scenario, "T right after the input change", [float(after)], [T_after], ABS_STRAIN * EA)
    # the jump is the damping term: E2*A2*d_r*dv_b/x, about 27 N here
    assert float(after) - float(before) > 20


def test_state_restore_and_deserialization_continue_identically(run, defaults):
    """importer.c compares the continuations bit for bit (memcmp); here the
    continuation is also checked against the exact solution."""
    _, lines = run
    checks = dict(records(lines, "check"))
    assert checks["restore identical"] == "1"
    assert checks["deserialized identical"] == "1"
    assert checks["freed state is NULL"] == "1"
    params = _params(defaults, lines)
    cont = records(lines, "cont")
    assert len(cont) == N_CONT
    times = [float(r[2]) for r in cont]
    ref = exact_solution(params, _table(), [N_STEPS * H] + times)
    EA = params["wp2.E"] * params["wp2.width"] * params["wp2.thickness"]
    scenario = "C importer: continuation after the FMU state tests"
    compare(scenario, "T", [float(r[3]) for r in cont], ref["tension"][1:], ABS_STRAIN * EA, times=times)
    compare(scenario, "summary_Strain", [float(r[4]) for r in cont], ref["strain"][1:], ABS_STRAIN, times=times)


# --------------------------------------------------------------------------
# The FMI 3.0 FMU through tests/integration/c_importer/importer3.c (FMPy's FMI 3.0 headers)

SOURCE3 = SOURCE.parent / "importer3.c"


@pytest.fixture(scope="module")
def run3(tmp_path_factory):
    from fmpy import extract, read_model_description

    from conftest import ROOT, packaged

    fmu3 = packaged(ROOT / "out" / "fmi3" / "ConvertingSpan.fmu")
    md = read_model_description(str(fmu3))
    out = tmp_path_factory.mktemp("c_importer3") / "importer3"
    build = subprocess.run(["gcc", "-Wall", "-Werror", "-O1", "-I", str(HEADERS), str(SOURCE3), "-o", str(out), "-ldl"],
                           capture_output=True, text=True)
    assert build.returncode == 0 and build.stderr == "", f"importer3.c does not compile cleanly:\n{build.stderr}"
    library = Path(extract(str(fmu3))) / "binaries" / "x86_64-linux" / f"{md.coSimulation.modelIdentifier}.so"
    vrs = {v.name: v.valueReference for v in md.modelVariables}
    proc = subprocess.run([str(out), str(library), md.instantiationToken] + [f"{n}={vrs[n]}" for n in NAMES],
                          capture_output=True, text=True, timeout=60)
    return proc, [line.split(",") for line in proc.stdout.splitlines()]


def test_fmi3_importer_runs_the_same_scene_bit_identically(run, run3):
    proc3, lines3 = run3
    assert proc3.returncode == 0, f"importer3 exit code {proc3.returncode}\n{proc3.stdout[-2000:]}\n{proc3.stderr[-2000:]}"
    bad = [(label, s) for label, s in records(lines3, "status") if int(s) != FMI2_OK]
    assert not bad, f"calls that must succeed failed: {bad}"
    failed = [name for name, ok in records(lines3, "check") if ok != "1"]
    assert not failed, f"checks in importer3.c failed: {failed}"
    assert dict(records(lines3, "info"))["version"] == "3.0"
    # %.17g round-trips a double: equal text is equal bits.
    rows2, rows3 = records(run[1], "row"), records(lines3, "row")
    assert len(rows3) == N_STEPS + 1 and rows3 == rows2


def test_fmi3_importer_bad_calls_return_fmi3Error_with_a_log_line_each(run3):
    proc3, lines3 = run3
    illegal = records(lines3, "illegal")
    assert len(illegal) >= 25
    wrong = {label: s for label, s in illegal if int(s) != FMI2_ERROR}  # fmi3Error is 3 too
    assert not wrong, f"refused calls that did not return fmi3Error: {wrong}"
    errors = [line for line in proc3.stderr.splitlines() if line.startswith("log,3,")]
    # One line per refusal on an instance (NULL and foreign pointers have no logger to reach).
    assert len(errors) >= len(illegal) - 2
    assert "fmi2" not in proc3.stderr
    for needle in ("fmi3SetBoolean: includeDamping = 2 is not a Boolean", "fmi3DoStep: earlyReturn is NULL",
                   "fmi3SetInt32: toUnitV (value reference", "is not the current time", "checksum mismatch"):
        assert needle in proc3.stderr, needle
