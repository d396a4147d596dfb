//! The span's partial derivatives (`fmi2GetDirectionalDerivative`): the
//! equations of `physics` differentiated by hand in forward mode. A
//! `Direction` moves the state and the inputs; `tangents` gives how fast every
//! output moves along it. The input rates the outputs read (dv_b/dt, the
//! given derivatives of the roller positions) are held: they are not inputs.

use crate::description::Effect;
use crate::parameters::{Inputs, Parameters, Rates};
use crate::physics::{self, Forces, Outputs};
use crate::sensor::SensorScale;
use solver::CompensatedSum;

/// Where each effect enters the tangents of `Point::tangents`: a new effect
/// in the XML stops the build here until its terms are written there.
pub const fn tangent_terms(effect: Effect) -> &'static str {
    match effect {
        Effect::includeDamping => "d_force: d_r times the tangent of the strain rate [E4], [E5]",
        Effect::preventNegativeTension => "d_tension: zero on the slack side of the clamp [E5]",
        Effect::includeMass => "d_exit_force: the momentum terms [E10]",
        Effect::variableLength => "d_length and d_length_rate: the roller positions [E9]",
    }
}

/// A direction in the knowns: d(unstretched length) and d(inputs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Direction {
    pub x: f64,
    pub u: Inputs,
}

/// The derivatives along a `Direction` of everything the span computes, each named as the
/// span's own (`t.x` for `ConvertingSpan::x()`): every output, dx/dt [E2] among its forces, the
/// state and the web mass [E10]. The binding (variables.rs) reads them by the same names.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tangents {
    pub outputs: Outputs,
    pub unstretched_length: f64,
    pub web_mass: f64,
}

/// What the outputs read besides the state and the inputs.
pub struct Point<'a> {
    pub params: &'a Parameters,
    pub inputs: &'a Inputs,
    pub x: CompensatedSum,
    /// The rates the outputs use ([E11]; zero when no effect reads them).
    pub rates: Rates,
    /// The importer's input derivatives for the next step, when given: dL/dt
    /// is formed from them and the current roller positions.
    pub given: Option<&'a Inputs>,
    pub sensor: &'a SensorScale,
}

impl<'a> Point<'a> {
    /// d(everything)/d(direction) at this point.
    #[inline]
    pub fn tangents(&self, d: &Direction) -> Tangents {
        self.linearize().along(d)
    }

    /// What the tangents along every direction share: the point's own values.
    #[inline]
    pub fn linearize(&self) -> Linearization<'a> {
        let (p, u) = (self.params, self.inputs);
        let x = self.x.value();
        let length = physics::span_length(p, u);
        // [E1]: 1 + eps_b = L/x.
        let strain = physics::strain(length, self.x, 0.0);
        let forward = u.speed_a >= 0.0;
        let length_rate = self.rates.length;
        let rate = physics::unstretched_rate(u, strain);
        let web = &p.span_web;
        // The stress-strain curve's tangent and curvature at the strain (unused without a curve).
        let (tangent, curvature) = match &web.curve {
            None => (0.0, 0.0),
            Some(curve) => (curve.at(strain).1, if p.effects.include_damping { curve.curvature(strain) } else { 0.0 }),
        };
        Linearization {
            params: p,
            inputs: u,
            given: self.given,
            sensor: self.sensor,
            speed_b_rate: self.rates.speed_b,
            length,
            stretch: 1.0 + strain,
            forward,
            inv_in: 1.0 / (1.0 + if forward { u.strain_a } else { strain }),
            inv_x: 1.0 / x,
            inv_length: 1.0 / length,
            inv_stretch: 1.0 / (1.0 + strain),
            inflow: physics::inflow(u, strain),
            rate,
            length_rate,
            factor: (1.0 + strain) * (1.0 + strain) / length,
            strain_rate: physics::strain_rate(length, length_rate, x, strain, rate),
            tangent,
            curvature,
            force: physics::web_force(p, u, length, x, strain, length_rate),
        }
    }
}

