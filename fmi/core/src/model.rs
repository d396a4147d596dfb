//! What a model provides to the FMI layer. The layer owns the state machine,
//! the checks against the model description, logging and FMU states; a model
//! only stores values, computes outputs and advances in time.

use super::description::{Causality, ModelDescription, Start};
use super::persist::{StateReader, StateWriter};
use super::resources::Resources;
use super::status::{FmiError, FmiResult};

fn no_model_exchange() -> FmiError {
    FmiError::error("this model does not implement Model Exchange")
}

/// Which function of the FMU a partial derivative is of (FMI 2.0,
/// `fmi2GetDirectionalDerivative`): the knowns and unknowns differ by phase.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Jacobian {
    /// Initialization mode: the initial unknowns (the states among them) as
    /// functions of the inputs, through the initial state.
    Initialization,
    /// Model Exchange: outputs and state derivatives as functions of the
    /// continuous states and the inputs.
    ContinuousTime,
    /// Co-Simulation at a communication point: outputs (and state
    /// derivatives) as functions of the inputs, the state held.
    CommunicationPoint,
}

/// What the importer said in `fmi2Instantiate` and `fmi2SetupExperiment`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Experiment {
    /// The instance is a Model Exchange instance (the importer integrates).
    pub model_exchange: bool,
    pub tolerance: Option<f64>,
    pub start_time: f64,
    pub stop_time: Option<f64>,
}

/// Something that happened inside a communication step, `offset` seconds
/// after its start. Static text: reporting costs nothing unless logged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Event {
    pub offset: f64,
    pub what: &'static str,
}

/// What a Model Exchange event changed, and when the next one is due.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EventUpdate {
    pub next_event_time: Option<f64>,
    /// The continuous states jumped (the importer must read them again).
    pub states_changed: bool,
}

/// A type an Integer variable can be bound to: `i32`, or an enumeration
/// type the generator emits from the model description.
pub trait IntegerValue: Copy {
    fn from_i32(x: i32) -> Option<Self>;
    fn to_i32(self) -> i32;
}

impl IntegerValue for i32 {
    fn from_i32(x: i32) -> Option<Self> {
        Some(x)
    }
    fn to_i32(self) -> i32 {
        self
    }
}

/// Value access by value reference, and the variables' part of an FMU
/// state: written by [`crate::bind_variables!`] from one binding per variable.
/// The layer calls the setters only with value references of the right
/// type, with values already checked against the description (finite, in
/// range, a legal Boolean or enumeration value) and only where causality
/// and phase allow the set.
pub trait Variables {
    fn get_real(&self, vr: u32) -> FmiResult<f64>;
    fn set_real(&mut self, vr: u32, value: f64) -> FmiResult;
    fn get_integer(&self, vr: u32) -> FmiResult<i32>;
    fn set_integer(&mut self, vr: u32, value: i32) -> FmiResult;
    fn get_boolean(&self, vr: u32) -> FmiResult<bool>;
    fn set_boolean(&mut self, vr: u32, value: bool) -> FmiResult;
    fn get_string(&self, vr: u32) -> FmiResult<&str>;
    fn set_string(&mut self, vr: u32, value: &str) -> FmiResult;
    /// Every parameter and input, in the binding's order.
    fn save_variables(&self, out: &mut StateWriter);
    fn load_variables(&mut self, input: &mut StateReader) -> FmiResult;
}

