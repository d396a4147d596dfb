"""The native loop (`--engine line`: a point's steps in one call into the Line library) against FMPy's
(`--engine fmpy-line`): the same communication points as FMPy's loop takes, and the same rows and
series, bit for bit, on three shipped scenes, with every option a study gives the Line FMU (its
tolerance, another step, a stop time between two steps), for a point that fails too, and through a
whole study on Dask."""

from math import isclose
from types import SimpleNamespace

import numpy as np
import pyarrow.parquet as pq
import pytest
from fmpy.simulation import simulateCS
from webline import native
from webline.linestudy import LineFmus, Planner, run_point
from webline.sampling import design, parse_grid, parse_sample
from webline.sweep import run_sweep

from .conftest import SCENES


class _Steps:
    """An FMU to FMPy's loop that only notes each fmi2DoStep's arguments."""

    def __init__(self):
        self.steps = []

    def setupExperiment(self, **_):
        pass

    enterInitializationMode = exitInitializationMode = terminate = setupExperiment

    def getReal(self, vr):
        return []

    def doStep(self, currentCommunicationPoint, communicationStepSize):
        self.steps.append((currentCommunicationPoint, communicationStepSize))


@pytest.mark.parametrize("start, stop, interval", [
    (0.0, 2.5, 5e-4), (0.0, 0.3, 0.1), (0.0, 1.0, 0.3), (0.0, 1.0, 0.3333333333), (0.1, 0.7, 0.1),
    (0.0, 0.40025, 5e-4), (0.0, 1.0, 1.0), (0.0, 0.0, 1e-3), (0.0, 1e-3 * (1 + 5e-10), 1e-3),
])
@pytest.mark.parametrize("variable", [True, False])
def test_the_communication_points_are_fmpys(start, stop, interval, variable):
    """FMPy 0.3.32's own loop (simulateCS) run on an FMU that notes its steps: every point and step
    size bit for bit, where the stop time falls between two points, within 1e-9 of one, or at the start."""
    description = SimpleNamespace(fmiVersion="2.0", modelVariables=[], unitDefinitions=[],
                                  coSimulation=SimpleNamespace(canHandleVariableCommunicationStepSize=variable))
    fmu = _Steps()
    simulateCS(description, fmu, start, stop, None, {}, False, None, [], interval, None, None, False, False, False,
               True, True, True, True)
    times = native.communication_points(start, stop, interval, variable)
    assert times[0] == start and len(times) == len(fmu.steps) + 1
    assert [(t, h) for t, h in fmu.steps] == [(times[k], times[k + 1] - times[k]) for k in range(len(fmu.steps))]
    assert not fmu.steps or isclose(times[-1], stop) or times[-1] < stop  # the grid never runs past the stop time


def _outcomes(fmu_dir, scene, points, step=None):
    """Each point's outcome through both loops on one instance, alternating (the instance is reset per point)."""
    planner = Planner(SCENES / scene, fmu_dir, step, series=True)
    fmus = LineFmus()
    try:
        both = []
        for point in points:
            s, task = planner.plan(point)
            assert s.fmu is not None, s.error
            pair = []
            for loop in (False, True):
                task.native = loop
                pair.append(run_point(s.fmu, task, fmus))
            both.append(pair)
        return both
    finally:
        fmus.close()


def _same(fmpy, ours):
    assert fmpy.row == ours.row  # the row of the table: floats compared exactly, and the status
    assert (fmpy.time is None) == (ours.time is None)
    if fmpy.time is not None:
        assert fmpy.time.tobytes() == ours.time.tobytes() and fmpy.data.tobytes() == ours.data.tobytes()


SPLICE = [parse_sample(s) for s in ["line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)", "line.first.L=normal(1.5 m, 0.05 m)"]]


@pytest.mark.parametrize("scene, points, step", [
    # events (the splice), equilibrium start, two parameters per point; the tolerance; a stop time between two steps
    ("splice.json", design(parse_grid(["tolerance=1e-9,1e-7"]), SPLICE, 2, 7).points + [{"stop_time": "1.60025 s"}], None),
    # a laminate (its layers' outputs), a profile's table per structure, another step than the scene's
    ("lamination.json", design(parse_grid(["line.rewind.drive.tension=250 N,300 N", "line.to_rewind.L=1 m,2 m"])).points, 2e-3),
    # a dancer started from its given values (a difference Jacobian)
    ("dancer.json", design(parse_grid(["line.dancer.mass=4 kg,6 kg"])).points, None),
])
def test_rows_and_series_are_fmpys_bit_for_bit(fmus, scene, points, step):
    for fmpy, ours in _outcomes(fmus, scene, [dict(p) for p in points], step):
        assert ours.row["status"] == "ok", ours.row["status"]
        _same(fmpy, ours)


def test_a_failing_point_fails_alike(fmus):
    """A step the FMU refuses: the same failed row, the FMU's message and FMPy's words alike."""
    ((fmpy, ours),) = _outcomes(fmus, "splice.json", [{"tolerance": 1e-30}])
    assert ours.row["status"].startswith("failed"), ours.row
    _same(fmpy, ours)


def test_a_study_through_either_loop_is_the_same(fmus, tmp_path):
    """`webline sweep --engine line` and `--engine fmpy-line`: the same table file byte for byte, and the
    same series bit for bit (the Parquet file's metadata names the engine and the time points took)."""
    points = design(parse_grid(["line.first.L=1.4 m,1.6 m"]), SPLICE[:1], 2, 3)
    files = {}
    for engine in ("line", "fmpy-line"):
        table = run_sweep(SCENES / "splice.json", points, engine=engine, workers=1, fmu_dir=fmus,
                          series=tmp_path / f"{engine}.parquet")
        assert [r["status"] for r in table.rows] == ["ok"] * 4
        table.write(tmp_path / f"{engine}.csv")
        files[engine] = (tmp_path / f"{engine}.csv").read_bytes()
    assert files["line"] == files["fmpy-line"]
    series = [pq.read_table(tmp_path / f"{engine}.parquet").replace_schema_metadata(None) for engine in files]
    assert series[0].equals(series[1])
    assert pq.read_table(tmp_path / "line.parquet").num_rows == 4 * 5001


def test_a_library_without_the_entry_says_so():
    with pytest.raises(native.NativeError, match="--engine fmpy-line"):
        native.entry(SimpleNamespace(dll=SimpleNamespace()))
