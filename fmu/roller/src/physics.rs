//! The equation of a roller of a web line (model documentation, "The rollers
//! around a span"; numbers in brackets refer to the Roller FMU's
//! documentation):
//!
//! [R1]  J * d(omega)/dt = R * (F_down - F_up) + tau_m - b * omega
//! [R2]  v = R * omega
//!
//! With the inputs held over a communication step, [R1] is a linear ODE with
//! constant coefficients, `d(omega)/dt = a - (b/J) * omega`, whose exact
//! solution is the step below: exact, so L-stable for any `b/J * h`, and a
//! plain integration `omega + a*h` when b = 0.

use solver::{decay_integral, CompensatedSum};

/// Parameters, SI.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Parameters {
    /// J, kg m2 (> 0).
    pub inertia: f64,
    /// R, m (> 0).
    pub radius: f64,
    /// b, N m s (>= 0).
    pub damping: f64,
    /// omega at the start time, rad/s.
    pub omega_start: f64,
}

/// Inputs, SI, held over a communication step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Inputs {
    /// F_up, N: the span before the roller pulls the web back.
    pub force_up: f64,
    /// F_down, N: the span after the roller pulls the web forward.
    pub force_down: f64,
    /// tau_m, N m: motor torque, forward positive.
    pub torque: f64,
}

/// The driving part of [R1] over J, a = (R*(F_down - F_up) + tau_m)/J, rad/s2.
pub fn drive(p: &Parameters, u: &Inputs) -> f64 {
    (p.radius * (u.force_down - u.force_up) + u.torque) / p.inertia
}

/// The decay rate of [R1], b/J, 1/s (0 without damping).
pub fn decay_rate(p: &Parameters) -> f64 {
    p.damping / p.inertia
}

/// d(omega)/dt of [R1], rad/s2.
pub fn angular_acceleration(p: &Parameters, u: &Inputs, omega: f64) -> f64 {
    drive(p, u) - decay_rate(p) * omega
}

/// The exact step of [R1] over h with held inputs:
/// omega(t+h) = omega + (a - (b/J)*omega) * integral_0^h exp(-(b/J)*s) ds.
pub fn exact_step(p: &Parameters, u: &Inputs, omega: CompensatedSum, h: f64) -> CompensatedSum {
    omega.plus(angular_acceleration(p, u, omega.value()) * decay_integral(decay_rate(p), h))
}

/// Surface speed [R2], m/s.
pub fn surface_speed(p: &Parameters, omega: f64) -> f64 {
    p.radius * omega
}
