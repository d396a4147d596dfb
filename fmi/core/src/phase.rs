//! The phases an instance goes through, common to FMI 2.0 and FMI 3.0 (a
//! co-simulation instance never enters event or continuous-time mode, a
//! model-exchange instance never a step phase); each standard's functions
//! and the phases they are allowed in are in `standard`.

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    Instantiated = 0,
    InitializationMode = 1,
    StepComplete = 2,
    StepFailed = 3,
    Terminated = 4,
    Error = 5,
    /// Model Exchange: discrete-time changes may happen.
    EventMode = 6,
    /// Model Exchange: the importer integrates the continuous states.
    ContinuousTimeMode = 7,
}

impl Phase {
    pub const ALL: [Phase; 8] = [
        Phase::Instantiated,
        Phase::InitializationMode,
        Phase::StepComplete,
        Phase::StepFailed,
        Phase::Terminated,
        Phase::Error,
        Phase::EventMode,
        Phase::ContinuousTimeMode,
    ];

    pub const fn bit(self) -> u8 {
        1 << self as u8
    }

    /// Phases reached only through a finished initialization (the error state may have been
    /// entered before it, so it is not one).
    pub const fn initialized(self) -> bool {
        matches!(self, Phase::StepComplete | Phase::StepFailed | Phase::Terminated | Phase::EventMode | Phase::ContinuousTimeMode)
    }

    pub fn from_u8(x: u8) -> Option<Phase> {
        Phase::ALL.get(x as usize).copied()
    }

    pub fn name(self) -> &'static str {
        match self {
            Phase::Instantiated => "instantiated",
            Phase::InitializationMode => "initialization mode",
            Phase::StepComplete => "step complete",
            Phase::StepFailed => "step failed",
            Phase::Terminated => "terminated",
            Phase::Error => "error",
            Phase::EventMode => "event mode",
            Phase::ContinuousTimeMode => "continuous-time mode",
        }
    }
}
