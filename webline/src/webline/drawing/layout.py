"""Where a scene's line is drawn, in metres: each part's centre and radius, each span's two tangent
points, each wrap. Pure geometry (no matplotlib): render.py draws what this places, and
`layout_dict` is the NAME.layout.json `webline draw` writes (its schema: docs/scenes.md, "Drawing a
line").

A scene whose parts all carry "at" is drawn where it puts them: the spans are the tangents that match
the web's side on each roller, and a wrap those positions do not give is refused by name. Otherwise the
layout is automatic, left to right: each span is drawn at its length L (a dancer's legs at its
y_start), each wrap the scene states is kept, and the rest turn the web into a serpentine of spans
alternately ZIGZAG degrees down and up, the side of each wrap chosen so that no roller overlaps another
and no span runs through a roller (tried in order over SEARCH; refused where none fits)."""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field

from ..scene import Dancer, SceneError
from .checking import WRAP_TOLERANCE, overlaps, radius_of
from .geometry import (
    CCW, CW, SIDE_NAMES, add, angle_apart, contact, cross, direction, left, norm, segments_cross, sub, tangent_heading,
    turn, wrap_angle,
)

ZIGZAG = (20.0, 30.0, 10.0, 45.0)  # degrees: a free span's heading below or above the horizontal, tried in order
FANS = (60.0, 90.0, 40.0, 120.0)  # degrees: a side path's span off the main line's at its nip or slitter
FLIP_ALL = 5  # up to this many parts whose side is a choice, every combination of them is tried
ROOM = 0.1  # m: the gap an automatic layout leaves between parts where it can
LENGTH_TOLERANCE = 0.01  # a span drawn at its positions this much longer or shorter than its L is warned of


class DrawError(SceneError):
    """A line that cannot be drawn as its scene says: positions that contradict a wrap, or no layout."""


@dataclass
class RollerAt:
    name: str
    type: str
    path: str  # "line", "merge into NIP", "split from SLITTER"
    centre: tuple
    radius: float  # 0: a point (a part without a radius in the scene)


@dataclass
class SpanAt:
    name: str
    start: str  # the part the web leaves
    end: str  # the part it arrives at
    path: str
    a: tuple  # where it leaves `start`
    b: tuple  # where it arrives at `end`
    length: float | None  # the scene's L (a dancer's leg: its y_start)
    web: str

    @property
    def drawn(self) -> float:
        return norm(sub(self.b, self.a))


@dataclass
class WrapAt:
    roller: str
    span_in: str
    span_out: str
    side: int  # CCW or CW, as seen with y up
    angle: float  # degrees, [0, 360)
    stated: float | None  # the scene's wrap, degrees (None: the layout's choice)


@dataclass
class Layout:
    scene: str
    placement: str  # "scene" (its "at" positions) or "automatic"
    rollers: list
    spans: list
    wraps: list
    warnings: list = field(default_factory=list)

    def roller(self, name) -> RollerAt:
        return next(r for r in self.rollers if r.name == name)


def layout_dict(layout: Layout) -> dict:
    """The layout as JSON holds it (NAME.layout.json): metres and degrees, y up."""
    return {
        "scene": layout.scene,
        "units": {"length": "m", "angle": "deg"},
        "placement": layout.placement,
        "rollers": [{"name": r.name, "type": r.type, "path": r.path, "centre": list(r.centre), "radius": r.radius}
                    for r in layout.rollers],
        "spans": [{"name": s.name, "from": s.start, "to": s.end, "path": s.path, "a": list(s.a), "b": list(s.b),
                   "length": s.drawn, "L": s.length, "web": s.web} for s in layout.spans],
        "wraps": [{"roller": w.roller, "in": w.span_in, "out": w.span_out, "direction": SIDE_NAMES[w.side],
                   "angle": w.angle, "stated": w.stated} for w in layout.wraps],
    }


@dataclass
class _Path:
    label: str
    nodes: list
    spans: list


