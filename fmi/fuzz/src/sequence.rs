//! What one sequence holds, below the operations that make its calls (lib.rs), the Model
//! Exchange driver (model_exchange.rs) and the scenes (scene.rs): the model a fuzz target hands
//! the harness, the bytes a sequence is read from, the oracle's states and rules (where a call is
//! allowed, what may be set, how far values let it predict), the instances of a sequence and what
//! the oracle knows of each, and its outcome.

use crate::api::{Api, Instance};
use crate::newton::Newton;
use fmi_core::description::{Causality, Initial, Kind, ModelDescription, Variability, Variable};
use fmi_testkit::*;

pub(crate) type Desc = &'static ModelDescription;

/// The model a fuzz target drives: what the harness needs to know of it. A target binary
/// links exactly one model (each exports the same C names) and hands it to `run` or
/// `driver::main` (the span's in fuzz/, the Roller's in models/roller/fuzz, the Line's in
/// models/line/fuzz).
#[derive(Clone, Debug)]
pub struct Fuzzed {
    pub description: Desc,
    /// Its resources/ folder, what its FMU ships: a path ending in '/'.
    pub resources: String,
    /// It cannot be instantiated without its resources (the Line's interface is in them).
    pub needs_resources: bool,
    /// A contact whose stick/slide mode the harness follows (None: the model has none).
    pub contact: Option<Contact>,
    /// Values that make the contact work, taken by some of the driven instances.
    pub scene: Option<Scene>,
}

impl Fuzzed {
    /// The model `M` (its description and whether it needs resources) with the resources folder.
    pub fn of<M: Tested>(resources: &str) -> Fuzzed {
        Fuzzed {
            description: M::description(),
            resources: resources.to_string(),
            needs_resources: M::needs_resources(),
            contact: None,
            scene: None,
        }
    }
}

/// A contact's mode, read from one of the model's outputs after every step: the harness counts
/// the transitions between sticking and sliding in consecutive reads.
#[derive(Clone, Copy, Debug)]
pub struct Contact {
    /// The output the mode is read from.
    pub output: &'static str,
    /// Whether a value of it means sliding.
    pub sliding: fn(f64) -> bool,
}

/// Values for a driven instance to take: parameters set before initialization, and inputs that
/// start at a value and are set again, as the instance runs, to values drawn in a range (in
/// Co-Simulation before a step, in Model Exchange in event mode and continuous-time mode).
/// They must be valid: an instance that takes them is still expected to initialize and step.
#[derive(Clone, Debug)]
pub struct Scene {
    pub parameters: Vec<(&'static str, Value)>,
    /// (input, start value, lowest, highest)
    pub inputs: Vec<(&'static str, f64, f64, f64)>,
}

/// A parameter's value in a scene.
#[derive(Clone, Copy, Debug)]
pub enum Value {
    Real(f64),
    Boolean(bool),
}

/// A name of the fuzzed model's interface, as a value reference (a fuzz target's own mistake
/// stops the run).
pub(crate) fn named(d: Desc, name: &str) -> &'static Variable {
    d.variables
        .iter()
        .find(|v| v.name == name)
        .unwrap_or_else(|| panic!("the fuzz target names {name:?}, which the model does not have"))
}


// ---------------------------------------------------------------- input

/// The bytes of one sequence, read front to back; zeros once they run out.
pub struct Source<'a> {
    bytes: &'a [u8],
}

impl<'a> Source<'a> {
    pub fn new(bytes: &'a [u8]) -> Self {
        Source { bytes }
    }
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
    pub fn u8(&mut self) -> u8 {
        match self.bytes.split_first() {
            Some((&b, rest)) => {
                self.bytes = rest;
                b
            }
            None => 0,
        }
    }
    pub fn u32(&mut self) -> u32 {
        u32::from_le_bytes([self.u8(), self.u8(), self.u8(), self.u8()])
    }
    pub fn u64(&mut self) -> u64 {
        (self.u32() as u64) << 32 | self.u32() as u64
    }
    /// One of `n` choices.
    pub fn pick(&mut self, n: usize) -> usize {
        self.u8() as usize % n
    }
    /// True with probability about k/256.
    pub fn chance(&mut self, k: u8) -> bool {
        self.u8() < k
    }
}


