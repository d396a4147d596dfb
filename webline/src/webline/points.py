"""What one point of a study keeps, whichever engine ran it.

Its row of the table: each span's minimum, maximum, end and RMS tension, its overshoot, settling
time and the time of its maximum, each roller's end speed (every span and roller of the line,
recorded by the scene or not), the most traction each roller the web may slip on used, the user's
own metrics (`usermetric`), and its status: "ok", or why it failed. When asked, its recorded signals too (the scene's `record`), for the series file and the
envelope plot. The times it took are kept apart from the row, so that the table of a study is
the same bit for bit however it was run.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .scene import Scene, Span


@dataclass
class Outcome:
    row: dict  # the metrics and "status"
    time: np.ndarray | None = None  # the communication points of the recorded signals
    data: np.ndarray | None = None  # one column per recorded signal, one row per time
    simulation: float = 0.0  # seconds of the run itself (the Line FMU: fmi2Reset and simulate_fmu)
    started: float = 0.0  # when its task began and ended on its worker (time.time(): one clock per machine)
    ended: float = 0.0


def failed(why: str) -> Outcome:
    """A failed point's row: why, on one line (the FMU's messages after FMPy's)."""
    why = "; ".join(line.strip() for line in str(why).splitlines() if line.strip())
    return Outcome(row={"status": f"failed: {why}"})


SETTLED = 0.02  # a tension has settled once it stays within 2 % of its end value


def metric_record(scene: Scene, user=()) -> list:
    """The scene's record, then what the metrics read that it does not record: every span's
    tension, every roller's speed and the user's metrics' signals, as (component, quantity)."""
    extra = [(c.name, "T" if isinstance(c, Span) else "v") for c in scene.parts]
    extra += [(c.name, "traction") for c in scene.parts if getattr(c, "traction", None) is not None]
    extra += [tuple(m.signal.split(".")) for m in user]
    record = list(scene.record)
    for r in extra:
        if r not in record:
            record.append(r)
    return record


def settling_time(time, x) -> float:
    """When `x` last enters the band of SETTLED of its end value for good (the first time if it never leaves it)."""
    outside = np.flatnonzero(np.abs(x - x[-1]) > SETTLED * abs(x[-1]))
    return float(time[outside[-1] + 1] if len(outside) else time[0])


def layout(scene: Scene) -> list:
    """The parts the metrics cover, in line order: (name, "span", "roller" or "slips": a roller the
    web may slip on)."""
    def kind(c):
        return "span" if isinstance(c, Span) else "slips" if getattr(c, "traction", None) is not None else "roller"
    return [(c.name, kind(c)) for c in scene.parts]


def metrics(parts: list, column, time, user=()) -> dict:
    """The row of a run: `parts` as `layout` gives them, `column("first.T")` a recorded signal at
    the times `time`, `user` the user's metrics (usermetric.Metric)."""
    row = {}
    time = np.asarray(time, dtype=float)
    for name, kind in parts:
        if kind == "span":
            x = np.asarray(column(f"{name}.T"), dtype=float)
            row[f"{name}.T_min [N]"] = float(x.min())
            row[f"{name}.T_max [N]"] = float(x.max())
            row[f"{name}.T_end [N]"] = float(x[-1])
            row[f"{name}.T_rms [N]"] = float(np.sqrt(np.mean((x - x.mean()) ** 2)))  # about its mean: the fluctuation
            row[f"{name}.T_overshoot [N]"] = float(x.max() - x[-1])
            row[f"{name}.T_settling [s]"] = settling_time(time, x)
            row[f"{name}.T_peak_time [s]"] = float(time[np.argmax(x)])
        else:
            row[f"{name}.v_end [m/s]"] = float(column(f"{name}.v")[-1])
        if kind == "slips":
            row[f"{name}.traction_max [1]"] = float(column(f"{name}.traction").max())
    for m in user:
        row[m.column] = m.value(column, time)
    return row