def _paths(scene) -> list[_Path]:
    """The main line, then each side path with its nip or slitter: nodes[k] -> spans[k] -> nodes[k+1]."""
    out = [_Path("line", scene.line[0::2], scene.line[1::2])]
    for b in scene.branches:
        node = scene.component(b.node)
        if b.kind == "merge":
            out.append(_Path(f"merge into {node.name}", b.parts[0::2] + [node], b.parts[1::2]))
        else:
            out.append(_Path(f"split from {node.name}", [node] + b.parts[1::2], b.parts[0::2]))
    return out


def _length(scene, span) -> float:
    """A span's length: its L, or the carriage position of the dancer it hangs from."""
    if span.length is not None:
        return span.length
    dancer = next(n for n in (scene.upstream(span), scene.downstream(span)) if isinstance(n, Dancer))
    return dancer.y_start


def lay_out(scene) -> Layout:
    """The layout of a scene's line: at its positions where it gives them, else automatic."""
    if scene.nodes and all(n.at is not None for n in scene.nodes):
        return _Placed(scene).layout()
    return _automatic(scene)


class _Geometry:
    """Centres, the side each roller's web wraps it on, the spans' headings: what both placements fill."""

    def __init__(self, scene):
        self.scene = scene
        self.centre, self.side, self.heading = {}, {}, {}
        self.pair_side = {}  # (roller, span in, span out) -> side, where a point's turn says it

    def r(self, node) -> float:
        return radius_of(node)

    def ends(self, span):
        """Its tangent points: where the web leaves its first roller and arrives at its second."""
        h = self.heading[span.name]
        up, down = self.scene.upstream(span), self.scene.downstream(span)
        return (contact(self.centre[up.name], self.r(up), self.side[up.name], h),
                contact(self.centre[down.name], self.r(down), self.side[down.name], h))

    def wrap_side(self, node, a, b) -> int:
        """The side of the wrap from span a to span b: a roller's own; a point's, as its turn goes."""
        if self.r(node) > 0:
            return self.side[node.name]
        key = (node.name, a.name, b.name)
        if key in self.pair_side:
            return self.pair_side[key]
        return CCW if turn(self.heading[a.name], self.heading[b.name]) >= 0 else CW

    def wrap(self, node, a, b) -> float:
        return wrap_angle(self.heading[a.name], self.heading[b.name], self.wrap_side(node, a, b))

    def layout(self, placement, warnings=()) -> Layout:
        scene = self.scene
        where = {c.name: p.label for p in _paths(scene) for c in p.nodes[1:-1] + p.spans}
        where.update({c.name: "line" for c in scene.line})
        for p in _paths(scene):
            where.setdefault(p.nodes[0].name, p.label)
            where.setdefault(p.nodes[-1].name, p.label)
        rollers = [RollerAt(n.name, n.type, where[n.name], tuple(self.centre[n.name]), self.r(n)) for n in scene.nodes]
        spans = []
        for sp in scene.spans:
            a, b = self.ends(sp)
            web = sp.wp2.name if sp.wp1 is sp.wp2 else f"{sp.wp1.name} > {sp.wp2.name}"
            spans.append(SpanAt(sp.name, scene.upstream(sp).name, scene.downstream(sp).name, where[sp.name], a, b,
                                _length(scene, sp), web))
        wraps = []
        for n in scene.nodes:
            ins, outs = scene.spans_in(n), scene.spans_out(n)
            for i, a in enumerate(ins):
                for j, b in enumerate(outs):
                    stated = getattr(n, "wrap", None) if i == j == 0 else None
                    wraps.append(WrapAt(n.name, a.name, b.name, self.wrap_side(n, a, b), self.wrap(n, a, b), stated))
        return Layout(scene.name, placement, rollers, spans, wraps, list(warnings))


# ------------------------------------------------------------------ automatic


