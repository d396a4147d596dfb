//! FMU states: what an instance saves, how it restores one, and the checks
//! a deserialized state must pass.

use super::*;

impl<M: Model> Instance<M> {
    pub fn snapshot(&self) -> Snapshot<M> {
        Snapshot { phase: self.phase, time: self.time, experiment: self.experiment, model: self.model.clone() }
    }

    /// Restores a saved state; one of the other interface (Model Exchange /
    /// Co-Simulation) is refused, since the phases do not carry over.
    pub fn restore(&mut self, call: CallName, snapshot: &Snapshot<M>) -> FmiResult {
        if snapshot.experiment.model_exchange != self.experiment.model_exchange {
            let kind = |me: bool| if me { "Model Exchange" } else { "Co-Simulation" };
            return Err(FmiError::error(format!(
                "{}: the state was saved by a {} instance; this is a {} instance",
                call,
                kind(snapshot.experiment.model_exchange),
                kind(self.experiment.model_exchange)
            )));
        }
        self.phase = snapshot.phase;
        self.time = snapshot.time;
        self.experiment = snapshot.experiment;
        self.model.clone_from(&snapshot.model);
        self.settled = false;
        self.log_event(&format!("FMU state restored at t = {}", self.time));
        Ok(())
    }

    /// Checks a deserialized state's values as `fmi2Set*` and initialization
    /// would have: Booleans and enumerations always, inputs against their
    /// ranges, parameters against theirs once initialization has ended.
    pub fn check_snapshot(snapshot: &Snapshot<M>) -> FmiResult {
        // A phase of the other interface is no state this instance could have saved.
        let me_phase = matches!(snapshot.phase, Phase::EventMode | Phase::ContinuousTimeMode);
        let cs_phase = matches!(snapshot.phase, Phase::StepComplete | Phase::StepFailed);
        if (me_phase && !snapshot.experiment.model_exchange) || (cs_phase && snapshot.experiment.model_exchange) {
            let kind = if snapshot.experiment.model_exchange { "a Model Exchange" } else { "a Co-Simulation" };
            return Err(FmiError::error(format!("the state's phase \"{}\" cannot belong to {kind} instance", snapshot.phase.name())));
        }
        let initialized = snapshot.phase.initialized();
        check_values(&snapshot.model, initialized)?;
        if initialized {
            snapshot.model.outputs_defined()?;
        }
        Ok(())
    }
}

/// The values of a restored `model` checked as `fmi2Set*` and
/// initialization would have: Booleans and enumerations always, inputs
/// against their ranges, parameters against theirs if `initialized`. Part of
/// `Instance::check_snapshot`; public for a model whose own state depends on
/// its parameters (the Line: its network), to check them first in its
/// `load_state` and so name the value rather than the structure it breaks.
pub fn check_values<M: Model>(model: &M, initialized: bool) -> FmiResult {
    for v in model.description().variables.iter() {
        let checked_range = v.causality == Causality::Input || (v.causality == Causality::Parameter && initialized);
        let wrong = match v.kind {
            Kind::Real if matches!(v.causality, Causality::Input | Causality::Parameter) => {
                let x = model.get_real(v.vr)?;
                (!x.is_finite() || (checked_range && !v.range.contains(x))).then(|| format!("{x}, allowed {}", v.range))
            }
            Kind::Integer if v.causality == Causality::Parameter => {
                let x = model.get_integer(v.vr)?;
                (checked_range && !v.range.contains(x as f64)).then(|| format!("{x}, allowed {}", v.range))
            }
            Kind::Enumeration { values, .. } => {
                let x = model.get_integer(v.vr)?;
                (!values.contains(&x)).then(|| format!("{x}, not a value of the enumeration"))
            }
            _ => None,
        };
        if let Some(why) = wrong {
            return Err(FmiError::error(format!("{} = {why}", v.name)));
        }
    }
    Ok(())
}