// ---------------------------------------------------------------- oracle

/// The states of FMI 2.0 that this FMU can be in: co-simulation's, and model exchange's two.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum St {
    Instantiated,
    Init,
    StepComplete,
    StepFailed,
    Terminated,
    Error,
    /// Model Exchange only.
    Event,
    Continuous,
}

impl St {
    /// The serialized phase byte (documented order of fmi/core/src/snapshot.rs).
    pub(crate) fn from_byte(b: u8) -> Option<St> {
        [
            St::Instantiated,
            St::Init,
            St::StepComplete,
            St::StepFailed,
            St::Terminated,
            St::Error,
            St::Event,
            St::Continuous,
        ]
        .get(b as usize)
        .copied()
    }
}

/// Where the standard allows each call (FMI 2.0 co-simulation state table;
/// stepInProgress and stepCanceled never occur: steps are synchronous).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Fn {
    SetDebugLogging,
    SetupExperiment,
    EnterInit,
    ExitInit,
    Terminate,
    Reset,
    Get,
    Set,
    StateOp,
    GetDirectionalDerivative,
    /// Calls whose expected status each op decides alone (every state is the same to them).
    Other,
    // Model Exchange's functions (FMI 2.0, 3.2.3; FMI 3.0's alike).
    EnterEventMode,
    NewDiscreteStates,
    EnterContinuousTimeMode,
    CompletedIntegratorStep,
    SetTime,
    SetContinuousStates,
    /// Derivatives, event indicators, continuous states.
    GetComputed,
    GetNominals,
    SetRealInputDerivatives,
    GetRealOutputDerivatives,
    DoStep,
    CancelStep,
    GetStatus,
}

/// Where the standard allows each call of an instance of Co-Simulation (FMI 2.0, 4.2.4) or of
/// Model Exchange (`me`: FMI 2.0, 3.2.3; FMI 3.0's tables are the same for these calls).
pub(crate) fn allowed(f: Fn, s: St, me: bool) -> bool {
    use St::*;
    let cs = !me;
    match f {
        Fn::SetDebugLogging | Fn::Reset | Fn::StateOp | Fn::Other => true,
        Fn::SetupExperiment | Fn::EnterInit => s == Instantiated,
        Fn::ExitInit => s == Init,
        Fn::Terminate if me => matches!(s, Event | Continuous),
        Fn::Terminate => matches!(s, StepComplete | StepFailed),
        Fn::Get | Fn::GetDirectionalDerivative => s != Instantiated,
        Fn::Set if me => matches!(s, Instantiated | Init | Event | Continuous),
        Fn::Set => matches!(s, Instantiated | Init | StepComplete),
        Fn::SetRealInputDerivatives => cs && matches!(s, Instantiated | Init | StepComplete),
        Fn::GetRealOutputDerivatives => cs && matches!(s, StepComplete | StepFailed | Terminated | Error),
        Fn::DoStep => cs && s == StepComplete,
        Fn::CancelStep => false,
        Fn::GetStatus => cs && matches!(s, StepComplete | StepFailed | Terminated),
        Fn::EnterEventMode | Fn::SetTime => me && matches!(s, Event | Continuous),
        Fn::NewDiscreteStates | Fn::EnterContinuousTimeMode => me && s == Event,
        Fn::CompletedIntegratorStep | Fn::SetContinuousStates => me && s == Continuous,
        Fn::GetComputed => me && matches!(s, Init | Event | Continuous | Terminated | Error),
        Fn::GetNominals => me && matches!(s, Instantiated | Event | Continuous | Terminated | Error),
    }
}

/// Whether an instance of this interface can be in state `s` at all: only bytes forged by the
/// harness put it in one of the other interface's (its expected statuses are then loose).
pub(crate) fn own_state(s: St, me: bool) -> bool {
    match s {
        St::StepComplete | St::StepFailed => !me,
        St::Event | St::Continuous => me,
        _ => true,
    }
}

