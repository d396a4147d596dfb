//! The C API of an FMU library as an importer sees it, for every Rust test
//! of the C API (the conformance tests, thread, panic-boundary tests, the
//! fuzz harness) of any model of this project. All `unsafe` of those tests
//! lives here.
//!
//! The `fmi2*` and `fmi3*` functions are declared from the same lists of
//! signatures the exports are defined from (`fmi-abi`). They resolve
//! at link time to the `#[no_mangle]` exports of the model crate the test
//! binary links, so every call goes through the real C entry points. The
//! model type parameter `M` only supplies its description (GUID, value
//! references) and its resources ([`Tested`]); a test binary links exactly
//! one model.
//!
//! Each instance logs into its own `Log`, passed as `componentEnvironment`:
//! no global state, so tests can run in parallel threads.
//!
//! `conformance`: the suite of the FMI layer's tests that every model runs
//! (`conformance_tests!`), written over these functions without `unsafe`.

#![allow(non_snake_case, clippy::missing_safety_doc)]

pub use fmi_abi::fmi2::{
    fmi2Boolean, fmi2Byte, fmi2CallbackFunctions, fmi2CallbackLogger, fmi2Component, fmi2ComponentEnvironment,
    fmi2EventInfo, fmi2FMUstate, fmi2Integer, fmi2Real, fmi2Status, fmi2StatusKind, fmi2String, fmi2Type,
    fmi2ValueReference,
};
use fmi_core::description::{Causality, Kind, ModelDescription, Variable};
use fmi_core::{Compiled, Model, Resources};
use std::ffi::{c_int, c_void, CStr, CString};
use std::marker::PhantomData;
use std::sync::Mutex;

pub mod conformance;
/// For the macros: the panic hook's category exists only with fmi-core's feature.
pub use fmi_core;

pub const OK: i32 = 0;
pub const WARNING: i32 = 1;
pub const DISCARD: i32 = 2;
pub const ERROR: i32 = 3;
pub const FATAL: i32 = 4;
pub const PENDING: i32 = 5;

pub const ME: i32 = 0;
pub const CS: i32 = 1;

/// `fmi2StatusKind`.
pub const DO_STEP_STATUS: i32 = 0;
pub const PENDING_STATUS: i32 = 1;
pub const LAST_SUCCESSFUL_TIME: i32 = 2;
pub const TERMINATED: i32 = 3;

pub fn status_name(s: i32) -> &'static str {
    match s {
        OK => "fmi2OK",
        WARNING => "fmi2Warning",
        DISCARD => "fmi2Discard",
        ERROR => "fmi2Error",
        FATAL => "fmi2Fatal",
        PENDING => "fmi2Pending",
        _ => "not an fmi2Status",
    }
}

/// Declares the functions of a signature list; the bodies are the exports'.
macro_rules! declare {
    ($model:ty; $standard:ident in $module:ident; $($name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)? => $body:expr;)*) => {
        extern "C" {
            $(pub fn $name($($arg: $ty),*) $(-> $ret)?;)*
        }
    };
}

/// The 44 fmi2 functions, declared from the one list of their C signatures
/// that the exports are defined from (`fmi_abi::fmi2_functions!`); they
/// resolve at link time to the model crate's `#[no_mangle]` exports.
mod fmi2_api {
    use fmi_abi::fmi2::*;
    fmi_abi::fmi2_functions!(declare, ());
}
pub use fmi2_api::*;

/// `convertingSpanDoSteps`, declared from its signature (`fmi_abi::fmi2_steps_function!`): only a
/// test binary whose library exports it (the Line's, `export_fmi2_steps!`) calls it (`Fmu::do_steps`).
pub mod steps {
    use fmi_abi::fmi2::*;
    fmi_abi::fmi2_steps_function!(declare, ());
}

/// The fmi3 functions, likewise (`fmi_abi::fmi3_functions!`).
pub mod fmi3 {
    pub use fmi_abi::fmi3::*;
    fmi_abi::fmi3_functions!(declare, ());
}

// ---------------------------------------------------------------- the model under test

/// The model a test binary drives through the C API it links: its
/// interface, where its FMU's resources are, and what it needs to exist.
/// A model whose description is compiled in (`Compiled`) is all that by
/// itself. A model that builds its interface at instantiation from its
/// resources (the Line, from line.json) is tested through a stand-in type of
/// its tests that reads the description once from the fixture resources
/// (`description_from_resources`).
pub trait Tested: 'static {
    /// The interface of the model under test, as the library will build it
    /// from `resources()`.
    fn description() -> &'static ModelDescription;

    /// The resources/ folder the tests instantiate with (what the model's
    /// FMU ships in resources/), a path ending in '/': the folder of the
    /// package cargo runs the tests of (every model has the same shape),
    /// else the span's at the root (the fuzz harness runs outside cargo).
    fn resources() -> String {
        let package = std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../..").into());
        format!("{package}/resources/").replace('\\', "/")
    }

    /// The library crate whose exports the test binary links (for the
    /// checks of its compiled objects): the first segment of the type's path.
    fn library() -> &'static str {
        std::any::type_name::<Self>().split("::").next().unwrap_or_default()
    }

    /// The model cannot be instantiated without its resources (its
    /// interface is in them): a NULL resource location must be refused
    /// with a message that says so, where other models tolerate it.
    fn needs_resources() -> bool {
        false
    }

    /// Why a test of the conformance suite (`"module::test"`) cannot apply
    /// to this model, or None: the macros' test then passes after printing
    /// the reason (one line, so a skip is never silent). A few tests ask
    /// this also per case (`"module::test: <case>"`, as they print it).
    fn skipped(_test: &str) -> Option<&'static str> {
        None
    }
}

