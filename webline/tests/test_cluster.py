"""A real cluster: `dask scheduler` and two `dask worker` processes (the distributed package's own
commands, run by the venv's Python, over TCP on localhost). A study through it gives the very table
a local cluster of one worker gives; then one worker is killed once the first 5 results of a second
study have arrived, and every point still arrives (Dask runs the lost tasks again on the other)."""

import json
import subprocess
import sys
import time

import pytest
from dask.distributed import Client
from webline.sampling import design, parse_sample
from webline.sweep import run_sweep

from .conftest import SCENES

SPLICE = SCENES / "splice.json"
SAMPLES = ["line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)", "line.first.L=normal(1.5 m, 0.05 m)"]
STEP = 1e-3  # the splice at 1 ms: each point a few hundredths of a second, so the study takes seconds
POINTS = 30  # enough that most are still to come when the worker dies
WAIT = 60.0  # seconds the processes may take to start on a busy machine


def dask(*args, log):
    return subprocess.Popen([sys.executable, "-m", "dask", *args], stdout=log, stderr=subprocess.STDOUT)


@pytest.fixture
def cluster(tmp_path):
    """(scheduler address, the two worker processes); every process stopped at the end."""
    file = tmp_path / "scheduler.json"
    processes = []
    with open(tmp_path / "dask.log", "w") as log:
        try:
            processes.append(dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                  "--scheduler-file", str(file), log=log))
            deadline = time.monotonic() + WAIT
            while not (file.exists() and file.read_text().strip()):
                assert time.monotonic() < deadline, f"no scheduler after {WAIT} s: {(tmp_path / 'dask.log').read_text()}"
                time.sleep(0.1)
            address = json.loads(file.read_text())["address"]
            for name in ("one", "two"):
                # No nanny: the worker is this process, so killing it loses the worker (a nanny would restart it).
                processes.append(dask("worker", address, "--name", name, "--nthreads", "1", "--no-nanny",
                                      "--no-dashboard", "--host", "127.0.0.1", log=log))
            with Client(address) as client:
                client.wait_for_workers(2, timeout=WAIT)
            yield address, processes[1:]
        finally:
            for p in processes:
                p.kill()
                p.wait()


def test_a_study_on_a_scheduler_and_two_worker_processes_survives_a_lost_worker(cluster, fmus, tmp_path):
    address, workers = cluster
    points = design([], [parse_sample(s) for s in SAMPLES], POINTS, 11)
    remote = run_sweep(SPLICE, points, scheduler=address, step=STEP, fmu_dir=fmus)
    local = run_sweep(SPLICE, points, workers=1, step=STEP, fmu_dir=fmus)
    assert remote.info["workers"] == 2 and address in remote.info["cluster"]
    assert all(r["status"] == "ok" for r in remote.rows), remote.failed()
    remote.write(tmp_path / "remote.csv")
    local.write(tmp_path / "local.csv")
    assert (tmp_path / "remote.csv").read_bytes() == (tmp_path / "local.csv").read_bytes()

    arrived, lost = [], []

    with Client(address) as observer:
        one = next(a for a, w in observer.scheduler_info()["workers"].items() if w["name"] == "one")

        def kill_after_five(index, row):
            arrived.append(index)
            if len(arrived) == 5:
                lost.extend(observer.processing()[one])  # its tasks in hand: they must run again elsewhere
                workers[0].kill()
                workers[0].wait()

        again = run_sweep(SPLICE, points, scheduler=address, step=STEP, fmu_dir=fmus, on_row=kill_after_five)
        assert workers[0].poll() is not None and lost and len(arrived) == POINTS
        assert len(observer.scheduler_info()["workers"]) == 1  # the worker is gone, not restarted
    assert all(r["status"] == "ok" for r in again.rows), again.failed()
    again.write(tmp_path / "again.csv")
    assert (tmp_path / "again.csv").read_bytes() == (tmp_path / "local.csv").read_bytes()
