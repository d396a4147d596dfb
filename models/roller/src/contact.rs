//! The web's contact with a roller it may slip on (the Roller FMU's
//! documentation numbers them; docs/physics.md gives their sources):
//!
//! [R6]  m_w dv_w/dt = T_b - T_a + f,   J domega/dt = -r f + tau - b omega     (s = v_w - r omega)
//!       m_w = m_web * r * max(theta, THETA_MIN): the web's mass on the wrap
//! [R7]  f = f_nip + f_wrap,  g = tanh(s/v_slip)
//!       f_nip  = -mu_nip N g                                      (the nip line, where the web meets the roller)
//!       f_wrap = -2 sqrt(T_m+ T_b+) sinh(mu_eff theta g / 2),  T_m = T_a - f_nip   (the wrap after it)
//!       at rest on the wrap (m_w dv_w/dt = 0): T_b = (T_a + mu_nip N g) exp(mu_eff theta g), the capstan
//!       law with the regularized direction g of the slip; a slack side (T <= 0) transmits nothing
//! [R8]  h = 0.643 r (12 eta V / T_w)^(2/3),  V = |v_w + r omega|/2,  T_w = (T_a + T_b)/(2 W)
//!       mu_eff = mu * clamp((3 sigma - h)/(2 sigma), 0, 1)   (sigma > 0; without air mu_eff = mu)
//!
//! Each result is a value with its gradient in the contact's knowns (`Dual`): the tangents are the
//! equations' own, differentiated once, here, and formed once per point for every direction.

use crate::number::Number;
use crate::parameters::Parameters;

/// How the web meets the roller: today always by [R7]'s regularized friction, which covers
/// sticking (|s| << v_slip) and sliding alike.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Friction {
    #[default]
    Regularized,
}

/// The least wrap whose web mass [R6] counts: a roller the web only touches at a nip still
/// carries the web over a short arc there, and [R6] needs a mass to stay an ODE.
pub const THETA_MIN: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// The contact's knowns, the components of a gradient: the web's speed, the surface's, the
/// tensions T_a and T_b, the radius.
pub const V_WEB: usize = 0;
pub const V_SURFACE: usize = 1;
pub const T_A: usize = 2;
pub const T_B: usize = 3;
pub const RADIUS: usize = 4;
pub type Gradient = [f64; 5];

/// A value and its gradient in the knowns.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dual {
    pub x: f64,
    pub d: Gradient,
}

impl Dual {
    pub const fn constant(x: f64) -> Dual {
        Dual { x, d: [0.0; 5] }
    }

    fn known(x: f64, i: usize) -> Dual {
        let mut d = [0.0; 5];
        d[i] = 1.0;
        Dual { x, d }
    }

    /// The differential along a direction in the knowns.
    #[inline]
    pub fn along(&self, direction: &Gradient) -> f64 {
        self.d.iter().zip(direction).map(|(g, d)| g * d).sum()
    }

    /// This result in the roller's number, the knowns (v_web, v_surface, T_a, T_b, r) in it: the
    /// contact's own gradient, chained.
    #[inline]
    pub fn lift<N: Number>(&self, knowns: &[N; 5]) -> N {
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
}

/// The contact's results [R6]–[R8], each with its gradient.
#[derive(Clone, Copy, Debug, Default)]
pub struct Contact {
    /// The friction force on the web, along its motion.
    pub force: Dual,
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
    let v = if speed.x < 0.0 { speed.scaled(-1.0) } else { speed };
    let tw = Dual::known(s.t_a, T_A).plus(Dual::known(s.t_b, T_B)).scaled(1.0 / (2.0 * p.traction_width));
    if tw.x <= 0.0 {
        // No tension presses the web down: it lifts off, no traction (reported as a film of 3 sigma).
        return (Dual::constant(3.0 * sigma), Dual::default());
    }
    if v.x == 0.0 {
        return (Dual::default(), Dual::constant(p.traction_mu));
    }
    // h = 0.643 r (12 eta v / t_w)^(2/3): d ln h = d ln r + (2/3)(d ln v - d ln t_w).
    let h = 0.643 * s.radius * (12.0 * p.air_viscosity * v.x / tw.x).powf(2.0 / 3.0);
    let mut d = [0.0; 5];
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

/// [R7] and [R8] at the contact's state.
pub fn contact(p: &Parameters, s: &State) -> Contact {
    let slip = Dual::known(s.v_web, V_WEB).minus(Dual::known(s.v_surface, V_SURFACE));
    let g = {
        let g = (slip.x / p.traction_v_slip).tanh();
        slip.map(g, (1.0 - g * g) / p.traction_v_slip)
    };
    let (h_air, mu_eff) = air(p, s);
    let f_nip = g.scaled(-p.nip_mu * s.nip_load);
    let t_m = positive(Dual::known(s.t_a, T_A).minus(f_nip));
    let t_b = positive(Dual::known(s.t_b, T_B));
    let product = t_m.times(t_b);
    let root = if product.x > 0.0 { product.map(product.x.sqrt(), 0.5 / product.x.sqrt()) } else { Dual::default() };
    // sinh(k g), k = mu_eff theta / 2.
    let kg = mu_eff.scaled(0.5 * p.traction_wrap).times(g);
    let sinh = kg.map(kg.x.sinh(), kg.x.cosh());
    let f_wrap = root.times(sinh).scaled(-2.0);
    Contact { force: f_nip.plus(f_wrap), mu_eff, h_air }
}

/// The share of the available traction the tensions use: the direction g in [R7]'s law at rest,
/// T_b = (T_a + mu_nip N g) exp(mu_eff theta g), solved for g; its magnitude. On a wrap alone
/// |ln(T_b/T_a)|/(mu_eff theta), at a nip alone |T_b - T_a|/(mu_nip N). With no traction
/// available (a slack side, no friction), 1 where the tensions differ, else 0.
pub fn traction_used(p: &Parameters, s: &State, mu_eff: Dual) -> Dual {
    let (t_a, t_b) = (Dual::known(s.t_a, T_A), Dual::known(s.t_b, T_B));
    let nip = p.nip_mu * s.nip_load;
    let wrap = mu_eff.scaled(p.traction_wrap);
    let saturated = || Dual::constant(if t_a.x == t_b.x { 0.0 } else { 1.0 });
    let nip_alone = || t_b.minus(t_a).scaled(1.0 / nip);
    if t_a.x <= 0.0 || t_b.x <= 0.0 {
        return if nip > 0.0 && wrap.x == 0.0 { abs(nip_alone()) } else { saturated() };
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
            traction_width: 1.0,
            air_viscosity: 1.81e-5,
            mass_a: [0.0167, 1.0, 1.0, 1.0],
            ..Parameters::default()
        }
    }