impl<M: Compiled> Tested for M {
    fn description() -> &'static ModelDescription {
        M::compiled()
    }
}

/// The description `M` builds at instantiation from the resources folder
/// `folder` (`Model::instantiate`), leaked so that it lives as long as the
/// test binary: for a test's `Tested::description`, called once (a `OnceLock`).
pub fn description_from_resources<M: Model>(folder: &str) -> &'static ModelDescription {
    let model = M::instantiate(&Resources::from_path(Some(folder)))
        .unwrap_or_else(|e| panic!("the model under test cannot be instantiated from {folder}: {}", e.message));
    Box::leak(Box::new(model.description().clone()))
}

// ---------------------------------------------------------------- logging

/// One call of the logger callback, as the FMU made it (a message keeps the
/// printf escaping "%%" the FMU applies).
#[derive(Clone, Debug, PartialEq)]
pub struct LogLine {
    pub instance: String,
    pub status: i32,
    pub category: String,
    pub message: String,
}

/// Where one instance's logger writes; its address is the `componentEnvironment`.
#[derive(Default)]
pub struct Log {
    pub lines: Mutex<Vec<LogLine>>,
    /// Calls with a NULL string or a status that is no fmi2Status.
    pub malformed: Mutex<Vec<String>>,
}

impl Log {
    /// The lines logged since the last `take`, with the printf escaping undone.
    pub fn take(&self) -> Vec<LogLine> {
        let lines = std::mem::take(&mut *self.lines.lock().unwrap_or_else(|p| p.into_inner()));
        lines.into_iter().map(|l| LogLine { message: l.message.replace("%%", "%"), ..l }).collect()
    }
}

unsafe fn text(s: fmi2String) -> Option<String> {
    (!s.is_null()).then(|| CStr::from_ptr(s).to_string_lossy().into_owned())
}

unsafe fn string(s: fmi2String) -> String {
    text(s).unwrap_or_else(|| "<NULL>".to_string())
}

/// The logger: C declares it variadic, but the FMU formats its messages
/// itself and passes no variadic arguments, so on x86-64 (and aarch64) a
/// five-argument function is called correctly through the variadic type.
unsafe extern "C" fn capture(
    env: fmi2ComponentEnvironment,
    instance: fmi2String,
    status: fmi2Status,
    category: fmi2String,
    message: fmi2String,
) {
    let Some(log) = (env as *const Log).as_ref() else { return };
    if instance.is_null() || category.is_null() || message.is_null() || !(OK..=PENDING).contains(&status) {
        let what = format!("status {status}, strings {:?}", (text(instance), text(category), text(message)));
        log.malformed.lock().unwrap_or_else(|p| p.into_inner()).push(what);
    }
    let line = LogLine { instance: string(instance), status, category: string(category), message: string(message) };
    log.lines.lock().unwrap_or_else(|p| p.into_inner()).push(line);
}

fn logger() -> fmi2CallbackLogger {
    let f: unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2String, fmi2Status, fmi2String, fmi2String) = capture;
    // SAFETY: same calling convention for the fixed arguments; see `capture`.
    unsafe { std::mem::transmute(f) }
}

/// The callback functions that log into `log`, which must outlive every
/// instance created with them.
pub fn callbacks(log: &Log) -> fmi2CallbackFunctions {
    fmi2CallbackFunctions {
        logger: Some(logger()),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: log as *const Log as fmi2ComponentEnvironment,
    }
}

// ---------------------------------------------------------------- instantiation

/// What `fmi2Instantiate` is called with; `None` strings are passed as NULL.
#[derive(Debug)]
pub struct Setup<M> {
    pub name: Option<String>,
    pub fmu_type: i32,
    pub guid: Option<String>,
    pub resource_location: Option<String>,
    pub logging_on: bool,
    /// Pass a `fmi2CallbackFunctions` whose logger is NULL.
    pub no_logger: bool,
    pub model: PhantomData<M>,
}

// Not derived: that would ask the model type to be Clone, which a stand-in need not be.
impl<M> Clone for Setup<M> {
    fn clone(&self) -> Self {
        Setup {
            name: self.name.clone(),
            guid: self.guid.clone(),
            resource_location: self.resource_location.clone(),
            model: PhantomData,
            ..*self
        }
    }
}

impl<M: Tested> Default for Setup<M> {
    fn default() -> Self {
        Setup {
            name: Some(M::description().model_identifier.to_ascii_lowercase()),
            fmu_type: CS,
            guid: Some(guid::<M>().into()),
            resource_location: Some(shipped_resources::<M>()),
            logging_on: false,
            no_logger: false,
            model: PhantomData,
        }
    }
}

