"""Reading a scene: the JSON read strictly into the model of types.py, each part by its own keys,
then the line held to the rules of checks.py. Every problem is a `SceneError` whose message starts
with `file:line:column` of the offending key or value."""

from __future__ import annotations

import json
import math
from dataclasses import replace
from pathlib import Path

from .. import jsontree, records, units
from ..fmus import DEFAULT_FMU_DIR, SPAN_FMU, enumeration, span_description, span_effects
from ..jsontree import Node, Obj
from ..profiles import Profile, ScurveError
from ..units import UnitError
from .checks import WIDTH_TOLERANCE, check_dancer_spans, check_positions, check_layers, check_loops, check_merge, check_split, check_traction
from .types import (
    HARMONICS,
    NIP_SIDES,
    STRAIN_RANGE,
    TRACTION_QUANTITIES,
    Branch,
    Dancer,
    DancerLoop,
    Drive,
    Event,
    LayOn,
    Loop,
    Prescribed,
    Roller,
    Runout,
    Scene,
    SceneError,
    Span,
    Traction,
    Web,
    Wound,
    quantities_of,
    quantity_unit,
)

FIRST = ("source", "unwinder")
MIDDLE = ("roller", "dancer")
LAST = ("sink", "winder")

MIN_SAMPLE = 1e-5  # s: the Roller's shortest sample period [R14]
MU_MAX = 10.0  # the Roller's traction.mu and nip.mu at most


class _Reader:
    def __init__(self, source: str, fmu_dir=None):
        self.source = source
        self.fmu_dir = fmu_dir

    def solvers(self):
        """The span's solvers: the items of its Enumeration `solver`, from its model description."""
        return enumeration(span_description(self.fmu_dir), "solver")

    def effects(self):
        """The span's effects, as its model description names them."""
        return span_effects(self.fmu_dir)

    def err(self, node_or_pos, message):
        if isinstance(node_or_pos, Node):
            pos = f"{node_or_pos.line}:{node_or_pos.col}"
        else:
            pos = node_or_pos
        return SceneError(f"{self.source}:{pos}: {message}")

    def key_pos(self, node: Node):
        return f"{node.key_line}:{node.key_col}" if node.key_line else f"{node.line}:{node.col}"

    def obj(self, node: Node, what: str) -> Obj:
        if not isinstance(node.value, Obj):
            raise self.err(node, f"{what} must be a JSON object {{...}}")
        return node.value

    def keys(self, node: Node, what: str, required=(), optional=()):
        """The object's entries, refusing unknown keys and missing required ones."""
        o = self.obj(node, what)
        allowed = list(required) + list(optional)
        for k, v in o.items.items():
            if k not in allowed:
                raise self.err(self.key_pos(v), f"unknown key {k!r} in {what} (allowed: {', '.join(allowed)})")
        for k in required:
            if k not in o:
                raise self.err(node, f"{what} needs the key {k!r}")
        return o

    def string(self, node: Node, what: str) -> str:
        if not isinstance(node.value, str) or not node.value:
            raise self.err(node, f"{what} must be a non-empty string")
        return node.value

    def boolean(self, node: Node, what: str) -> bool:
        if not isinstance(node.value, bool):
            raise self.err(node, f"{what} must be true or false, found {node.value!r}")
        return node.value

    def quantity(self, node: Node, dimension, what: str, positive=False, nonnegative=False):
        try:
            x = units.parse_quantity(node.value, dimension)
        except UnitError as e:
            raise self.err(node, f"{what}: {e}") from None
        if positive and not x > 0:
            raise self.err(node, f"{what} must be > 0, found {node.value!r}")
        if nonnegative and not x >= 0:
            raise self.err(node, f"{what} must be >= 0, found {node.value!r}")
        return x

    def profile(self, node: Node, dimension, what: str) -> Profile:
        v = node.value
        if not isinstance(v, Obj):
            return Profile.constant(self.quantity(node, dimension, what))
        kinds = ("constant", "step", "ramp", "scurve", "table")
        if len(v.items) != 1 or next(iter(v.keys())) not in kinds:
            raise self.err(node, f"{what}: a profile is a value or an object with one key of {', '.join(kinds)}")
        kind, body = next(iter(v.items.items()))
        T = units.TIME
        if kind == "constant":
            return Profile.constant(self.quantity(body, dimension, f"{what}.constant"))
        if kind == "step":
            o = self.keys(body, f"{what}.step", required=("time", "from", "to"))
            t = self.quantity(o["time"], T, f"{what}.step.time", nonnegative=True)
            a = self.quantity(o["from"], dimension, f"{what}.step.from")
            b = self.quantity(o["to"], dimension, f"{what}.step.to")
            return Profile(((t, a), (t, b)))
        if kind == "ramp":
            o = self.keys(body, f"{what}.ramp", required=("start", "duration", "from", "to"))
            t0 = self.quantity(o["start"], T, f"{what}.ramp.start", nonnegative=True)
            dt = self.quantity(o["duration"], T, f"{what}.ramp.duration", positive=True)
            a = self.quantity(o["from"], dimension, f"{what}.ramp.from")
            b = self.quantity(o["to"], dimension, f"{what}.ramp.to")
            return Profile(((t0, a), (t0 + dt, b)))
        if kind == "scurve":
            return self._scurve(body, dimension, f"{what}.scurve")
        # table: [[time, value], ...]
        if not isinstance(body.value, list) or not body.value:
            raise self.err(body, f"{what}.table must be a non-empty list of [time, value] pairs")
        knots = []
        for i, pair in enumerate(body.value):
            if not isinstance(pair.value, list) or len(pair.value) != 2:
                raise self.err(pair, f"{what}.table[{i}] must be a [time, value] pair")
            t = self.quantity(pair.value[0], T, f"{what}.table[{i}] time", nonnegative=True)
            x = self.quantity(pair.value[1], dimension, f"{what}.table[{i}] value")
            if knots and t < knots[-1][0]:
                raise self.err(pair, f"{what}.table[{i}]: times must not decrease")
            if len(knots) >= 2 and t == knots[-1][0] == knots[-2][0]:
                raise self.err(pair, f"{what}.table[{i}]: at most two entries at one time (a jump)")
            knots.append((t, x))
        return Profile(tuple(knots))

    def _scurve(self, node: Node, dimension, what: str) -> Profile:
        """A jerk-limited ramp, {"start", "from", "to"} and "jerk" (per s^2 of the profile's unit), "duration",
        or both (`Profile.scurve`: which fixes what, and the duration the jerk needs)."""
        o = self.keys(node, what, required=("start", "from", "to"), optional=("duration", "jerk"))
        if "duration" not in o and "jerk" not in o:
            raise self.err(node, f"{what} needs a jerk, a duration or both (the jerk fixes the shortest ramp, a duration the least jerk)")
        t0 = self.quantity(o["start"], units.TIME, f"{what}.start", nonnegative=True)
        a = self.quantity(o["from"], dimension, f"{what}.from")
        b = self.quantity(o["to"], dimension, f"{what}.to")
        duration = self.quantity(o["duration"], units.TIME, f"{what}.duration", positive=True) if "duration" in o else None
        jerk = self.quantity(o["jerk"], units.DIMENSIONLESS, f"{what}.jerk (per s^2, in the profile's SI unit)", positive=True) \
            if "jerk" in o else None
        try:
            return Profile.scurve(t0, a, b, jerk, duration)
        except ScurveError as e:
            raise self.err(node, f"{what}: {e}") from None


