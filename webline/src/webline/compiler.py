"""Scenes compiled into a System, and a scene compiled and run.

Every part of a line becomes an FMU component: a ConvertingSpan per span, a
Roller per everything else (source, sink, driven roller, idler, unwinder,
winder, dancer). What a scene says with profiles and events becomes each
component's profile JSON (tables and timed `set` entries), read by the FMU
itself. The connected inputs start at the outputs that feed them, settled
through the FMUs (`master.settle_start_values`).

Ports (a roller's match a span's): span.web_a.v <- roller.web_b.v,
roller.web_b.F <- span.web_a.F, span.web_b.v <- roller.web_a.v,
roller.web_a.F <- span.web_b.F; the strain goes span to span
(span2.web_a.eps <- span1.web_b.eps), the first span's from the line's
first roller (web_b.eps); spans on a dancer take the height of their moving
end from its tangent points (web_a.y, web_b.y; the x are constants).
A nip where webs merge and a slitter that splits the web use the Roller's
extra ports (web_a2..4, web_b2..4; docs/merge-split.md, "The FMUs' wiring"):
there the strain goes through the roller (web_a<k>.eps in, web_b<j>.eps out). A winder
reads the strain of the web it winds (web_a.eps <- span.web_b.eps): its roll counts the web's
unstretched length [R3].
A span that carries a laminate is a ConvertingSpan per layer, `NAME.<label>`,
side by side between the same rollers, each at a port of its own (the rollers
`layered`: each outlet passes one inlet's strain on, [R6]); a layer takes its
strain from the span that brings its web, as a plain span after a plain roller
does (docs/merge-split.md, [M6]).
"""

from __future__ import annotations

import math
from pathlib import Path

from .bound import tension_bounds
from .fmus import DEFAULT_FMU_DIR, ROLLER_FMU, SPAN_FMU, FmuFile, span_effects
from .master import Master, Options, settle_start_values
from .profiles import Profile
from .result import Result
from .names import ROLLER_VARIABLES, SPAN_VARIABLES
from .scene import BRAKE_V_SLIP, NIP_SIDES, Dancer, Scene, SceneError, Span
from .system import Component, Connection, System

# A roller whose surface speed is prescribed (source, sink, speed drive) needs
# J and R > 0 though its speed ignores them: these only scale omega and tau.
PRESCRIBED_J = 0.01  # kg.m2
PRESCRIBED_R = 0.1  # m
ROLL = {"unwinder": 1, "winder": 2}  # the Roller's Integer `roll`; 0 otherwise
MAX_PORTS = 4  # the Roller's inlets web_a..web_a4 and outlets web_b..web_b4
WEB_FIELDS = ("E", "thickness", "width", "density", "d_r")

def table(profile: Profile):
    """A scene profile as a profile-JSON table [[t, value], ...], [t, value, curvature] where the piece
    ending at a knot is quadratic (an S-curve's jerk phase)."""
    q = profile.curvature or (0.0,) * len(profile.knots)
    return [[float(t), float(v)] + ([float(c)] if c else []) for (t, v), c in zip(profile.knots, q)]


def web_values(side: str, web, web_library=None, clear_record=False) -> dict:
    """A span's parameters for one web ("wp1"/"wp2"): its record's name (the FMU
    reads the record; not for engines that cannot set Strings), or the values one
    by one. `clear_record`: also empty `side.record` (a set event after a record web)."""
    if web.record:
        values = {f"{side}.record": web.record}
        if web_library:
            values["webLibrary"] = web_library
        return values
    values = {f"{side}.{k}": float(getattr(web, k)) for k in WEB_FIELDS}
    if clear_record:
        values[f"{side}.record"] = ""
    return values


