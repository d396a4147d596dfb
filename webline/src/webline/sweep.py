"""Sweeps: one scene over a grid of parameters, on Dask.

    webline sweep webline/scenes/lamination.json \\
        --grid "line.nip.drive.speed.table.22.1=4 m/s,5 m/s" --grid "line.film.L=1 m,2 m"

Each grid key names a value of the scene by its path (components of the
line by their name, list entries by their index); the grid is the product
of the values. Every point is one co-simulation, run as a Dask task: on a
local cluster (worker processes on this machine) by default, or on an
existing Dask scheduler given by its address. The scene text and the two
FMUs travel with the tasks (scattered to the workers once), so workers need
the webline package but no shared file system. The result is a table: the
grid values, and per point the tensions (min, max, end) of every span, the
end speed of every roller, the wall time and whether it ran.
"""

from __future__ import annotations

import csv
import hashlib
import itertools
import json
import os
import tempfile
import time as clock
from dataclasses import dataclass, field
from pathlib import Path

from .fmus import DEFAULT_FMU_DIR, ROLLER_FMU, SPAN_FMU


def parse_grid(specs):
    """["key=v1,v2", ...] -> [(key, [v1, v2]), ...]; values stay scene text
    ("2 m") unless they read as JSON numbers."""
    grid = []
    for spec in specs:
        key, sep, values = spec.partition("=")
        if not sep or not key.strip() or not values.strip():
            raise ValueError(f"--grid {spec!r}: expected KEY=V1,V2,...")
        vals = []
        for v in values.split(","):
            v = v.strip()
            try:
                vals.append(json.loads(v))
            except ValueError:
                vals.append(v)
        grid.append((key.strip(), vals))
    return grid


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


def run_point(scene_text: str, source: str, overrides: dict, files: dict, step=None):
    """One grid point (runs on a Dask worker): the metrics of one co-simulation."""
    from .compiler import run_scene
    from .scene import Span, parse_scene, set_path

    start = clock.perf_counter()
    row = dict(overrides)
    try:
        data = json.loads(scene_text)
        for k, v in overrides.items():
            set_path(data, k, v)
        label = f"{source} (with {', '.join(f'{k}={v}' for k, v in overrides.items())})"
        fmu_dir = _fmu_dir_on_worker(files)
        scene = parse_scene(json.dumps(data, indent=2), label, fmu_dir)
        result = run_scene(scene, fmu_dir=fmu_dir, step=step)
        for c in scene.line:
            key = f"{c.name}.T" if isinstance(c, Span) else f"{c.name}.v"
            if key not in result.keys():
                continue
            x = result.column(key)
            if isinstance(c, Span):
                row[f"{c.name}.T_min [N]"] = float(x.min())
                row[f"{c.name}.T_max [N]"] = float(x.max())
                row[f"{c.name}.T_end [N]"] = float(x[-1])
            else:
                row[f"{c.name}.v_end [m/s]"] = float(x[-1])
        row["steps"] = result.info["steps"]
        row["rollbacks"] = result.info["rollbacks"]
        row["status"] = "ok"
    except Exception as e:  # a point that fails is a row that says why
        row["status"] = f"failed: {e}"
    row["wall_time [s]"] = round(clock.perf_counter() - start, 3)
    return row


@dataclass
class Table:
    keys: list
    rows: list = field(default_factory=list)
    info: dict = field(default_factory=dict)

    def columns(self):
        cols = list(self.keys)
        for r in self.rows:
            for k in r:
                if k not in cols and k not in ("status",):
                    cols.append(k)
        return cols + ["status"]

    def write(self, path):
        cols = self.columns()
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(cols)
            for r in self.rows:
                w.writerow([r.get(c, "") for c in cols])

    def format(self):
        cols = self.columns()
        shown = [c for c in cols if c in self.keys or c.endswith("T_max [N]") or c.endswith("T_min [N]") or c in ("wall_time [s]", "status")]

        def cell(x):
            return f"{x:.4g}" if isinstance(x, float) else str(x)

        widths = [max(len(c), *(len(cell(r.get(c, ""))) for r in self.rows)) for c in shown]
        lines = ["  ".join(c.rjust(w) for c, w in zip(shown, widths))]
        for r in self.rows:
            lines.append("  ".join(cell(r.get(c, "")).rjust(w) for c, w in zip(shown, widths)))
        lines.append(
            f"{len(self.rows)} points on {self.info.get('cluster', '?')} in {self.info.get('wall_time', 0):.1f} s"
        )
        return "\n".join(lines)


def run_sweep(scene_path, grid, scheduler=None, workers=2, step=None, fmu_dir=DEFAULT_FMU_DIR, progress=False, client=None) -> Table:
    """Runs every point of the grid as a Dask task and collects the table.
    `scheduler`: address of a running scheduler; default: a local cluster of
    `workers` processes (closed at the end). `client`: an existing Client."""
    from dask.distributed import Client, LocalCluster, as_completed

    from .scene import load_scene

    # Fail early, here, on a bad scene or a bad key.
    for key, values in grid:
        load_scene(scene_path, {key: values[0]}, fmu_dir)
    text = Path(scene_path).read_text(encoding="utf-8")
    files = {n: (Path(fmu_dir) / n).read_bytes() for n in (SPAN_FMU, ROLLER_FMU)}
    keys = [k for k, _ in grid]
    points = [dict(zip(keys, combo)) for combo in itertools.product(*[v for _, v in grid])]

    start = clock.perf_counter()
    cluster = None
    own_client = client is None
    if client is None:
        if scheduler:
            client = Client(scheduler)
            where = f"the Dask scheduler at {scheduler}"
        else:
            cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
            client = Client(cluster)
            where = f"a local Dask cluster of {workers} worker processes"
    else:
        where = f"the Dask scheduler at {client.scheduler.address}"
    try:
        files_future = client.scatter(files, broadcast=True)
        futures = [client.submit(run_point, text, str(scene_path), p, files_future, step, pure=False) for p in points]
        index = {f.key: i for i, f in enumerate(futures)}
        rows = [None] * len(points)
        bar = None
        if progress:
            from tqdm import tqdm

            bar = tqdm(total=len(points), unit="point", desc="sweep", leave=False)
        for fut in as_completed(futures):
            rows[index[fut.key]] = fut.result()
            if bar is not None:
                bar.update(1)
        if bar is not None:
            bar.close()
    finally:
        if own_client:
            client.close()
        if cluster is not None:
            cluster.close()
    return Table(keys=keys, rows=rows, info={"cluster": where, "wall_time": clock.perf_counter() - start})
