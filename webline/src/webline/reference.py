"""The monolithic reference: the whole line as one ODE, integrated by SciPy's Radau.

An independent implementation of the line equations of the physics
documentation (docs "The rollers around a span", the span's [E1]-[E10]); it
shares nothing with the FMUs or the co-simulation master but the parsed
scene. States:

* each span's strain eps, one per layer of a laminate (the FMU carries the
  unstretched length x = L/(1+eps); here the strain itself, so that the
  tolerance acts on the quantity the tension is made of):
      d(eps)/dt = (1+eps)/L * (dL/dt + v_b - (1+eps) * q_a),
      q_a = v_a/(1+eps_a) for v_a >= 0, v_a/(1+eps) for v_a < 0;
  a laminate's layer i enters at its own eps_a,i: after a nip, the strain of
  the span that brought that web there; after another roller, the strain of
  layer i of the span before (docs/merge-split.md [M6]); after a nip where webs
  i merge into a web of one layer ([M1]),
      q_a = v_a * sum_i (m_i/sum_j m_j)/(1+eps_i),  m_i the webs' mass per length;
  after a slitter, each lane's eps_a is the strain of the web it cuts ([S1]);
* each roller's angular speed (roller, unwinder, winder, dancer):
      (J + sum m_up*R^2) * d(omega)/dt = R*(sum F_down - sum (T_up + p_up)) + tau - b*omega,
  summed over the spans that end at it (several at a nip, [M4]) and the spans
  that start at it (several at a slitter, [S3]); the web mass of a span
  before it (with includeMass) adds m_up*R^2: F_b = T + p + m*dv_b/dt and
  v_b = R*omega; on a roll being wound J = J(R) moves, with no J'*omega: the web
  leaving or arriving carries that angular momentum itself (docs/physics.md,
  "Winders and unwinders");
* each dancer's position y and speed y': m*y'' = load - F_b,up - F_a,down - c*y' - k*(y - y0);
* each drive's loop (docs/physics.md [R10]-[R11]): its integrator I, and its motor's torque tau_m where
  it lags (`loop_torque`);
* each roll with runout (docs/physics.md, "A roll with runout"), its angle, d(angle)/dt = omega: the web
  touches the offset circle on the line from its span's far end, pulls with the arm p and crosses the
  span's moving end at omega*p +- dL/dt (`runout_geometry`);
* each winder's lay-on roller (docs/physics.md, "A lay-on roller", [R18]): its carriage's position X and
  speed X', the roller's spin omega_l; the nip (a spring and damper that only push) between the roller and
  the winder's surface, the traction that turns the roller, and its torque on the winder (`layon_nip`);
* where the web may slip on a roller or dancer (docs/physics.md, "Rollers that slip"), the web's
  speed over it v_w: m_w dv_w/dt = T_b - T_a + f, the spans on both sides see v_w, and the roller
  turns by -R*f instead of R*(T_b - T_a) (`friction`); and the contact's grip u, the bristles' share
  of the kinetic limit (docs/physics.md, "Contacts that stick"; `grip`), which a brake has too, on the
  roll's surface speed.

Tension: T = EA*(eps + d_r*deps/dt) (damping), or for a web record's
stress-strain table T = A*(sigma(eps) + d_r*dsigma/deps*deps/dt); clamped at
0 for a slack web; a laminate's the sum of its layers' ([M6]), slack only as one (its sum).
Profiles are integrated piece by piece between their breakpoints and the
events, where parameters change (a splice) with the state kept (strain;
a roller's surface speed).
"""

from __future__ import annotations

import math
import time as clock
from itertools import accumulate

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq, root

from .bound import runaway, tension_bounds
from .result import Result
from .scene import BRAKE_V_SLIP, STRAIN_RANGE, Dancer, Prescribed, Roller, Scene, SceneError, Span, span_layers

RTOL = 1e-10



def stepwise_radius(r, r0, h, merge, sign):
    """The stepwise radius at the smooth radius r, and its slope [R17]: u = sign (r - r0)/h layers wound on
    (sign 1) or off (-1) since r0, n = floor(u), m = merge/(2 pi): r0 + sign h (n + max(0, (u - n - (1 - m))/m)),
    which is r where each merge ends."""
    m = min(merge / (2.0 * np.pi), 1.0)
    u = sign * (r - r0) / h
    n = np.floor(u)
    into = u - n - (1.0 - m)
    return (r0 + sign * h * n, 0.0) if into <= 0.0 else (r0 + sign * h * (n + into / m), 1.0 / m)

class EquilibriumError(SceneError):
    """The line has no steady state for its drives at the start; the message says why and the way out."""


# A steady state is accepted when every rate is below this fraction of how much it changes when every
# state moves by its own size (the rates' own scale: a dancer's acceleration from forces of 800 N
# rounds to 1e-14 m/s^2, which no fraction of its speed's size would accept).
STEADY = 1e-9
DUE = 1e-9  # s: two times this close are one event (the parts' profiles' tolerance)
GIVEN = '"start": "given" in the scene starts every part from its given values instead'


def start_strain(span: Span, up, down, va: float, vb: float, eps_a: float) -> float:
    """The strain a span without T_start or eps_start starts at: at rest between its ends' start speeds,
    (1 + eps) = (v_b / v_a) * (1 + eps_a), or eps_a when v_a = 0. Ends that run apart in opposite
    directions, a far end at rest under a moving one, or a strain outside (-1, 10] give no such strain:
    a SceneError names the part that causes it, with its position, before any arithmetic sees it."""
    if va == 0:
        return eps_a
    ends = f"span {span.name!r} between {up.type} {up.name!r} ({va:g} m/s) and {down.type} {down.name!r} ({vb:g} m/s)"
    way_out = f"give span {span.name!r} a T_start or eps_start, or start its ends at speeds of one sign"
    if vb == 0:
        raise SceneError(f"{down.where}: {down.type} {down.name!r} stands still at the start while {up.type} {up.name!r} "
                         f"feeds span {span.name!r} at {va:g} m/s: the span would start with no web in it (strain -1); {way_out}")
    if vb / va < 0:
        culprit, other = (up, down) if va < 0 else (down, up)
        raise SceneError(f"{culprit.where}: {culprit.type} {culprit.name!r} runs backwards at the start "
                         f"({va if culprit is up else vb:g} m/s) while {other.type} {other.name!r} at the other end of span "
                         f"{span.name!r} runs forwards: no strain carries the web between them, so the span has no start "
                         f"strain; {way_out}")
    eps = (vb - va + vb * eps_a) / va
    lo, hi = STRAIN_RANGE
    if not lo < eps <= hi:
        raise SceneError(f"{span.where}: {ends} would start at a strain of {eps:.4g} (the arriving web's {eps_a:.4g} "
                         f"stretched by the speeds' ratio), outside ({lo:g}, {hi:g}]; {way_out}")
    return eps


