"""The scene's model: the webs, the parts of a line with their drives, and the Scene that joins
them, as reading.py builds them from the JSON and checks.py holds them to the line's rules."""

from __future__ import annotations

import re
from dataclasses import dataclass, field, replace
from functools import cached_property

from .. import records
from ..profiles import Profile

# What can be recorded from each kind of component: quantity -> unit.
QUANTITIES = {
    "span": {"T": "N", "eps": "1", "L": "m", "F_a": "N", "F_b": "N"},
    "source": {"v": "m/s", "eps": "1"},
    "sink": {"v": "m/s"},
    "roller": {"v": "m/s", "omega": "rad/s", "tau": "N.m"},
    "unwinder": {"v": "m/s", "omega": "rad/s", "tau": "N.m", "r": "m"},
    "winder": {"v": "m/s", "omega": "rad/s", "tau": "N.m", "r": "m"},
    "dancer": {"v": "m/s", "omega": "rad/s", "y": "m", "y_dot": "m/s"},
}
# What a roller or dancer the web may slip on records besides (docs/physics.md, "Rollers that slip").
TRACTION_QUANTITIES = {"v_web": "m/s", "slip": "m/s", "traction": "1", "mu_eff": "1", "h_air": "m"}


# What a roller with a wrap records besides: its load cell (docs/physics.md, "A load cell").
LOAD_CELL_QUANTITIES = {"F": "N"}

# What a winder with a lay-on roller records besides (docs/physics.md, "A lay-on roller", [R18]): the nip's
# force and compression, the carriage's position and speed, the roller's spin (the Roller's outputs).
LAYON_QUANTITIES = {"layon.N": "N", "layon.delta": "m", "layon.x": "m", "layon.v": "m/s", "layon.omega": "rad/s"}


def quantities_of(c) -> dict:
    """What a component records: its type's quantities, where the web may slip the traction's, a
    roller's load cell where it has a wrap (every quantity a loop may measure), a lay-on roller's."""
    return {**QUANTITIES[c.type], **(TRACTION_QUANTITIES if getattr(c, "traction", None) is not None else {}),
            **(LOAD_CELL_QUANTITIES if getattr(c, "wrap", None) else {}),
            **(LAYON_QUANTITIES if getattr(c, "layon", None) is not None else {})}


class SceneError(ValueError):
    """A scene that cannot be used; the message names the file position."""


# A strain the span FMU accepts: (-1, 10] (its eps_start and web_a.eps).
STRAIN_RANGE = (-1.0, 10.0)


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
    # A laminate: its layers, each a web of its own, laminates among them flattened, each layer's density
    # carrying its share of the adhesive (docs/merge-split.md, [M6]); () for a web of one layer.
    layers: tuple = ()

    @property
    def area(self):
        return self.width * self.thickness

    @property
    def EA(self):
        return self.E * self.area

    @property
    def rho_l(self):
        return self.density * self.area

    @property
    def plies(self) -> tuple:
        """The webs that carry its tension side by side: a laminate's layers, else the web itself."""
        return self.layers or (self,)

    @property
    def layer_names(self) -> tuple:
        return tuple(w.name for w in self.layers)

    def strain_at(self, tension: float) -> float:
        """The strain at which the web carries `tension` (N) at rest."""
        return tension / self.EA if self.curve is None else self.curve.strain_at_stress(tension / self.area)

    @classmethod
    def laminate(cls, name: str, webs: list, compression: float = 1.0, adhesive: float = 0.0) -> Web:
        """The laminate of `webs` (their layers, laminates among them flattened to theirs, each keeping its
        own E, thickness, d_r and strain, [M6]), pressed by `compression` with `adhesive` (kg/m^2) between
        them: the adhesive's mass shared among the layers' densities in proportion to their mass, so that it
        adds mass and no stiffness. Its own values are the law of mixtures (docs/merge-split.md, [M3]):
        thickness the webs' sum times the compression factor (what a winder's roll grows by); E and density
        over that thickness so that E*A and the mass per length add; d_r weighted by E*A, as Kelvin–Voigt
        elements in parallel combine."""
        layers = [w for web in webs for w in web.plies]
        h = compression * sum(w.thickness for w in webs)
        EA = sum(w.EA for w in webs)
        mass = sum(w.density * w.thickness for w in webs)  # per width: the layers' and their own adhesives'
        share = (mass + adhesive) / mass
        return cls(
            name=name,
            E=sum(w.E * w.thickness for w in webs) / h,
            thickness=h,
            width=layers[0].width,
            density=(mass + adhesive) / h,
            d_r=sum(w.EA * w.d_r for w in webs) / EA,
            # A layer's values one by one (its record's name would give the FMU the record's density).
            layers=tuple(replace(w, density=w.density * share, record=None) for w in layers),
        )


