//! Roller: an FMI 2.0 FMU of a roller of a web line, the companion of the
//! converting span: a rotating inertia driven by the tensions of the spans
//! on either side and a motor torque. It is built like the span: the FMI
//! layer (crate `fmi2`) does the C API, this crate only the model.
//!
//! * `physics` — the equation and its exact step;
//! * `description` — the interface generated from modelDescription.xml;
//! * this file — the variables bound to their fields, and the FMI model hooks.

#![deny(unsafe_code)]

pub mod description;
pub mod physics;

use description::{Boolean, Integer, Real, Text, DESCRIPTION};
use fmi2::{Experiment, FmiError, FmiResult, Model, StateReader, StateWriter};
use physics::{Inputs, Parameters};
use solver::CompensatedSum;

fmi2::export_fmi2!(crate::Roller);

fmi2::bind_variables! {
    model: Roller,
    inputs: Inputs,
    real {
        J: param(params.inertia),
        R: param(params.radius),
        b: param(params.damping),
        omega_start: param(params.omega_start),
        F_up: input(force_up),
        F_down: input(force_down),
        tau_m: input(torque),
        v: computed(surface_speed()),
        omega: computed(omega()),
    }
    integer {}
    boolean {}
    string {}
}

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

    /// v [R2].
    pub fn surface_speed(&self) -> f64 {
        physics::surface_speed(&self.params, self.omega.value())
    }
}

impl Model for Roller {
    fn description() -> &'static fmi2::description::ModelDescription {
        &DESCRIPTION
    }

    /// omega, as a compensated sum.
    fn save_state(&self, out: &mut StateWriter) {
        out.f64(self.omega.hi());
        out.f64(self.omega.lo());
    }

    fn load_state(&mut self, r: &mut StateReader) -> FmiResult {
        self.omega = CompensatedSum::from_parts(r.finite("omega")?, r.finite("omega carry")?);
        Ok(())
    }

    /// `canInterpolateInputs="false"`: the layer refuses input derivatives
    /// before they reach the model.
    fn set_input_derivative(&mut self, vr: u32, _value: f64) -> FmiResult {
        Err(FmiError::error(format!(
            "value reference {vr}: the roller holds its inputs over a step (canInterpolateInputs = false)"
        )))
    }

    fn initialize(&mut self, _experiment: &Experiment, _resources: &fmi2::Resources) -> FmiResult {
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
