"""Sweeps and Monte Carlo studies of one scene, on Dask.

    webline sweep webline/scenes/splice.json --sample "line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)" \\
        --sample "line.first.L=normal(1.5 m, 0.05 m)" --n 1000 --seed 7 --series out/splice.parquet --plot

A key names a value of the scene by its path (components of the line by their name, list entries
by their index); the points are a grid, random samples or both (`sampling`). Points run as Dask
tasks: on a local cluster (worker processes on this machine) by default, or on a running Dask
scheduler given by its address. Engines:

- `line` (default): the scene as one Line FMU (`linestudy`): exported once per structure, its
  bytes scattered once to every worker, one instance per worker reset for every point, a few
  points per task (`chunk_size`), a point's steps in one call into the library (`native`);
- `fmpy-line`: the same, each point through FMPy's simulate_fmu (the same numbers bit for bit);
- `parts`: the co-simulation of the line's span and Roller FMUs (whose bytes travel likewise),
  a point per task;
- `reference`: the monolithic SciPy reference, a point per task.

The result is a table, one row per point in the order of the design: the point's values, each
span's minimum, maximum and end tension, each roller's end speed, and its status (a point that
fails is a row that says why; the study goes on). `--series` keeps every point's recorded signals
in one Parquet file. Nothing in the table depends on where or how fast a point ran, so the same
design gives the same table bit for bit on any number of workers (docs/studies.md).
"""

from __future__ import annotations

import csv
import hashlib
import json
import os
import tempfile
import time as clock
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path

from . import linestudy
from .fmus import DEFAULT_FMU_DIR, ROLLER_FMU, SPAN_FMU
from .points import Outcome, failed, layout, metric_record, metrics
from .scene import SceneError, load_scene, set_path

# The engines a sweep runs a scene with (names.py names every engine). The Line FMU's two give the same
# numbers bit for bit: `line` steps it in one call per point (native.py), `fmpy-line` in FMPy's loop.
ENGINES = ("line", "fmpy-line", "parts", "reference")
LINE_ENGINES = ("line", "fmpy-line")
WHAT = {"line": "the Line FMU", "fmpy-line": "the Line FMU in FMPy's loop", "parts": "the co-simulation of parts",
        "reference": "the monolithic reference"}


def engine_name(name: str) -> str:
    if name not in ENGINES:
        raise SceneError(f"engine {name!r}: a sweep runs {', '.join(ENGINES)}")
    return name


def check_keys(scene_path, keys, engine):
    """Every key names a value the scene has (before any task runs); `tolerance` goes with the Line FMU."""
    data = json.loads(Path(scene_path).read_text(encoding="utf-8"))
    for key in keys:
        if key == linestudy.TOLERANCE:
            if engine not in LINE_ENGINES:
                raise SceneError(f"{key!r} is the Line FMU's tolerance: it goes with --engine line")
            continue
        if key == "record" or key.startswith("record."):
            raise SceneError(f"{key!r}: the record says what every point keeps; it is not a value to sweep")
        set_path(data, key, None)


def _fmu_dir_on_worker(files: dict) -> str:
    """Writes the FMU bytes into a folder of this worker (once per content)."""
    digest = hashlib.sha256(b"".join(files[k] for k in sorted(files))).hexdigest()[:16]
    d = Path(tempfile.gettempdir()) / f"webline-fmus-{digest}"
    if not d.exists():
        tmp = Path(tempfile.mkdtemp(prefix="webline-fmus-"))
        for name, data in files.items():
            (tmp / name).write_bytes(data)
        try:
            os.replace(tmp, d)
        except OSError:  # another task of this worker was first
            pass
    return str(d)


def run_scene_point(scene_text: str, source: str, overrides: dict, files: dict, engine: str, step=None, series=False) -> Outcome:
    """One point by the parts' co-simulation or the reference (a Dask task): a step above the
    parts' stable limit makes the point a failed row that says so, as `webline run` refuses it."""
    from .engines import run_scene
    from .scene import parse_scene

    started = clock.time()
    try:
        data = json.loads(scene_text)
        for k, v in overrides.items():
            set_path(data, k, v)
        label = f"{source} (with {', '.join(f'{k}={v}' for k, v in overrides.items())})"
        fmu_dir = _fmu_dir_on_worker(files)
        scene = parse_scene(json.dumps(data, indent=2), label, fmu_dir, Path(source).parent)
        recorded = len(scene.record)
        scene.record = metric_record(scene)
        t0 = clock.perf_counter()
        result = run_scene(scene, engine, fmu_dir=fmu_dir, step=step)
        outcome = Outcome(row=metrics(layout(scene), result.column), simulation=clock.perf_counter() - t0)
        if engine == "parts":
            outcome.row.update(steps=result.info["steps"], rollbacks=result.info["rollbacks"])
        outcome.row["status"] = "ok"
        if series:
            outcome.time, outcome.data = result.time, result.data[:, :recorded]
    except Exception as e:  # a point that fails is a row that says why
        outcome = failed(str(e))
    outcome.started, outcome.ended = started, clock.time()
    return outcome