# A layer's label names its outputs (`NAME.T_<label>`) and its span's parts in the Line FMU (`NAME.<label>`):
# the web's name with every character but a letter, a digit or _ as _, numbered _1, _2, ... where a
# web is a layer twice; these would shadow the laminate's own outputs.
LABEL_TAKEN = ("T", "eps", "L", "F_a", "F_b", "length")


def layer_labels(web: Web) -> list[str]:
    """The labels of a web's layers, in its order (docs/merge-split.md, "Outputs")."""
    names = [re.sub(r"[^A-Za-z0-9_]", "_", w.name) for w in web.plies]
    names = ["_" + n if n[0].isdigit() else n for n in names]
    seen = {}
    out = []
    for n in names:
        if names.count(n) > 1:
            seen[n] = seen.get(n, 0) + 1
            n = f"{n}_{seen[n]}"
        out.append(n)
    return out


def span_layers(wp1: Web, wp2: Web) -> list[tuple[Web, Web]]:
    """A span's layers as (web arriving, web in the span) pairs: one pair for a plain span."""
    return list(zip(wp1.plies, wp2.plies))


# A powder brake's speed scale [R12]: the damping of its grip and its Stribeck speed (docs/physics.md).
BRAKE_V_SLIP = 0.01  # m/s
# The presliding displacements (the bristle's creep, docs/physics.md "Contacts that stick"): the web's travel
# over a traction contact, and a brake's surface travel, that loads its grip from 0 to the kinetic limit.
TRACTION_CREEP = 5e-8  # m
BRAKE_CREEP = 1e-6  # m


@dataclass
class DancerLoop:
    """A dancer position loop [R13]: a PI on dancer `dancer`'s carriage position y against `set` (m) whose
    output, a speed (gains in m/s per m and m/s per m.s), trims a speed loop's reference; `sign` +1 where
    the dancer is upstream of the drive (a longer loop of web stored calls for more speed), -1 downstream."""

    dancer: str
    set: float
    kp: float
    ki: float
    sign: float = 1.0


@dataclass
class Loop:
    """A PI loop in a drive ([R10]-[R11] of the physics docs): the torque that holds a span's tension
    (`measure` = (span, "T")) or a load cell's (roller, "F") at `set`; gains in SI (N.m per N,
    N.m per N.s); the motor's torque `limit` (N.m, 0: none) and `lag` (s, 0: none); with
    `feedforward` the torque J*d(v_ref/R)/dt of the line's speed reference (its first speed drive)."""

    measure: tuple | None  # None: a speed loop, on the roller's own surface speed
    set: Profile  # a force, or a speed loop's reference speed
    kp: float
    ki: float
    limit: float = 0.0
    lag: float = 0.0
    feedforward: bool = False
    sign: float = 1.0  # +1: more torque raises the measured force (it is upstream of the drive), -1: lowers it
    set_input: bool = False  # the set point is the Line FMU's input <name>.T_set (<name>.v_ref), starting at `set`
    sample: float = 0.0  # a zero-order hold's period on the loop's command (s, 0: continuous) [R14]
    delay: float = 0.0  # each sample applied this much later (s, at most `sample`)
    dancer: DancerLoop | None = None  # a speed loop's reference trimmed by a dancer's position loop [R13]
    compression: bool = False  # a set point <= 0 N is meant: the loop holds the span in compression

    @property
    def speed(self) -> bool:
        """A speed loop: a real motor holds the surface speed at `set` (N.m per m/s, N.m per m)."""
        return self.measure is None


@dataclass
class Drive:
    """How a roller is driven: 'idler' (no torque), 'torque', 'tension' (an
    end roller's motor holds a tension: tau = -R*T at an unwinder, +R*T at a
    winder), 'speed' (an ideal speed drive: the surface speed follows the
    profile; no Roller FMU), 'pi' (a tension loop, `loop`), 'speed loop' (a real motor's, `loop`)
    or 'brake' (a powder brake: -B*g_b, B the profile, g_b its grip's law, [R12]; `creep` its delta_b)."""

    kind: str
    profile: Profile | None = None
    loop: Loop | None = None
    input: bool = False  # an ideal speed drive on the Line FMU's input <name>.v_ref, `profile` its start value
    creep: float = BRAKE_CREEP  # a brake's presliding surface travel, m
    taper: float = 0.0  # a winder's tension taper k [R16]: T(r) = T0 (1 - k (1 - R/r)), T0 the profile


