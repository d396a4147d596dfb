"""Plane geometry of a drawn line, in metres and degrees: headings, the side a web wraps a roller on,
tangent lines between circles, distances. Pure numbers: no scene, no matplotlib."""

from __future__ import annotations

import math

# The web wraps a roller turning counter-clockwise (+1, the roller's centre on the web's left) or
# clockwise (-1, on its right), as seen with y up.
CCW, CW = 1, -1
SIDE_NAMES = {CCW: "ccw", CW: "cw"}


def direction(heading: float) -> tuple:
    """The unit vector of a heading (degrees from +x, counter-clockwise)."""
    a = math.radians(heading)
    return (math.cos(a), math.sin(a))


def left(heading: float) -> tuple:
    """The unit vector 90 degrees to the left of a heading."""
    a = math.radians(heading)
    return (-math.sin(a), math.cos(a))


def add(p, v, k=1.0) -> tuple:
    return (p[0] + k * v[0], p[1] + k * v[1])


def sub(p, q) -> tuple:
    return (p[0] - q[0], p[1] - q[1])


def dot(u, v) -> float:
    return u[0] * v[0] + u[1] * v[1]


def cross(u, v) -> float:
    return u[0] * v[1] - u[1] * v[0]


def norm(v) -> float:
    return math.hypot(v[0], v[1])


def heading_of(v) -> float:
    return math.degrees(math.atan2(v[1], v[0]))


def turn(h_from: float, h_to: float) -> float:
    """The signed turn from one heading to another, in (-180, 180] degrees (+: counter-clockwise)."""
    t = math.fmod(h_to - h_from, 360.0)
    t = t + 360.0 if t <= -180.0 else t - 360.0 if t > 180.0 else t
    return t


def wrap_angle(h_in: float, h_out: float, side: int) -> float:
    """The angle the web wraps a roller turning `side` from heading h_in to h_out, in [0, 360): the
    arc between its tangent points, which is the turn of its heading."""
    return math.fmod(side * (h_out - h_in), 360.0) % 360.0


def angle_apart(a: float, b: float) -> float:
    """How far apart two angles are, in [0, 180] degrees."""
    return abs(turn(a, b))


def tangent_heading(c1, r1, s1, c2, r2, s2):
    """The heading of the web leaving circle 1 (side s1) for circle 2 (side s2) on their common
    tangent: the external tangent for equal sides, the crossed one otherwise; None where there is none
    (the circles too close for the web to pass)."""
    d = sub(c2, c1)
    dist = norm(d)
    k = (s1 * r1 - s2 * r2) / dist if dist > 0 else math.inf
    if abs(k) > 1.0:
        return None
    return heading_of(d) + math.degrees(math.asin(k))


def contact(centre, radius: float, side: int, heading: float) -> tuple:
    """Where a web running at `heading` touches a circle it wraps turning `side`."""
    return add(centre, left(heading), -side * radius)


def segment_distance(p, a, b) -> float:
    """The distance of point p from the segment a-b."""
    ab = sub(b, a)
    n2 = dot(ab, ab)
    t = 0.0 if n2 == 0 else max(0.0, min(1.0, dot(sub(p, a), ab) / n2))
    return norm(sub(p, add(a, ab, t)))


def segments_cross(a, b, c, d) -> bool:
    """Whether segments a-b and c-d cross at a point inside both (touching ends do not count)."""
    d1, d2 = cross(sub(b, a), sub(c, a)), cross(sub(b, a), sub(d, a))
    d3, d4 = cross(sub(d, c), sub(a, c)), cross(sub(d, c), sub(b, c))
    return d1 * d2 < 0 and d3 * d4 < 0