    fn state(v_web: f64, v_surface: f64, t_a: f64, t_b: f64) -> State {
        State { v_web, v_surface, t_a, t_b, nip_load: 0.0, radius: 0.05 }
    }

    /// Sliding (s >> v_slip) on a wrap, at rest: the capstan law, T_b = T_a exp(mu theta).
    #[test]
    fn sliding_on_a_wrap_holds_the_capstan_ratio() {
        let p = params();
        let (t_a, mu_theta) = (50.0, 0.3 * std::f64::consts::FRAC_PI_2);
        for (s, t_b) in [(0.1, t_a * mu_theta.exp()), (-0.1, t_a * (-mu_theta).exp())] {
            let c = contact(&p, &state(5.0 + s, 5.0, t_a, t_b));
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
        let c = contact(&p, &s);
        assert!((180.0 - 80.0 + c.force.x).abs() < 1e-12);
        let both = Parameters { nip_mu: 0.5, ..params() };
        let t_b = (80.0 + 100.0) * (0.3 * std::f64::consts::FRAC_PI_2).exp();
        let s = State { nip_load: 200.0, ..state(5.1, 5.0, 80.0, t_b) };
        let c = contact(&both, &s);
        assert!((t_b - 80.0 + c.force.x).abs() < 1e-12 * t_b, "{}", t_b - 80.0 + c.force.x);
        assert!((traction_used(&both, &s, c.mu_eff).x - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_slack_side_transmits_no_friction() {
        let p = params();
        assert_eq!(contact(&p, &state(5.1, 5.0, 0.0, 80.0)).force.x, 0.0);
        assert_eq!(contact(&p, &state(4.9, 5.0, 80.0, -3.0)).force.x, 0.0);
    }

    /// Knox and Sweeney's film against the formula, and the friction it leaves.
    #[test]
    fn the_air_film_is_knox_and_sweeneys_and_takes_friction_away_between_sigma_and_three_sigma() {
        let p = Parameters { air_roughness: 0.8e-6, ..params() };
        let s = state(10.0, 10.0, 100.0, 100.0);
        let (h, mu) = air(&p, &s);
        let expected = 0.643 * 0.05 * (12.0 * 1.81e-5 * 10.0 / 100.0f64).powf(2.0 / 3.0);
        assert!((h.x - expected).abs() < 1e-15 * expected, "{} {}", h.x, expected);
        let a = ((3.0 * 0.8e-6 - expected) / (1.6e-6)).clamp(0.0, 1.0);
        assert!((mu.x - 0.3 * a).abs() < 1e-15, "{} {}", mu.x, 0.3 * a);
    }

    /// Every gradient against central differences of the values, along several directions.
    #[test]
    fn the_gradients_are_the_equations_own() {
        let cases = [
            (params(), 0.0),
            (Parameters { nip_mu: 0.5, ..params() }, 150.0),
            (Parameters { air_roughness: 2e-6, ..params() }, 0.0),
            (Parameters { air_roughness: 2e-6, nip_mu: 0.4, ..params() }, 90.0),
        ];
        let points = [(5.0004, 5.0, 60.0, 75.0), (4.9993, 5.0, 90.0, 70.0), (12.0, 11.998, 40.0, 41.0)];
        let directions: [Gradient; 2] = [[1.3e-4, -0.7e-4, 0.9, -1.7, 1e-3], [-2e-4, 1e-4, -2.0, 0.5, -2e-3]];
        for (p, n) in &cases {
            for &(vw, vs, ta, tb) in &points {
                for d in &directions {
                    let at = |e: f64| State {
                        v_web: vw + e * d[V_WEB],
                        v_surface: vs + e * d[V_SURFACE],
                        t_a: ta + e * d[T_A],
                        t_b: tb + e * d[T_B],
                        nip_load: *n,
                        radius: 0.05 + e * d[RADIUS],
                    };
                    let e = 1e-5; // the displacements are small beside the speeds themselves
                    let c = contact(p, &at(0.0));
                    let (hi, lo) = (contact(p, &at(e)), contact(p, &at(-e)));
                    let close = |what: &str, x: Dual, hi: f64, lo: f64, floor: f64| {
                        let fd = (hi - lo) / (2.0 * e);
                        assert!((x.along(d) - fd).abs() <= 1e-6 * (fd.abs() + floor), "{what}: {} vs {fd}", x.along(d));
                    };
                    close("force", c.force, hi.force.x, lo.force.x, 1.0);
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