pub trait Model: Variables + Clone + 'static {
    /// The model as an importer instantiates it, every parameter and input at
    /// its start value; `resources` is the FMU's `resources/` folder, where a
    /// model whose interface comes with the FMU (a line) finds it. A model
    /// whose interface is compiled in takes `Compiled::at_start_values`.
    fn instantiate(resources: &Resources) -> FmiResult<Self>;

    /// The table of this model's interface: generated from its
    /// `modelDescription.xml`, or built from what its FMU carries.
    fn description(&self) -> &ModelDescription;

    /// The model's own state in an FMU state (what is not a variable), after
    /// the variables; `load_state` runs after `load_variables`.
    fn save_state(&self, out: &mut StateWriter);
    fn load_state(&mut self, input: &mut StateReader) -> FmiResult;

    /// A Real input's or tunable parameter's value that its range allows but the model's other
    /// parameters do not (a force loop's set point <= 0 N without `loop.compression`), set after
    /// initialization: checked with the ranges, before any value of the call applies.
    #[inline(always)]
    fn check_real(&self, _vr: u32, _value: f64) -> FmiResult {
        Ok(())
    }

    /// First derivative of a continuous Real input over the next
    /// communication step (`fmi2SetRealInputDerivatives`, order 1). The layer
    /// has checked that `vr` is a Real input and the value finite.
    fn set_input_derivative(&mut self, vr: u32, value: f64) -> FmiResult;

    /// Checks what the description's ranges cannot say (relations between
    /// values) and computes the initial state from parameters and inputs;
    /// `resources` is the FMU's `resources/` folder, for models that read
    /// files. Called when initialization ends, and before outputs are read
    /// during initialization. Must not change anything when it fails. What
    /// it returns are warnings, logged once when initialization ends (a
    /// profile the FMU carries for other instances but none for this one).
    fn initialize(&mut self, experiment: &Experiment, resources: &Resources) -> FmiResult<Vec<String>>;

    /// Advances the model over a communication step of length `h` > 0, the
    /// inputs held at their current values. On failure the model must be
    /// left as it was before the step.
    fn do_step(&mut self, h: f64) -> FmiResult;

    /// The time now: the start of the next communication step, or the time
    /// a Model Exchange importer set. Models whose inputs come from profiles
    /// of time keep it; others ignore it.
    #[inline]
    fn set_time(&mut self, _time: f64) {}

    /// Model Exchange, in event mode: applies what is due at the time set
    /// (parameter changes, jumps) and names the next time event.
    fn event_update(&mut self) -> EventUpdate {
        EventUpdate::default()
    }

    /// What happened inside the last step, for the `logEvents` category.
    fn step_events(&self) -> &[Event] {
        &[]
    }

    // Model Exchange. Slices have the lengths the description declares
    // (`states`, `number_of_event_indicators`); the layer checks them.

    fn get_continuous_states(&self, _x: &mut [f64]) -> FmiResult {
        Err(no_model_exchange())
    }

    /// Must not change anything when it fails.
    fn set_continuous_states(&mut self, _x: &[f64]) -> FmiResult {
        Err(no_model_exchange())
    }

    fn get_derivatives(&self, _dx: &mut [f64]) -> FmiResult {
        Err(no_model_exchange())
    }

    fn get_nominals(&self, _nominals: &mut [f64]) -> FmiResult {
        Err(no_model_exchange())
    }

    fn get_event_indicators(&self, _z: &mut [f64]) -> FmiResult {
        Err(no_model_exchange())
    }

    /// d(unknown)/d(known) now, for `fmi2GetDirectionalDerivative` (when the
    /// description says `providesDirectionalDerivative`). The layer has
    /// checked that `unknown` is an unknown and `known` a known of `of`
    /// (FMI 2.0, 2.1.9), that the unknown depends on the known in
    /// ModelStructure, and that outputs are computable. Where the function
    /// has a kink the model picks one side and documents which.
    fn partial_derivative(&self, _unknown: u32, _known: u32, _of: Jacobian) -> FmiResult<f64> {
        Err(FmiError::error("this model does not provide directional derivatives"))
    }

    /// Whether the outputs can be computed from the model's parameters and
    /// state: asked after an error (the parameters may never have passed
    /// initialization; `inputs_valid` is asked too) and of a restored state
    /// that had passed it. A failure answers the get, or the restore, with
    /// fmi2Error.
    fn outputs_defined(&self) -> FmiResult {
        Ok(())
    }

    /// Whether the inputs set since the last step still describe something
    /// the outputs can be computed for: asked before every read of computed
    /// values, so keep it cheap.
    fn inputs_valid(&self) -> FmiResult {
        Ok(())
    }

    /// After the start values are set: a provisional state, so that outputs
    /// read before initialization (in the error state, for diagnosis) are
    /// defined. Initialization replaces it.
    fn provisional_state(&mut self) {}

}

/// A model whose interface is compiled in: the table generated from its
/// `modelDescription.xml` by the build script.
pub trait Compiled: Model + Default {
    fn compiled() -> &'static ModelDescription;

    /// The model with every parameter and input at its start value.
    fn at_start_values() -> Self {
        with_start_values(Self::default(), Self::compiled())
    }
}

/// `model` with every parameter and input set to its start value in
/// `description` (the model's own), then a provisional state (so outputs
/// read before initialization are defined).
pub fn with_start_values<M: Model>(mut model: M, description: &ModelDescription) -> M {
    for v in description.variables.iter() {
        if !matches!(v.causality, Causality::Parameter | Causality::Input) {
            continue;
        }
        // The start values are checked by the generator (or the model that
        // built the description) and a test covers that every one is
        // accepted, so a failure here cannot happen.
        let _ = match v.start {
            Start::Real(x) => model.set_real(v.vr, x),
            Start::Integer(x) => model.set_integer(v.vr, x),
            Start::Boolean(x) => model.set_boolean(v.vr, x),
            Start::String(x) => model.set_string(v.vr, x),
            Start::None => Ok(()),
        };
    }
    model.provisional_state();
    model
}

// What `bind_variables!` reports; cold, so that the binding's fast paths stay small.

#[doc(hidden)]
#[cold]
pub fn unknown_vr(vr: u32) -> FmiError {
    FmiError::error(format!("value reference {vr} is not a variable of this type"))
}

#[doc(hidden)]
#[cold]
pub fn not_settable(name: &str) -> FmiError {
    FmiError::error(format!("{name} cannot be set"))
}

/// An Integer value for a field of type `T` (an enumeration: one of its items).
#[doc(hidden)]
pub fn integer_value<T: IntegerValue>(name: &str, value: i32) -> FmiResult<T> {
    T::from_i32(value).ok_or_else(|| FmiError::error(format!("{name} = {value} is not a value of its enumeration")))
}