/// A point's values the tangents along any direction use (`Point::linearize`).
pub struct Linearization<'a> {
    params: &'a Parameters,
    inputs: &'a Inputs,
    given: Option<&'a Inputs>,
    sensor: &'a SensorScale,
    speed_b_rate: f64,
    length: f64,
    stretch: f64,
    forward: bool,
    /// 1/(1 + the entering strain), 1/x, 1/L, 1/(1 + eps_b).
    inv_in: f64,
    inv_x: f64,
    inv_length: f64,
    inv_stretch: f64,
    inflow: f64,
    rate: f64,
    length_rate: f64,
    factor: f64,
    strain_rate: f64,
    tangent: f64,
    curvature: f64,
    force: f64,
}

impl Linearization<'_> {
    /// d(everything)/d(direction).
    #[inline]
    pub fn along(&self, d: &Direction) -> Tangents {
        let (p, u) = (self.params, self.inputs);
        let (length, stretch) = (self.length, self.stretch);
        let [sx, sy] = u.span_vector();
        let [dsx, dsy] = d.u.span_vector();
        let d_length = if p.effects.variable_length { (sx * dsx + sy * dsy) / length } else { 0.0 };
        // Products with the point's reciprocals (`linearize`): a tangent is asked along many directions.
        let (inv_x, inv_length) = (self.inv_x, self.inv_length);
        let d_strain = (d_length - stretch * d.x) * inv_x;
        // [E2]: q_a - v_b/(1+eps_b). At v_a = 0 exactly: the forward branch, as `physics::inflow` takes it.
        let d_strain_in = if self.forward { d.u.strain_a } else { d_strain };
        let inflow = self.inflow;
        let d_inflow = (d.u.speed_a - inflow * d_strain_in) * self.inv_in;
        let d_outflow = (d.u.speed_b - u.speed_b * self.inv_stretch * d_strain) * self.inv_stretch;
        let d_rate = d_inflow - d_outflow;
        // [E9]: dL/dt = (r_b - r_a).(given rates)/L moves with the positions; an estimate is held.
        let length_rate = self.length_rate;
        let d_length_rate = match self.given {
            Some(r) if p.effects.variable_length => {
                let [rx, ry] = r.span_vector();
                ((dsx * rx + dsy * ry) - length_rate * d_length) / length
            }
            _ => 0.0,
        };
        // [E4]: d(eps_b)/dt = dL/dt / x - (1+eps_b)^2/L * dx/dt.
        let factor = self.factor;
        let d_factor = (2.0 * stretch * d_strain - factor * d_length) * inv_length;
        let d_strain_rate = d_length_rate * inv_x - length_rate * d.x * inv_x * inv_x - (d_factor * self.rate + factor * d_rate);
        // [E5], [E5a].
        let web = &p.span_web;
        let damping = if p.effects.include_damping { web.retardation_time } else { 0.0 };
        let d_force = match &web.curve {
            None => web.stiffness() * (d_strain + damping * d_strain_rate),
            Some(_) => {
                let tangent = self.tangent;
                let d_tangent = if damping != 0.0 { self.curvature * d_strain } else { 0.0 };
                web.area() * (tangent * d_strain + damping * (d_tangent * self.strain_rate + tangent * d_strain_rate))
            }
        };
        // The slack clamp: at a force of exactly 0 the slack side (derivative 0).
        let d_tension = if physics::carries(p, self.force) { d_force } else { 0.0 };
        // [E10]: F_b - F_a = q_a (rho_l2 v_b - rho_in v_a) + rho_l2 x dv_b/dt, dv_b/dt held.
        let d_exit_force = if p.effects.include_mass {
            let rho_span = web.linear_density();
            let rho_in = if self.forward { p.incoming.linear_density() } else { rho_span };
            d_tension
                + d_inflow * (rho_span * u.speed_b - rho_in * u.speed_a)
                + inflow * (rho_span * d.u.speed_b - rho_in * d.u.speed_a)
                + rho_span * d.x * self.speed_b_rate
        } else {
            d_tension
        };
        let sensor_on = |value: f64| if p.use_sensor { value } else { 0.0 };
        Tangents {
            outputs: Outputs {
                forces: Forces { length: d_length, strain: d_strain, tension: d_tension, exit_force: d_exit_force, unstretched_rate: d_rate },
                stress: d_tension / web.area(),
                sensor_speed: sensor_on(d.u.speed_b * self.sensor.speed),
                sensor_tension: sensor_on(d_tension * self.sensor.force),
            },
            unstretched_length: d.x,
            web_mass: web.linear_density() * d.x,
        }
    }
}

