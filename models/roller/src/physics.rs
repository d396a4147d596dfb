//! The equations of a line part that is not a span (the Roller FMU's
//! documentation numbers them):
//!
//! [R1]  d(J*omega)/dt = r*(F_b - F_a) + tau - b*omega     (F_a: sum of web_a*.F, F_b: sum of web_b*.F)
//! [R2]  v = r*omega
//! [R3]  d(r^2)/dt = s*h_w*v/pi, J = J0 + (pi/2)*rho*w*(r^4 - r0^4)   (s = -1 unwinder, +1 winder)
//! [R4]  m*y'' = F_load + load - F_a - F_b - d*y' - k*(y - y_start)    (a dancer's carriage)
//! [R5]  1/(1+eps_b) = sum_i (m_i/M)/(1+eps_i), M = sum_i m_i          (several inlets: the merge)
//!       evaluated as eps_b = sum_i q_i*eps_i / sum_i q_i, q_i = m_i/(1+eps_i)
//! [R9]  eps_b,k = eps_a,((k-1) mod n)+1                                 (layered: each outlet one inlet's)
//! [R12] tau_brake = -B*tanh(v/v_slip)                                   (a powder brake, B >= 0 its torque)
//!
//! Over a piece of a communication step where the inputs are held and the
//! profiles are linear in time, [R1] with r and J held is a linear ODE with
//! forcing linear in time, and [R4] a linear ODE too: both are stepped
//! exactly. [R3] moves r and J after the piece, keeping J*omega (physics
//! docs: accurate to O(h*v*dt/r^2) per step).

use crate::parameters::{ports, Inputs, Parameters, PORTS};
use solver::{decay_integral, expm, ramp_integral, CompensatedSum};
use std::f64::consts::PI;

/// The strain of the web leaving the nip [R5]: with one inlet the arriving
/// strain itself; with several, the mean of their strains weighted by
/// q_i = m_i/(1+eps_i) (each web's share of the mass flowing in). Both sums
/// have terms of one sign where the strains do, so nothing cancels
/// (1/(1+eps_b) - 1 would lose digits for small strains).
pub fn merged_strain(p: &Parameters, strain: &[f64; PORTS]) -> f64 {
    let n = ports(p.inlets);
    if n == 1 {
        return strain[0];
    }
    let (mut weighted, mut total) = (0.0, 0.0);
    for i in 0..n {
        let q = p.mass_a[i] / (1.0 + strain[i]);
        weighted += q * strain[i];
        total += q;
    }
    weighted / total
}

/// The inlet (0-based) whose strain outlet `outlet` (0-based) passes on where the webs stay layers [R9]:
/// (outlet mod inlets), so that n inlets pass to n outlets one by one, and one inlet's layers to as
/// many outlets per lane after a slitter, lane after lane.
#[inline]
pub fn layer_inlet(p: &Parameters, outlet: usize) -> usize {
    outlet % ports(p.inlets)
}

/// d(eps_b)/d(eps_i) of [R5], for each inlet i (0 beyond `inlets`):
/// (m_i/M)*((1+eps_b)/(1+eps_i))^2, from differentiating 1/(1+eps_b).
pub fn merged_strain_gradient(p: &Parameters, strain: &[f64; PORTS]) -> [f64; PORTS] {
    let n = ports(p.inlets);
    let mut gradient = [0.0; PORTS];
    if n == 1 {
        gradient[0] = 1.0;
        return gradient;
    }
    let merged = merged_strain(p, strain);
    let total: f64 = p.mass_a[..n].iter().sum();
    for i in 0..n {
        gradient[i] = p.mass_a[i] / total * ((1.0 + merged) / (1.0 + strain[i])).powi(2);
    }
    gradient
}

/// The roll's size: r, and J as [R3] gives it from a reference (J0 at r0).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Roll {
    pub radius: f64,
    pub inertia: f64,
    pub reference_radius: f64,
    pub reference_inertia: f64,
}

impl Roll {
    pub fn new(radius: f64, inertia: f64) -> Roll {
        Roll { radius, inertia, reference_radius: radius, reference_inertia: inertia }
    }

    /// J at radius r [R3].
    pub fn inertia_at(&self, p: &Parameters, radius: f64) -> f64 {
        self.reference_inertia + 0.5 * PI * p.wound_density * p.wound_width * (radius.powi(4) - self.reference_radius.powi(4))
    }

