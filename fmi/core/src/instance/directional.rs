//! Directional derivatives (`fmi2GetDirectionalDerivative`, `fmi3GetDirectionalDerivative`): which unknowns and knowns the standard
//! allows in each phase (FMI 2.0, 2.1.9), checked before anything is
//! computed; the sum over the model's partial derivatives, without allocation.

use super::*;
use crate::description::Dependency;
use crate::model::Jacobian;

impl<M: Model> Instance<M> {
    /// dv_unknown = (d unknowns / d knowns) * dv_known. Entries that
    /// ModelStructure declares structurally zero are not asked of the model.
    pub fn get_directional_derivative(
        &mut self,
        call: CallName,
        unknowns: &[u32],
        knowns: &[u32],
        seed: &[f64],
        out: &mut [f64],
    ) -> FmiResult {
        let d = self.model.description();
        let me = self.experiment.model_exchange;
        if !d.provides_directional_derivative[me as usize] {
            let interface = if me { "Model Exchange" } else { "Co-Simulation" };
            return Err(FmiError::error(format!(
                "{} is not supported: providesDirectionalDerivative is false for {interface}",
                call
            )));
        }
        let of = match self.phase {
            Phase::InitializationMode => Jacobian::Initialization,
            _ if me => Jacobian::ContinuousTime,
            _ => Jacobian::CommunicationPoint,
        };
        for &vr in unknowns {
            self.unknown_dependencies(call, vr, of)?;
        }
        for (j, (&vr, &s)) in knowns.iter().zip(seed).enumerate() {
            self.check_known(call, vr, of)?;
            if !s.is_finite() {
                return Err(FmiError::error(format!("{}: dvKnown[{j}] = {s} must be finite", call)));
            }
        }
        self.prepare_get(call)?;
        self.check_computable(call)?;
        for (slot, &unknown) in out.iter_mut().zip(unknowns) {
            let on = self.unknown_dependencies(call, unknown, of)?.on.as_deref();
            let mut sum = 0.0;
            for (&known, &s) in knowns.iter().zip(seed) {
                if s == 0.0 || on.is_some_and(|on| !on.contains(&known)) {
                    continue;
                }
                sum += s * self.model.partial_derivative(unknown, known, of).map_err(|e| e.prefixed(call))?;
            }
            *slot = sum;
        }
        Ok(())
    }

    /// The ModelStructure entry of an unknown of `of`: an initial unknown
    /// during initialization, otherwise an output or a state derivative.
    fn unknown_dependencies(&self, call: CallName, vr: u32, of: Jacobian) -> FmiResult<&Dependency> {
        let d = self.model.description();
        let found = match of {
            Jacobian::Initialization => d.initial_dependencies.iter().find(|u| u.vr == vr),
            _ => d.output_dependencies.iter().chain(d.derivatives.iter()).find(|u| u.vr == vr),
        };
        match (found, d.variable(vr)) {
            (Some(u), Some(v)) if v.family == Family::Real => Ok(u),
            (_, v) => Err(not_an_unknown(call, vr, v, of)),
        }
    }

    /// Knowns: the inputs, and in Model Exchange after initialization also the continuous states.
    fn check_known(&self, call: CallName, vr: u32, of: Jacobian) -> FmiResult {
        let d = self.model.description();
        let v = d.variable(vr);
        let ok = v.is_some_and(|v| {
            v.family == Family::Real
                && (v.causality == Causality::Input || (of == Jacobian::ContinuousTime && d.states.contains(&vr)))
        });
        if ok {
            Ok(())
        } else {
            Err(not_a_known(call, vr, v, of))
        }
    }
}

fn phase_name(of: Jacobian) -> &'static str {
    match of {
        Jacobian::Initialization => "initialization mode",
        Jacobian::ContinuousTime => "Model Exchange after initialization",
        Jacobian::CommunicationPoint => "Co-Simulation after initialization",
    }
}

fn named(vr: u32, v: Option<&Variable>) -> String {
    match v {
        Some(v) => format!("{} (value reference {vr})", v.name),
        None => format!("value reference {vr} (no variable)"),
    }
}

#[cold]
fn not_an_unknown(call: CallName, vr: u32, v: Option<&Variable>, of: Jacobian) -> FmiError {
    let allowed = match of {
        Jacobian::Initialization => "the Real variables of ModelStructure/InitialUnknowns",
        _ => "the Real variables of ModelStructure/Outputs and ModelStructure/Derivatives",
    };
    FmiError::error(format!(
        "{}: vUnknown_ref: {} is not an unknown in {}; allowed: {allowed}",
        call,
        named(vr, v),
        phase_name(of)
    ))
}

#[cold]
fn not_a_known(call: CallName, vr: u32, v: Option<&Variable>, of: Jacobian) -> FmiError {
    let allowed = match of {
        Jacobian::ContinuousTime => "the Real inputs and the continuous states",
        _ => "the Real inputs",
    };
    FmiError::error(format!(
        "{}: vKnown_ref: {} is not a known in {}; allowed: {allowed}",
        call,
        named(vr, v),
        phase_name(of)
    ))
}
