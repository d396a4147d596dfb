"""Studies on Dask: designs (grids, Latin hypercube samples), the Line FMU engine against
`webline run --engine fmpy-line` point by point, one instance reset between points against a fresh
one, failed points as rows, the series file, the plots, the parts and the reference engines. A
scheduler and workers as separate processes, the same table on one worker and on two, and a lost
worker: test_cluster.py."""

import time

import numpy as np
import pytest
from webline import linefmu
from webline.cli import main
from webline.compiler import run_scene
from webline.linestudy import LineFmus, Planner, run_point
from webline.sampling import DesignError, design, parse_grid, parse_sample
from webline.scene import SceneError, load_scene
from webline.sweep import Table, run_sweep

from .conftest import SCENES

SCENE = SCENES / "lamination.json"
GRID = ["stop_time=0.4 s", "line.rewind.drive.tension=250 N,300 N", "line.to_rewind.L=1 m,2 m"]
SPLICE = SCENES / "splice.json"
SAMPLES = ["line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)", "line.first.L=normal(1.5 m, 0.05 m)"]


@pytest.fixture(scope="module")
def client():
    """One local cluster of two worker processes for the tests of this file (each start costs seconds)."""
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, Client(cluster) as c:
        yield c


def test_parse_grid():
    assert parse_grid(["a.b=1 m,2 m", "c=0.5,3"]) == [("a.b", ["1 m", "2 m"]), ("c", [0.5, 3])]
    with pytest.raises(DesignError):
        parse_grid(["nothing"])


def test_latin_hypercube_is_repeatable_covers_each_range_and_never_repeats():
    samples = [parse_sample(s) for s in SAMPLES]
    a, b = design([], samples, 200, 7), design([], samples, 200, 7)
    assert a.points == b.points and a.values == b.values  # the same seed, the same points, bit for bit
    assert design([], samples, 200, 8).values != a.values
    J = np.array([v["line.idler.J [kg.m2]"] for v in a.values])
    L = np.array([v["line.first.L [m]"] for v in a.values])
    assert len(np.unique(J)) == 200 and len(np.unique(L)) == 200
    # One point in each of the 200 strata of the uniform range (a Latin hypercube's defining property).
    assert sorted(np.floor((J - 0.01) / 0.04 * 200).astype(int)) == list(range(200))
    assert abs(L.mean() - 1.5) < 0.005 and abs(L.std() - 0.05) < 0.005
    # The scene reads back the very number drawn: the SI value written exactly.
    s = load_scene(SPLICE, a.points[3])
    assert s.component("idler").J == a.values[3]["line.idler.J [kg.m2]"]
    assert s.component("first").length == a.values[3]["line.first.L [m]"]
    # Grids cross the samples.
    both = design(parse_grid(["stop_time=2 s,2.5 s"]), samples, 3, 1)
    assert [p["stop_time"] for p in both.points] == ["2 s"] * 3 + ["2.5 s"] * 3
    assert both.keys == ["stop_time", "line.idler.J [kg.m2]", "line.first.L [m]"]


@pytest.mark.parametrize("spec, message", [
    ("line.idler.J=uniform(0.05 kg.m2, 0.01 kg.m2)", "lower bound"),
    ("line.idler.J=normal(1 kg.m2, 0 kg.m2)", "standard deviation"),
    ("line.idler.J=uniform(1 kg.m2, 2 m)", "one kind"),
    ("line.idler.J=lognormal(1, 2)", "unknown distribution"),
    ("line.idler.J=uniform(1 furlong, 2 furlong)", "unknown unit"),
    ("line.idler.J", "expected KEY="),
])
def test_a_bad_sample_says_why(spec, message):
    with pytest.raises(DesignError, match=message):
        parse_sample(spec)


def test_design_needs_points_and_n():
    with pytest.raises(DesignError, match="needs --n"):
        design([], [parse_sample(SAMPLES[0])], None, 1)
    with pytest.raises(DesignError, match="twice"):
        design(parse_grid(["line.idler.J=0.02 kg.m2"]), [parse_sample(SAMPLES[0])], 2, 1)


