//! A powder brake on the roller [R12], its torque a table of time (the profile's `brake`), held by
//! the bristle (`bristle`) on the surface speed v with its own grip u_b (k_s = 1):
//!
//! [R12] tau_brake = -B g_b,  g_b = u_b + exp(-(v/v_slip_b)^2) (v - |v| u_b)/v_slip_b,  du_b/dt = (v - |v| u_b)/delta_b
//!       (B >= 0 its rated torque)

use crate::bristle::{self, Grip};
use crate::number::Number;
use crate::parameters::Parameters;

/// A powder brake of rated torque B at surface speed v and grip u_b [R12]: its torque, and its grip's
/// rate. At rest it holds any torque up to B (|u_b| < 1); turning, it slides at B.
#[inline]
pub fn torque<N: Number>(p: &Parameters, b: f64, v: N, grip: N) -> (N, N) {
    let Grip { share, rate } = bristle::grip(v, grip, 1.0, p.brake_v_slip, p.brake_creep);
    (-(share * b), rate)
}
