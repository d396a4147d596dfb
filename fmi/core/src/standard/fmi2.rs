//! FMI 2.0's functions and, for each, the phases in which it may be called
//! (FMI 2.0 standard: 3.2.3 for Model Exchange, 4.2.4 for Co-Simulation).
//! One table serves both interfaces.

use crate::phase::Phase;
use crate::standard::Standard;

const INSTANTIATED: u8 = Phase::Instantiated.bit();
const INIT: u8 = Phase::InitializationMode.bit();
const COMPLETE: u8 = Phase::StepComplete.bit();
const FAILED: u8 = Phase::StepFailed.bit();
const TERMINATED: u8 = Phase::Terminated.bit();
const ERROR: u8 = Phase::Error.bit();
const EVENT: u8 = Phase::EventMode.bit();
const CONTINUOUS: u8 = Phase::ContinuousTimeMode.bit();
const ANY: u8 = INSTANTIATED | INIT | COMPLETE | FAILED | TERMINATED | ERROR | EVENT | CONTINUOUS;
/// Where values may be read: after initialization started, for diagnosis also after errors.
const READABLE: u8 = INIT | COMPLETE | FAILED | TERMINATED | ERROR | EVENT | CONTINUOUS;

/// Every fmi2 function that takes an instance.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Call {
    SetDebugLogging,
    FreeInstance,
    SetupExperiment,
    EnterInitializationMode,
    ExitInitializationMode,
    Terminate,
    Reset,
    GetReal,
    GetInteger,
    GetBoolean,
    GetString,
    SetReal,
    SetInteger,
    SetBoolean,
    SetString,
    GetFMUstate,
    SetFMUstate,
    FreeFMUstate,
    SerializedFMUstateSize,
    SerializeFMUstate,
    DeSerializeFMUstate,
    GetDirectionalDerivative,
    // Model Exchange
    EnterEventMode,
    NewDiscreteStates,
    EnterContinuousTimeMode,
    CompletedIntegratorStep,
    SetTime,
    SetContinuousStates,
    GetDerivatives,
    GetEventIndicators,
    GetContinuousStates,
    GetNominalsOfContinuousStates,
    // Co-Simulation
    SetRealInputDerivatives,
    GetRealOutputDerivatives,
    DoStep,
    CancelStep,
    GetStatus,
    GetRealStatus,
    GetIntegerStatus,
    GetBooleanStatus,
    GetStringStatus,
}

impl Call {
    /// The phases in which the standard allows this call.
    #[inline(always)]
    const fn allowed(self) -> u8 {
        use Call::*;
        match self {
            SetDebugLogging | FreeInstance | Reset => ANY,
            SetupExperiment | EnterInitializationMode => INSTANTIATED,
            ExitInitializationMode => INIT,
            Terminate => COMPLETE | FAILED | EVENT | CONTINUOUS,
            GetReal | GetInteger | GetBoolean | GetString => READABLE,
            SetReal | SetInteger | SetBoolean | SetString => INSTANTIATED | INIT | COMPLETE | EVENT | CONTINUOUS,
            GetFMUstate | SetFMUstate | FreeFMUstate | SerializedFMUstateSize | SerializeFMUstate
            | DeSerializeFMUstate => ANY,
            GetDirectionalDerivative => READABLE,
            EnterEventMode | SetTime => EVENT | CONTINUOUS,
            NewDiscreteStates | EnterContinuousTimeMode => EVENT,
            CompletedIntegratorStep | SetContinuousStates => CONTINUOUS,
            GetDerivatives | GetEventIndicators | GetContinuousStates => INIT | EVENT | CONTINUOUS | TERMINATED | ERROR,
            GetNominalsOfContinuousStates => INSTANTIATED | EVENT | CONTINUOUS | TERMINATED | ERROR,
            SetRealInputDerivatives => INSTANTIATED | INIT | COMPLETE,
            GetRealOutputDerivatives => COMPLETE | FAILED | TERMINATED | ERROR,
            DoStep => COMPLETE,
            // Steps are synchronous, so there is never a step in progress to
            // cancel; accepted where a step could be, to say "not supported".
            CancelStep => COMPLETE | FAILED,
            GetStatus | GetRealStatus | GetIntegerStatus | GetBooleanStatus | GetStringStatus => {
                COMPLETE | FAILED | TERMINATED
            }
        }
    }

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
        use Call::*;
        match self {
            EnterEventMode | NewDiscreteStates | EnterContinuousTimeMode | CompletedIntegratorStep | SetTime
            | SetContinuousStates | GetDerivatives | GetEventIndicators | GetContinuousStates
            | GetNominalsOfContinuousStates => Some(true),
            SetRealInputDerivatives | GetRealOutputDerivatives | DoStep | CancelStep | GetStatus | GetRealStatus
            | GetIntegerStatus | GetBooleanStatus | GetStringStatus => Some(false),
            _ => None,
        }
    }

    /// The C name, for log messages.
    pub const fn c_name(self) -> &'static str {
        use Call::*;
        match self {
            SetDebugLogging => "fmi2SetDebugLogging",
            FreeInstance => "fmi2FreeInstance",
            SetupExperiment => "fmi2SetupExperiment",
            EnterInitializationMode => "fmi2EnterInitializationMode",
            ExitInitializationMode => "fmi2ExitInitializationMode",
            Terminate => "fmi2Terminate",
            Reset => "fmi2Reset",
            GetReal => "fmi2GetReal",
            GetInteger => "fmi2GetInteger",
            GetBoolean => "fmi2GetBoolean",
            GetString => "fmi2GetString",
            SetReal => "fmi2SetReal",
            SetInteger => "fmi2SetInteger",
            SetBoolean => "fmi2SetBoolean",
            SetString => "fmi2SetString",
            GetFMUstate => "fmi2GetFMUstate",
            SetFMUstate => "fmi2SetFMUstate",
            FreeFMUstate => "fmi2FreeFMUstate",
            SerializedFMUstateSize => "fmi2SerializedFMUstateSize",
            SerializeFMUstate => "fmi2SerializeFMUstate",
            DeSerializeFMUstate => "fmi2DeSerializeFMUstate",
            GetDirectionalDerivative => "fmi2GetDirectionalDerivative",
            EnterEventMode => "fmi2EnterEventMode",
            NewDiscreteStates => "fmi2NewDiscreteStates",
            EnterContinuousTimeMode => "fmi2EnterContinuousTimeMode",
            CompletedIntegratorStep => "fmi2CompletedIntegratorStep",
            SetTime => "fmi2SetTime",
            SetContinuousStates => "fmi2SetContinuousStates",
            GetDerivatives => "fmi2GetDerivatives",
            GetEventIndicators => "fmi2GetEventIndicators",
            GetContinuousStates => "fmi2GetContinuousStates",
            GetNominalsOfContinuousStates => "fmi2GetNominalsOfContinuousStates",
            SetRealInputDerivatives => "fmi2SetRealInputDerivatives",
            GetRealOutputDerivatives => "fmi2GetRealOutputDerivatives",
            DoStep => "fmi2DoStep",
            CancelStep => "fmi2CancelStep",
            GetStatus => "fmi2GetStatus",
            GetRealStatus => "fmi2GetRealStatus",
            GetIntegerStatus => "fmi2GetIntegerStatus",
            GetBooleanStatus => "fmi2GetBooleanStatus",
            GetStringStatus => "fmi2GetStringStatus",
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
