//! The roller's partial derivatives (`fmi2GetDirectionalDerivative`): [R1]–[R4]
//! and the outputs differentiated by hand along a direction in the states
//! (omega, r, y, y') and the inputs. The profile's tables are functions of
//! time only, so they and their slopes are held.

use crate::contact::{self, Contact, Dual};
use crate::control;
use crate::parameters::{Inputs, Parameters, PORTS, STATES};
use crate::physics::{self, Roll};
use std::f64::consts::PI;

/// A direction in the knowns: d(omega, r, y, y', v_web, loop.I, motor.torque, dancer.I) and d(inputs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Direction {
    pub state: [f64; STATES],
    pub u: Inputs,
}

/// The derivatives along a `Direction` of everything the roller computes, each named as the
/// roller's own (`t.x` for `Roller::x()`): the outputs, the states and their derivatives.
/// The binding (variables.rs) reads them by the same names.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tangents {
    pub surface_speed: f64,
    pub web_speed: f64,
    pub slip: f64,
    pub traction_used: f64,
    pub mu_eff: f64,
    pub h_air: f64,
    /// The strain leaving at each outlet (`strain_leaving`).
    pub outlet_strains: [f64; PORTS],
    pub drive_torque: f64,
    pub loop_integrator: f64,
    pub motor_state: f64,
    pub dancer_integrator: f64,
    /// d of (omega, r, y, y', v_web, loop.I, motor.torque, dancer.I)/dt.
    pub derivatives: [f64; STATES],
    pub omega: f64,
    pub radius: f64,
    /// The carriage's (y, y').
    pub carriage: [f64; 2],
    pub contact_a_x: f64,
    pub contact_b_x: f64,
    pub contact_y: f64,
    pub load_cell_force: f64,
}

impl Tangents {
    /// The tangent of `Roller::strain_leaving(outlet)`.
    #[inline]
    pub fn strain_leaving(&self, outlet: usize) -> f64 {
        self.outlet_strains[outlet]
    }
}

/// Whether the tangents along omega, the carriage's y and y' and every input are the same at
/// every state, input and time, for as long as the parameters and the roll stay: [R1], [R2]
/// and [R4] are then linear with coefficients made of parameters. So for a roller that winds
/// no roll (J and r fixed) and merges no webs ([R5] with one inlet passes the strain on, and so do
/// layers [R9], each its own). Not where the web may slip: [R7] is nonlinear; nor where a drive has a
/// loop: its limit [R11] is nonlinear, and its gains and limit are tunable; nor with a load cell, a
/// root of the forces.
pub fn tangents_fixed(p: &Parameters) -> bool {
    !p.winding() && (p.inlets <= 1 || p.layered) && !p.traction && control::Kind::of(p) == control::Kind::None && p.load_cell_wrap == 0.0
}

/// What the tangents read besides the direction: the roller now, its drive's tables read at
/// the time now (they are functions of time only, so they and their slopes are held).
pub struct Point<'a> {
    pub params: &'a Parameters,
    pub inputs: &'a Inputs,
    pub omega: f64,
    pub roll: Roll,
    /// The surface speed [R2] (a speed table's where the surface follows one).
    pub speed: f64,
    /// The speed table's slope where the surface follows one.
    pub speed_slope: Option<f64>,
    /// A tension drive's tension; 0 for the other drives.
    pub tension: f64,
    /// The drive's torque (not read where the surface follows a speed table).
    pub torque: f64,
    /// The leaving strain follows a table.
    pub strain_table: bool,
    /// Where the web may slip: the contact [R6]–[R8] now (its differentials zero).
    pub contact: Option<contact::State>,
    /// The drive's loop [R10]-[R11].
    pub control: Option<control::Point>,
    /// d(a powder brake's torque)/d(surface speed) [R12] (0 without one).
    pub brake_slope: f64,
}

impl<'a> Point<'a> {
    /// What the tangents along every direction share.
    #[inline]
    pub fn linearize(&self) -> Linearization<'a> {
        let p = self.params;
        let r = self.roll.radius;
        let c = if p.winding() { p.roll_sign() * p.wound_thickness / (2.0 * PI) } else { 0.0 };
        // Where the web may slip, the contact and what it moves, with their gradients, once for every direction.
        let slip = self.contact.map(|s| {
            let c = contact::contact(p, &s);
            Slip { web_acceleration: contact::web_acceleration(p, &s, c.force), traction_used: contact::traction_used(p, &s, c.mu_eff), contact: c }
        });
        Linearization {
            params: p,
            inputs: self.inputs,
            inertia: self.roll.inertia,
            speed_table: self.speed_slope.is_some(),
            omega: self.omega,
            r,
            v: self.speed,
            c,
            r_rate: c * self.speed / r,
            slope: self.speed_slope.unwrap_or(0.0),
            tension: self.tension,
            web_torque: slip.as_ref().map_or_else(|| physics::web_torque(p, r, self.inputs), |s| -r * s.contact.force.x),
            torque: self.torque,
            strain_table: self.strain_table,
            slip,
            control: self.control,
            brake_slope: self.brake_slope,
        }
    }
}

