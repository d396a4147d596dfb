//! FMI 3.0's functions and the states each is allowed in (FMI 3.0 standard:
//! 3.2 for Model Exchange, 4.2 for Co-Simulation), over the phases FMI 2.0
//! has too: a co-simulation instance's Step Mode is its "step complete",
//! and since the FMU declares no event mode for co-simulation
//! (`hasEventMode` is false), a co-simulation instance never enters Event Mode.

use super::{ANY, COMPLETE, COMPUTED, CONTINUOUS, ERROR, EVENT, FAILED, INIT, INSTANTIATED, READABLE, TERMINATED, WRITABLE};
use crate::phase::Phase;
use crate::standard::Standard;

/// FMI 3.0's words for two of the phases: Step Mode, and Step Mode after a discarded step.
const STEP: u8 = COMPLETE;
const DISCARDED: u8 = FAILED;

/// Which instances a function serves.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interface {
    Both,
    ModelExchange,
    CoSimulation,
    /// Model Exchange, or co-simulation's Event Mode, which this FMU does not declare.
    ModelExchangeOrEventMode,
    /// Only co-simulation's Event Mode (`fmi3EnterStepMode`).
    CoSimulationEventMode,
}

calls! {
    "fmi3";
    SetDebugLogging = ANY, Both;
    FreeInstance = ANY, Both;
    EnterInitializationMode = INSTANTIATED, Both;
    ExitInitializationMode = INIT, Both;
    EnterEventMode = EVENT | CONTINUOUS, ModelExchangeOrEventMode;
    Terminate = STEP | DISCARDED | EVENT | CONTINUOUS, Both;
    Reset = ANY, Both;
    GetFloat32 = READABLE, Both;
    GetFloat64 = READABLE, Both;
    GetInt8 = READABLE, Both;
    GetUInt8 = READABLE, Both;
    GetInt16 = READABLE, Both;
    GetUInt16 = READABLE, Both;
    GetInt32 = READABLE, Both;
    GetUInt32 = READABLE, Both;
    GetInt64 = READABLE, Both;
    GetUInt64 = READABLE, Both;
    GetBoolean = READABLE, Both;
    GetString = READABLE, Both;
    GetBinary = READABLE, Both;
    GetClock = ANY, Both;
    SetFloat32 = WRITABLE, Both;
    SetFloat64 = WRITABLE, Both;
    SetInt8 = WRITABLE, Both;
    SetUInt8 = WRITABLE, Both;
    SetInt16 = WRITABLE, Both;
    SetUInt16 = WRITABLE, Both;
    SetInt32 = WRITABLE, Both;
    SetUInt32 = WRITABLE, Both;
    SetInt64 = WRITABLE, Both;
    SetUInt64 = WRITABLE, Both;
    SetBoolean = WRITABLE, Both;
    SetString = WRITABLE, Both;
    SetBinary = WRITABLE, Both;
    SetClock = ANY, Both;
    GetNumberOfVariableDependencies = ANY, Both;
    GetVariableDependencies = ANY, Both;
    GetFMUState = ANY, Both;
    SetFMUState = ANY, Both;
    FreeFMUState = ANY, Both;
    SerializedFMUStateSize = ANY, Both;
    SerializeFMUState = ANY, Both;
    DeserializeFMUState = ANY, Both;
    GetDirectionalDerivative = READABLE, Both;
    GetAdjointDerivative = READABLE, Both;
    EnterConfigurationMode = ANY, Both;
    ExitConfigurationMode = ANY, Both;
    GetIntervalDecimal = ANY, Both;
    GetIntervalFraction = ANY, Both;
    GetShiftDecimal = ANY, Both;
    GetShiftFraction = ANY, Both;
    SetIntervalDecimal = ANY, Both;
    SetIntervalFraction = ANY, Both;
    SetShiftDecimal = ANY, Both;
    SetShiftFraction = ANY, Both;
    EvaluateDiscreteStates = ANY, Both;
    UpdateDiscreteStates = EVENT, ModelExchangeOrEventMode;
    // Model Exchange
    EnterContinuousTimeMode = EVENT, ModelExchange;
    CompletedIntegratorStep = CONTINUOUS, ModelExchange;
    SetTime = EVENT | CONTINUOUS, ModelExchange;
    SetContinuousStates = CONTINUOUS, ModelExchange;
    GetContinuousStateDerivatives = COMPUTED, ModelExchange;
    GetEventIndicators = COMPUTED, ModelExchange;
    GetContinuousStates = COMPUTED, ModelExchange;
    GetNominalsOfContinuousStates = INSTANTIATED | EVENT | CONTINUOUS | TERMINATED | ERROR, ModelExchange;
    GetNumberOfEventIndicators = ANY, ModelExchange;
    GetNumberOfContinuousStates = ANY, ModelExchange;
    // Co-Simulation
    EnterStepMode = EVENT, CoSimulationEventMode;
    GetOutputDerivatives = STEP | DISCARDED | TERMINATED | ERROR, CoSimulation;
    DoStep = STEP, CoSimulation;
    // Scheduled Execution
    ActivateModelPartition = ANY, Both;
}

