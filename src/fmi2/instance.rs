//! One FMU instance: the state machine, the checks every get and set goes
//! through (value reference, type, causality, phase, value), time keeping
//! for `fmi2DoStep`, and FMU states. Plain safe Rust over a generic model;
//! the FFI module calls it and turns its errors into statuses and log lines.

use super::description::{Causality, Initial, Kind, ModelDescription, Variability, Variable};
use super::ffi::Logger;
use super::logging::LogFilter;
use super::model::{Experiment, Model};
use super::phase::{Call, Phase};
use super::snapshot::Snapshot;
use super::status::{FmiError, FmiResult, Status};

/// `fmi2StatusKind` values (FMI 2.0 headers).
pub const DO_STEP_STATUS: i32 = 0;
pub const PENDING_STATUS: i32 = 1;
pub const LAST_SUCCESSFUL_TIME: i32 = 2;
pub const TERMINATED: i32 = 3;

/// Test-only (feature `test-hooks`): `fmi2SetDebugLogging(c, fmi2True, 1,
/// {TEST_PANIC_CATEGORY})` arms the instance so that its next `fmi2DoStep`
/// panics inside the step, after the model has advanced and before the time
/// has: the half-done update that poisoning guards against.
#[cfg(feature = "test-hooks")]
pub const TEST_PANIC_CATEGORY: &str = "testHook.panicInNextDoStep";

/// Relative tolerance when the communication point is compared with the
/// instance's time: importers compute time in their own ways (t + h, or
/// t0 + n*h), which may differ by a few ulps, never by 1e-13 of the time.
const TIME_TOLERANCE: f64 = 1e-13;

/// What `fmi2NewDiscreteStates` reports.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DiscreteUpdate {
    pub new_discrete_states_needed: bool,
    pub terminate_simulation: bool,
    pub next_event_time: Option<f64>,
}

/// The type family of a get/set function.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Family {
    Real,
    Integer,
    Boolean,
    String,
}

impl Family {
    fn of(kind: Kind) -> Family {
        match kind {
            Kind::Real => Family::Real,
            Kind::Integer | Kind::Enumeration { .. } => Family::Integer,
            Kind::Boolean => Family::Boolean,
            Kind::String => Family::String,
        }
    }
    fn name(self) -> &'static str {
        match self {
            Family::Real => "Real",
            Family::Integer => "Integer",
            Family::Boolean => "Boolean",
            Family::String => "String",
        }
    }
}

pub struct Instance<M: Model> {
    logger: Logger,
    log: LogFilter,
    phase: Phase,
    time: f64,
    experiment: Experiment,
    /// Kept for models that ship resources; this one needs none.
    #[allow(dead_code)]
    resource_location: Option<String>,
    model: M,
    #[cfg(feature = "test-hooks")]
    panic_in_next_step: bool,
}

impl<M: Model> Instance<M> {
    pub fn new(logger: Logger, logging_on: bool, resource_location: Option<String>, model_exchange: bool) -> Self {
        let instance = Instance {
            logger,
            log: LogFilter::new(Self::description().log_categories, logging_on),
            phase: Phase::Instantiated,
            time: 0.0,
            experiment: Experiment { model_exchange, ..Experiment::default() },
            resource_location,
            model: M::at_start_values(),
            #[cfg(feature = "test-hooks")]
            panic_in_next_step: false,
        };
        instance.log_event("instantiated");
        instance
    }