/// d(eps_b) of [R5] along d(inputs) at each outlet: one inlet passes its strain on, and so does each
/// of the inlets that stay layers [R9].
fn strain_leaving_tangent(p: &Parameters, u: &Inputs, d: &Inputs) -> [f64; PORTS] {
    if p.layered {
        return std::array::from_fn(|k| d.strain_a[physics::layer_inlet(p, k)]);
    }
    if p.inlets == 1 {
        return [d.strain_a[0]; PORTS];
    }
    let gradient = physics::merged_strain_gradient(p, &u.strain_a);
    [gradient.iter().zip(&d.strain_a).map(|(g, x)| g * x).sum(); PORTS]
}

/// d(load cell) along d(F_a), d(F_b): F = sqrt(F_a^2 + F_b^2 - 2 F_a F_b cos(wrap)), so
/// dF = ((F_a - F_b cos) dF_a + (F_b - F_a cos) dF_b)/F; 0 where F is 0 (a cusp, where a
/// central difference gives 0 too).
fn load_cell_tangent(a: f64, b: f64, cos: f64, da: f64, db: f64) -> f64 {
    let f = physics::load_cell(a, b, cos);
    if f > 0.0 {
        ((a - b * cos) * da + (b - a * cos) * db) / f
    } else {
        0.0
    }
}

/// A roller's values the tangents along any direction use (`Point::linearize`).
pub struct Linearization<'a> {
    params: &'a Parameters,
    inputs: &'a Inputs,
    inertia: f64,
    /// The surface speed follows a speed table.
    speed_table: bool,
    omega: f64,
    r: f64,
    v: f64,
    /// r' = c v / r on a roll being wound.
    c: f64,
    r_rate: f64,
    /// The speed table's slope, the tension table's value (a tension drive).
    slope: f64,
    tension: f64,
    web_torque: f64,
    torque: f64,
    strain_table: bool,
    slip: Option<Slip>,
    control: Option<control::Point>,
    brake_slope: f64,
}

/// Where the web may slip on the roller: the contact [R6]-[R8] and what it moves, with gradients.
struct Slip {
    contact: Contact,
    web_acceleration: Dual,
    traction_used: Dual,
}

