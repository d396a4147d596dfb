"""The rules a scene keeps beyond each part's own keys, checked once the line is read: the webs at a
slitter and a nip, a web's layers from span to span, the spans around a roller the web may slip on and
around a dancer, what a drive's loop measures, and the parts' positions. Each refusal names the part and
its position."""

from __future__ import annotations

import math

from .types import LABEL_TAKEN, Branch, Dancer, Scene, Span

# Widths that add up: to this fraction of the web's width (units convert with rounding).
WIDTH_TOLERANCE = 1e-9
# What a slitter's lanes keep of the web they are cut from.
MATERIAL = ("E", "thickness", "density", "d_r")


def check_traction(r, scene: Scene, raw):
    """A roller the web may slip on moves the web on its wrap as a mass [R6]: the mode of that mass
    between the two spans (about a kilohertz for a thin film) is damped by their Kelvin-Voigt damping
    only, so both need includeDamping with a retardation time d_r > 0. Web mass (includeMass) next to
    it is not modelled. A traction's slip_start is a given start's: an equilibrium start solves the web's speed
    over the roller (at zero slip where it sticks), so one given there would be ignored: it is refused."""
    for node in scene.nodes:
        if getattr(node, "traction", None) is None:
            continue
        what = f"{node.type} {node.name!r}"
        if node.traction.slip_start_given and scene.start == "equilibrium":
            raise r.err(raw[node.name], f"{what}: traction: slip_start is the web's slip at a given start; with "
                                        "\"start\": \"equilibrium\" the line starts steady, where the slip is solved (0 where the "
                                        "web sticks), so slip_start would be ignored: remove it, or use \"start\": \"given\"")
        for sp in scene.spans_in(node) + scene.spans_out(node):
            if "includeDamping" not in sp.effects or not sp.wp2.d_r > 0:
                raise r.err(raw[sp.name], f"span {sp.name!r} next to {what}, which has traction, needs the effect includeDamping "
                                          f"and a web with d_r > 0 (its d_r is {sp.wp2.d_r:g} s): the web's mass on the wrap "
                                          "moves between the two spans, and their damping is what damps it")
            if "includeMass" in sp.effects:
                raise r.err(raw[sp.name], f"span {sp.name!r} next to {what}, which has traction: includeMass there is not modelled")


def _downstream_of(scene: Scene, node) -> set:
    """The names of every part the web reaches after `node`."""
    seen, todo = set(), list(scene.spans_out(node))
    while todo:
        sp = todo.pop()
        if sp.name in seen:
            continue
        seen.add(sp.name)
        down = scene.downstream(sp)
        seen.add(down.name)
        todo += scene.spans_out(down)
    return seen


