//! The exact step of a linear ODE with constant coefficients,
//! `dx/dt = f(x)`, `df/dx = -lambda`:
//!
//! `x(t+h) = x(t) + f(x(t)) * integral_0^h exp(-lambda*s) ds`.
//!
//! The integral is written so that it stays exact and finite for
//! `lambda -> 0` (stopped line) and for `lambda*h` as large as a float goes
//! (very short span at high speed, any step size).

/// `phi1(z) = (exp(z) - 1) / z`, with `phi1(0) = 1`. `expm1` keeps full
/// precision for tiny `|z|`, where `exp(z) - 1` would cancel; the `libm`
/// crate's, so that every platform gets the same bits (docs/platforms.md).
pub fn phi1(z: f64) -> f64 {
    if z == 0.0 {
        1.0
    } else {
        libm::expm1(z) / z
    }
}

/// `phi2(z) = (exp(z) - 1 - z) / z^2`, with `phi2(0) = 1/2`: the weight of a
/// forcing that grows linearly over a step. A series near 0, where the
/// closed form cancels.
pub fn phi2(z: f64) -> f64 {
    if z.abs() < 0.1 {
        // sum of z^k/(k+2)! for k <= 8: the next term is below 3e-17; the
        // closed form loses at most 20 ulps at |z| = 0.1.
        let mut sum = 0.0;
        for k in (0..=8).rev() {
            let factorial: f64 = (1..=k + 2).map(|i| i as f64).product();
            sum = sum * z + 1.0 / factorial;
        }
        sum
    } else {
        (libm::expm1(z) - z) / (z * z)
    }
}

/// `integral_0^h s * exp(-lambda*(h-s)) ds = h^2 * phi2(-lambda*h)`: the
/// response at `h` to a forcing `s` of unit slope.
pub fn ramp_integral(lambda: f64, h: f64) -> f64 {
    h * h * phi2(-lambda * h)
}

/// `integral_0^h exp(-lambda*s) ds = h * phi1(-lambda*h)`.
///
/// For `|lambda*h| >= 1` it is evaluated as `-expm1(-lambda*h)/lambda`, which
/// tends to `1/lambda` without forming `h * 0` when `exp(-lambda*h)` underflows.
/// Negative `lambda` (growth) gives an infinite result once it overflows;
/// the caller must check.
pub fn decay_integral(lambda: f64, h: f64) -> f64 {
    let z = -lambda * h;
    if z.abs() < 1.0 {
        h * phi1(z)
    } else {
        -libm::expm1(z) / lambda
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phi2_is_continuous_where_the_series_meets_the_closed_form() {
        assert_eq!(phi2(0.0), 0.5);
        for z in [-0.1, 0.1] {
            let (below, above) = (phi2(z * (1.0 - 1e-15)), phi2(z * (1.0 + 1e-15)));
            assert!((below - above).abs() < 1e-14, "{below} {above}");
        }
        // Against the closed form in exact-enough arithmetic: z = -1: (e^-1 - 1 + 1)/1.
        assert!((phi2(-1.0) - (-1.0f64).exp()).abs() < 1e-15);
        // lambda -> 0: h^2/2, the integral of s.
        assert_eq!(ramp_integral(0.0, 2.0), 2.0);
    }

    #[test]
    fn phi1_is_one_at_zero_and_accurate_near_it() {
        assert_eq!(phi1(0.0), 1.0);
        assert_eq!(phi1(-1e-300), 1.0);
        // phi1(z) = 1 + z/2 + z^2/6 + ...
        let z = -1e-8;
        assert!((phi1(z) - (1.0 + z / 2.0)).abs() < 1e-16);
    }

    #[test]
    fn decay_integral_matches_closed_form_over_many_decades() {
        for &lambda in &[1e-12, 1e-3, 1.0, 1e3, 6e3, 1e9] {
            for &h in &[1e-9, 1e-5, 1e-2, 1.0, 1e3] {
                let exact = -(-lambda * h as f64).exp_m1() / lambda;
                let got = decay_integral(lambda, h);
                assert!((got - exact).abs() <= 4.0 * f64::EPSILON * exact, "lambda {lambda} h {h}: {got} vs {exact}");
            }
        }
        assert_eq!(decay_integral(0.0, 2.5), 2.5);
        assert_eq!(decay_integral(1e300, 1e300), 1e-300);
    }
}
