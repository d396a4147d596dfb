//! The web's contact with a roller it may slip on (the Roller FMU's
//! documentation numbers them; docs/physics.md derives them and gives their sources):
//!
//! [R6]  m_w dv_w/dt = T_b - T_a + f,   J domega/dt = -r f + tau - b omega     (s = v_w - r omega)
//!       m_w = m_web * r * max(theta, THETA_MIN): the web's mass on the wrap
//! [R7]  f = f_nip + f_wrap,  T' = T - m_web v_w^2 (the pressure left after the web's centripetal force),
//!       g the bristles' share of the kinetic limit (`bristle`, the grip u a state):
//!       du/dt = (s - |s| u/psi(s))/delta,  g = u + exp(-(s/v_slip)^2) (s - |s| u/psi(s))/v_slip,
//!       psi(s) = 1 + (k_s - 1) exp(-(s/v_slip)^2)
//!       f_nip  = -mu_nip N g                                       (the nip line, on the wrap's entry or exit)
//!       f_wrap = -2 sqrt(T'_in+ T'_out+) sinh(mu_eff theta g / 2)  (the wrap between the nip and the other side)
//!       nip at the entry (`nip.side` 0): T'_in = T'_a - f_nip, T'_out = T'_b
//!       nip at the exit  (`nip.side` 1): T'_in = T'_a,         T'_out = T'_b + f_nip
//!       at rest (m_w dv_w/dt = 0): T'_b = (T'_a + mu_nip N g) exp(mu_eff theta g) (entry), or
//!       T'_b = T'_a exp(mu_eff theta g) + mu_nip N g (exit): the capstan law with the share g in use
//!       (|g| = 1 sliding); a side where T' <= 0 leaves the wrap no traction
//! [R8]  h = 0.643 r (12 eta V / T_w)^(2/3),  V = |v_w + r omega|/2,  T_w = T_entry / W, T_entry the
//!       tension of the side the air is dragged in from: T_a where v_w + r omega >= 0, else T_b
//!       mu_eff = mu * clamp((3 sigma - h)/(2 sigma), 0, 1)   (sigma > 0; without air mu_eff = mu)
//!
//! Each result is a value with its gradient in the contact's knowns (`Dual`): the tangents are the
//! equations' own, differentiated once, here, and formed once per point for every direction.

use crate::bristle;
use crate::number::{Lanes, Number};
use crate::parameters::Parameters;

/// How the web meets the roller: by [R7]'s bristle, which covers sticking and sliding alike; or,
/// where a line solves the steady state it starts in, held (`bristle::held`): the grip's rate is
/// then the slip itself, s/delta, so that the steady state is the sticking one (s = 0, the grip
/// solved from the force balance) whatever the grip needs, and a grip beyond its limit is found and refused.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Friction {
    #[default]
    Bristle,
    Held,
}

/// Which side of the wrap the nip presses on (`nip.side`), named for the web running from web_a
/// to web_b: the entry (web_a's side, 0) or the exit (web_b's, 1). It stays there when the web runs back.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NipSide {
    #[default]
    Entry,
    Exit,
}

impl NipSide {
    pub fn of(p: &Parameters) -> NipSide {
        if p.nip_side == 1 {
            NipSide::Exit
        } else {
            NipSide::Entry
        }
    }

    /// Its value of `nip.side`.
    pub fn value(self) -> i32 {
        self as i32
    }
}

/// sinh's argument past which the wrap's law goes on linearly (sinh(300) = 1e130, a float's limit near 710).
pub const SINH_MAX: f64 = 300.0;