class LineODE:
    def __init__(self, scene: Scene):
        self.s = scene
        self.spans = scene.spans
        self.movers = [c for c in scene.nodes if isinstance(c, (Roller, Dancer)) and c.has_fmu]
        self.dancers = [c for c in scene.nodes if isinstance(c, Dancer)]
        self.slippers = [c for c in scene.nodes if getattr(c, "traction", None) is not None]
        # A span's strains: one per layer, from its first (i_eps) on.
        self.layers = {sp.name: len(sp.wp2.plies) for sp in self.spans}
        self.i_eps = dict(zip(self.layers, accumulate(self.layers.values(), initial=0)))
        n_s, n_m, n_d = sum(self.layers.values()), len(self.movers), len(self.dancers)
        self.n_strains = n_s
        # Where each layer of a laminate after a nip comes from: the strain states it enters at ([M6]).
        self.feeds = {sp.name: [self.i_eps[src.name] + i for src, i in scene.layer_sources(sp)]
                      for sp in self.spans if sp.layered and len(scene.spans_in(scene.upstream(sp))) > 1}
        self.i_omega = {m.name: n_s + i for i, m in enumerate(self.movers)}
        self.i_y = {d.name: n_s + n_m + 2 * i for i, d in enumerate(self.dancers)}
        self.i_vw = {c.name: n_s + n_m + 2 * n_d + i for i, c in enumerate(self.slippers)}
        # Each contact's grip, then each brake's.
        self.i_grip = {c.name: n_s + n_m + 2 * n_d + len(self.slippers) + i for i, c in enumerate(self.slippers)}
        self.brakes = [m for m in self.movers if getattr(getattr(m, "drive", None), "kind", None) == "brake"]
        first_brake = n_s + n_m + 2 * n_d + 2 * len(self.slippers)
        self.i_brake = {m.name: first_brake + i for i, m in enumerate(self.brakes)}
        # A roll whose web winds off or on: its radius is a state [R3].
        self.rolls = [m for m in self.movers if getattr(m, "wound", None) is not None]
        first_roll = first_brake + len(self.brakes)
        self.i_r = {m.name: first_roll + i for i, m in enumerate(self.rolls)}
        # A drive's loop: its integrator, then its motor's torque where it lags.
        self.loops = [c for c in self.movers if getattr(getattr(c, "drive", None), "loop", None) is not None]
        first = first_roll + len(self.rolls)
        self.i_loop = {}
        for c in self.loops:
            self.i_loop[c.name] = (first, first + 1 if c.drive.loop.lag > 0 else None)
            first += 1 + (c.drive.loop.lag > 0)
        # A dancer loop's integrator [R13], a speed trim.
        trims = [c for c in self.loops if c.drive.loop.dancer is not None]
        self.i_trim = {c.name: first + i for i, c in enumerate(trims)}
        # The dancers whose position a dancer loop holds: steady at its set point, spring or not.
        self.held_by_loop = {c.drive.loop.dancer.dancer for c in trims}
        # A roll with runout: its angle [R15].
        self.runouts = [c for c in scene.nodes if getattr(c, "runout", None) is not None]
        self.i_angle = {c.name: first + len(trims) + i for i, c in enumerate(self.runouts)}
        # A winder's lay-on roller [R18]: its carriage's X, X' and the roller's omega_l.
        self.layons = [c for c in scene.nodes if getattr(c, "layon", None) is not None]
        first_layon = first + len(trims) + len(self.runouts)
        self.i_layon = {c.name: first_layon + 3 * i for i, c in enumerate(self.layons)}
        self.n = first_layon + 3 * len(self.layons)
        # A sampled loop's hold [R14]: the command it applies (None before its first sample: continuous),
        # a sample waiting out the delay (when it applies, its command), the last continuous command.
        self.sampled = {c.name: c.drive.loop for c in self.loops if c.drive.loop.sample > 0.0}
        self.held = dict.fromkeys(self.sampled)
        self.waiting = {}
        self.commands = {}
        # The line's shape, once: each span's rollers, each roller's spans in and out.
        self.up = {sp.name: scene.upstream(sp) for sp in self.spans}
        self.down = {sp.name: scene.downstream(sp) for sp in self.spans}
        self.ins = {c.name: scene.spans_in(c) for c in scene.nodes}
        self.outs = {c.name: scene.spans_out(c) for c in scene.nodes}
        # Mutable parameters (events change them).
        self.web = {sp.name: (sp.wp1, sp.wp2) for sp in self.spans}
        self.inertia = {m.name: [m.J, m.R, m.b] for m in self.movers}
        self.segment = (0.0, scene.stop_time)
        self.stuck = False  # the web held to every roller's surface (the equilibrium's first search)

    # profile values inside the current segment [a, b]: the left limit at b
    def pv(self, profile, t):
        a, b = self.segment
        return profile.value_left(t) if t >= b and b > a else profile.value(t)

    def pslope(self, profile, t):
        """A profile's slope at t inside the current segment [a, b]: the left slope at b (one piece of every
        profile: an S-curve's slope moves within it)."""
        a, b = self.segment
        return profile.slope_left(t) if t >= b and b > a else profile.slope(t)

    def radius(self, node, z):
        """The roller's radius: a roll's state where its web winds [R3], else its R."""
        i = self.i_r.get(node.name)
        return z[i] if i is not None else self.inertia[node.name][1]

    def lever(self, node, z):
        """The radius the web meets, [R1]'s lever and v = r_w omega: the roll's radius, or with a stepwise
        `wound.merge` its stepwise radius [R17] (`stepwise_radius`); the radius itself moves smoothly."""
        r = self.radius(node, z)
        w = getattr(node, "wound", None)
        return r if w is None or not w.merge else stepwise_radius(r, self.inertia[node.name][1], w.thickness, w.merge,
                                                                  -1.0 if node.type == "unwinder" else 1.0)[0]

    def lever_slope(self, node, z):
        """d(lever)/dr: 1 where the radius the web meets moves smoothly, a stepwise radius's slope [R17]."""
        w = getattr(node, "wound", None)
        if w is None or not w.merge:
            return 1.0
        return stepwise_radius(self.radius(node, z), self.inertia[node.name][1], w.thickness, w.merge,
                               -1.0 if node.type == "unwinder" else 1.0)[1]

    def roll_inertia(self, node, r):
        """J(r) = J_0 + (pi/2) rho w (r^4 - r_0^4) [R3], J_0 and r_0 the roll's at the start."""
        J, R, _ = self.inertia[node.name]
        w = node.wound
        return J + 0.5 * np.pi * w.density * w.width * (r**4 - R**4)

    def radius_rate(self, node, t, z, R, v):
        """dr/dt = s h v/(2 pi r (1 + eps)) [R3] of a roll whose surface moves at v: it counts the web's
        unstretched length, eps the strain of the web where it meets the roll (an unwinder's leaving,
        a winder's arriving, merged with the mass weights of [R5] where several arrive: `entry`), so
        that the roll's mass moves at the web's mass flow rho_l v/(1 + eps)."""
        sign = -1.0 if node.type == "unwinder" else 1.0
        return sign * node.wound.thickness * v / (2.0 * np.pi * R * self.entry(node, t, z))

    def torque(self, node, t, z):
        d = getattr(node, "drive", None)
        if d is None:  # a dancer's roller is an idler
            return 0.0
        if d.kind == "torque":
            return self.pv(d.profile, t)
        if d.kind == "tension":
            R = self.lever(node, z)
            return (-R if node.type == "unwinder" else self.tapered_lever(node, R)) * self.pv(d.profile, t)
        if d.kind == "brake":  # a powder brake: its grip on the surface's speed carries up to its rating [R12]
            return -self.pv(d.profile, t) * self.brake_grip(node, t, z)[1]
        return 0.0

    def tapered_lever(self, node, r):
        """r T(r)/T0 of a winder's tension drive with the hyperbolic taper k [R16], T(r) = T0 (1 - k (1 - R/r)):
        (1 - k) r + k R, R the roll's start radius (a new roll's after an event)."""
        k = node.drive.taper
        return r if k == 0.0 else (1.0 - k) * r + k * self.inertia[node.name][1]

    def brake_grip(self, node, t, z):
        """(du_b/dt, g_b) of a brake's grip on its roll's surface speed (k_s = 1, `grip`)."""
        return grip(z[self.i_brake[node.name]], self.speed(node, t, z), BRAKE_V_SLIP, node.drive.creep, 1.0)

    def loop_torque(self, node, t, z, q, dz):
        """A drive's PI loop [R10] and its motor [R11] at (t, z): its torque, its rates into dz.
        e = sign*(set - measured), or v_ref - R*omega for a speed loop; u = kp*e + I + ff; I' = ki*e + (limit(u) - u)*ki/kp; the motor's torque
        limit(u), or with a lag tau_m' = (limit(u) - tau_m)/lag. The limit is the identity up to 95 % of
        it and bends exponentially into it over the last 5 %; ff = J*d(v_ref/R)/dt, the inertia torque of
        the speed reference (its own for a speed loop, else the line's): J*a_ref/R, and on a roll being
        wound - J*R_rate*v_ref/R^2 with R_rate of [R3] at v_ref (and the strain the roll sees)."""
        lp = node.drive.loop
        R = self.lever(node, z)
        J = self.roll_inertia(node, self.radius(node, z)) if node.name in self.i_r else self.inertia[node.name][0]
        if lp.speed:  # a speed loop on its own surface speed
            e = self.pv(lp.set, t) - R * z[self.i_omega[node.name]]
            if lp.dancer is not None:  # its reference trimmed by a PI on the dancer's position [R13]
                d, i_trim = lp.dancer, self.i_trim[node.name]
                e_d = d.sign * (z[self.i_y[d.dancer]] - d.set)
                dz[i_trim] = d.ki * e_d
                e += d.kp * e_d + z[i_trim]
        elif lp.measure[1] == "F":  # a roller's load cell
            e = lp.sign * (self.pv(lp.set, t) - self.load_cell(self.s.component(lp.measure[0]), q))
        else:  # a span's tension
            e = lp.sign * (self.pv(lp.set, t) - q[lp.measure[0]]["T"])
        ff = 0.0
        if lp.feedforward:
            reference = lp.set if lp.speed else self.s.speed_reference()
            v_ref, a_ref = self.pv(reference, t), self.pslope(reference, t)
            ff = J * a_ref / R
            if node.name in self.i_r:
                ff -= J * self.radius_rate(node, t, z, R, v_ref) * v_ref / R**2
        i_int, i_motor = self.i_loop[node.name]
        u = lp.kp * e + z[i_int] + ff
        limited = u
        if lp.limit > 0.0:
            knee = 0.95 * lp.limit
            if abs(u) > knee:
                limited = np.sign(u) * (lp.limit - 0.05 * lp.limit * np.exp(-(abs(u) - knee) / (0.05 * lp.limit)))
        tracking = lp.ki / lp.kp if lp.kp > 0.0 and lp.ki > 0.0 else 1.0
        dz[i_int] = lp.ki * e + (limited - u) * tracking
        self.commands[node.name] = limited
        applied = limited if self.held.get(node.name) is None else self.held[node.name]  # a sampled loop's hold [R14]
        if i_motor is None:
            return applied
        dz[i_motor] = (applied - z[i_motor]) / lp.lag
        return z[i_motor]

    def sample_times(self):
        """The sampled loops' samples k*T and their applications k*T + delay in (0, stop) [R14]."""
        times = set()
        for lp in self.sampled.values():
            k = np.arange(int(np.ceil(self.s.stop_time / lp.sample)) + 1) * lp.sample
            times.update(float(t) for t in np.concatenate([k, k + lp.delay]) if 0.0 < t < self.s.stop_time)
        return times

    def hold(self, t, z):
        """At time t (z the line there): each sampled loop applies a sample whose delay is over, then
        takes the sample due, the command of its continuous loop at (t, z) [R14]."""
        if not self.sampled:
            return
        self.evaluate(t, z)  # the continuous commands at (t, z), in self.commands
        for name, lp in self.sampled.items():
            waiting = self.waiting.get(name)
            if waiting is not None and waiting[0] <= t + DUE:
                self.held[name] = self.waiting.pop(name)[1]
            k = round(t / lp.sample)
            if abs(t - k * lp.sample) <= DUE:
                if lp.delay > 0.0 and self.held[name] is not None:
                    self.waiting[name] = (k * lp.sample + lp.delay, self.commands[name])
                else:  # the first sample applies at once: the drive ran at it before the start
                    self.held[name] = self.commands[name]

    def speed(self, node, t, z):
        if isinstance(node, Prescribed):
            return self.pv(node.speed, t)
        if isinstance(node, Roller) and node.drive.kind == "speed":
            return self.pv(node.drive.profile, t)
        return self.lever(node, z) * z[self.i_omega[node.name]]

    def contact(self, node, t, z, v, q):
        """Where the web may slip on `node`: its friction on the web and what it reports, at (t, z)."""
        (up,), (down,) = self.ins[node.name], self.outs[node.name]
        web = self.web[up.name][1]
        R = self.inertia[node.name][1] if node.name in self.inertia else node.R
        tr = node.traction
        load = self.pv(tr.nip_load, t) if tr.nip_load is not None else 0.0
        return friction(tr, R, node.wrap or 0.0, web, z[self.i_vw[node.name]], v[node.name], q[up.name]["T"], q[down.name]["T"],
                        load, z[self.i_grip[node.name]])

    def evaluate(self, t, z):
        """Rates and every quantity of the line at (t, z)."""
        s = self.s
        dz = np.zeros(self.n)
        q = {}
        v = {node.name: self.speed(node, t, z) for node in s.nodes}
        # The spans see the web's speed where it may slip, the surface's elsewhere.
        w = v if self.stuck else {**v, **{c.name: z[i] for c, i in zip(self.slippers, self.i_vw.values())}}
        runout = self.runout_state(t, z, dz)
        for sp in self.spans:
            up, down = self.up[sp.name], self.down[sp.name]
            dancer = up if isinstance(up, Dancer) else down if isinstance(down, Dancer) else None
            if dancer is not None:
                L = z[self.i_y[dancer.name]]
                dL = z[self.i_y[dancer.name] + 1]
            else:
                L, dL = sp.length, 0.0
            va, vb = w[up.name], w[down.name]
            if up.name in runout and up.type == "unwinder":  # the roll's tangent point is the span's entry
                L, dL, va = runout[up.name]["L"], runout[up.name]["dL"], runout[up.name]["v"]
            if down.name in runout and down.type == "winder":
                L, dL, vb = runout[down.name]["L"], runout[down.name]["dL"], runout[down.name]["v"]
            first = self.i_eps[sp.name]
            entries = self.entries(sp, t, z) if va >= 0 else None
            layers = []
            for i, (w1, w2) in enumerate(span_layers(*self.web[sp.name])):
                eps = z[first + i]
                if va >= 0:
                    qa = va / entries[i]
                else:  # web entering backwards carries the span's own strain
                    qa = va / (1.0 + eps)
                deps = (1.0 + eps) / L * (dL + vb - (1.0 + eps) * qa)
                dz[first + i] = deps
                layers.append(self.layer(sp, w1, w2, eps, deps, L, qa, va, vb, clamp=not sp.layered))
            if len(layers) == 1:
                q[sp.name] = layers[0]
            else:  # a laminate ([M6]): its layers in parallel, the strain weighted by their stiffness
                if "preventNegativeTension" in sp.effects and not sum(x["T"] for x in layers) > 0.0:
                    for x in layers:  # bonded, it goes slack as one: every layer carries 0
                        x["T"] = x["F_a"] = 0.0
                q[sp.name] = {k: sum(x[k] for x in layers) for k in ("T", "p", "m")}
                q[sp.name].update(eps=sum(x["EA"] * x["eps"] for x in layers) / sum(x["EA"] for x in layers), L=L,
                                  F_a=q[sp.name]["T"], **{f"T_{label}": x["T"] for label, x in zip(sp.labels, layers)})
        accel = {}
        for node in self.movers:
            J, R, b = self.inertia[node.name]
            omega = z[self.i_omega[node.name]]
            slope = 1.0  # d(lever)/dr
            if node.name in self.i_r:  # [R3]: d(r^2)/dt = s h v/(pi (1 + eps)), J(r); [R1] balances J domega/dt
                r = z[self.i_r[node.name]]
                J = self.roll_inertia(node, r)
                R = self.lever(node, z)  # the radius the web meets [R17]: r, or stepwise
                slope = self.lever_slope(node, z)
                dz[self.i_r[node.name]] = self.radius_rate(node, t, z, r, R * omega)
            # Every web leaving pulls forward, every web arriving pulls back (a nip, a slitter: several).
            F_down = sum(q[sp.name]["T"] for sp in self.outs[node.name])
            F_up = sum(q[sp.name]["T"] + q[sp.name]["p"] for sp in self.ins[node.name])
            m_up = sum(q[sp.name]["m"] for sp in self.ins[node.name])
            if node.name in self.i_vw and not self.stuck:  # the web pulls the roller through its friction only [R6]
                contact = self.contact(node, t, z, v, q)
                F_down, F_up = -contact["f"], 0.0
            tau = self.torque(node, t, z)
            if node.name in self.i_brake:
                dz[self.i_brake[node.name]] = self.brake_grip(node, t, z)[0]
            if node.name in self.i_loop:
                q[node.name] = {"tau": tau + self.loop_torque(node, t, z, q, dz)}
                tau = q[node.name]["tau"]
            if node.name in runout:  # the web at the roll pulls with the arm p [R15]
                p = runout[node.name]["p"]
                F_down, F_up = (F_down * p / R, F_up) if node.type == "unwinder" else (F_down, F_up * p / R)
            if node.name in self.i_layon:  # the lay-on roller's traction on the roll [R18]
                r_rate = dz[self.i_r[node.name]] if node.name in self.i_r else 0.0
                q[f"{node.name}.layon"] = self.layon_state(node, t, z, dz, omega, self.radius(node, z), r_rate)
                tau = tau + q[f"{node.name}.layon"]["torque"]
            num = R * (F_down - F_up) + tau - b * omega
            domega = num / (J + m_up * R * R)
            dz[self.i_omega[node.name]] = domega
            accel[node.name] = R * domega + omega * slope * dz[self.i_r[node.name]] if node.name in self.i_r else R * domega
        for node in self.layons:
            if node.name not in self.i_omega:  # a speed-driven winder: it turns as its profile says, whatever the nip
                q[f"{node.name}.layon"] = self.layon_state(node, t, z, dz, self.speed(node, t, z) / node.R, node.R, 0.0)
        for sp in self.spans:
            down = self.down[sp.name]
            if down.name in accel:
                dvb = accel[down.name]
            else:
                prof = s.speed_profile(down)
                dvb = self.pslope(prof, t) if prof is not None else 0.0
            qs = q[sp.name]
            qs["F_b"] = qs["T"] + qs["p"] + qs["m"] * dvb
        for c in self.slippers:
            contact = self.contact(c, t, z, v, q)
            (up,), (down,) = self.ins[c.name], self.outs[c.name]
            dz[self.i_vw[c.name]] = (q[down.name]["T"] - q[up.name]["T"] + contact["f"]) / contact["m_w"]
            dz[self.i_grip[c.name]] = contact["du"]
            q[c.name] = contact
        for d in self.dancers:
            i = self.i_y[d.name]
            y, ydot = z[i], z[i + 1]
            F = (self.pv(d.load, t) - sum(q[sp.name]["F_b"] for sp in self.ins[d.name])
                 - sum(q[sp.name]["F_a"] for sp in self.outs[d.name]))
            dz[i] = ydot
            dz[i + 1] = (F - d.damping * ydot - d.stiffness * (y - d.y_start)) / d.mass
        return dz, q, v

    def runout_state(self, t, z, dz):
        """Each roll with runout at (t, z): its geometry (`runout_geometry`) by name, its angle's rate into dz."""
        out = {}
        for node in self.runouts:
            mover = node.name in self.i_omega
            R = self.radius(node, z) if mover else node.R
            omega = z[self.i_omega[node.name]] if mover else self.speed(node, t, z) / R
            span = self.s.spans_out(node)[0] if node.type == "unwinder" else self.s.spans_in(node)[0]
            out[node.name] = runout_geometry(node, span.length, z[self.i_angle[node.name]], omega, R)
            dz[self.i_angle[node.name]] = omega
        return out

    def layon_state(self, node, t, z, dz, omega, r, r_rate):
        """A winder's lay-on roller at (t, z) (`layon_nip`): the winder turning at omega, its radius r growing at
        r_rate, its centre where its runout's angle puts it; its three rates into dz."""
        i = self.i_layon[node.name]
        e, psi = 0.0, 0.0
        if node.runout is not None:  # a winder's psi = -(angle + phase) [R15]
            e, psi = node.runout.eccentricity, -(z[self.i_angle[node.name]] + node.runout.phase)
        nip = layon_nip(node.layon, self.pv(node.layon.load, t), z[i], z[i + 1], z[i + 2], r, r_rate, e, psi, -omega, omega)
        dz[i], dz[i + 1], dz[i + 2] = z[i + 1], nip["X''"], nip["omega_l'"]
        return nip

    @staticmethod
    def layer(sp, w1, w2, eps, deps, L, qa, va, vb, clamp=True):
        """One layer of a span (the span itself, for a web of one layer): its tension, momentum flux and mass.
        `clamp`: a web of one layer is slack when its own pull is not positive; a laminate's layer is
        not clamped on its own (the laminate clamps on the sum, [M6])."""
        damped = "includeDamping" in sp.effects
        if w2.curve is None:
            T = w2.EA * (eps + (w2.d_r * deps if damped else 0.0))
        else:  # a record's stress-strain table, with the tangent modulus in the damping term
            T = w2.area * (float(w2.curve.sigma(eps)) + (w2.d_r * float(w2.curve.tangent(eps)) * deps if damped else 0.0))
        if clamp and "preventNegativeTension" in sp.effects:
            T = max(T, 0.0)
        x = L / (1.0 + eps)
        if "includeMass" in sp.effects:
            rho_in = w1.rho_l if va >= 0 else w2.rho_l
            p = qa * (w2.rho_l * vb - rho_in * va)
            m = w2.rho_l * x
        else:
            p, m = 0.0, 0.0
        return {"T": T, "eps": eps, "L": L, "F_a": T, "p": p, "m": m, "x": x, "q_a": qa, "EA": w2.EA}

    def rhs(self, t, z):
        return self.evaluate(t, z)[0]

    def steady_rates(self, t, z):
        """The rates a steady state zeroes: rhs, but for a roll being wound its surface's acceleration
        over R, domega/dt + omega*R_rate/R: at a constant surface speed omega still moves with R."""
        dz = self.rhs(t, z)
        for name, i in self.i_r.items():
            k = self.i_omega[name]
            node = self.s.component(name)
            dz[k] += z[k] * self.lever_slope(node, z) * dz[i] / self.lever(node, z)
        return dz

    def entries(self, sp, t, z):
        """1 + eps_a of each layer of span `sp` entering it forwards ([M6]): at the line's first roller its
        strain profile; after a nip, each layer the strain of the span that brought its web there, or,
        into a web of one layer, the merge of every web arriving ([M1]); after another roller, layer i
        the strain of layer i of the span before (a slitter's lanes all start at it, [S1]), each layer
        the strain of a web of one layer."""
        node = self.up[sp.name]
        ins = self.ins[node.name]
        k = self.layers[sp.name]
        if sp.name in self.feeds:
            return [1.0 + z[i] for i in self.feeds[sp.name]]
        if len(ins) == 1 and self.layers[ins[0].name] == k:
            first = self.i_eps[ins[0].name]
            return [1.0 + z[first + i] for i in range(k)]
        return [self.entry(node, t, z)] * k

    def entry(self, node, t, z):
        """1 + eps_a of a web of one layer leaving `node` forwards. At the line's first roller its strain
        profile; after a roller, the strain of the span before it (a slitter's lanes all start at it,
        [S1]); after a nip, 1/(1+eps_a) is the mass-weighted mean of the arriving webs' (their layers')
        1/(1+eps_i) ([M1])."""
        ins = self.ins[node.name]
        if not ins:
            return 1.0 + self.pv(node.strain, t)
        if len(ins) == 1 and self.layers[ins[0].name] == 1:
            return 1.0 + z[self.i_eps[ins[0].name]]
        m = self.s.inlet_masses(node, lambda sp: self.web[sp.name][1])
        strains = [z[self.i_eps[sp.name] + i] for sp in ins for i in range(self.layers[sp.name])]
        return sum(m) / sum(mi / (1.0 + e) for mi, e in zip(m, strains))

    def initial_state(self):
        """The start: the scene's start values, or with `"start": "equilibrium"` the steady state for
        the drives at t = 0 (`equilibrium`); a line that has none is refused (EquilibriumError)."""
        z = self.given_state()
        return self.equilibrium(z) if self.s.start == "equilibrium" else z

    def operating_state(self, t):
        """The line at time t as a linearization needs it: its steady state for the drives then
        (given start values where the scene starts given or none exists), at t = 0 its start."""
        if t == 0.0:
            return self.initial_state()
        z = self.given_state(t)
        if self.s.start == "equilibrium":
            try:
                self.segment = (t, self.s.stop_time)
                z = self.equilibrium(z, t)
            except EquilibriumError:
                pass
        return z

    def equilibrium(self, z0, t=0.0):
        """The state where every rate vanishes, from z0 (SciPy's root, 'hybr'), checked before it is
        returned (`STEADY`); a roll being wound turns at a steady surface speed (`steady_rates`). A dancer without a spring is steady at any position: its position is held
        at its start and its carriage's balance of forces checked on its own, which names what is off.
        Where the web may slip, the line is solved with the web held to every roller's surface, and each
        contact's grip from its force balance at zero slip (`hold`): a contact that cannot carry its
        demand there is refused in plain words. A brake's grip is solved with its roll at rest, where it
        stands still at the start, and is its kinetic limit (u_b = sign(v)) where it turns."""
        springless = [d for d in self.dancers if d.stiffness == 0.0 and d.name not in self.held_by_loop]
        held = [self.i_y[d.name] for d in springless]  # their positions: held
        balance = [i + 1 for i in held]  # their accelerations: checked afterwards
        # A roll's radius is never steady while web winds: held at its start, its rate not solved for.
        rolls = list(self.i_r.values()) + list(self.i_angle.values())  # and a roll's angle, which turns
        held, balance = held + rolls, balance + rolls
        # A lay-on's carriage at rest (X' = 0 held, so X's own rate is nil): its position solved from its balance
        # N = F, its roller's spin from its own.
        held += [i + 1 for i in self.i_layon.values()]
        balance += list(self.i_layon.values())
        # A laminate at rest is steady at any strains of its layers that pull as one: its layers move
        # together from their start (each layer's rate is zero whatever its strain; [M6]).
        tied = {first + i: first for first, k in self.resting_laminates(t, z0) for i in range(1, k)}
        z = z0.copy()
        # A brake at rest holds its roll with the torque its grip solves for; turning, it slides at its rating.
        resting = [b for b in self.brakes if self.speed(b, t, z0) == 0.0]
        for b in self.brakes:
            if b not in resting:
                z[self.i_brake[b.name]] = np.sign(self.speed(b, t, z0))
        brake_held = [self.i_omega[b.name] if b in resting else self.i_brake[b.name] for b in self.brakes]
        held, skipped = held + brake_held, balance + list(self.i_brake.values())
        contact = list(self.i_vw.values()) + list(self.i_grip.values())
        self.stuck = bool(contact)
        try:
            z, scale = self._solve(t, z0, z, held + contact, skipped + contact, tied)
        finally:
            self.stuck = False
        for c in self.slippers:  # every web at its roller's surface first: a damped span's tension reads both ends' speeds
            z[self.i_vw[c.name]] = self.speed(c, t, z)
        for c in self.slippers:
            z[self.i_grip[c.name]] = self.held_grip(c, t, z)
            scale[self.i_vw[c.name]], scale[self.i_grip[c.name]] = c.traction.v_slip, 1.0
        for b in self.brakes:
            self.check_brake(b, t, z, b in resting)
            scale[self.i_brake[b.name]] = 1.0
        off = self.unsteadiness(t, z, scale)
        rows = np.array([i for i in range(self.n) if i not in balance], dtype=int)
        if len(rows) and not np.max(off[rows]) < STEADY:
            worst = self.state_names()[rows[np.argmax(off[rows])]]
            raise EquilibriumError(f"{self.s.path}: the line has no steady state at t = {t:g} s for its drives "
                                   f"(SciPy's root: {self.last_root.message.strip()} The rate of {worst} stays at "
                                   f"{np.max(off[rows]):.2g} of its scale); {GIVEN}")
        for d, i in zip(springless, balance):
            if not off[i] < STEADY:
                _, q, _ = self.evaluate(t, z)
                spans = [(sp.name, q[sp.name]["F_b"]) for sp in self.ins[d.name]] + [
                    (sp.name, q[sp.name]["F_a"]) for sp in self.outs[d.name]]
                pull = " + ".join(f"{name} {F:.4g} N" for name, F in spans)
                raise EquilibriumError(
                    f"{d.where}: dancer {d.name!r} has no spring, so its carriage is steady only where its load "
                    f"({self.pv(d.load, t):.4g} N) equals the pull of its spans, which the drives set ({pull} = "
                    f"{sum(F for _, F in spans):.6g} N at the line's steady speeds): {self.pv(d.load, t) - sum(F for _, F in spans):.3g} N "
                    f"are left over, the carriage runs away and "
                    f"the line has no steady state to start from. Give the dancer a \"stiffness\" (its spring takes the "
                    f"difference), or {GIVEN}")
        return z

    def held_grip(self, c, t, z):
        """The grip u of contact `c` at zero slip (g = u) that balances its web, T_b - T_a + f(u) = 0, within
        its static limit |u| <= k_s; where none does, the demand exceeds the limit: refused in plain words."""
        _, q, v = self.evaluate(t, z)
        (up,), (down,) = self.ins[c.name], self.outs[c.name]
        T_a, T_b = q[up.name]["T"], q[down.name]["T"]

        def balance(u):
            x = z.copy()
            x[self.i_grip[c.name]] = u
            return T_b - T_a + self.contact(c, t, x, v, q)["f"]

        k = c.traction.static
        lo, hi = balance(-k), balance(k)  # f falls with u: the balance too
        if lo == hi and abs(lo) <= STEADY * max(abs(T_a), abs(T_b)):  # it carries nothing (on air), nor needs to
            return 0.0
        if lo >= 0.0 >= hi:
            return brentq(balance, -k, k, xtol=1e-15, rtol=4 * np.finfo(float).eps)
        raise EquilibriumError(self.demand_message(c, t, z, q, v, T_a, T_b))

    def demand_message(self, c, t, z, q, v, T_a, T_b):
        """What a contact that cannot hold its steady tensions at the start needs, and its limit."""
        tr = c.traction
        contact = self.contact(c, t, z, v, q)
        relief = self.web[self.ins[c.name][0].name][1].rho_l * v[c.name] ** 2
        load = self.pv(tr.nip_load, t) if tr.nip_load is not None else 0.0
        side, high, low = ("downstream", T_b, T_a) if T_b > T_a else ("upstream", T_a, T_b)
        nip_low = (tr.nip_side == "entry") == (T_b > T_a)
        limit = holding_limit(contact["mu_eff"] * np.radians(c.wrap or 0.0), tr.nip_mu * load, tr.static, relief, low, nip_low)
        kinds, what = [], []
        if tr.mu > 0.0:
            kinds.append("capstan")
            what.append(f"mu {contact['mu_eff']:g}{' on its air film' if contact['mu_eff'] != tr.mu else ''}, {c.wrap:g} deg")
        if tr.nip_load is not None:
            kinds.append("nip")
            what.append(f"nip mu {tr.nip_mu:g}, {load:g} N")
        if tr.static != 1.0:
            what.append(f"static {tr.static:g}")
        other = "upstream" if side == "downstream" else "downstream"
        return (f"{c.where}: {c.name}: needs {high:.4g} N {side}, its {' and '.join(kinds)} limit is {limit:.4g} N "
                f"({'; '.join(what)}): the web slides from the start; use \"start\": \"given\" (the limit with the "
                f"{low:.4g} N {other} that the line's steady draws give)")

    def check_brake(self, b, t, z, resting):
        """A brake at rest holds its roll within its rating; one turning keeps turning the way it started."""
        u = z[self.i_brake[b.name]]
        rating = self.pv(b.drive.profile, t)
        if resting and not abs(u) <= 1.0:
            raise EquilibriumError(f"{b.where}: {b.type} {b.name!r}: its brake must hold {abs(u) * rating:.4g} N.m at "
                                   f"rest, its rating is {rating:.4g} N.m: the roll turns from the start; use \"start\": \"given\"")
        if not resting and np.sign(self.speed(b, t, z)) != u:
            raise EquilibriumError(f"{b.where}: {b.type} {b.name!r}: its brake slides at its rating the way the roll "
                                   f"starts, but the steady line turns it the other way; {GIVEN}")

    def _solve(self, t, z0, z, held, skipped, tied):
        """SciPy's root on the rates but `skipped`, over the states but `held`, from z; a tied state
        {i: first} moves with the state it is tied to and has no rate of its own to solve. (z, scale)."""
        free = np.array([i for i in range(self.n) if i not in held and i not in tied], dtype=int)
        rows = np.array([i for i in range(self.n) if i not in skipped and i not in tied], dtype=int)
        z = z.copy()
        # Scaled by the start, then again by the first answer: a strain that starts at 0 is scaled
        # by its tolerance at first, a thousand times below its steady value, and hybr stalls there.
        for _ in range(2):
            scale = np.maximum(np.abs(z), atol_of(self, z0) * 1e6)
            for c in self.slippers:  # the web's speed over a roller moves on the scale of its slip, a grip on 1
                scale[self.i_vw[c.name]] = c.traction.v_slip
                scale[self.i_grip[c.name]] = 1.0
            for i in self.i_brake.values():
                scale[i] = 1.0

            def rates(u, scale=scale, z=z):
                x = z.copy()
                x[free] = u * scale[free]
                for i, first in tied.items():
                    x[i] = z[i] + x[first] - z[first]
                return self.steady_rates(t, x)[rows]

            sol = root(rates, z[free] / scale[free], method="hybr", options={"xtol": 1e-15})
            moved = sol.x * scale[free] - z[free]
            z[free] += moved
            for i, first in tied.items():
                z[i] += moved[np.searchsorted(free, first)]
        self.last_root = sol
        return z, scale

    def resting_laminates(self, t, z):
        """(first strain state, layers) of each laminate span whose ends stand still at (t, z)."""
        v = {node.name: self.speed(node, t, z) for node in self.s.nodes}
        return [(self.i_eps[sp.name], self.layers[sp.name]) for sp in self.spans
                if sp.layered and v[self.up[sp.name].name] == 0.0 and v[self.down[sp.name].name] == 0.0]

    def unsteadiness(self, t, z, scale):
        """Each rate at z relative to how much it changes when every state moves by its own size
        (the sum of |d rate/d state| * scale over the states, by central differences)."""
        f = self.steady_rates(t, z)
        size = np.zeros(self.n)
        for j in range(self.n):
            dz = np.zeros(self.n)
            dz[j] = 1e-6 * scale[j]
            size += np.abs(self.steady_rates(t, z + dz) - self.steady_rates(t, z - dz)) / 2e-6
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(f == 0.0, 0.0, np.abs(f) / size)

    def state_names(self):
        names = [""] * self.n
        for sp in self.spans:
            i = self.i_eps[sp.name]
            if sp.layered:
                for j, label in enumerate(sp.labels):
                    names[i + j] = f"span {sp.name!r}'s layer {label}'s strain"
            else:
                names[i] = f"span {sp.name!r}'s strain"
        for k, i in self.i_omega.items():
            names[i] = f"{k!r}'s speed"
        for k, i in self.i_y.items():
            names[i], names[i + 1] = f"dancer {k!r}'s position", f"dancer {k!r}'s carriage speed"
        for k, i in self.i_vw.items():
            names[i] = f"the web's speed over {k!r}"
        for k, i in self.i_grip.items():
            names[i] = f"{k!r}'s grip"
        for k, i in self.i_brake.items():
            names[i] = f"{k!r}'s brake grip"
        for k, i in self.i_r.items():
            names[i] = f"roll {k!r}'s radius"
        for k, (i, m) in self.i_loop.items():
            names[i] = f"{k!r}'s loop integrator"
            if m is not None:
                names[m] = f"{k!r}'s motor torque"
        for k, i in self.i_trim.items():
            names[i] = f"{k!r}'s dancer loop integrator"
        for k, i in self.i_angle.items():
            names[i] = f"roll {k!r}'s angle"
        for k, i in self.i_layon.items():
            names[i], names[i + 1], names[i + 2] = (f"{k!r}'s lay-on carriage's position", f"{k!r}'s lay-on carriage's speed",
                                                    f"{k!r}'s lay-on roller's speed")
        return names

    def given_state(self, t=0.0):
        """The scene's start values (at a later time t: the speeds then, each span at rest between them)."""
        s = self.s
        z = np.zeros(self.n)
        for node in self.movers:
            z[self.i_omega[node.name]] = s.initial_speed(node, t) / node.R
        for node in self.rolls:
            z[self.i_r[node.name]] = node.R
        for d in self.dancers:
            z[self.i_y[d.name]] = d.y_start
        for c in self.slippers:
            z[self.i_vw[c.name]] = s.initial_speed(c, t) + c.traction.slip_start
            z[self.i_grip[c.name]] = start_grip(c.traction)
        for b in self.brakes:  # a brake that starts turning starts sliding, as a web that starts slipping
            z[self.i_brake[b.name]] = np.sign(s.initial_speed(b, t))
        for c in self.layons:
            i = self.i_layon[c.name]
            z[i:i + 3] = layon_start(c, s.initial_speed(c, t), self.pv(c.layon.load, t))
        for sp in self.spans:  # in the order the web flows: what feeds a span comes before it
            first = self.i_eps[sp.name]
            if sp.eps_start is not None:  # every layer of a laminate at it
                z[first:first + self.layers[sp.name]] = sp.eps_start
                continue
            up, down = self.up[sp.name], self.down[sp.name]
            for i, entry in enumerate(self.entries(sp, t, z)):
                # at rest between its ends' start speeds (or refused, naming why)
                z[first + i] = start_strain(sp, up, down, s.initial_speed(up, t), s.initial_speed(down, t), float(entry) - 1.0)
        return z

    def apply_event(self, ev, z):
        comp = self.s.component(ev.component)
        if isinstance(comp, Span):
            w1, w2 = self.web[comp.name]
            ch = dict(ev.changes)
            if "web" in ch:
                w1 = w2 = ch["web"]
            w1 = ch.get("wp1", w1)
            w2 = ch.get("wp2", w2)
            self.web[comp.name] = (w1, w2)
        else:
            J, R, b = self.inertia[comp.name]
            i = self.i_omega[comp.name]
            v = R * z[i]
            J = ev.changes.get("J", J)
            R = ev.changes.get("R", R)
            b = ev.changes.get("b", b)
            self.inertia[comp.name] = [J, R, b]
            z[i] = v / R  # the same surface speed
        return z

    def largest_excess(self, t, z, bounds) -> tuple:
        """(span, its T, |T| - its bound) of the span whose tension comes nearest its bound (bound.py)."""
        _, q, _ = self.evaluate(t, z)
        span = max(bounds, key=lambda n: abs(q[n]["T"]) - bounds[n])
        T = float(q[span]["T"])
        return span, T, abs(T) - bounds[span]

    def load_cell(self, cell, q) -> float:
        """A roller's load cell: the resultant of the web forces it carries, as the Roller's pulls."""
        F_a = sum(q[sp.name]["T"] + q[sp.name]["p"] for sp in self.ins[cell.name])
        F_b = sum(q[sp.name]["T"] for sp in self.outs[cell.name])
        return float(np.sqrt(max(F_a * F_a + F_b * F_b - 2.0 * F_a * F_b * np.cos(np.radians(cell.wrap)), 0.0)))

    def record(self, t, z):
        dz, q, v = self.evaluate(t, z)
        row = []
        for cname, quantity in self.s.record:
            c = self.s.component(cname)
            if isinstance(c, Span):
                row.append(q[cname][quantity])
            elif quantity == "v":
                row.append(v[cname])
            elif quantity in ("v_web", "slip", "traction", "mu_eff", "h_air"):
                row.append(q[cname][quantity])
            elif quantity == "eps":
                row.append(self.pv(c.strain, t))
            elif quantity == "omega":
                row.append(z[self.i_omega[cname]])
            elif quantity == "tau":
                row.append(q[cname]["tau"] if cname in self.i_loop else self.torque(c, t, z))
            elif quantity == "r":
                row.append(self.radius(c, z))
            elif quantity == "y":
                row.append(z[self.i_y[cname]])
            elif quantity == "y_dot":
                row.append(z[self.i_y[cname] + 1])
            elif quantity == "F":
                row.append(self.load_cell(c, q))
            elif quantity.startswith("layon."):
                row.append(q[f"{cname}.layon"][quantity])
        return row


