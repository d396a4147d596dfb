//! The equations of the converting span. Numbers in brackets refer to the
//! equations of the model documentation (documentation/index.html).
//!
//! The state is the unstretched length of web in the span, x = L/(1+eps_b).

use crate::description::{Effect, Effects, Real, DESCRIPTION};
use crate::parameters::{Inputs, Parameters, Rates, SlackRule, WebProperties};
use crate::sensor::SensorScale;
use solver::{decay_integral, CompensatedSum};

/// Every output of the span at one instant: its forces and what the stress and the sensor add.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outputs {
    pub forces: Forces,
    /// Stress on the unstrained cross-section of wp2 [E8], Pa.
    pub stress: f64,
    /// The sensor outputs v and T in the chosen units [E7] (0 with the sensor off).
    pub sensor_speed: f64,
    pub sensor_tension: f64,
}

/// The outputs [E1], [E5], [E7]-[E10] for the state x, the inputs u and the
/// rates of the inputs. Effects that are off are not computed at all.
#[inline(always)]
pub fn outputs(p: &Parameters, u: &Inputs, x: CompensatedSum, rates: Rates, sensor: &SensorScale) -> Outputs {
    let forces = forces(p, u, x, rates);
    let sensor_on = |value: f64| if p.use_sensor { value } else { 0.0 };
    Outputs {
        forces,
        stress: forces.tension / p.span_web.area(),
        sensor_speed: sensor_on(u.speed_b * sensor.speed),
        sensor_tension: sensor_on(forces.tension * sensor.force),
    }
}

/// The part of the outputs the rollers at a span's ends read (its forces and strain), with
/// dx/dt [E2], which the damped force needs too: computed once for both.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Forces {
    /// L [E9], m.
    pub length: f64,
    /// eps_b [E1].
    pub strain: f64,
    /// T [E5], N: the force at the entry end a.
    pub tension: f64,
    /// F_b [E10], N: the force at the exit end b.
    pub exit_force: f64,
    /// dx/dt [E2], m/s.
    pub unstretched_rate: f64,
}

/// `Forces` for the state x, the inputs u and the rates of the inputs.
#[inline(always)]
pub fn forces(p: &Parameters, u: &Inputs, x: CompensatedSum, rates: Rates) -> Forces {
    let length = span_length(p, u);
    let strain = strain(length, x, 0.0);
    let rate = unstretched_rate(u, strain);
    let tension = tension(p, force_of(p, length, x.value(), strain, rates.length, || rate));
    let exit_force =
        if p.effects.include_mass { tension + momentum_difference(p, u, strain, x.value(), rates.speed_b) } else { tension };
    Forces { length, strain, tension, exit_force, unstretched_rate: rate }
}

/// The web's pull before the slack clamp [E5]: E*A*(eps_b + d_r2*deps_b/dt),
/// or with a stress–strain table [E5a] A*(sigma(eps_b) + d_r2*E_t(eps_b)*deps_b/dt)
/// with the tangent modulus E_t. The rate [E4] is computed only with damping.
#[inline(always)]
pub fn web_force(p: &Parameters, u: &Inputs, length: f64, x: f64, strain_b: f64, length_rate: f64) -> f64 {
    force_of(p, length, x, strain_b, length_rate, || unstretched_rate(u, strain_b))
}

/// `web_force` with dx/dt [E2] from `unstretched_rate`, called only where damping needs it.
#[inline(always)]
fn force_of(p: &Parameters, length: f64, x: f64, strain_b: f64, length_rate: f64, unstretched_rate: impl Fn() -> f64) -> f64 {
    let web = &p.span_web;
    let rate = || strain_rate(length, length_rate, x, strain_b, unstretched_rate());
    match &web.curve {
        None if p.effects.include_damping => web.stiffness() * (strain_b + web.retardation_time * rate()),
        None => web.stiffness() * strain_b,
        Some(curve) => {
            let (sigma, tangent) = curve.at(strain_b);
            let damping = if p.effects.include_damping { web.retardation_time * tangent * rate() } else { 0.0 };
            web.area() * (sigma + damping)
        }
    }
}

