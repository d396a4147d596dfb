//! FMI 2.0's functions and, for each, the phases in which it may be called
//! (FMI 2.0 standard: 3.2.3 for Model Exchange, 4.2.4 for Co-Simulation).
//! One table serves both interfaces.

use super::{ANY, COMPLETE, COMPUTED, CONTINUOUS, ERROR, EVENT, FAILED, INIT, INSTANTIATED, READABLE, TERMINATED, WRITABLE};
use crate::phase::Phase;
use crate::standard::Standard;

/// Where the status functions answer.
const STATUS: u8 = COMPLETE | FAILED | TERMINATED;

/// Which instances a function serves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interface {
    Both,
    ModelExchange,
    CoSimulation,
}

calls! {
    "fmi2";
    SetDebugLogging = ANY, Both;
    FreeInstance = ANY, Both;
    SetupExperiment = INSTANTIATED, Both;
    EnterInitializationMode = INSTANTIATED, Both;
    ExitInitializationMode = INIT, Both;
    Terminate = COMPLETE | FAILED | EVENT | CONTINUOUS, Both;
    Reset = ANY, Both;
    GetReal = READABLE, Both;
    GetInteger = READABLE, Both;
    GetBoolean = READABLE, Both;
    GetString = READABLE, Both;
    SetReal = WRITABLE, Both;
    SetInteger = WRITABLE, Both;
    SetBoolean = WRITABLE, Both;
    SetString = WRITABLE, Both;
    GetFMUstate = ANY, Both;
    SetFMUstate = ANY, Both;
    FreeFMUstate = ANY, Both;
    SerializedFMUstateSize = ANY, Both;
    SerializeFMUstate = ANY, Both;
    DeSerializeFMUstate = ANY, Both;
    GetDirectionalDerivative = READABLE, Both;
    // Model Exchange
    EnterEventMode = EVENT | CONTINUOUS, ModelExchange;
    NewDiscreteStates = EVENT, ModelExchange;
    EnterContinuousTimeMode = EVENT, ModelExchange;
    CompletedIntegratorStep = CONTINUOUS, ModelExchange;
    SetTime = EVENT | CONTINUOUS, ModelExchange;
    SetContinuousStates = CONTINUOUS, ModelExchange;
    GetDerivatives = COMPUTED, ModelExchange;
    GetEventIndicators = COMPUTED, ModelExchange;
    GetContinuousStates = COMPUTED, ModelExchange;
    GetNominalsOfContinuousStates = INSTANTIATED | EVENT | CONTINUOUS | TERMINATED | ERROR, ModelExchange;
    // Co-Simulation
    SetRealInputDerivatives = INSTANTIATED | INIT | COMPLETE, CoSimulation;
    GetRealOutputDerivatives = COMPLETE | FAILED | TERMINATED | ERROR, CoSimulation;
    DoStep = COMPLETE, CoSimulation;
    // Steps are synchronous, so there is never a step in progress to cancel;
    // accepted where a step could be, to say "not supported".
    CancelStep = COMPLETE | FAILED, CoSimulation;
    GetStatus = STATUS, CoSimulation;
    GetRealStatus = STATUS, CoSimulation;
    GetIntegerStatus = STATUS, CoSimulation;
    GetBooleanStatus = STATUS, CoSimulation;
    GetStringStatus = STATUS, CoSimulation;
}

impl Call {
    #[inline(always)]
    pub fn is_allowed_in(self, phase: Phase) -> bool {
        self.allowed() & phase.bit() != 0
    }

    /// Whether the call is one of this interface's functions and allowed in
    /// this phase: the whole check of the state machine in one mask.
    #[inline(always)]
    pub fn is_allowed(self, phase: Phase, model_exchange: bool) -> bool {
        let own = match self.model_exchange_only() {
            Some(me) => me == model_exchange,
            None => true,
        };
        own && self.is_allowed_in(phase)
    }

    /// `Some(true)` for functions of Model Exchange only, `Some(false)` for
    /// functions of Co-Simulation only, `None` for the common ones.
    #[inline(always)]
    pub const fn model_exchange_only(self) -> Option<bool> {
        match self.interface() {
            Interface::Both => None,
            Interface::ModelExchange => Some(true),
            Interface::CoSimulation => Some(false),
        }
    }
}

impl crate::standard::Call for Call {
    const STANDARD: Standard = Standard::Fmi2;

    #[inline]
    fn name(self) -> &'static str {
        self.c_name()
    }

    #[inline(always)]
    fn is_allowed(self, phase: Phase, model_exchange: bool) -> bool {
        Call::is_allowed(self, phase, model_exchange)
    }

    #[cold]
    fn refusal(self, phase: Phase, model_exchange: bool) -> Option<String> {
        if self.model_exchange_only().is_some_and(|me| me != model_exchange) {
            let (this, other) = if model_exchange { ("Model Exchange", "Co-Simulation") } else { ("Co-Simulation", "Model Exchange") };
            return Some(format!("{}: illegal call sequence: a {other} function, and this is a {this} instance", self.c_name()));
        }
        (!self.is_allowed_in(phase)).then(|| {
            format!("{}: illegal call sequence: not allowed in {}", self.c_name(), Standard::Fmi2.state(phase))
        })
    }

    fn is_allowed_when_poisoned(self) -> bool {
        matches!(self, Call::Reset | Call::FreeInstance)
    }

    fn is_reset(self) -> bool {
        self == Call::Reset
    }
}