/// The tested model's resources/ folder (`Tested::resources`) as a file:
/// URI, spaces percent-encoded as importers do.
/// (No canonicalize: on Windows it gives a verbatim \\?\ path, which is no URI.)
pub fn shipped_resources<M: Tested>() -> String {
    let folder = M::resources().replace('%', "%25").replace(' ', "%20");
    if folder.starts_with('/') { format!("file://{folder}") } else { format!("file:///{folder}") }
}

fn c_opt(s: &Option<String>) -> Option<CString> {
    s.as_ref().map(|s| CString::new(s.as_str()).expect("no NUL in test strings"))
}

fn ptr_of(s: &Option<CString>) -> fmi2String {
    s.as_ref().map_or(std::ptr::null(), |s| s.as_ptr())
}

/// `fmi2Instantiate` with a NULL `functions` pointer (and every other
/// argument valid, so that only that can be refused): must not crash.
pub fn instantiate_without_callbacks<M: Tested>() -> bool {
    let name = CString::new("x").unwrap();
    let guid = CString::new(guid::<M>()).unwrap();
    let resources = CString::new(shipped_resources::<M>()).unwrap();
    // SAFETY: valid strings; the FMU must cope with the NULL functions pointer.
    let c = unsafe { fmi2Instantiate(name.as_ptr(), CS, guid.as_ptr(), resources.as_ptr(), std::ptr::null(), 0, 0) };
    let got = !c.is_null();
    // SAFETY: c is NULL or an instance of this library.
    unsafe { fmi2FreeInstance(c) };
    got
}

pub fn types_platform() -> String {
    // SAFETY: a static C string.
    unsafe { string(fmi2GetTypesPlatform()) }
}

pub fn version() -> String {
    // SAFETY: a static C string.
    unsafe { string(fmi2GetVersion()) }
}

pub fn guid<M: Tested>() -> &'static str {
    &M::description().guid
}

/// Looks a variable up by name; panics on a name the model does not have.
pub fn var<M: Tested>(name: &str) -> &'static Variable {
    M::description().variable_by_name(name).unwrap_or_else(|| panic!("no variable {name}"))
}

pub fn vr<M: Tested>(name: &str) -> u32 {
    var::<M>(name).vr
}

/// An opaque FMU state pointer. `Copy` on purpose: tests use stale and
/// foreign pointers, which the FMU must recognise and refuse (it only
/// compares such pointers, it never dereferences them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct State(fmi2FMUstate);

static FOREIGN_STATE: [u64; 64] = [0; 64];

impl State {
    pub const NULL: State = State(std::ptr::null_mut());
    /// A pointer the FMU never handed out.
    pub fn foreign() -> State {
        State(FOREIGN_STATE.as_ptr() as *mut c_void)
    }
    pub fn is_null(self) -> bool {
        self.0.is_null()
    }
}

/// One FMU instance; freed on drop.
pub struct Fmu<M> {
    pub c: fmi2Component,
    // Boxed: its address is the componentEnvironment, so it must not move,
    // and it must outlive the instance (see Drop).
    pub log: Box<Log>,
    model: PhantomData<M>,
}

// SAFETY: an instance is used by one thread at a time (the `Fmu` is moved,
// not shared), which is what FMI 2.0 asks of importers.
unsafe impl<M> Send for Fmu<M> {}

impl<M> Drop for Fmu<M> {
    fn drop(&mut self) {
        // SAFETY: c came from fmi2Instantiate and is freed once.
        unsafe { fmi2FreeInstance(self.c) };
        self.c = std::ptr::null_mut();
    }
}

/// Instantiates; on NULL returns what was logged.
pub fn instantiate<M: Tested>(setup: &Setup<M>) -> Result<Fmu<M>, Vec<LogLine>> {
    let log: Box<Log> = Box::default();
    let functions = fmi2CallbackFunctions {
        logger: if setup.no_logger { None } else { Some(logger()) },
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: &*log as *const Log as *mut c_void,
    };
    let (name, guid, res) = (c_opt(&setup.name), c_opt(&setup.guid), c_opt(&setup.resource_location));
    // SAFETY: all pointers are valid or NULL for the duration of the call; the
    // environment outlives the instance (see Fmu::drop).
    let c = unsafe {
        fmi2Instantiate(
            ptr_of(&name),
            setup.fmu_type,
            ptr_of(&guid),
            ptr_of(&res),
            &functions,
            0,
            setup.logging_on as c_int,
        )
    };
    if c.is_null() {
        Err(log.lines.into_inner().unwrap())
    } else {
        Ok(Fmu { c, log, model: PhantomData })
    }
}

/// Every function that takes an `fmi2Component`: the standard's one list of them
/// (`fmi_core::standard::fmi2::Call`). `Fmu::call` makes each but fmi2FreeInstance (the
/// `Fmu` frees its instance when dropped) with harmless arguments.
pub use fmi_core::standard::fmi2::Call as Api;

/// The functions `Fmu::call` makes: every one that takes an instance but fmi2FreeInstance.
pub fn callable() -> impl Iterator<Item = Api> {
    Api::ALL.iter().copied().filter(|&api| api != Api::FreeInstance)
}