@dataclass(frozen=True)
class _Choice:
    """One try of the automatic layout: the serpentine's angle and sense, the side paths' fan, and the
    parts whose preferred side is flipped."""

    zigzag: float
    fan: float
    down_first: bool = True
    fan_flipped: bool = False
    flipped: frozenset = frozenset()


def _choices(scene):
    # The parts whose side is a choice: a stated wrap (which way it turns), a line's ends (which side of
    # the roll the web runs on).
    free = [n.name for n in scene.nodes if getattr(n, "wrap", None) is not None or not scene.spans_in(n)
            or not scene.spans_out(n)]
    if len(free) <= FLIP_ALL:  # every set of them, the smaller first
        flips = [frozenset(c) for k in range(len(free) + 1) for c in itertools.combinations(free, k)]
    else:
        flips = [frozenset()] + [frozenset([n]) for n in free] + [frozenset(free)]
    for flipped, zigzag, fan, down, fan_flipped in itertools.product(flips, ZIGZAG, FANS, (True, False), (False, True)):
        yield _Choice(zigzag, fan, down, fan_flipped, flipped)


def _automatic(scene) -> Layout:
    """The first try that leaves ROOM between parts and crosses no webs; else the first that just
    leaves CLEARANCE and crosses none; else the first that leaves CLEARANCE (its crossing webs warned
    of); else refused with what overlaps."""
    fits, first = [None, None], None
    for choice in _choices(scene):
        layout = _Chained(scene, choice).layout("automatic")
        d = layout_dict(layout)
        first = first or overlaps(d)
        if overlaps(d):
            continue
        crossed = crossings(d)
        if not crossed and not overlaps(d, ROOM):
            return layout
        tier = 1 if crossed else 0
        if fits[tier] is None:
            fits[tier] = layout
            if crossed:
                layout.warnings.append(f"webs cross: {crossed[0]}")
    if fits[0] or fits[1]:
        return fits[0] or fits[1]
    raise DrawError(f"{scene.path}: no layout draws the line without overlap ({first[0]}): give the parts "
                    "positions (\"at\")")


def crossings(layout: dict) -> list[str]:
    """Two spans whose webs cross each other (not at a roller they share)."""
    spans = layout["spans"]
    return [f"spans {p['name']!r} and {q['name']!r}" for i, p in enumerate(spans) for q in spans[i + 1:]
            if segments_cross(p["a"], p["b"], q["a"], q["b"])]


