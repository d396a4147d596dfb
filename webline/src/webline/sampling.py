"""The points of a study: full grids and random samples of scene values.

    --grid "line.film.L=1 m,2 m"                                   every value, crossed with the other grids
    --sample "line.idler.J=uniform(0.01 kg.m2, 0.05 kg.m2)"         n values from a distribution
    --sample "line.first.L=normal(1.5 m, 0.05 m)" --n 1000 --seed 7

Random samples come from a Latin hypercube (SciPy's `qmc.LatinHypercube`): each key's range of
probability is cut into n equal strata and each stratum holds exactly one point, so no value repeats
and few points already cover every range. The design is drawn here, once, before any task runs, so
the same seed gives the same points bit for bit however many workers run them. The distributions'
quantities are read by the scene's unit parser (`units`); a sampled value goes into the scene as its
SI value written exactly (`repr`), so the scene reads back the very number drawn.
"""

from __future__ import annotations

import itertools
import json
import re
from dataclasses import dataclass

import numpy as np

from . import units


class DesignError(ValueError):
    """A --grid or --sample that cannot be read; the message says which and why."""


def parse_grid(specs):
    """["key=v1,v2", ...] -> [(key, [v1, v2]), ...]; values stay scene text
    ("2 m") unless they read as JSON numbers."""
    grid = []
    for spec in specs:
        key, sep, values = spec.partition("=")
        if not sep or not key.strip() or not values.strip():
            raise DesignError(f"--grid {spec!r}: expected KEY=V1,V2,...")
        vals = []
        for v in values.split(","):
            v = v.strip()
            try:
                vals.append(json.loads(v))
            except ValueError:
                vals.append(v)
        grid.append((key.strip(), vals))
    return grid


@dataclass(frozen=True)
class Sample:
    """One sampled key: `kind` names the distribution, `a` and `b` its two parameters in SI
    (uniform: lower and upper bound; normal: mean and standard deviation)."""

    key: str
    kind: str
    a: float
    b: float
    quantity: units.Kind

    @property
    def column(self) -> str:
        """The table's column of the sampled values: the key and its SI unit."""
        return f"{self.key} [{self.quantity.si}]"

    def values(self, u: np.ndarray) -> np.ndarray:
        """The values at probabilities u in [0, 1)."""
        if self.kind == "uniform":
            return self.a + (self.b - self.a) * u
        from scipy.stats import norm

        return norm.ppf(u, loc=self.a, scale=self.b)

    def scene_value(self, x: float):
        """How the value goes into the scene: a number if dimensionless, else "x unit" in SI."""
        return float(x) if self.quantity is units.DIMENSIONLESS else f"{float(x)!r} {self.quantity.si}"


DISTRIBUTIONS = {"uniform": ("lower bound", "upper bound"), "normal": ("mean", "standard deviation")}
_CALL = re.compile(r"^\s*([a-z]+)\s*\((.*)\)\s*$")


def _quantity(text: str, what: str):
    """A quantity of any kind the scene knows, by its unit: (SI value, kind)."""
    text = text.strip()
    m = units._QUANTITY.match(text)  # the scene's own reading of "number unit"
    if not m:
        raise DesignError(f"{what}: {text!r} is not a number with a unit, e.g. \"1.5 m\"")
    unit = m.group(2)
    kind = units.KIND_OF_UNIT.get(unit) if unit else units.DIMENSIONLESS
    if kind is None:
        raise DesignError(f"{what}: unknown unit {unit!r} in {text!r} (units: {', '.join(units.KIND_OF_UNIT)})")
    try:
        return units.parse_quantity(text if unit else float(m.group(1)), kind), kind
    except units.UnitError as e:
        raise DesignError(f"{what}: {e}") from None


def parse_sample(spec: str) -> Sample:
    """"key=uniform(a, b)" or "key=normal(mean, sd)" -> a Sample."""
    key, sep, body = spec.partition("=")
    m = _CALL.match(body)
    if not sep or not key.strip() or not m:
        raise DesignError(f"--sample {spec!r}: expected KEY=uniform(LOW, HIGH) or KEY=normal(MEAN, SD)")
    kind, args = m.group(1), [a for a in m.group(2).split(",")]
    if kind not in DISTRIBUTIONS:
        raise DesignError(f"--sample {spec!r}: unknown distribution {kind!r} (known: {', '.join(DISTRIBUTIONS)})")
    if len(args) != 2:
        raise DesignError(f"--sample {spec!r}: {kind} takes two values, its {' and '.join(DISTRIBUTIONS[kind])}")
    (a, ka), (b, kb) = (_quantity(x, f"--sample {spec!r}") for x in args)
    if ka is not kb:
        raise DesignError(f"--sample {spec!r}: {args[0].strip()!r} is {ka.name}, {args[1].strip()!r} is {kb.name}: give both in units of one kind")
    if kind == "uniform" and not a < b:
        raise DesignError(f"--sample {spec!r}: the lower bound must be below the upper bound")
    if kind == "normal" and not b > 0:
        raise DesignError(f"--sample {spec!r}: the standard deviation must be > 0")
    return Sample(key.strip(), kind, a, b, ka)


@dataclass
class Design:
    """The points of a study in order: `points[i]` holds the scene overrides of point i, `values[i]`
    what the table shows of them (a grid value as given, a sampled value as its SI number)."""

    keys: list  # the table's columns of the point's values
    points: list  # [{scene key: override}]
    values: list  # [{column: value}]
    seed: int | None = None


def latin_hypercube(samples: list, n: int, seed: int) -> np.ndarray:
    """n rows of one value per sample; each column's values all distinct."""
    from scipy.stats import qmc

    u = qmc.LatinHypercube(d=len(samples), rng=np.random.default_rng(seed)).random(n)
    x = np.column_stack([s.values(u[:, j]) for j, s in enumerate(samples)])
    for j, s in enumerate(samples):
        if len(np.unique(x[:, j])) != n:  # a stratum per point: only a broken transform repeats
            raise DesignError(f"--sample {s.key}: the design repeats a value")
    return x


def design(grid=(), samples=(), n: int | None = None, seed: int | None = None) -> Design:
    """Every grid combination crossed with the n sampled points (either part may be empty)."""
    grid, samples = list(grid), list(samples)
    keys = [k for k, _ in grid] + [s.key for s in samples]
    twice = sorted({k for k in keys if keys.count(k) > 1})
    if twice:
        raise DesignError(f"the key {twice[0]!r} is given twice")
    if not grid and not samples:
        raise DesignError("no points: give --grid KEY=V1,V2,... or --sample KEY=DISTRIBUTION(...) with --n")
    if samples and not (n and n > 0):
        raise DesignError("--sample needs --n, the number of points to draw (> 0)")
    if n and not samples:
        raise DesignError("--n goes with --sample")
    rows = latin_hypercube(samples, n, seed) if samples else np.empty((1, 0))
    points, values = [], []
    for combo in itertools.product(*[v for _, v in grid]):
        fixed = dict(zip([k for k, _ in grid], combo))
        for row in rows:
            points.append({**fixed, **{s.key: s.scene_value(x) for s, x in zip(samples, row)}})
            values.append({**fixed, **{s.column: float(x) for s, x in zip(samples, row)}})
    columns = [k for k, _ in grid] + [s.column for s in samples]
    return Design(keys=columns, points=points, values=values, seed=seed if samples else None)