def relative(a, b):
    return float(np.max(np.abs(a - b)) / np.max(np.abs(b)))


def test_line_fmu_points_match_a_run_of_each_point_alone(fmus):
    """Points that set the FMU's parameters (a span's L, a roller's J, a web's modulus, which also moves
    the spans' start strains through T_start) and a point of another structure (an event's time) give
    the numbers `webline run --engine fmpy-line` gives for the same point: to 1e-12 of each signal's
    largest magnitude (rounding; in practice they are equal)."""
    planner = Planner(SPLICE, fmus, series=True)
    points = [
        {"line.idler.J": "0.04 kg.m2", "line.first.L": "1.4 m"},
        {"line.idler.J": "0.015 kg.m2", "line.first.L": "1.6 m", "webs.PET50.E": "5 GPa"},
        {"line.idler.J": "0.015 kg.m2", "line.first.L": "1.6 m", "events.2.time": "1.2 s"},
    ]
    fmus_here = LineFmus()
    try:
        planned = [planner.plan(p) for p in points]
        assert [s.index for s, _ in planned] == [0, 0, 1]  # one export per structure
        assert set(planned[1][1].parameters) >= {"idler.J", "first.L", "first.wp2.E", "second.wp1.E", "first.eps_start"}
        for (s, task), p in zip(planned, points):
            out = run_point(s.fmu, task, fmus_here)
            assert out.row["status"] == "ok", out.row
            alone = linefmu.run(load_scene(SPLICE, p, fmus), fmus)
            assert np.array_equal(out.time, alone.time)
            for j, c in enumerate(alone.columns):
                assert relative(out.data[:, j], alone.data[:, j]) <= 1e-12, c
            assert abs(out.row["second.T_max [N]"] - alone.column("second.T").max()) <= 1e-12 * alone.column("second.T").max()
    finally:
        fmus_here.close()


def test_a_run_after_reset_equals_a_fresh_instance_bit_for_bit(fmus):
    planner = Planner(SPLICE, fmus, series=True)
    s, first = planner.plan({"line.idler.J": "0.02 kg.m2", "tolerance": 1e-10})
    same, other = planner.plan({"line.idler.J": "0.05 kg.m2", "tolerance": 1e-8})
    # The FMU carries the first point's J; the other point sets its own, and reset must bring 0.02 back.
    assert same is s and first.parameters == {"tolerance": 1e-10} and other.parameters == {"idler.J": 0.05, "tolerance": 1e-8}
    reused, fresh = LineFmus(), LineFmus()
    try:
        run_point(s.fmu, first, reused)
        run_point(s.fmu, other, reused)
        again = run_point(s.fmu, first, reused)  # after two fmi2Reset
        new = run_point(s.fmu, first, fresh)  # a new instance's first run
        assert again.row["status"] == new.row["status"] == "ok"
        assert np.array_equal(again.time, new.time) and np.array_equal(again.data, new.data)
        assert again.row == new.row
        assert not np.array_equal(run_point(s.fmu, other, reused).data, new.data)  # the parameters do reach the FMU
    finally:
        reused.close()
        fresh.close()