def _web(r: _Reader, name: str, node: Node, web_library, webs) -> Web:
    what = f"web {name!r}"
    if isinstance(node.value, Obj) and "laminate" in node.value.keys():
        return _laminate(r, name, node, webs)
    if isinstance(node.value, Obj) and "slit" in node.value.keys():
        o = r.keys(node, what, required=("slit", "width"), optional=("description",))
        base = _web_ref(r, webs, o["slit"], f"{what}: slit")
        width = r.quantity(o["width"], units.LENGTH, f"{what}: width", positive=True)
        if width > base.width * (1 + WIDTH_TOLERANCE):
            raise r.err(o["width"], f"{what}: a lane of {width:g} m is wider than the web {base.name!r} it is slit from ({base.width:g} m)")
        # The same material, narrower (a laminate's layers too); a record's name would give the FMU the record's width.
        return replace(base, name=name, width=width, record=None, layers=tuple(replace(w, width=width) for w in base.layers))
    if isinstance(node.value, Obj) and "record" in node.value.keys():
        o = r.keys(node, what, required=("record",), optional=("description",))
        record = r.string(o["record"], f"{what}: record")
        try:
            rec = records.find(record, web_library, Path(r.fmu_dir or DEFAULT_FMU_DIR) / SPAN_FMU)
        except (records.RecordError, OSError) as e:
            raise r.err(o["record"], f"{what}: {e}") from None
        fields = {k: getattr(rec, k) for k in ("E", "thickness", "width", "density", "d_r")}
        return Web(name=name, record=record, curve=rec.curve(), **fields)
    o = r.keys(node, what, required=("E", "thickness", "width", "density"), optional=("d_r", "description"))
    U = units
    return Web(
        name=name,
        E=r.quantity(o["E"], U.PRESSURE, f"{what}: E", positive=True),
        thickness=r.quantity(o["thickness"], U.LENGTH, f"{what}: thickness", positive=True),
        width=r.quantity(o["width"], U.LENGTH, f"{what}: width", positive=True),
        density=r.quantity(o["density"], U.DENSITY, f"{what}: density", positive=True),
        d_r=r.quantity(o["d_r"], U.TIME, f"{what}: d_r", nonnegative=True) if "d_r" in o else 0.0,
    )


def _laminate(r: _Reader, name: str, node: Node, webs) -> Web:
    """A laminate's entry: its layers (webs of the scene, of one width and linear), its compression and
    adhesive; its values are the law of mixtures (`Web.laminate`)."""
    what = f"web {name!r}"
    o = r.keys(node, what, required=("laminate",), optional=("compression", "adhesive", "description"))
    lst = o["laminate"]
    if not isinstance(lst.value, list) or len(lst.value) < 2:
        raise r.err(lst, f"{what}: laminate must be a list of at least two webs (its layers)")
    webs_in = [_web_ref(r, webs, n, f"{what}: laminate layer") for n in lst.value]
    layers = [w for web in webs_in for w in web.plies]
    for w in layers:
        if w.curve is not None:
            raise r.err(lst, f"{what}: layer {w.name!r} has a stress-strain table; a laminate's layers must be linear "
                             "(give the laminate's measured values as a web of its own)")
        if abs(w.width - layers[0].width) > WIDTH_TOLERANCE * layers[0].width:
            raise r.err(lst, f"{what}: layers {layers[0].name!r} ({layers[0].width:g} m) and {w.name!r} ({w.width:g} m) "
                             "differ in width; a laminate stacks equal widths (give the laminate's measured values instead)")
    compression = 1.0
    if "compression" in o:
        compression = r.quantity(o["compression"], units.DIMENSIONLESS, f"{what}: compression", positive=True)
        if compression > 1:
            raise r.err(o["compression"], f"{what}: compression {compression:g} must be in (0, 1]: the nip presses, it does not swell")
    coat = r.quantity(o["adhesive"], units.AREAL_DENSITY, f"{what}: adhesive", nonnegative=True) if "adhesive" in o else 0.0
    return Web.laminate(name, webs_in, compression, coat)


class _Webs(dict):
    """The scene's webs, read in any order: a laminate or a lane may name a web defined after it.
    A web is read when first named (`ref`); one that leads back to itself is refused with the chain."""

    def __init__(self, r: _Reader, nodes: Obj, web_library):
        super().__init__()
        self.r, self.nodes, self.library = r, nodes, web_library
        self.reading = []  # the webs being read, outermost first

    def ref(self, node: Node, what: str) -> Web:
        name = self.r.string(node, what)
        if name in self:
            return self[name]
        if name not in self.nodes:
            raise self.r.err(node, f"{what}: no web {name!r} in \"webs\" (defined: {', '.join(self.nodes.keys()) or 'none'})")
        if name in self.reading:
            chain = " -> ".join(self.reading[self.reading.index(name):] + [name])
            raise self.r.err(node, f"{what}: web {name!r} is made of itself ({chain}): a laminate's layers and a "
                                   "lane's web must be other webs")
        self.reading.append(name)
        try:
            web = _web(self.r, name, self.nodes[name], self.library, self)
        finally:
            self.reading.pop()
        self[name] = web
        return web

    def read_all(self) -> dict:
        """Every web, in the file's order."""
        for name, node in self.nodes.items.items():
            if name not in self:
                self.reading.append(name)
                try:
                    self[name] = _web(self.r, name, node, self.library, self)
                finally:
                    self.reading.pop()
        return {name: self[name] for name in self.nodes.keys()}


def _web_ref(r: _Reader, webs: dict, node: Node, what: str) -> Web:
    if isinstance(webs, _Webs):
        return webs.ref(node, what)
    name = r.string(node, what)
    if name not in webs:
        raise r.err(node, f"{what}: no web {name!r} in \"webs\" (defined: {', '.join(webs) or 'none'})")
    return webs[name]


