"""The packaged Roller FMU through FMPy: validation, exports, the exact
solution of J*dw/dt = R*(F_b - F_a) + tau_m - b*w at every output point,
FMU states, bad values, and a Roller next to a ConvertingSpan in one process.

Tolerance: the FMU takes the closed-form step, so with inputs held between
communication points it agrees with the closed form evaluated here (in
mpmath) to rounding: 1e-12 relative (the state is a compensated sum; the
error observed is about 1e-15).
"""

import shutil
import subprocess
from pathlib import Path

import mpmath
import numpy as np
import pytest
from fmpy import read_model_description
from fmpy.fmi2 import FMU2Slave
from fmpy.validation import validate_fmu

from conftest import simulate_fmu  # the FMI 2.0 FMU, then its FMI 3.0 twin: bit-identical

ROOT = Path(__file__).resolve().parents[3]
ROLLER = ROOT / "out" / "Roller.fmu"
SPAN = ROOT / "out" / "ConvertingSpan.fmu"


@pytest.fixture(scope="module")
def roller_path():
    if not ROLLER.exists():
        subprocess.run(["python3", "fmu/package.py"], cwd=ROOT, check=True)
    assert ROLLER.exists(), "fmu/package.py did not write out/Roller.fmu"
    return ROLLER


@pytest.fixture(scope="module")
def md(roller_path):
    return read_model_description(str(roller_path))


def exact_omega(J, R, b, w0, pieces, t):
    """omega(t) for piecewise-constant inputs [(start, F_up, F_down, tau)], in mpmath."""
    mpmath.mp.dps = 30
    J, R, b = map(mpmath.mpf, (J, R, b))
    w = mpmath.mpf(w0)
    t = mpmath.mpf(t)
    for i, (start, fu, fd, tau) in enumerate(pieces):
        end = mpmath.mpf(pieces[i + 1][0]) if i + 1 < len(pieces) else mpmath.inf
        h = min(end, t) - mpmath.mpf(start)
        if h <= 0:
            break
        a = (R * (mpmath.mpf(fd) - mpmath.mpf(fu)) + mpmath.mpf(tau)) / J
        if b == 0:
            w = w + a * h
        else:
            k = b / J
            w = a / k + (w - a / k) * mpmath.exp(-k * h)
    return w


def test_validates_and_is_the_roller(roller_path, md):
    assert validate_fmu(str(roller_path)) == []
    assert md.coSimulation.modelIdentifier == "Roller"
    assert md.guid != read_model_description(str(SPAN)).guid
    names = [v.name for v in md.modelVariables]
    assert names[:4] == ["J", "R", "b", "v_start"]
    assert [n for n in names if n.startswith("web_")] == ["web_a.F", "web_b.F", "web_a.eps", "web_a.v", "web_b.v", "web_b.eps",
                                                          "web_a.x", "web_a.y", "web_b.x", "web_b.y",
                                                          # the extra inlets and outlets, after the plain roller's variables
                                                          "web_a.m", "web_a2.m", "web_a3.m", "web_a4.m",
                                                          "web_a2.F", "web_a2.eps", "web_a3.F", "web_a3.eps", "web_a4.F", "web_a4.eps",
                                                          "web_b2.F", "web_b3.F", "web_b4.F", "web_a2.v", "web_a3.v", "web_a4.v",
                                                          "web_b2.v", "web_b2.eps", "web_b3.v", "web_b3.eps", "web_b4.v", "web_b4.eps"]
    assert [v.valueReference for v in md.modelVariables if v.name in ("inlets", "outlets")] == [36, 37]
    assert md.modelExchange is not None and md.modelExchange.modelIdentifier == "Roller"
    units = {v.name: v.unit for v in md.modelVariables}
    assert units["J"] == "kg.m2" and units["b"] == "N.m.s" and units["tau_m"] == "N.m" and units["omega"] == "rad/s"


def test_exports_the_44_functions(roller_path, tmp_path):
    import zipfile

    with zipfile.ZipFile(roller_path) as z:
        names = z.namelist()
        assert "binaries/linux64/Roller.so" in names and "documentation/index.html" in names
        so = tmp_path / "Roller.so"
        so.write_bytes(z.read("binaries/linux64/Roller.so"))
        doc = z.read("documentation/index.html").decode()
    assert "<!--" not in doc.split("<body>")[1] or "VARIABLES" not in doc, "documentation placeholders left"
    assert "J*domega/dt = r*(F_b - F_a) + tau - b*omega" in doc
    nm = shutil.which("nm")
    assert nm
    out = subprocess.run([nm, "-D", "--defined-only", str(so)], capture_output=True, text=True, check=True).stdout
    exported = {line.split()[-1] for line in out.splitlines() if line.split()[-1].startswith("fmi2")}
    assert len(exported) == 44, sorted(exported)