def test_a_study_through_the_line_fmu_writes_table_series_and_plots(fmus, client, tmp_path):
    """`webline sweep` as the issue's example, small: the table, the series that pandas and polars
    read (one row per point and time, one column per signal), both plots; a point that fails is a
    row that says why, and the study goes on."""
    import pandas as pd
    import polars as pl

    out, series = tmp_path / "study.csv", tmp_path / "study.parquet"
    args = ["sweep", str(SPLICE), "--grid", "line.second.L=1.6 m,-1 m", "--n", "3", "--seed", "7",
            "--out", str(out), "--series", str(series), "--plot", "second.T_max", "--fmu-dir", str(fmus),
            "--scheduler", client.scheduler.address, "--metric", "peak=max(second.T)", "--metric", "late=mean(idler.v, 2.0)",
            "--metric", "when=argmax(first.T, 1.0, 2.0)"]
    for s in SAMPLES:
        args += ["--sample", s]
    assert main(args) == 1  # some points failed
    assert out.read_text().startswith("point,line.second.L,line.idler.J [kg.m2],line.first.L [m],unwind.v_end [m/s],first.T_min [N]")
    table = pd.read_csv(out)
    status = list(table["status"])
    assert status[:3] == ["ok"] * 3 and all(s.startswith("failed") and "L must be > 0" in s for s in status[3:]), status
    frame = pd.read_parquet(series)
    assert list(frame.columns) == ["point", "time [s]", "first.T [N]", "second.T [N]", "first.eps [1]", "second.eps [1]",
                                   "unwind.v [m/s]", "idler.v [m/s]", "nip.v [m/s]", "unwind.omega [rad/s]"]
    assert sorted(frame["point"].unique()) == [0, 1, 2] and len(frame) == 3 * 5001
    assert pl.read_parquet(series).shape == frame.shape
    # The series is the point's run: its largest tension is the table's.
    assert frame[frame["point"] == 1]["second.T [N]"].max() == table["second.T_max [N]"][1]
    # The metrics of each point, against its series.
    for i in range(3):
        run, row = frame[frame["point"] == i], table.iloc[i]
        t, T = run["time [s]"].to_numpy(), run["second.T [N]"].to_numpy()
        assert row["peak [N]"] == T.max() == row["second.T_max [N]"]
        assert row["second.T_overshoot [N]"] == T.max() - T[-1] and row["second.T_peak_time [s]"] == t[np.argmax(T)]
        assert abs(row["second.T_rms [N]"] - T.std()) <= 1e-9 * T.std()  # two summations of the same squares
        inside = np.abs(T - T[-1]) <= 0.02 * abs(T[-1])
        settled = next(k for k in range(len(T)) if inside[k:].all())
        assert row["second.T_settling [s]"] == t[settled]
        assert row["late [m/s]"] == np.mean(run["idler.v [m/s]"].to_numpy()[t >= 2.0])
        window = run[(run["time [s]"] >= 1.0) & (run["time [s]"] <= 2.0)]
        assert row["when [s]"] == window["time [s]"].iloc[np.argmax(window["first.T [N]"].to_numpy())]
    # The series file says how it was made.
    import json

    import pyarrow.parquet as pq

    meta = json.loads(pq.read_schema(series).metadata[b"webline"])
    assert meta["seed"] == 7 and meta["engine"] == "line" and meta["design"]["points"] == 6 and meta["missing"] == 0
    assert meta["statuses"]["ok"] == 3 and sum(meta["statuses"].values()) == 6 and meta["seconds per point"] > 0
    assert (tmp_path / "study_envelope.png").stat().st_size > 0 and (tmp_path / "study_scatter.png").stat().st_size > 0


def test_the_parts_engine_runs_the_grid_and_matches_single_runs(fmus, client, tmp_path):
    table = run_sweep(SCENE, design(parse_grid(GRID)), engine="parts", client=client, fmu_dir=fmus)
    assert len(table.rows) == 4 and all(r["status"] == "ok" for r in table.rows), table.rows
    points = [(r["line.rewind.drive.tension"], r["line.to_rewind.L"]) for r in table.rows]
    assert points == [("250 N", "1 m"), ("250 N", "2 m"), ("300 N", "1 m"), ("300 N", "2 m")]
    # The grid changes what it should: a lower rewind tension, a lower laminate tension.
    low, high = table.rows[0], table.rows[2]
    assert low["to_rewind.T_end [N]"] < high["to_rewind.T_end [N]"]
    # Each row is the same co-simulation as the point run on its own.
    row = table.rows[1]
    s = load_scene(SCENE, {"stop_time": "0.4 s", "line.rewind.drive.tension": "250 N", "line.to_rewind.L": "2 m"})
    alone = run_scene(s, fmu_dir=fmus)
    assert row["to_rewind.T_max [N]"] == float(alone.column("to_rewind.T").max())
    assert row["film.T_end [N]"] == float(alone.column("film.T")[-1])
    path = tmp_path / "sweep.csv"
    table.write(path)
    lines = path.read_text().splitlines()
    assert len(lines) == 5 and lines[0].startswith("point,stop_time,line.rewind.drive.tension,line.to_rewind.L,")


