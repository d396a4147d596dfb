"""Scenes: a web line described in JSON, read strictly.

A scene is a chain, source -> span -> roller -> span -> ... -> sink, with
the webs the spans carry, input profiles, the communication step, the stop
time, events (properties that change on the fly) and the outputs to record.
The format is documented in docs/scenes.md. Every problem is a
`SceneError` whose message starts with `file:line:column` of the offending
key or value: an unknown key, a missing value, a wrong unit, a chain that is
not a line.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path

from . import jsontree, records, units
from .fmus import DEFAULT_FMU_DIR, SPAN_FMU, enumeration, span_description, span_effects
from .jsontree import Node, Obj
from .profiles import Profile
from .units import UnitError

import numpy as np
from scipy.optimize import brentq

FIRST = ("source", "unwinder")
MIDDLE = ("roller", "dancer")
LAST = ("sink", "winder")

# What can be recorded from each kind of component: quantity -> unit.
QUANTITIES = {
    "span": {"T": "N", "eps": "1", "L": "m", "F_a": "N", "F_b": "N"},
    "source": {"v": "m/s", "eps": "1"},
    "sink": {"v": "m/s"},
    "roller": {"v": "m/s", "omega": "rad/s", "tau": "N.m"},
    "unwinder": {"v": "m/s", "omega": "rad/s", "tau": "N.m"},
    "winder": {"v": "m/s", "omega": "rad/s", "tau": "N.m"},
    "dancer": {"v": "m/s", "omega": "rad/s", "y": "m", "y_dot": "m/s"},
}


class SceneError(ValueError):
    """A scene that cannot be used; the message names the file position."""


# ---------------------------------------------------------------- the model


@dataclass(frozen=True)
class Web:
    name: str
    E: float
    thickness: float
    width: float
    density: float
    d_r: float = 0.0
    # A web given by a record: the span FMU is set up with the record's name
    # (its own reader); the line reference evaluates the record's curve.
    record: str | None = None
    curve: records.Curve | None = field(default=None, compare=False)

    @property
    def area(self):
        return self.width * self.thickness

    @property
    def EA(self):
        return self.E * self.area

    @property
    def rho_l(self):
        return self.density * self.area


@dataclass
class Drive:
    """How a roller is driven: 'idler' (no torque), 'torque', 'tension' (an
    end roller's motor holds a tension: tau = -R*T at an unwinder, +R*T at a
    winder) or 'speed' (an ideal speed drive: the surface speed follows the
    profile; no Roller FMU)."""

    kind: str
    profile: Profile | None = None


@dataclass
class Component:
    name: str
    type: str
    index: int = 0  # position in the chain
    where: str = ""  # file:line:col of its object


@dataclass
class Span(Component):
    length: float | None = None  # None: from the dancer next to it
    wp1: Web | None = None
    wp2: Web | None = None
    effects: frozenset = frozenset()
    eps_start: float | None = None  # None: start at equilibrium
    solver: str = "auto"
    tolerance: float | None = None
    substeps: int | None = None


@dataclass
class Prescribed(Component):
    """A source or sink: speed (and, for a source, strain) from profiles."""

    speed: Profile | None = None
    strain: Profile | None = None
    wrap: float | None = None


@dataclass
class Roller(Component):
    """A roller, unwinder or winder (Roller FMU unless speed-driven)."""

    J: float | None = None
    R: float | None = None
    b: float = 0.0
    v_start: float | None = None
    drive: Drive = field(default_factory=lambda: Drive("idler"))
    strain: Profile | None = None  # unwinder: strain of the web leaving the roll
    wrap: float | None = None  # degrees: a load cell on its bearings (Line FMU output <name>.F)

    @property
    def has_fmu(self):
        return self.drive.kind != "speed"


@dataclass
class Dancer(Component):
    """A dancer: a roller (Roller FMU) on a carriage loaded with a force.
    The two spans next to it hang from it: their length is the carriage
    position y; m*y'' = load - F_a - F_b - damping*y' - stiffness*(y - y_start), F_a and F_b the
    tensions of the spans before and after."""

    J: float = 0.0
    R: float = 0.0
    b: float = 0.0
    mass: float = 0.0
    load: Profile | None = None
    damping: float = 0.0
    stiffness: float = 0.0
    y_start: float = 0.0
    v_start: float | None = None
    wrap: float | None = None

    has_fmu = True


@dataclass
class Event:
    time: float
    component: str
    changes: dict  # key -> value (Web for web keys, float otherwise)
    where: str = ""


@dataclass
class Scene:
    name: str
    description: str
    path: str
    stop_time: float
    step: float
    webs: dict
    line: list
    events: list
    record: list  # [(component name, quantity)]
    web_library: str | None = None  # absolute path of the scene's own web records
    # "equilibrium": the line starts in its steady state for the drives at t = 0
    # (reference, webline run, Line FMU); "given": from the start values; None: not said
    # (the parts' start values; the Line FMU's default is equilibrium).
    start: str | None = None

    def component(self, name):
        return next(c for c in self.line if c.name == name)

    @property
    def spans(self):
        return [c for c in self.line if isinstance(c, Span)]

    @property
    def nodes(self):
        return [c for c in self.line if not isinstance(c, Span)]

    def upstream(self, span):
        return self.line[span.index - 1]

    def downstream(self, span):
        return self.line[span.index + 1]

    def span_before(self, node):
        return self.line[node.index - 1] if node.index > 0 else None

    def span_after(self, node):
        return self.line[node.index + 1] if node.index + 1 < len(self.line) else None

    def speed_profile(self, node):
        """The prescribed speed of a node, or None if it has dynamics."""
        if isinstance(node, Prescribed):
            return node.speed
        if isinstance(node, Roller) and node.drive.kind == "speed":
            return node.drive.profile
        return None

    def initial_speed(self, node):
        """Surface speed at the start: prescribed, v_start, or the default
        (the initial speed of the first speed-driven component, else 0)."""
        profile = self.speed_profile(node)
        if profile is not None:
            return profile.value(0.0)
        if node.v_start is not None:
            return node.v_start
        for other in self.nodes:
            p = self.speed_profile(other)
            if p is not None:
                return p.value(0.0)
        return 0.0

    def torque_profile(self, node):
        """The motor torque of a Roller-FMU node as a profile (N m)."""
        d = getattr(node, "drive", Drive("idler"))
        if d.kind == "torque":
            return d.profile
        if d.kind == "tension":
            sign = -1.0 if node.type == "unwinder" else 1.0
            return d.profile.scaled(sign * node.R)
        return Profile.constant(0.0)

    def breakpoints(self):
        """Every time a profile kinks or jumps, and every event time, in (0, stop)."""
        times = set()
        for c in self.line:
            for p in profiles_of(c):
                times.update(p.breakpoints())
        times.update(e.time for e in self.events)
        return sorted(t for t in times if 0.0 < t < self.stop_time)

    def columns(self):
        """The recorded columns: 'name.quantity [unit]'."""
        return [f"{c}.{q} [{QUANTITIES[self.component(c).type][q]}]" for c, q in self.record]


def profiles_of(c):
    out = []
    for attr in ("speed", "strain", "load"):
        p = getattr(c, attr, None)
        if isinstance(p, Profile):
            out.append(p)
    d = getattr(c, "drive", None)
    if d is not None and d.profile is not None:
        out.append(d.profile)
    return out


# ---------------------------------------------------------------- reading


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
        kinds = ("constant", "step", "ramp", "table")
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


def _web(r: _Reader, name: str, node: Node, web_library) -> Web:
    what = f"web {name!r}"
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


def _strain_at(web: Web, tension: float) -> float:
    """The strain at which the web carries `tension` (N) at rest."""
    if web.curve is None:
        return tension / web.EA
    stress = tension / web.area
    # sigma is non-decreasing and linear beyond the table: bracket, then solve.
    lo, hi = -0.5, 1.0
    return brentq(lambda e: float(web.curve.sigma(e)) - stress, lo, hi, xtol=1e-16, rtol=4 * np.finfo(float).eps)


def _web_ref(r: _Reader, webs: dict, node: Node, what: str) -> Web:
    name = r.string(node, what)
    if name not in webs:
        raise r.err(node, f"{what}: no web {name!r} in \"webs\" (defined: {', '.join(webs) or 'none'})")
    return webs[name]


def _drive(r: _Reader, node: Node, what: str, kinds) -> Drive:
    o = r.obj(node, what)
    if len(o.items) != 1 or next(iter(o.keys())) not in kinds:
        raise r.err(node, f"{what} must be an object with one key of {', '.join(kinds)}")
    kind, body = next(iter(o.items.items()))
    dim = {"torque": units.TORQUE, "tension": units.FORCE, "speed": units.SPEED}[kind]
    return Drive(kind, r.profile(body, dim, f"{what}.{kind}"))


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
        s.eps_start = _strain_at(s.wp2, r.quantity(o["T_start"], units.FORCE, f"{what}: T_start"))
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
    optional = ["J", "R", "b", "v_start", "drive", "description", "wrap"]
    required = ["type", "name"]
    if kind == "unwinder":
        required.append("strain")
    o = r.keys(o_node, what, required=required, optional=optional)
    c = Roller(name=name, type=kind, where=f"{r.source}:{o_node.line}:{o_node.col}")
    drives = {"roller": ("torque", "speed"), "unwinder": ("torque", "tension", "speed"), "winder": ("torque", "tension", "speed")}
    if "drive" in o:
        c.drive = _drive(r, o["drive"], f"{what}: drive", drives[kind])
    if c.drive.kind == "speed":
        for k in ("J", "R", "b", "v_start"):
            if k in o:
                raise r.err(r.key_pos(o[k]), f"{what}: {k} is not used: a speed-driven roller follows its speed profile exactly (no Roller FMU)")
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
        c.strain = r.profile(o["strain"], units.DIMENSIONLESS, f"{what}: strain")
    c.wrap = _wrap(r, o, what)
    return c


def _wrap(r, o, what):
    """A roller's wrap angle (a load cell), degrees, in [0, 360]."""
    if "wrap" not in o:
        return None
    w = r.quantity(o["wrap"], units.ANGLE, f"{what}: wrap", nonnegative=True)
    if w > 360.0:
        raise r.err(o["wrap"], f"{what}: wrap = {w} degrees is more than a full turn")
    return w


