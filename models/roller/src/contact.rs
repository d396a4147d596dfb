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
//! Each function returns the value and its differential along a direction (`Dual`), so the
//! tangents are the equations' own, differentiated once, here.

use crate::parameters::Parameters;

/// The least wrap whose web mass [R6] counts: a roller the web only touches at a nip still
/// carries the web over a short arc there, and [R6] needs a mass to stay an ODE.
pub const THETA_MIN: f64 = 5.0 * std::f64::consts::PI / 180.0;

/// A value and its differential along one direction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Dual {
    pub x: f64,
    pub d: f64,
}

impl Dual {
    pub const fn new(x: f64, d: f64) -> Dual {
        Dual { x, d }
    }
}

/// What the contact needs from the roller, each with its differential.
#[derive(Clone, Copy, Debug, Default)]
pub struct State {
    pub v_web: Dual,
    pub v_surface: Dual,
    pub t_a: Dual,
    pub t_b: Dual,
    /// The nip's load N (a table of time: held along a direction).
    pub nip_load: f64,
    pub radius: Dual,
}

/// The contact's results [R6]–[R8], each with its differential.
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

/// The web's acceleration over the roller [R6], with its differential.
pub fn web_acceleration(p: &Parameters, s: &State, friction: Dual) -> Dual {
    let m = wrap_mass(p, s.radius.x);
    let a = (s.t_b.x - s.t_a.x + friction.x) / m;
    Dual::new(a, (s.t_b.d - s.t_a.d + friction.d) / m - a * s.radius.d / s.radius.x)
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
        return (Dual::default(), Dual::new(p.traction_mu, 0.0));
    }
    let speed = Dual::new(0.5 * (s.v_web.x + s.v_surface.x), 0.5 * (s.v_web.d + s.v_surface.d));
    let (v, dv) = if speed.x < 0.0 { (-speed.x, -speed.d) } else { (speed.x, speed.d) };
    let tw = (s.t_a.x + s.t_b.x) / (2.0 * p.traction_width);
    let dtw = (s.t_a.d + s.t_b.d) / (2.0 * p.traction_width);
    if tw <= 0.0 {
        // No tension presses the web down: it lifts off, no traction (reported as a film of 3 sigma).
        return (Dual::new(3.0 * sigma, 0.0), Dual::default());
    }
    if v == 0.0 {
        return (Dual::default(), Dual::new(p.traction_mu, 0.0));
    }
    let h = 0.643 * s.radius.x * (12.0 * p.air_viscosity * v / tw).powf(2.0 / 3.0);
    let dh = h * ((2.0 / 3.0) * (dv / v - dtw / tw) + s.radius.d / s.radius.x);
    let a = (3.0 * sigma - h) / (2.0 * sigma);
    let mu = if a >= 1.0 {
        Dual::new(p.traction_mu, 0.0)
    } else if a <= 0.0 {
        Dual::default()
    } else {
        Dual::new(p.traction_mu * a, -p.traction_mu * dh / (2.0 * sigma))
    };
    (Dual::new(h, dh), mu)
}

/// [R7] and [R8] at the contact's state.
pub fn contact(p: &Parameters, s: &State) -> Contact {
    let slip = s.v_web.x - s.v_surface.x;
    let d_slip = s.v_web.d - s.v_surface.d;
    let g = (slip / p.traction_v_slip).tanh();
    let dg = (1.0 - g * g) / p.traction_v_slip * d_slip;
    let (h_air, mu_eff) = air(p, s);
    let nip = p.nip_mu * s.nip_load;
    let f_nip = Dual::new(-nip * g, -nip * dg);
    let t_m = positive(Dual::new(s.t_a.x - f_nip.x, s.t_a.d - f_nip.d));
    let t_b = positive(s.t_b);
    let product = t_m.x * t_b.x;
    let (root, d_root) = if product > 0.0 {
        let root = product.sqrt();
        (root, (t_m.d * t_b.x + t_m.x * t_b.d) / (2.0 * root))
    } else {
        (0.0, 0.0)
    };
    let theta = p.traction_wrap;
    let k = 0.5 * theta * mu_eff.x;
    let dk = 0.5 * theta * mu_eff.d;
    let (sh, ch) = ((k * g).sinh(), (k * g).cosh());
    let f_wrap = Dual::new(-2.0 * root * sh, -2.0 * (d_root * sh + root * ch * (dk * g + k * dg)));
    Contact { force: Dual::new(f_nip.x + f_wrap.x, f_nip.d + f_wrap.d), mu_eff, h_air }
}

