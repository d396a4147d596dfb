"""What one point of a study keeps, whichever engine ran it.

Its row of the table: each span's minimum, maximum and end tension and each roller's end speed
(every span and roller of the line, recorded by the scene or not), the most traction each roller
the web may slip on used, and its status: "ok", or why it
failed. When asked, its recorded signals too (the scene's `record`), for the series file and the
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


def metric_record(scene: Scene) -> list:
    """The scene's record, then what the metrics read that it does not record: every span's
    tension and every roller's speed, as (component, quantity)."""
    extra = [(c.name, "T" if isinstance(c, Span) else "v") for c in scene.parts]
    extra += [(c.name, "traction") for c in scene.parts if getattr(c, "traction", None) is not None]
    return list(scene.record) + [r for r in extra if r not in scene.record]


def layout(scene: Scene) -> list:
    """The parts the metrics cover, in line order: (name, "span", "roller" or "slips": a roller the
    web may slip on)."""
    def kind(c):
        return "span" if isinstance(c, Span) else "slips" if getattr(c, "traction", None) is not None else "roller"
    return [(c.name, kind(c)) for c in scene.parts]


def metrics(parts: list, column) -> dict:
    """The row of a run: `parts` as `layout` gives them, `column("first.T")` a recorded signal."""
    row = {}
    for name, kind in parts:
        if kind == "span":
            x = column(f"{name}.T")
            row[f"{name}.T_min [N]"] = float(x.min())
            row[f"{name}.T_max [N]"] = float(x.max())
            row[f"{name}.T_end [N]"] = float(x[-1])
        else:
            row[f"{name}.v_end [m/s]"] = float(column(f"{name}.v")[-1])
        if kind == "slips":
            row[f"{name}.traction_max [1]"] = float(column(f"{name}.traction").max())
    return row