@dataclass
class Table:
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
        return [r for r in self.rows if r["status"].startswith("failed")]

    def format(self, shown=12):
        cols = self.columns()
        cols = [c for c in cols if c in ("point", "status") or c in self.keys or "T_max" in c or "T_min" in c]

        def cell(x):
            return f"{x:.5g}" if isinstance(x, float) else str(x)

        rows = self.rows if len(self.rows) <= shown else self.rows[: shown // 2] + self.rows[-shown // 2:]
        widths = [max(len(c), *(len(cell(r.get(c, ""))) for r in rows)) for c in cols]
        lines = ["  ".join(c.rjust(w) for c, w in zip(cols, widths))]
        for k, r in enumerate(rows):
            if len(rows) < len(self.rows) and k == shown // 2:
                lines.append(f"  ... {len(self.rows) - len(rows)} more rows in the table file")
            lines.append("  ".join(cell(r.get(c, "")).rjust(w) for c, w in zip(cols, widths)))
        info = self.info
        wall = info.get("wall_time", 0.0)
        rate = len(self.rows) / wall / max(info.get("workers", 1), 1) if wall else 0.0
        n = info.get("structures")
        exports = f", {n} export{'s' if n != 1 else ''}" if n is not None else ""
        lines.append(f"{len(self.rows)} points ({len(self.failed())} failed) through {WHAT.get(info.get('engine'), '?')}"
                     f"{exports} on {info.get('cluster', '?')} in {wall:.1f} s: {rate:.3g} points/s per worker")
        for r in self.failed()[:3]:
            lines.append(f"  point {r['point']}: {r['status']}")
        return "\n".join(lines)


class SeriesWriter:
    """Every point's recorded signals in one Parquet file: columns point, time [s] and one per signal,
    one row per point and time, in the order of the points (they arrive in any order)."""

    ROWS_PER_GROUP = 200_000

    def __init__(self, path, columns):
        import pyarrow as pa
        import pyarrow.parquet as pq

        self.columns = list(columns)
        self.schema = pa.schema([("point", pa.int32()), ("time [s]", pa.float64())] + [(c, pa.float64()) for c in self.columns])
        self.writer = pq.ParquetWriter(str(path), self.schema)
        self.next = 0
        self.waiting = {}
        self.pending = []  # (point, outcome) in order, not yet written

    def add(self, index: int, outcome: Outcome):
        self.waiting[index] = outcome
        while self.next in self.waiting:
            o = self.waiting.pop(self.next)
            if o.data is not None:
                self.pending.append((self.next, o))
            self.next += 1
        if sum(len(o.time) for _, o in self.pending) >= self.ROWS_PER_GROUP:
            self._flush()

    def _flush(self):
        import numpy as np
        import pyarrow as pa

        if not self.pending:
            return
        point = np.concatenate([np.full(len(o.time), i, dtype=np.int32) for i, o in self.pending])
        time = np.concatenate([o.time for _, o in self.pending])
        data = np.concatenate([o.data for _, o in self.pending])
        arrays = [pa.array(point), pa.array(time)] + [pa.array(data[:, j]) for j in range(data.shape[1])]
        self.writer.write_table(pa.Table.from_arrays(arrays, schema=self.schema))
        self.pending = []

    def close(self):
        self._flush()
        self.writer.close()


def run_sweep(scene_path, design, engine="line", scheduler=None, workers=2, step=None, fmu_dir=DEFAULT_FMU_DIR,
              progress=False, client=None, series=None, envelope=False, on_row=None) -> Table:
    """Runs every point of `design` (sampling.Design) as Dask tasks and collects the table.
    `scheduler`: address of a running scheduler; default: a local cluster of `workers` processes
    (closed at the end); `client`: an existing Client. `series`: a Parquet file for the recorded
    signals; `envelope`: keep each recorded tension's band over the points (table.info["envelope"]);
    `on_row(index, row)`: called as each point's row arrives."""
    engine = engine_name(engine)
    check_keys(scene_path, [k for p in design.points[:1] for k in p], engine)
    columns = load_scene(scene_path, fmu_dir=fmu_dir).columns()
    keep = bool(series) or envelope
    writer = SeriesWriter(series, columns) if series else None
    band = None
    if envelope:
        from .sweepplot import Envelope

        band = Envelope(columns)

    rows = [None] * len(design.points)
    tasks = [None] * len(design.points)  # (started, ended, seconds of the run itself) on its worker
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=len(design.points), unit="point", desc="sweep", leave=False)

    def arrived(i: int, outcome: Outcome):
        rows[i] = {"point": i, **design.values[i], **outcome.row}
        tasks[i] = (outcome.started, outcome.ended, outcome.simulation)
        if writer is not None:
            writer.add(i, outcome)
        if band is not None:
            band.add(outcome)
        if bar is not None:
            bar.update(1)
        if on_row is not None:
            on_row(i, rows[i])

    info = {"engine": engine, "seed": design.seed}
    try:
        with dask_client(scheduler, workers, client) as (client, where):
            info["started"] = clock.time()  # the cluster is up: from here on the study itself
            info.update(cluster=where, **_run(client, scene_path, design, engine, step, fmu_dir, keep, arrived))
            info["wall_time"] = clock.time() - info["started"]
    finally:
        if bar is not None:
            bar.close()
        if writer is not None:
            writer.close()
    info["tasks"] = tasks
    if band is not None:
        info["envelope"] = band
    return Table(keys=list(design.keys), rows=rows, info=info)


