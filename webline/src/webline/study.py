"""Co-simulation against the monolithic reference: errors, observed order, cost."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .compiler import run_scene
from .master import scene_grid
from .reference import reference
from .result import Result


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


def convergence(scene, steps, ref: Result | None = None, **options):
    """Runs the scene at each communication step and measures it against one
    reference sampled on the union of the grids. Returns (rows, reference)."""
    steps = sorted(steps, reverse=True)
    if ref is None:
        ref = reference(scene, times=union_grid(scene, steps))
    rows = []
    for h in steps:
        try:
            r = run_scene(scene, step=h, **options)
        except Exception as e:  # an unstable coupling fails; the study records that
            rows.append(Row(h, math.inf, math.inf, math.nan, 0, 0, failed=str(e).split(":")[0][:80]))
            continue
        errs = errors(r, ref)
        speed = [e for k, e in errs.items() if k.endswith(".v")]
        rows.append(Row(h, tension_error(errs), max(speed) if speed else 0.0, r.info["wall_time"], r.info["steps"], r.info["rollbacks"]))
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


VARIANTS = [
    ("gauss-seidel", "extrapolate"),
    ("gauss-seidel", "hold"),
    ("jacobi", "extrapolate"),
    ("jacobi", "hold"),
]
UNSTABLE = 0.1  # an error above 10 % of the tension's range: the coupling diverged


def line_study(scene, stiff_scene, steps, stiff_steps, fmu_dir, out_png):
    """The line-level accuracy–cost study: co-simulation error and wall time
    against the communication step for each master variant (scene), and the
    stability limit of a stiff line with and without input derivatives
    (stiff_scene). Writes a PNG; returns the rows for printing."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    accuracy = {}
    ref = reference(scene, times=union_grid(scene, steps))
    for alg, coupling in VARIANTS:
        accuracy[(alg, coupling)], _ = convergence(scene, steps, ref=ref, algorithm=alg, coupling=coupling, fmu_dir=fmu_dir)
    stiff = {}
    sref = reference(stiff_scene, times=union_grid(stiff_scene, stiff_steps))
    for coupling in ("extrapolate", "hold"):
        stiff[coupling], _ = convergence(stiff_scene, stiff_steps, ref=sref, coupling=coupling, fmu_dir=fmu_dir)

    fig, axes = plt.subplots(1, 3, figsize=(14, 4.2))
    for (alg, coupling), rows in accuracy.items():
        ok = [r for r in rows if r.error < UNSTABLE]
        label = f"{alg}, {coupling}"
        axes[0].loglog([r.step * 1e3 for r in ok], [r.error for r in ok], "o-", label=label)
        axes[1].loglog([r.step * 1e3 for r in ok], [r.wall_time for r in ok], "o-", label=label)
        bad = [r for r in rows if not r.error < UNSTABLE]
        if bad:
            axes[0].plot([r.step * 1e3 for r in bad], [UNSTABLE] * len(bad), "x", color=axes[0].lines[-1].get_color(), ms=10)
    axes[0].set_title(f"{scene.name}: error against the reference\n(x: diverged)")
    axes[0].set_xlabel("communication step [ms]")
    axes[0].set_ylabel("largest tension error / tension range")
    axes[1].set_title(f"{scene.name}: wall time ({scene.stop_time:g} s simulated)")
    axes[1].set_xlabel("communication step [ms]")
    axes[1].set_ylabel("wall time [s]")
    for coupling, rows in stiff.items():
        label = "input derivatives, extrapolation" if coupling == "extrapolate" else "inputs held"
        ok = [r for r in rows if r.error < UNSTABLE]
        (line,) = axes[2].loglog([r.step * 1e3 for r in ok], [r.error for r in ok], "o-", label=label)
        bad = [r for r in rows if not r.error < UNSTABLE]
        axes[2].plot([r.step * 1e3 for r in bad], [UNSTABLE] * len(bad), "x", color=line.get_color(), ms=10)
    axes[2].set_title(f"{stiff_scene.name}: stability limit\n(x: diverged)")
    axes[2].set_xlabel("communication step [ms]")
    axes[2].set_ylabel("largest tension error / tension range")
    from matplotlib.ticker import NullFormatter

    for ax, hs in zip(axes, (steps, steps, stiff_steps)):
        ax.set_xticks([h * 1e3 for h in hs])
        ax.set_xticklabels([f"{h * 1e3:g}" for h in hs], fontsize=7)
        ax.xaxis.set_minor_formatter(NullFormatter())
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    plt.close(fig)
    return accuracy, stiff


def stability_limit(rows):
    """The largest step at which the run stayed within UNSTABLE, and the smallest at which it did not."""
    stable = [r.step for r in rows if r.error < UNSTABLE]
    unstable = [r.step for r in rows if not r.error < UNSTABLE]
    return (max(stable) if stable else None, min(unstable) if unstable else None)