def _roller(scene: Scene, node, fmu: Path, positions: dict) -> Component:
    start = {}
    profile = {}
    speed = scene.speed_profile(node)
    traction = getattr(node, "traction", None)
    if speed is not None:
        # With traction or runout the radius counts (the web's mass on the wrap, the air film; where the web touches): the scene's.
        given_radius = traction is not None or getattr(node, "runout", None) is not None
        start.update(J=PRESCRIBED_J, R=float(node.R) if given_radius else PRESCRIBED_R, b=0.0)
        if getattr(getattr(node, "drive", None), "input", False):  # held at loop.speed: the Line FMU's input v_ref
            start.update({"speed.input": True, "loop.speed": float(speed.value(0.0))})
        else:
            profile["speed"] = table(speed)
    else:
        start.update(J=float(node.J), R=float(node.R), b=float(node.b))
    start["v_start"] = float(scene.initial_speed(node))
    if (node.name, "F") in scene.record:  # its load cell recorded: the Roller's load_cell.F at its wrap
        start["load_cell.wrap"] = math.radians(node.wrap)
    if node.type in ROLL:
        start["roll"] = ROLL[node.type]
    wound = getattr(node, "wound", None)
    if wound is not None:
        start.update({"wound.thickness": float(wound.thickness), "wound.density": float(wound.density),
                      "wound.width": float(wound.width)})
        if wound.merge:
            start["wound.merge"] = float(wound.merge)
    start.update(runout_values(scene, node))
    layon = getattr(node, "layon", None)
    if layon is not None:
        start.update(layon_values(layon))
        if not layon.load.is_constant():
            profile["layon"] = table(layon.load)
    drive = getattr(node, "drive", None)
    if drive is not None and drive.kind in ("torque", "tension", "brake"):
        profile[drive.kind] = table(drive.profile)
    if drive is not None and drive.kind == "brake":
        start.update({"brake.v_slip": BRAKE_V_SLIP, "brake.creep": float(drive.creep)})
    if drive is not None and drive.taper:
        start["drive.taper"] = float(drive.taper)
    if drive is not None and drive.loop is not None:
        start.update(loop_values(drive.loop))
        if drive.loop.speed and drive.loop.set_input:  # the Line FMU's input v_ref, starting there
            start["loop.speed"] = float(drive.loop.set.value(0.0))
        elif drive.loop.speed:  # its reference: the speed it holds, and the one it feeds forward
            profile["reference"] = table(drive.loop.set)
        elif drive.loop.feedforward and scene.input_reference() is not None:
            # The Line FMU's input v_ref: loop.speed and loop.acceleration, which the Line sets (line.json's
            # feedforward_from); held at its start elsewhere, as the input is.
            start["loop.speed"] = float(scene.speed_reference().value(0.0))
        elif drive.loop.feedforward:
            profile["reference"] = table(scene.speed_reference())
        if not drive.loop.speed and not drive.loop.set.is_constant():
            profile["setpoint"] = table(drive.loop.set)
    strain = getattr(node, "strain", None)
    if strain is not None:
        if strain.is_constant():
            start["web_a.eps"] = float(strain.value(0.0))  # unconnected: the strain it feeds through
        else:
            profile["strain"] = table(strain)
    if isinstance(node, Dancer):
        # The Roller starts its carriage at carriage.y_start, its spring's rest position. One that starts
        # elsewhere (its steady position) takes that as the rest position and the load less the spring's
        # force there: the same force, load - k*(y - y_start), at every y.
        y0 = positions.get(node.name, node.y_start)
        start.update({
            "carriage": True,
            "carriage.m": float(node.mass),
            "carriage.d": float(node.damping),
            "carriage.k": float(node.stiffness),
            "carriage.y_start": float(y0),
        })
        profile["load"] = table(node.load.shifted(-node.stiffness * (y0 - node.y_start)))
    if traction is not None:
        start.update(traction_values(scene, node))
        if traction.nip_load is not None:
            profile["nip"] = table(traction.nip_load)
            start["nip.side"] = NIP_SIDES.index(traction.nip_side)
    sets = [{"time": float(e.time), **{k: float(v) for k, v in e.changes.items()}} for e in scene.events if e.component == node.name]
    if sets:
        profile["set"] = sets
    return Component(node.name, "roller", fmu, start, profile or None)