/// Calls `api` on the raw component `c` with harmless arguments; `state` is
/// passed where a function takes an FMU state.
unsafe fn raw_call<M: Tested>(c: fmi2Component, api: Api, state: fmi2FMUstate, bytes: &[u8]) -> fmi2Status {
    let description = M::description();
    let first = |causality: Causality, kind: fn(&Kind) -> bool| {
        description.variables.iter().find(|v| v.causality == causality && kind(&v.kind)).map(|v| v.vr)
    };
    let input = [first(Causality::Input, |k| *k == Kind::Real).expect("a Real input")];
    let output = [first(Causality::Output, |k| *k == Kind::Real).expect("a Real output")];
    let integer: Vec<u32> = first(Causality::Parameter, |k| matches!(k, Kind::Integer | Kind::Enumeration { .. })).into_iter().collect();
    let boolean: Vec<u32> = first(Causality::Parameter, |k| *k == Kind::Boolean).into_iter().collect();
    let mut real = [0.0f64; 4];
    // Model Exchange arrays sized as the description declares.
    let nx = description.states.len().min(4);
    let ni = description.number_of_event_indicators.min(4);
    let mut int = [0 as c_int; 4];
    let mut strings: [fmi2String; 4] = [std::ptr::null(); 4];
    let order = [1 as c_int];
    let none: [u32; 0] = [];
    let category = CString::new("logEvents").unwrap();
    let categories = [category.as_ptr()];
    match api {
        Api::SetDebugLogging => fmi2SetDebugLogging(c, 0, 1, categories.as_ptr()),
        Api::SetupExperiment => fmi2SetupExperiment(c, 0, 0.0, 0.0, 0, 0.0),
        Api::EnterInitializationMode => fmi2EnterInitializationMode(c),
        Api::ExitInitializationMode => fmi2ExitInitializationMode(c),
        Api::Terminate => fmi2Terminate(c),
        Api::Reset => fmi2Reset(c),
        Api::GetReal => fmi2GetReal(c, output.as_ptr(), 1, real.as_mut_ptr()),
        Api::GetInteger => fmi2GetInteger(c, integer.as_ptr(), integer.len(), int.as_mut_ptr()),
        Api::GetBoolean => fmi2GetBoolean(c, boolean.as_ptr(), boolean.len(), int.as_mut_ptr()),
        Api::GetString => fmi2GetString(c, none.as_ptr(), 0, strings.as_mut_ptr()),
        Api::SetReal => fmi2SetReal(c, input.as_ptr(), 1, [5.0].as_ptr()),
        Api::SetInteger => fmi2SetInteger(c, none.as_ptr(), 0, int.as_ptr()),
        Api::SetBoolean => fmi2SetBoolean(c, none.as_ptr(), 0, int.as_ptr()),
        Api::SetString => fmi2SetString(c, none.as_ptr(), 0, strings.as_ptr()),
        Api::GetFMUstate => {
            let mut s: fmi2FMUstate = std::ptr::null_mut();
            fmi2GetFMUstate(c, &mut s)
        }
        Api::SetFMUstate => fmi2SetFMUstate(c, state),
        Api::FreeFMUstate => {
            let mut s: fmi2FMUstate = std::ptr::null_mut();
            fmi2FreeFMUstate(c, &mut s)
        }
        Api::SerializedFMUstateSize => {
            let mut n = 0usize;
            fmi2SerializedFMUstateSize(c, state, &mut n)
        }
        Api::SerializeFMUstate => {
            // Room for any state here (a line of many parts needs some kB); fmu_states tests a short buffer.
            let mut buffer = vec![0u8; 1 << 20];
            fmi2SerializeFMUstate(c, state, buffer.as_mut_ptr() as *mut fmi2Byte, buffer.len())
        }
        Api::DeSerializeFMUstate => {
            let mut s: fmi2FMUstate = std::ptr::null_mut();
            fmi2DeSerializeFMUstate(c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut s)
        }
        Api::GetDirectionalDerivative => {
            fmi2GetDirectionalDerivative(c, output.as_ptr(), 1, input.as_ptr(), 1, [1.0].as_ptr(), real.as_mut_ptr())
        }
        Api::EnterEventMode => fmi2EnterEventMode(c),
        Api::NewDiscreteStates => {
            let mut info = fmi2EventInfo::default();
            fmi2NewDiscreteStates(c, &mut info)
        }
        Api::EnterContinuousTimeMode => fmi2EnterContinuousTimeMode(c),
        Api::CompletedIntegratorStep => {
            let (mut a, mut b) = (0, 0);
            fmi2CompletedIntegratorStep(c, 1, &mut a, &mut b)
        }
        Api::SetTime => fmi2SetTime(c, 0.0),
        Api::SetContinuousStates => {
            let x = [1.0f64; 4];
            fmi2SetContinuousStates(c, x.as_ptr(), nx)
        }
        Api::GetDerivatives => fmi2GetDerivatives(c, real.as_mut_ptr(), nx),
        Api::GetEventIndicators => fmi2GetEventIndicators(c, real.as_mut_ptr(), ni),
        Api::GetContinuousStates => fmi2GetContinuousStates(c, real.as_mut_ptr(), nx),
        Api::GetNominalsOfContinuousStates => fmi2GetNominalsOfContinuousStates(c, real.as_mut_ptr(), nx),
        Api::SetRealInputDerivatives => {
            fmi2SetRealInputDerivatives(c, input.as_ptr(), 1, order.as_ptr(), [0.0].as_ptr())
        }
        Api::GetRealOutputDerivatives => {
            fmi2GetRealOutputDerivatives(c, output.as_ptr(), 1, order.as_ptr(), real.as_mut_ptr())
        }
        Api::DoStep => fmi2DoStep(c, 0.0, 0.01, 0),
        Api::CancelStep => fmi2CancelStep(c),
        Api::GetStatus => {
            let mut s = 0;
            fmi2GetStatus(c, DO_STEP_STATUS, &mut s)
        }
        Api::GetRealStatus => fmi2GetRealStatus(c, LAST_SUCCESSFUL_TIME, real.as_mut_ptr()),
        Api::GetIntegerStatus => fmi2GetIntegerStatus(c, DO_STEP_STATUS, int.as_mut_ptr()),
        Api::GetBooleanStatus => fmi2GetBooleanStatus(c, TERMINATED, int.as_mut_ptr()),
        Api::GetStringStatus => fmi2GetStringStatus(c, PENDING_STATUS, strings.as_mut_ptr()),
        Api::FreeInstance => panic!("fmi2FreeInstance is made by dropping the Fmu, not by Fmu::call"),
    }
}

