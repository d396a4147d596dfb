"""Never a silent loop: the line's modes at the start of a run and after each `set` event, and those that
grow enough over the rest of the run to matter (the bound past which a run's tensions stop it: `bound`).

A mode lambda = sigma + j omega grows as exp(sigma t); over the time left in the run, t_left, it
matters when it more than doubles: sigma > 0 (beyond what the derivatives resolve) and
sigma * t_left > ln 2. A roll's radius (its own slow drift over the roll's life) is not counted.
"""

from __future__ import annotations

import math

from . import statespace
from .linefmu import LineFmuError

DOUBLING = math.log(2.0)


def grows(m, duration: float) -> bool:
    """Whether mode `m` grows more than twofold over `duration` (s)."""
    sigma = m.eigenvalue.real
    return sigma > m.error and sigma * duration > DOUBLING and not statespace.radius_mode(m)


def describe(m) -> str:
    """A growing mode as the warning names it: its frequencies (4 digits), damping, the states that carry it."""
    sigma = m.eigenvalue.real
    if m.frequency > 0 and m.eigenvalue.imag > m.error:
        what = f"an oscillation at {m.frequency:.4g} Hz (natural frequency {m.natural_frequency:.4g} Hz)"
    else:
        what = "a mode that does not oscillate"
    states = ", ".join(f"{part}.{s}" for part, _, carried in m.parts for s in carried)
    return (f"{what}, damping ratio {m.damping:.3g}, growing as exp({sigma:.4g} t) (doubling every {DOUBLING / sigma:.3g} s); "
            f"the states it moves most: {states}")


def check(scene, fmu_dir=None) -> list[str]:
    """Warnings for the modes that grow over the run: linearized (the Line FMU, `statespace`) at its
    start and right after each `set` event, each over the time left from there."""
    times = sorted({0.0} | {e.time for e in scene.events if 0.0 < e.time < scene.stop_time})
    loops = [c.name for c in scene.nodes if getattr(getattr(c, "drive", None), "loop", None) is not None]
    hint = f"`webline linearize --loop {loops[0]}` gives its margins" if loops else "`webline linearize` lists the modes"
    warnings = []
    for at in times:
        try:
            ss = statespace.linearize(scene, at, fmu_dir)
        except LineFmuError as e:
            return warnings + [f"the line's modes could not be checked for growth at t = {at:g} s ({e})"]
        left = scene.stop_time - at
        for m in ss.modes():
            if grows(m, left):
                where = "at the start" if at == 0.0 else f"after the event at t = {at:g} s"
                warnings.append(f"the line is unstable {where}: {describe(m)}; over the {left:g} s left it grows "
                                f"{math.exp(m.eigenvalue.real * left):.3g} times ({hint}, --at {at:g}s)")
    return warnings