def loop_values(loop) -> dict:
    """The Roller's parameters of a drive's loop [R10]-[R11]: a force loop on loop.measured, which the
    line wires from the span it names (`compile_scene`), or a speed loop on its own surface speed."""
    values = {
        "loop.kind": (3 if loop.dancer is not None else 2) if loop.speed else 1,
        "loop.sign": float(loop.dancer.sign if loop.dancer is not None else loop.sign),
        "loop.set": float(loop.set.value(0.0)),
        "loop.kp": float(loop.kp),
        "loop.ki": float(loop.ki),
        "loop.feedforward": bool(loop.feedforward),
        "motor.limit": float(loop.limit),
        "motor.lag": float(loop.lag),
    }
    if loop.compression:  # a set point <= 0 N is meant
        values["loop.compression"] = True
    if loop.sample > 0.0:  # a zero-order hold on the command, each sample applied `delay` later [R14]
        values.update({"loop.sample": float(loop.sample), "loop.delay": float(loop.delay)})
    if loop.dancer is not None:  # a dancer loop [R13] on dancer.y, which the line wires from the dancer
        values.update({"dancer.set": float(loop.dancer.set), "dancer.kp": float(loop.dancer.kp), "dancer.ki": float(loop.dancer.ki)})
    return values


def traction_values(scene: Scene, node) -> dict:
    """The Roller's parameters where the web may slip on it [R6]-[R8]: the web arriving sets the mass
    on the wrap (web_a.m) and the width the air film sees."""
    t = node.traction
    web = scene.span_before(node).wp2
    return {
        "includeTraction": True,
        "traction.mu": float(t.mu),
        "traction.wrap": math.radians(node.wrap or 0.0),
        "traction.v_slip": float(t.v_slip),
        "traction.static": float(t.static),
        "traction.creep": float(t.creep),
        "traction.width": float(web.width),
        "traction.slip_start": float(t.slip_start),
        "web_a.m": float(web.rho_l),
        "nip.mu": float(t.nip_mu),
        "air.roughness": float(t.roughness),
        "air.viscosity": float(t.viscosity),
    }


def runout_span(scene: Scene, node) -> Span:
    """The span whose length a roll's runout moves [R15]: an unwinder's leaving, a winder's arriving."""
    (span,) = scene.spans_out(node) if node.type == "unwinder" else scene.spans_in(node)
    return span


def runout_values(scene: Scene, node) -> dict:
    """A roll's runout [R15] as the Roller takes it: on, its eccentricity, phase, and its span's length."""
    runout = getattr(node, "runout", None)
    if runout is None:
        return {}
    values = {"runout": True, "runout.e": float(runout.eccentricity), "runout.phase": float(runout.phase),
              "runout.L": float(runout_span(scene, node).length)}
    for j, (order, amplitude, phase) in enumerate(runout.harmonics, start=1):
        values.update({f"runout.h{j}.k": order, f"runout.h{j}.a": float(amplitude), f"runout.h{j}.phase": float(phase)})
    return values


def layon_values(layon) -> dict:
    """A winder's lay-on roller [R18] as the Roller takes it; its load `layon.F` where it is constant (else the
    profile's table "layon")."""
    values = {"layon": True, "layon.m": float(layon.mass), "layon.k": float(layon.stiffness), "layon.c": float(layon.damping),
              "layon.r": float(layon.radius), "layon.J": float(layon.inertia), "layon.b": float(layon.bearing),
              "layon.mu": float(layon.mu), "layon.v_slip": float(layon.v_slip), "layon.angle": float(layon.angle)}
    if layon.load.is_constant():
        values["layon.F"] = float(layon.load.value(0.0))
    return values


def _runout_roll(scene: Scene, span: Span):
    """The roll with runout at an end of `span` whose tangent point moves its length [R15], or None."""
    up, down = scene.upstream(span), scene.downstream(span)
    if getattr(up, "runout", None) is not None and up.type == "unwinder":
        return up
    if getattr(down, "runout", None) is not None and down.type == "winder":
        return down
    return None