def atol_of(ode: LineODE, z0):
    a = np.empty(ode.n)
    a[: ode.n_strains] = 1e-15
    for name, i in ode.i_omega.items():
        a[i] = 1e-11 * max(1.0, 1.0 / ode.inertia[name][1])
    for name, i in ode.i_y.items():
        a[i] = 1e-13
        a[i + 1] = 1e-12
    for name, i in ode.i_vw.items():
        a[i] = 1e-11
    for i in list(ode.i_grip.values()) + list(ode.i_brake.values()):  # shares of a limit
        a[i] = 1e-11
    for name, i in ode.i_r.items():
        a[i] = 1e-13
    for name, (i, m) in ode.i_loop.items():  # torques
        a[i] = 1e-10
        if m is not None:
            a[m] = 1e-10
    for name, i in ode.i_trim.items():  # speeds
        a[i] = 1e-12
    for name, i in ode.i_angle.items():  # radians
        a[i] = 1e-12
    for name, i in ode.i_layon.items():  # a carriage's metres (its nip compresses by micrometres), m/s, rad/s
        a[i], a[i + 1], a[i + 2] = 1e-14, 1e-12, 1e-11
    return a


def layon_nip(layon, load, X, X_rate, omega_l, r, r_rate, e, psi, psi_rate, omega) -> dict:
    """A lay-on roller against a winder [R18] (docs/physics.md, "A lay-on roller"), in vectors: the winder's
    axis O at the origin, its surface a circle of radius r about C = e (sin psi, cos psi) (runout [R15]), the
    carriage's line u = (sin beta, cos beta) with psi - beta = phi, the roller's axis D = X u. The nip along
    n = (D - C)/|D - C| compresses by delta = r + r_l - |D - C| and pushes with N = k delta + c delta' while
    both are positive; the carriage takes N n.u against the load; at the contact P = C + r n the winder's
    surface moves at omega (n.P) across n, the roller's at omega_l r_l, and the traction mu N tanh(slip/v_s)
    turns the roller and brakes the winder with the arm n.P. Returns N, delta, X'', omega_l', and the
    winder's torque."""
    beta = -layon.angle  # the carriage's line in runout's frame, mirrored on a winder (s = -1)
    u = np.array([math.sin(beta), math.cos(beta)])
    C = e * np.array([math.sin(psi), math.cos(psi)])
    C_rate = e * psi_rate * np.array([math.cos(psi), -math.sin(psi)])
    gap = X * u - C
    d = math.hypot(*gap)
    n = gap / d
    delta = r + layon.radius - d
    delta_rate = r_rate - float(n @ (X_rate * u - C_rate))
    push = layon.stiffness * delta + layon.damping * delta_rate
    N = push if delta > 0.0 and push > 0.0 else 0.0
    arm = r + float(n @ C)  # n.P, P = C + r n
    f = layon.mu * N * math.tanh((omega * arm - omega_l * layon.radius) / layon.v_slip)
    return {"layon.N": N, "layon.delta": delta, "layon.x": X, "layon.v": X_rate, "layon.omega": omega_l,
            "X''": (N * float(n @ u) - load) / layon.mass, "omega_l'": (layon.radius * f - layon.bearing * omega_l) / layon.inertia,
            "torque": -arm * f}