    fn description() -> &'static ModelDescription {
        M::description()
    }

    pub fn phase(&self) -> Phase {
        self.phase
    }

    pub fn log(&self, status: Status, category: &str, message: &str) {
        if self.log.allows(category) {
            self.logger.log(status, category, message);
        }
    }

    fn log_event(&self, message: &str) {
        self.log(Status::Ok, "logEvents", message);
    }

    /// Entry check of every call: does it belong to this instance's
    /// interface, and is it allowed in the current phase?
    pub fn begin(&mut self, call: Call) -> FmiResult {
        if self.log.traces_calls() {
            self.log(Status::Ok, "logAll", call.name());
        }
        let model_exchange = self.experiment.model_exchange;
        if call.model_exchange_only().is_some_and(|me| me != model_exchange) {
            let (this, other) = if model_exchange { ("Model Exchange", "Co-Simulation") } else { ("Co-Simulation", "Model Exchange") };
            return Err(FmiError::error(format!(
                "{}: illegal call sequence: a {other} function, and this is a {this} instance",
                call.name()
            )));
        }
        if call.is_allowed_in(self.phase) {
            Ok(())
        } else {
            Err(FmiError::error(format!(
                "{}: illegal call sequence: not allowed in the state \"{}\"",
                call.name(),
                self.phase.name()
            )))
        }
    }

    /// Reports a failed call; an `Error` puts the instance into the error
    /// state, from which `fmi2Reset` or `fmi2SetFMUstate` bring it back.
    pub fn fail(&mut self, error: FmiError) -> Status {
        self.log(error.status, error.status.log_category(), &error.message);
        if error.status >= Status::Error {
            self.phase = Phase::Error;
        }
        error.status
    }

    pub fn set_debug_logging(&mut self, on: bool, categories: &[String]) -> FmiResult {
        #[cfg(feature = "test-hooks")]
        if on && categories.len() == 1 && categories[0] == TEST_PANIC_CATEGORY {
            self.panic_in_next_step = true;
            return Ok(());
        }
        self.log.set(on, categories).map_err(|m| FmiError::error(format!("fmi2SetDebugLogging: {m}")))
    }

    pub fn setup_experiment(&mut self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> FmiResult {
        let name = "fmi2SetupExperiment";
        if !start.is_finite() {
            return Err(FmiError::error(format!("{name}: startTime = {start} must be finite")));
        }
        if let Some(stop) = stop {
            if !(stop.is_finite() && stop >= start) {
                return Err(FmiError::error(format!("{name}: stopTime = {stop} must be finite and >= startTime = {start}")));
            }
        }
        if let Some(tol) = tolerance {
            if !(tol.is_finite() && tol > 0.0) {
                return Err(FmiError::error(format!("{name}: tolerance = {tol} must be finite and > 0")));
            }
        }
        self.experiment = Experiment { tolerance, start_time: start, stop_time: stop, ..self.experiment };
        self.time = start;
        Ok(())
    }

    pub fn enter_initialization_mode(&mut self) -> FmiResult {
        self.phase = Phase::InitializationMode;
        self.log_event("entered initialization mode");
        Ok(())
    }

    pub fn exit_initialization_mode(&mut self) -> FmiResult {
        self.settle_initial_values().map_err(|e| prefixed(Call::ExitInitializationMode, e))?;
        self.phase = if self.experiment.model_exchange { Phase::EventMode } else { Phase::StepComplete };
        self.log_event("initialization done");
        Ok(())
    }

    /// Checks every parameter against its allowed range, then lets the model
    /// compute its initial state. Nothing changes when a check fails.
    fn settle_initial_values(&mut self) -> FmiResult {
        for v in Self::description().variables {
            if v.causality != Causality::Parameter || v.range.is_unbounded() {
                continue;
            }
            let value = match v.kind {
                Kind::Real => self.model.get_real(v.vr)?,
                Kind::Integer => self.model.get_integer(v.vr)? as f64,
                _ => continue,
            };
            if !v.range.contains(value) {
                return Err(out_of_range(v, value));
            }
        }
        let mut model = self.model.clone();
        model.initialize(&self.experiment)?;
        self.model = model;
        Ok(())
    }

    pub fn terminate(&mut self) -> FmiResult {
        self.phase = Phase::Terminated;
        self.log_event("terminated");
        Ok(())
    }

    pub fn reset(&mut self) -> FmiResult {
        self.model = M::at_start_values();
        self.phase = Phase::Instantiated;
        self.time = 0.0;
        self.experiment = Experiment { model_exchange: self.experiment.model_exchange, ..Experiment::default() };
        self.log_event("reset to the start values");
        Ok(())
    }

    /// Looks up a value reference and checks that it is of the family the
    /// function handles.
    #[inline]
    fn variable(&self, call: Call, vr: u32, family: Family) -> FmiResult<&'static Variable> {
        match Self::description().variable(vr) {
            Some(v) if Family::of(v.kind) == family => Ok(v),
            found => Err(wrong_variable(call, vr, found, family)),
        }
    }

    /// In initialization mode the outputs follow the parameters and inputs
    /// set so far, so they are computed before they are read.
    fn prepare_get(&mut self, call: Call) -> FmiResult {
        if self.phase == Phase::InitializationMode {
            self.settle_initial_values().map_err(|e| prefixed(call, e))?;
        }
        Ok(())
    }

    /// Diagnosis after an error: parameters and inputs are always there, but
    /// computed values only where the model can compute them (the parameters
    /// may never have passed initialization).
    fn check_computable(&self, call: Call, computed: bool) -> FmiResult {
        if computed && self.phase == Phase::Error {
            self.model.outputs_defined().map_err(|e| prefixed(call, e))?;
        }
        Ok(())
    }

    pub fn get_reals(&mut self, vrs: &[u32], values: &mut [f64]) -> FmiResult {
        self.prepare_get(Call::GetReal)?;
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            let v = self.variable(Call::GetReal, *vr, Family::Real)?;
            self.check_computable(Call::GetReal, !matches!(v.causality, Causality::Parameter | Causality::Input))?;
            *value = self.model.get_real(*vr)?;
        }
        Ok(())
    }

    pub fn get_integers(&mut self, vrs: &[u32], values: &mut [i32]) -> FmiResult {
        self.prepare_get(Call::GetInteger)?;
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            self.variable(Call::GetInteger, *vr, Family::Integer)?;
            *value = self.model.get_integer(*vr)?;
        }
        Ok(())
    }

    pub fn get_booleans(&mut self, vrs: &[u32], values: &mut [i32]) -> FmiResult {
        self.prepare_get(Call::GetBoolean)?;
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            self.variable(Call::GetBoolean, *vr, Family::Boolean)?;
            *value = self.model.get_boolean(*vr)? as i32;
        }
        Ok(())
    }

    /// The model has no String variables, so only an empty request succeeds.
    pub fn check_strings(&self, call: Call, vrs: &[u32]) -> FmiResult {
        vrs.iter().try_for_each(|&vr| self.variable(call, vr, Family::String).map(|_| ()))
    }

    /// May `v` be set now? FMI 2.0, section 2.2.7 (the table of when a
    /// variable may be set) for co-simulation.
    #[inline]
    fn check_settable(&self, call: Call, v: &Variable) -> FmiResult {
        let ok = match v.causality {
            Causality::Input => true,
            Causality::Parameter => match self.phase {
                Phase::Instantiated => matches!(v.initial, Initial::Exact | Initial::Approx),
                Phase::InitializationMode => v.initial == Initial::Exact,
                _ => v.variability == Variability::Tunable,
            },
            _ => false,
        } && v.variability != Variability::Constant;
        if ok {
            Ok(())
        } else {
            Err(not_settable(call, v, self.phase))
        }
    }

    /// Validates every value before it applies any, so a rejected call
    /// changes nothing.
    #[inline]
    fn set_all<T: Copy>(
        &mut self,
        call: Call,
        family: Family,
        vrs: &[u32],
        values: &[T],
        check: impl Fn(&Variable, T) -> FmiResult,
        apply: impl Fn(&mut M, u32, T) -> FmiResult,
    ) -> FmiResult {
        for (&vr, &value) in vrs.iter().zip(values) {
            let v = self.variable(call, vr, family)?;
            self.check_settable(call, v)?;
            check(v, value).map_err(|e| prefixed(call, e))?;
        }
        for (&vr, &value) in vrs.iter().zip(values) {
            apply(&mut self.model, vr, value)?;
        }
        Ok(())
    }

    pub fn set_reals(&mut self, vrs: &[u32], values: &[f64]) -> FmiResult {
        self.set_all(
            Call::SetReal,
            Family::Real,
            vrs,
            values,
            |v, x| {
                // Parameters are range-checked when initialization ends (they
                // may pass through odd values while a user sets them one by
                // one); inputs take effect at once, so they are checked now.
                let checked = !x.is_finite() || v.causality == Causality::Input;
                if checked && !(x.is_finite() && v.range.contains(x)) {
                    Err(out_of_range(v, x))
                } else {
                    Ok(())
                }
            },
            |m, vr, x| m.set_real(vr, x),
        )
    }

    pub fn set_integers(&mut self, vrs: &[u32], values: &[i32]) -> FmiResult {
        self.set_all(
            Call::SetInteger,
            Family::Integer,
            vrs,
            values,
            |v, x| match v.kind {
                Kind::Enumeration { type_name, values } if !values.contains(&x) => Err(FmiError::error(format!(
                    "{} = {x} is not a value of the enumeration {type_name} (allowed {}..{})",
                    v.name,
                    values.iter().min().unwrap_or(&0),
                    values.iter().max().unwrap_or(&0)
                ))),
                _ => Ok(()),
            },
            |m, vr, x| m.set_integer(vr, x),
        )
    }

    pub fn set_booleans(&mut self, vrs: &[u32], values: &[i32]) -> FmiResult {
        self.set_all(
            Call::SetBoolean,
            Family::Boolean,
            vrs,
            values,
            |v, x| {
                if x == 0 || x == 1 {
                    Ok(())
                } else {
                    Err(FmiError::error(format!("{} = {x} is not a Boolean (allowed 0 = false, 1 = true)", v.name)))
                }
            },
            |m, vr, x| m.set_boolean(vr, x != 0),
        )
    }

    /// `fmi2SetRealInputDerivatives`: first derivatives of Real inputs.
    pub fn set_input_derivatives(&mut self, vrs: &[u32], orders: &[i32], values: &[f64]) -> FmiResult {
        let call = Call::SetRealInputDerivatives;
        if !Self::description().can_interpolate_inputs {
            return Err(FmiError::error(format!("{}: canInterpolateInputs is false", call.name())));
        }
        for ((&vr, &order), &value) in vrs.iter().zip(orders).zip(values) {
            let v = self.variable(call, vr, Family::Real)?;
            if v.causality != Causality::Input {
                return Err(FmiError::error(format!("{}: {} is not an input", call.name(), v.name)));
            }
            if order != 1 {
                return Err(FmiError::error(format!(
                    "{}: order {order} for {}: only first derivatives (order 1) are supported",
                    call.name(),
                    v.name
                )));
            }
            if !value.is_finite() {
                return Err(FmiError::error(format!("{}: derivative of {} = {value} must be finite", call.name(), v.name)));
            }
        }
        let mut model = self.model.clone();
        for (&vr, &value) in vrs.iter().zip(values) {
            model.set_input_derivative(vr, value).map_err(|e| FmiError::error(format!("{}: {}", call.name(), e.message)))?;
        }
        self.model = model;
        Ok(())
    }

    pub fn do_step(&mut self, current: f64, h: f64) -> FmiResult {
        let name = Call::DoStep.name();
        if !(h.is_finite() && h > 0.0) {
            return Err(FmiError::error(format!("{name}: communicationStepSize = {h} must be finite and > 0")));
        }
        let tolerance = TIME_TOLERANCE * current.abs().max(self.time.abs()).max(1.0);
        if !current.is_finite() || (current - self.time).abs() > tolerance {
            return Err(FmiError::error(format!(
                "{name}: currentCommunicationPoint = {current} is not the current time {} of the instance",
                self.time
            )));
        }
        if !(current + h).is_finite() {
            return Err(FmiError::error(format!("{name}: the step's end time {current} + {h} overflows")));
        }
        match self.model.do_step(h) {
            Ok(()) => {
                #[cfg(feature = "test-hooks")]
                if std::mem::take(&mut self.panic_in_next_step) {
                    panic!("test hook: forced panic inside the model's step (state advanced, time not)");
                }
                // Take the importer's time so that rounding never accumulates.
                self.time = current + h;
                let events = self.model.step_events();
                if !events.is_empty() && self.log.allows("logEvents") {
                    for e in events {
                        self.log(Status::Ok, "logEvents", &format!("t = {}: {}", current + e.offset, e.what));
                    }
                }
                Ok(())
            }
            Err(e) => {
                if e.status == Status::Discard {
                    self.phase = Phase::StepFailed;
                }
                Err(FmiError { status: e.status, message: format!("{name} at t = {current} with h = {h}: {}", e.message) })
            }
        }
    }

    // ---- Model Exchange

    pub fn set_time(&mut self, time: f64) -> FmiResult {
        if !time.is_finite() {
            return Err(FmiError::error(format!("{}: time = {time} must be finite", Call::SetTime.name())));
        }
        self.time = time;
        Ok(())
    }

    fn check_count(call: Call, what: &str, given: usize, declared: usize) -> FmiResult {
        if given == declared {
            Ok(())
        } else {
            Err(FmiError::error(format!("{}: {given} {what} given, the model has {declared}", call.name())))
        }
    }

    pub fn set_continuous_states(&mut self, x: &[f64]) -> FmiResult {
        let call = Call::SetContinuousStates;
        Self::check_count(call, "states", x.len(), Self::description().states.len())?;
        if let Some(bad) = x.iter().find(|v| !v.is_finite()) {
            return Err(FmiError::error(format!("{}: a state value is {bad}", call.name())));
        }
        self.model.set_continuous_states(x).map_err(|e| prefixed(call, e))
    }

    pub fn get_continuous_states(&mut self, x: &mut [f64]) -> FmiResult {
        let call = Call::GetContinuousStates;
        Self::check_count(call, "states", x.len(), Self::description().states.len())?;
        self.prepare_get(call)?;
        self.check_computable(call, true)?;
        self.model.get_continuous_states(x).map_err(|e| prefixed(call, e))
    }

    pub fn get_derivatives(&mut self, dx: &mut [f64]) -> FmiResult {
        let call = Call::GetDerivatives;
        Self::check_count(call, "derivatives", dx.len(), Self::description().states.len())?;
        self.prepare_get(call)?;
        self.check_computable(call, true)?;
        self.model.get_derivatives(dx).map_err(|e| prefixed(call, e))
    }

    pub fn get_event_indicators(&mut self, z: &mut [f64]) -> FmiResult {
        let call = Call::GetEventIndicators;
        Self::check_count(call, "event indicators", z.len(), Self::description().number_of_event_indicators)?;
        self.prepare_get(call)?;
        self.check_computable(call, true)?;
        self.model.get_event_indicators(z).map_err(|e| prefixed(call, e))
    }

    pub fn get_nominals(&mut self, nominals: &mut [f64]) -> FmiResult {
        let call = Call::GetNominalsOfContinuousStates;
        Self::check_count(call, "nominals", nominals.len(), Self::description().states.len())?;
        self.model.get_nominals(nominals).map_err(|e| prefixed(call, e))
    }

    pub fn enter_event_mode(&mut self) -> FmiResult {
        self.phase = Phase::EventMode;
        Ok(())
    }

    /// The model has no discrete states and no time events; the slack
    /// event indicator only marks a kink in the tension.
    pub fn new_discrete_states(&mut self) -> DiscreteUpdate {
        DiscreteUpdate::default()
    }

    pub fn enter_continuous_time_mode(&mut self) -> FmiResult {
        self.phase = Phase::ContinuousTimeMode;
        Ok(())
    }

    pub fn real_status(&self, kind: i32) -> FmiResult<f64> {
        match kind {
            LAST_SUCCESSFUL_TIME => Ok(self.time),
            _ => Err(unavailable_status(Call::GetRealStatus, kind)),
        }
    }

    pub fn boolean_status(&self, kind: i32) -> FmiResult<bool> {
        match kind {
            // The model never asks the importer to stop.
            TERMINATED => Ok(false),
            _ => Err(unavailable_status(Call::GetBooleanStatus, kind)),
        }
    }

    pub fn snapshot(&self) -> Snapshot<M> {
        Snapshot { phase: self.phase, time: self.time, experiment: self.experiment, model: self.model.clone() }
    }

    /// Restores a saved state; one of the other interface (Model Exchange /
    /// Co-Simulation) is refused, since the phases do not carry over.
    pub fn restore(&mut self, call: Call, snapshot: &Snapshot<M>) -> FmiResult {
        if snapshot.experiment.model_exchange != self.experiment.model_exchange {
            let kind = |me: bool| if me { "Model Exchange" } else { "Co-Simulation" };
            return Err(FmiError::error(format!(
                "{}: the state was saved by a {} instance; this is a {} instance",
                call.name(),
                kind(snapshot.experiment.model_exchange),
                kind(self.experiment.model_exchange)
            )));
        }
        self.phase = snapshot.phase;
        self.time = snapshot.time;
        self.experiment = snapshot.experiment;
        self.model.clone_from(&snapshot.model);
        self.log_event(&format!("FMU state restored at t = {}", self.time));
        Ok(())
    }

    /// Checks a deserialized state's values as `fmi2Set*` and initialization
    /// would have: Booleans and enumerations always, inputs against their
    /// ranges, parameters against theirs once initialization has ended.
    pub fn check_snapshot(snapshot: &Snapshot<M>) -> Result<(), String> {
        // Phases reached only through a finished initialization; the error
        // state may have been entered before it.
        let initialized = matches!(
            snapshot.phase,
            Phase::StepComplete | Phase::StepFailed | Phase::Terminated | Phase::EventMode | Phase::ContinuousTimeMode
        );
        for v in Self::description().variables {
            let checked_range = v.causality == Causality::Input || (v.causality == Causality::Parameter && initialized);
            let wrong = match v.kind {
                Kind::Real if matches!(v.causality, Causality::Input | Causality::Parameter) => {
                    let x = snapshot.model.get_real(v.vr).map_err(|e| e.message)?;
                    (!x.is_finite() || (checked_range && !v.range.contains(x))).then(|| format!("{x}, allowed {}", v.range))
                }
                Kind::Integer if v.causality == Causality::Parameter => {
                    let x = snapshot.model.get_integer(v.vr).map_err(|e| e.message)?;
                    (checked_range && !v.range.contains(x as f64)).then(|| format!("{x}, allowed {}", v.range))
                }
                Kind::Enumeration { values, .. } => {
                    let x = snapshot.model.get_integer(v.vr).map_err(|e| e.message)?;
                    (!values.contains(&x)).then(|| format!("{x}, not a value of the enumeration"))
                }
                _ => None,
            };
            if let Some(why) = wrong {
                return Err(format!("{} = {why}", v.name));
            }
        }
        Ok(())
    }
}

