"""Sweeps on Dask: a small grid on a local cluster, the same grid through an
existing scheduler's address, and each row equal to the same point run alone."""

import pytest
from webline.compiler import run_scene
from webline.scene import SceneError, load_scene
from webline.sweep import Table, parse_grid, run_sweep

from .conftest import SCENES

SCENE = SCENES / "lamination.json"
GRID = ["stop_time=0.4 s", "line.rewind.drive.tension=250 N,300 N", "line.to_rewind.L=1 m,2 m"]


def test_parse_grid():
    assert parse_grid(["a.b=1 m,2 m", "c=0.5,3"]) == [("a.b", ["1 m", "2 m"]), ("c", [0.5, 3])]
    with pytest.raises(ValueError):
        parse_grid(["nothing"])


def test_local_cluster_runs_the_grid_and_matches_single_runs(fmus, tmp_path):
    table = run_sweep(SCENE, parse_grid(GRID), workers=2, fmu_dir=fmus)
    assert "local Dask cluster of 2 worker processes" in table.info["cluster"]
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
    assert len(lines) == 5 and lines[0].startswith("stop_time,line.rewind.drive.tension,line.to_rewind.L,")


def test_an_existing_scheduler_by_its_address(fmus):
    from dask.distributed import LocalCluster

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        table = run_sweep(SCENE, parse_grid(["stop_time=0.2 s", "line.to_rewind.L=1 m,2 m"]), scheduler=cluster.scheduler_address, fmu_dir=fmus)
        assert cluster.scheduler_address in table.info["cluster"]
        assert [r["status"] for r in table.rows] == ["ok", "ok"]


def test_a_bad_key_fails_before_any_task(fmus):
    with pytest.raises(SceneError, match="no 'Lx'"):
        run_sweep(SCENE, parse_grid(["line.film.Lx=1 m"]), fmu_dir=fmus)
    assert isinstance(Table(keys=[]).columns(), list)