/// The least wrap whose web mass [R6] counts: a roller the web only touches at a nip still
/// carries the web over a short arc there, and [R6] needs a mass to stay an ODE.
pub const THETA_MIN: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// The contact's knowns, the components of a gradient: the web's speed, the surface's, the
/// tensions T_a and T_b, the radius, the grip.
pub const V_WEB: usize = 0;
pub const V_SURFACE: usize = 1;
pub const T_A: usize = 2;
pub const T_B: usize = 3;
pub const RADIUS: usize = 4;
pub const GRIP: usize = 5;
pub const KNOWNS: usize = 6;
pub type Gradient = [f64; KNOWNS];

/// A value and its gradient in the knowns.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dual {
    pub x: f64,
    pub d: Gradient,
}

impl Dual {
    pub const fn constant(x: f64) -> Dual {
        Dual { x, d: [0.0; KNOWNS] }
    }

    fn known(x: f64, i: usize) -> Dual {
        let mut d = [0.0; KNOWNS];
        d[i] = 1.0;
        Dual { x, d }
    }

    /// The differential along a direction in the knowns.
    #[inline]
    pub fn along(&self, direction: &Gradient) -> f64 {
        self.d.iter().zip(direction).map(|(g, d)| g * d).sum()
    }

    /// This result in the roller's number, the knowns (v_web, v_surface, T_a, T_b, r, grip) in it:
    /// the contact's own gradient, chained.
    #[inline]
    pub fn lift<N: Number>(&self, knowns: &[N; KNOWNS]) -> N {
        N::chain(self.x, &self.d, knowns)
    }

    /// f(self), f' its slope there.
    fn map(self, x: f64, slope: f64) -> Dual {
        Dual { x, d: self.d.map(|g| slope * g) }
    }

    fn plus(self, o: Dual) -> Dual {
        Dual { x: self.x + o.x, d: std::array::from_fn(|i| self.d[i] + o.d[i]) }
    }

    fn minus(self, o: Dual) -> Dual {
        Dual { x: self.x - o.x, d: std::array::from_fn(|i| self.d[i] - o.d[i]) }
    }

    fn times(self, o: Dual) -> Dual {
        Dual { x: self.x * o.x, d: std::array::from_fn(|i| self.d[i] * o.x + self.x * o.d[i]) }
    }

    fn scaled(self, a: f64) -> Dual {
        self.map(a * self.x, a)
    }

    /// As a number of the roller's equations: its gradient the lanes.
    fn lanes(self) -> Lanes<KNOWNS> {
        Lanes { x: self.x, d: self.d }
    }

    fn of(x: Lanes<KNOWNS>) -> Dual {
        Dual { x: x.x, d: x.d }
    }
}

/// What the contact needs from the roller now.
#[derive(Clone, Copy, Debug, Default)]
pub struct State {
    pub v_web: f64,
    pub v_surface: f64,
    pub t_a: f64,
    pub t_b: f64,
    /// The nip's load N (a table of time: no known of the contact).
    pub nip_load: f64,
    pub radius: f64,
    /// The bristles' grip u [R7].
    pub grip: f64,
}

/// The contact's results [R6]–[R8], each with its gradient.
#[derive(Clone, Copy, Debug, Default)]
pub struct Contact {
    /// The friction force on the web, along its motion.
    pub force: Dual,
    /// The grip's rate du/dt [R7].
    pub grip_rate: Dual,
    pub mu_eff: Dual,
    pub h_air: Dual,
}

/// The web's mass on the roller [R6].
pub fn wrap_mass(p: &Parameters, radius: f64) -> f64 {
    p.mass_a[0] * radius * p.traction_wrap.max(THETA_MIN)
}

/// The web's acceleration over the roller [R6].
pub fn web_acceleration(p: &Parameters, s: &State, friction: Dual) -> Dual {
    // (T_b - T_a + f)/m_w with m_w proportional to r.
    let mut pull = friction;
    pull.x += s.t_b - s.t_a;
    pull.d[T_B] += 1.0;
    pull.d[T_A] -= 1.0;
    let m = wrap_mass(p, s.radius);
    let a = pull.scaled(1.0 / m);
    let mut a_r = a;
    a_r.d[RADIUS] -= a.x / s.radius;
    a_r
}

