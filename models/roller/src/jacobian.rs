//! The roller's partial derivatives (`fmi2GetDirectionalDerivative`): [R1]–[R4]
//! and the outputs differentiated by hand along a direction in the states
//! (omega, r, y, y') and the inputs. The profile's tables are functions of
//! time only, so they and their slopes are held.

use crate::drive::{Drive, Key};
use crate::physics::{self, Inputs, Parameters};
use crate::Roller;
use std::f64::consts::PI;

/// A direction in the knowns: d(omega, r, y, y') and d(inputs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Direction {
    pub state: [f64; 4],
    pub u: Inputs,
}

/// The derivatives of the outputs and of the state derivatives along a `Direction`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tangents {
    pub speed: f64,
    pub strain_leaving: f64,
    pub torque: f64,
    /// d of (omega, r, y, y')/dt.
    pub derivatives: [f64; 4],
}

/// d(eps_b) of [R5] along d(inputs): one inlet passes its strain on.
fn strain_leaving_tangent(p: &Parameters, u: &Inputs, d: &Inputs) -> f64 {
    if p.inlets == 1 {
        return d.strain_a[0];
    }
    let gradient = physics::merged_strain_gradient(p, &u.strain_a);
    gradient.iter().zip(&d.strain_a).map(|(g, x)| g * x).sum()
}

impl Roller {
    /// d(everything)/d(direction) now.
    #[inline]
    pub fn tangents(&self, d: &Direction) -> Tangents {
        let p = &self.params;
        let u = &self.inputs;
        let [d_omega, d_r, d_y, d_y_dot] = d.state;
        let (omega, r, j) = (self.omega(), self.radius(), self.roll.inertia);
        let winding = p.winding();
        // [R3]: J(r), and with v = r*omega (or a speed table) r' = s*h_w*v/(2*pi*r).
        let d_j = if winding { 2.0 * PI * p.wound_density * p.wound_width * r.powi(3) * d_r } else { 0.0 };
        let speed_table = self.table(Key::Speed).filter(|_| self.drive() == Drive::Speed);
        let v = self.surface_speed();
        let d_v = if speed_table.is_some() { 0.0 } else { omega * d_r + r * d_omega };
        let c = if winding { p.roll_sign() * p.wound_thickness / (2.0 * PI) } else { 0.0 };
        let r_rate = c * v / r;
        let d_r_rate = c * (d_v * r - v * d_r) / (r * r);
        let web_torque = physics::web_torque(p, r, u);
        let d_web_torque = d_r * (u.pull_forward(p) - u.pull_back(p)) + r * (d.u.pull_forward(p) - d.u.pull_back(p));
        let (d_torque, d_omega_rate) = match speed_table {
            // tau = J*v'/r + b*omega - r*(F_b - F_a); omega' = v'/r - v*r'/r^2.
            Some(t) => {
                let slope = t.slope(self.time);
                let d_torque = d_j * slope / r - j * slope * d_r / (r * r) + p.damping * d_omega - d_web_torque;
                let d_omega_rate = -slope * d_r / (r * r) - (d_v * r_rate + v * d_r_rate) / (r * r) + 2.0 * v * r_rate * d_r / r.powi(3);
                (d_torque, d_omega_rate)
            }
            // omega' = (r*(F_b - F_a) + tau - b*omega - J'*omega)/J with J' = 2*pi*rho*w*r^3*r'.
            None => {
                let d_torque = d.u.torque + if self.drive() == Drive::Tension {
                    p.roll_sign() * self.table(Key::Tension).map_or(0.0, |t| t.value(self.time)) * d_r
                } else {
                    0.0
                };
                let k = 2.0 * PI * p.wound_density * p.wound_width;
                let j_rate = if winding { k * r.powi(3) * r_rate } else { 0.0 };
                let d_j_rate = if winding { k * (3.0 * r * r * d_r * r_rate + r.powi(3) * d_r_rate) } else { 0.0 };
                let torque = self.drive_torque();
                let omega_rate = (web_torque + torque - p.damping * omega - j_rate * omega) / j;
                let d_net = d_web_torque + d_torque - p.damping * d_omega - d_j_rate * omega - j_rate * d_omega;
                (d_torque, (d_net - omega_rate * d_j) / j)
            }
        };
        // [R4] on a carriage: y'' = (F_load + load - F_a - F_b - d*y' - k*(y - y_start))/m.
        let (d_y_rate, d_y_dot_rate) = if p.carriage {
            let force = d.u.load - d.u.pull_back(p) - d.u.pull_forward(p);
            (d_y_dot, (force - p.carriage_damping * d_y_dot - p.carriage_stiffness * d_y) / p.carriage_mass)
        } else {
            (0.0, 0.0)
        };
        Tangents {
            speed: if speed_table.is_some() { 0.0 } else { d_v },
            strain_leaving: if self.table(Key::Strain).is_some() { 0.0 } else { strain_leaving_tangent(p, u, &d.u) },
            torque: d_torque,
            derivatives: [d_omega_rate, d_r_rate, d_y_rate, d_y_dot_rate],
        }
    }
}