def _drive(r: _Reader, node: Node, what: str, kinds) -> Drive:
    o = r.obj(node, what)
    if "speed" in kinds and "speed" in o and isinstance(o["speed"].value, Obj) and "input" in o["speed"].value \
            and "loop" not in o:  # an ideal speed drive on the Line FMU's input <name>.v_ref, held over a step
        o = r.keys(node, what, required=("speed",))
        start = r.keys(o["speed"], f"{what}.speed", required=("input",))["input"]
        return Drive("speed", Profile.constant(r.quantity(start, units.SPEED, f"{what}.speed.input")), input=True)
    if "speed" in kinds and "speed" in o and "loop" in o:  # a speed loop on a real motor
        o = r.keys(node, what, required=("speed", "loop"), optional=("feedforward", "dancer"))
        g = r.keys(o["loop"], f"{what}.loop", required=("kp", "ki"), optional=("limit", "lag", "sample", "delay"))
        speed_node, speed_input = o["speed"], False
        if isinstance(speed_node.value, Obj) and "input" in speed_node.value:  # the Line FMU's input <name>.v_ref
            speed_node, speed_input = r.keys(speed_node, f"{what}.speed", required=("input",))["input"], True
            if "feedforward" in o:
                raise r.err(r.key_pos(o["feedforward"]), f"{what}: a speed loop fed by an input has no reference "
                                                         "acceleration to feed forward")
        loop = Loop(measure=None, set_input=speed_input,
                    set=Profile.constant(r.quantity(speed_node, units.SPEED, f"{what}.speed.input")) if speed_input
                    else r.profile(speed_node, units.SPEED, f"{what}.speed"),
                    kp=r.quantity(g["kp"], units.DIMENSIONLESS, f"{what}.loop.kp (N.m per m/s)", nonnegative=True),
                    ki=r.quantity(g["ki"], units.DIMENSIONLESS, f"{what}.loop.ki (N.m per m)", nonnegative=True))
        _motor(r, g, f"{what}.loop", loop)
        if "feedforward" in o:
            _feedforward(r, o["feedforward"], f"{what}.feedforward", loop)
        if "dancer" in o:  # a dancer position loop trims the reference [R13]; its dancer is checked in check_loops
            d = r.keys(o["dancer"], f"{what}.dancer", required=("dancer", "set", "kp", "ki"))
            loop.dancer = DancerLoop(
                dancer=r.string(d["dancer"], f"{what}.dancer.dancer"),
                set=r.quantity(d["set"], units.LENGTH, f"{what}.dancer.set"),
                kp=r.quantity(d["kp"], units.DIMENSIONLESS, f"{what}.dancer.kp (m/s per m)", nonnegative=True),
                ki=r.quantity(d["ki"], units.DIMENSIONLESS, f"{what}.dancer.ki (m/s per m.s)", nonnegative=True))
        return Drive("speed loop", None, loop)
    if "tension" in kinds and "tension" in o and "taper" in o:
        return _tapered(r, node, what)
    if len(o.items) != 1 or next(iter(o.keys())) not in kinds:
        raise r.err(node, f"{what} must be an object with one key of {', '.join(kinds)}")
    kind, body = next(iter(o.items.items()))
    if kind == "pi":
        return Drive("pi", None, _loop(r, body, f"{what}.pi"))
    if kind == "brake":
        return _brake(r, body, f"{what}.brake")
    dim = {"torque": units.TORQUE, "tension": units.FORCE, "speed": units.SPEED}[kind]
    return Drive(kind, r.profile(body, dim, f"{what}.{kind}"))


def _tapered(r: _Reader, node: Node, what: str) -> Drive:
    """A tension drive with a taper, {"tension": profile, "taper": k}: T(r) = T0 (1 - k (1 - R/r)) [R16],
    0 <= k <= 1 (k = 1: a constant torque T0 R). Only a winder's (checked in _roller)."""
    o = r.keys(node, what, required=("tension", "taper"))
    drive = Drive("tension", r.profile(o["tension"], units.FORCE, f"{what}.tension"))
    drive.taper = r.quantity(o["taper"], units.DIMENSIONLESS, f"{what}.taper", nonnegative=True)
    if drive.taper > 1.0:
        raise r.err(o["taper"], f"{what}.taper = {drive.taper:g}: a taper is 0 to 1 (1 - k (1 - R/r) stays > 0 as the roll grows)")
    return drive


def _brake(r: _Reader, node: Node, what: str) -> Drive:
    """A powder brake: its rated torque (a profile, N.m >= 0), or {"torque": profile, "creep": length},
    creep its presliding surface travel delta_b (docs/physics.md, "Contacts that stick")."""
    drive = Drive("brake")
    torque = node
    if isinstance(node.value, Obj) and "torque" in node.value:
        o = r.keys(node, what, required=("torque",), optional=("creep",))
        torque = o["torque"]
        if "creep" in o:
            drive.creep = r.quantity(o["creep"], units.LENGTH, f"{what}: creep", positive=True)
    drive.profile = r.profile(torque, units.TORQUE, f"{what}" if torque is node else f"{what}: torque")
    negative = next(((t, v) for t, v in drive.profile.knots if v < 0), None)
    if negative is not None:
        raise r.err(torque, f"{what}: {negative[1]:g} N.m at t = {negative[0]:g} s: a brake's rated torque is >= 0 "
                            "(it opposes the roll's motion whichever way it turns)")
    return drive


def _loop(r: _Reader, node: Node, what: str) -> Loop:
    """A drive's "pi": {"measure": "SPAN.T" or "ROLLER.F", "set", "kp", "ki", "limit", "lag", "feedforward",
    "compression", "sample", "delay"}.
    Which parts it names is checked once the line is read (`check_loops`)."""
    o = r.keys(node, what, required=("measure", "set", "kp", "ki"),
               optional=("limit", "lag", "feedforward", "compression", "sample", "delay"))
    measure = r.string(o["measure"], f"{what}.measure")
    part, _, quantity = measure.rpartition(".")
    if not part or quantity not in ("T", "F"):
        raise r.err(o["measure"], f"{what}.measure must be \"SPAN.T\" (a span's tension) or \"ROLLER.F\" (a load cell), found {measure!r}")
    set_node, set_input = o["set"], False
    if isinstance(set_node.value, Obj) and "input" in set_node.value:  # the Line FMU's input <name>.T_set
        set_node, set_input = r.keys(set_node, f"{what}.set", required=("input",))["input"], True
    loop = Loop(
        measure=(part, quantity),
        set=Profile.constant(r.quantity(set_node, units.FORCE, f"{what}.set.input")) if set_input
        else r.profile(set_node, units.FORCE, f"{what}.set"),
        set_input=set_input,
        kp=r.quantity(o["kp"], units.DIMENSIONLESS, f"{what}.kp (N.m per N)", nonnegative=True),
        ki=r.quantity(o["ki"], units.DIMENSIONLESS, f"{what}.ki (N.m per N.s)", nonnegative=True),
    )
    if "compression" in o:
        loop.compression = r.boolean(o["compression"], f"{what}.compression")
        if loop.compression and quantity == "F":
            raise r.err(o["compression"], f"{what}.compression: a load cell reads the size of a force (>= 0); "
                                          "only a span's tension (\"SPAN.T\") can be held in compression")
    _set_point(r, set_node, loop, f"{what}.set" + (".input" if set_input else ""))
    _motor(r, o, what, loop)
    if "feedforward" in o:
        _feedforward(r, o["feedforward"], f"{what}.feedforward", loop)
    return loop


def _set_point(r: _Reader, node: Node, loop: Loop, what: str):
    """A tension set point is > 0 (a web pushed is no longer held by its tension), unless the loop
    says it means compression ("compression": true)."""
    low = min(v for _, v in loop.set.knots)
    if low <= 0.0 and not loop.compression:
        raise r.err(node, f"{what} = {low:g} N: a tension set point must be > 0 N (a web in compression buckles); "
                          "give the loop \"compression\": true if it is meant")


def _motor(r: _Reader, o, what: str, loop: Loop):
    """A loop's motor: its torque "limit" and "lag"; a sampled loop's hold "sample" and "delay" [R14]."""
    if "limit" in o:
        loop.limit = r.quantity(o["limit"], units.TORQUE, f"{what}.limit", positive=True)
    if "lag" in o:
        loop.lag = r.quantity(o["lag"], units.TIME, f"{what}.lag", nonnegative=True)
    if "sample" in o:
        loop.sample = r.quantity(o["sample"], units.TIME, f"{what}.sample", positive=True)
        if loop.sample < MIN_SAMPLE:
            raise r.err(o["sample"], f"{what}.sample = {loop.sample:g} s: a sampled loop's period is at least {MIN_SAMPLE:g} s "
                                     "(leave \"sample\" out for a continuous loop)")
    if "delay" in o:
        loop.delay = r.quantity(o["delay"], units.TIME, f"{what}.delay", nonnegative=True)
        if not loop.delay <= loop.sample:
            raise r.err(o["delay"], f"{what}.delay = {loop.delay:g} s: a sampled loop's delay is at most its \"sample\" "
                                    f"period ({loop.sample:g} s; a loop without one has no delay)")


