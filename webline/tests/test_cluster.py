"""A real cluster: `dask scheduler` and `dask worker` processes (the distributed package's own
commands, run by the venv's Python, over TCP on localhost). A study through it gives the very table
a local cluster of one worker gives; one worker killed while a second study runs loses nothing;
every worker killed, the study waits and new workers finish it; several studies on one client,
each study's release landing just after the next study sent its FMUs, never lose an FMU; a study
process killed (SIGKILL) or interrupted (SIGINT) half way and resumed gives the uninterrupted
table byte for byte; a scheduler that cannot be used is one line, exit 2, within 15 s; a scheduler
without workers stops the study after its --worker-timeout."""

import json
import os
import signal
import socket
import subprocess
import sys
import threading
import time

import pytest
from dask.distributed import Client
from webline import delivery
from webline.cli import main
from webline.sampling import design, parse_grid, parse_sample
from webline.sweep import run_sweep

from .conftest import SCENES

SPLICE = SCENES / "splice.json"
LAMINATION = SCENES / "lamination.json"
SAMPLES = ["line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)", "line.first.L=normal(1.5 m, 0.05 m)"]
STEP = 1e-3  # the splice at 1 ms: each point a few hundredths of a second, so the study takes seconds
POINTS = 30  # enough that most are still to come when the worker dies
WAIT = 60.0  # seconds the processes may take to start on a busy machine


