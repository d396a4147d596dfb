//! One FMU instance: the state machine, the checks every get and set goes
//! through (value reference, type, causality, phase, value), time keeping
//! for a co-simulation step, and FMU states. Plain safe Rust over a generic
//! model; the C boundary (`fmi-abi`) calls it and turns its errors into
//! statuses and log lines. Every function that can fail takes the C name of
//! the call it serves (`call`), so that messages name what the importer
//! called, in FMI 2.0's or FMI 3.0's words.
//!
//! * this file — the instance, its lifecycle, `fmi2DoStep` and the status queries;
//! * `values` — getting and setting variables, with every check;
//! * `model_exchange` — the Model Exchange functions;
//! * `directional` — `fmi2GetDirectionalDerivative`: its knowns and unknowns;
//! * `states` — FMU states: save, restore, check a deserialized one.

mod directional;
mod model_exchange;
/// FMU states; `states::check_values` is public for a model that checks its values itself.
pub mod states;
mod values;

use super::description::{Causality, Family, Kind, ModelDescription, Slot, Variability, Variable};
use super::logging::{Log, LogFilter};
use super::model::{Experiment, Model};
use super::phase::Phase;
use super::standard::{Call, Standard};
use super::resources::Resources;
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
    pub states_changed: bool,
}

/// The C name of the function a call of the instance serves, for its messages.
pub type CallName = &'static str;

pub struct Instance<M: Model> {
    logger: Box<dyn Log>,
    /// The standard the importer instantiated through: its words for the phases.
    standard: Standard,
    log: LogFilter,
    phase: Phase,
    time: f64,
    experiment: Experiment,
    /// The FMU's resources/ folder, from fmi2Instantiate.
    resources: Resources,
    model: M,
    /// The model as instantiated: what a reset returns to, and what FMU states are read into.
    start: M,
    /// In initialization mode: the initial values are computed for the values set so far (a get
    /// computes them once, not once per call; anything that changes the model clears it).
    settled: bool,
    #[cfg(feature = "test-hooks")]
    panic_in_next_step: bool,
}

impl<M: Model> Instance<M> {
    pub fn new(logger: Box<dyn Log>, standard: Standard, logging_on: bool, model_exchange: bool, resources: Resources, model: M) -> Self {
        let log = LogFilter::new(model.description().log_categories, logging_on);
        let instance = Instance {
            logger,
            standard,
            log,
            phase: Phase::Instantiated,
            time: 0.0,
            experiment: Experiment { model_exchange, ..Experiment::default() },
            resources,
            start: model.clone(),
            model,
            settled: false,
            #[cfg(feature = "test-hooks")]
            panic_in_next_step: false,
        };
        instance.log_event("instantiated");
        instance
    }

    /// The interface of the model this instance serves.
    #[inline(always)]
    pub fn description(&self) -> &ModelDescription {
        self.model.description()
    }

