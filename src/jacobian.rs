//! The span's partial derivatives (`fmi2GetDirectionalDerivative`): the
//! equations of `physics` differentiated by hand in forward mode. A
//! `Direction` moves the state and the inputs; `tangents` gives how fast every
//! output moves along it. The input rates the outputs read (dv_b/dt, the
//! given derivatives of the roller positions) are held: they are not inputs.

use crate::parameters::{Inputs, Parameters, Rates};
use crate::physics::{self, Outputs};
use crate::sensor::SensorScale;
use solver::CompensatedSum;

/// A direction in the knowns: d(unstretched length) and d(inputs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Direction {
    pub x: f64,
    pub u: Inputs,
}

/// The derivatives of every output, of dx/dt [2] and of the web mass [10] along a `Direction`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Tangents {
    pub outputs: Outputs,
    pub unstretched_rate: f64,
    pub web_mass: f64,
}

/// What the outputs read besides the state and the inputs.
pub struct Point<'a> {
    pub params: &'a Parameters,
    pub inputs: &'a Inputs,
    pub x: CompensatedSum,
    /// The rates the outputs use ([11]; zero when no effect reads them).
    pub rates: Rates,
    /// The importer's input derivatives for the next step, when given: dL/dt
    /// is formed from them and the current roller positions.
    pub given: Option<&'a Inputs>,
    pub sensor: &'a SensorScale,
}

impl Point<'_> {
    /// d(everything)/d(direction) at this point.
    pub fn tangents(&self, d: &Direction) -> Tangents {
        let (p, u) = (self.params, self.inputs);
        let x = self.x.value();
        let length = physics::span_length(p, u);
        let [sx, sy] = u.span_vector();
        let [dsx, dsy] = d.u.span_vector();
        let d_length = if p.variable_length { (sx * dsx + sy * dsy) / length } else { 0.0 };
        // [1]: 1 + eps_b = L/x.
        let strain = physics::strain(length, self.x, 0.0);
        let stretch = 1.0 + strain;
        let d_strain = (d_length - stretch * d.x) / x;
        // [2]: q_a - v_b/(1+eps_b). At v_a = 0 exactly: the forward branch, as `physics::inflow` takes it.
        let forward = u.speed_a >= 0.0;
        let (strain_in, d_strain_in) = if forward { (u.strain_a, d.u.strain_a) } else { (strain, d_strain) };
        let inflow = physics::inflow(u, strain);
        let d_inflow = (d.u.speed_a - inflow * d_strain_in) / (1.0 + strain_in);
        let d_outflow = (d.u.speed_b - u.speed_b / stretch * d_strain) / stretch;
        let rate = physics::unstretched_rate(u, strain);
        let d_rate = d_inflow - d_outflow;
        // [9]: dL/dt = (r_b - r_a).(given rates)/L moves with the positions; an estimate is held.
        let length_rate = self.rates.length;
        let d_length_rate = match self.given {
            Some(r) if p.variable_length => {
                let [rx, ry] = r.span_vector();
                ((dsx * rx + dsy * ry) - length_rate * d_length) / length
            }
            _ => 0.0,
        };
        // [4]: d(eps_b)/dt = dL/dt / x - (1+eps_b)^2/L * dx/dt.
        let factor = stretch * stretch / length;
        let strain_rate = physics::strain_rate(length, length_rate, x, strain, rate);
        let d_factor = (2.0 * stretch * d_strain - factor * d_length) / length;
        let d_strain_rate = d_length_rate / x - length_rate * d.x / (x * x) - (d_factor * rate + factor * d_rate);
        // [5], [5a].
        let web = &p.span_web;
        let damping = if p.include_damping { web.retardation_time } else { 0.0 };
        let d_force = match &web.curve {
            None => web.stiffness() * (d_strain + damping * d_strain_rate),
            Some(curve) => {
                let tangent = curve.at(strain).1;
                let d_tangent = if damping != 0.0 { curve.curvature(strain) * d_strain } else { 0.0 };
                web.area() * (tangent * d_strain + damping * (d_tangent * strain_rate + tangent * d_strain_rate))
            }
        };
        let force = physics::web_force(p, u, length, x, strain, length_rate);
        // The slack clamp: at a force of exactly 0 the slack side (derivative 0).
        let d_tension = if !p.prevent_negative_tension || force > 0.0 { d_force } else { 0.0 };
        // [10]: F_b - F_a = q_a (rho_l2 v_b - rho_in v_a) + rho_l2 x dv_b/dt, dv_b/dt held.
        let d_exit_force = if p.include_mass {
            let rho_span = web.linear_density();
            let rho_in = if forward { p.incoming.linear_density() } else { rho_span };
            d_tension
                + d_inflow * (rho_span * u.speed_b - rho_in * u.speed_a)
                + inflow * (rho_span * d.u.speed_b - rho_in * d.u.speed_a)
                + rho_span * d.x * self.rates.speed_b
        } else {
            d_tension
        };
        let sensor_on = |value: f64| if p.use_sensor { value } else { 0.0 };
        Tangents {
            outputs: Outputs {
                length: d_length,
                strain: d_strain,
                tension: d_tension,
                exit_force: d_exit_force,
                stress: d_tension / web.area(),
                sensor_speed: sensor_on(d.u.speed_b * self.sensor.speed),
                sensor_tension: sensor_on(d_tension * self.sensor.force),
            },
            unstretched_rate: d_rate,
            web_mass: web.linear_density() * d.x,
        }
    }
}

/// d(x_0) along `d` [6]: the initial state L/(1 + eps_0) moves with L and,
/// when starting at equilibrium, with eps_0 = (v_b/v_a)(1 + eps_a) - 1.
pub fn initial_state_tangent(p: &Parameters, u: &Inputs, d: &Inputs) -> f64 {
    let length = physics::span_length(p, u);
    let [sx, sy] = u.span_vector();
    let [dsx, dsy] = d.span_vector();
    let d_length = if p.variable_length { (sx * dsx + sy * dsy) / length } else { 0.0 };
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
