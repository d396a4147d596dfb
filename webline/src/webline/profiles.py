"""Input profiles of a scene: constants, steps, ramps, S-curves and tables.

Every profile is piecewise polynomial in time, stored as knots (t, value) in time
order; two knots at the same time make a jump (the later value holds from
that time on: profiles are right-continuous). Between knots a piece is linear,
or quadratic where `curvature` gives it a second derivative (an S-curve's jerk
phases: `curvature[i]` is the piece that ends at knot i). Before the first knot
and after the last the value is constant. The master puts a communication point
on every knot time (`breakpoints`), so that within a communication step a
profile is one piece: its value, slope and average over the step are exact.
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass


@dataclass(frozen=True)
class Profile:
    knots: tuple  # ((t, v), ...), t non-decreasing
    curvature: tuple = ()  # the second derivative of the piece ending at each knot; () all linear

    @staticmethod
    def constant(v: float) -> "Profile":
        return Profile(((0.0, float(v)),))

    def _times(self):
        return [t for t, _ in self.knots]

    def _interpolate(self, t: float, i: int) -> float:
        """The value at t on the piece that ends at knot i (held before the first knot and after the last)."""
        if i == 0:
            return self.knots[0][1]
        if i == len(self.knots):
            return self.knots[-1][1]
        (t0, v0), (t1, v1) = self.knots[i - 1], self.knots[i]
        q = self._curvature(i)
        if q == 0.0:
            return v0 + (v1 - v0) * (t - t0) / (t1 - t0)
        s = t - t0
        return v0 + s * ((v1 - v0) / (t1 - t0) - 0.5 * q * (t1 - t0)) + 0.5 * q * s * s

    def _curvature(self, i: int) -> float:
        return self.curvature[i] if self.curvature else 0.0

    def _slope_on(self, i: int, t: float) -> float:
        """The slope at t on the piece that ends at knot i (0 outside the knots)."""
        if i == 0 or i == len(self.knots):
            return 0.0
        (t0, v0), (t1, v1) = self.knots[i - 1], self.knots[i]
        return (v1 - v0) / (t1 - t0) + self._curvature(i) * ((t - t0) - 0.5 * (t1 - t0))

    def value(self, t: float) -> float:
        """The value at t (the value after a jump at t)."""
        return self._interpolate(t, bisect.bisect_right(self._times(), t))

    def value_left(self, t: float) -> float:
        """The limit from the left at t (the value before a jump at t)."""
        return self._interpolate(t, bisect.bisect_left(self._times(), t))

    def slope(self, t: float) -> float:
        """The derivative just after t."""
        return self._slope_on(bisect.bisect_right(self._times(), t), t)

    def slope_left(self, t: float) -> float:
        """The derivative just before t."""
        return self._slope_on(bisect.bisect_left(self._times(), t), t)

    def average(self, t0: float, t1: float) -> float:
        """The mean over [t0, t1], exact (Simpson's rule, exact on each linear or quadratic piece
        between the knots inside)."""
        if t1 <= t0:
            return self.value(t0)
        inner = [t for t in self._times() if t0 < t < t1]
        points = [t0] + inner + [t1]
        total = 0.0
        for a, b in zip(points[:-1], points[1:]):
            middle = self._interpolate(0.5 * (a + b), bisect.bisect_right(self._times(), a))
            total += (self.value(a) + 4.0 * middle + self.value_left(b)) * (b - a) / 6.0
        return total / (t1 - t0)

    def breakpoints(self):
        return sorted(set(self._times())) if len(self.knots) > 1 else []

    def scaled(self, k: float) -> "Profile":
        return Profile(tuple((t, k * v) for t, v in self.knots), tuple(k * q for q in self.curvature))

    def shifted(self, c: float) -> "Profile":
        return Profile(tuple((t, v + c) for t, v in self.knots), self.curvature)

    def is_constant(self) -> bool:
        return len({v for _, v in self.knots}) == 1 and not self.is_curved()

    def is_curved(self) -> bool:
        return any(q != 0.0 for q in self.curvature)

    @staticmethod
    def scurve(start: float, source: float, target: float, jerk: float | None, duration: float | None) -> "Profile":
        """A jerk-limited ramp from `source` to `target` starting at `start`: the acceleration rises at
        `jerk` for tau, holds for duration - 2 tau and falls at `jerk` for tau, with
        jerk tau (duration - tau) = |target - source|. Given the jerk alone, the shortest ramp
        (tau = duration/2 = sqrt(|change|/jerk)); the duration alone, the least jerk (4 |change|/duration^2);
        both, tau from the quadratic above, which needs duration >= 2 sqrt(|change|/jerk) (ScurveError
        otherwise, with the numbers)."""
        change = target - source
        if change == 0.0:
            return Profile(((start, source),))
        if duration is None:
            duration = 2.0 * math.sqrt(abs(change) / jerk)
        if jerk is None:
            jerk = 4.0 * abs(change) / duration**2
        least = 2.0 * math.sqrt(abs(change) / jerk)
        if duration < least * (1.0 - 1e-12):
            raise ScurveError(f"a jerk of {jerk:g} per s^2 takes at least {least:g} s from {source:g} to {target:g}, "
                              f"longer than the duration {duration:g} s: give a longer duration or a higher jerk "
                              f"(at least {4.0 * abs(change) / duration**2:g})")
        tau = 0.5 * (duration - math.sqrt(max(duration**2 - 4.0 * abs(change) / jerk, 0.0)))
        q = math.copysign(jerk, change)
        rise, end = start + tau, start + duration
        if duration - 2.0 * tau <= 1e-12 * duration:  # no constant acceleration: two jerk phases
            middle = 0.5 * (source + target)
            return Profile(((start, source), (start + 0.5 * duration, middle), (end, target)), (0.0, q, -q))
        held = end - tau
        return Profile(((start, source), (rise, source + 0.5 * q * tau**2), (held, target - 0.5 * q * tau**2), (end, target)),
                       (0.0, q, 0.0, -q))


class ScurveError(ValueError):
    """An S-curve whose jerk, duration and change do not fit together."""