def _feedforward(r: _Reader, node: Node, what: str, loop: Loop):
    ff = r.string(node, what)
    if ff != "inertia":
        raise r.err(node, f"{what}: the one feed-forward is \"inertia\", found {ff!r}")
    loop.feedforward = True


def _span(r, o_node, name, webs) -> Span:
    what = f"span {name!r}"
    o = r.keys(
        o_node,
        what,
        required=("type", "name"),
        optional=("L", "web", "wp1", "wp2", "effects", "T_start", "eps_start", "solver", "tolerance", "substeps", "description"),
    )
    s = Span(name=name, type="span", where=f"{r.source}:{o_node.line}:{o_node.col}")
    if "L" in o:
        s.length = r.quantity(o["L"], units.LENGTH, f"{what}: L", positive=True)
    if "web" in o:
        for k in ("wp1", "wp2"):
            if k in o:
                raise r.err(r.key_pos(o[k]), f"{what}: give either \"web\" (both sides) or \"wp1\" and \"wp2\", not both")
        s.wp1 = s.wp2 = _web_ref(r, webs, o["web"], f"{what}: web")
    else:
        for k in ("wp1", "wp2"):
            if k not in o:
                raise r.err(o_node, f"{what} needs \"web\" (a plain span) or both \"wp1\" and \"wp2\" (a converting span)")
        s.wp1 = _web_ref(r, webs, o["wp1"], f"{what}: wp1")
        s.wp2 = _web_ref(r, webs, o["wp2"], f"{what}: wp2")
    effects = set()
    if "effects" in o:
        node = o["effects"]
        known = r.effects()
        if not isinstance(node.value, list):
            raise r.err(node, f"{what}: effects must be a list of effect names ({', '.join(known)})")
        for e in node.value:
            name_e = r.string(e, f"{what}: effect")
            if name_e not in known:
                raise r.err(e, f"{what}: unknown effect {name_e!r} (effects: {', '.join(known)})")
            if name_e in effects:
                raise r.err(e, f"{what}: effect {name_e!r} listed twice")
            effects.add(name_e)
    s.effects = frozenset(effects)
    if "includeDamping" in effects and s.wp2.d_r == 0.0:
        raise r.err(o["effects"], f"{what}: includeDamping needs d_r > 0 in web {s.wp2.name!r}")
    if "T_start" in o and "eps_start" in o:
        raise r.err(r.key_pos(o["eps_start"]), f"{what}: give T_start or eps_start, not both")
    if "T_start" in o:
        s.eps_start = s.wp2.strain_at(r.quantity(o["T_start"], units.FORCE, f"{what}: T_start"))
    elif "eps_start" in o:
        s.eps_start = r.quantity(o["eps_start"], units.DIMENSIONLESS, f"{what}: eps_start")
    if s.eps_start is not None and not s.eps_start > -1:
        raise r.err(o_node, f"{what}: the start strain {s.eps_start} must be > -1")
    if "solver" in o:
        s.solver = r.string(o["solver"], f"{what}: solver")
        if s.solver not in r.solvers():
            raise r.err(o["solver"], f"{what}: unknown solver {s.solver!r} (solvers: {', '.join(r.solvers())})")
    if "tolerance" in o:
        s.tolerance = r.quantity(o["tolerance"], units.DIMENSIONLESS, f"{what}: tolerance", positive=True)
    if "substeps" in o:
        n = o["substeps"]
        if not isinstance(n.value, int) or isinstance(n.value, bool) or n.value < 1:
            raise r.err(n, f"{what}: substeps must be an integer >= 1")
        s.substeps = n.value
    return s


def _roller(r, o_node, name, kind) -> Roller:
    what = f"{kind} {name!r}"
    optional = ["J", "R", "b", "v_start", "drive", "description", "wrap", "traction", "nip", "wound", "runout", "layon", "at"]
    if kind == "roller":
        optional += ["merge", "split", "trim"]  # side paths: read by _branch
    required = ["type", "name"]
    if kind == "unwinder":
        required.append("strain")
    o = r.keys(o_node, what, required=required, optional=optional)
    c = Roller(name=name, type=kind, where=f"{r.source}:{o_node.line}:{o_node.col}")
    drives = {"roller": ("torque", "speed", "pi", "brake"), "unwinder": ("torque", "tension", "speed", "pi", "brake"),
              "winder": ("torque", "tension", "speed", "pi", "brake")}
    if "drive" in o:
        c.drive = _drive(r, o["drive"], f"{what}: drive", drives[kind])
        if c.drive.taper and kind != "winder":
            raise r.err(r.key_pos(o["drive"]), f"{what}: drive.taper = {c.drive.taper:g}: a taper is a winder's (the tension "
                                               "falls as the roll it winds grows); an unwinder's roll has its wound-in stresses already")
    slips = "traction" in o or "nip" in o
    if c.drive.kind == "speed":
        # With traction the roll's radius sets the web's mass on it and the air film, with runout where
        # the web touches [R15], with a lay-on roller where the nip presses [R18]: R is needed then.
        needs = [(k, why) for k, why in (("traction", "the web's mass on the wrap and the air film depend on it"),
                                         ("nip", "the web's mass on the wrap depends on it"),
                                         ("runout", "the roll's surface, where the web touches"),
                                         ("layon", "the roll's surface, where the nip presses")) if k in o]
        radius = bool(needs)
        for k in ("J", "b", "v_start") if radius else ("J", "R", "b", "v_start"):
            if k in o:
                raise r.err(r.key_pos(o[k]), f"{what}: {k} is not used: a speed-driven roller follows its speed profile exactly")
        if radius:
            if "R" not in o:
                raise r.err(o_node, f"{what} needs the key 'R' with {needs[0][0]} ({needs[0][1]})")
            c.R = r.quantity(o["R"], units.LENGTH, f"{what}: R", positive=True)
    else:
        for k in ("J", "R"):
            if k not in o:
                raise r.err(o_node, f"{what} needs the key {k!r} (the Roller FMU's parameter)")
        c.J = r.quantity(o["J"], units.INERTIA, f"{what}: J", positive=True)
        c.R = r.quantity(o["R"], units.LENGTH, f"{what}: R", positive=True)
        if "b" in o:
            c.b = r.quantity(o["b"], units.ROT_DAMPING, f"{what}: b", nonnegative=True)
        if "v_start" in o:
            c.v_start = r.quantity(o["v_start"], units.SPEED, f"{what}: v_start")
    if kind == "unwinder":
        c.strain = _strain_profile(r, o["strain"], what)
    c.wrap = _wrap(r, o, what)
    c.at = _at(r, o, what)
    if "merge" in o and "split" in o:
        raise r.err(r.key_pos(o["split"]), f"{what} carries both merge and split: laminate at one roller, slit at another")
    if "trim" in o:
        if "split" not in o:
            raise r.err(r.key_pos(o["trim"]), f"{what}: trim goes with split (the width a slitter cuts off)")
        c.trim = r.quantity(o["trim"], units.LENGTH, f"{what}: trim", nonnegative=True)
    if slips and (c.drive.loop is not None or c.drive.kind == "brake"):
        raise r.err(r.key_pos(o["traction" if "traction" in o else "nip"]),
                    f"{what}: traction or a nip on a roller whose drive has a loop or a brake is not modelled")
    if slips:
        for k, why in (("merge", "a laminating nip"), ("split", "a slitter")):
            if k in o:
                raise r.err(r.key_pos(o["traction" if "traction" in o else "nip"]),
                            f"{what}: traction or a nip on {why} is not modelled: the web slips only on a roller with one web in and one out")
        if kind != "roller":
            raise r.err(r.key_pos(o["traction" if "traction" in o else "nip"]),
                        f"{what}: traction or a nip on {'an' if kind == 'unwinder' else 'a'} {kind} is not modelled (its roll's radius "
                        "changes): put it on a roller or a dancer")
        c.traction = _traction(r, o, what, c.wrap)
    if "wound" in o:
        if kind == "roller":
            raise r.err(r.key_pos(o["wound"]), f"{what}: wound is a roll's: put it on an unwinder or a winder")
        if c.drive.kind == "speed":
            raise r.err(r.key_pos(o["wound"]), f"{what}: wound moves a roll's radius and inertia, which a speed-driven "
                                               "roll does not use (its surface follows its speed profile): drive it by torque or tension")
        w = r.keys(o["wound"], f"{what}: wound", required=("thickness",), optional=("density", "width", "stepwise"))
        c.wound = Wound(thickness=r.quantity(w["thickness"], units.LENGTH, f"{what}: wound: thickness", positive=True))
        if "density" in w:
            c.wound.density = r.quantity(w["density"], units.DENSITY, f"{what}: wound: density", positive=True)
        if "width" in w:
            c.wound.width = r.quantity(w["width"], units.LENGTH, f"{what}: wound: width", positive=True)
        if "stepwise" in w:
            c.wound.merge = _stepwise(r, w["stepwise"], f"{what}: wound: stepwise")
    if "runout" in o:
        c.runout = _runout(r, o["runout"], what, kind)
    if "layon" in o:
        c.layon = _layon(r, o["layon"], what, kind)
        if getattr(c.wound, "merge", 0.0):
            raise r.err(r.key_pos(o["layon"]), f"{what}: a lay-on roller on a stepwise radius (wound.stepwise) is not modelled "
                                               "(the nip presses on the smooth radius); drop one")
        if c.runout is not None and c.runout.harmonics:
            raise r.err(r.key_pos(o["layon"]), f"{what}: a lay-on roller on an out-of-round roll (runout: harmonics) is not "
                                               "modelled (the nip presses on runout's circle); drop one")
    return c