fn positive(t: Dual) -> Dual {
    if t.x > 0.0 {
        t
    } else {
        Dual::default()
    }
}

/// The air film [R8]: its thickness and the coefficient of friction it leaves.
fn air(p: &Parameters, s: &State) -> (Dual, Dual) {
    let sigma = p.air_roughness;
    if sigma <= 0.0 {
        return (Dual::default(), Dual::constant(p.traction_mu));
    }
    let speed = Dual::known(s.v_web, V_WEB).plus(Dual::known(s.v_surface, V_SURFACE)).scaled(0.5);
    // The film forms where both surfaces drag the air in: the entry in the mean speed's direction.
    let (v, entry) = if speed.x < 0.0 { (speed.scaled(-1.0), Dual::known(s.t_b, T_B)) } else { (speed, Dual::known(s.t_a, T_A)) };
    let tw = entry.scaled(1.0 / p.traction_width);
    if tw.x <= 0.0 {
        // No tension presses the web down: it lifts off, no traction (reported as a film of 3 sigma).
        return (Dual::constant(3.0 * sigma), Dual::default());
    }
    if v.x == 0.0 {
        return (Dual::default(), Dual::constant(p.traction_mu));
    }
    // h = 0.643 r (12 eta v / t_w)^(2/3): d ln h = d ln r + (2/3)(d ln v - d ln t_w).
    let h = 0.643 * s.radius * (12.0 * p.air_viscosity * v.x / tw.x).powf(2.0 / 3.0);
    let mut d = [0.0; KNOWNS];
    for (i, di) in d.iter_mut().enumerate() {
        *di = h * ((2.0 / 3.0) * (v.d[i] / v.x - tw.d[i] / tw.x));
    }
    d[RADIUS] += h / s.radius;
    let h = Dual { x: h, d };
    let a = (3.0 * sigma - h.x) / (2.0 * sigma);
    let mu = if a >= 1.0 {
        Dual::constant(p.traction_mu)
    } else if a <= 0.0 {
        Dual::default()
    } else {
        h.map(p.traction_mu * a, -p.traction_mu / (2.0 * sigma))
    };
    (h, mu)
}

/// The tensions less the web's centripetal force, T - m_web v_w^2: what presses the web on the wrap [R7].
fn relieved(p: &Parameters, s: &State) -> (Dual, Dual) {
    let rho = p.mass_a[0];
    let relief = Dual::known(s.v_web, V_WEB).map(rho * s.v_web * s.v_web, 2.0 * rho * s.v_web);
    (Dual::known(s.t_a, T_A).minus(relief), Dual::known(s.t_b, T_B).minus(relief))
}

/// [R7] and [R8] at the contact's state, its bristle as `friction` has it.
pub fn contact(p: &Parameters, s: &State, friction: Friction) -> Contact {
    let slip = Dual::known(s.v_web, V_WEB).minus(Dual::known(s.v_surface, V_SURFACE));
    let grip = Dual::known(s.grip, GRIP);
    let bristle = match friction {
        Friction::Bristle => bristle::grip(slip.lanes(), grip.lanes(), p.traction_static, p.traction_v_slip, p.traction_creep),
        Friction::Held => bristle::held(slip.lanes(), grip.lanes(), p.traction_v_slip, p.traction_creep),
    };
    let (g, grip_rate) = (Dual::of(bristle.share), Dual::of(bristle.rate));
    let (h_air, mu_eff) = air(p, s);
    let f_nip = g.scaled(-p.nip_mu * s.nip_load);
    let (t_a, t_b) = relieved(p, s);
    // The wrap's two ends: the nip's jump -f_nip lies between T_a and the wrap, or between the wrap and T_b.
    let (t_in, t_out) = match NipSide::of(p) {
        NipSide::Entry => (t_a.minus(f_nip), t_b),
        NipSide::Exit => (t_a, t_b.plus(f_nip)),
    };
    let product = positive(t_in).times(positive(t_out));
    let root = if product.x > 0.0 { product.map(product.x.sqrt(), 0.5 / product.x.sqrt()) } else { Dual::default() };
    // sinh(k g), k = mu_eff theta / 2.
    let kg = mu_eff.scaled(0.5 * p.traction_wrap).times(g);
    // Past |k g| = SINH_MAX it goes on linearly (as the reference's does): a trial state's huge grip stays finite.
    let sinh = if kg.x.abs() <= SINH_MAX {
        kg.map(kg.x.sinh(), kg.x.cosh())
    } else {
        kg.map(SINH_MAX.sinh().copysign(kg.x) * (1.0 + kg.x.abs() - SINH_MAX), SINH_MAX.sinh())
    };
    let f_wrap = root.times(sinh).scaled(-2.0);
    Contact { force: f_nip.plus(f_wrap), grip_rate, mu_eff, h_air }
}

