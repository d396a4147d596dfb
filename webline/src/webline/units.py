"""Quantities with units in scenes: "1.2 m", "50 um", "4.5 GPa", "300 m/min".

Pint knows what the units mean (factors and dimensions); this module only
says which quantity a scene key needs (a `Kind`) and which spellings a scene
may use for it, so that a scene stays strict: a unit of another kind, a unit
outside the list (even one Pint knows, such as furlong) or a bare number for
a dimensional value is an error that says what was expected. Products are
written as in FMI model descriptions: "kg.m2", "N.m.s", "kg/m3".
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from functools import lru_cache


@dataclass(frozen=True)
class Kind:
    """A kind of quantity: its name in messages, its SI unit and the units a scene may give."""

    name: str
    si: str
    units: tuple


DIMENSIONLESS = Kind("dimensionless (a plain number, or %)", "1", ("1", "%"))
LENGTH = Kind("a length", "m", ("m", "mm", "cm", "um", "µm", "nm", "in", "ft"))
TIME = Kind("a time", "s", ("s", "ms", "us", "min"))
MASS = Kind("a mass", "kg", ("kg", "g"))
SPEED = Kind("a speed", "m/s", ("m/s", "m/min", "mm/s", "ft/min", "ft/s"))
FORCE = Kind("a force", "N", ("N", "kN", "lbf", "kgf"))
PRESSURE = Kind("a pressure or modulus", "Pa", ("Pa", "kPa", "MPa", "GPa"))
DENSITY = Kind("a density", "kg/m3", ("kg/m3", "g/cm3"))
INERTIA = Kind("a moment of inertia", "kg.m2", ("kg.m2",))
TORQUE = Kind("a torque", "N.m", ("N.m",))
ROT_DAMPING = Kind("a rotational damping", "N.m.s", ("N.m.s",))
ANGULAR_SPEED = Kind("an angular speed", "rad/s", ("rad/s", "rpm"))
STIFFNESS = Kind("a stiffness (force per length)", "N/m", ("N/m", "kN/m"))
LIN_DAMPING = Kind("a translational damping (force per speed)", "N.s/m", ("N.s/m",))
ANGLE = Kind("an angle", "deg", ("deg", "rad"))
AREAL_DENSITY = Kind("a mass per area (a coat weight)", "kg/m2", ("g/m2", "kg/m2"))
VISCOSITY = Kind("a dynamic viscosity", "Pa.s", ("Pa.s", "mPa.s"))

KINDS = (DIMENSIONLESS, LENGTH, TIME, MASS, SPEED, FORCE, PRESSURE, DENSITY, INERTIA, TORQUE,
         ROT_DAMPING, ANGULAR_SPEED, STIFFNESS, LIN_DAMPING, ANGLE, AREAL_DENSITY, VISCOSITY)
KIND_OF_UNIT = {unit: kind for kind in KINDS for unit in kind.units}

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S+)?\s*$")


class UnitError(ValueError):
    """A quantity that cannot be read, or has the wrong unit (message without position)."""


def _fmi_spelling(text: str) -> str:
    """"kg.m2" -> "kg*m**2": FMI's product dot and exponent digits, in Pint's syntax."""
    return re.sub(r"(?<=[A-Za-zµ])(\d+)", r"**\1", text.replace(".", "*"))


@lru_cache(maxsize=1)
def registry():
    import pint

    return pint.UnitRegistry(preprocessors=[_fmi_spelling])


@lru_cache(maxsize=None)
def factor(unit: str, kind: Kind) -> float:
    """The factor from `unit` to the SI unit of `kind` (Pint checks the dimensions agree)."""
    ureg = registry()
    name = {"%": "percent", "1": "dimensionless"}
    return float(ureg.Quantity(1.0, name.get(unit, unit)).to(name.get(kind.si, kind.si)).magnitude)


def parse_quantity(value, kind: Kind) -> float:
    """`value` (a JSON number or a "number unit" string) in SI, checked against `kind`."""
    want = kind.name
    if isinstance(value, bool) or value is None:
        raise UnitError(f"expected {want}, found {value!r}")
    if isinstance(value, (int, float)):
        if kind is not DIMENSIONLESS:
            raise UnitError(f"{value!r} has no unit; give {want} with a unit, e.g. \"{value} {kind.si}\"")
        x = float(value)
    elif isinstance(value, str):
        m = _QUANTITY.match(value)
        if not m:
            raise UnitError(f"{value!r} is not a number followed by a unit, e.g. \"1.5 {kind.si}\"")
        number, unit = m.group(1), m.group(2)
        if unit is None:
            if kind is not DIMENSIONLESS:
                raise UnitError(f"{value!r} has no unit; give {want}, e.g. \"{number} {kind.si}\"")
            unit = "1"
        if unit not in KIND_OF_UNIT:
            raise UnitError(f"unknown unit {unit!r} in {value!r} (known units of {want}: {', '.join(kind.units)})")
        if KIND_OF_UNIT[unit] is not kind:
            raise UnitError(
                f"{value!r} is {KIND_OF_UNIT[unit].name}, but {want} is needed (units: {', '.join(kind.units)})"
            )
        x = float(number) * factor(unit, kind)
    else:
        raise UnitError(f"expected {want}, found {type(value).__name__}")
    if not math.isfinite(x):
        raise UnitError(f"{value!r} is not finite")
    return x