def _layon(r, node, what, kind) -> LayOn:
    """`"layon": {"mass", "stiffness", "damping", "radius", "load", ...}` on a winder [R18]."""
    if kind != "winder":
        raise r.err(r.key_pos(node), f"{what}: a lay-on roller presses on a roll being wound: put it on a winder")
    w = f"{what}: layon"
    o = r.keys(node, w, required=("mass", "stiffness", "damping", "radius", "load"),
               optional=("inertia", "bearing", "mu", "v_slip", "angle"))
    load = r.profile(o["load"], units.FORCE, f"{w}: load")
    negative = next(((t, v) for t, v in load.knots if v < 0), None)
    if negative is not None:
        raise r.err(o["load"], f"{w}: load {negative[1]:g} N at t = {negative[0]:g} s: a lay-on roller presses with a load >= 0")
    layon = LayOn(mass=r.quantity(o["mass"], units.MASS, f"{w}: mass", positive=True),
                  stiffness=r.quantity(o["stiffness"], units.STIFFNESS, f"{w}: stiffness", positive=True),
                  damping=r.quantity(o["damping"], units.LIN_DAMPING, f"{w}: damping", nonnegative=True),
                  radius=r.quantity(o["radius"], units.LENGTH, f"{w}: radius", positive=True), load=load)
    for key, kind, sign in (("inertia", units.INERTIA, "positive"), ("bearing", units.ROT_DAMPING, "nonnegative"),
                            ("mu", units.DIMENSIONLESS, "nonnegative"), ("v_slip", units.SPEED, "positive")):
        if key in o:
            setattr(layon, key, r.quantity(o[key], kind, f"{w}: {key}", **{sign: True}))
    if layon.mu > MU_MAX:
        raise r.err(o["mu"], f"{w}: mu = {layon.mu:g}: a friction coefficient is 0 to {MU_MAX:g}")
    if "angle" in o:
        layon.angle = math.radians(r.quantity(o["angle"], units.ANGLE, f"{w}: angle"))
    return layon


def _runout(r, node, what, kind) -> Runout:
    """`"runout": {"eccentricity": length, "phase": angle, "harmonics": [...]}` on an unwinder or a winder [R15];
    each harmonic `{"order": k >= 2, "amplitude": length, "phase": angle}`, at most HARMONICS."""
    if kind == "roller":
        raise r.err(r.key_pos(node), f"{what}: runout is a roll's: put it on an unwinder or a winder")
    o = r.keys(node, f"{what}: runout", required=("eccentricity",), optional=("phase", "harmonics"))
    e = r.quantity(o["eccentricity"], units.LENGTH, f"{what}: runout: eccentricity", nonnegative=True)
    phase = math.radians(r.quantity(o["phase"], units.ANGLE, f"{what}: runout: phase")) if "phase" in o else 0.0
    harmonics = []
    if "harmonics" in o:
        items = o["harmonics"].value
        if not isinstance(items, list) or len(items) > HARMONICS:
            raise r.err(o["harmonics"], f"{what}: runout: harmonics must be a list of at most {HARMONICS} "
                                        "{\"order\", \"amplitude\", \"phase\"}")
        for i, item in enumerate(items):
            where = f"{what}: runout: harmonics[{i}]"
            h = r.keys(item, where, required=("order", "amplitude"), optional=("phase",))
            order = h["order"].value
            if isinstance(order, bool) or not isinstance(order, int) or not 2 <= order <= 64:
                raise r.err(h["order"], f"{where}.order = {order!r}: a harmonic's order is a whole number from 2 to 64 "
                                        "(the first, 1, is the eccentricity)")
            amplitude = r.quantity(h["amplitude"], units.LENGTH, f"{where}.amplitude", nonnegative=True)
            angle = math.radians(r.quantity(h["phase"], units.ANGLE, f"{where}.phase")) if "phase" in h else 0.0
            harmonics.append((order, amplitude, angle))
    return Runout(eccentricity=e, phase=phase, harmonics=tuple(harmonics))


def check_runout(r, scene, raw):
    """A roll with runout moves the length of its own span [R15]: a plain span of given length (not a
    dancer's, not a laminate's)."""
    for c in scene.nodes:
        if getattr(c, "runout", None) is None:
            continue
        (sp,) = scene.spans_out(c) if c.type == "unwinder" else scene.spans_in(c)
        if sp.length is None or sp.layered:
            raise SceneError(f"{c.where}: {c.type} {c.name!r}: runout moves the length of span {sp.name!r}, which "
                             f"{'hangs from a dancer' if sp.length is None else 'carries a laminate'}: put a span of its own "
                             f"length between the roll and it")
        if getattr(c.wound, "merge", 0.0):
            raise SceneError(f"{c.where}: {c.type} {c.name!r} has runout and a stepwise radius (wound.stepwise): the two "
                             "together are not modelled (runout's arm is the smooth radius's); drop one")
        if scene.start == "equilibrium":
            raise SceneError(f"{c.where}: {c.type} {c.name!r} has runout and the scene starts at \"equilibrium\": a roll that "
                             "turns off its centre holds no steady state (its tangent point moves once a turn); start it "
                             "\"given\" (the steady state of its round roll) and let the ripple settle")
        reach = c.runout.eccentricity + sum(a for _, a, _ in c.runout.harmonics)
        if not sp.length > reach + c.R:
            raise SceneError(f"{sp.where}: span {sp.name!r} of {sp.length:g} m is too short for {c.type} {c.name!r}'s runout: "
                             f"its length must exceed the roll's radius plus its eccentricity and harmonics ({c.R + reach:g} m)")
        lobes = sum((k * k - 1) * a for k, a, _ in c.runout.harmonics)
        if not lobes < c.R:
            raise SceneError(f"{c.where}: {c.type} {c.name!r}: its runout's harmonics sum (k^2 - 1)*amplitude to {lobes:g} m, "
                             f"not below its radius {c.R:g} m: the roll's surface must stay convex (the web would bridge its "
                             "hollows, which is not modelled)")