def _dancer_of(scene: Scene, span: Span):
    up, down = scene.upstream(span), scene.downstream(span)
    return up if isinstance(up, Dancer) else down if isinstance(down, Dancer) else None


def layer_parts(span: Span) -> list[str]:
    """The components of a span: itself, or one per layer of a laminate, `NAME.<label>` ([M6])."""
    return [f"{span.name}.{label}" for label in span.labels] if span.layered else [span.name]


def _span(scene: Scene, span: Span, eps: float, fmu: Path, solvers: dict, effects: tuple, positions: dict,
          layer: int = 0) -> Component:
    """The ConvertingSpan of a span, or of its layer `layer` (a laminate's: that layer's webs)."""
    dancer = _dancer_of(scene, span)
    y0 = positions.get(dancer.name, dancer.y_start) if dancer is not None else None  # the carriage's start
    lib = scene.web_library
    wp1, wp2 = span.wp1.plies[layer], span.wp2.plies[layer]
    start = {
        "L": float(span.length if span.length is not None else y0),
        **web_values("wp1", wp1, lib),
        **web_values("wp2", wp2, lib),
        **{e: e in span.effects for e in effects},
        # The start strain is given, not the FMU's equilibrium of its first inputs
        # (FMPy's first inputs are all 0.0): every engine starts the same.
        "startAtEquilibrium": False,
    }
    start["eps_start"] = float(eps)
    if span.solver != "auto":  # an Enumeration: left at its default unless asked (libcosim ignores them)
        start["solver"] = solvers[span.solver]
    if span.tolerance is not None:
        start["tolerance"] = float(span.tolerance)
    if span.substeps is not None:
        start["substeps"] = int(span.substeps)
    if dancer is not None:
        # The span's fixed end, y_start above the dancer's start position (the
        # Roller's contact points are measured from there, up positive).
        # The x of the moving end is a constant too, so not connected: an engine
        # that starts its inputs at 0 (FMPy) then sees the right geometry.
        if scene.downstream(span) is dancer:
            start.update({"frame_a.x": 0.0, "frame_a.y": float(y0), "frame_b.x": 0.0})
        else:
            start.update({"frame_b.x": 2.0 * float(dancer.R), "frame_b.y": float(y0),
                          "frame_a.x": 2.0 * float(dancer.R)})
    if _runout_roll(scene, span) is not None:
        # Its length the tangent point's on the roll [R15]: along a line from frame_a (0, 0) to frame_b
        # (0, L), the roll's end connected (an unwinder's web_b.y = L - L(angle), a winder's web_a.y = L(angle)).
        start.update({"variableLength": True, "frame_a.x": 0.0, "frame_a.y": 0.0, "frame_b.x": 0.0, "frame_b.y": float(span.length)})
    sets = []
    webs = {"wp1": wp1, "wp2": wp2}
    for e in scene.events:
        if e.component != span.name:
            continue
        changes = dict(e.changes)
        if "web" in changes:
            changes["wp1"] = changes["wp2"] = changes.pop("web")
        entry = {"time": float(e.time)}
        for side, web in changes.items():
            web = web.plies[layer]  # a laminate's layer changes to the new web's (scene: as many layers)
            entry.update(web_values(side, web, lib, clear_record=bool(webs[side].record)))
            webs[side] = web
        sets.append(entry)
    return Component(layer_parts(span)[layer], "span", fmu, start, {"set": sets} if sets else None)


def _record_variable(scene: Scene, cname: str, quantity: str) -> str:
    c = scene.component(cname)
    if isinstance(c, Span):
        return SPAN_VARIABLES[quantity]
    return ROLLER_VARIABLES[quantity]