def test_the_reference_engine_and_the_line_fmu_agree(fmus, client):
    """The same two points by the monolithic reference and through the Line FMU: within the
    reference's own error (Radau at rtol 1e-10; the Line FMU is held to 1e-6 of scale elsewhere)."""
    points = design(parse_grid(["stop_time=0.4 s", "line.to_rewind.L=1 m,2 m"]))
    ref = run_sweep(SCENE, points, engine="reference", client=client, fmu_dir=fmus)
    line = run_sweep(SCENE, points, engine="fmpy-line", client=client, fmu_dir=fmus)
    assert [r["status"] for r in ref.rows + line.rows] == ["ok"] * 4
    for a, b in zip(ref.rows, line.rows):
        assert abs(a["to_rewind.T_max [N]"] - b["to_rewind.T_max [N]"]) <= 1e-6 * b["to_rewind.T_max [N]"]


def test_bad_keys_fail_before_any_task(fmus):
    with pytest.raises(SceneError, match="no 'Lx'"):
        run_sweep(SCENE, design(parse_grid(["line.film.Lx=1 m"])), fmu_dir=fmus)
    with pytest.raises(SceneError, match="goes with --engine line"):
        run_sweep(SCENE, design(parse_grid(["tolerance=1e-8"])), engine="parts", fmu_dir=fmus)
    with pytest.raises(SceneError, match="not a value to sweep"):
        run_sweep(SCENE, design(parse_grid(["record.0=film.eps"])), fmu_dir=fmus)
    with pytest.raises(SceneError, match="a sweep runs"):
        run_sweep(SCENE, design(parse_grid(["line.film.L=1 m"])), engine="libcosim", fmu_dir=fmus)
    assert Table(keys=[]).columns() == ["point", "status"]


def study_args(tmp_path, client, fmus, *extra, out="t.csv"):
    return ["sweep", str(SPLICE), "--step", "1 ms", "--fmu-dir", str(fmus), "--out", str(tmp_path / out),
            "--scheduler", client.scheduler.address, *extra]


@pytest.mark.parametrize("extra, message", [
    (["--sample", "line.first.L=uniform(1 kg, 2 kg)", "--n", "3", "--seed", "1"], "a mass, but the scene's value there ('1.2 m') is a length"),
    (["--grid", "line.first.L=1 m,2 s"], "a time, but the scene's value there ('1.2 m') is a length"),
    (["--grid", "line.first.L=1 m", "--plot", "first.T_maximum"], "--plot 'first.T_maximum': the table has no such output"),
    (["--grid", "line.first.L=1 m", "--max-failed", "-1"], "--max-failed -1"),
])
def test_a_study_refused_before_it_runs_is_one_line_and_exit_2(extra, message, tmp_path, fmus, capsys):
    """No cluster is started (none is given and the refusal comes first): one line, exit 2, no table."""
    started = time.monotonic()
    assert main(["sweep", str(SPLICE), "--fmu-dir", str(fmus), "--out", str(tmp_path / "t.csv"), *extra]) == 2
    err = capsys.readouterr().err
    assert message in err and len(err.strip().splitlines()) == 1, err
    assert time.monotonic() - started < 15 and not (tmp_path / "t.csv").exists()


