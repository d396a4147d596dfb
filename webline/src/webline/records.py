"""Web records by name: the Python side's one reader of the record format the
span FMU reads with serde_json (its resources/webs.json, and a user's file
named by the parameter webLibrary).

A file is {"description": ..., "webs": [record, ...]}; a record has "name",
"description", "E" (Pa) or "stress_strain" ([[strain, stress in Pa], ...]),
"thickness", "width", "density", "d_r" and optionally "source". The FMU
checks every rule and reports it; this reader refuses what it cannot use
(unknown or missing fields, duplicate names) so that a scene fails early,
and builds the curve the line reference evaluates.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.interpolate import PchipInterpolator
from scipy.optimize import brentq

REQUIRED = ("name", "description", "thickness", "width", "density", "d_r")
OPTIONAL = ("E", "stress_strain", "source")
SHIPPED = "resources/webs.json"


class RecordError(ValueError):
    """A record file or name that cannot be used; the message names it."""


class Curve:
    """sigma(eps) of a stress-strain table: SciPy's PCHIP between the nodes,
    the end tangents beyond them (as the FMU evaluates it)."""

    def __init__(self, points):
        pts = np.asarray(points, dtype=float)
        self.strain, self.stress = pts[:, 0], pts[:, 1]
        self.pchip = PchipInterpolator(self.strain, self.stress, extrapolate=True)
        self.slope = self.pchip.derivative()
        self.steepest_chord = float(np.max(np.diff(self.stress) / np.diff(self.strain)))

    def _ends(self, eps):
        lo, hi = self.strain[0], self.strain[-1]
        below, above = eps <= lo, eps >= hi
        return lo, hi, below, above

    def sigma(self, eps):
        eps = np.asarray(eps, dtype=float)
        lo, hi, below, above = self._ends(eps)
        inside = self.pchip(np.clip(eps, lo, hi))
        return np.where(below, self.stress[0] + self.slope(lo) * (eps - lo),
                        np.where(above, self.stress[-1] + self.slope(hi) * (eps - hi), inside))

    def tangent(self, eps):
        eps = np.asarray(eps, dtype=float)
        lo, hi, below, above = self._ends(eps)
        return np.where(below, self.slope(lo), np.where(above, self.slope(hi), self.slope(np.clip(eps, lo, hi))))

    def strain_at_stress(self, stress: float) -> float:
        """The strain at `stress` (Pa): sigma is non-decreasing and linear beyond the table, so a bracket
        of strains from -0.5 to 1 holds it, and Brent's method finds it to the last bits."""
        return brentq(lambda e: float(self.sigma(e)) - stress, -0.5, 1.0, xtol=1e-16, rtol=4 * np.finfo(float).eps)


@dataclass(frozen=True)
class Record:
    name: str
    E: float  # Pa; a table's steepest chord, which the FMU reports as wpN.E
    thickness: float
    width: float
    density: float
    d_r: float
    table: tuple | None = None  # ((strain, stress), ...)

    def curve(self) -> Curve | None:
        return Curve(self.table) if self.table else None


def parse_library(text: str, source: str) -> dict[str, Record]:
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise RecordError(f"{source}: line {e.lineno} column {e.colno}: {e.msg}") from None
    if not isinstance(data, dict) or set(data) - {"description", "webs"} or not isinstance(data.get("webs"), list):
        raise RecordError(f'{source}: a web library is an object {{"description": ..., "webs": [...]}}')
    records: dict[str, Record] = {}
    for i, r in enumerate(data["webs"]):
        what = f"{source}: webs[{i}]"
        if not isinstance(r, dict):
            raise RecordError(f"{what} is not an object")
        what = f'{source}: record "{r.get("name", i)}"'
        unknown = set(r) - set(REQUIRED) - set(OPTIONAL)
        missing = [k for k in REQUIRED if k not in r]
        if unknown or missing:
            raise RecordError(f"{what}: unknown fields {sorted(unknown)}, missing fields {missing}")
        if ("E" in r) == ("stress_strain" in r):
            raise RecordError(f"{what}: give E or stress_strain, one of them")
        if r["name"] in records:
            raise RecordError(f"{what}: the name is used twice in this file")
        table = tuple(tuple(map(float, p)) for p in r["stress_strain"]) if "stress_strain" in r else None
        E = float(r["E"]) if table is None else Curve(table).steepest_chord
        records[r["name"]] = Record(r["name"], E, *(float(r[k]) for k in ("thickness", "width", "density", "d_r")), table)
    return records


def read_library(path) -> dict[str, Record]:
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise RecordError(f"{path}: cannot read the web library: {e.strerror}") from None
    return parse_library(text, str(path))


def shipped_library(span_fmu) -> dict[str, Record]:
    """The records the span FMU ships in its resources/webs.json."""
    with zipfile.ZipFile(span_fmu) as z:
        return parse_library(z.read(SHIPPED).decode("utf-8"), f"{span_fmu}:{SHIPPED}")


def find(name: str, user_library, span_fmu) -> Record:
    """The record `name`: from the user's file first, then the shipped ones."""
    searched = []
    if user_library:
        records = read_library(user_library)
        if name in records:
            return records[name]
        searched.append(str(user_library))
    shipped = shipped_library(span_fmu)
    if name in shipped:
        return shipped[name]
    searched.append(f"{span_fmu}:{SHIPPED}")
    raise RecordError(f"no web record {name!r} in {' or '.join(searched)}")