def _record(scene: Scene) -> tuple[list, list | None]:
    """The variables the System records for the scene's columns, and how they make the columns
    (`System.sums`; None where each column is one variable). A laminate's column is made of its layers'
    ([M6]): T, F_a and F_b their sums, eps their strains weighted by E*A, L the first's, T_<label> one
    layer's tension."""
    if not any(isinstance(scene.component(c), Span) and scene.component(c).layered for c, _ in scene.record):
        return [(c, _record_variable(scene, c, q)) for c, q in scene.record], None
    record, sums = [], []

    def read(comp, var):
        if (comp, var) not in record:
            record.append((comp, var))
        return record.index((comp, var))

    for (c, q), column in zip(scene.record, scene.columns()):
        sp = scene.component(c)
        if not (isinstance(sp, Span) and sp.layered):
            terms = [(read(c, _record_variable(scene, c, q)), 1.0)]
        elif q.startswith("T_"):
            terms = [(read(layer_parts(sp)[sp.labels.index(q[2:])], SPAN_VARIABLES["T"]), 1.0)]
        elif q == "L":
            terms = [(read(layer_parts(sp)[0], SPAN_VARIABLES["L"]), 1.0)]
        elif q == "eps":
            EA = [w.EA for w in sp.wp2.plies]
            terms = [(read(name, SPAN_VARIABLES["eps"]), k / sum(EA)) for name, k in zip(layer_parts(sp), EA)]
        else:
            terms = [(read(name, SPAN_VARIABLES[q]), 1.0) for name in layer_parts(sp)]
        sums.append((column, terms))
    return record, sums


def equilibrium_starts(scene: Scene, at: float = 0.0) -> tuple[dict, dict]:
    """With `"start": "equilibrium"`: each span's strain and each roller's speed in the line's steady
    state (from the monolithic reference's equations, solved and checked once: a line without one is
    refused), as the parts' start values; and each dancer's steady position. ({}, {}) otherwise.
    `at` > 0: the line's operating point at that time instead (`LineODE.operating_state`)."""
    if scene.start != "equilibrium" and at == 0.0:
        return {}, {}
    from .reference import LineODE

    ode = LineODE(scene)
    z = ode.operating_state(at)
    starts = {name: {"eps_start": float(z[ode.i_eps[sp.name] + i])} for sp in scene.spans for i, name in enumerate(layer_parts(sp))}
    for m in ode.movers:
        starts[m.name] = {"v_start": float(m.R * z[ode.i_omega[m.name]])}
    for m in ode.slippers:  # the web's speed over it, as its slip over the surface's
        v = ode.speed(m, at, z)
        starts.setdefault(m.name, {})["traction.slip_start"] = float(z[ode.i_vw[m.name]] - v)
    return starts, {d.name: float(z[ode.i_y[d.name]]) for d in ode.dancers}


class TooManyWebs(SceneError):
    """More webs at a roller than the Roller FMU has ports: no engine of FMUs runs the scene (the reference does)."""


def port(side: str, k: int) -> str:
    """The Roller's port k (1-based) on side "web_a" (inlets) or "web_b" (outlets): web_a, web_a2, ..."""
    return side if k == 1 else f"{side}{k}"


def _ports(scene: Scene, node, side: str, spans: list) -> int:
    """How many webs meet at (side "web_a") or leave (side "web_b") a roller, a laminate's layers each
    one: the Roller has four of each."""
    count = sum(len(sp.wp2.plies if side == "web_a" else sp.wp1.plies) for sp in spans)
    if count > MAX_PORTS:
        what = "merges" if side == "web_a" else "splits the web into"
        webs = "webs" if side == "web_a" else "lanes"
        layers = f" of {count} layers in all (each layer of a laminate takes a port)" if count != len(spans) else ""
        raise TooManyWebs(f"{scene.path}: {node.type} {node.name!r} {what} {len(spans)} {webs} ({', '.join(sp.name for sp in spans)})"
                         f"{layers}; the Roller FMU has at most {MAX_PORTS} {'inlets' if side == 'web_a' else 'outlets'}")
    return count