/// Where the grip has reached its static limit (|u| >= psi(0) (1 - 1e-6), the contact's "slides"),
/// what the tensions need of the contact against what it can give, in words: a wrap's capstan limit
/// on the side the higher tension needs, a nip's mu N; None while it sticks.
pub fn demand(p: &Parameters, s: &State) -> Option<String> {
    if s.grip.abs() < p.traction_static * (1.0 - 1e-6) {
        return None;
    }
    let tenth = |x: f64| (10.0 * x).round() / 10.0;
    let (t_a, t_b) = relieved(p, s);
    let relief = s.t_a - t_a.x;
    let (_, mu_eff) = air(p, s);
    let wrap = p.traction_static * mu_eff.x * p.traction_wrap;
    let nip = p.traction_static * p.nip_mu * s.nip_load;
    let (side, need, other) = if s.t_b >= s.t_a { ("downstream", s.t_b, t_a.x) } else { ("upstream", s.t_a, t_b.x) };
    let mu = if p.traction_static == 1.0 { format!("mu {}", mu_eff.x) } else { format!("mu {}, static x{}", mu_eff.x, p.traction_static) };
    Some(if nip == 0.0 {
        let limit = relief + other.max(0.0) * wrap.exp();
        format!("needs {} N {side}, its capstan limit is {} N ({mu}, {} deg)", tenth(need), tenth(limit), tenth(p.traction_wrap.to_degrees()))
    } else if wrap == 0.0 {
        format!("needs {} N across its nip, its limit is {} N (nip.mu {} x {} N)", tenth((s.t_b - s.t_a).abs()), tenth(nip), p.nip_mu * p.traction_static, s.nip_load)
    } else {
        format!("needs {} % of the traction its nip and its wrap give together ({mu}, {} deg; nip.mu {} x {} N)", tenth(100.0 * s.grip.abs() / p.traction_static), tenth(p.traction_wrap.to_degrees()), p.nip_mu, s.nip_load)
    })
}

/// The share of the available traction the tensions use: the direction g in [R7]'s law at rest,
/// T'_b = (T'_a + mu_nip N g) exp(mu_eff theta g) with the nip at the entry, solved for g; its
/// magnitude. With the nip at the exit, T'_b = T'_a exp(mu_eff theta g) + mu_nip N g is the same law
/// read from web_b to web_a (T'_a and T'_b swapped, g negated), so |g| is the entry's with the sides
/// swapped. On a wrap alone |ln(T'_b/T'_a)|/(mu_eff theta), at a nip alone |T_b - T_a|/(mu_nip N),
/// also where a side's T' <= 0 leaves the wrap no traction. With no traction available at all, 1
/// where the tensions differ, else 0.
pub fn traction_used(p: &Parameters, s: &State, mu_eff: Dual) -> Dual {
    // A share past f64's range (a traction limit of 1e-300 N against a tension difference) reads as the
    // largest finite number, not inf: the web slides there either way.
    let used = share_used(p, s, mu_eff);
    if used.x.is_finite() {
        used
    } else {
        Dual::constant(f64::MAX)
    }
}

