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
//!
//! An out-of-round roll adds harmonics to the surface's support function h(theta) (the distance from
//! the axis to the tangent whose outward normal is n(theta) = (sin theta, cos theta)), of which the
//! offset circle's is r + e*cos(theta - psi):
//!       h = r + e*cos(theta - psi) + sum a_j*cos(k_j*(theta - psi_j)),   psi_j = s*(angle + phase_j)
//!       the tangent through B: B.n(theta) = h(theta)  (Newton from the circle's theta)
//!       p = h,  L = B.t - h',  dL/dt = -(h + h'')*dh/dt/L - dh'/dt      (' = d/dtheta, t = dn/dtheta)

use crate::number::Number;
use crate::parameters::{Inputs, Parameters, HARMONICS, UNWINDER};

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
    let (round, theta) = circle(p, angle, omega, radius);
    if out_of_round(p) {
        harmonic(p, angle, omega, radius, theta)
    } else {
        round
    }
}

/// Whether the roll has an out-of-round harmonic.
#[inline]
pub fn out_of_round(p: &Parameters) -> bool {
    p.runout_amplitudes.iter().any(|&a| a != 0.0)
}

/// [R15] on the offset circle, in closed form, and the angle of its tangent's normal.
#[inline]
fn circle<N: Number>(p: &Parameters, angle: N, omega: N, radius: N) -> (Runout<N>, f64) {
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
    let normal = ((radius * wx - length * wy).value(), (radius * wy + length * wx).value());
    (Runout { arm, length, length_rate, speed: omega * arm + length_rate * s }, normal.0.atan2(normal.1))
}

/// The support function h and h', h'' along theta, and the rates of h and h' as the roll turns [R15].
#[derive(Clone, Copy, Default)]
struct Support<N> {
    h: N,
    h1: N,
    h2: N,
    h_rate: N,
    h1_rate: N,
}

/// The roll's support function at the normal's angle theta: the offset circle's and the harmonics'.
#[inline]
fn support<N: Number>(p: &Parameters, theta: N, angle: N, omega: N, radius: N) -> Support<N> {
    let s = side(p);
    let first = std::iter::once((1, p.runout_e, p.runout_phase));
    let terms = first.chain((0..HARMONICS).map(|j| (p.runout_orders[j], p.runout_amplitudes[j], p.runout_phases[j])));
    let mut out = Support { h: radius, ..Support::default() };
    for (k, a, phase) in terms.filter(|&(_, a, _)| a != 0.0) {
        let k = k as f64;
        let x = (theta - (angle + phase) * s) * k;
        let (sin, cos) = (x.sin(), x.cos());
        // d/dt of cos(k (theta - psi_j)) is k psi_j' sin(...), psi_j' = s omega.
        let turning = omega * (s * a * k);
        out.h = out.h + cos * a;
        out.h1 = out.h1 - sin * (a * k);
        out.h2 = out.h2 - cos * (a * k * k);
        out.h_rate = out.h_rate + sin * turning;
        out.h1_rate = out.h1_rate + cos * turning * k;
    }
    out
}