    /// The model as instantiated (FMU states are read into a copy of it).
    pub fn start_model(&self) -> &M {
        &self.start
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
    /// interface, and is it allowed in the current phase? The common case
    /// is one mask test; the rest (tracing, the reason for a refusal) is cold.
    #[inline(always)]
    pub fn begin<C: Call>(&mut self, call: C) -> FmiResult {
        if call.is_allowed(self.phase, self.experiment.model_exchange) && !self.log.traces_calls() {
            return Ok(());
        }
        self.begin_traced_or_refused(call)
    }

    #[cold]
    #[inline(never)]
    fn begin_traced_or_refused<C: Call>(&mut self, call: C) -> FmiResult {
        if self.log.traces_calls() {
            self.log(Status::Ok, "logAll", call.name());
        }
        match call.refusal(self.phase, self.experiment.model_exchange) {
            Some(why) => Err(FmiError::error(why)),
            None => Ok(()),
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

    pub fn set_debug_logging(&mut self, call: CallName, on: bool, categories: &[String]) -> FmiResult {
        #[cfg(feature = "test-hooks")]
        if on && categories.len() == 1 && categories[0] == TEST_PANIC_CATEGORY {
            self.panic_in_next_step = true;
            return Ok(());
        }
        self.log.set(on, categories).map_err(|e| e.prefixed(call))
    }

    pub fn setup_experiment(&mut self, call: CallName, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> FmiResult {
        let name = call;
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
        self.settled = false;
        Ok(())
    }

    pub fn enter_initialization_mode(&mut self) -> FmiResult {
        self.phase = Phase::InitializationMode;
        self.settled = false;
        self.log_event("entered initialization mode");
        Ok(())
    }

    pub fn exit_initialization_mode(&mut self, call: CallName) -> FmiResult {
        let warnings = self.settle_initial_values().map_err(|e| e.prefixed(call))?;
        for warning in warnings {
            self.log(Status::Warning, Status::Warning.log_category(), &format!("{call}: {warning}"));
        }
        self.phase = if self.experiment.model_exchange { Phase::EventMode } else { Phase::StepComplete };
        self.log_event("initialization done");
        Ok(())
    }

    /// Checks every parameter against its allowed range, then lets the model
    /// compute its initial state; returns the model's warnings. Nothing
    /// changes when a check fails.
    fn settle_initial_values(&mut self) -> FmiResult<Vec<String>> {
        self.check_parameter_ranges()?;
        let mut model = self.model.clone();
        let warnings = model.initialize(&self.experiment, &self.resources)?;
        self.model = model;
        Ok(warnings)
    }

    /// Every parameter within its allowed range.
    fn check_parameter_ranges(&self) -> FmiResult {
        for v in self.model.description().variables.iter() {
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
        Ok(())
    }

    pub fn terminate(&mut self) -> FmiResult {
        self.phase = Phase::Terminated;
        self.log_event("terminated");
        Ok(())
    }

    pub fn reset(&mut self) -> FmiResult {
        self.model = self.start.clone();
        self.settled = false;
        self.phase = Phase::Instantiated;
        self.time = 0.0;
        self.experiment = Experiment { model_exchange: self.experiment.model_exchange, ..Experiment::default() };
        self.log_event("reset to the start values");
        Ok(())
    }

    #[inline(always)]
    pub fn do_step(&mut self, call: CallName, current: f64, h: f64) -> FmiResult {
        // The common case inline: a positive finite step from the instance's
        // time (within TIME_TOLERANCE) to a finite end; `check_step` says why not.
        let usual = h > 0.0 && h < f64::INFINITY && self.is_current_time(current) && (current + h).is_finite();
        if !usual {
            self.check_step(call, current, h)?;
        }
        self.model.set_time(current);
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
            Err(e) => Err(self.step_failed(e, call, current, h)),
        }
    }

    /// A step the model refused: a discard leaves the instance in "step
    /// failed"; the message says where.
    #[cold]
    #[inline(never)]
    fn step_failed(&mut self, e: FmiError, call: CallName, current: f64, h: f64) -> FmiError {
        if e.status == Status::Discard {
            self.phase = Phase::StepFailed;
        }
        e.prefixed(&format!("{call} at t = {current} with h = {h}"))
    }

    /// `current` is the instance's time up to `TIME_TOLERANCE` (false for NaN and infinities).
    #[inline]
    fn is_current_time(&self, current: f64) -> bool {
        // The time itself (the importer kept ours) is the common case; then within the tolerance.
        current == self.time
            || (current.is_finite() && (current - self.time).abs() <= TIME_TOLERANCE * current.abs().max(self.time.abs()).max(1.0))
    }

    /// Why `fmi2DoStep(current, h)` is refused, if it is.
    #[cold]
    fn check_step(&self, call: CallName, current: f64, h: f64) -> FmiResult {
        let name = call;
        if !(h.is_finite() && h > 0.0) {
            return Err(FmiError::error(format!("{name}: communicationStepSize = {h} must be finite and > 0")));
        }
        if !self.is_current_time(current) {
            return Err(FmiError::error(format!(
                "{name}: currentCommunicationPoint = {current} is not the current time {} of the instance",
                self.time
            )));
        }
        if !(current + h).is_finite() {
            return Err(FmiError::error(format!("{name}: the step's end time {current} + {h} overflows")));
        }
        Ok(())
    }

    /// The time reached: the end of the last step (FMI 3.0's `lastSuccessfulTime`, its `time`).
    #[inline]
    pub fn time(&self) -> f64 {
        self.time
    }

    pub fn real_status(&self, call: CallName, kind: i32) -> FmiResult<f64> {
        match kind {
            LAST_SUCCESSFUL_TIME => Ok(self.time),
            _ => Err(unavailable_status(call, kind)),
        }
    }

    pub fn boolean_status(&self, call: CallName, kind: i32) -> FmiResult<bool> {
        match kind {
            // The model never asks the importer to stop.
            TERMINATED => Ok(false),
            _ => Err(unavailable_status(call, kind)),
        }
    }
}

#[cold]
fn out_of_range(v: &Variable, value: f64) -> FmiError {
    let unit = if v.unit.is_empty() || v.unit == "1" { String::new() } else { format!(" {}", v.unit) };
    FmiError::error(format!("{} = {value}{unit} is outside its allowed range {}", v.name, v.range))
}


/// FMI 2.0: a status kind the FMU does not provide answers fmi2Discard.
pub fn unavailable_status(call: CallName, kind: i32) -> FmiError {
    let what = match kind {
        DO_STEP_STATUS | PENDING_STATUS => "steps are synchronous, so there is no pending step".to_string(),
        _ => format!("status kind {kind} is not provided by {call}"),
    };
    FmiError::discard(format!("{call}: {what}"))
}