fn share_used(p: &Parameters, s: &State, mu_eff: Dual) -> Dual {
    let (t_a, t_b) = match (NipSide::of(p), relieved(p, s)) {
        (NipSide::Entry, (a, b)) => (a, b),
        (NipSide::Exit, (a, b)) => (b, a),
    };
    let nip = p.nip_mu * s.nip_load;
    let wrap = mu_eff.scaled(p.traction_wrap);
    let saturated = || Dual::constant(if t_a.x == t_b.x { 0.0 } else { 1.0 });
    let nip_alone = || t_b.minus(t_a).scaled(1.0 / nip);
    if t_a.x <= 0.0 || t_b.x <= 0.0 {
        return if nip > 0.0 { abs(nip_alone()) } else { saturated() };
    }
    if nip == 0.0 && wrap.x == 0.0 {
        return saturated();
    }
    if nip == 0.0 {
        // |ln(T_b/T_a)|/(mu theta)
        let ln = t_b.map(t_b.x.ln(), 1.0 / t_b.x).minus(t_a.map(t_a.x.ln(), 1.0 / t_a.x));
        let x = ln.x / wrap.x;
        return abs(Dual { x, d: std::array::from_fn(|i| (ln.d[i] - x * wrap.d[i]) / wrap.x) });
    }
    if wrap.x == 0.0 {
        return abs(nip_alone());
    }
    // phi(g) = ln(T_a + n g) + w g - ln T_b = 0, increasing in g where T_a + n g > 0: Newton from the
    // nip's own estimate, kept inside that domain.
    let w = wrap.x;
    let mut g = ((t_b.x - t_a.x) / nip).clamp(-1.0, 1.0);
    for _ in 0..50 {
        let m = t_a.x + nip * g;
        if m <= 0.0 {
            g = 0.5 * (g - t_a.x / nip);
            continue;
        }
        let step = (m.ln() + w * g - t_b.x.ln()) / (nip / m + w);
        g -= step;
        if step.abs() <= 1e-15 * (1.0 + g.abs()) {
            break;
        }
    }
    let m = t_a.x + nip * g;
    // dphi = dT_a/m + g dw - dT_b/T_b + (n/m + w) dg = 0
    let slope = nip / m + w;
    abs(Dual { x: g, d: std::array::from_fn(|i| -(t_a.d[i] / m + g * wrap.d[i] - t_b.d[i] / t_b.x) / slope) })
}