def _stepwise(r: _Reader, node: Node, what: str) -> float:
    """A stepwise radius, {"merge": angle}: the angle over which the radius the web meets steps by a layer
    [R17], in (0, 360] degrees; returned in radians."""
    o = r.keys(node, what, required=("merge",))
    merge = r.quantity(o["merge"], units.ANGLE, f"{what}.merge", positive=True)
    if merge > 360.0:
        raise r.err(o["merge"], f"{what}.merge = {merge:g} degrees: a merge is at most a turn (360 degrees: the smooth radius)")
    return math.radians(merge)


def _fill_wound(scene):
    """A roll's wound width and density, where the scene leaves them out: its web's width (the span it
    feeds or the span that feeds it), and the density that holds the web's mass per length in a layer
    of the wound thickness (air wound in included), rho_l/(width*thickness), so that the mass the roll
    loses or gains is the mass the web carries ([R3])."""
    for c in scene.parts:
        w = getattr(c, "wound", None)
        if w is None:
            continue
        span = scene.spans_out(c)[0] if c.type == "unwinder" else scene.spans_in(c)[0]
        web = span.wp2
        if w.width is None:
            w.width = web.width
        if w.density is None:
            w.density = web.rho_l / (w.width * w.thickness)


def _traction(r, o, what, wrap) -> Traction:
    """The keys "traction" (friction on the wrap, which needs "wrap") and "nip" of a roller or dancer."""
    t = Traction()
    if "traction" in o:
        tr = r.keys(o["traction"], f"{what}: traction", required=("mu",),
                    optional=("v_slip", "static", "creep", "air", "slip_start"))
        if wrap is None or wrap == 0.0:
            raise r.err(r.key_pos(o["traction"]), f"{what}: traction acts on the web's wrap: give the roller a \"wrap\" angle")
        t.mu = r.quantity(tr["mu"], units.DIMENSIONLESS, f"{what}: traction: mu", nonnegative=True)
        if t.mu > MU_MAX:  # the Roller's traction.mu range: no pair of surfaces grips harder
            raise r.err(tr["mu"], f"{what}: traction: mu = {t.mu:g}: a friction coefficient is 0 to {MU_MAX:g}")
        if "v_slip" in tr:
            t.v_slip = r.quantity(tr["v_slip"], units.SPEED, f"{what}: traction: v_slip", positive=True)
        if "static" in tr:
            t.static = r.quantity(tr["static"], units.DIMENSIONLESS, f"{what}: traction: static", positive=True)
            if t.static < 1.0:
                raise r.err(tr["static"], f"{what}: traction: static {t.static:g}: it is mu_s/mu, the static limit over "
                                          "the kinetic one, and must be >= 1")
        if "creep" in tr:
            t.creep = r.quantity(tr["creep"], units.LENGTH, f"{what}: traction: creep", positive=True)
        if "slip_start" in tr:
            t.slip_start = r.quantity(tr["slip_start"], units.SPEED, f"{what}: traction: slip_start")
            t.slip_start_given = True
        if "air" in tr:
            air = r.keys(tr["air"], f"{what}: traction: air", required=("roughness",), optional=("viscosity",))
            t.roughness = r.quantity(air["roughness"], units.LENGTH, f"{what}: traction: air: roughness", positive=True)
            if "viscosity" in air:
                t.viscosity = r.quantity(air["viscosity"], units.VISCOSITY, f"{what}: traction: air: viscosity", positive=True)
    if "nip" in o:
        nip = r.keys(o["nip"], f"{what}: nip", required=("load", "mu"), optional=("side",))
        t.nip_mu = r.quantity(nip["mu"], units.DIMENSIONLESS, f"{what}: nip: mu", nonnegative=True)
        if t.nip_mu > MU_MAX:
            raise r.err(nip["mu"], f"{what}: nip: mu = {t.nip_mu:g}: a friction coefficient is 0 to {MU_MAX:g}")
        if "side" in nip:
            if nip["side"].value not in NIP_SIDES:
                raise r.err(nip["side"], f"{what}: nip: side {nip['side'].value!r} is not one of {', '.join(map(repr, NIP_SIDES))} "
                                         "(the side of the wrap the nip presses on, in the direction of travel)")
            t.nip_side = nip["side"].value
        t.nip_load = r.profile(nip["load"], units.FORCE, f"{what}: nip: load")
        negative = next(((tk, v) for tk, v in t.nip_load.knots if v < 0), None)
        if negative is not None:
            raise r.err(nip["load"], f"{what}: nip: load {negative[1]:g} N at t = {negative[0]:g} s: a nip presses with a load >= 0")
    return t


def _strain_profile(r, node, what) -> Profile:
    """The strain of the web a source or unwinder feeds: a profile inside STRAIN_RANGE."""
    p = r.profile(node, units.DIMENSIONLESS, f"{what}: strain")
    lo, hi = STRAIN_RANGE
    bad = next((x for _, x in p.knots if not lo < x <= hi), None)
    if bad is not None:
        raise r.err(node, f"{what}: strain {bad:g} is outside ({lo:g}, {hi:g}]: a strain of -1 or less is no web")
    return p


def _wrap(r, o, what):
    """A roller's wrap angle (a load cell), degrees, in [0, 360]."""
    if "wrap" not in o:
        return None
    w = r.quantity(o["wrap"], units.ANGLE, f"{what}: wrap", nonnegative=True)
    if w > 360.0:
        raise r.err(o["wrap"], f"{what}: wrap = {w} degrees is more than a full turn")
    return w


def _at(r, o, what):
    """A part's centre where the scene places it, `"at": [x, y]` (two lengths, y up), for `webline draw`."""
    if "at" not in o:
        return None
    node = o["at"]
    if not isinstance(node.value, list) or len(node.value) != 2:
        raise r.err(node, f"{what}: at must be a list of two lengths [x, y], the centre's position (e.g. [\"1.2 m\", \"0.4 m\"])")
    return tuple(r.quantity(v, units.LENGTH, f"{what}: at[{i}]") for i, v in enumerate(node.value))


def _prescribed(r, o_node, name, kind) -> Prescribed:
    what = f"{kind} {name!r}"
    required = ["type", "name", "speed"] + (["strain"] if kind == "source" else [])
    o = r.keys(o_node, what, required=required, optional=("description", "wrap", "at"))
    c = Prescribed(name=name, type=kind, where=f"{r.source}:{o_node.line}:{o_node.col}")
    c.speed = r.profile(o["speed"], units.SPEED, f"{what}: speed")
    backwards = next(((t, v) for t, v in c.speed.knots if v < 0), None)
    if kind == "source" and backwards is not None:
        raise r.err(o["speed"], f"{what}: speed {backwards[1]:g} m/s at t = {backwards[0]:g} s: a source feeds web into the line, "
                                "so its speed must be >= 0 (web pulled back into a source would carry no defined strain)")
    if kind == "source":
        c.strain = _strain_profile(r, o["strain"], what)
    c.wrap = _wrap(r, o, what)
    c.at = _at(r, o, what)
    return c


