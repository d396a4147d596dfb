//! A powder brake on the roller [R12], its torque a table of time (the profile's `brake`):
//!
//! [R12] tau_brake = -B*tanh(v/v_slip)   (B >= 0 its torque)

use crate::number::Number;

/// A powder brake's torque at surface speed v [R12]: it opposes the motion with its full torque
/// B once |v| is well above v_slip, and passes through 0 at rest (regularized like Coulomb
/// friction [12] of the physics docs), so that a line can start from there.
#[inline]
pub fn torque<N: Number>(b: f64, v: N, v_slip: f64) -> N {
    -((v / v_slip).tanh() * b)
}
