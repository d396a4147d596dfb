"""Pictures of a study: the band each recorded tension spans over all points, and an output of the
table against each swept key."""

from __future__ import annotations

import numpy as np

from .plot import plt  # matplotlib without a display, as every plot of webline


def is_tension(column: str) -> bool:
    """A recorded span tension: "first.T [N]"."""
    return column.split(" [")[0].endswith(".T")


class Envelope:
    """Each recorded tension's smallest and largest value at each time over the points added so far,
    on the time grid of the first point (another grid, from a swept stop time or step, is interpolated)."""

    def __init__(self, columns):
        self.columns = [c for c in columns if is_tension(c)]
        self.index = [i for i, c in enumerate(columns) if is_tension(c)]
        self.time = None
        self.lo = self.hi = None
        self.points = 0

    def add(self, outcome):
        if outcome.data is None or not self.index:
            return
        x = outcome.data[:, self.index]
        if self.time is None:
            self.time, self.lo, self.hi = outcome.time, x.copy(), x.copy()
        else:
            if len(outcome.time) != len(self.time) or not np.array_equal(outcome.time, self.time):
                x = np.column_stack([np.interp(self.time, outcome.time, x[:, j]) for j in range(x.shape[1])])
            np.minimum(self.lo, x, out=self.lo)
            np.maximum(self.hi, x, out=self.hi)
        self.points += 1


def plot_envelope(envelope: Envelope, path, title: str):
    fig, ax = plt.subplots(figsize=(9, 3.6))
    for j, c in enumerate(envelope.columns):
        (line,) = ax.plot(envelope.time, envelope.lo[:, j], lw=0.7, label=c.split(" [")[0])
        ax.plot(envelope.time, envelope.hi[:, j], lw=0.7, color=line.get_color())  # a band of no width stays a line
        ax.fill_between(envelope.time, envelope.lo[:, j], envelope.hi[:, j], alpha=0.3, lw=0, color=line.get_color())
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tension [N]")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(f"{title}\nsmallest to largest tension at each time over {envelope.points} points", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def output_column(table, name: str | None) -> str:
    """The table's column for `name` ("second.T_max", with or without its unit); default: the first
    span's largest tension."""
    metrics = [c for c in table.columns() if c not in table.keys and c not in ("point", "status")]
    if not name:
        name = next((c for c in metrics if "T_max" in c), metrics[0] if metrics else "")
    for c in metrics:
        if c == name or c.split(" [")[0] == name:
            return c
    raise ValueError(f"--plot {name!r}: the table has no such output (outputs: {', '.join(c.split(' [')[0] for c in metrics)})")


def _numbers(values):
    """A swept key's values as numbers, (numbers, labels, SI unit): a grid's "1.2 m" is read by the
    scene's units; anything else (a web's name) is placed by its order of appearance (labels)."""
    from .units import KIND_OF_UNIT, UnitError, parse_quantity

    out, si = [], None
    for v in values:
        if isinstance(v, (int, float)) and not isinstance(v, bool):
            out.append(float(v))
            continue
        words = str(v).split()
        kind = KIND_OF_UNIT.get(words[-1]) if len(words) > 1 else None
        try:
            out.append(parse_quantity(v, kind))
            si = kind.si
        except (AttributeError, UnitError):
            labels = list(dict.fromkeys(str(x) for x in values))
            return [labels.index(str(x)) for x in values], labels, None
    return out, None, si


def plot_scatter(table, output: str, path, title: str):
    """The output against each swept key, one panel per key; failed points left out."""
    ok = [r for r in table.rows if not r["status"].startswith("failed") and output in r]
    keys = list(table.keys)
    fig, axes = plt.subplots(1, max(len(keys), 1), figsize=(4.2 * max(len(keys), 1) + 0.6, 3.6), squeeze=False)
    for ax, key in zip(axes[0], keys):
        x, labels, si = _numbers([r[key] for r in ok])
        ax.plot(x, [r[output] for r in ok], "o", ms=3, alpha=0.6)
        if labels is not None:
            ax.set_xticks(range(len(labels)), labels, fontsize=8)
        ax.set_xlabel(f"{key} [{si}]" if si else key)
        ax.set_ylabel(output)
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"{title}: {output} over {len(ok)} points", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
