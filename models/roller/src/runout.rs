//! A roll with runout [R15]: its surface, a circle of radius r, turns about an axis a distance e
//! from the circle's centre. The web runs straight from the roll to a fixed point B, the end of
//! its span (where it meets the next roller, or leaves the last one for a winder), tangent to
//! the surface. Coordinates: the axis at 0, t along the web's line of a round roll (towards B),
//! n the outward normal where it touches; a winder is seen in a mirror (psi's sign), so that
//! both roll the web off towards +t.
//!
//! [R15] psi = s*(angle + phase)   (s = +1 unwinder, -1 winder),   angle' = omega
//!       C = e*(sin psi, cos psi),  B = (L0, r),  w = B - C
//!       L = sqrt(|w|^2 - r^2)                               the span's free length
//!       p = r + n.C,  n = (r*w + L*w_perp)/|w|^2             the axis's distance from the web's line
//!       web torque T*p;  the web's speed at the tangent point, relative to it: v = omega*p + s*dL/dt

use crate::number::Number;
use crate::parameters::{Inputs, Parameters, UNWINDER};

/// The roll's geometry now and the web's speed at its end of the span [R15].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Runout<N> {
    /// p: the axis's distance from the web's line (the arm of the web's tension).
    pub arm: N,
    /// L: from the tangent point to B.
    pub length: N,
    /// dL/dt as the roll turns.
    pub length_rate: N,
    /// The web's speed where it leaves (arrives), relative to the moving tangent point.
    pub speed: N,
}

/// [R15] at the roll's angle, omega and radius r. The tangent point's drift with a winding radius,
/// (e cos(psi)/L) dr/dt in dL/dt, is left out: 1e-8 of the web's speed at 1 mm runout over a 1 m
/// span and 0.1 mm/s of build-up, and it would make the web's speed read the strains through dr/dt.
#[inline]
pub fn at<N: Number>(p: &Parameters, angle: N, omega: N, radius: N) -> Runout<N> {
    let s = side(p);
    let psi = (angle + p.runout_phase) * s;
    let (sin, cos) = (psi.sin(), psi.cos());
    let e = p.runout_e;
    let (cx, cy) = (sin * e, cos * e);
    let (wx, wy) = (-cx + p.runout_length, radius - cy);
    let d2 = wx * wx + wy * wy;
    let length = (d2 - radius * radius).sqrt();
    // n.C with n = (r w + L w_perp)/|w|^2, w_perp = (-w_y, w_x).
    let arm = radius + ((wx * cx + wy * cy) * radius + (wx * cy - wy * cx) * length) / d2;
    // dL/dt = w.w'/L with w' = -C' = -e psi' (cos psi, -sin psi), psi' = s*omega.
    let length_rate = (-(wx * cos) + wy * sin) * omega * (s * e) / length;
    Runout { arm, length, length_rate, speed: omega * arm + length_rate * s }
}

/// +1 on an unwinder, -1 on a winder (seen in a mirror).
#[inline]
fn side(p: &Parameters) -> f64 {
    if p.roll == UNWINDER {
        1.0
    } else {
        -1.0
    }
}

/// The webs' torque on the roll [R1] with runout [R15]: the web at the roll (an unwinder's leaving,
/// a winder's arriving) pulls with the arm p, any other at r.
#[inline]
pub fn web_torque<N: Number>(p: &Parameters, radius: N, arm: N, u: &Inputs<N>) -> N {
    if p.roll == UNWINDER {
        arm * u.pull_forward(p) - radius * u.pull_back(p)
    } else {
        radius * u.pull_forward(p) - arm * u.pull_back(p)
    }
}

/// The position of the web's end on the roll along the span's line, which the span's frame reads
/// (its length the distance to its fixed end): an unwinder's leaving point L0 - L (its span's fixed
/// end at L0), a winder's arriving point L (its span's fixed end at 0).
#[inline]
pub fn frame<N: Number>(p: &Parameters, g: &Runout<N>) -> N {
    if p.roll == UNWINDER {
        -g.length + p.runout_length
    } else {
        g.length
    }
}