@contextmanager
def dask_client(scheduler=None, workers=2, client=None):
    """(client, where it runs): `client` itself, or one of the scheduler at `scheduler`, or of a
    local cluster of `workers` processes, closed at the end."""
    from dask.distributed import Client, LocalCluster

    if client is not None:
        yield client, f"the Dask scheduler at {client.scheduler.address}"
    elif scheduler:
        with Client(scheduler) as c:
            yield c, f"the Dask scheduler at {scheduler}"
    else:
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=":0") as cluster, \
                Client(cluster) as c:
            yield c, f"a local Dask cluster of {workers} worker processes"


def _run(client, scene_path, design, engine, step, fmu_dir, keep, arrived) -> dict:
    """Submits every point, hands each outcome to `arrived` as it comes; what the run was."""
    from dask.distributed import as_completed

    info = {"workers": len(client.scheduler_info().get("workers", {}))}
    futures = {}  # future -> its points
    if engine in LINE_ENGINES:
        client.register_plugin(linestudy.LineFmusPlugin())
        planner = linestudy.Planner(scene_path, fmu_dir, step, series=keep, native=engine == "line")
        scattered = {}  # structure -> its FMU's bytes, on every worker
        chunk = chunk_size(len(design.points), info["workers"])
        waiting = {}  # structure -> [(point, task)] not yet submitted

        def submit(index):
            items = waiting.pop(index)
            fut = client.submit(linestudy.run_points, scattered[index], [t for _, t in items], pure=False)
            futures[fut] = [i for i, _ in items]

        planned = clock.perf_counter()
        for i, point in enumerate(design.points):
            try:
                s, task = planner.plan(point)
            except Exception as e:  # its scene cannot be read or its line not exported: a row that says why
                arrived(i, failed(str(e)))
                continue
            if s.index not in scattered:
                scattered[s.index] = client.scatter(s.fmu, broadcast=True)
            waiting.setdefault(s.index, []).append((i, task))
            if len(waiting[s.index]) == chunk:
                submit(s.index)
        for index in list(waiting):
            submit(index)
        info.update(structures=len(planner.structures), planning=clock.perf_counter() - planned, chunk=chunk)
    else:
        text = Path(scene_path).read_text(encoding="utf-8")
        files = client.scatter({n: (Path(fmu_dir) / n).read_bytes() for n in (SPAN_FMU, ROLLER_FMU)}, broadcast=True)
        for i, point in enumerate(design.points):
            futures[client.submit(run_scene_point, text, str(scene_path), point, files, engine, step, keep, pure=False)] = [i]
    for fut in as_completed(list(futures)):
        points = futures[fut]
        try:
            outcomes = fut.result()
        except Exception as e:  # the task itself was lost (a worker died too often): the rows say so
            outcomes = [failed(f"{type(e).__name__}: {e}")] * len(points)
        for i, outcome in zip(points, outcomes if isinstance(outcomes, list) else [outcomes]):
            arrived(i, outcome)
        fut.release()
    return info


# Points of the Line FMU take tens of milliseconds, of the order of what Dask spends handing a task
# over: a task runs several, so that this is paid once for them (bench/studies.py), yet each worker
# still gets some eight tasks to balance the load and a lost task costs few points.
TASKS_PER_WORKER, MOST_POINTS_PER_TASK = 8, 16


def chunk_size(points: int, workers: int) -> int:
    return max(1, min(MOST_POINTS_PER_TASK, points // (max(workers, 1) * TASKS_PER_WORKER)))