    /// dr/dt [R3] at surface speed v.
    pub fn radius_rate(&self, p: &Parameters, speed: f64) -> f64 {
        p.roll_sign() * p.wound_thickness * speed / (2.0 * PI * self.radius)
    }

    /// dJ/dt [R3] at surface speed v.
    pub fn inertia_rate(&self, p: &Parameters, speed: f64) -> f64 {
        2.0 * PI * p.wound_density * p.wound_width * self.radius.powi(3) * self.radius_rate(p, speed)
    }
}

/// v [R2].
pub fn surface_speed(radius: f64, omega: f64) -> f64 {
    radius * omega
}

/// The webs' torque on the roller, r*(F_b - F_a) [R1], N m.
#[inline]
pub fn web_torque(p: &Parameters, radius: f64, u: &Inputs) -> f64 {
    radius * (u.pull_forward(p) - u.pull_back(p))
}

/// d(omega)/dt [R1] at the webs' torque `web_torque` ([R1]'s r*(F_b - F_a), or [R6]'s -r*f where
/// the web may slip) and the drive torque `torque`, J moving at `inertia_rate` (a roll being
/// wound: d(J*omega)/dt = J*omega' + J'*omega).
#[inline]
pub fn omega_rate(p: &Parameters, roll: &Roll, web_torque: f64, omega: f64, torque: f64, inertia_rate: f64) -> f64 {
    (web_torque + torque - p.damping * omega - inertia_rate * omega) / roll.inertia
}

/// d(omega)/dt of a surface that follows a speed v(t) with slope v' [R2]: omega = v/r, r moving at r'.
#[inline]
pub fn omega_rate_at_speed(slope: f64, speed: f64, radius: f64, radius_rate: f64) -> f64 {
    slope / radius - speed * radius_rate / (radius * radius)
}

/// The torque [R1] that makes the surface follow a speed table with slope v' (r and J held):
/// J*v'/r + b*omega - (the webs' torque, as in `omega_rate`).
#[inline]
pub fn speed_drive_torque(p: &Parameters, roll: &Roll, web_torque: f64, omega: f64, slope: f64) -> f64 {
    roll.inertia * slope / roll.radius + p.damping * omega - web_torque
}

/// [R1] with r and J held over a piece of length h: the drive torque is
/// `tau0 + tau1*s` (s from the piece's start). Exact:
/// omega(h) = omega + (a0 - (b/J)*omega)*int e^{-(b/J)(h-s)} ds + a1*int s e^{-(b/J)(h-s)} ds.
pub fn rotation_step(p: &Parameters, roll: &Roll, u: &Inputs, omega: CompensatedSum, tau0: f64, tau1: f64, h: f64) -> CompensatedSum {
    let j = roll.inertia;
    let decay = p.damping / j;
    let a0 = (web_torque(p, roll.radius, u) + tau0) / j;
    let a1 = tau1 / j;
    omega.plus((a0 - decay * omega.value()) * decay_integral(decay, h) + a1 * ramp_integral(decay, h))
}

/// A load cell under the roller's bearings: the resultant of the webs pulling back (`back`, every
/// arriving web) and forward (`forward`, every leaving one, as parallel webs do) at a wrap
/// angle with cosine `cos_wrap`, by the law of cosines: sqrt(a^2 + b^2 - 2 a b cos(wrap)).
pub fn load_cell(back: f64, forward: f64, cos_wrap: f64) -> f64 {
    (back * back + forward * forward - 2.0 * back * forward * cos_wrap).max(0.0).sqrt()
}

/// [R3] after a piece in which the surface moved `travel` metres: the new
/// radius squared (None: the roll ran empty).
pub fn wound_radius(p: &Parameters, radius: f64, travel: f64) -> Option<f64> {
    let r2 = radius * radius + p.roll_sign() * p.wound_thickness * travel / PI;
    (r2 > 0.0).then(|| r2.sqrt())
}

/// [R4] over a piece of length h with the force `g0 + g1*s` (load minus the
/// spans' pull), exactly: exp of the augmented matrix acting on (y - y_start, y', 1, s).
pub fn carriage_step(p: &Parameters, state: [f64; 2], g0: f64, g1: f64, h: f64) -> [f64; 2] {
    let m = p.carriage_mass;
    let (k, d) = (p.carriage_stiffness / m, p.carriage_damping / m);
    let a = [
        [0.0, h, 0.0, 0.0],
        [-k * h, -d * h, g0 / m * h, g1 / m * h],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, h, 0.0],
    ];
    let e = expm(a);
    let z = [state[0] - p.carriage_start, state[1]];
    // (z, 1, s=0) at the start; the fourth column is never needed.
    let y = e[0][0] * z[0] + e[0][1] * z[1] + e[0][2];
    let v = e[1][0] * z[0] + e[1][1] * z[1] + e[1][2];
    [y + p.carriage_start, v]
}