class _Chained(_Geometry):
    """The automatic layout: the main line from its first part at the origin, each span at its length
    and heading from the part before; side paths from their nip (laid back to front) or slitter."""

    def __init__(self, scene, choice: _Choice):
        super().__init__(scene)
        self.choice = choice
        paths = _paths(scene)
        main = paths[0]
        first = main.nodes[0]
        self.centre[first.name] = (0.0, 0.0)
        self.side[first.name] = self.preferred(first, CW)
        targets = self.targets(main)
        self.chain(main.nodes, main.spans, targets[0], targets, reverse=False)
        fans = {}
        for p in paths[1:]:
            merge = p.label.startswith("merge")
            node = p.nodes[-1] if merge else p.nodes[0]
            k = fans[node.name] = fans.get(node.name, -1) + 1
            h = self.fan(node, k, merge)
            # A side path leans away from the main line, the way its fan left it.
            lean = 1.0 if turn(self.heading[self.scene.spans_out(node)[0].name], h) > 0 else -1.0
            targets = self.targets(p, lean)
            if merge:  # back from the nip: the web reversed, its sides mirrored
                back = [(t + 180.0) % 360.0 for t in reversed(targets)]
                self.chain(p.nodes[::-1], p.spans[::-1], h + 180.0, back, reverse=True)
            else:
                self.chain(p.nodes, p.spans, h, targets, reverse=False)

    def preferred(self, node, side: int) -> int:
        return -side if node.name in self.choice.flipped else side

    def targets(self, path, lean: float | None = None) -> list[float]:
        """The heading each span of a path aims for: a dancer's legs hang down to it and up again (its
        wrap split evenly about the vertical); the others zigzag, or on a side path lean (+1 up, -1 down)."""
        z = self.choice.zigzag if self.choice.down_first else -self.choice.zigzag
        out = []
        for k, sp in enumerate(path.spans):
            up, down = path.nodes[k], path.nodes[k + 1]
            if isinstance(down, Dancer):
                out.append(-90.0 + (180.0 - (down.wrap if down.wrap is not None else 180.0)) / 2)
            elif isinstance(up, Dancer):
                out.append(90.0 - (180.0 - (up.wrap if up.wrap is not None else 180.0)) / 2)
            elif lean is not None:
                out.append(lean * abs(z))
            else:
                out.append(-z if k % 2 == 0 else z)
        return out

    def fan(self, node, k: int, merge: bool) -> float:
        """The heading of side path k's span at its nip (arriving) or slitter (leaving): off the main
        line's by the fan angle, on the other side from the main web's turn there; on a roller with a
        radius, on the side its web wraps."""
        scene = self.scene
        h_in, h_out = self.heading[scene.spans_in(node)[0].name], self.heading[scene.spans_out(node)[0].name]
        angle = self.choice.fan + 30.0 * (k // 2)
        if self.r(node) > 0:
            s = self.side[node.name]
            return h_out - s * angle if merge else h_out + s * angle
        away = -1.0 if turn(h_in, h_out) > 0 else 1.0
        sign = away * (1 if k % 2 == 0 else -1) * (-1 if self.choice.fan_flipped else 1)
        return h_out - sign * angle if merge else h_out + sign * angle

    def turn_at(self, node, h: float, target: float, prev: int):
        """The heading a part turns the web to and the side it wraps on: a stated wrap either way, the
        one nearer the target unless flipped; else straight to the target."""
        w = getattr(node, "wrap", None)
        if w is not None:
            options = sorted((CCW, CW), key=lambda s: (round(angle_apart(h + s * w, target), 9), s == prev))
            s = options[1] if node.name in self.choice.flipped else options[0]
            return h + s * w, s
        t = turn(h, target)
        if abs(t) < 1e-9:
            return h, self.preferred(node, -prev)
        if t == 180.0:  # a dancer's legs: it hangs below, the web going on to the right
            return h + t, self.preferred(node, CCW)
        return h + t, CCW if t > 0 else CW

    def chain(self, nodes, spans, heading: float, targets, reverse: bool):
        """Places nodes[1:] from nodes[0], span by span. Reversed (a merge path, laid from its nip back),
        headings run 180 degrees round and sides are mirrored; `targets` are then the reversed path's."""
        sgn, off = (-1, 180.0) if reverse else (1, 0.0)
        h = heading
        for k, sp in enumerate(spans):
            n0, n1 = nodes[k], nodes[k + 1]
            leave = contact(self.centre[n0.name], self.r(n0), sgn * self.side[n0.name], h)
            arrive = add(leave, direction(h), _length(self.scene, sp))
            self.heading[sp.name] = (h + off) % 360.0
            if k + 1 < len(spans):
                h_next, s1 = self.turn_at(n1, h, targets[k + 1], sgn * self.side[n0.name])
                if self.r(n1) == 0:
                    after = spans[k + 1]
                    pair = (after, sp) if reverse else (sp, after)
                    self.pair_side[(n1.name, pair[0].name, pair[1].name)] = sgn * s1
            else:
                h_next, s1 = h, self.preferred(n1, CW)
            if n1.name not in self.centre:
                self.side[n1.name] = sgn * s1
                self.centre[n1.name] = add(arrive, left(h), s1 * self.r(n1))
            h = h_next


# ------------------------------------------------------------------ placed by the scene


class _Placed(_Geometry):
    """Every part at its "at": each roller's side from the way the line turns there (flipped where the
    scene's wrap asks it), each span the tangent between its rollers on those sides."""

    def __init__(self, scene):
        super().__init__(scene)
        self.centre = {n.name: tuple(n.at) for n in scene.nodes}

    def neighbours(self, node):
        ins, outs = self.scene.spans_in(node), self.scene.spans_out(node)
        return (self.scene.upstream(ins[0]) if ins else None, self.scene.downstream(outs[0]) if outs else None)

    def natural_sides(self, flipped=frozenset()):
        """Each roller on the outside of the line's turn there (`flipped` ones inside); a line's end on its
        neighbour's side."""
        ends = []
        for n in self.scene.nodes:
            before, after = self.neighbours(n)
            if before is None or after is None:
                ends.append((n, before or after))
                continue
            c = cross(sub(self.centre[n.name], self.centre[before.name]), sub(self.centre[after.name], self.centre[n.name]))
            self.side[n.name] = (CCW if c > 0 else CW) * (-1 if n.name in flipped else 1)
        for n, other in ends:  # a line's end runs on the same side as its neighbour: the outer tangent
            self.side[n.name] = self.side[other.name] if self.r(other) > 0 else CW

    def headings(self):
        scene = self.scene
        for sp in scene.spans:
            up, down = scene.upstream(sp), scene.downstream(sp)
            h = tangent_heading(self.centre[up.name], self.r(up), self.side[up.name],
                                self.centre[down.name], self.r(down), self.side[down.name])
            if h is None:
                raise DrawError(f"{scene.path}: span {sp.name!r} cannot run from {up.type} {up.name!r} to {down.type} "
                                f"{down.name!r} at their positions: the rollers are too close for the web to pass between them")
            self.heading[sp.name] = h

    def mismatches(self):
        """The parts whose drawn wrap is not the scene's: (part, stated, drawn)."""
        out = []
        for n in self.scene.nodes:
            ins, outs = self.scene.spans_in(n), self.scene.spans_out(n)
            stated = getattr(n, "wrap", None)
            if stated is None or not ins or not outs:
                continue
            if self.r(n) == 0:  # a point turns either way: the way that gives the wrap, if one does
                for s in (CCW, CW):
                    if abs(math.remainder(wrap_angle(self.heading[ins[0].name], self.heading[outs[0].name], s) - stated,
                                          360.0)) <= WRAP_TOLERANCE:
                        self.pair_side[(n.name, ins[0].name, outs[0].name)] = s
            drawn = self.wrap(n, ins[0], outs[0])
            if abs(math.remainder(drawn - stated, 360.0)) > WRAP_TOLERANCE:
                out.append((n, stated, drawn))
        return out

    def layout(self) -> Layout:
        scene = self.scene
        flipped = frozenset()
        self.natural_sides(flipped)
        self.headings()
        for n, _, _ in self.mismatches():  # a wrap beyond the turn: the web on the roller's other side
            if self.r(n) == 0:
                continue
            count = len(self.mismatches())
            self.natural_sides(flipped ^ {n.name})
            if _tangents_exist(self) and len(self.mismatches()) < count:
                flipped = flipped ^ {n.name}
            self.natural_sides(flipped)
            self.headings()
        wrong = self.mismatches()
        if wrong:
            n, stated, drawn = wrong[0]
            raise DrawError(f"{scene.path}: {n.type} {n.name!r}: the scene states a wrap of {stated:g} deg, its positions "
                            f"give {drawn:.1f} deg")
        warnings = []
        layout = super().layout("scene")
        for s in layout.spans:
            if abs(s.drawn - s.length) > LENGTH_TOLERANCE * s.length:
                warnings.append(f"span {s.name!r} is {s.drawn:.3g} m between its rollers' positions, its L {s.length:g} m")
        problems = overlaps(layout_dict(layout))
        if problems:
            raise DrawError(f"{scene.path}: at their positions, {problems[0]}")
        layout.warnings = warnings
        return layout


def _tangents_exist(placed: _Placed) -> bool:
    try:
        placed.headings()
        return True
    except DrawError:
        return False