/// d(x_0) along `d` [E6]: the initial state L/(1 + eps_0) moves with L and,
/// when starting at equilibrium, with eps_0 = (v_b/v_a)(1 + eps_a) - 1.
pub fn initial_state_tangent(p: &Parameters, u: &Inputs, d: &Inputs) -> f64 {
    let length = physics::span_length(p, u);
    let [sx, sy] = u.span_vector();
    let [dsx, dsy] = d.span_vector();
    let d_length = if p.effects.variable_length { (sx * dsx + sy * dsy) / length } else { 0.0 };
    let (strain, d_strain) = match p.start_at_equilibrium.then(|| physics::equilibrium_strain(u)).flatten() {
        None => (p.strain_start, 0.0),
        // At v_a = 0 exactly the start is eps_a (the derivative of that branch).
        Some(eps) if u.speed_a == 0.0 => (eps, d.strain_a),
        Some(eps) => {
            let stretch = 1.0 + eps;
            (eps, (d.speed_b * (1.0 + u.strain_a) + u.speed_b * d.strain_a - stretch * d.speed_a) / u.speed_a)
        }
    };
    let x0 = length / (1.0 + strain);
    (d_length - x0 * d_strain) / (1.0 + strain)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::description::Effects;
    use crate::stress_strain::StressStrain;
    use std::sync::Arc;

    /// The k-th input (web_a.v, web_a.eps, web_b.v, frame_a.x/y, frame_b.x/y).
    fn input_mut(v: &mut Inputs, k: usize) -> &mut f64 {
        match k {
            0 => &mut v.speed_a,
            1 => &mut v.strain_a,
            2 => &mut v.speed_b,
            3 => &mut v.frame_a[0],
            4 => &mut v.frame_a[1],
            5 => &mut v.frame_b[0],
            _ => &mut v.frame_b[1],
        }
    }

    fn web(curve: bool) -> crate::parameters::WebProperties {
        let table = [[0.0, 0.0], [0.005, 1.5e5], [0.01, 4.5e5], [0.02, 1.2e6], [0.04, 2.6e6]];
        crate::parameters::WebProperties {
            modulus: 4.5e9,
            thickness: 5e-5,
            width: 1.2,
            density: 1390.0,
            retardation_time: 0.01,
            curve: curve.then(|| Arc::new(StressStrain::new(&table).unwrap())),
        }
    }

    /// The outputs, dx/dt and the mass at (x, u), the rates formed as the model forms them.
    fn values(p: &Parameters, u: &Inputs, x: f64, rates: Rates, given: Option<&Inputs>) -> [f64; 9] {
        let rates = match given {
            Some(r) => Rates { speed_b: r.speed_b, length: physics::length_rate(p, u, r) },
            None => rates,
        };
        let x = CompensatedSum::from_parts(x, 0.0);
        let o = physics::outputs(p, u, x, rates, &SensorScale { speed: 60.0, force: 0.2 });
        let (f, rate) = (o.forces, physics::unstretched_rate(u, o.forces.strain));
        [f.length, f.strain, f.tension, f.exit_force, o.stress, o.sensor_speed, o.sensor_tension, rate, physics::web_mass(&p.span_web, x.value())]
    }

    fn field(t: &Tangents) -> [f64; 9] {
        let (o, f) = (t.outputs, t.outputs.forces);
        [f.length, f.strain, f.tension, f.exit_force, o.stress, o.sensor_speed, o.sensor_tension, f.unstretched_rate, t.web_mass]
    }

    /// Every effect combination, forward and reverse flow, linear and
    /// nonlinear web, held and given rates: each known's tangent against a
    /// central difference of `physics` with step 1e-7 of its scale (the
    /// functions are rational, or a cubic of the strain, on that scale:
    /// truncation ~ 1e-14 relative; rounding ~ 1e-16 * |y| / 1e-7 ~ 1e-9 of
    /// |y|). Tolerance 1e-6 relative plus that rounding floor; a missing term
    /// of the equations is at least O(strain) ~ 1e-3 relative.
    #[test]
    fn tangents_match_central_differences_of_the_equations() {
        let mut checked = 0;
        for (effects, nonlinear) in Effects::every_combination().flat_map(|e| [(e, false), (e, true)]) {
            let p = Parameters {
                span_length: 1.0,
                incoming: web(false),
                span_web: web(nonlinear),
                effects,
                use_sensor: true,
                ..Parameters::default()
            };
            let strain = if nonlinear { 0.015 } else { 2e-3 };
            for (va, vb) in [(5.0, 5.02), (-3.0, -2.9)] {
                let u = Inputs { speed_a: va, strain_a: 1e-3, speed_b: vb, frame_a: [0.1, 0.2], frame_b: [0.9, 0.8] };
                let x = physics::span_length(&p, &u) / (1.0 + strain);
                let rate_in = Inputs { speed_b: 3.0, frame_a: [0.02, 0.0], frame_b: [0.1, -0.05], ..Inputs::default() };
                for given in [None, Some(&rate_in)] {
                    let held = Rates { speed_b: 2.0, length: 0.3 };
                    let rates = match given {
                        Some(r) => Rates { speed_b: r.speed_b, length: physics::length_rate(&p, &u, r) },
                        None => held,
                    };
                    let sensor = SensorScale { speed: 60.0, force: 0.2 };
                    let point = Point { params: &p, inputs: &u, x: CompensatedSum::from_parts(x, 0.0), rates, given, sensor: &sensor };
                    for k in 0..8 {
                        let mut d = Direction::default();
                        let (mut up, mut down) = (u, u);
                        let (mut xu, mut xd) = (x, x);
                        let h;
                        if k == 7 {
                            h = 1e-7 * x;
                            d.x = 1.0;
                            xu += h;
                            xd -= h;
                        } else {
                            h = 1e-7 * input_mut(&mut up, k).abs().max(if k == 1 { 1e-3 } else { 1.0 });
                            *input_mut(&mut d.u, k) = 1.0;
                            *input_mut(&mut up, k) += h;
                            *input_mut(&mut down, k) -= h;
                        }
                        let (a, b) = (values(&p, &up, xu, held, given), values(&p, &down, xd, held, given));
                        let tangent = field(&point.tangents(&d));
                        for i in 0..9 {
                            let fd = (a[i] - b[i]) / (2.0 * h);
                            let floor = 1e3 * f64::EPSILON * a[i].abs().max(b[i].abs()).max(va.abs()) / h;
                            let err = (tangent[i] - fd).abs();
                            assert!(err <= 1e-6 * fd.abs() + floor, "{effects:?}, nonlinear {nonlinear}, v_a {va}, given {}, known {k}, output {i}: {} vs {fd}", given.is_some(), tangent[i]);
                            checked += (fd.abs() > floor * 1e6) as usize;
                        }
                    }
                }
            }
        }
        assert!(checked > 1500, "only {checked} nonzero entries checked");
    }

    /// The initial state's tangent against a central difference of x_0(u) [E6].
    #[test]
    fn initial_state_tangent_matches_a_central_difference() {
        for (equilibrium, variable) in [(true, false), (true, true), (false, true), (false, false)] {
            let effects = Effects { variable_length: variable, ..Effects::default() };
            let p = Parameters { span_length: 1.0, start_at_equilibrium: equilibrium, effects, strain_start: 2e-3, ..Parameters::default() };
            let u = Inputs { speed_a: 5.0, strain_a: 1e-3, speed_b: 5.02, frame_a: [0.1, 0.2], frame_b: [0.9, 0.8] };
            let x0 = |u: &Inputs| {
                let eps = if equilibrium { physics::equilibrium_strain(u).unwrap() } else { p.strain_start };
                physics::span_length(&p, u) / (1.0 + eps)
            };
            for k in 0..7 {
                let mut d = Inputs::default();
                let (mut up, mut down) = (u, u);
                let h = 1e-7 * input_mut(&mut up, k).abs().max(if k == 1 { 1e-3 } else { 1.0 });
                *input_mut(&mut d, k) = 1.0;
                *input_mut(&mut up, k) += h;
                *input_mut(&mut down, k) -= h;
                let fd = (x0(&up) - x0(&down)) / (2.0 * h);
                let got = initial_state_tangent(&p, &u, &d);
                assert!((got - fd).abs() <= 1e-6 * fd.abs() + 1e3 * f64::EPSILON / h, "eq {equilibrium}, var {variable}, known {k}: {got} vs {fd}");
            }
        }
    }
}