/// May `v` be set in state `s`? FMI 2.0, section 2.2.7 (co-simulation) and 3.2.3 (model
/// exchange: inputs and tunable parameters in event mode, continuous inputs alone in
/// continuous-time mode).
pub(crate) fn settable(v: &Variable, s: St) -> bool {
    if v.variability == Variability::Constant {
        return false;
    }
    if s == St::Continuous {
        return v.causality == Causality::Input && v.variability == Variability::Continuous;
    }
    match v.causality {
        Causality::Input => true,
        Causality::Parameter => match s {
            St::Instantiated => matches!(v.initial, Initial::Exact | Initial::Approx),
            St::Init => v.initial == Initial::Exact,
            _ => v.variability == Variability::Tunable,
        },
        _ => false,
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Family {
    Real,
    Integer,
    Boolean,
    String,
}

pub(crate) fn family(v: &Variable) -> Family {
    match v.kind {
        Kind::Real => Family::Real,
        Kind::Integer | Kind::Enumeration { .. } => Family::Integer,
        Kind::Boolean => Family::Boolean,
        Kind::String => Family::String,
    }
}

pub(crate) fn var(d: Desc, vr: u32, f: Family) -> Option<&'static Variable> {
    d.variable(vr).filter(|v| family(v) == f)
}

/// What the oracle knows of an FMU state it holds.
#[derive(Clone, Debug)]
pub(crate) struct StateInfo {
    pub(crate) ptr: usize,
    pub(crate) st: St,
    pub(crate) time: f64,
    /// Values of the instance when it was saved, as far as the oracle knows.
    pub(crate) values: Values,
    pub(crate) initialized: bool,
    /// Saved by a Model Exchange instance.
    pub(crate) me: bool,
    /// Its continuous states, where a Model Exchange instance had them (event and
    /// continuous-time mode): a restored state must give them back.
    pub(crate) x: Option<Vec<f64>>,
}

/// How far the oracle can predict model-dependent outcomes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Values {
    /// Start values and a plain experiment: initialization and moderate
    /// steps must succeed.
    Pristine,
    /// Changed, all with moderate magnitudes.
    Moderate,
    /// Some value of magnitude above 1e13 or below 1e-12 was accepted.
    Extreme,
    /// Restored from bytes forged by the harness (checksum recomputed).
    Forged,
}

impl Values {
    pub(crate) fn worsen(self, to: Values) -> Values {
        let rank = |v: Values| v as u8;
        if rank(to) > rank(self) {
            to
        } else {
            self
        }
    }
}

pub(crate) fn magnitude(x: f64) -> Values {
    let a = x.abs();
    // Physical values of this kind of model lie well inside: E up to 1e12
    // Pa, thicknesses down to 1e-9 m, speeds below 1e3 m/s.
    if a == 0.0 || (1e-12..=1e13).contains(&a) {
        Values::Moderate
    } else {
        Values::Extreme
    }
}

/// One instance slot of a sequence.
pub(crate) struct Slot {
    pub(crate) c: Instance,
    pub(crate) log: Box<Log>,
    /// FMI 2.0's callbacks (FMI 3.0 passes the logger itself).
    pub(crate) _functions: Option<Box<fmi2CallbackFunctions>>,
    /// Instantiated without a logger (FMI 3.0): no log lines to check.
    pub(crate) silent: bool,
    pub(crate) name: String,
    pub(crate) st: St,
    pub(crate) time: f64,
    pub(crate) values: Values,
    /// Initialization ended since the instance was created or reset.
    pub(crate) initialized: bool,
    /// A Model Exchange instance (FMI 2.0's state machine of section 3.2.3).
    pub(crate) me: bool,
    /// It took the model's scene (`Fuzzed::scene`).
    pub(crate) scene: bool,
    /// The contact's mode at the last read (None: not read since the instance started,
    /// was reset or restored).
    pub(crate) sliding: Option<bool>,
    /// What the Model Exchange driver knows between its moves.
    pub(crate) integration: Integration,
    pub(crate) poisoned: bool,
    pub(crate) armed: bool,
    /// Which of logStatusWarning/Discard/Error and logAll are on.
    pub(crate) status_log: [bool; 3],
    pub(crate) log_all: bool,
    pub(crate) states: Vec<StateInfo>,
}

/// A serialized state the harness got from the FMU.
#[derive(Clone)]
pub(crate) struct Blob {
    pub(crate) bytes: Vec<u8>,
    pub(crate) info: StateInfo,
}

/// A broken rule: what was called, what came back, what was expected.
#[derive(Debug, Clone)]
pub struct Violation(pub String);