/// Calls `api` with a NULL `fmi2Component`.
pub fn call_with_null_component<M: Tested>(api: Api) -> i32 {
    // SAFETY: NULL is refused by the FMU before anything is dereferenced;
    // every other pointer argument is valid.
    unsafe { raw_call::<M>(std::ptr::null_mut(), api, std::ptr::null_mut(), &[0u8; 64]) }
}

/// fmi2FreeInstance(NULL): must do nothing.
pub fn free_null_instance() {
    // SAFETY: NULL is allowed.
    unsafe { fmi2FreeInstance(std::ptr::null_mut()) }
}

fn status_of<T>(status: fmi2Status, value: T) -> Result<T, i32> {
    if status == OK {
        Ok(value)
    } else {
        Err(status)
    }
}

impl<M: Tested> Fmu<M> {
    /// A Co-Simulation instance named after the model, logging off, or panics.
    pub fn new() -> Self {
        Self::with(&Setup::default())
    }

    /// A Co-Simulation instance named `name`, logging off, or panics.
    pub fn named(name: &str) -> Self {
        Self::with(&Setup { name: Some(name.into()), ..Setup::default() })
    }

    pub fn with(setup: &Setup<M>) -> Self {
        instantiate(setup).unwrap_or_else(|log| panic!("fmi2Instantiate failed: {log:?}"))
    }

    pub fn logging(on: bool) -> Self {
        Self::with(&Setup { logging_on: on, ..Setup::default() })
    }

    // ---- log

    pub fn logs(&self) -> Vec<LogLine> {
        self.log.lines.lock().unwrap().clone()
    }

    /// The lines logged since the last `take_logs`.
    pub fn take_logs(&self) -> Vec<LogLine> {
        std::mem::take(&mut *self.log.lines.lock().unwrap())
    }

    /// The messages logged so far.
    pub fn messages(&self) -> Vec<String> {
        self.logs().into_iter().map(|l| l.message).collect()
    }

    // ---- calls

    /// Calls `api` with harmless arguments. Functions that take an FMU state
    /// get one freshly saved from this instance (fmi2GetFMUstate), so that
    /// only the phase decides the outcome; fmi2DeSerializeFMUstate gets the
    /// serialized form of such a state.
    pub fn call(&self, api: Api) -> i32 {
        let (mut state, bytes) = match api {
            Api::SetFMUstate | Api::SerializedFMUstateSize | Api::SerializeFMUstate | Api::DeSerializeFMUstate => {
                let log_len = self.log.lines.lock().unwrap().len();
                let state = self.get_state().expect("fmi2GetFMUstate for a state-taking call");
                let bytes = if api == Api::DeSerializeFMUstate {
                    self.serialize(state).expect("serialize for fmi2DeSerializeFMUstate")
                } else {
                    Vec::new()
                };
                // The preparation must not show up in the log.
                self.log.lines.lock().unwrap().truncate(log_len);
                (state, bytes)
            }
            _ => (State::NULL, Vec::new()),
        };
        // SAFETY: c is this library's live instance; all arguments are valid.
        let status = unsafe { raw_call::<M>(self.c, api, state.0, &bytes) };
        if !state.is_null() {
            let log_len = self.log.lines.lock().unwrap().len();
            let _ = self.free_state(&mut state);
            self.log.lines.lock().unwrap().truncate(log_len);
        }
        status
    }

    pub fn set_debug_logging(&self, on: bool, categories: &[&str]) -> i32 {
        let owned: Vec<CString> = categories.iter().map(|c| CString::new(*c).unwrap()).collect();
        let ptrs: Vec<fmi2String> = owned.iter().map(|c| c.as_ptr()).collect();
        let p = if ptrs.is_empty() { std::ptr::null() } else { ptrs.as_ptr() };
        // SAFETY: live instance, `ptrs.len()` valid C strings (NULL when none).
        unsafe { fmi2SetDebugLogging(self.c, on as c_int, ptrs.len(), p) }
    }