/// [R15] on an out-of-round roll: the tangent through B found by Newton's method on
/// g(theta) = B.n - h, g' = B.t - h' = L, from the circle's theta; one more step in N carries the
/// derivatives (Newton's map has none of its own at the root).
#[inline]
fn harmonic<N: Number>(p: &Parameters, angle: N, omega: N, radius: N, start: f64) -> Runout<N> {
    let l0 = p.runout_length;
    let tangent = |theta: N| {
        let (sin, cos) = (theta.sin(), theta.cos());
        let h = support(p, theta, angle, omega, radius);
        (sin * l0 + cos * radius - h.h, cos * l0 - sin * radius - h.h1, h)
    };
    let mut theta = N::constant(start);
    for _ in 0..50 {
        let (g, slope, _) = tangent(theta);
        let step = (g / slope).value();
        theta = theta - step;
        if step.abs() <= 1e-15 * (1.0 + start.abs()) {
            break;
        }
    }
    let (g, slope, _) = tangent(theta);
    theta = theta - g / slope;
    let (_, length, h) = tangent(theta);
    let length_rate = -((h.h + h.h2) * h.h_rate) / length - h.h1_rate;
    Runout { arm: h.h, length, length_rate, speed: omega * h.h + length_rate * side(p) }
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
    let lobes: f64 = (0..HARMONICS).map(|j| (f64::from(p.runout_orders[j]).powi(2) - 1.0) * p.runout_amplitudes[j]).sum();
    if out_of_round(p) && !(lobes < p.radius) {
        return Some(format!(
            "runout.h*.a with R = {} m: the harmonics' sum of (k^2 - 1)*a is {lobes} m; the roll's surface must stay convex \
             (that sum below R), or the web would bridge its hollows, which is not modelled",
            p.radius
        ));
    }
    if out_of_round(p) && p.layon {
        return Some("layon = true with an out-of-round roll (runout.h*.a > 0): a lay-on roller is modelled on runout's offset circle only".into());
    }
    let reach: f64 = p.runout_e + p.runout_amplitudes.iter().sum::<f64>();
    if !(p.runout_length > reach + p.radius) {
        return Some(format!(
            "runout.L = {} m with runout.e = {} m, the harmonics' amplitudes {:?} m and R = {} m: the span's fixed end must lie beyond \
             the roll (runout.L > runout.e + their sum + R)",
            p.runout_length, p.runout_e, p.runout_amplitudes, p.radius
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
    /// relative to the tangent point is omega*p + dL/dt; a winder's omega*p - dL/dt: on the offset circle
    /// and on the out-of-round roll.
    #[test]
    fn the_length_rate_is_the_tangent_points_motion() {
        for role in [UNWINDER, WINDER] {
            for p in [Parameters { roll: role, ..roll(0.02, -0.7) }, lobed(role)] {
                let (angle, omega, r, h) = (2.1, 3.0, 0.3, 1e-6);
                let g = at(&p, angle, omega, r);
                let rate = (at(&p, angle + h, 0.0, r).length - at(&p, angle - h, 0.0, r).length) / (2.0 * h) * omega;
                assert!((g.length_rate - rate).abs() < 1e-8, "{} {rate}", g.length_rate);
                let s = if role == UNWINDER { 1.0 } else { -1.0 };
                assert!((g.speed - (omega * g.arm + s * g.length_rate)).abs() < 1e-14);
            }
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

    /// An oval and a three-lobed roll with 1 mm of runout.
    fn lobed(role: i32) -> Parameters {
        let mut p = Parameters { roll: role, ..roll(1e-3, 0.4) };
        p.runout_orders = [2, 3, 5, 7];
        p.runout_amplitudes = [2e-3, 5e-4, 0.0, 0.0];
        p.runout_phases = [0.3, -1.1, 0.0, 0.0];
        p
    }

    /// Without harmonics the support function's Newton path gives the circle's closed form (started
    /// 0.05 rad off): p, L, dL/dt and the speed to 1e-13.
    #[test]
    fn the_support_function_of_a_circle_is_the_offset_circle() {
        for role in [UNWINDER, WINDER] {
            let p = Parameters { roll: role, ..roll(0.03, 0.2) };
            for angle in [0.0, 0.7, 2.5, 4.0] {
                let (round, theta) = circle(&p, angle, 12.0, 0.4);
                let general = harmonic(&p, angle, 12.0, 0.4, theta + 0.05);
                for (a, b) in [(round.arm, general.arm), (round.length, general.length), (round.length_rate, general.length_rate), (round.speed, general.speed)] {
                    assert!((a - b).abs() < 1e-13 * a.abs().max(1.0), "role {role}, angle {angle}: {a} {b}");
                }
            }
        }
    }

    /// The web's line through B supports the out-of-round surface: B is at L along t(theta) from the
    /// tangent point T = h n + h' t, and every point of the surface (T of every other normal, 4096 of
    /// them) lies on the roll's side of the line, n.x <= h (to 1e-15 m); p = h is the axis's distance.
    #[test]
    fn the_web_touches_the_out_of_round_surface_and_does_not_cut_it() {
        for role in [UNWINDER, WINDER] {
            let p = lobed(role);
            let (angle, r) = (1.3, 0.4);
            let (_, start) = circle(&p, angle, 0.0, r);
            let g = harmonic(&p, angle, 0.0, r, start);
            // The normal's angle: B.n = p with B = (L0, r) and n.t-component from L = B.t - h'.
            let mut theta = start;
            for _ in 0..60 {
                let h = support(&p, theta, angle, 0.0, r);
                theta -= (2.0 * theta.sin() + r * theta.cos() - h.h) / (2.0 * theta.cos() - r * theta.sin() - h.h1);
            }
            let h = support(&p, theta, angle, 0.0, r);
            let (n, t) = ((theta.sin(), theta.cos()), (theta.cos(), -theta.sin()));
            let touch = (h.h * n.0 + h.h1 * t.0, h.h * n.1 + h.h1 * t.1);
            assert!((touch.0 + g.length * t.0 - 2.0).abs() < 1e-14 && (touch.1 + g.length * t.1 - r).abs() < 1e-14);
            assert!((g.arm - h.h).abs() < 1e-15);
            for k in 0..4096 {
                let phi = std::f64::consts::TAU * k as f64 / 4096.0;
                let q = support(&p, phi, angle, 0.0, r);
                let (m, u) = ((phi.sin(), phi.cos()), (phi.cos(), -phi.sin()));
                let x = (q.h * m.0 + q.h1 * u.0, q.h * m.1 + q.h1 * u.1);
                assert!(x.0 * n.0 + x.1 * n.1 <= g.arm + 1e-15, "role {role}: the surface at {phi} crosses the web's line");
            }
        }
    }

    /// Over a turn the out-of-round roll's arm averages to r too (its harmonics average out; to e^2 and a^2).
    #[test]
    fn the_out_of_round_arm_averages_to_the_radius_over_a_turn() {
        let (p, n, r) = (lobed(UNWINDER), 4096, 0.3);
        let mean: f64 = (0..n).map(|k| at(&p, std::f64::consts::TAU * k as f64 / n as f64, 0.0, r).arm).sum::<f64>() / n as f64;
        assert!((mean - r).abs() < 2e-5, "{mean}");
    }

    /// Written once, generic over the number: on the out-of-round roll the tangents of p, L, dL/dt and
    /// the speed along the angle, omega and r are their central differences (h = 1e-6: truncation 1e-12).
    #[test]
    fn the_out_of_round_geometry_differentiates_as_it_computes() {
        use crate::number::Tangent;
        let p = lobed(WINDER);
        let x = [0.8, 7.0, 0.35];
        let values = |x: &[f64; 3]| {
            let g = at(&p, x[0], x[1], x[2]);
            [g.arm, g.length, g.length_rate, g.speed]
        };
        for i in 0..3 {
            let seed = |k: usize| Tangent::new(x[k], if k == i { 1.0 } else { 0.0 });
            let g = at(&p, seed(0), seed(1), seed(2));
            let tangent = [g.arm.d, g.length.d, g.length_rate.d, g.speed.d];
            let (mut up, mut down) = (x, x);
            up[i] += 1e-6;
            down[i] -= 1e-6;
            let (a, b) = (values(&up), values(&down));
            for k in 0..4 {
                let difference = (a[k] - b[k]) / 2e-6;
                assert!((tangent[k] - difference).abs() < 1e-7 * difference.abs().max(1.0), "along {i}, value {k}: {} {difference}", tangent[k]);
            }
        }
    }
}