def _dancer(r, o_node, name) -> Dancer:
    what = f"dancer {name!r}"
    o = r.keys(
        o_node,
        what,
        required=("type", "name", "J", "R", "mass", "load", "damping", "y_start"),
        optional=("b", "stiffness", "v_start", "description", "wrap", "traction", "nip", "at"),
    )
    U = units
    wrap = _wrap(r, o, what)
    return Dancer(
        name=name,
        type="dancer",
        where=f"{r.source}:{o_node.line}:{o_node.col}",
        J=r.quantity(o["J"], U.INERTIA, f"{what}: J", positive=True),
        R=r.quantity(o["R"], U.LENGTH, f"{what}: R", positive=True),
        b=r.quantity(o["b"], U.ROT_DAMPING, f"{what}: b", nonnegative=True) if "b" in o else 0.0,
        mass=r.quantity(o["mass"], U.MASS, f"{what}: mass", positive=True),
        load=r.profile(o["load"], U.FORCE, f"{what}: load"),
        damping=r.quantity(o["damping"], U.LIN_DAMPING, f"{what}: damping", nonnegative=True),
        stiffness=r.quantity(o["stiffness"], U.STIFFNESS, f"{what}: stiffness", nonnegative=True) if "stiffness" in o else 0.0,
        y_start=r.quantity(o["y_start"], U.LENGTH, f"{what}: y_start", positive=True),
        v_start=r.quantity(o["v_start"], U.SPEED, f"{what}: v_start") if "v_start" in o else None,
        wrap=wrap,
        traction=_traction(r, o, what, wrap) if "traction" in o or "nip" in o else None,
        at=_at(r, o, what),
    )


def _event(r, node, i, scene_line, webs, stop_time) -> Event:
    what = f"events[{i}]"
    o = r.keys(node, what, required=("time", "component", "set"), optional=("description",))
    t = r.quantity(o["time"], units.TIME, f"{what}: time")
    if not 0 < t < stop_time:
        raise r.err(o["time"], f"{what}: time must be inside the run (0, {stop_time} s)")
    cname = r.string(o["component"], f"{what}: component")
    comp = next((c for c in scene_line if c.name == cname), None)
    if comp is None:
        raise r.err(o["component"], f"{what}: no component {cname!r} in the line")
    changes = {}
    if isinstance(comp, Span):
        allowed = ("web", "wp1", "wp2")
    elif getattr(comp, "wound", None) is not None:
        allowed = ("b",)  # J and R move with the roll's web [R3]
    elif getattr(comp, "layon", None) is not None:
        allowed = ("J", "b")
        if isinstance(o["set"].value, Obj) and "R" in o["set"].value:
            raise r.err(o["set"], f"{what}: {comp.type} {cname!r} has a lay-on roller: a new roll (set R) would move its surface "
                                  "under the lay-on's carriage [R18], which is not modelled (J and b may change)")
    elif isinstance(comp, (Roller, Dancer)) and comp.has_fmu:
        allowed = ("J", "R", "b")
    else:
        raise r.err(o["component"], f"{what}: {comp.type} {cname!r} has no properties to change (its inputs are profiles)")
    so = r.keys(o["set"], f"{what}: set", optional=allowed)
    if not so.items:
        raise r.err(o["set"], f"{what}: set is empty (allowed: {', '.join(allowed)})")
    dims = {"J": (units.INERTIA, True), "R": (units.LENGTH, True), "b": (units.ROT_DAMPING, False)}
    for k, v in so.items.items():
        if k in ("web", "wp1", "wp2"):
            changes[k] = _web_ref(r, webs, v, f"{what}: set.{k}")
        else:
            dim, strict = dims[k]
            changes[k] = r.quantity(v, dim, f"{what}: set.{k}", positive=strict, nonnegative=not strict)
    if "web" in changes and ("wp1" in changes or "wp2" in changes):
        raise r.err(o["set"], f"{what}: set either web or wp1/wp2")
    for k, web in changes.items():
        if isinstance(comp, Span) and isinstance(web, Web):
            n = len((comp.wp1 if k == "wp1" else comp.wp2).plies)
            if len(web.plies) != n:
                raise r.err(o["set"], f"{what}: span {cname!r} carries {n} layer(s); web {web.name!r} has {len(web.plies)}: "
                            "a change of web keeps the number of layers (each layer changes to the new web's)")
    return Event(time=t, component=cname, changes=changes, where=f"{r.source}:{node.line}:{node.col}")


def parse_scene(text: str, source: str = "<scene>", fmu_dir=None, base_dir=None) -> Scene:
    """A scene from JSON text; `source` names it in error messages. Solver
    names are checked against the model description of the span FMU in
    `fmu_dir` (see `fmus.span_description`), and webs given by a record are
    looked up in the scene's `web_library` (relative to `base_dir`) and then
    in that FMU's resources/webs.json."""
    try:
        root = jsontree.parse(text, source)
    except jsontree.JsonError as e:
        raise SceneError(str(e)) from None
    r = _Reader(source, fmu_dir)
    o = r.keys(
        root,
        "the scene",
        required=("name", "stop_time", "step", "webs", "line"),
        optional=("description", "events", "record", "web_library", "start"),
    )
    name = r.string(o["name"], "name")
    description = r.string(o["description"], "description") if "description" in o else ""
    stop = r.quantity(o["stop_time"], units.TIME, "stop_time", positive=True)
    step = r.quantity(o["step"], units.TIME, "step", positive=True)
    if step > stop:
        raise r.err(o["step"], f"step {step} s is longer than stop_time {stop} s")

    start = "equilibrium"  # every engine starts alike, as the Line FMU does (docs/scenes.md)
    if "start" in o:
        start = r.string(o["start"], "start")
        if start not in ("equilibrium", "given"):
            raise r.err(o["start"], f"start must be \"equilibrium\" or \"given\", not {start!r}")

    web_library = None
    if "web_library" in o:
        web_library = str((Path(base_dir or ".") / r.string(o["web_library"], "web_library")).resolve())
    webs = _Webs(r, r.obj(o["webs"], "webs"), web_library).read_all()
    if not webs:
        raise r.err(o["webs"], "webs must define at least one web")

    line_node = o["line"]
    if not isinstance(line_node.value, list) or len(line_node.value) < 3:
        raise r.err(line_node, "line must be a list of at least three components: a source, a span and a sink")
    items = line_node.value
    line = []
    branches = []
    raw = {}  # component name -> its JSON node (for messages)
    for i, node in enumerate(items):
        last = i == len(items) - 1
        if i == 0:
            allowed, place = FIRST, "first"
        elif last:
            allowed, place = LAST, "last"
        elif i % 2 == 1:
            allowed, place = ("span",), "at an odd position (after a roller)"
        else:
            allowed, place = MIDDLE, "between two spans"
        c = _component(r, node, f"line[{i}]", allowed, place, raw, webs,
                       "a line is source/unwinder, span, roller/dancer, span, ..., span, sink/winder")
        c.index = i
        line.append(c)
        for kind in ("merge", "split"):
            if isinstance(c, Roller) and kind in node.value:
                branches += _branches(r, node.value[kind], kind, c, raw, webs)
    if len(line) % 2 == 0:
        raise r.err(line_node, "line must end with a sink or a winder after the last span")

    scene = Scene(name=name, description=description, path=source, stop_time=stop, step=step, webs=webs,
                  line=line, events=[], record=[], web_library=web_library, start=start, branches=branches)
    for b in {b.node: b for b in branches}.values():  # once per nip or slitter
        (check_merge if b.kind == "merge" else check_split)(r, scene, b, raw)
    check_layers(r, scene, raw)

    check_traction(r, scene, raw)
    check_loops(r, scene, raw)
    check_runout(r, scene, raw)
    _fill_wound(scene)

    check_dancer_spans(r, scene, raw)
    check_positions(r, scene, raw)

    parts = scene.parts
    events = []
    if "events" in o:
        ev = o["events"]
        if not isinstance(ev.value, list):
            raise r.err(ev, "events must be a list")
        events = [_event(r, n, i, parts, webs, stop) for i, n in enumerate(ev.value)]

    record = []
    if "record" in o:
        rec = o["record"]
        if not isinstance(rec.value, list) or not rec.value:
            raise r.err(rec, "record must be a non-empty list of \"component.quantity\"")
        for n in rec.value:
            s = r.string(n, "record entry")
            cname, _, q = s.partition(".")
            comp = next((c for c in parts if c.name == cname), None)
            if comp is None:
                raise r.err(n, f"record: no component {cname!r} in the line")
            if quantity_unit(comp, q) is None:
                layers = [f"T_{x}" for x in comp.labels] if isinstance(comp, Span) and comp.layered else []
                slip = " (traction's v_web, slip, traction, mu_eff, h_air go with a \"traction\" or \"nip\")" if q in TRACTION_QUANTITIES else ""
                raise r.err(n, f"record: {comp.type} {cname!r} records {', '.join(list(quantities_of(comp)) + layers)}, not {q!r}{slip}")
            record.append((cname, q))
    else:
        record = [(c.name, "T") for c in parts if isinstance(c, Span)] + [(c.name, "v") for c in parts if not isinstance(c, Span)]
        record += [(c.name, "y") for c in parts if isinstance(c, Dancer)]

    scene.events = sorted(events, key=lambda e: e.time)
    scene.record = record
    return scene


