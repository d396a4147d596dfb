"""The bound past which a run's tensions stop it, in every engine.

A run stops where a span's tension |T| passes BOUND_STRAIN of its web's EA: a strain of 10 %, past
the break of paper and the yield of films, no tension a line holds (a snatch that peaks at 2.7 kN on
a 225 kN PET film is 1.2 %). The Line FMU's run and the reference stop at the step that passes it,
the parts' master at the communication point; an engine webline does not step (libcosim, FMPy's
SSP) is held to it on its recorded tensions when it returns.
"""

from __future__ import annotations

BOUND_STRAIN = 0.1


class Runaway(RuntimeError):
    """A run's tension passed its bound (`tension_bounds`); the message names the span, the time and the value."""


def tension_bounds(scene) -> dict:
    """{span: the tension (N) whose magnitude stops a run}: BOUND_STRAIN of the EA of the stiffest web the
    span carries over the run (its webs and those its events set; a laminate's, its layers' together)."""
    bounds = {}
    for sp in scene.spans:
        webs = [sp.wp1, sp.wp2] + [w for e in scene.events if e.component == sp.name for w in e.changes.values()
                                   if hasattr(w, "EA")]
        bounds[sp.name] = BOUND_STRAIN * max(w.EA for w in webs)
    return bounds


def runaway(scene_name: str, span: str, tension: float, bound: float, t: float) -> Runaway:
    return Runaway(f"{scene_name}: the tension of span {span!r} reached {tension:.4g} N at t = {t:.6g} s, past the bound of "
                   f"{bound:.4g} N ({100 * BOUND_STRAIN:g} % of its web's EA, a strain no line holds): the run stops there "
                   "(a loop that grows? `webline linearize` marks growing modes)")


def check_result(scene, result):
    """A run's recorded tensions against their bounds (`tension_bounds`): the first past one raises Runaway."""
    bounds = tension_bounds(scene)
    for (c, q), column in zip(scene.record, result.columns):
        if q == "T" and c in bounds:
            over = abs(result.column(column)) > bounds[c]
            if over.any():
                k = int(over.argmax())
                raise runaway(scene.name, c, float(result.column(column)[k]), bounds[c], float(result.time[k]))
