//! The roll on the roller and its bearings: [R3] (a roll being wound or unwound: r and J move
//! with the web that passes) and the bearings' torque in [R1].
//!
//! [R3]  d(r^2)/dt = s*h_w*v/(pi*(1+eps)), J = J0 + (pi/2)*rho*w*(r^4 - r0^4)   (s = -1 unwinder, +1 winder)
//!       eps: the web's strain at the roll (`rhs::roll_strain`), so that the roll counts the web's
//!       unstretched length and its mass rho*w*pi*r^2 moves at the web's mass flow rho_l*v/(1+eps).

use crate::number::Number;
use crate::parameters::Parameters;
use std::f64::consts::PI;

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
        self.inertia_of(p, radius)
    }

    /// J at radius r [R3], in any number.
    #[inline]
    pub fn inertia_of<N: Number>(&self, p: &Parameters, radius: N) -> N {
        (radius.powi(4) - self.reference_radius.powi(4)) * (0.5 * PI * p.wound_density * p.wound_width) + self.reference_inertia
    }

    /// J at radius r: [R3]'s where a roll winds, else the roll's own.
    #[inline]
    pub fn inertia<N: Number>(&self, p: &Parameters, radius: N) -> N {
        if p.winding() {
            self.inertia_of(p, radius)
        } else {
            N::constant(self.inertia)
        }
    }
}

/// dr/dt [R3] at radius r, surface speed v and the web's strain eps at the roll (0 where no roll
/// winds). J moves with r, but [R1] needs no dJ/dt: the web carries off (or brings) the angular
/// momentum J'*omega itself.
#[inline]
pub fn radius_rate<N: Number>(p: &Parameters, radius: N, speed: N, strain: N) -> N {
    if !p.winding() {
        return N::default();
    }
    speed * (p.roll_sign() * p.wound_thickness) / (radius * (strain + 1.0) * (2.0 * PI))
}

/// The radius at which the web meets the roll [R17]: r, or with `wound.merge` > 0 the stepwise radius
/// (`stepwise`), which the lever of [R1] and the surface speed v = r_w*omega read; r itself (the roll's
/// mass and inertia, [R3]) moves smoothly.
#[inline]
pub fn contact_radius<N: Number>(p: &Parameters, radius: N) -> N {
    if !stepped(p) {
        return radius;
    }
    let (value, slope) = stepwise(p, radius.value());
    radius.map(value, slope)
}

/// Whether the radius the web meets steps [R17].
#[inline]
pub fn stepped(p: &Parameters) -> bool {
    p.winding() && p.wound_merge > 0.0
}

/// The stepwise radius at the smooth radius r, and its slope d(r_w)/dr [R17]: with u = s*(r - R)/h the
/// layers wound on (s = 1) or off (s = -1) since the start radius R, n = floor(u) and m = merge/(2 pi),
/// r_w = R + s*h*(n + max(0, (u - n - (1 - m))/m)): held for 1 - m of each layer, moved by h over its
/// last m, so that r_w = r where each merge ends (u an integer).
pub fn stepwise(p: &Parameters, radius: f64) -> (f64, f64) {
    let (s, h) = (p.roll_sign(), p.wound_thickness);
    let m = (p.wound_merge / (2.0 * PI)).min(1.0);
    let layers = s * (radius - p.radius) / h;
    let n = layers.floor();
    let into_merge = layers - n - (1.0 - m);
    if into_merge <= 0.0 {
        (p.radius + s * h * n, 0.0)
    } else {
        (p.radius + s * h * (n + into_merge / m), 1.0 / m)
    }
}

/// The warning for a roll that winds with no density: its radius moves while J stays J_start, so the
/// angular momentum and mass the web carries are not the roll's ([R1], [R3]); legal (a massless wound
/// web), but rarely meant.
pub fn massless_roll(p: &Parameters) -> Option<String> {
    (p.winding() && p.wound_density == 0.0).then(|| {
        format!(
            "wound.density = 0 with wound.thickness = {} m: the roll's radius moves but its inertia stays J = {} kg.m2, \
             so the web it winds carries momentum and mass the roll does not lose or gain; give wound.density \
             (the web's mass per length / (wound.width * wound.thickness) keeps both)",
            p.wound_thickness, p.inertia
        )
    })
}

