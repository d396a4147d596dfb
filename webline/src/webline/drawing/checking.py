"""A drawing checked from its layout (the dict of `layout_dict`, or its NAME.layout.json read back)
against its scene: the radii are the scene's; each span's tangent points lie on its rollers' circles,
the span perpendicular to the radius there and the web on the side its wrap turns; the wrap angles are
the scene's; no two rollers' circles intersect and no span crosses a roller other than its own two.
`check_layout` answers with the problems found, none for a good drawing."""

from __future__ import annotations

import math

from .geometry import CCW, CW, add, dot, heading_of, left, norm, segment_distance, sub, wrap_angle

ON_CIRCLE = 1e-6  # m: a tangent point's distance from its circle
PERPENDICULAR = 1e-6  # rad: a span's angle off the normal to the radius at its tangent point
WRAP_TOLERANCE = 0.5  # degrees: a drawn wrap against the scene's (the scene's to 1 degree)
CLEARANCE = 1e-3  # m: the least gap between two rollers, and between a span and a roller not its own
SIDES = {"ccw": CCW, "cw": CW}


def radius_of(node) -> float:
    """A part's radius in the scene; 0 for one without (a source, a sink, a speed-driven roller), drawn
    as a point."""
    return float(getattr(node, "R", None) or 0.0)


def check_layout(layout: dict, scene, clearance: float = CLEARANCE) -> list[str]:
    """The problems of a drawing's layout against its scene, each a line naming the part; [] when none."""
    rollers = {r["name"]: r for r in layout["rollers"]}
    spans = {s["name"]: s for s in layout["spans"]}
    missing = [f"{c.type} {c.name!r} is not drawn" for c in scene.nodes + scene.spans
               if c.name not in (spans if c.type == "span" else rollers)]
    if missing:
        return missing
    problems = []
    for node in scene.nodes:
        r = rollers[node.name]
        if abs(r["radius"] - radius_of(node)) > 1e-12:
            problems.append(f"{node.type} {node.name!r}: radius {r['radius']:g} m drawn, the scene's is {radius_of(node):g} m")
    for sp in scene.spans:
        s = spans[sp.name]
        ends = (scene.upstream(sp).name, scene.downstream(sp).name)
        if (s["from"], s["to"]) != ends:
            problems.append(f"span {sp.name!r} runs from {s['from']!r} to {s['to']!r}, the scene's from {ends[0]!r} to {ends[1]!r}")
        else:
            problems += _tangent_problems(sp.name, s, rollers)
    problems += _wrap_problems(layout, scene, rollers, spans)
    problems += overlaps(layout, clearance)
    return problems


def _tangent_problems(name, s, rollers) -> list[str]:
    out = []
    a, b = s["a"], s["b"]
    along = sub(b, a)
    if norm(along) == 0.0:
        return [f"span {name!r} has no length"]
    u = (along[0] / norm(along), along[1] / norm(along))
    for point, roller in ((a, rollers[s["from"]]), (b, rollers[s["to"]])):
        radial = sub(point, roller["centre"])
        off = abs(norm(radial) - roller["radius"])
        if off > ON_CIRCLE:
            out.append(f"span {name!r}: its tangent point {point} is {off:.3g} m off the circle of {roller['name']!r}")
        elif roller["radius"] > 0:
            angle = math.asin(min(1.0, abs(dot(u, radial)) / norm(radial)))
            if angle > PERPENDICULAR:
                out.append(f"span {name!r} meets {roller['name']!r} {angle:.3g} rad off the tangent")
    return out


def _wrap_problems(layout, scene, rollers, spans) -> list[str]:
    out = []
    drawn = {}
    for w in layout["wraps"]:
        node = scene.component(w["roller"])
        r = rollers[w["roller"]]
        s_in, s_out = spans[w["in"]], spans[w["out"]]
        h_in, h_out = heading_of(sub(s_in["b"], s_in["a"])), heading_of(sub(s_out["b"], s_out["a"]))
        side = SIDES[w["direction"]]
        for point, h, which in ((s_in["b"], h_in, "arrives"), (s_out["a"], h_out, "leaves")):
            # The centre lies on the side the web turns to: it is the tangent that matches the wrap.
            if norm(sub(add(point, left(h), side * r["radius"]), r["centre"])) > ON_CIRCLE:
                out.append(f"{node.type} {node.name!r}: the web {which} on the side opposite its {w['direction']} wrap")
        angle = wrap_angle(h_in, h_out, side)
        if abs(math.remainder(angle - w["angle"], 360.0)) > 1e-6:
            out.append(f"{node.type} {node.name!r}: the layout says a wrap of {w['angle']:.6g} deg, its spans make {angle:.6g} deg")
        drawn[(w["roller"], w["in"], w["out"])] = angle
    for node in scene.nodes:
        ins, outs = scene.spans_in(node), scene.spans_out(node)
        for a in ins:
            for b in outs:
                if (node.name, a.name, b.name) not in drawn:
                    out.append(f"{node.type} {node.name!r}: no wrap drawn from span {a.name!r} to span {b.name!r}")
        stated = getattr(node, "wrap", None)
        if stated is not None and ins and outs:  # at a slitter, the wrap of the main line's lane
            angle = drawn.get((node.name, ins[0].name, outs[0].name))
            if angle is not None and abs(math.remainder(angle - stated, 360.0)) > WRAP_TOLERANCE:
                out.append(f"{node.type} {node.name!r}: wrap {angle:.1f} deg drawn, the scene's is {stated:g} deg")
    return out


def overlaps(layout: dict, clearance: float = CLEARANCE) -> list[str]:
    """Two rollers whose circles intersect (closer than `clearance`), a span that runs through a roller
    other than its own two."""
    out = []
    rollers = layout["rollers"]
    for i, p in enumerate(rollers):
        for q in rollers[i + 1:]:
            gap = norm(sub(p["centre"], q["centre"])) - p["radius"] - q["radius"]
            if gap < clearance:
                out.append(f"rollers {p['name']!r} and {q['name']!r} overlap (a gap of {gap:.3g} m)")
    for s in layout["spans"]:
        for p in rollers:
            if p["name"] in (s["from"], s["to"]):
                continue
            gap = segment_distance(p["centre"], s["a"], s["b"]) - p["radius"]
            if gap < clearance:
                out.append(f"span {s['name']!r} runs through roller {p['name']!r} (a gap of {gap:.3g} m)")
    return out