@pytest.mark.parametrize("b", [0.0, 0.02])
def test_simulate_fmu_follows_the_exact_solution(roller_path, b):
    J, R, w0 = 0.05, 0.1, 50.0
    pieces = [(0.0, 800.0, 650.0, 3.0), (0.3, 800.0, 900.0, 0.0), (0.7, 100.0, 100.0, -2.0)]
    rows = []
    for i, (t, fu, fd, tau) in enumerate(pieces):
        if i:
            prev = pieces[i - 1]
            rows.append((t, prev[1], prev[2], prev[3]))
        rows.append((t, fu, fd, tau))
    rows.append((1.0, *pieces[-1][1:]))
    table = np.array(rows, dtype=[("time", float), ("web_a.F", float), ("web_b.F", float), ("tau_m", float)])
    res = simulate_fmu(
        str(roller_path),
        stop_time=1.0,
        output_interval=1e-3,
        start_values={"J": J, "R": R, "b": b, "v_start": w0 * R},
        input=table,
        output=["omega", "web_a.v"],
    )
    want = np.array([float(exact_omega(J, R, b, w0, pieces, t)) for t in res["time"]])
    # omega crosses zero here: the error is measured against the largest |omega|.
    worst = np.max(np.abs(res["omega"] - want)) / np.max(np.abs(want))
    assert worst < 1e-12, worst
    assert np.allclose(res["web_a.v"], R * res["omega"], rtol=1e-15, atol=0)


def _callbacks(logged):
    """Callbacks of our own, kept alive by the caller. Not FMPy's defaults: FMPy
    0.3.32 routes them through a process-wide logger proxy that any earlier
    simulate_fmu(..., logger=f) re-points at f, so once f is freed an instance
    with the default callbacks crashes the process when it logs."""
    from fmpy import calloc, free
    from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE, fmi2CallbackFunctions,
                           fmi2CallbackLoggerTYPE)

    callbacks = fmi2CallbackFunctions()
    callbacks.logger = fmi2CallbackLoggerTYPE(lambda env, inst, status, cat, msg: logged.append(msg.decode()))
    callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
    callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
    return callbacks


def _slave(path, name="roller"):
    from fmpy import extract

    md = read_model_description(str(path))
    d = extract(str(path))
    s = FMU2Slave(guid=md.guid, unzipDirectory=d, modelIdentifier=md.coSimulation.modelIdentifier, instanceName=name)
    s.logged = []
    s.instantiate(callbacks=_callbacks(s.logged))
    return s, md


def test_fmu_state_round_trip_continues_bit_identically(roller_path):
    s, md = _slave(roller_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s.setReal([vr["J"], vr["b"]], [0.05, 0.01])
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    s.setReal([vr["web_a.F"], vr["web_b.F"], vr["tau_m"]], [100.0, 120.0, 0.5])
    s.doStep(0.0, 0.1)
    state = s.getFMUstate()
    blob = s.serializeFMUstate(state)
    s.doStep(0.1, 0.2)
    first = s.getReal([vr["omega"]])[0]
    s.setFMUstate(s.deSerializeFMUstate(blob))
    s.doStep(0.1, 0.2)
    assert s.getReal([vr["omega"]])[0] == first  # bit for bit
    s.terminate()
    s.freeInstance()


@pytest.mark.parametrize(
    "name,value,message",
    [("J", 0.0, "J = 0 kg.m2 is outside its allowed range [0.000000000001, 1000000000]"),
     ("R", -0.1, "R = -0.1 m is outside its allowed range [0.000001, 100]"),
     ("b", -1.0, "b = -1 N.m.s is outside its allowed range [0, 1000000000]")],
)
def test_bad_parameters_are_refused_with_the_range(roller_path, name, value, message):
    # Through FMU2Slave with callbacks of our own (see _callbacks).
    from fmpy.fmi1 import FMICallException

    logged = []
    callbacks = _callbacks(logged)
    from fmpy import extract

    md = read_model_description(str(roller_path))
    s = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(roller_path)), modelIdentifier="Roller", instanceName="bad")
    s.instantiate(callbacks=callbacks)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s.setReal([vr[name]], [value])
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.exitInitializationMode()
    assert any(message in m for m in logged), logged
    s.freeInstance()


def test_nan_input_is_refused_and_changes_nothing(roller_path):
    from fmpy.fmi1 import FMICallException

    s, md = _slave(roller_path)
    vr = {v.name: v.valueReference for v in md.modelVariables}
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    with pytest.raises(FMICallException):
        s.setReal([vr["web_a.F"], vr["web_b.F"]], [5.0, float("nan")])
    s.reset()
    s.setupExperiment(startTime=0.0)
    s.enterInitializationMode()
    s.exitInitializationMode()
    assert s.getReal([vr["web_a.F"]]) == [0.0]
    # canInterpolateInputs is false: input derivatives are refused.
    assert md.coSimulation.canInterpolateInputs in (False, None)
    with pytest.raises(FMICallException):
        s.setRealInputDerivatives([vr["tau_m"]], [1], [1.0])
    s.freeInstance()


def test_roller_and_span_in_one_process(roller_path):
    """Both FMUs loaded side by side (same crate, same FMI layer): each accepts
    only its own GUID, and each runs."""
    from fmpy import extract

    r, _ = _slave(roller_path, "r")
    span_md = read_model_description(str(SPAN))
    d = extract(str(roller_path))
    wrong = FMU2Slave(guid=span_md.guid, unzipDirectory=d, modelIdentifier="Roller", instanceName="wrong")
    logged = []
    with pytest.raises(Exception):
        wrong.instantiate(callbacks=_callbacks(logged))
    assert any("does not match" in m for m in logged), logged
    res = simulate_fmu(str(SPAN), stop_time=0.01, output_interval=1e-3, output=["T"])
    assert np.isfinite(res["T"]).all()
    r.setupExperiment(startTime=0.0)
    r.enterInitializationMode()
    r.exitInitializationMode()
    r.doStep(0.0, 0.01)
    r.freeInstance()