def check_loops(r, scene: Scene, raw):
    """A drive's loop measures a span's tension of this line, or the load cell of a roller with a wrap;
    its sign follows from where that is: downstream of the drive more torque lowers it (-1), upstream it
    raises it (+1) (a load cell's webs both lie on one side of another roller). A feed-forward needs a speed drive whose profile is the line's speed reference."""
    for node in scene.nodes:
        loop = getattr(getattr(node, "drive", None), "loop", None)
        if loop is not None and loop.dancer is not None:
            d = loop.dancer
            c = {c.name: c for c in scene.parts}.get(d.dancer)
            if not isinstance(c, Dancer):
                raise r.err(raw[node.name], f"{node.type} {node.name!r}: drive.dancer.dancer: {d.dancer!r} is "
                                            f"{'no part of the line' if c is None else 'a ' + c.type + ', not a dancer'}")
            d.sign = -1.0 if d.dancer in _downstream_of(scene, node) else 1.0
        if loop is None or loop.speed:
            continue
        what = f"{node.type} {node.name!r}: drive.pi.measure"
        part, quantity = loop.measure
        names = {c.name: c for c in scene.parts}
        c = names.get(part)
        if c is None:
            raise r.err(raw[node.name], f"{what}: no part {part!r} in the line")
        if quantity == "T" and not isinstance(c, Span):
            raise r.err(raw[node.name], f"{what}: {part!r} is a {c.type}, not a span: measure its load cell as \"{part}.F\"")
        if quantity == "F" and (isinstance(c, Span) or not getattr(c, "wrap", None)):
            raise r.err(raw[node.name], f"{what}: {part!r} has no load cell: \"{part}.F\" needs a roller with a wrap > 0 "
                                        "(its \"wrap\", degrees)")
        if quantity == "F" and any("includeMass" in sp.effects for sp in scene.spans_in(c)):
            raise r.err(raw[node.name], f"{what}: a loop on {part!r}'s load cell with includeMass on the span into it is not "
                                        "modelled (the web's mass moves the force the cell reads within the line's solve)")
        if part == node.name:
            raise r.err(raw[node.name], f"{what}: a drive's loop measures another part than its own roller")
        if quantity == "T" and c.layered:
            raise r.err(raw[node.name], f"{what}: a loop on a laminate's tension is not modelled (measure a plain span)")
        loop.sign = -1.0 if part in _downstream_of(scene, node) else 1.0
        if loop.feedforward and scene.speed_reference() is None:
            raise r.err(raw[node.name], f"{node.type} {node.name!r}: drive.pi.feedforward needs the line's speed reference, "
                                        "a speed-driven part (its first)")


def check_split(r, scene: Scene, b: Branch, raw):
    """The lanes of a slitter: the incoming web's material, widths that add up to its width (with the trim)."""
    node = scene.component(b.node)
    (incoming,) = scene.spans_in(node)
    web = incoming.wp2
    lanes = scene.spans_out(node)
    for lane in lanes:
        w = lane.wp1
        differs = [k for k in MATERIAL if not math.isclose(getattr(w, k), getattr(web, k), rel_tol=1e-12, abs_tol=0.0)]
        if differs or w.curve is not web.curve:
            raise r.err(raw[lane.name], f"roller {node.name!r} slits web {web.name!r}, but span {lane.name!r} starts with web "
                        f"{w.name!r}, which differs in {', '.join(differs) or 'its stress-strain table'}: a slitter cuts the web, "
                        "it does not change the material")
        if len(w.plies) != len(web.plies):
            raise r.err(raw[lane.name], f"roller {node.name!r} slits web {web.name!r} of {len(web.plies)} layer(s), but span "
                        f"{lane.name!r} starts with web {w.name!r} of {len(w.plies)}: a lane of a laminate is a slit of it "
                        f"({{\"slit\": {web.name!r}, ...}}), its layers narrowed")
    total = sum(lane.wp1.width for lane in lanes) + node.trim
    if abs(total - web.width) > WIDTH_TOLERANCE * web.width:
        parts = " + ".join(f"{lane.wp1.width:g}" for lane in lanes)
        raise r.err(raw[node.name], f"roller {node.name!r} slits web {web.name!r} ({web.width:g} m wide) into {parts} m "
                    f"with {node.trim:g} m trim = {total:g} m: the lanes and the trim must add up to the web's width")


def check_merge(r, scene: Scene, b: Branch, raw):
    """The span after a nip carries the laminate: one web (not wp1/wp2), made of the webs that meet there."""
    node = scene.component(b.node)
    out = scene.span_after(node)
    if out.wp1 is not out.wp2:
        raise r.err(raw[out.name], f"span {out.name!r} leaves roller {node.name!r}, where webs merge: its web is the laminate; "
                    "give it as \"web\", not wp1 and wp2")
    if node.trim:
        raise r.err(raw[node.name], f"roller {node.name!r} merges webs: trim goes with split")
    if getattr(node, "wrap", None) is not None:
        raise r.err(raw[node.name], f"roller {node.name!r} merges webs, which arrive from different directions: one wrap "
                    "angle cannot place its load cell; put the load cell on a roller before or after the nip")
    layers = out.wp2.layer_names
    meeting = sorted(w.name for sp in scene.spans_in(node) for w in sp.wp2.plies)
    if layers and sorted(layers) != meeting:
        raise r.err(raw[out.name], f"span {out.name!r} carries laminate {out.wp2.name!r} of {', '.join(layers)}, but the webs "
                    f"meeting at {node.name!r} are {', '.join(meeting)}")


