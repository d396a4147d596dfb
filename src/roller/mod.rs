//! A roller of a web line, the companion of the converting span: a rotating
//! inertia driven by the tensions of the spans on either side and a motor
//! torque. It reuses the whole FMI layer (`crate::fmi2`) through the same
//! `Model` and `Persist` traits as the span.
//!
//! * `physics` — the equation and its exact step;
//! * `description` — the interface generated from fmu/roller/modelDescription.xml;
//! * this file — the mapping of variables to fields, and the FMI model hooks.

pub mod description;
pub mod physics;

use crate::fmi2::{Experiment, FmiError, FmiResult, Model, Persist, StateReader, StateWriter};
use crate::solver::CompensatedSum;
use description::{Real, DESCRIPTION};
use physics::{Inputs, Parameters};

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Roller {
    pub params: Parameters,
    pub inputs: Inputs,
    /// The state: angular speed omega, rad/s, carried as a compensated sum so
    /// that a million tiny steps do not drift.
    omega: CompensatedSum,
}

impl Roller {
    pub fn omega(&self) -> f64 {
        self.omega.value()
    }

    /// The value of a Real variable.
    pub fn real(&self, var: Real) -> f64 {
        let p = &self.params;
        let u = &self.inputs;
        match var {
            Real::J => p.inertia,
            Real::R => p.radius,
            Real::b => p.damping,
            Real::omega_start => p.omega_start,
            Real::F_up => u.force_up,
            Real::F_down => u.force_down,
            Real::tau_m => u.torque,
            Real::v => physics::surface_speed(p, self.omega.value()),
            Real::omega => self.omega.value(),
        }
    }

    /// The field behind a parameter or input; `None` for outputs.
    fn real_field(&mut self, var: Real) -> Option<&mut f64> {
        let p = &mut self.params;
        let u = &mut self.inputs;
        Some(match var {
            Real::J => &mut p.inertia,
            Real::R => &mut p.radius,
            Real::b => &mut p.damping,
            Real::omega_start => &mut p.omega_start,
            Real::F_up => &mut u.force_up,
            Real::F_down => &mut u.force_down,
            Real::tau_m => &mut u.torque,
            Real::v | Real::omega => return None,
        })
    }
}

#[cold]
fn unknown_vr(vr: u32) -> FmiError {
    FmiError::error(format!("value reference {vr} is not a variable of this type"))
}

impl Model for Roller {
    fn description() -> &'static crate::fmi2::description::ModelDescription {
        &DESCRIPTION
    }

    fn get_real(&self, vr: u32) -> FmiResult<f64> {
        Real::from_vr(vr).map(|var| self.real(var)).ok_or_else(|| unknown_vr(vr))
    }

    fn set_real(&mut self, vr: u32, value: f64) -> FmiResult {
        let var = Real::from_vr(vr).ok_or_else(|| unknown_vr(vr))?;
        let field = self.real_field(var).ok_or_else(|| FmiError::error(format!("{} cannot be set", var.name())))?;
        *field = value;
        Ok(())
    }

    // The roller has no Integer or Boolean variables; the layer refuses
    // such value references before it calls these.
    fn get_integer(&self, vr: u32) -> FmiResult<i32> {
        Err(unknown_vr(vr))
    }

    fn set_integer(&mut self, vr: u32, _value: i32) -> FmiResult {
        Err(unknown_vr(vr))
    }

    fn get_boolean(&self, vr: u32) -> FmiResult<bool> {
        Err(unknown_vr(vr))
    }

    fn set_boolean(&mut self, vr: u32, _value: bool) -> FmiResult {
        Err(unknown_vr(vr))
    }

    /// `canInterpolateInputs="false"`: the layer refuses input derivatives
    /// before they reach the model.
    fn set_input_derivative(&mut self, vr: u32, _value: f64) -> FmiResult {
        Err(FmiError::error(format!(
            "value reference {vr}: the roller holds its inputs over a step (canInterpolateInputs = false)"
        )))
    }

    fn initialize(&mut self, _experiment: &Experiment) -> FmiResult {
        self.omega = CompensatedSum::from_parts(self.params.omega_start, 0.0);
        Ok(())
    }

    fn do_step(&mut self, h: f64) -> FmiResult {
        let next = physics::exact_step(&self.params, &self.inputs, self.omega, h);
        let omega = next.value();
        if !(omega.is_finite() && physics::surface_speed(&self.params, omega).is_finite()) {
            return Err(FmiError::discard(format!(
                "the angular speed would become {omega} rad/s (J = {} kg.m2, R*(F_down - F_up) + tau_m = {} N.m): \
                 take a shorter step or check the inputs",
                self.params.inertia,
                self.params.radius * (self.inputs.force_down - self.inputs.force_up) + self.inputs.torque
            )));
        }
        self.omega = next;
        Ok(())
    }
}

impl Persist for Roller {
    fn save(&self, out: &mut StateWriter) {
        let p = &self.params;
        let u = &self.inputs;
        for x in [p.inertia, p.radius, p.damping, p.omega_start, u.force_up, u.force_down, u.torque] {
            out.f64(x);
        }
        out.f64(self.omega.hi());
        out.f64(self.omega.lo());
    }

    fn load(r: &mut StateReader) -> Result<Self, String> {
        let params = Parameters {
            inertia: r.finite("J")?,
            radius: r.finite("R")?,
            damping: r.finite("b")?,
            omega_start: r.finite("omega_start")?,
        };
        let inputs = Inputs { force_up: r.finite("F_up")?, force_down: r.finite("F_down")?, torque: r.finite("tau_m")? };
        let omega = CompensatedSum::from_parts(r.finite("omega")?, r.finite("omega carry")?);
        Ok(Roller { params, inputs, omega })
    }
}