class Cluster:
    """A scheduler and worker processes; every process stopped at the end."""

    def __init__(self, tmp_path):
        self.log = open(tmp_path / "dask.log", "w")
        self.tmp = tmp_path / "workers-tmp"  # the workers' temporary folders: what a study leaves there shows
        self.tmp.mkdir()
        self.processes, self.workers = [], []
        file = tmp_path / "scheduler.json"
        self.processes.append(self.dask("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                                        "--scheduler-file", str(file)))
        deadline = time.monotonic() + WAIT
        while not (file.exists() and file.read_text().strip()):
            assert time.monotonic() < deadline, f"no scheduler after {WAIT} s: {(tmp_path / 'dask.log').read_text()}"
            time.sleep(0.1)
        self.address = json.loads(file.read_text())["address"]

    def dask(self, *args):
        return subprocess.Popen([sys.executable, "-m", "dask", *args], stdout=self.log, stderr=subprocess.STDOUT,
                                env={**os.environ, "TMPDIR": str(self.tmp)})

    def start_workers(self, *names):
        # No nanny: the worker is this process, so killing it loses the worker (a nanny would restart it).
        started = [self.dask("worker", self.address, "--name", n, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                             "--host", "127.0.0.1") for n in names]
        self.processes += started
        self.workers += started
        return started

    def wait_for_workers(self, n):
        with Client(self.address) as client:
            client.wait_for_workers(n, timeout=WAIT)

    def close(self):
        for p in self.processes:
            p.kill()
            p.wait()
        self.log.close()


@pytest.fixture
def cluster(tmp_path):
    """A scheduler and two worker processes, "one" and "two"."""
    c = Cluster(tmp_path)
    try:
        c.start_workers("one", "two")
        c.wait_for_workers(2)
        yield c
    finally:
        c.close()


def written(table, path):
    table.write(path)
    return path.read_bytes()


def test_a_study_on_a_scheduler_and_two_worker_processes_survives_a_lost_worker(cluster, fmus, tmp_path):
    address, workers = cluster.address, cluster.workers
    points = design([], [parse_sample(s) for s in SAMPLES], POINTS, 11)
    remote = run_sweep(SPLICE, points, scheduler=address, step=STEP, fmu_dir=fmus)
    local = run_sweep(SPLICE, points, workers=1, step=STEP, fmu_dir=fmus)
    assert remote.info["workers"] == 2 and address in remote.info["cluster"]
    assert all(r["status"] == "ok" for r in remote.rows), remote.failed()
    assert written(remote, tmp_path / "remote.csv") == written(local, tmp_path / "local.csv")
    # The study's end removed what it extracted on the workers.
    assert not list(cluster.tmp.glob("webline-*")), list(cluster.tmp.iterdir())

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
    assert written(again, tmp_path / "again.csv") == (tmp_path / "local.csv").read_bytes()


def test_a_study_that_loses_every_worker_waits_and_new_workers_finish_it(cluster, fmus, tmp_path, capsys):
    points = design([], [parse_sample(s) for s in SAMPLES], POINTS, 11)
    arrived = []

    def kill_all_after_five(index, row):
        arrived.append(index)
        if len(arrived) == 5:
            for w in cluster.workers:
                w.kill()
                w.wait()
            # New workers, later: the study has waited for them with no worker at all.
            threading.Timer(2.0, cluster.start_workers, ("three", "four")).start()

    table = run_sweep(SPLICE, points, scheduler=cluster.address, step=STEP, fmu_dir=fmus, on_row=kill_all_after_five,
                      worker_timeout=WAIT, progress=False)
    assert all(r["status"] == "ok" for r in table.rows) and len(table.rows) == POINTS, table.failed()[:2]
    assert "no Dask worker is left: waiting" in capsys.readouterr().err
    local = run_sweep(SPLICE, points, workers=1, step=STEP, fmu_dir=fmus)
    assert written(table, tmp_path / "again.csv") == written(local, tmp_path / "local.csv")


def test_a_release_landing_after_the_next_study_sent_its_fmus_drops_nothing_100_times(cluster, fmus):
    """Three studies on one client in turn, 100 times, the very same FMU each time (as the line, parts
    and reference studies that hung shared the part FMUs): each study's release (its plugin
    unregistered) is forced to land just after the next study sent its FMUs, and the next study's
    tasks on every worker still find them."""
    data = {"ConvertingSpan.fmu": b"the same FMU's bytes" * 1000}
    with Client(cluster.address) as client:
        workers = list(client.nthreads())
        previous = None
        for k in range(100):
            for study in ("line", "parts", "reference"):
                name = delivery.study_name(study)
                client.register_plugin(delivery.StudyFiles(name, data), name=name)
                if previous is not None:
                    client.unregister_worker_plugin(previous)  # the last study's release, just after this one sent
                got = client.gather([client.submit(delivery.study_files, name, workers=[w], pure=False) for w in workers])
                assert [g.files for g in got] == [data] * len(workers), (k, study)
                previous = name
        client.unregister_worker_plugin(previous)
    # And the three engines' studies on one client, each one's release held back until the next one ran.
    grid = design(parse_grid(["stop_time=0.2 s", "line.to_rewind.L=1 m,2 m"]))
    with Client(cluster.address) as client:
        held = []
        unregister = client.unregister_worker_plugin
        client.unregister_worker_plugin = held.append
        try:
            tables = [run_sweep(LAMINATION, grid, engine=e, client=client, fmu_dir=fmus) for e in ("line", "parts", "reference")]
        finally:
            client.unregister_worker_plugin = unregister
        for name in held:
            unregister(name)
    assert [r["status"] for t in tables for r in t.rows] == ["ok"] * 6


def sweep_command(cluster, fmus, out, *extra):
    args = ["sweep", str(SPLICE), "--n", "80", "--seed", "5", "--step", "1 ms", "--out", str(out),
            "--fmu-dir", str(fmus), "--scheduler", cluster.address]
    for s in SAMPLES:
        args += ["--sample", s]
    return args + list(extra)


def run_until_half(cluster, fmus, out, sig, tmp_path):
    """The study as its own process, redirected, sent `sig` once half its points are in its journal."""
    args = [sys.executable, "-m", "webline", *sweep_command(cluster, fmus, out)]
    err, out_text = open(tmp_path / f"stderr-{sig}.txt", "w"), open(tmp_path / f"stdout-{sig}.txt", "w")
    # SIGINT as a terminal's Ctrl-C finds it: a shell without job control (CI's, a script's `&`) starts
    # its children with SIGINT ignored, and Python then never raises KeyboardInterrupt.
    process = subprocess.Popen(args, stdout=out_text, stderr=err,
                               preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    journal = out.with_name(f"{out.stem}.partial") / "rows.jsonl"
    deadline = time.monotonic() + 3 * WAIT
    while not (journal.exists() and len(journal.read_text().splitlines()) >= 40):
        assert process.poll() is None and time.monotonic() < deadline, (tmp_path / f"stderr-{sig}.txt").read_text()
        time.sleep(0.02)
    process.send_signal(sig)
    code = process.wait(timeout=WAIT)
    err.close()
    out_text.close()
    return (code, len(journal.read_text().splitlines()), (tmp_path / f"stderr-{sig}.txt").read_text(),
            (tmp_path / f"stdout-{sig}.txt").read_text())


@pytest.mark.parametrize("sig", [signal.SIGKILL, signal.SIGINT])
def test_a_study_stopped_half_way_and_resumed_gives_the_uninterrupted_table(cluster, fmus, tmp_path, sig):
    whole = tmp_path / "whole.csv"
    assert main(sweep_command(cluster, fmus, whole)) == 0
    out = tmp_path / "study.csv"
    code, kept, err, printed = run_until_half(cluster, fmus, out, sig, tmp_path)
    assert kept < 80, "the study ended before it was stopped"
    if sig == signal.SIGINT:
        assert code == 130, err
        assert "Traceback" not in err + printed and "stopped: interrupted" in printed and "not run" in printed, printed
        assert 40 <= len(out.read_text().splitlines()) - 1 < 80  # the finished rows, written
    else:
        assert code == -signal.SIGKILL
    assert "sweep: " in err and "points" in err  # progress, though stderr is a file
    assert main(sweep_command(cluster, fmus, out)) == 2  # the journal is there: refused without --resume
    assert main(sweep_command(cluster, fmus, out, "--resume")) == 0
    assert out.read_bytes() == whole.read_bytes()
    assert not out.with_name("study.partial").exists()


def test_a_scheduler_that_cannot_be_used_is_one_line_and_exit_2(fmus, tmp_path, capsys):
    def sweep(address, *extra):
        started = time.monotonic()
        code = main(["sweep", str(SPLICE), "--grid", "line.first.L=1.4 m", "--fmu-dir", str(fmus),
                     "--out", str(tmp_path / "t.csv"), "--scheduler", address, *extra])
        err = capsys.readouterr().err
        assert code == 2 and time.monotonic() - started < 15, err
        assert len(err.strip().splitlines()) == 1, err
        return err

    with socket.socket() as s:  # a port nobody listens on
        s.bind(("127.0.0.1", 0))
        port = s.getsockname()[1]
    assert "no Dask scheduler could be reached within 2 s" in sweep(f"tcp://127.0.0.1:{port}", "--connect-timeout", "2")
    assert "not a Dask scheduler's address" in sweep("tcp://127.0.0.1:notaport")
    for answer, message in [(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n" * 4, "is not a Dask scheduler"),
                            (b"", "did not answer as a Dask scheduler")]:  # a web server's answer; no answer at all
        with socket.socket() as server:
            server.bind(("127.0.0.1", 0))
            server.listen()

            def reply():
                conn, _ = server.accept()
                conn.recv(1024)
                conn.sendall(answer)
                time.sleep(8)
                conn.close()

            threading.Thread(target=reply, daemon=True).start()
            assert message in sweep(f"tcp://127.0.0.1:{server.getsockname()[1]}", "--connect-timeout", "3")


def test_a_study_without_workers_stops_after_its_worker_timeout(tmp_path, fmus, capsys):
    """A scheduler with no worker at all: the study says it waits, stops after --worker-timeout with
    no row lost (there is none), exit 1, and its journal is not left behind empty."""
    c = Cluster(tmp_path)
    try:
        started = time.monotonic()
        code = main(["sweep", str(SPLICE), "--grid", "line.first.L=1.4 m,1.5 m", "--step", "1 ms", "--fmu-dir", str(fmus),
                     "--out", str(tmp_path / "t.csv"), "--scheduler", c.address, "--worker-timeout", "2"])
        captured = capsys.readouterr()
        assert code == 1 and time.monotonic() - started < 30
        assert "no Dask worker is left: waiting up to 2 s" in captured.err
        assert "stopped: no Dask worker joined within 2 s (--worker-timeout)" in captured.out and "2 not run" in captured.out
        assert not (tmp_path / "t.partial").exists() and "--resume" not in captured.out
    finally:
        c.close()