/// Whether an effect's equation reads the input rates dv_b/dt and dL/dt [E11]:
/// decided here for every effect, so a new one in the XML stops the build
/// until it is placed (only the effects that read the rates pay for them).
pub const fn reads_input_rates(effect: Effect) -> bool {
    match effect {
        Effect::includeDamping | Effect::includeMass => true,
        Effect::preventNegativeTension | Effect::variableLength => false,
    }
}

/// Whether any effect that is on reads the input rates.
#[inline(always)]
pub fn needs_input_rates(effects: &Effects) -> bool {
    let mut any = false;
    for effect in Effect::ALL {
        any |= reads_input_rates(effect) && effects.get(effect);
    }
    any
}

/// Span length [E9]: the parameter L, or |r_b - r_a| with `variableLength`.
pub fn span_length(p: &Parameters, u: &Inputs) -> f64 {
    if p.effects.variable_length {
        let [dx, dy] = u.span_vector();
        dx.hypot(dy)
    } else {
        p.span_length
    }
}

/// dL/dt [E9] when the roller positions move at `rates` (0 for a fixed L).
pub fn length_rate(p: &Parameters, u: &Inputs, rates: &Inputs) -> f64 {
    if !p.effects.variable_length {
        return 0.0;
    }
    let [dx, dy] = u.span_vector();
    let [rx, ry] = rates.span_vector();
    (dx * rx + dy * ry) / dx.hypot(dy)
}

/// Span strain, eps_b = L/x - 1 [E1], written (L - x)/x with x = x0 + y:
/// with x0 a compensated sum, `L - hi` is exact near L and the strain keeps
/// full relative precision even at strains of 1e-6.
pub fn strain(length: f64, x0: CompensatedSum, y: f64) -> f64 {
    (((length - x0.hi()) - x0.lo()) - y) / (x0.value() + y)
}

/// Whether x is a state the equations can evaluate: short enough that
/// 1 + eps_b = L/x is not lost to rounding (x < L/2^-52; beyond that the
/// strain is -1 to double precision and the rates divide by zero: web fed in
/// from both ends for too long), and long enough that the strain stays
/// within the physical bound of every strain, `web_a.eps`'s maximum (web
/// pulled out faster than it comes in would otherwise stretch without end).
pub fn representable(length: f64, x: f64) -> bool {
    x > 0.0 && x.is_finite() && length > f64::EPSILON * x && length <= (1.0 + max_strain()) * x
}

// The physical bounds the equations rely on, as modelDescription.xml declares them.

/// The largest strain any web may have: the declared maximum of `web_a.eps`.
#[inline]
pub fn max_strain() -> f64 {
    DESCRIPTION.variable(Real::web_a_eps.vr()).map_or(f64::INFINITY, |v| v.range.hi)
}

/// The shortest span: the declared minimum of `L`, also for `variableLength`.
#[inline]
pub fn min_length() -> f64 {
    DESCRIPTION.variable(Real::L.vr()).map_or(0.0, |v| v.range.lo)
}

/// An input's largest rate of change (`maxRate`), per second.
#[inline]
pub fn max_rate(var: Real) -> f64 {
    DESCRIPTION.variable(var.vr()).map_or(f64::INFINITY, |v| v.max_rate)
}

/// The unstretched length that holds strain `eps` in a span of length L [E1]:
/// L/(1+eps) = L - L*eps/(1+eps), split so that no digit of eps is lost.
pub fn unstretched_length(length: f64, eps: f64) -> CompensatedSum {
    CompensatedSum::two_sum(length, -length * eps / (1.0 + eps))
}

/// The strain of the web entering through a: eps_a for forward flow; web
/// leaving backwards through a carries the span's strain.
fn strain_in(u: &Inputs, strain_b: f64) -> f64 {
    if u.speed_a >= 0.0 {
        u.strain_a
    } else {
        strain_b
    }
}

/// Unstretched length entering through a per second, q_a [E2].
pub fn inflow(u: &Inputs, strain_b: f64) -> f64 {
    u.speed_a / (1.0 + strain_in(u, strain_b))
}

