"""Results of a run: time, recorded columns, and what it cost; CSV in and out."""

from __future__ import annotations

import csv
from dataclasses import dataclass, field

import numpy as np


@dataclass
class Result:
    scene: str
    columns: list  # "name.quantity [unit]"
    time: np.ndarray
    data: np.ndarray  # rows: time points, columns: as `columns`
    info: dict = field(default_factory=dict)

    def column(self, key: str) -> np.ndarray:
        """A column by "name.quantity" (with or without the unit)."""
        for i, c in enumerate(self.columns):
            if c == key or c.split(" [")[0] == key:
                return self.data[:, i]
        raise KeyError(f"no column {key!r} (columns: {', '.join(self.columns)})")

    def keys(self):
        return [c.split(" [")[0] for c in self.columns]

    def write_csv(self, path):
        with open(path, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["time [s]"] + list(self.columns))
            for t, row in zip(self.time, self.data):
                w.writerow([repr(float(t))] + [repr(float(x)) for x in row])

    @staticmethod
    def read_csv(path, scene="") -> "Result":
        with open(path, newline="") as f:
            rows = list(csv.reader(f))
        header, body = rows[0], rows[1:]
        arr = np.array([[float(x) for x in r] for r in body])
        return Result(scene=scene, columns=header[1:], time=arr[:, 0], data=arr[:, 1:])


def scale_of(result: Result, key: str) -> float:
    """The scale errors of a column are measured against: its largest magnitude."""
    x = result.column(key)
    return float(np.max(np.abs(x))) or 1.0


def max_error(a: Result, b: Result, key: str, scale: float | None = None) -> float:
    """Largest difference of a column at the common time points, relative to `scale`
    (default: the largest magnitude of the column in `b`)."""
    ta, tb = a.time, b.time
    if len(ta) != len(tb) or np.max(np.abs(ta - tb)) > 1e-9 * max(1.0, float(tb[-1])):
        xb = np.interp(ta, tb, b.column(key))
    else:
        xb = b.column(key)
    s = scale if scale is not None else scale_of(b, key)
    return float(np.max(np.abs(a.column(key) - xb))) / s