impl Call {
    /// Whether the call serves an instance of this interface (this FMU
    /// declares no event mode for co-simulation).
    #[inline]
    fn serves(self, model_exchange: bool) -> bool {
        match self.interface() {
            Interface::Both => true,
            Interface::ModelExchange | Interface::ModelExchangeOrEventMode => model_exchange,
            Interface::CoSimulation => !model_exchange,
            Interface::CoSimulationEventMode => false,
        }
    }
}

impl crate::standard::Call for Call {
    const STANDARD: Standard = Standard::Fmi3;

    #[inline]
    fn name(self) -> &'static str {
        self.c_name()
    }

    #[inline(always)]
    fn is_allowed(self, phase: Phase, model_exchange: bool) -> bool {
        self.serves(model_exchange) && self.allowed() & phase.bit() != 0
    }

    /// Why the call is refused now, if it is: the interface first, then the phase.
    #[cold]
    fn refusal(self, phase: Phase, model_exchange: bool) -> Option<String> {
        let this = if model_exchange { "Model Exchange" } else { "Co-Simulation" };
        const NO_EVENT_MODE: &str = "a function of co-simulation's Event Mode, which this FMU does not use \
             (hasEventMode is false: events are handled inside fmi3DoStep)";
        let wrong_interface = match (self.interface(), model_exchange) {
            (Interface::ModelExchange, false) => Some("a Model Exchange function"),
            (Interface::CoSimulation | Interface::CoSimulationEventMode, true) => Some("a Co-Simulation function"),
            (Interface::ModelExchangeOrEventMode | Interface::CoSimulationEventMode, false) => Some(NO_EVENT_MODE),
            _ => None,
        };
        if let Some(what) = wrong_interface {
            return Some(format!("{}: illegal call sequence: {what}, and this is a {this} instance", self.c_name()));
        }
        (self.allowed() & phase.bit() == 0)
            .then(|| format!("{}: illegal call sequence: not allowed in {}", self.c_name(), Standard::Fmi3.state(phase)))
    }

    fn is_allowed_when_poisoned(self) -> bool {
        matches!(self, Call::Reset | Call::FreeInstance)
    }

    fn is_reset(self) -> bool {
        self == Call::Reset
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::standard::Call as _;

    #[test]
    fn names_are_the_c_names() {
        assert_eq!(Call::GetFloat64.c_name(), "fmi3GetFloat64");
        assert_eq!(Call::DeserializeFMUState.c_name(), "fmi3DeserializeFMUState");
    }

    #[test]
    fn co_simulation_never_reaches_event_mode_functions() {
        for call in [Call::EnterEventMode, Call::UpdateDiscreteStates, Call::EnterStepMode, Call::SetTime] {
            for phase in Phase::ALL {
                assert!(call.refusal(phase, false).is_some(), "{call:?} in {phase:?}");
            }
        }
    }

    #[test]
    fn do_step_only_in_step_mode() {
        for phase in Phase::ALL {
            assert_eq!(Call::DoStep.refusal(phase, false).is_none(), phase == Phase::StepComplete);
            assert!(Call::DoStep.refusal(phase, true).is_some());
        }
    }
}
