"""The span FMU in other importers than FMPy: rust-fmi's `fmi-sim` (crates.io,
installed by tests/tools.sh) and DNV's libcosim (PyPI `libcosimpy`).

Each importer runs the same step scene as FMPy: the three inputs step at
communication points and are held in between. Every importer sets each new
value at the same communication point as FMPy (fmi-sim applies the left limit
at a repeated time, so its table puts each step half a step earlier), and the
tension, strain and speed must agree with FMPy's at every point.

Tolerance: 1e-14 relative. Why: the importers load the same binary and call
the same exact step with the same held inputs; only the step size differs by
rounding. FMPy passes (n+1)*h - n*h, which is h to within a few ulps of t,
while fmi-sim and libcosim pass h (to an ulp); exp(-v*dt/L) then differs by
~1e-16 per step, and the tension magnifies a state error by 1/strain (1e3),
so a few 1e-15 are expected (seen: under 3e-15).
"""

import csv
import shutil
import subprocess

import numpy as np
import pytest
from fmpy import simulate_fmu

from conftest import INPUTS, step_table

H = 1e-3
STOP = 1.0
START = {"web_a.v": 5.0, "web_a.eps": 1e-3, "web_b.v": 5.0}
# (time, {input: new value}): a draw, a stronger arriving strain, a slower a.
STEPS = [(0.2, {"web_b.v": 5.005}), (0.6, {"web_a.eps": 2e-3}), (0.8, {"web_a.v": 4.99})]
COMPARED = ["T", "summary_Tension", "summary_Strain", "web_b.eps", "v"]
REL = 1e-14

AGREEMENT = {}  # importer -> the largest relative difference from FMPy


@pytest.fixture(scope="module")
def fmpy_result(fmu_path):
    """FMPy's outputs at t = H, 2H, ..., STOP (one row per communication point after the start)."""
    # The frame inputs are fed by no importer: they keep their start values.
    return simulate_fmu(str(fmu_path), stop_time=STOP, output_interval=H, input=step_table(STOP, START, STEPS),
                        output=COMPARED)


def held_inputs(t):
    """The inputs every importer holds over [t, t + H)."""
    current = dict(START)
    for when, change in STEPS:
        if t >= when - H / 2:
            current.update(change)
    return current


def assert_agrees(importer, times, got, reference):
    """got, reference: {name: array} at the same times; records the worst relative difference."""
    worst = 0.0
    for name in COMPARED:
        g, r = np.asarray(got[name], float), np.asarray(reference[name], float)
        assert len(g) == len(r), f"{importer}: {len(g)} points of {name}, FMPy has {len(r)}"
        rel = np.abs(g - r) / np.maximum(np.abs(r), np.finfo(float).tiny)
        i = int(np.argmax(rel))
        worst = max(worst, float(rel[i]))
        assert rel[i] <= REL, f"{importer}: {name} at t = {times[i]!r} is {g[i]!r}, FMPy {r[i]!r} (rel. diff. {rel[i]:.2e} > {REL:g})"
    AGREEMENT[importer] = worst


def test_fmi_sim_gives_fmpys_tension(fmu_path, fmpy_result, tmp_path):
    fmi_sim = shutil.which("fmi-sim")
    assert fmi_sim, "fmi-sim is not on PATH: tests/run.sh installs it (tests/tools.sh)"
    # A step half a step before each communication point, so that fmi-sim (which
    # applies the value before an event) sets it at the point, as FMPy does.
    inputs = tmp_path / "in.csv"
    with open(inputs, "w", newline="") as f:
        w = csv.writer(f, quoting=csv.QUOTE_NONE)
        f.write(",".join(f'"{n}"' for n in ("time", *INPUTS)) + "\n")
        rows = [(0.0, START)]
        for when, _ in STEPS:
            rows += [(when - H / 2, held_inputs(when - H)), (when - H / 2, held_inputs(when))]
        rows.append((STOP, held_inputs(STOP)))
        for t, values in rows:
            w.writerow([repr(float(t))] + [repr(float(values[n])) for n in INPUTS])
    out = tmp_path / "out.csv"
    run = subprocess.run(
        [fmi_sim, "--model", str(fmu_path), "-i", str(inputs), "-o", str(out),
         "co-simulation", "--output-interval", repr(H), "-s", "0", "-f", repr(STOP)],
        capture_output=True, text=True, timeout=120,
    )
    assert run.returncode == 0, f"fmi-sim failed:\n{run.stdout}\n{run.stderr}"
    with open(out) as f:
        rows = list(csv.DictReader(f))
    got = {name: [float(r[name]) for r in rows] for name in ["time", *COMPARED]}
    # fmi-sim records the start point too; FMPy's rows are the same points.
    np.testing.assert_allclose(got["time"], fmpy_result["time"], rtol=0, atol=1e-12)
    assert_agrees("fmi-sim", got["time"], got, fmpy_result)