# The sides of the wrap a nip may press on, in the direction of travel (web_a to web_b), each at the
# index that is its value of the Roller's nip.side [R7].
NIP_SIDES = ("entry", "exit")


@dataclass
class Traction:
    """Where the web may slip on a roller or dancer [R6]-[R8]: friction on the wrap (mu, with the
    roller's wrap angle), at a nip (nip_mu, pressed with nip_load, on the wrap's nip_side), under an air
    film (roughness)."""

    mu: float = 0.0
    v_slip: float = 1e-3  # the grip's damping and Stribeck speed
    static: float = 1.0  # k_s = mu_s/mu >= 1, the static limit over the kinetic one
    creep: float = TRACTION_CREEP  # the presliding displacement delta, m
    roughness: float = 0.0
    viscosity: float = 1.81e-5
    nip_mu: float = 0.0
    nip_load: Profile | None = None
    nip_side: str = "entry"  # the side of the wrap the nip presses on, one of NIP_SIDES
    slip_start: float = 0.0  # the web's speed over the roller at a given start, minus the surface's
    slip_start_given: bool = False  # the scene set slip_start (refused under an equilibrium start)


@dataclass
class Wound:
    """The web an unwinder's roll loses or a winder's gains [R3]: the roll's radius and inertia move
    with it. thickness is the build-up per turn (the web's caliper plus the air wound in with it) of
    unstretched web: the roll counts the web's unstretched length;
    width defaults to the roll's web's, density to the web's mass per length over width*thickness
    (None until the line is read)."""

    thickness: float
    density: float | None = None
    width: float | None = None
    merge: float = 0.0  # a stepwise radius [R17]: the angle (rad) over which it steps by a layer; 0: smooth


# The out-of-round harmonics a roll may have: the Roller's slots runout.h1 ... runout.h4.
HARMONICS = 4


@dataclass
class Runout:
    """An unwinder's or winder's roll whose surface, a circle of its radius, turns about an axis
    `eccentricity` (m) off its centre [R15]; `phase` (rad) is the centre's angle from the web's side
    at the start, in the roll's sense of turning (docs/physics.md, "A roll with runout"). `harmonics`:
    an out-of-round surface's, (order k >= 2, amplitude m, phase rad) each, of its support function."""

    eccentricity: float
    phase: float = 0.0
    harmonics: tuple = ()


@dataclass
class LayOn:
    """A lay-on roller pressed against a winder by `load` (N, a profile) [R18]: its carriage's moving mass
    (kg), the nip's stiffness (N/m) and damping (N s/m), the roller's radius (m), inertia (kg m^2) and
    bearing (N m s), the nip's friction mu and its slip speed (m/s), and `angle` (rad), the carriage's
    line from the web's side in the roll's sense of turning (docs/physics.md, "A lay-on roller").
    The defaults are the Roller FMU's start values."""

    mass: float
    stiffness: float
    damping: float
    radius: float
    load: Profile
    inertia: float = 0.05
    bearing: float = 1e-3
    mu: float = 0.5
    v_slip: float = 1e-3
    angle: float = 0.0


@dataclass
class Component:
    name: str
    type: str
    index: int = 0  # position in the chain
    where: str = ""  # file:line:col of its object


@dataclass
class Node(Component):
    """A part the web runs over (every component but a span): `at` is its centre where the scene places
    it ("at", metres; None: `webline draw` lays it out)."""

    at: tuple | None = None


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

    @property
    def layered(self) -> bool:
        """It carries a laminate of several layers, each with its own strain ([M6])."""
        return len(self.wp2.plies) > 1

    @property
    def labels(self) -> list[str]:
        """Its layers' labels (its web at the start names them)."""
        return layer_labels(self.wp2)


@dataclass
class Prescribed(Node):
    """A source or sink: speed (and, for a source, strain) from profiles."""

    speed: Profile | None = None
    strain: Profile | None = None
    wrap: float | None = None