def bounce_omega(layon, load, e):
    """The winder's speed of rotation above which a lay-on roller under `load` lets go of a roll with runout e
    [R18]: the carriage on the nip's spring k and damper c, its base moved by the surface's e cos(omega t), takes a
    force that swings by m omega^2 e |k + i c omega| / |k - m omega^2 + i c omega|; that swing reaches the load at
    omega_c (below the nip's resonance sqrt(k/m), where it grows with omega). None where it never does there.
    A rigid nip's is sqrt(F/(m e))."""
    m, k, c = layon.mass, layon.stiffness, layon.damping

    def excess(w):
        return m * w * w * e * abs(complex(k, c * w)) / abs(complex(k - m * w * w, c * w)) - load

    top = math.sqrt(k / m)
    return brentq(excess, 0.0, top, xtol=1e-14, rtol=4 * np.finfo(float).eps) if excess(top) >= 0.0 else None


def layon_start(node, v0, load):
    """(X, X', omega_l) of a winder's lay-on roller at the start: the nip pressed by load/k at the roll's start
    angle (runout's centre at phi0 = layon.angle - phase from the carriage's line), the carriage at rest, the roller
    turning with the roll's surface speed v0."""
    layon, R = node.layon, node.R
    e, phi0 = (node.runout.eccentricity, layon.angle - node.runout.phase) if node.runout is not None else (0.0, 0.0)
    reach = R + layon.radius - load / layon.stiffness
    return (e * math.cos(phi0) + math.sqrt(reach**2 - (e * math.sin(phi0)) ** 2), 0.0, v0 / layon.radius)


