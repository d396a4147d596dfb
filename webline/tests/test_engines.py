"""The engines of `webline run` by one set of names (webline/src/webline/engines.py): the exact engine
by default, the parts refused above their coupling's stable step and stopped when an oscillation grows,
the same CSV columns from every engine, and one start for all of them.

The laminator with unequal source speeds and the two rewind lines are scenes users wrote (cases/).
"""

import json
import subprocess
import sys

import numpy as np
import pytest

from webline import engines, linefmu
from webline.accuracy import errors
from webline.reference import EquilibriumError, reference
from webline.scene import SceneError, load_scene, parse_scene

from .conftest import ROOT, SCENES
from .test_scenes import BASE

CASES = ROOT / "webline" / "tests" / "cases"
# The Line FMU against the reference: 1e-7 of each signal's scale (the bound; docs/line-fmu.md
# states 1e-6 for any scene, and this one measured 8.6e-9 over its 6 s).
EXACT = 1e-7


def scene_file(tmp_path, name, **changes):
    """A case with top-level values changed (a shorter stop time: the tests stay short)."""
    data = json.loads((CASES / f"{name}.json").read_text())
    data.update(changes)
    path = tmp_path / f"{name}.json"
    path.write_text(json.dumps(data, indent=1))
    return path


def webline(*args):
    return subprocess.run([sys.executable, "-m", "webline", *map(str, args)], capture_output=True, text=True, cwd=ROOT)


def test_run_takes_the_line_fmu_by_default_and_matches_the_reference(fmus, tmp_path):
    """`webline run` with no options: the Line FMU, named in the summary; every signal within EXACT of the
    reference. The parts at the scene's own 1 ms ended this scene at 1,397 N where the truth is 762 N."""
    path = scene_file(tmp_path, "laminator_unequal_sources", stop_time="0.5 s")
    run = webline("run", path, "--out", tmp_path, "--no-plot")
    assert run.returncode == 0, run.stderr
    assert run.stdout.startswith("laminator_unequal_sources: engine line: Line FMU in FMPy"), run.stdout
    from webline.result import Result

    scene = load_scene(path)
    got = Result.read_csv(tmp_path / "laminator_unequal_sources.csv")
    assert got.columns == scene.columns()
    err = errors(got, reference(scene, times=got.time))
    assert max(err.values()) <= EXACT, err


def test_the_parts_refuse_a_step_above_their_coupling_limit(fmus, tmp_path):
    """1 ms is above the Gauss–Seidel/extrapolation limit of this line (0.912 ms, its idler's mode): one
    line names the limit, the part and the step to use, before a step is taken. Below the limit it runs."""
    path = scene_file(tmp_path, "laminator_unequal_sources", stop_time="0.2 s")
    run = webline("run", path, "--engine", "parts", "--step", "1ms", "--out", tmp_path, "--no-plot")
    assert run.returncode == 2 and not (tmp_path / "laminator_unequal_sources.csv").exists()
    assert run.stderr.count("\n") == 1, run.stderr
    for words in ("a step of 1 ms is above", "0.912 ms", "set by roller 'idler'", "use --step 0.2ms", "--force"):
        assert words in run.stderr, run.stderr
    run = webline("run", path, "--engine", "parts", "--step", "0.5ms", "--out", tmp_path, "--no-plot")
    assert run.returncode == 0 and "engine parts: co-simulation (gauss-seidel, extrapolate), step 0.5 ms" in run.stdout, run.stderr


def test_a_forced_run_at_twice_the_limit_is_stopped_by_the_growth_detector(fmus, tmp_path):
    """--force at 2 x 0.912 ms (the map's radius 1.037 per step): the oscillation of the laminate's tension
    grows, and the master stops the run (at 0.22 s) with the span's name (its foil layer's FMU, lam1.Al)
    and a non-zero exit."""
    path = scene_file(tmp_path, "laminator_unequal_sources", stop_time="0.5 s")
    run = webline("run", path, "--engine", "parts", "--step", "1.824ms", "--force", "--out", tmp_path, "--no-plot")
    assert run.returncode == 2, run.stdout
    assert "the tension of span 'lam1.Al' oscillates ever more at t = 0.2" in run.stderr, run.stderr
    assert "unstable at this step" in run.stderr


def test_no_shipped_scene_trips_the_growth_detector_at_its_own_step(fmus):
    """The detector watches every run of the parts; the shipped scenes at their own steps run through it in
    test_line_reference (lamination, emergency_stop, dancer, splice, stiff_line) and test_merge_split
    (laminator, slitter); this is the one left, paper_line."""
    from webline.compiler import run_scene

    run = run_scene(load_scene(SCENES / "paper_line.json"), fmu_dir=fmus)
    assert run.time[-1] == pytest.approx(1.5)


# test_scenes' small line, shorter, recording a quantity of every kind a span, a source, a roller and a sink offer.
SMALL = BASE.replace('"stop_time": "0.2 s"', '"stop_time": "0.05 s"').replace('"time": "0.1 s"', '"time": "0.02 s"').replace(
    '"line": [', '"record": ["a.T", "a.eps", "a.L", "a.F_a", "b.F_b", "in.v", "in.eps", "idler.v", "idler.omega", "idler.tau", '
    '"out.v"],\n  "line": [')