/// The share of the available traction the tensions use: the direction g in [R7]'s law at rest,
/// T_b = (T_a + mu_nip N g) exp(mu_eff theta g), solved for g; its magnitude. On a wrap alone
/// |ln(T_b/T_a)|/(mu_eff theta), at a nip alone |T_b - T_a|/(mu_nip N). With no traction
/// available (a slack side, no friction), 1 where the tensions differ, else 0.
pub fn traction_used(p: &Parameters, s: &State, mu_eff: Dual) -> Dual {
    let (t_a, t_b) = (s.t_a, s.t_b);
    let nip = p.nip_mu * s.nip_load;
    let wrap = mu_eff.x * p.traction_wrap;
    let saturated = || Dual::new(if t_a.x == t_b.x { 0.0 } else { 1.0 }, 0.0);
    if t_a.x <= 0.0 || t_b.x <= 0.0 {
        return if nip > 0.0 && wrap == 0.0 { abs(ratio_nip(t_a, t_b, nip)) } else { saturated() };
    }
    if nip == 0.0 && wrap == 0.0 {
        return saturated();
    }
    if nip == 0.0 {
        // |ln(T_b/T_a)|/(mu theta)
        let x = (t_b.x / t_a.x).ln() / wrap;
        let dx = (t_b.d / t_b.x - t_a.d / t_a.x) / wrap - x * mu_eff.d / mu_eff.x;
        return abs(Dual::new(x, dx));
    }
    if wrap == 0.0 {
        return abs(ratio_nip(t_a, t_b, nip));
    }
    // phi(g) = ln(T_a + n g) + w g - ln T_b = 0, increasing in g where T_a + n g > 0: Newton from the
    // nip's own estimate, kept inside that domain.
    let mut g = ((t_b.x - t_a.x) / nip).clamp(-1.0, 1.0);
    for _ in 0..50 {
        let m = t_a.x + nip * g;
        if m <= 0.0 {
            g = 0.5 * (g - t_a.x / nip);
            continue;
        }
        let step = ((m).ln() + wrap * g - t_b.x.ln()) / (nip / m + wrap);
        g -= step;
        if step.abs() <= 1e-15 * (1.0 + g.abs()) {
            break;
        }
    }
    let m = t_a.x + nip * g;
    // dphi = dT_a/m + theta g dmu - dT_b/T_b + (n/m + w) dg = 0
    let dg = -(t_a.d / m + p.traction_wrap * g * mu_eff.d - t_b.d / t_b.x) / (nip / m + wrap);
    abs(Dual::new(g, dg))
}

fn ratio_nip(t_a: Dual, t_b: Dual, nip: f64) -> Dual {
    Dual::new((t_b.x - t_a.x) / nip, (t_b.d - t_a.d) / nip)
}

fn abs(x: Dual) -> Dual {
    if x.x < 0.0 {
        Dual::new(-x.x, -x.d)
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
        State { v_web: Dual::new(v_web, 0.0), v_surface: Dual::new(v_surface, 0.0), t_a: Dual::new(t_a, 0.0), t_b: Dual::new(t_b, 0.0), nip_load: 0.0, radius: Dual::new(0.05, 0.0) }
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

    /// Every differential against central differences of the values, along random directions.
    #[test]
    fn the_differentials_are_the_equations_own() {
        let cases = [
            (Parameters { ..params() }, 0.0),
            (Parameters { nip_mu: 0.5, ..params() }, 150.0),
            (Parameters { air_roughness: 2e-6, ..params() }, 0.0),
            (Parameters { air_roughness: 2e-6, nip_mu: 0.4, ..params() }, 90.0),
        ];
        let points = [(5.0004, 5.0, 60.0, 75.0), (4.9993, 5.0, 90.0, 70.0), (12.0, 11.998, 40.0, 41.0)];
        let dirs = [(1.3e-4, -0.7e-4, 0.9, -1.7), (-2e-4, 1e-4, -2.0, 0.5)];
        for (p, n) in &cases {
            for &(vw, vs, ta, tb) in &points {
                for &(dvw, dvs, dta, dtb) in &dirs {
                    let at = |e: f64| State {
                        v_web: Dual::new(vw + e * dvw, dvw),
                        v_surface: Dual::new(vs + e * dvs, dvs),
                        t_a: Dual::new(ta + e * dta, dta),
                        t_b: Dual::new(tb + e * dtb, dtb),
                        nip_load: *n,
                        radius: Dual::new(0.05 + e * 1e-3, 1e-3),
                    };
                    let e = 1e-5; // the displacements are small beside the speeds themselves
                    let c = contact(p, &at(0.0));
                    let (hi, lo) = (contact(p, &at(e)), contact(p, &at(-e)));
                    let fd = (hi.force.x - lo.force.x) / (2.0 * e);
                    assert!((c.force.d - fd).abs() <= 1e-6 * (fd.abs() + 1.0), "force: {} vs {fd} at {:?} {n} {vw} {dvw}", c.force.d, (p.nip_mu, p.air_roughness));
                    let fd = (hi.mu_eff.x - lo.mu_eff.x) / (2.0 * e);
                    assert!((c.mu_eff.d - fd).abs() <= 1e-6 * (fd.abs() + 1e-3), "mu: {} vs {fd}", c.mu_eff.d);
                    let used = |s: &State, m: Dual| traction_used(p, s, m);
                    let fd = (used(&at(e), hi.mu_eff).x - used(&at(-e), lo.mu_eff).x) / (2.0 * e);
                    let u = used(&at(0.0), c.mu_eff);
                    assert!((u.d - fd).abs() <= 1e-6 * (fd.abs() + 1e-3), "used: {} vs {fd}", u.d);
                }
            }
        }
    }
}