def runout_geometry(node, L0, angle, omega, R) -> dict:
    """A roll with runout [R15] (docs/physics.md, "A roll with runout"): its surface a circle of radius R
    about the centre C, e off the axis O; the web runs from the fixed point B = (L0, R) (its span's far
    end; a winder seen in a mirror) along the line that touches the circle on the web's side. Returns
    the span's length L = |T - B| and its rate dL/dt, the arm p (the axis's distance from the line),
    and the web's speed across the span's moving end, omega*p + dL/dt (a winder's omega*p - dL/dt)."""
    s = 1.0 if node.type == "unwinder" else -1.0
    if node.runout.harmonics:
        return out_of_round_geometry(node, L0, angle, omega, R, s)
    e = node.runout.eccentricity
    psi = s * (angle + node.runout.phase)
    C = e * np.array([np.sin(psi), np.cos(psi)])
    C_rate = e * s * omega * np.array([np.cos(psi), -np.sin(psi)])
    B = np.array([L0, R])
    d = float(np.hypot(*(C - B)))
    L = math.sqrt(d * d - R * R)
    # The line from B turns off BC by asin(R/d), towards the web's side (clockwise seen from B).
    beta = -math.asin(R / d)
    u = (C - B) / d
    direction = np.array([u[0] * math.cos(beta) - u[1] * math.sin(beta), u[0] * math.sin(beta) + u[1] * math.cos(beta)])
    p = abs(float(direction[1] * B[0] - direction[0] * B[1]))  # |direction x (O - B)|
    dL = float(np.dot(C - B, C_rate)) / L
    return {"L": L, "dL": dL, "p": p, "v": omega * p + s * dL}