fn abs(x: Dual) -> Dual {
    if x.x < 0.0 {
        x.scaled(-1.0)
    } else {
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> Parameters {
        Parameters {
            traction: true,
            traction_mu: 0.3,
            traction_wrap: std::f64::consts::FRAC_PI_2,
            traction_v_slip: 1e-3,
            traction_static: 1.0,
            traction_creep: 5e-8,
            traction_width: 1.0,
            air_viscosity: 1.81e-5,
            mass_a: [0.0167, 1.0, 1.0, 1.0],
            ..Parameters::default()
        }
    }

    /// Steady sliding where the web slips (the grip at its limit, sign(s)), at rest where it does not.
    fn state(v_web: f64, v_surface: f64, t_a: f64, t_b: f64) -> State {
        let s = v_web - v_surface;
        let grip = if s == 0.0 { 0.0 } else { s.signum() };
        State { v_web, v_surface, t_a, t_b, nip_load: 0.0, radius: 0.05, grip }
    }

    /// A web too light for its centripetal force to count (m = 0).
    fn massless() -> Parameters {
        Parameters { mass_a: [0.0; 4], ..params() }
    }

    /// Sliding (s >> v_slip) on a wrap, at rest: the capstan law, T_b = T_a exp(mu theta).
    #[test]
    fn sliding_on_a_wrap_holds_the_capstan_ratio() {
        let p = massless();
        let (t_a, mu_theta) = (50.0, 0.3 * std::f64::consts::FRAC_PI_2);
        for (s, t_b) in [(0.1, t_a * mu_theta.exp()), (-0.1, t_a * (-mu_theta).exp())] {
            let c = contact(&p, &state(5.0 + s, 5.0, t_a, t_b), Friction::Bristle);
            let rest = t_b - t_a + c.force.x;
            assert!(rest.abs() < 1e-12 * t_a, "s = {s}: {rest}");
            let used = traction_used(&p, &state(5.0 + s, 5.0, t_a, t_b), c.mu_eff);
            assert!((used.x - 1.0).abs() < 1e-14, "{}", used.x);
        }
    }

    /// A nip alone slides at T_b - T_a = mu_nip N; nip and wrap in series: (T_a + mu N) e^(mu theta).
    #[test]
    fn a_sliding_nip_passes_mu_n_and_the_wrap_multiplies_after_it() {
        let p = Parameters { traction_wrap: 0.0, nip_mu: 0.5, ..params() };
        let s = State { nip_load: 200.0, ..state(5.1, 5.0, 80.0, 180.0) };
        let c = contact(&p, &s, Friction::Bristle);
        assert!((180.0 - 80.0 + c.force.x).abs() < 1e-12);
        let both = Parameters { nip_mu: 0.5, ..massless() };
        let t_b = (80.0 + 100.0) * (0.3 * std::f64::consts::FRAC_PI_2).exp();
        let s = State { nip_load: 200.0, ..state(5.1, 5.0, 80.0, t_b) };
        let c = contact(&both, &s, Friction::Bristle);
        assert!((t_b - 80.0 + c.force.x).abs() < 1e-12 * t_b, "{}", t_b - 80.0 + c.force.x);
        assert!((traction_used(&both, &s, c.mu_eff).x - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_slack_side_transmits_no_friction() {
        let p = params();
        assert_eq!(contact(&p, &state(5.1, 5.0, 0.0, 80.0), Friction::Bristle).force.x, 0.0);
        assert_eq!(contact(&p, &state(4.9, 5.0, 80.0, -3.0), Friction::Bristle).force.x, 0.0);
    }

    /// A web of mass m per length runs round the wrap at v_w: its centripetal force m v_w^2 per
    /// radius comes out of the pressure, so the capstan law holds for T - m v_w^2, and sliding at
    /// rest gives T_b - m v^2 = (T_a - m v^2) exp(mu theta) exactly (the sinh form's identity).
    #[test]
    fn centrifugal_relief_takes_m_v_squared_off_both_sides() {
        let p = Parameters { mass_a: [0.2, 1.0, 1.0, 1.0], ..params() };
        let (v, t_a, e) = (15.0, 80.0, (0.3 * std::f64::consts::FRAC_PI_2).exp());
        let relief = 0.2 * v * v;
        for (s, t_b) in [(0.1, relief + (t_a - relief) * e), (-0.1, relief + (t_a - relief) / e)] {
            let c = contact(&p, &state(v, v - s, t_a, t_b), Friction::Bristle);
            assert!((t_b - t_a + c.force.x).abs() < 1e-12 * t_a, "s = {s}: {}", t_b - t_a + c.force.x);
            let used = traction_used(&p, &state(v, v - s, t_a, t_b), c.mu_eff).x;
            assert!((used - 1.0).abs() < 1e-12, "{used}");
        }
    }

    /// Where T - m v_w^2 <= 0 on a side, the web floats on the wrap: no friction at all, however it slides.
    #[test]
    fn a_web_whose_tension_its_speed_cancels_has_no_traction_on_the_wrap() {
        let p = Parameters { mass_a: [0.2, 1.0, 1.0, 1.0], ..params() };
        // m v^2 = 0.2 * 20^2 = 80 N: one side at 70 N, then both below 80 N.
        for (t_a, t_b) in [(70.0, 120.0), (120.0, 70.0), (79.0, 75.0), (80.0, 90.0)] {
            for s in [0.5, -0.5, 1e-4] {
                let c = contact(&p, &state(20.0, 20.0 - s, t_a, t_b), Friction::Bristle);
                assert_eq!(c.force.x, 0.0, "T_a {t_a}, T_b {t_b}, s {s}");
                assert_eq!(c.force.d, [0.0; KNOWNS], "T_a {t_a}, T_b {t_b}, s {s}");
            }
        }
    }

    /// A nip on a wrap, sliding: with the nip on the wrap's low-tension side the wrap multiplies what
    /// the nip passes, T_high = (T_low + mu_nip N) e^(mu theta); on the high-tension side the nip
    /// adds after the wrap, T_high = T_low e^(mu theta) + mu_nip N. Sliding forward (web faster than
    /// the surface, T_b high), the entry (web_a's side) is the low side; backward, the high side.
    /// A massless web, and one whose m v^2 (0.2 * 5^2 = 5 N) the wrap's law takes off: T' = T - m v^2.
    #[test]
    fn a_nip_on_either_side_of_the_wrap_gives_its_own_capstan_law() {
        let (t_low, n, mu_n) = (80.0, 200.0, 0.5);
        let (nip, e) = (mu_n * n, (0.3 * std::f64::consts::FRAC_PI_2).exp());
        let (nip_on_low, nip_on_high) = ((t_low + nip) * e, t_low * e + nip);
        assert!((nip_on_low - nip_on_high - nip * (e - 1.0)).abs() < 1e-12 * nip_on_low);
        for ((side, s, nip_low), rho) in [
            (NipSide::Entry, 0.1, true),
            (NipSide::Entry, -0.1, false),
            (NipSide::Exit, 0.1, false),
            (NipSide::Exit, -0.1, true),
        ]
        .into_iter()
        .flat_map(|c| [(c, 0.0), (c, 0.2)])
        {
            let p = Parameters { nip_mu: mu_n, nip_side: side.value(), mass_a: [rho, 1.0, 1.0, 1.0], ..params() };
            let relief = rho * (5.0 + s) * (5.0 + s);
            let t_low = t_low + relief;
            let t_high = relief + if nip_low { (t_low - relief + nip) * e } else { (t_low - relief) * e + nip };
            // Sliding forward T_b is high, backward T_a.
            let (t_a, t_b) = if s > 0.0 { (t_low, t_high) } else { (t_high, t_low) };
            let at = State { nip_load: n, ..state(5.0 + s, 5.0, t_a, t_b) };
            let c = contact(&p, &at, Friction::Bristle);
            let rest = t_b - t_a + c.force.x;
            assert!(rest.abs() < 1e-12 * t_high, "{side:?}, s {s}: {rest}");
            let used = traction_used(&p, &at, c.mu_eff).x;
            assert!((used - 1.0).abs() < 1e-12, "{side:?}, s {s}: {used}");
        }
    }

    /// Knox and Sweeney's film at the entry tension: T_a where the surfaces drag the air in from
    /// web_a's side (v_w + v >= 0), T_b where they run back.
    #[test]
    fn the_air_film_forms_at_the_entry_tension() {
        let p = Parameters { air_roughness: 0.8e-6, ..params() };
        let film = |v: f64, t: f64| 0.643 * 0.05 * (12.0 * 1.81e-5 * v / t).powf(2.0 / 3.0);
        let (h, _) = air(&p, &state(10.0, 10.0, 100.0, 160.0));
        assert!((h.x - film(10.0, 100.0)).abs() < 1e-15 * h.x, "{} {}", h.x, film(10.0, 100.0));
        let (h, _) = air(&p, &state(-10.0, -10.0, 100.0, 160.0));
        assert!((h.x - film(10.0, 160.0)).abs() < 1e-15 * h.x, "{} {}", h.x, film(10.0, 160.0));
    }

    /// Every gradient against central differences of the values, along several directions.
    #[test]
    fn the_gradients_are_the_equations_own() {
        let heavy = [0.25, 1.0, 1.0, 1.0]; // m v^2 from 6 to 36 N at these speeds
        let cases = [
            (params(), 0.0),
            (Parameters { traction_static: 1.3, ..params() }, 0.0),
            (Parameters { nip_mu: 0.5, traction_static: 1.2, ..params() }, 150.0),
            (Parameters { nip_mu: 0.5, ..params() }, 150.0),
            (Parameters { nip_mu: 0.5, nip_side: NipSide::Exit.value(), ..params() }, 150.0),
            (Parameters { air_roughness: 2e-6, ..params() }, 0.0),
            (Parameters { air_roughness: 2e-6, nip_mu: 0.4, ..params() }, 90.0),
            (Parameters { air_roughness: 2e-6, nip_mu: 0.4, nip_side: NipSide::Exit.value(), mass_a: heavy, ..params() }, 90.0),
            (Parameters { nip_mu: 0.5, mass_a: heavy, ..params() }, 150.0),
        ];
        let points = [(5.0004, 5.0, 60.0, 75.0, 0.4), (4.9993, 5.0, 90.0, 70.0, -0.8), (12.0, 11.998, 40.0, 41.0, 0.9), (-6.0, -6.0005, 70.0, 55.0, 0.1)];
        let directions: [Gradient; 2] = [[1.3e-4, -0.7e-4, 0.9, -1.7, 1e-3, 0.2], [-2e-4, 1e-4, -2.0, 0.5, -2e-3, -0.3]];
        for (p, n) in &cases {
            for &(vw, vs, ta, tb, grip) in &points {
                for d in &directions {
                    let at = |e: f64| State {
                        v_web: vw + e * d[V_WEB],
                        v_surface: vs + e * d[V_SURFACE],
                        t_a: ta + e * d[T_A],
                        t_b: tb + e * d[T_B],
                        nip_load: *n,
                        radius: 0.05 + e * d[RADIUS],
                        grip: grip + e * d[GRIP],
                    };
                    let e = 1e-5; // the displacements are small beside the speeds themselves
                    let c = contact(p, &at(0.0), Friction::Bristle);
                    let (hi, lo) = (contact(p, &at(e), Friction::Bristle), contact(p, &at(-e), Friction::Bristle));
                    let close = |what: &str, x: Dual, hi: f64, lo: f64, floor: f64| {
                        let fd = (hi - lo) / (2.0 * e);
                        assert!((x.along(d) - fd).abs() <= 1e-6 * (fd.abs() + floor), "{what}: {} vs {fd}", x.along(d));
                    };
                    close("force", c.force, hi.force.x, lo.force.x, 1.0);
                    close("grip rate", c.grip_rate, hi.grip_rate.x, lo.grip_rate.x, 1.0);
                    close("mu_eff", c.mu_eff, hi.mu_eff.x, lo.mu_eff.x, 1e-3);
                    close("h_air", c.h_air, hi.h_air.x, lo.h_air.x, 1e-9);
                    let used = |s: &State, m: Dual| traction_used(p, s, m).x;
                    close("traction", traction_used(p, &at(0.0), c.mu_eff), used(&at(e), hi.mu_eff), used(&at(-e), lo.mu_eff), 1e-3);
                    let acc = |s: &State, f: Dual| web_acceleration(p, s, f).x;
                    close("acceleration", web_acceleration(p, &at(0.0), c.force), acc(&at(e), hi.force), acc(&at(-e), lo.force), 1.0);
                }
            }
        }
    }
}
