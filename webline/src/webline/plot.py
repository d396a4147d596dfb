"""PNG plots of a run: one panel per unit (tensions, speeds, strains, ...), each curve in line order."""

from __future__ import annotations

import textwrap

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

from .result import Result  # noqa: E402


# What a column's unit measures, for the axis label; a unit not listed is shown alone. Numbers without a
# unit are told apart by their quantity: a strain, the share of a roller's traction in use, a coefficient.
QUANTITY_OF_UNIT = {"N": "tension", "m/s": "speed", "rad/s": "angular speed", "m": "length or position", "N.m": "torque"}
DIMENSIONLESS = {"eps": "strain", "traction": "traction in use", "mu_eff": "friction coefficient"}
FIRST = ("N", "m/s")  # tensions on top, then speeds, then the rest in recording order


def _panel(key: str, unit: str) -> tuple:
    """The panel a column goes on: its unit, and for a number its quantity."""
    return (unit, DIMENSIONLESS.get(key.rsplit(".", 1)[-1], "strain")) if unit == "1" else (unit, QUANTITY_OF_UNIT.get(unit))


def panels(result: Result) -> list:
    """The run's quantities, one per unit (and, for a number, per quantity), in the order they are shown:
    tensions (N) first, speeds (m/s) next, then the rest as recorded; each as ((unit, what it
    measures), [column keys in line order])."""
    found = {}  # (unit, what it measures) -> [column key]
    for c in result.columns:
        key, unit = c.split(" [")[0], c.split(" [")[1].rstrip("]")
        found.setdefault(_panel(key, unit), []).append(key)
    first = [p for u in FIRST for p in found if p[0] == u]
    return [(p, found[p]) for p in first + [p for p in found if p not in first]]


def draw_panel(ax, result: Result, unit: str, what: str | None, keys: list, reference: Result | None = None):
    """One quantity's curves on `ax`, its unit on the y axis (a reference's as dashed lines)."""
    for key in keys:
        (line,) = ax.plot(result.time, result.column(key), lw=1.3, label=key)
        if reference is not None and key in reference.keys():
            ax.plot(reference.time, reference.column(key), lw=0.8, ls="--", color=line.get_color())
    ax.set_ylabel(f"{what} [{unit}]" if what else f"[{unit}]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8, ncol=2)


def subtitle(result: Result, reference: Result | None = None) -> str:
    info = result.info
    sub = f"{info.get('method', '')}, step {info.get('step', 0) * 1e3:g} ms" if info else ""
    return sub + ("; dashed: monolithic reference" if reference is not None else "")


def plot(result: Result, path, title=None, reference: Result | None = None):
    """One panel per unit, so that each quantity is read on an axis of its own
    unit (strains of 1e-3 and angular speeds of 40 rad/s never share one):
    tensions (N) on top, speeds (m/s) below, then strain, angular speed,
    position, torque as recorded; each curve in line order."""
    shown = panels(result)
    fig, axes = plt.subplots(len(shown), 1, figsize=(9, 2.6 * len(shown) + 0.6), sharex=True, squeeze=False)
    for ax, ((unit, what), keys) in zip(axes[:, 0], shown):
        draw_panel(ax, result, unit, what, keys, reference)
    axes[-1, 0].set_xlabel("time [s]")
    fig.suptitle(f"{textwrap.fill(title or result.scene, 100)}\n{subtitle(result, reference)}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
