//! The two standards an instance can serve, each with its own functions, the
//! states each function is allowed in, and its own words for the phases: the
//! instance checks and reports in the words of the standard it was
//! instantiated through.

/// A standard's functions that take an instance, each written once with the phases it is
/// allowed in and the interface it serves (the standard's `Interface`): the enum `Call`, its
/// masks (`allowed`, `interface`), its C names (`$prefix` and the name) and the list of all.
macro_rules! calls {
    ($prefix:literal; $($call:ident = $allowed:expr, $interface:ident;)*) => {
        /// Every function of the standard that takes an instance.
        #[derive(Clone, Copy, Debug, PartialEq, Eq)]
        pub enum Call { $($call,)* }

        impl Call {
            /// All of them, in the standard's order.
            pub const ALL: &'static [Call] = &[$(Call::$call,)*];

            /// The phases in which the standard allows this call.
            #[inline(always)]
            const fn allowed(self) -> u8 {
                match self { $(Call::$call => $allowed,)* }
            }

            /// The interface the call belongs to.
            pub const fn interface(self) -> Interface {
                match self { $(Call::$call => Interface::$interface,)* }
            }

            /// The C name, for log messages.
            pub const fn c_name(self) -> &'static str {
                match self { $(Call::$call => concat!($prefix, stringify!($call)),)* }
            }
        }
    };
}

pub mod fmi2;
pub mod fmi3;
pub mod fmi3_types;

use crate::phase::Phase;

// The phases as bits of the masks the standards' lists give their calls (FMI 2.0's words;
// fmi3.rs names the two it words otherwise).
const INSTANTIATED: u8 = Phase::Instantiated.bit();
const INIT: u8 = Phase::InitializationMode.bit();
const COMPLETE: u8 = Phase::StepComplete.bit();
const FAILED: u8 = Phase::StepFailed.bit();
const TERMINATED: u8 = Phase::Terminated.bit();
const ERROR: u8 = Phase::Error.bit();
const EVENT: u8 = Phase::EventMode.bit();
const CONTINUOUS: u8 = Phase::ContinuousTimeMode.bit();
const ANY: u8 = INSTANTIATED | INIT | COMPLETE | FAILED | TERMINATED | ERROR | EVENT | CONTINUOUS;
/// Where values may be read: from initialization on, for diagnosis also after errors.
const READABLE: u8 = INIT | COMPLETE | FAILED | TERMINATED | ERROR | EVENT | CONTINUOUS;
/// Where a set may be called (each variable's own rule is checked by the instance).
const WRITABLE: u8 = INSTANTIATED | INIT | COMPLETE | EVENT | CONTINUOUS;
/// Where Model Exchange's computed values (derivatives, event indicators, states) may be read.
const COMPUTED: u8 = INIT | EVENT | CONTINUOUS | TERMINATED | ERROR;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Standard {
    Fmi2,
    Fmi3,
}

impl Standard {
    /// A phase as a message names it: `the state "step complete"` (FMI 2.0), `Step Mode` (FMI 3.0).
    pub fn state(self, phase: Phase) -> String {
        match self {
            Standard::Fmi2 => format!("the state \"{}\"", phase.name()),
            Standard::Fmi3 => fmi3_state_name(phase).to_string(),
        }
    }
}

/// FMI 3.0's name of a phase.
fn fmi3_state_name(phase: Phase) -> &'static str {
    match phase {
        Phase::Instantiated => "the state Instantiated",
        Phase::InitializationMode => "Initialization Mode",
        Phase::StepComplete => "Step Mode",
        Phase::StepFailed => "Step Mode after a discarded step",
        Phase::Terminated => "the state Terminated",
        Phase::Error => "the error state (after fmi3Error)",
        Phase::EventMode => "Event Mode",
        Phase::ContinuousTimeMode => "Continuous-Time Mode",
    }
}


/// A function of one standard that takes an instance.
pub trait Call: Copy + PartialEq + std::fmt::Debug + 'static {
    const STANDARD: Standard;

    /// The C name, for log messages.
    fn name(self) -> &'static str;

    /// The whole check of the state machine, as cheap as one mask test:
    /// one of this interface's functions, and allowed in this phase.
    fn is_allowed(self, phase: Phase, model_exchange: bool) -> bool;

    /// Why the call is refused in this phase, if it is.
    fn refusal(self, phase: Phase, model_exchange: bool) -> Option<String>;

    /// After a caught panic only these calls are accepted: the instance may
    /// be half updated (the reset rebuilds it and clears the poison).
    fn is_allowed_when_poisoned(self) -> bool;

    /// The call that rebuilds the instance from its start values.
    fn is_reset(self) -> bool;
}