def out_of_round_geometry(node, L0, angle, omega, R, s) -> dict:
    """`runout_geometry` of an out-of-round roll [R15]: its support function h(theta) = R + e cos(theta - psi)
    + sum a_k cos(k (theta - psi_k)) over the normal n = (sin theta, cos theta); the web's line through
    B = (L0, R) touches where B.n = h, found by Brent's method on the web's side (|theta| < pi/2, where
    B.n - h changes sign once); p = h there, L the distance from the touching point h n + h' t to B,
    and dL/dt from L at the angle +- 1e-6 rad (a central difference, unlike the Roller's closed form)."""
    runout = node.runout
    terms = ((1, runout.eccentricity, runout.phase),) + tuple(runout.harmonics)

    def support(theta, at):
        h = R + sum(a * math.cos(k * (theta - s * (at + ph))) for k, a, ph in terms)
        slope = -sum(a * k * math.sin(k * (theta - s * (at + ph))) for k, a, ph in terms)
        return h, slope

    def touch(at):
        theta = brentq(lambda th: L0 * math.sin(th) + R * math.cos(th) - support(th, at)[0], -0.5 * math.pi, 0.5 * math.pi,
                       xtol=1e-15, rtol=1e-15)
        h, slope = support(theta, at)
        point = h * np.array([math.sin(theta), math.cos(theta)]) + slope * np.array([math.cos(theta), -math.sin(theta)])
        return h, float(np.hypot(*(np.array([L0, R]) - point)))

    p, L = touch(angle)
    dL = omega * (touch(angle + 1e-6)[1] - touch(angle - 1e-6)[1]) / 2e-6
    return {"L": L, "dL": dL, "p": p, "v": omega * p + s * dL}