def check_layers(r, scene: Scene, raw):
    """A web keeps its layers ([M6]): a span's wp1 and wp2 have as many; at a roller that is not a nip the
    span after it carries as many as the web arriving (layers are bonded at a nip, by a merge); the labels
    of a laminate's layers name outputs of their own."""
    for sp in scene.spans:
        n1, n2 = len(sp.wp1.plies), len(sp.wp2.plies)
        if n1 != n2:
            raise r.err(raw[sp.name], f"span {sp.name!r} converts web {sp.wp1.name!r} of {n1} layer(s) into {sp.wp2.name!r} "
                        f"of {n2}: a span keeps a web's layers (laminate webs at a nip, with a merge)")
        before = scene.spans_in(scene.upstream(sp))
        if len(before) == 1 and len(before[0].wp2.plies) != n1:
            up, p = scene.upstream(sp), before[0]
            raise r.err(raw[sp.name], f"span {sp.name!r} starts with web {sp.wp1.name!r} of {n1} layer(s), but span {p.name!r} "
                        f"brings {len(p.wp2.plies)} ({p.wp2.name!r}) to {up.type} {up.name!r}: a web keeps its layers from "
                        "span to span (laminate webs at a nip, with a merge; give a laminate's measured values as a web of its own)")
        if sp.layered:
            labels = sp.labels
            clash = [x for x in labels if labels.count(x) > 1 or x in LABEL_TAKEN or (x.startswith("T_") and x[2:] in labels)]
            if clash:
                raise r.err(raw[sp.name], f"span {sp.name!r}: the layers of {sp.wp2.name!r} would be labelled {', '.join(labels)}; "
                            f"{clash[0]!r} clashes with another output of the span (NAME.T, NAME.eps, NAME.T_<layer>, ...): "
                            "rename the layer's web")


def check_dancer_spans(r, scene: Scene, raw):
    """Spans next to a dancer take their length from it (variableLength, no L, not solver exact); no
    other span may."""
    for c in scene.spans:
        node = raw[c.name]
        up, down = scene.upstream(c), scene.downstream(c)
        next_to_dancer = isinstance(up, Dancer) or isinstance(down, Dancer)
        if next_to_dancer:
            if "variableLength" not in c.effects:
                raise r.err(node, f"span {c.name!r} hangs from a dancer: it needs the effect variableLength")
            if c.length is not None:
                raise r.err(r.key_pos(node.value["L"]), f"span {c.name!r}: L comes from the dancer's position, do not give it")
            if isinstance(up, Dancer) and isinstance(down, Dancer):
                raise r.err(node, f"span {c.name!r} between two dancers is not supported")
        else:
            if "variableLength" in c.effects:
                raise r.err(node, f"span {c.name!r}: variableLength needs a dancer next to the span")
            if c.length is None:
                raise r.err(node, f"span {c.name!r} needs the key 'L'")
        if c.solver == "exact" and next_to_dancer:
            raise r.err(node, f"span {c.name!r}: solver exact holds the length; a span on a dancer needs auto or rosenbrock")


def check_positions(r, scene: Scene, raw):
    """A scene places every part ("at") or none: between placed parts the lengths L and the wraps would
    over-determine where an unplaced one goes, so `webline draw` lays out all of them or none."""
    nodes = scene.nodes
    placed = [c for c in nodes if c.at is not None]
    if placed and len(placed) < len(nodes):
        missing = next(c for c in nodes if c.at is None)
        raise r.err(raw[missing.name], f"{missing.type} {missing.name!r} has no \"at\" while {placed[0].type} "
                    f"{placed[0].name!r} has one: give every part but the spans a position, or none (webline draw "
                    "then lays the line out)")