/// dx/dt = q_a - q_b [E2], unstretched length per second. Web leaving
/// through b carries the span's strain, and so does web entering
/// backwards at b (v_b < 0).
///
/// With eps_in the strain entering at a, the difference
/// v_a/(1+eps_in) - v_b/(1+eps_b) is formed as
/// ((v_a - v_b) + (v_a*eps_b - v_b*eps_in)) / ((1+eps_in)(1+eps_b)),
/// which does not cancel when v_a ~ v_b.
pub fn unstretched_rate(u: &Inputs, strain_b: f64) -> f64 {
    let (va, vb, eps_in) = (u.speed_a, u.speed_b, strain_in(u, strain_b));
    ((va - vb) + (va * strain_b - vb * eps_in)) / ((1.0 + eps_in) * (1.0 + strain_b))
}

/// lambda = -d(dx/dt)/dx = (v_b - min(v_a, 0)) / L [E3]: the inverse time
/// constant of the span, negative when web is fed in from both ends.
pub fn decay_rate(length: f64, u: &Inputs) -> f64 {
    (u.speed_b - u.speed_a.min(0.0)) / length
}

/// The exact step over h with inputs held and L constant [E3]: the balance
/// is then linear in x with constant coefficients.
pub fn exact_step(length: f64, u: &Inputs, x: CompensatedSum, h: f64) -> CompensatedSum {
    let rate = unstretched_rate(u, strain(length, x, 0.0));
    x.plus(rate * decay_integral(decay_rate(length, u), h))
}

/// d(eps_b)/dt = dL/dt / x - (1+eps_b)^2 / L * dx/dt [E4].
pub fn strain_rate(length: f64, length_rate: f64, x: f64, strain_b: f64, unstretched_rate: f64) -> f64 {
    length_rate / x - (1.0 + strain_b) * (1.0 + strain_b) / length * unstretched_rate
}

/// Whether the span carries its pull `web_force` as its tension [E5]: always without
/// `preventNegativeTension`; with it, while the pull is positive (a layer of a laminate: while
/// the laminate's is).
#[inline(always)]
pub fn carries(p: &Parameters, web_force: f64) -> bool {
    !p.effects.prevent_negative_tension
        || match p.slack_rule {
            SlackRule::Own => web_force > 0.0,
            SlackRule::Laminate { slack } => !slack,
        }
}

/// Span tension [E5]: the web's pull, 0 for a slack web with `preventNegativeTension` (`carries`).
pub fn tension(p: &Parameters, web_force: f64) -> f64 {
    if carries(p, web_force) {
        web_force
    } else {
        0.0
    }
}

/// Web mass in the span, m = rho_l2 * x [E10].
pub fn web_mass(web: &WebProperties, x: f64) -> f64 {
    web.linear_density() * x
}

/// F_b - F_a = q_a (rho_in v_b - rho_in' v_a) + m dv_b/dt [E10]: the momentum
/// the span's web gains per second. Web entering at a is wp1 (rho_l1);
/// web leaving backwards through a is the span's own (rho_l2).
pub fn momentum_difference(p: &Parameters, u: &Inputs, strain_b: f64, x: f64, speed_b_rate: f64) -> f64 {
    let rho_span = p.span_web.linear_density();
    let rho_in = if u.speed_a >= 0.0 { p.incoming.linear_density() } else { rho_span };
    inflow(u, strain_b) * (rho_span * u.speed_b - rho_in * u.speed_a) + web_mass(&p.span_web, x) * speed_b_rate
}

/// Strain at the steady state of the inputs [E6]:
/// 1 + eps_b = (v_b/v_a)(1 + eps_a), formed as (v_b - v_a + v_b*eps_a)/v_a;
/// eps_b = eps_a when v_a = 0. `None` where no steady state exists
/// (speeds of opposite signs, or a ratio that overflows).
pub fn equilibrium_strain(u: &Inputs) -> Option<f64> {
    let Inputs { speed_a: va, strain_a, speed_b: vb, .. } = *u;
    if va == 0.0 {
        return Some(strain_a);
    }
    let eps = (vb - va + vb * strain_a) / va;
    (vb / va > 0.0 && eps.is_finite() && eps > -1.0).then_some(eps)
}
