//! The bristle (LuGre, Canudas de Wit et al. 1995, normalized) that makes a contact stick: the
//! web on a roller [R7] and a powder brake [R12] share it. Its state, the grip u, is the share of
//! the kinetic limit the bristles carry (LuGre's z over its steady sliding value):
//!
//!   du/dt = (s - |s| u/psi(s))/delta,   g = u + exp(-(s/v_slip)^2) (s - |s| u/psi(s))/v_slip,
//!   psi(s) = 1 + (k_s - 1) exp(-(s/v_slip)^2)
//!
//! s the slip, delta the presliding displacement, v_slip the damping and Stribeck speed, k_s the
//! static over kinetic friction. The damping fades with the slip (LuGre's sigma_1(s)), so that a slip
//! far from the grip's asks at most about 0.43 (1 + |u|/psi) of the limit more, never e^(|s|/v_slip). Steady, either s = 0 with |u| < psi(0) (sticking, at any load up
//! to the static limit) or u = psi(s) sign(s) (sliding at the limit); g is the share in use.
//!
//! |s| keeps its kink at s = 0: the rate is Lipschitz there (slopes (1 -/+ u/psi)/delta, both > 0
//! while sticking), which a smoothed |s| would trade for a steady slip that is not 0. Its slope
//! at s = 0 exactly is the mean of both sides' (sign(0) = 0).

use crate::number::Number;

/// The share of the limit in use and the grip's rate.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Grip<N> {
    /// g: the friction over its kinetic limit.
    pub share: N,
    /// du/dt.
    pub rate: N,
}

/// The grip's limit psi(s) at slip s (Stribeck's curve from k_s at rest to 1 sliding).
#[inline]
pub fn limit(s: f64, k_s: f64, v_slip: f64) -> f64 {
    1.0 + (k_s - 1.0) * (-(s / v_slip).powi(2)).exp()
}

/// A grip that slides steadily at slip s: psi(s) sign(s) (0 at s = 0).
pub fn sliding(s: f64, k_s: f64, v_slip: f64) -> f64 {
    if s == 0.0 {
        0.0
    } else {
        limit(s, k_s, v_slip).copysign(s)
    }
}

/// The bristle at slip `s` and grip `u`.
#[inline]
pub fn grip<N: Number>(s: N, u: N, k_s: f64, v_slip: f64, delta: f64) -> Grip<N> {
    let x = s.value();
    let psi = if k_s == 1.0 {
        N::constant(1.0)
    } else {
        let peak = limit(x, k_s, v_slip) - 1.0;
        s.map(1.0 + peak, -2.0 * peak * x / (v_slip * v_slip))
    };
    let sign = if x == 0.0 { 0.0 } else { x.signum() };
    let deflection = s - s.map(x.abs(), sign) * u / psi;
    let fade = (-(x / v_slip).powi(2)).exp();
    let damping = s.map(fade, -2.0 * x * fade / (v_slip * v_slip));
    Grip { share: u + damping * deflection / v_slip, rate: deflection / delta }
}

/// The bristle held at zero slip while a line solves its steady state: the same share and rate at
/// s = 0, without the kink of |s| (so that Newton's method sees one smooth system whatever the
/// grip needs): g = u + s/v_slip, du/dt = s/delta.
#[inline]
pub fn held<N: Number>(s: N, u: N, v_slip: f64, delta: f64) -> Grip<N> {
    Grip { share: u + s / v_slip, rate: s / delta }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::number::Tangent;

    /// Sticking: du/dt = 0 at s = 0 for any |u| < psi(0); sliding: u = psi(s) sign(s) is steady and g = u.
    #[test]
    fn it_sticks_at_zero_slip_and_slides_at_the_limit() {
        for u in [-1.1, -0.5, 0.0, 0.7355, 1.1] {
            let at = grip(0.0, u, 1.2, 1e-3, 5e-8);
            assert_eq!((at.rate, at.share), (0.0, u));
        }
        for s in [-0.3, -2e-3, 1e-4, 5.0] {
            let psi = 1.0 + 0.2 * (-(s / 1e-3f64).powi(2)).exp();
            let at = grip(s, psi * f64::signum(s), 1.2, 1e-3, 5e-8);
            assert!(at.rate.abs() < 1e-9 * s.abs() / 5e-8, "s {s}: {}", at.rate);
            assert!((at.share - psi * s.signum()).abs() < 1e-12);
        }
    }

    /// The tangents against central differences, away from the kink.
    #[test]
    fn the_tangents_are_the_laws_own() {
        let e = 1e-9;
        for (s, u, ds, du) in [(3e-4, 0.4, 1.0, 0.3), (-1.3e-3, -0.2, -0.5, 1.0), (2e-2, 0.9, 0.2, -0.7)] {
            let t = grip(Tangent::new(s, ds), Tangent::new(u, du), 1.3, 1e-3, 5e-8);
            let (hi, lo) = (grip(s + e * ds, u + e * du, 1.3, 1e-3, 5e-8), grip(s - e * ds, u - e * du, 1.3, 1e-3, 5e-8));
            for (what, d, h, l) in [("share", t.share.d, hi.share, lo.share), ("rate", t.rate.d, hi.rate, lo.rate)] {
                let fd = (h - l) / (2.0 * e);
                assert!((d - fd).abs() <= 1e-6 * fd.abs().max(1.0), "{what} at s {s}: {d} vs {fd}");
            }
        }
    }
}