#[cold]
fn wrong_variable(call: Call, vr: u32, found: Option<&Variable>, family: Family) -> FmiError {
    FmiError::error(match found {
        None => format!("{}: unknown value reference {vr}", call.name()),
        Some(v) => format!(
            "{}: {} (value reference {vr}) is of type {}, not {}",
            call.name(),
            v.name,
            Family::of(v.kind).name(),
            family.name()
        ),
    })
}

#[cold]
fn not_settable(call: Call, v: &Variable, phase: Phase) -> FmiError {
    let why = match v.causality {
        Causality::Parameter => format!(
            "it is a {} parameter and cannot be set in the state \"{}\" (only before initialization ends)",
            if v.variability == Variability::Fixed { "fixed" } else { "tunable" },
            phase.name()
        ),
        other => format!("its causality is {other:?}; only parameters and inputs can be set"),
    };
    FmiError::error(format!("{}: cannot set {}: {why}", call.name(), v.name))
}

#[cold]
fn out_of_range(v: &Variable, value: f64) -> FmiError {
    let unit = if v.unit.is_empty() || v.unit == "1" { String::new() } else { format!(" {}", v.unit) };
    FmiError::error(format!("{} = {value}{unit} is outside its allowed range {}", v.name, v.range))
}

#[cold]
fn prefixed(call: Call, e: FmiError) -> FmiError {
    FmiError { status: e.status, message: format!("{}: {}", call.name(), e.message) }
}

/// FMI 2.0: a status kind the FMU does not provide answers fmi2Discard.
pub fn unavailable_status(call: Call, kind: i32) -> FmiError {
    let what = match kind {
        DO_STEP_STATUS | PENDING_STATUS => "steps are synchronous, so there is no pending step".to_string(),
        _ => format!("status kind {kind} is not provided by {}", call.name()),
    };
    FmiError::discard(format!("{}: {what}", call.name()))
}