def _prescribed(r, o_node, name, kind) -> Prescribed:
    what = f"{kind} {name!r}"
    required = ["type", "name", "speed"] + (["strain"] if kind == "source" else [])
    o = r.keys(o_node, what, required=required, optional=("description", "wrap"))
    c = Prescribed(name=name, type=kind, where=f"{r.source}:{o_node.line}:{o_node.col}")
    c.speed = r.profile(o["speed"], units.SPEED, f"{what}: speed")
    if kind == "source":
        c.strain = r.profile(o["strain"], units.DIMENSIONLESS, f"{what}: strain")
    c.wrap = _wrap(r, o, what)
    return c


def _dancer(r, o_node, name) -> Dancer:
    what = f"dancer {name!r}"
    o = r.keys(
        o_node,
        what,
        required=("type", "name", "J", "R", "mass", "load", "damping", "y_start"),
        optional=("b", "stiffness", "v_start", "description", "wrap"),
    )
    U = units
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
        wrap=_wrap(r, o, what),
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

    start = None
    if "start" in o:
        start = r.string(o["start"], "start")
        if start not in ("equilibrium", "given"):
            raise r.err(o["start"], f"start must be \"equilibrium\" or \"given\", not {start!r}")

    web_library = None
    if "web_library" in o:
        web_library = str((Path(base_dir or ".") / r.string(o["web_library"], "web_library")).resolve())
    webs_obj = r.obj(o["webs"], "webs")
    webs = {k: _web(r, k, v, web_library) for k, v in webs_obj.items.items()}
    if not webs:
        raise r.err(o["webs"], "webs must define at least one web")

    line_node = o["line"]
    if not isinstance(line_node.value, list) or len(line_node.value) < 3:
        raise r.err(line_node, "line must be a list of at least three components: a source, a span and a sink")
    items = line_node.value
    line = []
    names = set()
    for i, node in enumerate(items):
        co = r.obj(node, f"line[{i}]")
        if "type" not in co:
            raise r.err(node, f"line[{i}] needs the key 'type'")
        kind = r.string(co["type"], f"line[{i}].type")
        if "name" not in co:
            raise r.err(node, f"line[{i}] needs the key 'name'")
        cname = r.string(co["name"], f"line[{i}].name")
        if "." in cname:
            raise r.err(co["name"], f"line[{i}]: the name {cname!r} must not contain '.'")
        if cname in names:
            raise r.err(co["name"], f"line[{i}]: the name {cname!r} is used twice")
        names.add(cname)
        last = i == len(items) - 1
        if i == 0:
            allowed = FIRST
        elif last:
            allowed = LAST
        elif i % 2 == 1:
            allowed = ("span",)
        else:
            allowed = MIDDLE
        if kind not in allowed:
            place = "first" if i == 0 else "last" if last else "at an odd position (after a roller)" if i % 2 else "between two spans"
            raise r.err(
                co["type"],
                f"line[{i}] is a {kind!r}, but the component {place} must be one of: {', '.join(allowed)} "
                "(a line is source/unwinder, span, roller/dancer, span, ..., span, sink/winder)",
            )
        if kind == "span":
            c = _span(r, node, cname, webs)
        elif kind in ("source", "sink"):
            c = _prescribed(r, node, cname, kind)
        elif kind == "dancer":
            c = _dancer(r, node, cname)
        else:
            c = _roller(r, node, cname, kind)
        c.index = i
        line.append(c)
    if len(line) % 2 == 0:
        raise r.err(line_node, "line must end with a sink or a winder after the last span")

    # Spans next to a dancer take their length from it; no other span may.
    for i, c in enumerate(line):
        if not isinstance(c, Span):
            continue
        node = items[i]
        next_to_dancer = isinstance(line[i - 1], Dancer) or isinstance(line[i + 1], Dancer)
        if next_to_dancer:
            if "variableLength" not in c.effects:
                raise r.err(node, f"span {c.name!r} hangs from a dancer: it needs the effect variableLength")
            if c.length is not None:
                raise r.err(r.key_pos(node.value["L"]), f"span {c.name!r}: L comes from the dancer's position, do not give it")
            if isinstance(line[i - 1], Dancer) and isinstance(line[i + 1], Dancer):
                raise r.err(node, f"span {c.name!r} between two dancers is not supported")
        else:
            if "variableLength" in c.effects:
                raise r.err(node, f"span {c.name!r}: variableLength needs a dancer next to the span")
            if c.length is None:
                raise r.err(node, f"span {c.name!r} needs the key 'L'")
        if c.solver == "exact" and next_to_dancer:
            raise r.err(node, f"span {c.name!r}: solver exact holds the length; a span on a dancer needs auto or rosenbrock")

    events = []
    if "events" in o:
        ev = o["events"]
        if not isinstance(ev.value, list):
            raise r.err(ev, "events must be a list")
        events = [_event(r, n, i, line, webs, stop) for i, n in enumerate(ev.value)]

    record = []
    if "record" in o:
        rec = o["record"]
        if not isinstance(rec.value, list) or not rec.value:
            raise r.err(rec, "record must be a non-empty list of \"component.quantity\"")
        for n in rec.value:
            s = r.string(n, "record entry")
            cname, _, q = s.partition(".")
            comp = next((c for c in line if c.name == cname), None)
            if comp is None:
                raise r.err(n, f"record: no component {cname!r} in the line")
            if q not in QUANTITIES[comp.type]:
                raise r.err(n, f"record: a {comp.type} records {', '.join(QUANTITIES[comp.type])}, not {q!r}")
            record.append((cname, q))
    else:
        record = [(c.name, "T") for c in line if isinstance(c, Span)] + [(c.name, "v") for c in line if not isinstance(c, Span)]
        record += [(c.name, "y") for c in line if isinstance(c, Dancer)]

    return Scene(
        name=name,
        description=description,
        path=source,
        stop_time=stop,
        step=step,
        webs=webs,
        line=line,
        events=sorted(events, key=lambda e: e.time),
        record=record,
        web_library=web_library,
        start=start,
    )


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
    """Sets a value by a dotted path. Components of the line are named by
    their name, list entries by their index: "line.film.L",
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
        target[int(last)] = value
        return
    if not isinstance(target, dict):
        raise SceneError(f"override {key!r}: the path does not lead to an object")
    if last not in target:
        raise SceneError(f"override {key!r}: the scene has no {last!r} there (an override replaces a value, it adds none)")
    target[last] = value
