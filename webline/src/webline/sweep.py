"""Sweeps and Monte Carlo studies of one scene, on Dask.

    webline sweep webline/scenes/splice.json --sample "line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)" \\
        --sample "line.first.L=normal(1.5 m, 0.05 m)" --n 1000 --seed 7 --series out/splice.parquet --plot

A key names a value of the scene by its path (components of the line by their name, list entries
by their index); the points are a grid, random samples or both (`sampling`). Points run as Dask
tasks: on a local cluster (worker processes on this machine) by default, or on a running Dask
scheduler given by its address. Engines:

- `line` (default): the scene as one Line FMU (`linestudy`): exported once per structure, its
  bytes on every worker through the study's own plugin (`delivery`), one instance per worker reset
  for every point, a few points per task (`chunk_size`), a point's steps in one call into the
  library (`native`);
- `fmpy-line`: the same, each point through FMPy's simulate_fmu (the same numbers bit for bit);
- `parts`: the co-simulation of the line's span and Roller FMUs (whose bytes travel likewise),
  a point per task;
- `reference`: the monolithic SciPy reference, a point per task.

The result is a table, one row per point in the order of the design: the point's values, each
span's minimum, maximum and end tension, each roller's end speed, and its status (a point that
fails is a row that says why; the study goes on). `--series` keeps every point's recorded signals
in one Parquet file. Nothing in the table depends on where or how fast a point ran, so the same
design gives the same table bit for bit on any number of workers (docs/studies.md). Rows are kept
as they arrive (`journal`), so an interrupted study keeps what finished and `--resume` finishes it.
"""

from __future__ import annotations

import csv
import json
import re
import tempfile
import time as clock
from collections import Counter
from contextlib import ExitStack, contextmanager
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import delivery, linestudy, units
from .fmus import DEFAULT_FMU_DIR, ROLLER_FMU, SPAN_FMU
from .journal import Journal, StudyError, identity
from .points import Outcome, failed, layout, metric_record, metrics
from .progress import Progress
from .scene import SceneError, load_scene, set_path

# The engines a sweep runs a scene with (names.py names every engine). The Line FMU's two give the
# same numbers bit for bit: `line` steps it in one call per point (native.py), `fmpy-line` in FMPy's loop.
ENGINES = ("line", "fmpy-line", "parts", "reference")
LINE_ENGINES = ("line", "fmpy-line")
WHAT = {"line": "the Line FMU", "fmpy-line": "the Line FMU in FMPy's loop", "parts": "the co-simulation of parts",
        "reference": "the monolithic reference"}
CONNECT_TIMEOUT = 10.0  # seconds a scheduler has to answer (--connect-timeout)
WORKER_TIMEOUT = 300.0  # seconds a study without workers waits for one (--worker-timeout)


class Stopped(Exception):
    """The study stopped before its end (--max-failed, no worker came back): why."""


def engine_name(name: str) -> str:
    if name not in ENGINES:
        raise SceneError(f"engine {name!r}: a sweep runs {', '.join(ENGINES)}")
    return name


def _kind(value):
    """The kind of a quantity ("1.5 m"; a plain number is dimensionless), or None for anything else."""
    if isinstance(value, bool):
        return None
    if isinstance(value, (int, float)):
        return units.DIMENSIONLESS
    m = units._QUANTITY.match(value.strip()) if isinstance(value, str) else None  # the scene's own reading
    if not m:
        return None
    return units.KIND_OF_UNIT.get(m.group(2)) if m.group(2) else units.DIMENSIONLESS


