"""Quantities with units in scenes: "1.2 m", "50 um", "4.5 GPa", "300 m/min".

Each unit has a factor to SI and a dimension (exponents of kg, m, s, rad).
A quantity is checked against the dimension the scene key needs; a unit of
another dimension, an unknown unit or a bare number for a dimensional value
is an error that says what was expected.
"""

from __future__ import annotations

import math
import re

# dimension: (kg, m, s, rad)
DIMENSIONLESS = (0, 0, 0, 0)
LENGTH = (0, 1, 0, 0)
TIME = (0, 0, 1, 0)
MASS = (1, 0, 0, 0)
SPEED = (0, 1, -1, 0)
FORCE = (1, 1, -2, 0)
PRESSURE = (1, -1, -2, 0)
DENSITY = (1, -3, 0, 0)
INERTIA = (1, 2, 0, 0)
TORQUE = (1, 2, -2, 0)
ROT_DAMPING = (1, 2, -1, 0)  # N m s
ANGULAR_SPEED = (0, 0, -1, 1)
STIFFNESS = (1, 0, -2, 0)  # N/m
LIN_DAMPING = (1, 0, -1, 0)  # N s/m

DIMENSION_NAMES = {
    DIMENSIONLESS: "dimensionless (a plain number, or %)",
    LENGTH: "a length",
    TIME: "a time",
    MASS: "a mass",
    SPEED: "a speed",
    FORCE: "a force",
    PRESSURE: "a pressure or modulus",
    DENSITY: "a density",
    INERTIA: "a moment of inertia",
    TORQUE: "a torque",
    ROT_DAMPING: "a rotational damping",
    ANGULAR_SPEED: "an angular speed",
    STIFFNESS: "a stiffness (force per length)",
    LIN_DAMPING: "a translational damping (force per speed)",
}

LBF = 4.4482216152605
UNITS = {
    # dimensionless
    "1": (1.0, DIMENSIONLESS),
    "%": (0.01, DIMENSIONLESS),
    # length
    "m": (1.0, LENGTH),
    "mm": (1e-3, LENGTH),
    "cm": (1e-2, LENGTH),
    "um": (1e-6, LENGTH),
    "µm": (1e-6, LENGTH),
    "in": (0.0254, LENGTH),
    "ft": (0.3048, LENGTH),
    # time
    "s": (1.0, TIME),
    "ms": (1e-3, TIME),
    "us": (1e-6, TIME),
    "min": (60.0, TIME),
    # mass
    "kg": (1.0, MASS),
    "g": (1e-3, MASS),
    # speed
    "m/s": (1.0, SPEED),
    "m/min": (1.0 / 60.0, SPEED),
    "mm/s": (1e-3, SPEED),
    "ft/min": (0.3048 / 60.0, SPEED),
    "ft/s": (0.3048, SPEED),
    # force
    "N": (1.0, FORCE),
    "kN": (1e3, FORCE),
    "lbf": (LBF, FORCE),
    "kgf": (9.80665, FORCE),
    # pressure, modulus
    "Pa": (1.0, PRESSURE),
    "kPa": (1e3, PRESSURE),
    "MPa": (1e6, PRESSURE),
    "GPa": (1e9, PRESSURE),
    # density
    "kg/m3": (1.0, DENSITY),
    "g/cm3": (1e3, DENSITY),
    # rotation
    "kg.m2": (1.0, INERTIA),
    "N.m": (1.0, TORQUE),
    "N.m.s": (1.0, ROT_DAMPING),
    "rad/s": (1.0, ANGULAR_SPEED),
    "rpm": (2.0 * math.pi / 60.0, ANGULAR_SPEED),
    # translation
    "N/m": (1.0, STIFFNESS),
    "kN/m": (1e3, STIFFNESS),
    "N.s/m": (1.0, LIN_DAMPING),
}

_QUANTITY = re.compile(r"^\s*([-+]?(?:\d+\.?\d*|\.\d+)(?:[eE][-+]?\d+)?)\s*(\S+)?\s*$")


class UnitError(ValueError):
    """A quantity that cannot be read, or has the wrong unit (message without position)."""


def si_unit(dimension) -> str:
    """The SI unit name of a dimension, for messages."""
    for name, (factor, dim) in UNITS.items():
        if dim == dimension and factor == 1.0:
            return name
    return "?"


def parse_quantity(value, dimension) -> float:
    """`value` (a JSON number or a "number unit" string) in SI, checked against `dimension`."""
    want = DIMENSION_NAMES.get(dimension, str(dimension))
    if isinstance(value, bool) or value is None:
        raise UnitError(f"expected {want}, found {value!r}")
    if isinstance(value, (int, float)):
        if dimension != DIMENSIONLESS:
            raise UnitError(f"{value!r} has no unit; give {want} with a unit, e.g. \"{value} {si_unit(dimension)}\"")
        x = float(value)
    elif isinstance(value, str):
        m = _QUANTITY.match(value)
        if not m:
            raise UnitError(f"{value!r} is not a number followed by a unit, e.g. \"1.5 {si_unit(dimension)}\"")
        number, unit = m.group(1), m.group(2)
        if unit is None:
            if dimension != DIMENSIONLESS:
                raise UnitError(f"{value!r} has no unit; give {want}, e.g. \"{number} {si_unit(dimension)}\"")
            unit = "1"
        if unit not in UNITS:
            raise UnitError(f"unknown unit {unit!r} in {value!r} (known units of {want}: {', '.join(units_of(dimension))})")
        factor, dim = UNITS[unit]
        if dim != dimension:
            raise UnitError(
                f"{value!r} is {DIMENSION_NAMES.get(dim, dim)}, but {want} is needed "
                f"(units: {', '.join(units_of(dimension))})"
            )
        x = float(number) * factor
    else:
        raise UnitError(f"expected {want}, found {type(value).__name__}")
    if not math.isfinite(x):
        raise UnitError(f"{value!r} is not finite")
    return x


def units_of(dimension):
    return [name for name, (_, dim) in UNITS.items() if dim == dimension]


def dimension_of_unit(unit: str):
    """The dimension of a unit named in a model description ("m", "kg.m2", "N.m.s", ...)."""
    if unit in ("", "1"):
        return DIMENSIONLESS
    return UNITS[unit][1]