def _component(r, node, what, allowed, place, raw, webs, shape):
    """One component of a path: `allowed` kinds at its `place`; its name unique in the scene."""
    co = r.obj(node, what)
    if "type" not in co:
        raise r.err(node, f"{what} needs the key 'type'")
    kind = r.string(co["type"], f"{what}.type")
    if "name" not in co:
        raise r.err(node, f"{what} needs the key 'name'")
    cname = r.string(co["name"], f"{what}.name")
    if "." in cname:
        raise r.err(co["name"], f"{what}: the name {cname!r} must not contain '.'")
    if cname in raw:
        raise r.err(co["name"], f"{what}: the name {cname!r} is used twice")
    raw[cname] = node
    if kind not in allowed:
        raise r.err(co["type"], f"{what} is a {kind!r}, but the component {place} must be one of: {', '.join(allowed)} ({shape})")
    if kind == "span":
        return _span(r, node, cname, webs)
    if kind in ("source", "sink"):
        return _prescribed(r, node, cname, kind)
    if kind == "dancer":
        return _dancer(r, node, cname)
    return _roller(r, node, cname, kind)


def _branches(r, node, kind, roller, raw, webs) -> list:
    """A roller's side paths: "merge" (each from a source or unwinder to the span that meets
    the roller) or "split" (each from the span that leaves the roller to a sink or winder)."""
    what = f"roller {roller.name!r}: {kind}"
    if not isinstance(node.value, list) or not node.value:
        raise r.err(node, f"{what} must be a non-empty list of side paths, each a list of components")
    out = []
    for j, path in enumerate(node.value):
        parts = []
        pw = f"{what}[{j}]"
        if kind == "merge":
            shape = f"a merge path is source/unwinder, span, roller/dancer, span, ..., span: the last span meets {roller.name!r}"
        else:
            shape = f"a split path is span, roller/dancer, span, ..., span, sink/winder: the first span leaves {roller.name!r}"
        if not isinstance(path.value, list) or len(path.value) < 2:
            raise r.err(path, f"{pw} must be a list of at least two components ({shape})")
        n = len(path.value)
        for i, item in enumerate(path.value):
            span_here = i % 2 == (1 if kind == "merge" else 0)
            if span_here:
                allowed, place = ("span",), f"at position {i}"
            elif kind == "merge" and i == 0:
                allowed, place = FIRST, "first"
            elif kind == "split" and i == n - 1:
                allowed, place = LAST, "last"
            else:
                allowed, place = MIDDLE, "between two spans"
            c = _component(r, item, f"{pw}[{i}]", allowed, place, raw, webs, shape)
            c.index = i
            for inner in ("merge", "split"):
                if inner in item.value:
                    raise r.err(r.key_pos(item.value[inner]),
                                f"{c.type} {c.name!r} in a {kind} path of {roller.name!r} carries a {inner}: side paths "
                                "do not branch again (a web that splits or merges on its way to a nip, or after a "
                                "slitter, is not supported)")
            parts.append(c)
        if kind == "merge" and not isinstance(parts[-1], Span):
            raise r.err(path, f"{pw} must end with the span that meets {roller.name!r}, not {parts[-1].type} {parts[-1].name!r}")
        if kind == "split" and isinstance(parts[-1], Span):
            raise r.err(path, f"{pw} must end with a sink or winder after its span {parts[-1].name!r}")
        out.append(Branch(kind, roller.name, parts, f"{r.source}:{path.line}:{path.col}"))
    return out


def load_scene(path, overrides=None, fmu_dir=None) -> Scene:
    """Reads a scene file; `overrides` ({"line.film.L": "2 m", ...}) replace
    values first (the sweep uses them), and errors then name the override."""
    path = Path(path)
    text = path.read_text(encoding="utf-8")
    if not overrides:
        return parse_scene(text, str(path), fmu_dir, path.parent)
    data = json.loads(text)
    for key, value in overrides.items():
        set_path(data, key, value)
    label = f"{path} (with {', '.join(f'{k}={v}' for k, v in overrides.items())})"
    return parse_scene(json.dumps(data, indent=2), label, fmu_dir, path.parent)


def set_path(data, key: str, value):
    """Sets a value by a dotted path and returns the value it replaced. Components of the line are
    named by their name, list entries by their index: "line.film.L",
    "line.nip.drive.speed.ramp.to", "events.0.time", "stop_time"."""
    parts = key.split(".")
    target = data
    for p in parts[:-1]:
        if isinstance(target, list):
            if p.isdigit() and int(p) < len(target):
                target = target[int(p)]
                continue
            match = [c for c in target if isinstance(c, dict) and c.get("name") == p]
            if not match:
                raise SceneError(f"override {key!r}: no component named {p!r} (or index out of range)")
            target = match[0]
        elif isinstance(target, dict) and p in target:
            target = target[p]
        else:
            raise SceneError(f"override {key!r}: {p!r} is not in the scene")
    last = parts[-1]
    if isinstance(target, list):
        if not (last.isdigit() and int(last) < len(target)):
            raise SceneError(f"override {key!r}: {last!r} is not an index of the list there")
        old, target[int(last)] = target[int(last)], value
        return old
    if not isinstance(target, dict):
        raise SceneError(f"override {key!r}: the path does not lead to an object")
    if last not in target:
        raise SceneError(f"override {key!r}: the scene has no {last!r} there (an override replaces a value, it adds none)")
    old, target[last] = target[last], value
    return old