    pub fn setup_experiment(&self, start: f64) -> i32 {
        // SAFETY: live instance.
        unsafe { fmi2SetupExperiment(self.c, 0, 0.0, start, 0, 0.0) }
    }

    pub fn setup_experiment_full(&self, tolerance: Option<f64>, start: f64, stop: Option<f64>) -> i32 {
        // SAFETY: live instance.
        unsafe {
            fmi2SetupExperiment(
                self.c,
                tolerance.is_some() as c_int,
                tolerance.unwrap_or(0.0),
                start,
                stop.is_some() as c_int,
                stop.unwrap_or(0.0),
            )
        }
    }

    pub fn enter_init(&self) -> i32 {
        // SAFETY: live instance.
        unsafe { fmi2EnterInitializationMode(self.c) }
    }

    pub fn exit_init(&self) -> i32 {
        // SAFETY: live instance.
        unsafe { fmi2ExitInitializationMode(self.c) }
    }

    /// SetupExperiment(start), Enter- and ExitInitializationMode; panics
    /// unless all three succeed.
    pub fn init(&self, start: f64) {
        assert_eq!(self.setup_experiment(start), OK, "fmi2SetupExperiment: {:?}", self.logs());
        assert_eq!(self.enter_init(), OK, "fmi2EnterInitializationMode: {:?}", self.logs());
        assert_eq!(self.exit_init(), OK, "fmi2ExitInitializationMode: {:?}", self.logs());
    }

    pub fn terminate(&self) -> i32 {
        // SAFETY: live instance.
        unsafe { fmi2Terminate(self.c) }
    }

    pub fn reset(&self) -> i32 {
        // SAFETY: live instance.
        unsafe { fmi2Reset(self.c) }
    }

    pub fn do_step(&self, t: f64, h: f64) -> i32 {
        // SAFETY: live instance.
        unsafe { fmi2DoStep(self.c, t, h, 0) }
    }

    /// `convertingSpanDoSteps` over `times`, reading `vrs`: (status, the rows of values, steps
    /// taken, rows written); `None` for an argument passes NULL (`values` with room for every row).
    pub fn do_steps(&self, times: Option<&[f64]>, n_steps: usize, vrs: &[u32]) -> (i32, Vec<f64>, usize, usize) {
        let mut values = vec![f64::NAN; (n_steps + 1) * vrs.len()];
        let (mut taken, mut rows) = (usize::MAX, usize::MAX);
        let times = times.map_or(std::ptr::null(), <[f64]>::as_ptr);
        // SAFETY: live instance; `times` holds n_steps + 1 points or is NULL, `values` has a row per point.
        let s = unsafe { steps::convertingSpanDoSteps(self.c, times, n_steps, vrs.as_ptr(), vrs.len(), values.as_mut_ptr(), &mut taken, &mut rows) };
        (s, values, taken, rows)
    }

    // ---- values by value reference

