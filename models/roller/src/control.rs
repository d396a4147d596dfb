//! The drive's loop [R10] and the motor it commands [R11]: a PI controller
//! whose integrator is a state, a smooth torque limit with back-calculation
//! anti-windup, an inertia feed-forward and a first-order torque lag.
//!
//! [R10] e = s*(set - F_measured) (force loop), e = v_ref - v (speed loop; v_ref: the reference table, else loop.speed);
//!       u = kp*e + I + tau_ff;   dI/dt = ki*e + (sat(u) - u)/T_t,  T_t = kp/ki (1 s if a gain is 0);
//!       tau_ff = d(J*v_ref/r)/dt = J*a_ref/r + (J' - J*r'/r)*v_ref/r   (r', J' of [R3] at v_ref)
//! [R11] motor.torque = sat(u) (no lag), or d(motor.torque)/dt = (sat(u) - motor.torque)/T_m;
//!       sat(u) = u for |u| <= L - w, else sign(u)*(L - w*exp(-(|u| - L + w)/w)),  w = L/20.
//! [R13] a dancer loop: the speed loop of [R10] with v_ref + trim for v_ref,
//!       e_d = loop.sign*(dancer.y - dancer.set);  trim = dancer.kp*e_d + dancer.I;  d(dancer.I)/dt = dancer.ki*e_d.

use crate::parameters::Parameters;
use std::f64::consts::PI;

/// What the drive's loop holds (`loop.kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    None,
    /// A force (a span's tension, a load cell) at `loop.set` or the profile's setpoint table.
    Force,
    /// The surface speed at the profile's reference table.
    Speed,
    /// The speed loop with its reference trimmed by a PI on a dancer's position [R13].
    Dancer,
}

impl Kind {
    pub fn of(p: &Parameters) -> Kind {
        match p.loop_kind {
            1 => Kind::Force,
            2 => Kind::Speed,
            3 => Kind::Dancer,
            _ => Kind::None,
        }
    }
}

/// The share of the limit over which the torque bends into it: smooth (C1), so that Newton's
/// method in the Line's implicit steps sees a slope everywhere, and exact inside.
const BEND: f64 = 0.05;

/// sat(u) of [R11] and its slope.
#[inline]
pub fn limit(p: &Parameters, u: f64) -> (f64, f64) {
    let l = p.motor_limit;
    if l <= 0.0 {
        return (u, 1.0);
    }
    let w = BEND * l;
    let over = u.abs() - (l - w);
    if over <= 0.0 {
        return (u, 1.0);
    }
    let decay = (-over / w).exp();
    (u.signum() * (l - w * decay), decay)
}

/// The feed-forward torque d(J*v_ref/r)/dt [R10] at radius r, inertia j, reference speed v and
/// acceleration a, and its derivative in r (J moves with r on a roll being wound [R3]).
#[inline]
pub fn feedforward(p: &Parameters, r: f64, j: f64, v: f64, a: f64) -> (f64, f64) {
    if !p.winding() {
        return (j * a / r, -j * a / (r * r));
    }
    // r' = c*v/r, J' = k*r^3*r' = k*c*v*r^2, dJ/dr = k*r^3.
    let (k, c) = (2.0 * PI * p.wound_density * p.wound_width, p.roll_sign() * p.wound_thickness / (2.0 * PI));
    let dj = k * r.powi(3);
    let ff = j * a / r + k * c * v * v * r - j * c * v * v / r.powi(3);
    let d = dj * a / r - j * a / (r * r) + k * c * v * v - dj * c * v * v / r.powi(3) + 3.0 * j * c * v * v / r.powi(4);
    (ff, d)
}

/// The loop's point: its rates and the motor's torque, with their slopes in what moves them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Loop {
    /// d(loop.I)/dt and d(motor.torque)/dt.
    pub rates: [f64; 2],
    /// The torque the motor gives now.
    pub torque: f64,
    /// d(u)/d(e), d(u)/d(I) = 1, and sat'(u).
    pub kp: f64,
    pub slope: f64,
    pub ki: f64,
    pub tracking: f64,
    pub lag: f64,
}

/// The loop at a roller's point: its law, the error's slopes in (loop.measured, omega, r, dancer.y,
/// dancer.I) and the feed-forward's in r; a dancer loop's integrator rate [R13] and its slope in dancer.y.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Point {
    pub law: Loop,
    pub de: [f64; 5],
    pub dff_r: f64,
    pub dancer_rate: f64,
    pub dancer_rate_dy: f64,
}