/// Why runout cannot be on this roller (None: it can): only a roll has it, one web at its end of
/// the span, and a roll whose web may slip or whose axis rides a carriage is not modelled with it.
pub fn refusal(p: &Parameters) -> Option<String> {
    if !p.runout {
        return None;
    }
    if p.roll == 0 || p.carriage || p.traction {
        return Some(format!(
            "runout = true with roll = {}, carriage = {}, includeTraction = {}: runout [R15] is a roll's (an unwinder or a winder), \
             on an axis that does not move and without slip",
            p.roll, p.carriage, p.traction
        ));
    }
    if p.wound_merge > 0.0 {
        return Some(format!(
            "runout = true with wound.merge = {} rad: runout with a stepwise radius [R17] is not modelled (the arm is the \
             smooth radius's); set wound.merge = 0",
            p.wound_merge
        ));
    }
    if !(p.runout_length > p.runout_e + p.radius) {
        return Some(format!(
            "runout.L = {} m with runout.e = {} m and R = {} m: the span's fixed end must lie beyond the roll (runout.L > runout.e + R)",
            p.runout_length, p.runout_e, p.radius
        ));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parameters::WINDER;

    fn roll(e: f64, phase: f64) -> Parameters {
        Parameters { roll: UNWINDER, runout: true, runout_e: e, runout_phase: phase, runout_length: 2.0, ..Parameters::default() }
    }

    /// A round roll: L = L0 and p = r at every angle, the web paid out at omega*r.
    #[test]
    fn a_round_roll_is_the_plain_roll() {
        let g = at(&roll(0.0, 0.3), 1.7, 10.0, 0.4);
        assert!((g.length - 2.0).abs() < 1e-15 && (g.arm - 0.4).abs() < 1e-15 && (g.speed - 4.0).abs() < 1e-14);
    }

    /// The tangent from B touches the offset circle: |T - C| = r with T = B - L t, and (T - C) is
    /// normal to the line; p is T's distance along that normal from the axis.
    #[test]
    fn the_web_is_tangent_to_the_offset_circle() {
        let p = roll(0.05, 0.2);
        let (angle, r) = (0.9, 0.4);
        let g = at(&p, angle, 0.0, r);
        let (cx, cy) = (0.05 * (angle + 0.2_f64).sin(), 0.05 * (angle + 0.2_f64).cos());
        let (wx, wy) = (2.0 - cx, r - cy);
        let d2 = wx * wx + wy * wy;
        let n = ((r * wx - g.length * wy) / d2, (r * wy + g.length * wx) / d2);
        let t = (n.1, -n.0);
        let touch = (2.0 - g.length * t.0, r - g.length * t.1);
        assert!(((touch.0 - cx).hypot(touch.1 - cy) - r).abs() < 1e-14);
        assert!(((touch.0 - cx) * t.0 + (touch.1 - cy) * t.1).abs() < 1e-14);
        assert!((touch.0 * n.0 + touch.1 * n.1 - g.arm).abs() < 1e-14);
    }

    /// dL/dt is L's rate along the angle at omega (central differences), and the web's speed
    /// relative to the tangent point is omega*p + dL/dt; a winder's omega*p - dL/dt.
    #[test]
    fn the_length_rate_is_the_tangent_points_motion() {
        for role in [UNWINDER, WINDER] {
            let p = Parameters { roll: role, ..roll(0.02, -0.7) };
            let (angle, omega, r, h) = (2.1, 3.0, 0.3, 1e-6);
            let g = at(&p, angle, omega, r);
            let rate = (at(&p, angle + h, 0.0, r).length - at(&p, angle - h, 0.0, r).length) / (2.0 * h) * omega;
            assert!((g.length_rate - rate).abs() < 1e-8, "{} {rate}", g.length_rate);
            let s = if role == UNWINDER { 1.0 } else { -1.0 };
            assert!((g.speed - (omega * g.arm + s * g.length_rate)).abs() < 1e-14);
        }
    }

    /// Over a turn the arm's mean is r (to e^2): a roll pays out its circumference per turn.
    #[test]
    fn the_arm_averages_to_the_radius_over_a_turn() {
        let p = roll(1e-3, 0.5);
        let n = 4096;
        let mean: f64 = (0..n).map(|k| at(&p, 2.0 * std::f64::consts::PI * k as f64 / n as f64, 0.0, 0.4).arm).sum::<f64>() / n as f64;
        assert!((mean - 0.4).abs() < 1e-6, "{mean}");
    }
}