def check_keys(scene_path, design, engine):
    """Before any task runs: every key names a value the scene has, of the kind of every value the
    design gives it (`L=uniform(1 kg, 2 kg)` would fail every point); `tolerance` goes with the Line FMU."""
    data = json.loads(Path(scene_path).read_text(encoding="utf-8"))
    given = {}  # key -> {kind: a value of that kind}
    for point in design.points:
        for key, value in point.items():
            given.setdefault(key, {}).setdefault(_kind(value), value)
    for key, kinds in given.items():
        if key == linestudy.TOLERANCE:
            if engine not in LINE_ENGINES:
                raise SceneError(f"{key!r} is the Line FMU's tolerance: it goes with --engine line")
            continue
        if key == "record" or key.startswith("record."):
            raise SceneError(f"{key!r}: the record says what every point keeps; it is not a value to sweep")
        before = set_path(data, key, None)
        want = _kind(before)
        for kind, value in kinds.items():
            if want is not None and kind is not None and kind is not want:
                raise SceneError(f"{key}={value}: {kind.name}, but the scene's value there ({before!r}) is {want.name}")


def outputs(scene, engine: str, user=()) -> list:
    """The table's outputs, known before any point runs (what --plot may name)."""
    zero = np.zeros(2)
    return (list(metrics(layout(scene), lambda name: zero, zero)) + [m.column for m in user]
            + (["steps", "rollbacks"] if engine == "parts" else []))


def run_scene_point(scene_text: str, source: str, overrides: dict, files: str, engine: str, step=None, series=False,
                    user=()) -> Outcome:
    """One point by the parts' co-simulation or the reference (a Dask task; `files`: the study's
    plugin with the part FMUs): a step above the parts' stable limit makes the point a failed row
    that says so, as `webline run` refuses it."""
    from .engines import run_scene
    from .scene import parse_scene

    started = clock.time()
    try:
        data = json.loads(scene_text)
        for k, v in overrides.items():
            set_path(data, k, v)
        label = f"{source} (with {', '.join(f'{k}={v}' for k, v in overrides.items())})"
        fmu_dir = str(delivery.study_files(files).folder())
        scene = parse_scene(json.dumps(data, indent=2), label, fmu_dir, Path(source).parent)
        recorded = len(scene.record)
        scene.record = metric_record(scene, user)
        t0 = clock.perf_counter()
        result = run_scene(scene, engine, fmu_dir=fmu_dir, step=step)
        outcome = Outcome(row=metrics(layout(scene), result.column, result.time, user), simulation=clock.perf_counter() - t0)
        if engine == "parts":
            outcome.row.update(steps=result.info["steps"], rollbacks=result.info["rollbacks"])
        outcome.row["status"] = "ok"
        if series:
            outcome.time, outcome.data = result.time, result.data[:, :recorded]
    except Exception as e:  # a point that fails is a row that says why
        outcome = failed(str(e))
    outcome.started, outcome.ended = started, clock.time()
    return outcome


def is_failed(row: dict) -> bool:
    return row["status"].startswith("failed")


def reason(status: str) -> str:
    """A status without the point's own values (a scene's error names the file "with" them), so that
    points failing alike count as one reason."""
    return re.sub(r" \(with [^()]*\)(?=:)", "", status)