/// A dancer loop's error e_d = loop.sign*(dancer.y - dancer.set) and speed trim [R13].
#[inline]
pub fn dancer(p: &Parameters, y: f64, integrator: f64) -> (f64, f64) {
    let e = p.loop_sign * (y - p.dancer_set);
    (e, p.dancer_kp * e + integrator)
}

/// 1/T_t of the back-calculation [R10]: ki/kp, or 1/s where either gain is 0 (a pure P or I loop).
#[inline]
pub fn tracking(p: &Parameters) -> f64 {
    if p.loop_kp > 0.0 && p.loop_ki > 0.0 {
        p.loop_ki / p.loop_kp
    } else {
        1.0
    }
}

/// [R10]-[R11] at error e, feed-forward ff, integrator i and lagged torque m.
#[inline]
pub fn evaluate(p: &Parameters, e: f64, ff: f64, i: f64, m: f64) -> Loop {
    let u = p.loop_kp * e + i + ff;
    let (sat, slope) = limit(p, u);
    let tracking = tracking(p);
    let integrator_rate = p.loop_ki * e + (sat - u) * tracking;
    let (torque, motor_rate) = if p.motor_lag > 0.0 { (m, (sat - m) / p.motor_lag) } else { (sat, 0.0) };
    Loop { rates: [integrator_rate, motor_rate], torque, kp: p.loop_kp, slope, ki: p.loop_ki, tracking, lag: p.motor_lag }
}

impl Loop {
    /// Along d(e), d(ff), d(I), d(m): d(rates) and d(torque).
    #[inline]
    pub fn along(&self, de: f64, dff: f64, di: f64, dm: f64) -> ([f64; 2], f64) {
        let du = self.kp * de + di + dff;
        let dsat = self.slope * du;
        let d_integrator = self.ki * de + (dsat - du) * self.tracking;
        if self.lag > 0.0 {
            ([d_integrator, (dsat - dm) / self.lag], dm)
        } else {
            ([d_integrator, 0.0], dsat)
        }
    }
}

/// The loop's parameters checked when initialization ends: None if they fit.
pub fn refusal(p: &Parameters) -> Option<String> {
    if Kind::of(p) == Kind::None {
        return None;
    }
    if p.speed_input {
        return Some(format!("loop.kind = {} with speed.input = true: an ideal speed drive has no loop (a speed loop takes loop.speed itself)", p.loop_kind));
    }
    if p.traction {
        return Some("loop.kind > 0 with includeTraction = true: a loop on a roller where the web may slip is not modelled".into());
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limited(l: f64) -> Parameters {
        Parameters { motor_limit: l, loop_kp: 0.2, loop_ki: 2.0, ..Default::default() }
    }

    /// The limit is the identity inside its bend, never exceeds L, and its slope is continuous.
    #[test]
    fn limit_is_exact_inside_bounded_and_smooth() {
        let p = limited(50.0);
        assert_eq!(limit(&p, 47.4), (47.4, 1.0));
        assert_eq!(limit(&p, -47.4), (-47.4, 1.0));
        for u in [47.6, 50.0, 60.0, 1e3, 1e9] {
            let (x, s) = limit(&p, u);
            assert!(x <= 50.0 && x > 47.5 && s >= 0.0 && s < 1.0, "u = {u}: {x} {s}");
            let h = 1e-6;
            let fd = (limit(&p, u + h).0 - limit(&p, u - h).0) / (2.0 * h);
            assert!((fd - s).abs() < 1e-6, "u = {u}: slope {s}, difference {fd}");
        }
        let (below, above) = (limit(&p, 47.5 - 1e-9).1, limit(&p, 47.5 + 1e-9).1);
        assert!((below - above).abs() < 1e-9);
        assert_eq!(limit(&limited(0.0), 1e6), (1e6, 1.0));
    }

    /// The feed-forward's slope in r against a central difference, on a roll being wound.
    #[test]
    fn feedforward_slope_in_r() {
        let p = Parameters { roll: 1, wound_thickness: 1e-4, wound_density: 800.0, wound_width: 1.2, ..Default::default() };
        let (r, v, a) = (0.6, 6.0, 0.4);
        let j = |r: f64| 40.0 + 0.5 * PI * 800.0 * 1.2 * (r.powi(4) - 0.6f64.powi(4));
        let (_, d) = feedforward(&p, r, j(r), v, a);
        let h = 1e-6;
        let fd = (feedforward(&p, r + h, j(r + h), v, a).0 - feedforward(&p, r - h, j(r - h), v, a).0) / (2.0 * h);
        assert!((d - fd).abs() < 1e-6 * fd.abs().max(1.0), "{d} vs {fd}");
    }
}
