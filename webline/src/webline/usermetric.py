"""Scalars of the user's own over a point's recorded signals: `--metric "peak=max(first.T)"`.

    NAME=FUNCTION(SIGNAL)              over the whole run
    NAME=FUNCTION(SIGNAL, FROM)        from FROM seconds to the end
    NAME=FUNCTION(SIGNAL, FROM, TO)    from FROM to TO seconds (both included)

FUNCTION is one of FUNCTIONS; SIGNAL a quantity a component records (`first.T`, `idler.v`,
`dancer.y`), as the scene's record names it. The text is read by Python's own parser (`ast`) and
only this shape is accepted: a call of a listed function, a dotted name, one or two numbers.
Nothing is evaluated as Python.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass

import numpy as np

# function -> (what it gives, whether its unit is the signal's (else seconds))
FUNCTIONS = {
    "max": ("the largest value", True),
    "min": ("the smallest value", True),
    "mean": ("the mean over the communication points", True),
    "rms": ("the root mean square", True),
    "std": ("the standard deviation", True),
    "start": ("the first value", True),
    "end": ("the last value", True),
    "argmax": ("the time of the largest value (the first, if several)", False),
    "argmin": ("the time of the smallest value (the first, if several)", False),
}


class MetricError(ValueError):
    """A --metric that cannot be read or evaluated; the message names it."""


@dataclass(frozen=True)
class Metric:
    name: str
    function: str
    signal: str  # "component.quantity"
    start: float | None
    stop: float | None
    unit: str  # the column's: the signal's, or "s"
    spec: str

    @property
    def column(self) -> str:
        return f"{self.name} [{self.unit}]"

    def value(self, column, time) -> float:
        """The metric of a run: `column("first.T")` a recorded signal, `time` its times."""
        x = np.asarray(column(self.signal), dtype=float)
        t = np.asarray(time, dtype=float)
        keep = np.ones(len(t), dtype=bool)
        if self.start is not None:
            keep &= t >= self.start
        if self.stop is not None:
            keep &= t <= self.stop
        if not keep.any():
            raise MetricError(f"--metric {self.spec!r}: the window holds no time of the run ({t[0]:g} s to {t[-1]:g} s)")
        x, t = x[keep], t[keep]
        f = self.function
        if f in ("argmax", "argmin"):
            return float(t[np.argmax(x) if f == "argmax" else np.argmin(x)])
        if f == "rms":
            return float(np.sqrt(np.mean(x * x)))
        if f in ("start", "end"):
            return float(x[0] if f == "start" else x[-1])
        return float(getattr(np, f)(x))


def _signal(node) -> str | None:
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name):
        return f"{node.value.id}.{node.attr}"
    return None


def _seconds(node) -> float | None:
    neg = isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub)
    inner = node.operand if neg else node
    if isinstance(inner, ast.Constant) and isinstance(inner.value, (int, float)) and not isinstance(inner.value, bool):
        return -float(inner.value) if neg else float(inner.value)
    return None


def parse_metric(spec: str, scene) -> Metric:
    """"NAME=FUNCTION(SIGNAL[, FROM[, TO]])" -> a Metric, its signal checked against the scene."""
    from .scene import quantity_unit

    usage = "expected NAME=FUNCTION(SIGNAL[, FROM[, TO]]), e.g. \"peak=max(first.T)\" or \"late=mean(idler.v, 2.0)\""
    name, sep, body = spec.partition("=")
    name = name.strip()
    if not sep or not name.isidentifier():
        raise MetricError(f"--metric {spec!r}: {usage}")
    try:
        tree = ast.parse(body.strip(), mode="eval").body
    except SyntaxError:
        raise MetricError(f"--metric {spec!r}: {usage}") from None
    if not (isinstance(tree, ast.Call) and isinstance(tree.func, ast.Name) and not tree.keywords and 1 <= len(tree.args) <= 3):
        raise MetricError(f"--metric {spec!r}: {usage}")
    function = tree.func.id
    if function not in FUNCTIONS:
        raise MetricError(f"--metric {spec!r}: unknown function {function!r} (functions: {', '.join(FUNCTIONS)})")
    signal = _signal(tree.args[0])
    window = [_seconds(a) for a in tree.args[1:]]
    if signal is None or None in window:
        raise MetricError(f"--metric {spec!r}: {usage} (FROM and TO in seconds)")
    component, quantity = signal.split(".")
    try:
        unit = quantity_unit(scene.component(component), quantity)
    except Exception:
        unit = None
    if unit is None:
        raise MetricError(f"--metric {spec!r}: the scene records no {signal!r} (a component's quantity, as in its record)")
    start, stop = (window + [None, None])[:2]
    if start is not None and stop is not None and not start < stop:
        raise MetricError(f"--metric {spec!r}: the window's start {start:g} s must be before its end {stop:g} s")
    return Metric(name, function, signal, start, stop, unit if FUNCTIONS[function][1] else "s", spec)