impl Linearization<'_> {
    /// d(everything)/d(direction).
    #[inline]
    pub fn along(&self, d: &Direction) -> Tangents {
        let (p, u) = (self.params, self.inputs);
        let [d_omega, d_r, d_y, d_y_dot, d_v_web, d_integrator, d_motor, d_dancer] = d.state;
        let (omega, r, j, v, c, r_rate) = (self.omega, self.r, self.inertia, self.v, self.c, self.r_rate);
        let winding = p.winding();
        // [R3]: J(r), and with v = r*omega (or a speed table) r' = s*h_w*v/(2*pi*r).
        let d_j = if winding { 2.0 * PI * p.wound_density * p.wound_width * r.powi(3) * d_r } else { 0.0 };
        let d_v = if self.speed_table { 0.0 } else { omega * d_r + r * d_omega };
        let d_r_rate = c * (d_v * r - v * d_r) / (r * r);
        let web_torque = self.web_torque;
        // Where the web may slip [R6]–[R8]: the contact along d (its knowns: the speeds, the tensions, r),
        // its friction f moving the roller by -r*f.
        let along_contact = self.slip.as_ref().map(|s| {
            let d = [d_v_web, d_v, d.u.force_a[0], d.u.force_b[0], d_r];
            (s.contact.force.x, s.contact.force.along(&d), s.web_acceleration.along(&d), s.traction_used.along(&d), s.contact.mu_eff.along(&d), s.contact.h_air.along(&d))
        });
        let d_web_torque = match along_contact {
            Some((f, df, ..)) => -d_r * f - r * df,
            None => d_r * (u.pull_forward(p) - u.pull_back(p)) + r * (d.u.pull_forward(p) - d.u.pull_back(p)),
        };
        // The loop [R10]-[R11]: its rates and its motor's torque along d.
        let (d_loop_rates, d_motor_torque) = self.control.map_or(([0.0; 2], 0.0), |c| {
            let de = c.de[0] * d.u.measured + c.de[1] * d_omega + c.de[2] * d_r + c.de[3] * d.u.dancer_y + c.de[4] * d_dancer;
            c.law.along(de, c.dff_r * d_r, d_integrator, d_motor)
        });
        // A dancer loop's integrator [R13]: its rate dancer.ki*e_d moves with dancer.y only.
        let d_dancer_rate = self.control.map_or(0.0, |c| c.dancer_rate_dy * d.u.dancer_y);
        // Without traction the web's speed is the surface's, and so is its rate: d(r*omega)/dt.
        let (d_torque, d_omega_rate, d_surface_rate) = if self.speed_table {
            // tau = J*v'/r + b*omega - r*(F_b - F_a); omega' = v'/r - v*r'/r^2.
            let slope = self.slope;
            let d_torque = d_j * slope / r - j * slope * d_r / (r * r) + p.damping * d_omega - d_web_torque;
            let d_omega_rate = -slope * d_r / (r * r) - (d_v * r_rate + v * d_r_rate) / (r * r) + 2.0 * v * r_rate * d_r / r.powi(3);
            (d_torque, d_omega_rate, 0.0)
        } else {
            // omega' = (r*(F_b - F_a) + tau - b*omega - J'*omega)/J with J' = 2*pi*rho*w*r^3*r'.
            let d_torque = d.u.torque + p.roll_sign() * self.tension * d_r + d_motor_torque + self.brake_slope * d_v;
            let k = 2.0 * PI * p.wound_density * p.wound_width;
            let j_rate = if winding { k * r.powi(3) * r_rate } else { 0.0 };
            let d_j_rate = if winding { k * (3.0 * r * r * d_r * r_rate + r.powi(3) * d_r_rate) } else { 0.0 };
            let omega_rate = (web_torque + self.torque - p.damping * omega - j_rate * omega) / j;
            let d_net = d_web_torque + d_torque - p.damping * d_omega - d_j_rate * omega - j_rate * d_omega;
            let d_omega_rate = (d_net - omega_rate * d_j) / j;
            (d_torque, d_omega_rate, d_r * omega_rate + r * d_omega_rate + d_omega * r_rate + omega * d_r_rate)
        };
        // [R4] on a carriage: y'' = (F_load + load - F_a - F_b - d*y' - k*(y - y_start))/m.
        let (d_y_rate, d_y_dot_rate) = if p.carriage {
            let force = d.u.load - d.u.pull_back(p) - d.u.pull_forward(p);
            (d_y_dot, (force - p.carriage_damping * d_y_dot - p.carriage_stiffness * d_y) / p.carriage_mass)
        } else {
            (0.0, 0.0)
        };
        let surface = if self.speed_table { 0.0 } else { d_v };
        let (web_speed, slip, traction_used, mu_eff, h_air, d_v_web_rate) = match along_contact {
            Some((_, _, rate, used, mu_eff, h_air)) => (d_v_web, d_v_web - surface, used, mu_eff, h_air, rate),
            None => (surface, 0.0, 0.0, 0.0, 0.0, d_surface_rate),
        };
        Tangents {
            surface_speed: surface,
            web_speed,
            slip,
            traction_used,
            mu_eff,
            h_air,
            outlet_strains: if self.strain_table { [0.0; PORTS] } else { strain_leaving_tangent(p, u, &d.u) },
            drive_torque: d_torque,
            derivatives: [d_omega_rate, d_r_rate, d_y_rate, d_y_dot_rate, d_v_web_rate, d_loop_rates[0], d_loop_rates[1], d_dancer_rate],
            loop_integrator: d_integrator,
            motor_state: d_motor,
            dancer_integrator: d_dancer,
            omega: d_omega,
            radius: d_r,
            carriage: [d_y, d_y_dot],
            // [R4]: (0, y_start - y) and (2r, y_start - y).
            contact_a_x: 0.0,
            contact_b_x: 2.0 * d_r,
            contact_y: -d_y,
            load_cell_force: if p.load_cell_wrap > 0.0 {
                load_cell_tangent(u.pull_back(p), u.pull_forward(p), p.load_cell_wrap.cos(), d.u.pull_back(p), d.u.pull_forward(p))
            } else {
                0.0
            },
        }
    }
}
