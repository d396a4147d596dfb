//! Which field of the model each variable of the model description is:
//! one exhaustive `match` per type over the enums build.rs generates, so a
//! variable added to or removed from modelDescription.xml without a change
//! here stops the build.

use super::description::{Boolean, Integer, Real};
use super::parameters::{Inputs, Parameters, WebProperties};
use super::{physics, ConvertingSpan};
use crate::fmi2::{FmiError, FmiResult};

impl ConvertingSpan {
    /// The value of a Real variable.
    #[inline]
    pub fn real(&self, var: Real) -> f64 {
        let p = &self.params;
        let u = &self.inputs;
        let sensor_on = |x: f64| if p.use_sensor { x } else { 0.0 };
        match var {
            Real::L => p.span_length,
            Real::wp1_E => p.incoming.modulus,
            Real::wp1_thickness => p.incoming.thickness,
            Real::wp1_width => p.incoming.width,
            Real::wp1_density => p.incoming.density,
            Real::wp1_d_r => p.incoming.retardation_time,
            Real::wp2_E => p.span_web.modulus,
            Real::wp2_thickness => p.span_web.thickness,
            Real::wp2_width => p.span_web.width,
            Real::wp2_density => p.span_web.density,
            Real::wp2_d_r => p.span_web.retardation_time,
            Real::eps_start => p.strain_start,
            Real::tolerance => p.tolerance,
            Real::web_a_v => u.speed_a,
            Real::web_a_eps => u.strain_a,
            Real::web_b_v => u.speed_b,
            Real::frame_a_x => u.frame_a[0],
            Real::frame_a_y => u.frame_a[1],
            Real::frame_b_x => u.frame_b[0],
            Real::frame_b_y => u.frame_b[1],
            Real::v => sensor_on(u.speed_b * self.sensor.speed),
            Real::T => sensor_on(self.outputs().tension * self.sensor.force),
            Real::web_a_F | Real::summary_Tension => self.outputs().tension,
            Real::web_b_F => self.outputs().exit_force,
            Real::web_b_eps | Real::summary_Strain => self.outputs().strain,
            Real::summary_Length => self.outputs().length,
            // [8] stress on the unstrained cross-section of wp2
            Real::summary_Stress => self.outputs().tension / p.span_web.area(),
            Real::unstretchedLength => self.unstretched.value(),
            Real::m_web => physics::web_mass(&p.span_web, self.unstretched.value()),
            Real::der_unstretchedLength => self.unstretched_rate(),
        }
    }

    /// The field behind a Real parameter or input; `None` for outputs.
    #[inline]
    pub(super) fn real_field(&mut self, var: Real) -> Option<&mut f64> {
        let p = &mut self.params;
        let u = &mut self.inputs;
        fn web(w: &mut WebProperties, field: Real) -> Option<&mut f64> {
            Some(match field {
                Real::wp1_E | Real::wp2_E => &mut w.modulus,
                Real::wp1_thickness | Real::wp2_thickness => &mut w.thickness,
                Real::wp1_width | Real::wp2_width => &mut w.width,
                Real::wp1_density | Real::wp2_density => &mut w.density,
                _ => &mut w.retardation_time,
            })
        }
        Some(match var {
            Real::L => &mut p.span_length,
            Real::wp1_E | Real::wp1_thickness | Real::wp1_width | Real::wp1_density | Real::wp1_d_r => {
                return web(&mut p.incoming, var)
            }
            Real::wp2_E | Real::wp2_thickness | Real::wp2_width | Real::wp2_density | Real::wp2_d_r => {
                return web(&mut p.span_web, var)
            }
            Real::eps_start => &mut p.strain_start,
            Real::tolerance => &mut p.tolerance,
            Real::web_a_v
            | Real::web_a_eps
            | Real::web_b_v
            | Real::frame_a_x
            | Real::frame_a_y
            | Real::frame_b_x
            | Real::frame_b_y => return input_field(u, var),
            Real::v
            | Real::T
            | Real::web_a_F
            | Real::web_b_F
            | Real::web_b_eps
            | Real::summary_Tension
            | Real::summary_Length
            | Real::summary_Strain
            | Real::summary_Stress
            | Real::unstretchedLength
            | Real::m_web
            | Real::der_unstretchedLength => return None,
        })
    }

    /// Sets a parameter or input; `Err` for variables that cannot be set.
    #[inline]
    pub fn set_real_var(&mut self, var: Real, x: f64) -> FmiResult {
        match self.real_field(var) {
            Some(field) => {
                *field = x;
                Ok(())
            }
            None => Err(not_settable(var)),
        }
    }

    pub(super) fn boolean_field(p: &mut Parameters, var: Boolean) -> &mut bool {
        match var {
            Boolean::includeDamping => &mut p.include_damping,
            Boolean::preventNegativeTension => &mut p.prevent_negative_tension,
            Boolean::includeMass => &mut p.include_mass,
            Boolean::variableLength => &mut p.variable_length,
            Boolean::startAtEquilibrium => &mut p.start_at_equilibrium,
            Boolean::useSensor => &mut p.use_sensor,
        }
    }

    pub(super) fn integer_field(p: &mut Parameters, var: Integer) -> &mut i32 {
        match var {
            Integer::toUnitV => &mut p.speed_unit,
            Integer::toUnitF => &mut p.force_unit,
            Integer::solver => &mut p.solver,
            Integer::substeps => &mut p.substeps,
        }
    }
}

#[cold]
fn not_settable(var: Real) -> FmiError {
    FmiError::error(format!("{} cannot be set", var.name()))
}

/// The field of an input (in a set of input values, or of their rates);
/// `None` for variables that are not inputs.
pub(super) fn input_field(u: &mut Inputs, var: Real) -> Option<&mut f64> {
    Some(match var {
        Real::web_a_v => &mut u.speed_a,
        Real::web_a_eps => &mut u.strain_a,
        Real::web_b_v => &mut u.speed_b,
        Real::frame_a_x => &mut u.frame_a[0],
        Real::frame_a_y => &mut u.frame_a[1],
        Real::frame_b_x => &mut u.frame_b[0],
        Real::frame_b_y => &mut u.frame_b[1],
        _ => return None,
    })
}