/// A non-finite output of a known kind (see the module documentation).
#[derive(Debug, Clone, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Finding {
    OverflowAfterExtremeValues,
    ForgedState,
    /// fmi2GetReal in the error state of an instance whose initialization
    /// never ended returns outputs computed from the unset state (inf).
    OutputsOfUninitializedInstance,
    /// A state the FMU serialized itself is refused by fmi2DeSerializeFMUstate
    /// when it was saved while a parameter held an out-of-range value (legal
    /// until initialization ends): its own bytes do not round-trip.
    OwnStateRefusedOnDeserialize,
}

/// What one sequence did.
#[derive(Default, Debug, Clone)]
pub struct Outcome {
    pub calls: u64,
    /// Calls per answered status (OK, Warning, Discard, Error).
    pub statuses: [u64; 4],
    pub steps_ok: u64,
    pub panics_caught: u64,
    pub deserialized_ok: u64,
    pub findings: Vec<(Finding, String)>,
    /// Calls made on an instance, per state it was in (St order).
    pub by_state: [u64; 8],
    /// The random calls (`call_on`) made on an instance, and those of them on one in the error state.
    pub random: [u64; 2],
    /// Stick<->slide transitions between consecutive reads of the contact's mode
    /// (`Fuzzed::contact`): in Co-Simulation, in Model Exchange.
    pub transitions: [u64; 2],
    /// A Model Exchange instance finished an event iteration, and an integrator step.
    pub me_event: bool,
    pub me_step: bool,
    /// Events the Model Exchange driver handled after initialization: time events, state
    /// events (an event indicator changed sign), step events (fmi2CompletedIntegratorStep asked).
    pub events: [u64; 3],
}

pub(crate) struct Run {
    pub(crate) model: Fuzzed,
    pub(crate) api: Api,
    pub(crate) slots: [Option<Slot>; 2],
    /// Pointers of FMU states that were freed (for double frees).
    pub(crate) dead_states: Vec<usize>,
    pub(crate) blobs: Vec<Blob>,
    /// Readable memory that is no instance (a foreign component).
    pub(crate) foreign: Box<[u64; 8]>,
    pub(crate) out: Outcome,
    /// Description of the call under way, for messages.
    pub(crate) what: String,
    /// FUZZ_TRACE set: print every call (for replaying one sequence).
    pub(crate) trace: bool,
    /// The messages the FMU logged in the last call checked by `after`.
    pub(crate) last_log: Vec<String>,
    /// A driven sequence: mostly legal moves (`op_lifecycle_macro`), random calls between,
    /// until `moves` are made (then as the others).
    pub(crate) driven: bool,
    pub(crate) moves: u32,
    /// Integrator steps the Model Exchange driver has left in this sequence.
    pub(crate) me_steps: u32,
    /// Co-Simulation steps of a scene's instance left in this sequence (a sliding contact
    /// costs its model many steps): then the instance is terminated, and reset without it.
    pub(crate) scene_steps: u32,
}


pub(crate) fn fail<T>(msg: String) -> Result<T, Violation> {
    Err(Violation(msg))
}

impl Run {
    /// The fuzzed model's description.
    pub(crate) fn d(&self) -> Desc {
        self.model.description
    }

    pub(crate) fn check_status(&mut self, s: i32, allowed: &[i32]) -> Result<(), Violation> {
        self.out.calls += 1;
        if self.trace {
            eprintln!("{} -> {}", self.what, status_name(s));
        }
        if (0..=3).contains(&s) {
            self.out.statuses[s as usize] += 1;
        }
        if !allowed.contains(&s) {
            let names: Vec<&str> = allowed.iter().map(|&a| status_name(a)).collect();
            return fail(format!(
                "{}: returned {} ({s}), expected one of {names:?}",
                self.what,
                status_name(s)
            ));
        }
        Ok(())
    }