    pub fn get_reals_vr(&self, vrs: &[u32]) -> Result<Vec<f64>, i32> {
        let mut v = vec![f64::NAN; vrs.len()];
        // SAFETY: live instance; vrs and v have vrs.len() elements.
        let s = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) };
        status_of(s, v)
    }

    pub fn get_integers_vr(&self, vrs: &[u32]) -> Result<Vec<i32>, i32> {
        let mut v = vec![i32::MIN; vrs.len()];
        // SAFETY: as above.
        let s = unsafe { fmi2GetInteger(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) };
        status_of(s, v)
    }

    pub fn get_booleans_vr(&self, vrs: &[u32]) -> Result<Vec<i32>, i32> {
        let mut v = vec![i32::MIN; vrs.len()];
        // SAFETY: as above.
        let s = unsafe { fmi2GetBoolean(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) };
        status_of(s, v)
    }

    /// The status, and the texts when it is OK (copied before the next call).
    pub fn get_strings_vr(&self, vrs: &[u32]) -> Result<Vec<String>, i32> {
        let mut v: Vec<fmi2String> = vec![std::ptr::null(); vrs.len()];
        // SAFETY: as above.
        let s = unsafe { fmi2GetString(self.c, vrs.as_ptr(), vrs.len(), v.as_mut_ptr()) };
        if s != OK {
            return Err(s);
        }
        // SAFETY: on OK the FMU filled every slot with a text valid until the next call.
        Ok(v.iter().map(|&p| unsafe { string(p) }).collect())
    }

    /// A String variable's text by name.
    pub fn text(&self, name: &str) -> String {
        self.get_strings_vr(&[var::<M>(name).vr]).unwrap_or_else(|s| panic!("get {name}: status {s}: {:?}", self.logs())).remove(0)
    }

    pub fn set_text(&self, name: &str, value: &str) -> i32 {
        self.set_strings_vr(&[var::<M>(name).vr], &[value])
    }

    pub fn set_reals_vr(&self, vrs: &[u32], values: &[f64]) -> i32 {
        assert_eq!(vrs.len(), values.len());
        // SAFETY: live instance; both slices have vrs.len() elements.
        unsafe { fmi2SetReal(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }

    pub fn set_integers_vr(&self, vrs: &[u32], values: &[i32]) -> i32 {
        assert_eq!(vrs.len(), values.len());
        // SAFETY: as above.
        unsafe { fmi2SetInteger(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }

    pub fn set_booleans_vr(&self, vrs: &[u32], values: &[i32]) -> i32 {
        assert_eq!(vrs.len(), values.len());
        // SAFETY: as above.
        unsafe { fmi2SetBoolean(self.c, vrs.as_ptr(), vrs.len(), values.as_ptr()) }
    }

    pub fn set_strings_vr(&self, vrs: &[u32], values: &[&str]) -> i32 {
        assert_eq!(vrs.len(), values.len());
        let owned: Vec<CString> = values.iter().map(|s| CString::new(*s).unwrap()).collect();
        let ptrs: Vec<fmi2String> = owned.iter().map(|s| s.as_ptr()).collect();
        // SAFETY: as above.
        unsafe { fmi2SetString(self.c, vrs.as_ptr(), vrs.len(), ptrs.as_ptr()) }
    }

    // ---- values by name (any type: Real, Integer/Enumeration, Boolean; Strings hashed by `get`)

    /// Sets one variable by name; the value is converted to the variable's
    /// type (Booleans and enumerations take the raw integer).
    pub fn set(&self, name: &str, value: f64) -> i32 {
        let v = var::<M>(name);
        match v.kind {
            Kind::Real => self.set_reals_vr(&[v.vr], &[value]),
            Kind::Integer | Kind::Enumeration { .. } => self.set_integers_vr(&[v.vr], &[value as i32]),
            Kind::Boolean => self.set_booleans_vr(&[v.vr], &[value as i32]),
            Kind::String => panic!("{name} is a String: use set_text"),
        }
    }

    /// Sets several variables by name, panicking unless each set succeeds.
    pub fn set_all(&self, values: &[(&str, f64)]) {
        for &(name, x) in values {
            assert_eq!(self.set(name, x), OK, "set {name} = {x}: {:?}", self.logs());
        }
    }

    /// Gets one variable by name as f64 (Integers and Booleans converted).
    pub fn get(&self, name: &str) -> Result<f64, i32> {
        let v = var::<M>(name);
        match v.kind {
            Kind::Real => self.get_reals_vr(&[v.vr]).map(|x| x[0]),
            Kind::Integer | Kind::Enumeration { .. } => self.get_integers_vr(&[v.vr]).map(|x| x[0] as f64),
            Kind::Boolean => self.get_booleans_vr(&[v.vr]).map(|x| x[0] as f64),
            // A text as the FNV-1a hash of its bytes, so that comparisons of
            // every variable's value cover the String variables too.
            Kind::String => self.get_strings_vr(&[v.vr]).map(|x| f64::from_bits(fmi_core::snapshot::fnv1a(x[0].as_bytes()))),
        }
    }

    pub fn real(&self, name: &str) -> f64 {
        self.get(name).unwrap_or_else(|s| panic!("get {name}: status {s}: {:?}", self.logs()))
    }

    // ---- status functions

    pub fn get_status(&self, kind: i32) -> (i32, i32) {
        let mut v = -1;
        // SAFETY: live instance, valid out pointer.
        let s = unsafe { fmi2GetStatus(self.c, kind, &mut v) };
        (s, v)
    }

    pub fn get_real_status(&self, kind: i32) -> (i32, f64) {
        let mut v = f64::NAN;
        // SAFETY: as above.
        let s = unsafe { fmi2GetRealStatus(self.c, kind, &mut v) };
        (s, v)
    }

    pub fn get_integer_status(&self, kind: i32) -> (i32, i32) {
        let mut v = -1;
        // SAFETY: as above.
        let s = unsafe { fmi2GetIntegerStatus(self.c, kind, &mut v) };
        (s, v)
    }

    pub fn get_boolean_status(&self, kind: i32) -> (i32, i32) {
        let mut v = -1;
        // SAFETY: as above.
        let s = unsafe { fmi2GetBooleanStatus(self.c, kind, &mut v) };
        (s, v)
    }

    pub fn get_string_status(&self, kind: i32) -> i32 {
        let mut v: fmi2String = std::ptr::null();
        // SAFETY: as above.
        unsafe { fmi2GetStringStatus(self.c, kind, &mut v) }
    }

    /// The current time (fmi2GetRealStatus(fmi2LastSuccessfulTime)).
    pub fn time(&self) -> f64 {
        let (s, t) = self.get_real_status(LAST_SUCCESSFUL_TIME);
        assert_eq!(s, OK, "fmi2GetRealStatus: {:?}", self.logs());
        t
    }

    // ---- FMU states

    /// fmi2GetFMUstate into a fresh (NULL) slot.
    pub fn get_state(&self) -> Result<State, i32> {
        let mut s = State::NULL;
        let status = self.get_state_into(&mut s);
        status_of(status, s)
    }

    /// fmi2GetFMUstate into `slot` (NULL: new state; own state: overwritten).
    pub fn get_state_into(&self, slot: &mut State) -> i32 {
        // SAFETY: live instance; the slot is a valid pointer to a pointer.
        unsafe { fmi2GetFMUstate(self.c, &mut slot.0) }
    }

    pub fn set_state(&self, state: State) -> i32 {
        // SAFETY: the FMU checks that the pointer is one of its own before using it.
        unsafe { fmi2SetFMUstate(self.c, state.0) }
    }

    pub fn free_state(&self, slot: &mut State) -> i32 {
        // SAFETY: as above; the FMU frees only pointers it owns.
        unsafe { fmi2FreeFMUstate(self.c, &mut slot.0) }
    }

    pub fn serialized_size(&self, state: State) -> Result<usize, i32> {
        let mut n = usize::MAX;
        // SAFETY: as above.
        let s = unsafe { fmi2SerializedFMUstateSize(self.c, state.0, &mut n) };
        status_of(s, n)
    }

    /// fmi2SerializeFMUstate into `buffer`, telling the FMU its true size.
    pub fn serialize_into(&self, state: State, buffer: &mut [u8]) -> i32 {
        // SAFETY: the buffer has buffer.len() writable bytes.
        unsafe { fmi2SerializeFMUstate(self.c, state.0, buffer.as_mut_ptr() as *mut fmi2Byte, buffer.len()) }
    }

    /// Size, then serialize.
    pub fn serialize(&self, state: State) -> Result<Vec<u8>, i32> {
        let n = self.serialized_size(state)?;
        let mut buffer = vec![0u8; n];
        status_of(self.serialize_into(state, &mut buffer), buffer)
    }

    pub fn deserialize(&self, bytes: &[u8]) -> Result<State, i32> {
        let mut s = State::NULL;
        let status = self.deserialize_into(bytes, &mut s);
        status_of(status, s)
    }

    pub fn deserialize_into(&self, bytes: &[u8], slot: &mut State) -> i32 {
        // SAFETY: bytes.len() readable bytes; the slot is valid.
        unsafe { fmi2DeSerializeFMUstate(self.c, bytes.as_ptr() as *const fmi2Byte, bytes.len(), &mut slot.0) }
    }
}

impl<M: Tested> Fmu<M> {
    /// fmi2SetRealInputDerivatives.
    pub fn set_real_input_derivatives(&self, vrs: &[u32], orders: &[i32], values: &[f64]) -> i32 {
        assert!(orders.len() == vrs.len() && values.len() == vrs.len());
        // SAFETY: live instance; three slices of vrs.len() elements.
        unsafe { fmi2SetRealInputDerivatives(self.c, vrs.as_ptr(), vrs.len(), orders.as_ptr(), values.as_ptr()) }
    }

    /// `fmi2GetDirectionalDerivative` with separate arrays: the status and dvUnknown.
    pub fn directional_derivative(&self, unknowns: &[u32], knowns: &[u32], seed: &[f64]) -> (i32, Vec<f64>) {
        assert_eq!(knowns.len(), seed.len());
        let mut out = vec![f64::NAN; unknowns.len()];
        // SAFETY: live instance; slices of the lengths passed.
        let status = unsafe {
            fmi2GetDirectionalDerivative(self.c, unknowns.as_ptr(), unknowns.len(), knowns.as_ptr(), knowns.len(), seed.as_ptr(), out.as_mut_ptr())
        };
        (status, out)
    }

    /// `fmi2GetDirectionalDerivative` with one array as dvKnown and dvUnknown (refused), or NULL ones.
    pub fn directional_derivative_in_place(&self, unknowns: &[u32], knowns: &[u32], buffer: Option<&mut [f64]>) -> i32 {
        let p = buffer.map_or(std::ptr::null_mut(), |b| b.as_mut_ptr());
        // SAFETY: live instance; the FMU must refuse the shared or NULL array before it reads it.
        unsafe { fmi2GetDirectionalDerivative(self.c, unknowns.as_ptr(), unknowns.len(), knowns.as_ptr(), knowns.len(), p, p) }
    }
}

// The short forms the hardening tests and the fuzz harness use.
impl<M: Tested> Fmu<M> {
    pub fn set_real(&self, name: &str, x: f64) -> i32 {
        // SAFETY: live instance, one value.
        unsafe { fmi2SetReal(self.c, &vr::<M>(name), 1, &x) }
    }

    pub fn get_real(&self, name: &str) -> (i32, f64) {
        let mut x = f64::NAN;
        // SAFETY: live instance, one value.
        let status = unsafe { fmi2GetReal(self.c, &vr::<M>(name), 1, &mut x) };
        (status, x)
    }

    pub fn get_reals(&self, vrs: &[u32]) -> (i32, Vec<f64>) {
        let mut x = vec![f64::NAN; vrs.len()];
        // SAFETY: live instance; vrs and x have vrs.len() elements.
        let status = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), x.as_mut_ptr()) };
        (status, x)
    }

    /// setupExperiment at t = 0, enter and exit initialization mode.
    pub fn initialize(&self) -> i32 {
        match self.setup_experiment(0.0) {
            OK => match self.enter_init() {
                OK => self.exit_init(),
                status => status,
            },
            status => status,
        }
    }
}