@dataclass
class Roller(Node):
    """A roller, unwinder or winder (Roller FMU unless speed-driven)."""

    J: float | None = None
    R: float | None = None
    b: float = 0.0
    v_start: float | None = None
    drive: Drive = field(default_factory=lambda: Drive("idler"))
    strain: Profile | None = None  # unwinder: strain of the web leaving the roll
    wrap: float | None = None  # degrees: a load cell on its bearings (Line FMU output <name>.F), the wrap traction acts on
    trim: float = 0.0  # a slitter: the width cut off as trim (m), which leaves without tension
    traction: Traction | None = None  # the web may slip on it
    wound: Wound | None = None  # an unwinder's or winder's roll that changes as web winds off or on
    runout: Runout | None = None  # an unwinder's or winder's roll off its axis [R15]
    layon: LayOn | None = None  # a winder's lay-on roller [R18]

    @property
    def has_fmu(self):
        return self.drive.kind != "speed"


@dataclass
class Dancer(Node):
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
    traction: Traction | None = None

    has_fmu = True


@dataclass
class Branch:
    """Side path of a roller on the main line. "merge": webs that meet at the
    roller (a nip): parts = [source|unwinder, span, (roller, span)*], the last
    span ending at the nip. "split": webs the roller cuts the web into (a
    slitter): parts = [span, (roller, span)*, sink|winder], the first span
    starting at the slitter."""

    kind: str  # "merge" | "split"
    node: str  # the roller on the main line
    parts: list  # one side path
    where: str = ""


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
    # "equilibrium" (the default): every engine starts the line in its steady state for the drives
    # at t = 0; "given": from the parts' start values.
    start: str = "equilibrium"
    branches: list = field(default_factory=list)  # merges and splits (Branch), in line order

    @property
    def parts(self):
        """Every component, main line and side paths, in the order the web flows: a merge's
        side paths just before their nip, a split's just after its slitter."""
        out = []
        for c in self.line:
            out += [p for b in self.branches if b.node == c.name and b.kind == "merge" for p in b.parts]
            out.append(c)
            out += [p for b in self.branches if b.node == c.name and b.kind == "split" for p in b.parts]
        return out

    @cached_property
    def _links(self):
        """(up, down, ins, outs): each span's roller before and after it, each roller's spans
        coming in and going out (several at a nip or a slitter)."""
        up, down, ins, outs = {}, {}, {}, {}
        paths = [(self.line, None, None)] + [
            (b.parts, self.component(b.node), b.kind) for b in self.branches]
        for parts, node, kind in paths:
            chain = parts + [node] if kind == "merge" else [node] + parts if kind == "split" else parts
            for a, b in zip(chain[:-1], chain[1:]):
                if isinstance(b, Span):
                    up[b.name] = a
                    outs.setdefault(a.name, []).append(b)
                else:
                    down[a.name] = b
                    ins.setdefault(b.name, []).append(a)
        return up, down, ins, outs

    def component(self, name):
        return next(c for c in self.parts if c.name == name)

    def part_type(self, name) -> str:
        """The type of a part, named as its FMU component: a laminate's layer `NAME.<label>` is its span's."""
        return self.component(name.split(".")[0]).type

    @property
    def spans(self):
        return [c for c in self.parts if isinstance(c, Span)]

    @property
    def nodes(self):
        return [c for c in self.parts if not isinstance(c, Span)]

    def upstream(self, span):
        return self._links[0][span.name]

    def downstream(self, span):
        return self._links[1][span.name]

    def spans_in(self, node):
        """The spans that end at a roller: one, none at the line's start, several at a nip."""
        return self._links[2].get(node.name, [])

    def spans_out(self, node):
        """The spans that start at a roller: one, none at the line's end, several at a slitter."""
        return self._links[3].get(node.name, [])

    def inlet_masses(self, node, web_of=None):
        """The masses per unstretched length m_i = rho_i*A_i of the webs arriving at `node`, in port
        order (the main line's first, then the side paths', each span's layers in its order): the
        weights of a merge into a web of one layer ([M1], the Roller's [R5]). Each is the web its span
        carries at its end (wp2), or `web_of(span)` (the reference's, after an event changed it). The
        reference and the FMUs' compiler both take them from here."""
        return [w.rho_l for sp in self.spans_in(node) for w in (web_of(sp) if web_of else sp.wp2).plies]

    def layer_sources(self, span) -> list[tuple]:
        """Where each layer of a laminate span after a nip comes from ([M6]): per layer, in the span's
        order, (the span that brings it to the nip, its layer there). Matched by web: a web that is
        a layer twice takes its arriving webs in port order."""
        pool = [(sp, i, w.name) for sp in self.spans_in(self.upstream(span)) for i, w in enumerate(sp.wp2.plies)]
        out = []
        for w in span.wp1.plies:
            k = next(j for j, (_, _, name) in enumerate(pool) if name == w.name)
            sp, i, _ = pool.pop(k)
            out.append((sp, i))
        return out

    def span_before(self, node):
        return _single(self.spans_in(node), node, "merges webs")

    def span_after(self, node):
        return _single(self.spans_out(node), node, "splits the web")

    def speed_profile(self, node):
        """The prescribed speed of a node, or None if it has dynamics."""
        if isinstance(node, Prescribed):
            return node.speed
        if isinstance(node, Roller) and node.drive.kind == "speed":
            return node.drive.profile
        return None

    def initial_speed(self, node, t=0.0):
        """Surface speed at the start: prescribed, v_start, or the default (the initial speed
        of the first speed-driven component, else 0). At a later time t (an operating point
        of the run): prescribed, else the first speed-driven component's, else as at the start."""
        profile = self.speed_profile(node)
        if profile is not None:
            return profile.value(t)
        if node.v_start is not None and t == 0.0:
            return node.v_start
        for other in [node] + self.nodes:  # a speed loop starts at its reference
            p = self.speed_or_reference(other)
            if p is not None:
                return p.value(t)
        return node.v_start or 0.0

    def speed_times(self):
        """The operating points that span the run's speed range: the start, and the first times in
        [0, stop) the prescribed speeds are at their slowest and at their fastest (summed over the
        speed-driven parts; a piecewise linear profile reaches its extremes at its knots)."""
        profiles = [self.speed_profile(c) for c in self.nodes if self.speed_profile(c) is not None]
        knots = sorted({0.0} | {t for p in profiles for t in p.breakpoints() if 0.0 < t < self.stop_time})
        total = [sum(abs(p.value(t)) for p in profiles) for t in knots]
        picked = [0.0, knots[total.index(min(total))], knots[total.index(max(total))]]
        return sorted(set(picked))

    def speed_reference(self):
        """The line's speed reference: the profile of its first speed-driven part or speed loop (None: it
        has none)."""
        return next((p for p in map(self.speed_or_reference, self.nodes) if p is not None), None)

    def input_reference(self):
        """The part whose input <name>.v_ref of the Line FMU is the line's speed reference (an ideal speed
        drive or a speed loop on it); None where the reference is a profile or there is none."""
        node = next((n for n in self.nodes if self.speed_or_reference(n) is not None), None)
        drive = getattr(node, "drive", None)
        loop = getattr(drive, "loop", None)
        given = getattr(drive, "input", False) or (loop is not None and loop.speed and loop.set_input)
        return node if given else None

    def speed_or_reference(self, node):
        """The speed a node follows: prescribed, or its speed loop's reference (None: neither)."""
        loop = getattr(getattr(node, "drive", None), "loop", None)
        return loop.set if loop is not None and loop.speed else self.speed_profile(node)

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
        for c in self.parts:
            for p in profiles_of(c):
                times.update(p.breakpoints())
        times.update(e.time for e in self.events)
        return sorted(t for t in times if 0.0 < t < self.stop_time)

    def columns(self):
        """The recorded columns: 'name.quantity [unit]'."""
        return [f"{c}.{q} [{quantity_unit(self.component(c), q)}]" for c, q in self.record]


def quantity_unit(component, quantity: str):
    """The unit of a quantity a component records; None if it records no such quantity. A span with
    layers records each layer's tension, `T_<label>`, too; a roller the web may slip on its traction's."""
    unit = quantities_of(component).get(quantity)
    if unit is None and isinstance(component, Span) and component.layered and quantity.startswith("T_") \
            and quantity[2:] in component.labels:
        unit = "N"
    return unit


def _single(spans, node, what):
    if len(spans) > 1:
        raise ValueError(f"{node.type} {node.name!r} {what}: it has {len(spans)} spans on that side")
    return spans[0] if spans else None


def profiles_of(c):
    out = []
    for attr in ("speed", "strain", "load"):
        p = getattr(c, attr, None)
        if isinstance(p, Profile):
            out.append(p)
    d = getattr(c, "drive", None)
    if d is not None and d.profile is not None:
        out.append(d.profile)
    if d is not None and d.loop is not None:
        out.append(d.loop.set)
    t = getattr(c, "traction", None)
    if t is not None and t.nip_load is not None:
        out.append(t.nip_load)
    layon = getattr(c, "layon", None)
    if layon is not None:
        out.append(layon.load)
    return out
