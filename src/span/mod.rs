//! The converting span: a free web span between two rollers where the web's
//! properties change from wp1 (arriving) to wp2 (in the span).
//!
//! * `parameters` — what the user sets, in SI units;
//! * `physics` — the equations, numbered as in the model documentation;
//! * `sensor` — unit conversion of the sensor outputs;
//! * `description` — the interface generated from modelDescription.xml;
//! * this file — the mapping of variables to fields, and the FMI model hooks.

pub mod description;
pub mod parameters;
pub mod physics;
pub mod sensor;

use crate::fmi2::{FmiError, FmiResult, Model, Persist, StateReader, StateWriter};
use crate::solver::CompensatedSum;
use description::{Boolean, Integer, Real, DESCRIPTION};
use parameters::{Inputs, Parameters, WebProperties};
use sensor::SensorScale;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConvertingSpan {
    pub params: Parameters,
    pub inputs: Inputs,
    /// The state: unstretched length of web in the span, m.
    unstretched: CompensatedSum,
    /// Derived from the parameters when initialization ends.
    sensor: SensorScale,
}

/// Every output, computed together from the state and the inputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outputs {
    pub strain: f64,
    pub tension: f64,
}

impl ConvertingSpan {
    pub fn unstretched_length(&self) -> f64 {
        self.unstretched.value()
    }

    pub fn outputs(&self) -> Outputs {
        let strain = physics::strain(self.params.span_length, self.unstretched);
        Outputs { strain, tension: physics::tension(&self.params, &self.inputs, strain) }
    }

    /// The value of a Real variable.
    pub fn real(&self, var: Real) -> f64 {
        let p = &self.params;
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
            Real::web_a_v => self.inputs.speed_a,
            Real::web_a_eps => self.inputs.strain_a,
            Real::web_b_v => self.inputs.speed_b,
            Real::v => sensor_on(self.inputs.speed_b * self.sensor.speed),
            Real::T => sensor_on(self.outputs().tension * self.sensor.force),
            // Without web mass the web pulls equally on both rollers.
            Real::web_a_F | Real::web_b_F | Real::summary_Tension => self.outputs().tension,
            Real::web_b_eps | Real::summary_Strain => self.outputs().strain,
            Real::summary_Length => p.span_length,
            // [8] stress on the unstrained cross-section of wp2
            Real::summary_Stress => self.outputs().tension / p.span_web.area(),
            Real::unstretchedLength => self.unstretched.value(),
        }
    }

    /// Sets a parameter or input; `Err` for variables that cannot be set.
    pub fn set_real_var(&mut self, var: Real, x: f64) -> FmiResult {
        let p = &mut self.params;
        let web = |which: &mut WebProperties, field: Real| -> FmiResult {
            match field {
                Real::wp1_E | Real::wp2_E => which.modulus = x,
                Real::wp1_thickness | Real::wp2_thickness => which.thickness = x,
                Real::wp1_width | Real::wp2_width => which.width = x,
                Real::wp1_density | Real::wp2_density => which.density = x,
                Real::wp1_d_r | Real::wp2_d_r => which.retardation_time = x,
                _ => unreachable_var(field)?,
            }
            Ok(())
        };
        match var {
            Real::L => p.span_length = x,
            Real::wp1_E | Real::wp1_thickness | Real::wp1_width | Real::wp1_density | Real::wp1_d_r => {
                web(&mut p.incoming, var)?
            }
            Real::wp2_E | Real::wp2_thickness | Real::wp2_width | Real::wp2_density | Real::wp2_d_r => {
                web(&mut p.span_web, var)?
            }
            Real::eps_start => p.strain_start = x,
            Real::web_a_v => self.inputs.speed_a = x,
            Real::web_a_eps => self.inputs.strain_a = x,
            Real::web_b_v => self.inputs.speed_b = x,
            Real::v
            | Real::T
            | Real::web_a_F
            | Real::web_b_F
            | Real::web_b_eps
            | Real::summary_Tension
            | Real::summary_Length
            | Real::summary_Strain
            | Real::summary_Stress
            | Real::unstretchedLength => unreachable_var(var)?,
        }
        Ok(())
    }

    fn boolean_field(p: &mut Parameters, var: Boolean) -> &mut bool {
        match var {
            Boolean::includeDamping => &mut p.include_damping,
            Boolean::preventNegativeTension => &mut p.prevent_negative_tension,
            Boolean::startAtEquilibrium => &mut p.start_at_equilibrium,
            Boolean::useSensor => &mut p.use_sensor,
        }
    }

    fn integer_field(p: &mut Parameters, var: Integer) -> &mut i32 {
        match var {
            Integer::toUnitV => &mut p.speed_unit,
            Integer::toUnitF => &mut p.force_unit,
        }
    }
}

/// The FMI layer only sets parameters and inputs; reaching this is a bug
/// reported as an error rather than a panic.
fn unreachable_var(var: Real) -> FmiResult {
    Err(FmiError::error(format!("{var:?} cannot be set")))
}

fn unknown_vr(vr: u32) -> FmiError {
    FmiError::error(format!("value reference {vr} is not a variable of this type"))
}