/// Where the webs touch the roller [R4]: web_b's x (web_a's is 0), at the roller's start position.
#[inline]
pub fn contact_b_x(radius: f64) -> f64 {
    2.0 * radius
}

/// The contact points' height [R4], y up from the roller's start position: y_start - y.
#[inline]
pub fn contact_height(p: &Parameters, travel: f64) -> f64 {
    p.carriage_start - travel
}

/// The carriage's acceleration [R4] with the total force g.
pub fn carriage_acceleration(p: &Parameters, state: [f64; 2], g: f64) -> f64 {
    (g - p.carriage_damping * state[1] - p.carriage_stiffness * (state[0] - p.carriage_start)) / p.carriage_mass
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parameters::{UNWINDER, WINDER};

    fn params() -> Parameters {
        Parameters { inertia: 2.0, radius: 0.2, damping: 0.5, carriage_mass: 5.0, ..Parameters::default() }
    }

    #[test]
    fn rotation_step_solves_linear_forcing_exactly() {
        // J w' = tau0 + tau1 s - b w, from w0: w(h) against the closed form.
        let p = params();
        let roll = Roll::new(p.radius, p.inertia);
        let (tau0, tau1, h, w0) = (3.0, -7.0, 0.4, 10.0);
        let k = p.damping / p.inertia;
        let (a0, a1) = (tau0 / p.inertia, tau1 / p.inertia);
        // w(t) = a0/k + a1*(t/k - 1/k^2) + C e^{-kt}
        let c = w0 - a0 / k + a1 / (k * k);
        let exact = a0 / k + a1 * (h / k - 1.0 / (k * k)) + c * (-k * h).exp();
        let got = rotation_step(&p, &roll, &Inputs::default(), CompensatedSum::from_parts(w0, 0.0), tau0, tau1, h).value();
        assert!((got - exact).abs() < 1e-13 * exact.abs(), "{got} {exact}");
    }

    #[test]
    fn carriage_step_solves_the_damped_oscillator_exactly() {
        let p = Parameters { carriage_stiffness: 2000.0, carriage_damping: 30.0, carriage_start: 0.5, ..params() };
        // Constant force g: equilibrium y_e = y_start + g/k; an underdamped approach.
        let (g, h) = (100.0, 0.05);
        let (m, k, d) = (p.carriage_mass, p.carriage_stiffness, p.carriage_damping);
        let (alpha, beta) = (d / (2.0 * m), (k / m - (d / (2.0 * m)).powi(2)).sqrt());
        let y_e = p.carriage_start + g / k;
        // From rest at y_start: y = y_e - (g/k) e^{-alpha t} (cos(beta t) + alpha/beta sin(beta t)).
        let exact = y_e - g / k * (-alpha * h).exp() * ((beta * h).cos() + alpha / beta * (beta * h).sin());
        let [y, _] = carriage_step(&p, [p.carriage_start, 0.0], g, 0.0, h);
        assert!((y - exact).abs() < 1e-14, "{y} {exact}");
    }

    #[test]
    fn a_winder_grows_by_thickness_times_travel_over_pi() {
        let p = Parameters { roll: WINDER, wound_thickness: 50e-6, ..params() };
        let r = wound_radius(&p, 0.1, 100.0).unwrap();
        assert!((r * r - (0.01 + 50e-6 * 100.0 / PI)).abs() < 1e-16);
        let q = Parameters { roll: UNWINDER, ..p };
        assert_eq!(wound_radius(&q, 0.01, 100.0), None);
    }
}

/// A powder brake's torque at surface speed v [R12] and its slope in v: it opposes the motion with
/// its full torque B once |v| is well above v_slip, and passes through 0 at rest (regularized like
/// Coulomb friction [12] of the physics docs), so that a line can start from there.
#[inline]
pub fn brake_torque(b: f64, v: f64, v_slip: f64) -> (f64, f64) {
    let th = (v / v_slip).tanh();
    (-b * th, -b * (1.0 - th * th) / v_slip)
}