def roller_ports(scene: Scene, node) -> tuple[dict, dict]:
    """The Roller's ports of `node`: {(span, layer): port} for the webs arriving (inlets) and leaving
    (outlets), 1-based, in port order (the main line's span first, each span's layers in its order).
    At a nip into a laminate each layer leaves at the port its web arrived at, so that the Roller
    (`layered`) passes each layer's strain on: outlet k takes inlet ((k - 1) mod inlets) + 1 ([M6])."""
    ins, outs = scene.spans_in(node), scene.spans_out(node)
    inlets = {(sp.name, i): 0 for sp in ins for i in range(len(sp.wp2.plies))}
    inlets = {key: k for k, key in enumerate(inlets, 1)}
    outlets = {}
    for sp in outs:
        if len(ins) > 1 and sp.layered:
            outlets.update({(sp.name, i): inlets[(src.name, j)] for i, (src, j) in enumerate(scene.layer_sources(sp))})
        else:
            for i in range(len(sp.wp1.plies)):
                outlets[(sp.name, i)] = len(outlets) + 1
    return inlets, outlets


def compile_scene(scene: Scene, fmu_dir=None, settle=True, carriages_at_equilibrium=True, at=0.0) -> System:
    """The System of a scene: a Roller per node (in the order the web flows), then a span per
    span (the same order, side paths included), their profiles, connections and the recorded
    variables. `settle`: connected inputs start at the initial outputs that feed them, read
    from the FMUs themselves (`master.settle_start_values`). `carriages_at_equilibrium`: with
    `"start": "equilibrium"`, a dancer's carriage starts at its steady position (`_roller`); the Line
    FMU, which solves its own steady state from the scene's parameters, takes them as they are.
    `at`: the System from the line's operating point at that time (a linearization's, `stability`).

    A nip where webs merge is a Roller with `inlets` = the number of webs arriving: the main
    line's span at web_a, each side path's last span at web_a2..4, their masses per unstretched
    length (`Web.rho_l`, as the reference weights them) as web_a.m, web_a2..4.m; the span after
    the nip takes the merged strain, the nip's web_b.eps [R5]. A slitter has `outlets` = the
    number of lanes: the main line's lane at web_b, each side path's first span at web_b2..4,
    each taking its strain from its port (the strain arriving, through the slitter's web_a.eps).
    More than four webs at a roller are refused, naming it. The Line FMU takes the same parts and
    connections (`linefmu.line_spec`)."""
    d = Path(fmu_dir or DEFAULT_FMU_DIR)
    span_fmu, roller_fmu = d / SPAN_FMU, d / ROLLER_FMU
    solvers = FmuFile.load(span_fmu).enumeration("solver") if any(s.solver != "auto" for s in scene.spans) else {}
    equilibrium, positions = equilibrium_starts(scene, at)
    if not carriages_at_equilibrium:
        positions = {}
    effects = span_effects(d)
    rollers = []
    ports = {}
    for n in scene.nodes:
        comp = _roller(scene, n, roller_fmu, positions)
        ins, outs = scene.spans_in(n), scene.spans_out(n)
        ports[n.name] = roller_ports(scene, n)
        if _ports(scene, n, "web_a", ins) > 1:
            comp.start["inlets"] = len(ports[n.name][0])
            merged = len(ins) > 1 and not any(sp.layered for sp in outs)  # webs merged into one [R5]
            if merged or getattr(n, "wound", None) is not None:  # [R5]'s weights: also the mass a roll winds [R3]
                comp.start.update({f"{port('web_a', k)}.m": float(m) for k, m in enumerate(scene.inlet_masses(n), 1)})
            if not merged:  # the webs stay layers, each passed on at its port
                comp.start["layered"] = True
        if _ports(scene, n, "web_b", outs) > 1:
            comp.start["outlets"] = len(ports[n.name][1])
        rollers.append(comp)
    # The strains the spans start at when the scene gives none: the reference's own given start
    # (reference.start_strain, the merged strain [M2] after a nip), so that every engine starts alike.
    from .reference import LineODE

    ode = LineODE(scene)
    z = ode.given_state()
    spans = [_span(scene, sp, float(z[ode.i_eps[sp.name] + i]), span_fmu, solvers, effects, positions, i)
             for sp in scene.spans for i in range(len(sp.wp2.plies))]
    for comp in rollers + spans:
        comp.start.update(equilibrium.get(comp.name, {}))

    connections = []

    def connect(src, out, dst, inp):
        connections.append(Connection((src, out), (dst, inp)))

    def through(node):  # several ports (a nip, a slitter, a laminate's layers): the strain goes through the Roller
        return any(len(p) > 1 for p in ports[node.name])

    for sp in scene.spans:
        up, down = scene.upstream(sp), scene.downstream(sp)
        before = scene.spans_in(up)
        # A laminate's layer takes its strain from the span that brings its web, as a plain web after a
        # plain roller does: stepped before it in webline's Gauss-Seidel order, not a step behind through
        # the roller ([M6]). Where webs merge into one [R5] and at a slitter, from the roller's port.
        if sp.layered and len(before) > 1:
            feeds = [layer_parts(src)[j] for src, j in scene.layer_sources(sp)]
        elif sp.layered and before:
            feeds = layer_parts(before[0])
        else:
            feeds = [None] * len(sp.wp2.plies)
        for i, name in enumerate(layer_parts(sp)):
            a = port("web_b", ports[up.name][1][(sp.name, i)])  # the port of `up` the layer leaves from
            b = port("web_a", ports[down.name][0][(sp.name, i)])  # the port of `down` it arrives at
            connect(up.name, f"{a}.v", name, "web_a.v")
            if feeds[i] is not None:
                connect(feeds[i], "web_b.eps", name, "web_a.eps")
            elif not before or through(up):
                connect(up.name, f"{a}.eps", name, "web_a.eps")
            else:
                connect(before[0].name, "web_b.eps", name, "web_a.eps")
            connect(down.name, f"{b}.v", name, "web_b.v")
            if through(down) or getattr(down, "wound", None) is not None:  # a roll winds the web's unstretched length [R3]
                connect(name, "web_b.eps", down.name, f"{b}.eps")
            if isinstance(down, Dancer):
                connect(down.name, "web_a.y", name, "frame_b.y")
            if isinstance(up, Dancer):
                connect(up.name, "web_b.y", name, "frame_a.y")
            roll = _runout_roll(scene, sp)
            if roll is up:
                connect(up.name, "web_b.y", name, "frame_a.y")
            elif roll is down:
                connect(down.name, "web_a.y", name, "frame_b.y")
            connect(name, "web_a.F", up.name, f"{a}.F")
            connect(name, "web_b.F", down.name, f"{b}.F")

    for n in scene.nodes:  # a drive's loop reads the tension it holds: a span's, or a roller's load cell
        loop = getattr(getattr(n, "drive", None), "loop", None)
        if loop is not None and not loop.speed:
            connect(loop.measure[0], "load_cell.F" if loop.measure[1] == "F" else "summary_Tension", n.name, "loop.measured")
        if loop is not None and loop.dancer is not None:  # a dancer loop reads the dancer's position [R13]
            connect(loop.dancer.dancer, "y", n.name, "dancer.y")

    record, sums = _record(scene)
    system = System(
        name=scene.name,
        components=rollers + spans,
        connections=connections,
        start_time=float(at),
        stop_time=float(scene.stop_time),
        step=float(scene.step),
        record=record,
        sums=sums,
    )
    if settle:
        settle_start_values(system)
    return system


def run_scene(scene, fmu_dir=None, **options) -> Result:
    """A scene compiled and run; the columns named as the scene records them ("film.T [N]")."""
    bounds = {part: bound for span, bound in tension_bounds(scene).items() for part in layer_parts(scene.component(span))}
    result = Master(compile_scene(scene, fmu_dir), Options(bounds=bounds, **options)).run()
    result.scene = scene.name
    result.columns = scene.columns()
    return result