# The least wrap whose web mass counts (a roller the web touches only at a nip), as the Roller's.
THETA_MIN = np.radians(5.0)


def grip(u, s, v_slip, creep, static):
    """(du/dt, g) of a contact's grip u at slip s (docs/physics.md, "Contacts that stick"): the bristles'
    deflection rate du/dt = (s - |s| u/psi(s))/creep, psi(s) = 1 + (static - 1) exp(-(s/v_slip)^2) the
    Stribeck limit, and g = u + exp(-(s/v_slip)^2) (s - |s| u/psi(s))/v_slip the share of the kinetic
    limit the contact carries (bristle and its damping, which fades with the slip as LuGre's sigma_1(s)).
    Steady, s = 0 where |u| < psi(0) (it sticks) or u = psi(s) sign(s)."""
    rate = s - abs(s) * u / stribeck(s, v_slip, static)
    return rate / creep, u + np.exp(-np.square(s / v_slip)) * rate / v_slip


def stribeck(s, v_slip, static):
    """psi(s) = 1 + (static - 1) exp(-(s/v_slip)^2): the grip's limit at slip s, static at rest, 1 sliding."""
    return 1.0 + (static - 1.0) * np.exp(-np.square(s / v_slip))


def start_grip(tr):
    """A given start's grip: 0 where the web starts at the surface's speed; where it starts sliding
    (slip_start s0 != 0), the grip of a steady slide, psi(s0) sign(s0): from 0 the contact would carry
    no friction for the nanoseconds the bristles take to deflect, an event as stiff as any in the line."""
    s0 = tr.slip_start
    if s0 == 0.0:
        return 0.0
    return math.copysign(stribeck(s0, tr.v_slip, tr.static), s0)