def test_every_engine_names_its_csv_columns_as_the_scene_does(fmus, tmp_path):
    """The same header from the Line FMU, the reference, the parts, libcosim and FMPy (on the exported
    SSP), and the SSP archive run as parts: before, SSP runs said `a.summary_Tension` and `idler.web_a.v`."""
    from webline.compiler import compile_scene
    from webline.ssp import write_ssp

    scene = parse_scene(SMALL, "small.json", fmu_dir=fmus)
    want = ["a.T [N]", "a.eps [1]", "a.L [m]", "a.F_a [N]", "b.F_b [N]", "in.v [m/s]", "in.eps [1]", "idler.v [m/s]",
            "idler.omega [rad/s]", "idler.tau [N.m]", "out.v [m/s]"]
    assert scene.columns() == want
    for engine in ("line", "reference", "parts", "libcosim", "fmpy"):
        result = engines.run_scene(scene, engine, fmus)
        assert result.columns == want, engine
        assert result.info["engine"] == engine
        result.write_csv(tmp_path / f"{engine}.csv")
        assert (tmp_path / f"{engine}.csv").read_text().splitlines()[0] == "time [s]," + ",".join(want)
    archive = write_ssp(compile_scene(scene, fmus), tmp_path / "small.ssp")
    assert engines.run_archive(archive).columns == want
    # An archive runs as parts, checked as a scene is (at its start: an archive has no profiles to read speeds from).
    from webline.stability import UnstableStep

    with pytest.raises(UnstableStep, match="small: a step of 25 ms is above the largest stable step"):
        engines.run_archive(archive, step=0.025)
    # The old name of the Line FMU's engine still works.
    assert engines.engine_name("fmpy-line") == "line"


def test_a_spring_loaded_dancer_starts_in_its_steady_state_in_every_engine(fmus):
    """The rewind line's spring-loaded dancer: webline's steady-state solve converged and then rejected its
    answer, and every span started at 0 N where the Line FMU started at 410 N. Now the reference, the parts
    and the Line FMU start alike, at the steady state: the entry span at T = 400 N + b*omega/R (the unwind
    roll's bearing), the carriage where its spring takes what the spans leave of the load, and stay there."""
    scene = load_scene(CASES / "rewind_spring_dancer.json", fmu_dir=fmus)
    scene.stop_time = 0.02  # before the pull roll ramps (1 s): the line stays flat
    scene.record = [(c.name, "T") for c in scene.spans] + [("dancer", "y"), ("unwind", "v")]
    # 0.5 ms: the parts' coupling is stable up to 0.84 ms on this line (its dancer), and refuses its own 1 ms.
    runs = {e: engines.run_scene(scene, e, fmus, step=5e-4) for e in ("line", "reference", "parts")}
    ref = runs["reference"]
    first = ref.data[0]
    v = ref.column("unwind.v")[0]
    assert ref.column("entry.T")[0] == pytest.approx(400.0 + 0.4 * (v / 0.45) / 0.45, rel=1e-9)
    assert ref.column("entry.T")[0] == pytest.approx(409.87, abs=0.01)
    y, pull = ref.column("dancer.y")[0], ref.column("leg_in.T")[0] + ref.column("leg_out.T")[0]
    assert 4000.0 * (y - 0.6) == pytest.approx(800.0 - pull, rel=1e-9)  # the spring takes the rest of the load
    assert y - 0.6 == pytest.approx(8.7e-3, abs=1e-4)
    for engine, run in runs.items():
        # Alike at the start and at rest through the run: to 1e-9 of each value (the solve's checked bound).
        assert np.allclose(run.data, first, rtol=1e-9, atol=0.0), (engine, run.data[0] - first, run.data[-1] - first)


def test_a_springless_dancer_between_tension_drives_is_refused_by_name(fmus, tmp_path):
    """The same line without the spring has no steady state (the drives set 765 N of pull, the load is 800 N):
    the reference put the carriage 7.2e12 m away and ran on. Every engine, and the exporter, refuse it by name
    with the force left over and the way out; with `"start": "given"` it runs."""
    scene = load_scene(CASES / "rewind_springless_dancer.json", fmu_dir=fmus)
    for run in [lambda e=e: engines.run_scene(scene, e, fmus) for e in ("line", "reference", "parts")] + [
            lambda: linefmu.export(scene, tmp_path / "refused.fmu", fmus)]:
        with pytest.raises(EquilibriumError) as e:
            run()
        msg = str(e.value)
        assert msg.startswith(f"{CASES / 'rewind_springless_dancer.json'}:78:3: dancer 'dancer' has no spring"), msg
        for words in ("load (800 N)", "34.8 N are left over", "no steady state", '"stiffness"', '"start": "given"'):
            assert words in msg, msg
    assert not (tmp_path / "refused.fmu").exists()
    given = load_scene(scene_file(tmp_path, "rewind_springless_dancer", start="given", stop_time="0.01 s"), fmu_dir=fmus)
    assert engines.run_scene(given, "reference").column("dancer.y")[0] == 0.6