    /// Checks the log lines of slot `i` after a call that returned `s`, and
    /// moves the oracle's state on an error.
    pub(crate) fn after(&mut self, i: usize, s: i32) -> Result<(), Violation> {
        let what = self.what.clone();
        let slot = self.slots[i].as_mut().expect("slot");
        let lines = slot.log.take();
        self.last_log = lines.iter().map(|l| l.message.clone()).collect();
        let malformed = std::mem::take(&mut *slot.log.malformed.lock().unwrap());
        if !malformed.is_empty() {
            return fail(format!("{what}: malformed logger calls {malformed:?}"));
        }
        for l in &lines {
            if !self.model.description.log_categories.contains(&l.category.as_str()) {
                return fail(format!("{what}: log line with unknown category {l:?}"));
            }
            // (FMI 3.0's logger is given no instance name.)
            if self.api == Api::Fmi2 && l.instance != slot.name {
                return fail(format!(
                    "{what}: log line names instance {:?}, not {:?}",
                    l.instance, slot.name
                ));
            }
        }
        if (WARNING..=ERROR).contains(&s) {
            let on = !slot.silent && (slot.log_all || slot.status_log[(s - WARNING) as usize]);
            if on && !lines.iter().any(|l| l.status == s) {
                return fail(format!(
                    "{what}: returned {} without a log line saying why: {lines:?}",
                    status_name(s)
                ));
            }
        }
        if s == ERROR {
            slot.st = St::Error;
        }
        Ok(())
    }

    pub(crate) fn slot(&self, i: usize) -> &Slot {
        self.slots[i].as_ref().expect("slot")
    }

    pub(crate) fn slot_mut(&mut self, i: usize) -> &mut Slot {
        self.slots[i].as_mut().expect("slot")
    }

    pub(crate) fn finite(&mut self, i: usize, x: f64, name: &str) -> Result<(), Violation> {
        if x.is_finite() {
            return Ok(());
        }
        let (values, initialized) = (self.slot(i).values, self.slot(i).initialized);
        let finding = match values {
            Values::Forged => Finding::ForgedState,
            Values::Extreme => Finding::OverflowAfterExtremeValues,
            _ if !initialized => Finding::OutputsOfUninitializedInstance,
            _ => {
                return fail(format!(
                    "{}: {name} = {x} is not finite (values: {values:?})",
                    self.what
                ))
            }
        };
        self.out
            .findings
            .push((finding, format!("{}: {name} = {x}", self.what)));
        Ok(())
    }
}


pub(crate) fn new_slot(
    name: String,
    c: Instance,
    log: Box<Log>,
    functions: Option<Box<fmi2CallbackFunctions>>,
    logging_on: bool,
) -> Slot {
    Slot {
        c,
        log,
        _functions: functions,
        silent: false,
        name,
        st: St::Instantiated,
        time: 0.0,
        values: Values::Pristine,
        initialized: false,
        me: false,
        scene: false,
        sliding: None,
        integration: Default::default(),
        poisoned: false,
        armed: false,
        status_log: [true; 3],
        log_all: false,
        states: Vec::new(),
    }
    .with_logging(logging_on)
}

impl Slot {
    pub(crate) fn with_logging(self, _logging_on: bool) -> Slot {
        // logStatus* are on from the start whatever loggingOn says; logAll is off.
        self
    }

    /// After a successful reset: the start values, as instantiated (a scene is set again).
    pub(crate) fn reset(&mut self) {
        self.st = St::Instantiated;
        self.time = 0.0;
        self.values = Values::Pristine;
        self.initialized = false;
        self.poisoned = false;
        self.scene = false;
        self.sliding = None;
        self.integration = Default::default();
    }
}


/// A computed value (a derivative, an event indicator, a state, an output) where the standard
/// allows its read: defined for the start values and what the harness's driver sets; after other
/// values, or in the error state of an instance that never initialized (the Line has no network
/// before), the model may find it undefined, and say so.
pub(crate) fn computed(slot: &Slot) -> Vec<i32> {
    if slot.values == Values::Pristine && (slot.st != St::Error || slot.initialized) {
        vec![OK]
    } else {
        vec![OK, DISCARD, ERROR]
    }
}

/// What the Model Exchange driver keeps of an instance between its moves.
#[derive(Default)]
pub(crate) struct Integration {
    /// The next time event the model named.
    pub(crate) next_event: Option<f64>,
    /// The event indicators after the last step (empty: none read since continuous-time mode began).
    pub(crate) z: Vec<f64>,
    /// The Newton iteration's matrix, kept from step to step while it converges.
    pub(crate) newton: Option<Newton>,
}