impl Model for ConvertingSpan {
    fn description() -> &'static crate::fmi2::description::ModelDescription {
        &DESCRIPTION
    }

    fn get_real(&self, vr: u32) -> FmiResult<f64> {
        Real::from_vr(vr).map(|var| self.real(var)).ok_or_else(|| unknown_vr(vr))
    }

    fn set_real(&mut self, vr: u32, value: f64) -> FmiResult {
        self.set_real_var(Real::from_vr(vr).ok_or_else(|| unknown_vr(vr))?, value)
    }

    fn get_integer(&self, vr: u32) -> FmiResult<i32> {
        let var = Integer::from_vr(vr).ok_or_else(|| unknown_vr(vr))?;
        // Parameters is Copy: read through the one field mapping.
        Ok(*Self::integer_field(&mut self.params.clone(), var))
    }

    fn set_integer(&mut self, vr: u32, value: i32) -> FmiResult {
        *Self::integer_field(&mut self.params, Integer::from_vr(vr).ok_or_else(|| unknown_vr(vr))?) = value;
        Ok(())
    }

    fn get_boolean(&self, vr: u32) -> FmiResult<bool> {
        let var = Boolean::from_vr(vr).ok_or_else(|| unknown_vr(vr))?;
        Ok(*Self::boolean_field(&mut self.params.clone(), var))
    }

    fn set_boolean(&mut self, vr: u32, value: bool) -> FmiResult {
        *Self::boolean_field(&mut self.params, Boolean::from_vr(vr).ok_or_else(|| unknown_vr(vr))?) = value;
        Ok(())
    }

    fn initialize(&mut self) -> FmiResult {
        let p = &self.params;
        let strain = if p.start_at_equilibrium {
            physics::equilibrium_strain(&self.inputs).ok_or_else(|| {
                FmiError::error(format!(
                    "startAtEquilibrium: the inputs web_a.v = {} m/s, web_b.v = {} m/s, web_a.eps = {} have no steady state \
                     (1+eps_b) = (v_b/v_a)(1+eps_a) > 0: the speeds must have the same sign, or web_a.v = 0; \
                     or set startAtEquilibrium = false and eps_start",
                    self.inputs.speed_a, self.inputs.speed_b, self.inputs.strain_a
                ))
            })?
        } else {
            p.strain_start
        };
        self.sensor = SensorScale::new(p)
            .ok_or_else(|| FmiError::error(format!("toUnitV = {} or toUnitF = {} has no unit", p.speed_unit, p.force_unit)))?;
        self.unstretched = physics::unstretched_length(p.span_length, strain);
        Ok(())
    }

    fn do_step(&mut self, h: f64) -> FmiResult {
        let next = physics::exact_step(self.params.span_length, &self.inputs, self.unstretched, h);
        let x = next.value();
        if !(x.is_finite() && x > 0.0) {
            return Err(FmiError::discard(format!(
                "the unstretched length of web in the span would become {x} m (web_a.v = {}, web_b.v = {}): \
                 web fed in from both ends grows without bound; take a shorter step",
                self.inputs.speed_a, self.inputs.speed_b
            )));
        }
        self.unstretched = next;
        Ok(())
    }
}

impl Persist for ConvertingSpan {
    fn save(&self, out: &mut StateWriter) {
        let p = &self.params;
        out.f64(p.span_length);
        for web in [&p.incoming, &p.span_web] {
            for x in [web.modulus, web.thickness, web.width, web.density, web.retardation_time] {
                out.f64(x);
            }
        }
        for b in [p.include_damping, p.prevent_negative_tension, p.start_at_equilibrium, p.use_sensor] {
            out.bool(b);
        }
        out.f64(p.strain_start);
        out.i32(p.speed_unit);
        out.i32(p.force_unit);
        out.f64(self.inputs.speed_a);
        out.f64(self.inputs.strain_a);
        out.f64(self.inputs.speed_b);
        out.f64(self.unstretched.hi());
        out.f64(self.unstretched.lo());
    }

    fn load(r: &mut StateReader) -> Result<Self, String> {
        let span_length = r.finite("L")?;
        let mut web = |prefix: &str| -> Result<WebProperties, String> {
            Ok(WebProperties {
                modulus: r.finite(&format!("{prefix}.E"))?,
                thickness: r.finite(&format!("{prefix}.thickness"))?,
                width: r.finite(&format!("{prefix}.width"))?,
                density: r.finite(&format!("{prefix}.density"))?,
                retardation_time: r.finite(&format!("{prefix}.d_r"))?,
            })
        };
        let incoming = web("wp1")?;
        let span_web = web("wp2")?;
        let params = Parameters {
            span_length,
            incoming,
            span_web,
            include_damping: r.bool("includeDamping")?,
            prevent_negative_tension: r.bool("preventNegativeTension")?,
            start_at_equilibrium: r.bool("startAtEquilibrium")?,
            use_sensor: r.bool("useSensor")?,
            strain_start: r.finite("eps_start")?,
            speed_unit: r.i32("toUnitV")?,
            force_unit: r.i32("toUnitF")?,
        };
        let inputs = Inputs {
            speed_a: r.finite("web_a.v")?,
            strain_a: r.finite("web_a.eps")?,
            speed_b: r.finite("web_b.v")?,
        };
        let unstretched = CompensatedSum::from_parts(r.finite("unstretched length")?, r.finite("unstretched length carry")?);
        // The sensor scale is derived from the parameters; a state saved
        // before initialization ended has none yet and that is kept so.
        let sensor = SensorScale::new(&params).unwrap_or_default();
        Ok(ConvertingSpan { params, inputs, unstretched, sensor })
    }
}
