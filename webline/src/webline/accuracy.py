"""Co-simulation against the monolithic reference: errors, observed order, cost
(`webline run --reference`, `webline convergence`)."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import linefmu
from .compiler import run_scene
from .master import scene_grid
from .names import engine_name
from .reference import reference
from .result import Result

UNSTABLE = 0.1  # an error above 10 % of the tension's range: the coupling diverged


def union_grid(scene, steps):
    times = set()
    for h in steps:
        times.update(scene_grid(scene, h))
    return np.array(sorted(times))


def subsample(ref: Result, times) -> Result:
    """The reference at `times`, which must be among its own time points."""
    idx = np.searchsorted(ref.time, times)
    idx = np.clip(idx, 0, len(ref.time) - 1)
    left = np.clip(idx - 1, 0, len(ref.time) - 1)
    pick = np.where(np.abs(ref.time[left] - times) < np.abs(ref.time[idx] - times), left, idx)
    if np.max(np.abs(ref.time[pick] - times)) > 1e-9:
        raise ValueError("the reference was not sampled at these times")
    return Result(scene=ref.scene, columns=ref.columns, time=ref.time[pick], data=ref.data[pick], info=ref.info)


def errors(result: Result, ref: Result) -> dict:
    """Per recorded column: the largest deviation from the reference over the
    run, relative to the column's largest magnitude in the reference."""
    r = subsample(ref, result.time)
    out = {}
    for key in result.keys():
        scale = float(np.max(np.abs(r.column(key)))) or 1.0
        out[key] = float(np.max(np.abs(result.column(key) - r.column(key)))) / scale
    return out


def tension_error(errs: dict) -> float:
    """The largest relative error of the span tensions."""
    vals = [e for k, e in errs.items() if k.endswith(".T")]
    return max(vals) if vals else max(errs.values())


@dataclass
class Row:
    step: float
    error: float  # largest relative tension error
    speed_error: float
    wall_time: float
    steps: int
    rollbacks: int
    failed: str = ""


def convergence(scene, steps, ref: Result | None = None, engine="parts", fmu_dir=None, **options):
    """Runs the scene at each communication step (`engine` parts or line; `options`: the parts' master's)
    and measures it against one reference sampled on the union of the grids. Every step runs, one above
    the parts' stable step too: the table studies where the coupling diverges (its row says so).
    Returns (rows, reference)."""
    engine = engine_name(engine)
    if engine not in ("parts", "line"):
        raise ValueError(f"convergence measures the parts or the Line FMU, not the {engine} engine")
    steps = sorted(steps, reverse=True)
    if ref is None:
        ref = reference(scene, times=union_grid(scene, steps))
    rows = []
    for h in steps:
        try:
            r = run_scene(scene, fmu_dir=fmu_dir, step=h, **options) if engine == "parts" else linefmu.run(scene, fmu_dir, h)
        except Exception as e:  # an unstable coupling fails; its row records that
            rows.append(Row(h, math.inf, math.inf, math.nan, 0, 0, failed=str(e)[:160]))
            continue
        errs = errors(r, ref)
        speed = [e for k, e in errs.items() if k.endswith(".v")]
        rows.append(Row(h, tension_error(errs), max(speed) if speed else 0.0, r.info["wall_time"], r.info["steps"], r.info.get("rollbacks", 0)))
    return rows, ref


def observed_orders(rows):
    """log(e1/e2)/log(h1/h2) between consecutive steps."""
    out = []
    for a, b in zip(rows[:-1], rows[1:]):
        if a.error > 0 and b.error > 0 and math.isfinite(a.error) and math.isfinite(b.error):
            out.append(math.log(a.error / b.error) / math.log(a.step / b.step))
        else:
            out.append(math.nan)
    return out


def stability_limit(rows):
    """The largest step at which the run stayed within UNSTABLE, and the smallest at which it did not."""
    stable = [r.step for r in rows if r.error < UNSTABLE]
    unstable = [r.step for r in rows if not r.error < UNSTABLE]
    return (max(stable) if stable else None, min(unstable) if unstable else None)