def test_fmi_sim_cannot_read_our_fmi3_description_and_says_why(fmu_path):
    """The README's importers paragraph says fmi-sim 0.7.0 reads FMI 2.0 only: it
    refuses FMI 3.0's `unit` on a Float64 (legal in FMI 3.0). If a new fmi-sim
    reads it, this fails, and the paragraph must change."""
    fmi_sim = shutil.which("fmi-sim")
    assert fmi_sim, "fmi-sim is not on PATH: tests/run.sh installs it (tests/tools.sh)"
    fmu3 = fmu_path.parent / "fmi3" / fmu_path.name
    run = subprocess.run([fmi_sim, "--model", str(fmu3), "co-simulation"], capture_output=True, text=True, timeout=120)
    assert run.returncode != 0 and 'unknown field "unit" in element "FmiFloat64"' in run.stderr, run.stderr[-2000:]


def test_libcosim_gives_fmpys_tension(fmu_path, fmpy_result):
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimManipulator import CosimManipulator
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_step_size(step_size=int(round(H * 1e9)))  # nanoseconds
    span = execution.add_local_slave(CosimLocalSlave(fmu_path=str(fmu_path), instance_name="span"))
    override = CosimManipulator.create_override()
    execution.add_manipulator(override)
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    vr = {v.name.decode(): v.reference for v in execution.slave_variables(span)}
    # libcosim ignores Enumeration variables (toUnitV, toUnitF, solver): they keep their defaults.
    assert not {"toUnitV", "toUnitF", "solver"} & set(vr)
    rows = []
    steps = int(round(STOP / H))
    for k in range(steps):
        values = held_inputs(k * H)
        # The override is applied at the start of the next step, i.e. at t = k*H.
        assert override.slave_real_values(span, [vr[n] for n in INPUTS], [values[n] for n in INPUTS])
        assert execution.step()
        rows.append(observer.last_real_values(span, [vr[n] for n in COMPARED]))
    got = {name: np.array(rows)[:, j] for j, name in enumerate(COMPARED)}
    reference = {name: fmpy_result[name][1:] for name in COMPARED}
    assert_agrees("libcosim", fmpy_result["time"][1:], got, reference)


def test_the_scene_moves_the_tension(fmpy_result):
    """The comparison means something: each step changes the tension."""
    T = fmpy_result["T"]
    assert T[-1] != pytest.approx(T[0], rel=1e-3)
    for when, _ in STEPS:
        k = int(round(when / H))
        assert T[k + 5] != pytest.approx(T[k], rel=1e-6), f"the step at {when} s does not move T"


def teardown_module():
    """Printed with pytest -s (docs/importers.md)."""
    for importer, worst in AGREEMENT.items():
        print(f"\n{importer}: largest relative difference from FMPy {worst:.2e}")


def test_the_roller_loads_in_both(fmus, tmp_path):
    """Acceptance of the Roller's model description; with no torque and equal (zero) tensions omega holds exactly."""
    roller = fmus / "Roller.fmu"
    out = tmp_path / "roller.csv"
    run = subprocess.run([shutil.which("fmi-sim") or "fmi-sim", "--model", str(roller), "-o", str(out),
                          "co-simulation", "--output-interval", "0.01", "-f", "0.1"],
                         capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, f"fmi-sim refused Roller.fmu:\n{run.stderr}"
    with open(out) as f:
        assert [float(r["omega"]) for r in csv.DictReader(f)] == [100.0] * 11

    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave

    execution = CosimExecution.from_step_size(step_size=10_000_000)
    index = execution.add_local_slave(CosimLocalSlave(fmu_path=str(roller), instance_name="roller"))
    observer = CosimObserver.create_last_value()
    execution.add_observer(observer)
    omega = {v.name.decode(): v.reference for v in execution.slave_variables(index)}["omega"]
    assert execution.step(10)
    assert observer.last_real_values(index, [omega]) == [100.0]