def test_exit_codes_max_failed_and_the_summary(tmp_path, fmus, client, capsys):
    # Every point ok: 0, and the journal is gone.
    assert main(study_args(tmp_path, client, fmus, "--grid", "line.second.L=1.6 m,1.7 m")) == 0
    assert not (tmp_path / "t.partial").exists()
    # Failed points: 1, their reasons counted; the journal stays for --resume.
    assert main(study_args(tmp_path, client, fmus, "--grid", "line.second.L=1.6 m,-1 m,-2 m,-3 m", out="f.csv")) == 1
    text = capsys.readouterr().out
    assert "4 points: 1 ok (0 with a warning), 3 failed" in text
    assert "  1 x failed: " in text and "(first: point 1)" in text and "f.partial" in text
    # --max-failed 1 stops once two points have failed: not every point is run.
    assert main(study_args(tmp_path, client, fmus, "--grid", "line.second.L=-1 m,-2 m,-3 m,-4 m,-5 m,-6 m", "--max-failed", "1",
                           out="m.csv")) == 1
    text = capsys.readouterr().out
    assert "more than --max-failed 1" in text and "not run" in text


def test_resume_refuses_another_study_naming_what_differs(tmp_path, fmus, client, capsys):
    args = ["--sample", SAMPLES[0], "--grid", "line.second.L=1.6 m,-1 m"]
    assert main(study_args(tmp_path, client, fmus, *args, "--n", "4", "--seed", "3")) == 1  # failed points: the journal stays
    assert "  4 x failed: " in capsys.readouterr().out  # one reason, though each message names its point's values
    for extra, what in [(["--n", "4", "--seed", "4"], "the seed differs (3, now 4)"),
                        (["--n", "4", "--seed", "3", "--engine", "reference"], "the engine differs ('line', now 'reference')"),
                        (["--n", "5", "--seed", "3"], "the design"),
                        (["--n", "4", "--seed", "3", "--series", str(tmp_path / "s.parquet")], "whether series are kept")]:
        assert main(study_args(tmp_path, client, fmus, *args, *extra, "--resume")) == 2
        err = capsys.readouterr().err
        assert what in err and len(err.strip().splitlines()) == 1, err
    # The same study resumed, its seed from the journal: only the failed points run again (and fail again).
    assert main(study_args(tmp_path, client, fmus, *args, "--n", "4", "--resume")) == 1
    assert "resuming: 4 of 8 points kept, 4 to run" in capsys.readouterr().err


def test_a_torn_last_line_of_the_journal_runs_its_point_again(tmp_path):
    from webline.journal import Journal

    study = {"scene": "x", "seed": 1}
    journal, done = Journal.start(tmp_path / "t.csv", study, resume=False)
    journal.add(0, {"a": 0.1 + 0.2, "status": "ok"}, [1.0, 2.0, 0.5])
    journal.close()
    with open(tmp_path / "t.partial" / "rows.jsonl", "a") as f:
        f.write('{"point": 1, "row": {"a": 0.3')  # a kill in the middle of a line
    _, done = Journal.start(tmp_path / "t.csv", study, resume=True)
    assert list(done) == [0] and done[0].row == {"a": 0.1 + 0.2, "status": "ok"}


def test_progress_without_a_terminal_every_tenth_or_every_10_seconds(monkeypatch):
    import io

    from webline import progress

    now = [0.0]
    monkeypatch.setattr(progress.clock, "monotonic", lambda: now[0])
    stream = io.StringIO()
    p = progress.Progress(100, stream=stream, terminal=False)
    p.workers(2)
    for k in range(10):
        now[0] += 0.1
        p.point("ok" if k else "failed: x")
    assert stream.getvalue().count("\n") == 1 and "sweep: 10/100 points, 1 failed" in stream.getvalue()
    now[0] += 9.0
    p.tick()
    assert stream.getvalue().count("\n") == 1  # not yet 10 s since the last line
    now[0] += 1.5
    p.tick()
    assert stream.getvalue().count("\n") == 2
    assert "0.391 ok points/s per worker (2 workers)" in stream.getvalue().splitlines()[-1]