@dataclass
class Table:
    """The rows a study has, in the order of the design (a study stopped early lacks some)."""

    keys: list  # the columns of the points' values
    rows: list = field(default_factory=list)
    info: dict = field(default_factory=dict)

    def columns(self):
        cols = ["point"] + list(self.keys)
        for r in self.rows:
            cols += [k for k in r if k not in cols and k != "status"]
        return cols + ["status"]

    def write(self, path):
        cols = self.columns()
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(cols)
            for r in self.rows:
                w.writerow([r.get(c, "") for c in cols])

    def failed(self):
        return [r for r in self.rows if is_failed(r)]

    def format(self, shown=12):
        cols = self.columns()
        cols = [c for c in cols if c in ("point", "status") or c in self.keys or "T_max" in c or "T_min" in c]

        def cell(x):
            return f"{x:.5g}" if isinstance(x, float) else str(x)

        rows = self.rows if len(self.rows) <= shown else self.rows[: shown // 2] + self.rows[-shown // 2:]
        lines = []
        if rows:
            widths = [max(len(c), *(len(cell(r.get(c, ""))) for r in rows)) for c in cols]
            lines.append("  ".join(c.rjust(w) for c, w in zip(cols, widths)))
            for k, r in enumerate(rows):
                if len(rows) < len(self.rows) and k == shown // 2:
                    lines.append(f"  ... {len(self.rows) - len(rows)} more rows in the table file")
                lines.append("  ".join(cell(r.get(c, "")).rjust(w) for c, w in zip(cols, widths)))
        return "\n".join(lines + [self.summary()])

    def summary(self) -> str:
        """How many points, ok, warned, failed (reasons counted) and not run; the rate of ok points per
        worker present; the time a point took on its worker."""
        info = self.info
        failed_rows = self.failed()
        warned = sum(r["status"].startswith("warning") for r in self.rows)
        ok = len(self.rows) - len(failed_rows)
        wall = info.get("wall_time", 0.0)
        ran = ok - info.get("resumed", 0)  # the ok points of this run (a resumed study keeps others)
        rate = ran / wall / max(info.get("workers_mean") or 1, 1) if wall else 0.0
        n = info.get("structures")
        exports = f", {n} export{'s' if n != 1 else ''}" if n is not None else ""
        missing = info.get("missing", 0)
        lines = [f"{info.get('points', len(self.rows))} points: {ok} ok ({warned} with a warning), {len(failed_rows)} failed"
                 f"{f', {missing} not run' if missing else ''}, through {WHAT.get(info.get('engine'), '?')}{exports} on "
                 f"{info.get('cluster', '?')} in {wall:.1f} s: {rate:.3g} ok points/s per worker "
                 f"({info.get('workers_mean') or 0:.3g} workers on average), {info.get('seconds_per_point', 0):.3g} s per point "
                 "on its worker"]
        reasons = Counter(reason(r["status"]) for r in failed_rows)
        for why, count in reasons.most_common(5):
            first = next(r["point"] for r in failed_rows if reason(r["status"]) == why)
            lines.append(f"  {count} x {why} (first: point {first})")
        if len(reasons) > 5:
            lines.append(f"  ... {len(reasons) - 5} other reasons in the table")
        if info.get("stopped"):
            lines.append(f"stopped: {info['stopped']}")
        if info.get("journal"):
            lines.append(f"the finished points are kept in {info['journal']}: the same command with --resume runs the "
                         "missing and failed points")
        return "\n".join(lines)


ROWS_PER_GROUP = 200_000  # rows of a Parquet row group of the series


def write_series(path, columns, points, journal, metadata: dict):
    """Every kept point's recorded signals in one Parquet file, in the order of `points`: columns
    point, time [s] and one per signal, one row per point and time; `metadata` as the file's
    key "webline" (JSON)."""
    import pyarrow as pa
    import pyarrow.parquet as pq

    schema = pa.schema([("point", pa.int32()), ("time [s]", pa.float64())] + [(c, pa.float64()) for c in columns],
                       metadata={"webline": json.dumps(metadata)})
    pending = []

    def flush():
        if pending:
            point = np.concatenate([np.full(len(t), i, dtype=np.int32) for i, t, _ in pending])
            time = np.concatenate([t for _, t, _ in pending])
            data = np.concatenate([d for _, _, d in pending])
            arrays = [pa.array(point), pa.array(time)] + [pa.array(data[:, j]) for j in range(data.shape[1])]
            writer.write_table(pa.Table.from_arrays(arrays, schema=schema))
            pending.clear()

    with pq.ParquetWriter(str(path), schema) as writer:
        for i in points:
            got = journal.series_of(i)
            if got is not None:
                pending.append((i, *got))
                if sum(len(t) for _, t, _ in pending) >= ROWS_PER_GROUP:
                    flush()
        flush()


def _version() -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("webline")
    except PackageNotFoundError:
        return "unknown"


def run_sweep(scene_path, design, engine="line", scheduler=None, workers=2, step=None, fmu_dir=DEFAULT_FMU_DIR,
              progress=None, client=None, series=None, envelope=False, on_row=None, out=None, resume=False,
              max_failed=None, connect_timeout=CONNECT_TIMEOUT, worker_timeout=WORKER_TIMEOUT, user=()) -> Table:
    """Runs the points of `design` (sampling.Design) as Dask tasks and collects the table.
    `scheduler`: address of a running scheduler; default: a local cluster of `workers` processes
    (closed at the end); `client`: an existing Client. `series`: a Parquet file for the recorded
    signals; `envelope`: keep each recorded tension's band over the points (table.info["envelope"]);
    `on_row(index, row)`: called as each point's row arrives. `out`: the table, beside which the
    journal keeps rows as they arrive (`journal`; without it, a temporary one); `resume`: run only
    the points the journal lacks or has failed. `user`: the user's metrics (usermetric). Ctrl-C, `max_failed` failed points or no worker
    for `worker_timeout` s stop the study with the rows it has (info["stopped"] says why)."""
    engine = engine_name(engine)
    check_keys(scene_path, design, engine)
    columns = load_scene(scene_path, fmu_dir=fmu_dir).columns()
    keep = bool(series) or envelope
    n = len(design.points)
    with ExitStack() as stack:
        table_path = out or Path(stack.enter_context(tempfile.TemporaryDirectory(prefix="webline-sweep-"))) / "sweep.csv"
        journal, done = Journal.start(table_path, identity(scene_path, engine, design, step, keep, [m.spec for m in user]), resume)
        rows = {i: d.row for i, d in done.items()}  # a failed one runs again and is replaced
        times = {i: d.times for i, d in done.items()}
        todo = [i for i in range(n) if i not in rows or is_failed(rows[i])]
        bar = Progress(len(todo), terminal=progress)
        if resume:
            bar.say(f"sweep: resuming: {n - len(todo)} of {n} points kept, {len(todo)} to run")
        failures = 0

        def arrived(i: int, outcome: Outcome):
            nonlocal failures
            rows[i], times[i] = outcome.row, [outcome.started, outcome.ended, outcome.simulation]
            journal.add(i, outcome.row, times[i], outcome.time if keep else None, outcome.data)
            bar.point(outcome.row["status"])
            if on_row is not None:
                on_row(i, {"point": i, **design.values[i], **outcome.row})
            failures += is_failed(outcome.row)
            if max_failed is not None and failures > max_failed:
                raise Stopped(f"{failures} points failed, more than --max-failed {max_failed}")

        info = {"engine": engine, "seed": design.seed, "points": n, "resumed": n - len(todo), "stopped": None}
        try:
            with dask_client(scheduler, workers, client, connect_timeout) as (c, where):
                info.update(started=clock.time(), cluster=where)  # the cluster is up: from here on the study itself
                link = dashboard(c)
                if link:
                    bar.say(f"sweep: Dask's dashboard: {link}")
                try:
                    info.update(_run(c, scene_path, design, todo, engine, step, fmu_dir, keep, user, arrived, bar, worker_timeout))
                finally:
                    info["wall_time"] = clock.time() - info["started"]
        except KeyboardInterrupt:
            info["stopped"] = "interrupted (Ctrl-C)"
        except Stopped as e:
            info["stopped"] = str(e)
        finally:
            bar.close()
            journal.close()
        order = sorted(rows)
        table = Table(keys=list(design.keys), rows=[{"point": i, **design.values[i], **rows[i]} for i in order], info=info)
        spent = [times[i][1] - times[i][0] for i in order if not is_failed(rows[i])]
        info.update(missing=n - len(rows), tasks=[tuple(times[i]) for i in order], workers_mean=bar.mean_workers,
                    seconds_per_point=float(np.mean(spent)) if spent else 0.0)
        if series:
            write_series(series, columns, order, journal, {
                "webline": _version(), "scene": str(scene_path), "engine": engine, "seed": design.seed,
                "design": {"keys": list(design.keys), "points": n}, "statuses": dict(Counter(r["status"] for r in rows.values())),
                "missing": n - len(rows), "seconds per point": info["seconds_per_point"]})
        if envelope:
            from .sweepplot import Envelope

            band = info["envelope"] = Envelope(columns)
            for i in order:
                got = journal.series_of(i)
                if got is not None:
                    band.add(*got)
        complete = info["stopped"] is None and not info["missing"] and not table.failed()
        if complete or out is None:
            journal.remove()
        elif journal.folder.exists():  # (a study stopped before its first row has none: run it again as it was)
            info["journal"] = str(journal.folder)
        return table


def dashboard(client):
    """The address of Dask's dashboard, when the scheduler runs one (it needs bokeh)."""
    try:
        if "dashboard" not in client.scheduler_info().get("services", {}):
            return None
        return client.dashboard_link
    except Exception:  # a scheduler that cannot tell
        return None


def _identity(scheduler: str, timeout: float) -> dict:
    """What answers at `scheduler` says it is (Dask's `identity` call): an OSError if it cannot be
    reached within `timeout` seconds, a TimeoutError if it is reached but does not answer within 2 s
    more (a Client alone waits for ever on an endpoint that accepts the connection but never answers)."""
    import asyncio

    from distributed.core import rpc

    async def ask():
        remote = rpc(scheduler, timeout=timeout)
        try:
            return await remote.identity()
        finally:
            await remote.close_rpc()

    return asyncio.run(asyncio.wait_for(ask(), timeout + 2.0))


def connect(scheduler: str, timeout: float):
    """A Client of the scheduler at `scheduler`; a StudyError in one line if there is none."""
    from dask.distributed import Client

    try:
        identity = _identity(scheduler, timeout)
    except ValueError as e:
        raise StudyError(f"--scheduler {scheduler!r} is not a Dask scheduler's address (e.g. tcp://host:8786): {e}") from None
    except TimeoutError:  # connected, but no answer in Dask's protocol
        raise StudyError(f"--scheduler {scheduler}: what listens there did not answer as a Dask scheduler") from None
    except OSError:
        raise StudyError(f"--scheduler {scheduler}: no Dask scheduler could be reached within {timeout:g} s "
                         "(--connect-timeout)") from None
    except Exception as e:  # something answered, but not in Dask's protocol (a web server: a header read as a length)
        raise StudyError(f"--scheduler {scheduler}: what answers there is not a Dask scheduler ({type(e).__name__})") from None
    if not isinstance(identity, dict) or identity.get("type") != "Scheduler":
        raise StudyError(f"--scheduler {scheduler}: what answers there is not a Dask scheduler")
    return Client(scheduler, timeout=timeout)


@contextmanager
def dask_client(scheduler=None, workers=2, client=None, connect_timeout=CONNECT_TIMEOUT):
    """(client, where it runs): `client` itself, or one of the scheduler at `scheduler`, or of a
    local cluster of `workers` processes, closed at the end."""
    from dask.distributed import Client, LocalCluster

    if client is not None:
        yield client, f"the Dask scheduler at {client.scheduler.address}"
    elif scheduler:
        with connect(scheduler, connect_timeout) as c:
            yield c, f"the Dask scheduler at {scheduler}"
    else:
        with _ignoring_ctrl_c():  # the worker processes start ignoring it: Ctrl-C stops the study, which stops them
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0")
        with cluster, Client(cluster) as c:
            yield c, f"a local Dask cluster of {workers} worker processes"


@contextmanager
def _ignoring_ctrl_c():
    """SIGINT ignored meanwhile (in the main thread; a new Python process keeps ignoring it)."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _run(client, scene_path, design, todo, engine, step, fmu_dir, keep, user, arrived, progress, worker_timeout) -> dict:
    """Submits the points `todo`, hands each outcome to `arrived` as it comes; what the run was.
    The FMUs reach the workers through plugins of this study alone, unregistered at its end."""
    present = len(client.nthreads())
    progress.workers(present)
    info = {"workers": present}
    futures = {}  # future -> its points
    plugins = []

    def deliver(name, files):
        client.register_plugin(delivery.StudyFiles(name, files), name=name)
        plugins.append(name)

    try:
        if engine in LINE_ENGINES:
            client.register_plugin(linestudy.LineFmusPlugin())
            planner = linestudy.Planner(scene_path, fmu_dir, step, series=keep, user=user, native=engine == "line")
            chunk = chunk_size(len(todo), present)
            waiting = {}  # structure -> [(point, task)] not yet submitted

            def submit(index):
                items = waiting.pop(index)
                futures[client.submit(linestudy.run_points, [t for _, t in items], pure=False)] = [i for i, _ in items]

            planned = clock.perf_counter()
            for i in todo:
                try:
                    s, task = planner.plan(design.points[i])
                except Exception as e:  # its scene cannot be read or its line not exported: a row that says why
                    arrived(i, failed(str(e)))
                    continue
                if s.name not in plugins:
                    deliver(s.name, {linestudy.LINE_FMU: s.fmu})
                waiting.setdefault(s.index, []).append((i, task))
                if len(waiting[s.index]) == chunk:
                    submit(s.index)
            for index in list(waiting):
                submit(index)
            info.update(structures=len(planner.structures), planning=clock.perf_counter() - planned, chunk=chunk)
        else:
            text = Path(scene_path).read_text(encoding="utf-8")
            name = delivery.study_name(engine)
            deliver(name, {n: (Path(fmu_dir) / n).read_bytes() for n in (SPAN_FMU, ROLLER_FMU)})
            for i in todo:
                futures[client.submit(run_scene_point, text, str(scene_path), design.points[i], name, engine, step, keep,
                                      tuple(user), pure=False)] = [i]
        _collect(client, futures, arrived, progress, worker_timeout)
    finally:
        client.cancel([f for f in futures if not f.done()])
        for name in plugins:  # the study ends on every worker: its FMUs' instances freed, their folders removed
            try:
                client.unregister_worker_plugin(name)
            except Exception as e:  # the scheduler is gone: nothing of the study is left to release
                progress.say(f"sweep: the study's FMUs could not be released on the workers: {type(e).__name__}: {e}")
    return info


def _collect(client, futures, arrived, progress, worker_timeout):
    """Each outcome to `arrived` as it comes. About every second: the workers present (a study
    whose workers are all gone waits for new ones, which get the FMUs from the study's plugins),
    and the progress."""
    from dask.distributed import as_completed

    pending = as_completed(list(futures))
    checked, alone_since = 0.0, None
    tries = Counter()  # a result not fetched in time: tried again with twice the time, up to a minute
    while not pending.is_empty():
        batch = pending.next_batch(block=False)
        for k, fut in enumerate(batch):
            points = futures[fut]
            try:
                outcomes = fut.result(timeout=min(2.0 ** tries[fut.key], 60.0))
            except TimeoutError:  # its result was on a worker that died: Dask runs it again, meanwhile we watch
                tries[fut.key] += 1
                pending.update(batch[k:])
                break
            except Exception as e:  # the task itself was lost (a worker died too often): the rows say so
                outcomes = [failed(f"{type(e).__name__}: {e}")] * len(points)
            for i, outcome in zip(points, outcomes if isinstance(outcomes, list) else [outcomes]):
                arrived(i, outcome)
            fut.release()
        now = clock.monotonic()
        if now - checked >= 1.0:
            checked = now
            present = len(client.nthreads())
            progress.workers(present)
            progress.tick()
            if present == 0 and alone_since is None:
                alone_since = now
                progress.say(f"sweep: no Dask worker is left: waiting up to {worker_timeout:g} s for one "
                             "(--worker-timeout); Ctrl-C keeps what finished")
            elif present == 0 and now - alone_since > worker_timeout:
                raise Stopped(f"no Dask worker joined within {worker_timeout:g} s (--worker-timeout)")
            elif present and alone_since is not None:
                alone_since = None
                progress.say(f"sweep: {present} worker{'s' if present != 1 else ''} joined: going on")
        if not batch:
            clock.sleep(0.05)


# Points of the Line FMU take tens of milliseconds, of the order of what Dask spends handing a task
# over: a task runs several, so that this is paid once for them (bench/studies.py), yet each worker
# still gets some eight tasks to balance the load and a lost task costs few points.
TASKS_PER_WORKER, MOST_POINTS_PER_TASK = 8, 16


def chunk_size(points: int, workers: int) -> int:
    return max(1, min(MOST_POINTS_PER_TASK, points // (max(workers, 1) * TASKS_PER_WORKER)))
