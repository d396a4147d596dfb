"""Pictures of a study: the bands each recorded tension spans over all points (its median, 5 to
95 %, smallest to largest), and an output of the table against each swept key, failed points
marked. No axis has an offset: a constant output must not look like spread."""

from __future__ import annotations

import numpy as np

from .plot import plt  # matplotlib without a display, as every plot of webline


def is_tension(column: str) -> bool:
    """A recorded span tension: "first.T [N]"."""
    return column.split(" [")[0].endswith(".T")


PERCENTILES = (5, 50, 95)
BAND_TIMES = 1000  # the percentile bands on at most this many times (all points' curves are kept for them)


class Envelope:
    """Each recorded tension's smallest and largest value at each time over the points added so far,
    on the time grid of the first point (another grid, from a swept stop time or step, is
    interpolated), and its 5, 50 and 95 % percentiles over the points on a grid of at most
    BAND_TIMES of those times."""

    def __init__(self, columns):
        self.columns = [c for c in columns if is_tension(c)]
        self.index = [i for i, c in enumerate(columns) if is_tension(c)]
        self.time = None
        self.lo = self.hi = None
        self.points = 0
        self._coarse = None  # indices of self.time the percentiles are taken at
        self._curves = []  # each point's tensions at those times

    def add(self, time, data):
        """One point's recorded signals (a row per time, a column per signal)."""
        if not self.index:
            return
        x = data[:, self.index]
        if self.time is None:
            self.time, self.lo, self.hi = time, x.copy(), x.copy()
            self._coarse = np.unique(np.linspace(0, len(time) - 1, min(len(time), BAND_TIMES)).astype(int))
        else:
            if len(time) != len(self.time) or not np.array_equal(time, self.time):
                x = np.column_stack([np.interp(self.time, time, x[:, j]) for j in range(x.shape[1])])
            np.minimum(self.lo, x, out=self.lo)
            np.maximum(self.hi, x, out=self.hi)
        self._curves.append(x[self._coarse])
        self.points += 1

    def percentiles(self):
        """(times, {percentile: array of times x tensions})."""
        curves = np.stack(self._curves)
        return self.time[self._coarse], {q: np.percentile(curves, q, axis=0) for q in PERCENTILES}


def plot_envelope(envelope: Envelope, path, title: str):
    fig, ax = plt.subplots(figsize=(9, 3.6))
    times, bands = envelope.percentiles()
    low, median, high = (bands[q] for q in PERCENTILES)
    for j, c in enumerate(envelope.columns):
        (line,) = ax.plot(times, median[:, j], lw=1.0, label=f"{c.split(' [')[0]}: median")
        color = line.get_color()
        ax.fill_between(times, low[:, j], high[:, j], alpha=0.35, lw=0, color=color)
        ax.plot(envelope.time, envelope.lo[:, j], lw=0.5, color=color, ls=":")  # a band of no width stays a line
        ax.plot(envelope.time, envelope.hi[:, j], lw=0.5, color=color, ls=":")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tension [N]")
    ax.ticklabel_format(useOffset=False)  # an offset would make a constant look like spread
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(f"{title}\nmedian, 5 to 95 % band (shaded) and smallest to largest (dotted) over {envelope.points} points",
                 fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def output_column(metrics: list, name: str | None) -> str:
    """The column of `metrics` (the table's outputs) for `name` ("second.T_max", with or without its
    unit); default: the first span's largest tension."""
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
    """The output against each swept key, one panel per key; failed points marked at the bottom of each
    panel (they have no output)."""
    rows = [r for r in table.rows if output in r]
    lost = [r for r in table.rows if output not in r]
    keys = list(table.keys)
    fig, axes = plt.subplots(1, max(len(keys), 1), figsize=(4.2 * max(len(keys), 1) + 0.6, 3.6), squeeze=False)
    for ax, key in zip(axes[0], keys):
        x, labels, si = _numbers([r[key] for r in rows + lost])
        ax.plot(x[: len(rows)], [r[output] for r in rows], "o", ms=3, alpha=0.6)
        if lost:
            ax.plot(x[len(rows):], [0.02] * len(lost), "x", color="red", ms=5, transform=ax.get_xaxis_transform(),
                    label=f"failed ({len(lost)})")
            ax.legend(loc="best", fontsize=8)
        if labels is not None:
            ax.set_xticks(range(len(labels)), labels, fontsize=8)
        ax.set_xlabel(f"{key} [{si}]" if si else key)
        ax.set_ylabel(output)
        ax.ticklabel_format(useOffset=False, axis="y")
        if labels is None:
            ax.ticklabel_format(useOffset=False, axis="x")
        ax.grid(True, alpha=0.3)
    fig.suptitle(f"{title}: {output} over {len(rows)} points" + (f", {len(lost)} failed" if lost else ""), fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
