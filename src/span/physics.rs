//! The equations of the converting span. Numbers in brackets refer to the
//! equations of the model documentation (fmu/documentation/index.html).
//!
//! The state is the unstretched length of web in the span, x = L/(1+eps_b).

use super::parameters::{Inputs, Parameters};
use crate::solver::{decay_integral, CompensatedSum};

/// Span strain, eps_b = L/x - 1 [1], written (L - x)/x: with x as a
/// compensated sum, `L - hi` is exact near L and the strain keeps full
/// relative precision even at strains of 1e-6.
pub fn strain(span_length: f64, unstretched: CompensatedSum) -> f64 {
    ((span_length - unstretched.hi()) - unstretched.lo()) / unstretched.value()
}

/// The unstretched length that holds strain `eps` in a span of length L [1]:
/// L/(1+eps) = L - L*eps/(1+eps), split so that no digit of eps is lost.
pub fn unstretched_length(span_length: f64, eps: f64) -> CompensatedSum {
    CompensatedSum::two_sum(span_length, -span_length * eps / (1.0 + eps))
}

/// dx/dt = q_a - q_b [2], unstretched length per second. Web entering at a
/// carries eps_a; web leaving through either end carries the span's strain,
/// and so does web entering backwards at b (v_b < 0).
///
/// With eps_in the strain entering at a, the difference
/// v_a/(1+eps_in) - v_b/(1+eps_b) is formed as
/// ((v_a - v_b) + (v_a*eps_b - v_b*eps_in)) / ((1+eps_in)(1+eps_b)),
/// which does not cancel when v_a ~ v_b.
pub fn unstretched_rate(inputs: &Inputs, strain_b: f64) -> f64 {
    let Inputs { speed_a: va, strain_a, speed_b: vb } = *inputs;
    let strain_in = if va >= 0.0 { strain_a } else { strain_b };
    ((va - vb) + (va * strain_b - vb * strain_in)) / ((1.0 + strain_in) * (1.0 + strain_b))
}

/// lambda = -d(dx/dt)/dx = (v_b - min(v_a, 0)) / L [3]: the inverse time
/// constant of the span, negative when web is fed in from both ends.
pub fn decay_rate(span_length: f64, inputs: &Inputs) -> f64 {
    (inputs.speed_b - inputs.speed_a.min(0.0)) / span_length
}

/// The exact step over h with inputs held [3]: the balance is linear in x.
pub fn exact_step(span_length: f64, inputs: &Inputs, unstretched: CompensatedSum, h: f64) -> CompensatedSum {
    let rate = unstretched_rate(inputs, strain(span_length, unstretched));
    let lambda = decay_rate(span_length, inputs);
    unstretched.plus(rate * decay_integral(lambda, h))
}

/// d(eps_b)/dt = -(1+eps_b)^2 / L * dx/dt [4].
pub fn strain_rate(span_length: f64, strain_b: f64, unstretched_rate: f64) -> f64 {
    -(1.0 + strain_b) * (1.0 + strain_b) / span_length * unstretched_rate
}

/// Span tension [5]: T = E2*A2*(eps_b + d_r2*deps_b/dt), the damping term
/// only with `includeDamping` (computed only then), clamped at 0 for a
/// slack web with `preventNegativeTension`.
pub fn tension(p: &Parameters, inputs: &Inputs, strain_b: f64) -> f64 {
    let web = &p.span_web;
    let mut effective_strain = strain_b;
    if p.include_damping {
        let rate = unstretched_rate(inputs, strain_b);
        effective_strain += web.retardation_time * strain_rate(p.span_length, strain_b, rate);
    }
    let t = web.stiffness() * effective_strain;
    if p.prevent_negative_tension {
        t.max(0.0)
    } else {
        t
    }
}

/// Strain at the steady state of the inputs [6]:
/// 1 + eps_b = (v_b/v_a)(1 + eps_a), formed as (v_b - v_a + v_b*eps_a)/v_a;
/// eps_b = eps_a when v_a = 0. `None` where no steady state exists
/// (speeds of opposite signs, or a ratio that overflows).
pub fn equilibrium_strain(inputs: &Inputs) -> Option<f64> {
    let Inputs { speed_a: va, strain_a, speed_b: vb } = *inputs;
    if va == 0.0 {
        return Some(strain_a);
    }
    let eps = (vb - va + vb * strain_a) / va;
    (vb / va > 0.0 && eps.is_finite() && eps > -1.0).then_some(eps)
}