/// The bearings' torque on the roller [R1]: its viscous damping, -b*omega.
#[inline]
pub fn bearing_torque<N: Number>(p: &Parameters, omega: N) -> N {
    -(omega * p.damping)
}

/// The bearings' torque as -c*omega: c, which [R1]'s exact step takes (`physics::rotation_step`);
/// None where a term of `bearing_torque` is not linear in omega (the step and the tangents then
/// follow the right-hand side).
#[inline]
pub fn bearing_damping(p: &Parameters) -> Option<f64> {
    Some(p.damping)
}

/// [R3] after a piece in which the surface moved `travel` metres with the web at strain `strain`
/// there (travel/(1+strain) metres of unstretched web): the new radius (None: the roll ran empty).
pub fn wound_radius(p: &Parameters, radius: f64, travel: f64, strain: f64) -> Option<f64> {
    let r2 = radius * radius + p.roll_sign() * p.wound_thickness * travel / ((1.0 + strain) * PI);
    (r2 > 0.0).then(|| r2.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::parameters::{UNWINDER, WINDER};

    /// Where each merge ends (r = R + s*n*h) the stepwise radius is the smooth one, to 1e-9 of h (rounding
    /// leaves 1e-16 of r); before the merge it holds the last layer's radius, within it it moves by h/m per h.
    #[test]
    fn the_stepwise_radius_is_the_smooth_one_where_each_merge_ends() {
        for (roll, s) in [(WINDER, 1.0), (UNWINDER, -1.0)] {
            let (h, r0) = (50e-6, 0.3);
            let p = Parameters { roll, wound_thickness: h, radius: r0, wound_merge: 30f64.to_radians(), ..Parameters::default() };
            for n in 1..2000 {
                let end = r0 + s * h * n as f64;
                assert!((stepwise(&p, end).0 - end).abs() < 1e-9 * h, "n = {n}: {} against {end}", stepwise(&p, end).0);
                // Halfway through the layer: held at the last merge's radius, slope 0.
                let held = stepwise(&p, end + 0.5 * s * h);
                assert!((held.0 - end).abs() < 1e-9 * h && held.1 == 0.0, "n = {n}: {held:?}");
                // A quarter into the merge (the last 1/12 of the layer): a quarter of h on.
                let inside = stepwise(&p, end + s * h * (1.0 - 0.75 / 12.0));
                assert!((inside.0 - (end + 0.25 * s * h)).abs() < 1e-9 * h && (inside.1 - 12.0).abs() < 1e-9, "n = {n}: {inside:?}");
            }
            // Merging over the whole layer is the smooth law.
            let whole = Parameters { wound_merge: 2.0 * PI, ..p };
            assert!((stepwise(&whole, r0 + s * 3.3 * h).0 - (r0 + s * 3.3 * h)).abs() < 1e-15);
        }
    }

    #[test]
    fn a_winder_grows_by_thickness_times_unstretched_travel_over_pi() {
        let p = Parameters { roll: WINDER, wound_thickness: 50e-6, inertia: 2.0, radius: 0.2, ..Parameters::default() };
        // 100 m of surface at a strain of 0.25 is 80 m of unstretched web: r^2 grows by h*80/pi.
        let r = wound_radius(&p, 0.1, 100.0, 0.25).unwrap();
        assert!((r * r - (0.01 + 50e-6 * 80.0 / PI)).abs() < 1e-16);
        let q = Parameters { roll: UNWINDER, ..p };
        assert_eq!(wound_radius(&q, 0.01, 100.0, 0.0), None);
    }

    /// The rate is the piece's limit: d(r^2)/dt = 2 r r' = s h v/(pi (1 + eps)).
    #[test]
    fn the_radius_rate_is_the_unstretched_flow() {
        let p = Parameters { roll: UNWINDER, wound_thickness: 1e-4, ..Parameters::default() };
        let (r, v, eps) = (0.5, 10.0, 2e-3);
        assert!((2.0 * r * radius_rate(&p, r, v, eps) + 1e-4 * v / (PI * (1.0 + eps))).abs() < 1e-18);
    }
}
