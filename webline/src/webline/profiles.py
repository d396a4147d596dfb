"""Input profiles of a scene: constants, steps, ramps and tables.

Every profile is piecewise linear in time, stored as knots (t, value) in time
order; two knots at the same time make a jump (the later value holds from
that time on: profiles are right-continuous). Before the first knot and
after the last the value is constant. The master puts a communication point
on every knot time (`breakpoints`), so that within a communication step a
profile is exactly linear: its start value, slope and average over the step
are exact.
"""

from __future__ import annotations

import bisect
from dataclasses import dataclass


@dataclass(frozen=True)
class Profile:
    knots: tuple  # ((t, v), ...), t non-decreasing

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
        return v0 + (v1 - v0) * (t - t0) / (t1 - t0)

    def value(self, t: float) -> float:
        """The value at t (the value after a jump at t)."""
        return self._interpolate(t, bisect.bisect_right(self._times(), t))

    def value_left(self, t: float) -> float:
        """The limit from the left at t (the value before a jump at t)."""
        return self._interpolate(t, bisect.bisect_left(self._times(), t))

    def slope(self, t: float) -> float:
        """The derivative just after t (piecewise constant)."""
        times = self._times()
        i = bisect.bisect_right(times, t)
        if i == 0 or i == len(times):
            return 0.0
        (t0, v0), (t1, v1) = self.knots[i - 1], self.knots[i]
        return (v1 - v0) / (t1 - t0)

    def average(self, t0: float, t1: float) -> float:
        """The mean over [t0, t1], exact (trapezoids between the knots inside)."""
        if t1 <= t0:
            return self.value(t0)
        inner = [t for t in self._times() if t0 < t < t1]
        points = [t0] + inner + [t1]
        total = 0.0
        for a, b in zip(points[:-1], points[1:]):
            total += 0.5 * (self.value(a) + self.value_left(b)) * (b - a)
        return total / (t1 - t0)

    def breakpoints(self):
        return sorted(set(self._times())) if len(self.knots) > 1 else []

    def scaled(self, k: float) -> "Profile":
        return Profile(tuple((t, k * v) for t, v in self.knots))

    def shifted(self, c: float) -> "Profile":
        return Profile(tuple((t, v + c) for t, v in self.knots))

    def is_constant(self) -> bool:
        return len({v for _, v in self.knots}) == 1