def friction(tr, R, wrap_deg, web, v_w, v_s, T_a, T_b, load, u) -> dict:
    """The contact of a web that may slip (docs/physics.md, [R6]-[R8]): the friction f on the web along
    its motion, from the capstan law on the wrap and a nip on its entry or exit side, both carrying the
    share g of their kinetic limit that the contact's grip u gives (`grip`), the wrap's law on
    T - rho_l v_w^2 (the pressure its centripetal force leaves), under Knox and Sweeney's air film at
    the entry tension; with the grip's rate and what a roller with traction reports (the share of its
    traction the tensions use, `traction_used`: |g| once steady)."""
    theta = math.radians(wrap_deg)
    s = v_w - v_s
    du, g = grip(u, s, tr.v_slip, tr.creep, tr.static)
    mu, h = tr.mu, 0.0
    if tr.roughness > 0.0:
        # The film forms where both surfaces drag the air in: T_a's side running forward, T_b's back.
        V = (v_w + v_s) / 2.0
        tw = (T_a if V >= 0.0 else T_b) / web.width
        if tw <= 0.0:
            h, mu = 3.0 * tr.roughness, 0.0
        else:
            h = 0.643 * R * (12.0 * tr.viscosity * abs(V) / tw) ** (2.0 / 3.0)
            mu = tr.mu * min(1.0, max(0.0, (3.0 * tr.roughness - h) / (2.0 * tr.roughness)))
    n = tr.nip_mu * load
    f_nip = -n * g
    relief = web.rho_l * v_w * v_w
    A, B = T_a - relief, T_b - relief
    T_in, T_out = (A - f_nip, B) if tr.nip_side == "entry" else (A, B + f_nip)
    f_wrap = -2.0 * math.sqrt(max(T_in, 0.0) * max(T_out, 0.0)) * bounded_sinh(mu * theta * g / 2.0)
    # What the Roller's output `traction` reports: the share the tensions use at rest (|g| once steady).
    used = traction_used(A, B, n, mu * theta) if tr.nip_side == "entry" else traction_used(B, A, n, mu * theta)
    return {"f": f_nip + f_wrap, "du": du, "m_w": web.rho_l * R * max(theta, THETA_MIN), "v_web": v_w, "slip": s,
            "traction": used, "mu_eff": mu, "h_air": h}


def traction_used(T_a, T_b, n, w):
    """The share of the traction in use: g solving T_b = (T_a + n g) exp(w g), |g|, the tensions less
    rho_l v^2 and the nip on T_a's side (docs/physics.md); a slack side leaves the nip alone."""
    if T_a <= 0.0 or T_b <= 0.0:
        if n > 0.0:
            return abs(T_b - T_a) / n
        return 0.0 if T_a == T_b else 1.0
    if n == 0.0 and w == 0.0:
        return 0.0 if T_a == T_b else 1.0
    if n == 0.0:
        return abs(np.log(T_b / T_a)) / w
    if w == 0.0:
        return abs(T_b - T_a) / n
    from scipy.optimize import brentq

    lo = -T_a / n * (1.0 - 1e-15)  # T_a + n g > 0 there
    phi = lambda g: np.log(T_a + n * g) + w * g - np.log(T_b)
    hi = 1.0
    while phi(hi) < 0.0:
        hi *= 2.0
    return abs(brentq(phi, lo, hi, xtol=1e-15))


# sinh's argument beyond which the wrap's law goes on linearly (sinh(300) = 1e130; a float overflows past
# 710, and products with it sooner): a wrap that far in holds more than any tension, so its friction
# there only has to stay finite and rising (mu = 1e6 in a trial state of the integrator).
SINH_MAX = 300.0


def bounded_sinh(x):
    """sinh(x), continued linearly past +-SINH_MAX (a huge mu theta: no overflow in a trial state)."""
    if abs(x) <= SINH_MAX:
        return math.sinh(x)
    return math.copysign(math.sinh(SINH_MAX) * (1.0 + abs(x) - SINH_MAX), x)


def holding_limit(w, n, static, relief, low, nip_low):
    """The highest tension a contact holds on its high side against `low` on the other, at its static limit
    g = static: the wrap (w = mu_eff theta) multiplies T - rho_l v^2 by exp(w static), the nip adds
    n static before it (on the low side) or after it (docs/physics.md, "Rollers that slip")."""
    grow = math.exp(min(w * static, SINH_MAX))
    if nip_low:
        wrapped = low - relief + n * static
        return relief + wrapped * grow if wrapped > 0.0 else low + n * static
    return (relief + (low - relief) * grow if low > relief else low) + n * static


def merged(cuts):
    """Times within DUE of the one before dropped (a sample on a breakpoint is one event), in order."""
    out = []
    for t in cuts:
        if not out or t - out[-1] > DUE:
            out.append(t)
    out[-1] = cuts[-1]  # the stop
    return out


def reference(scene: Scene, times=None, rtol=RTOL) -> Result:
    """The line integrated by Radau, sampled at `times` (default: the scene's
    communication points, breakpoints included)."""
    start = clock.perf_counter()
    ode = LineODE(scene)
    if times is None:
        from .master import scene_grid

        times = scene_grid(scene)
    times = np.asarray(times, dtype=float)
    cuts = merged(sorted(set([0.0, scene.stop_time] + scene.breakpoints()) | ode.sample_times()))
    events = {}
    for ev in scene.events:
        events.setdefault(ev.time, []).append(ev)
    z = ode.initial_state()
    atol = atol_of(ode, z)
    bounds = tension_bounds(scene)

    def runaway_event(t, z):  # > 0 while every tension is inside its bound (bound.py)
        return -ode.largest_excess(t, z, bounds)[2]

    runaway_event.terminal = True
    rows = []
    nfev = 0
    recorded = np.zeros(len(times), dtype=bool)
    out = [None] * len(times)
    for a, b in zip(cuts[:-1], cuts[1:]):
        if a in events:
            for ev in events[a]:
                z = ode.apply_event(ev, z)
        ode.segment = (a, b)
        ode.hold(a, z)
        inside = np.nonzero((times >= a - 1e-12) & (times <= b + 1e-12) & ~recorded)[0]
        sol = solve_ivp(ode.rhs, (a, b), z, method="Radau", rtol=rtol, atol=atol, dense_output=True, events=runaway_event)
        if sol.status == 1:  # a tension passed its bound
            t = float(sol.t_events[0][0])
            span, T, _ = ode.largest_excess(t, sol.y_events[0][0], bounds)
            raise runaway(scene.name, span, T, bounds[span], t)
        if not sol.success:
            raise RuntimeError(f"Radau failed on [{a}, {b}]: {sol.message}")
        nfev += sol.nfev
        for k in inside:
            t = times[k]
            zt = sol.sol(t) if t < b else sol.y[:, -1]
            out[k] = ode.record(t, zt)
            recorded[k] = True
        z = sol.y[:, -1].copy()
    rows = np.array(out, dtype=float)
    return Result(
        scene=scene.name,
        columns=scene.columns(),
        time=times,
        data=rows,
        info={"method": f"monolithic reference (Radau, rtol {rtol:g})", "rhs_evaluations": nfev, "wall_time": clock.perf_counter() - start},
    )
