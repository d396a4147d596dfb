//! The only unsafe code of the crate: the C types of the FMI 2.0 headers,
//! the 44 exported functions (in `exports`), and the one entry path every
//! one of them goes through. That path
//!
//! * turns the `fmi2Component` into a reference, refusing NULL and pointers
//!   that do not carry this library's tag,
//! * catches panics, so that none crosses `extern "C"`, and poisons the
//!   instance that panicked (only `fmi2Reset` and `fmi2FreeInstance` then),
//! * checks the call against the state machine,
//! * turns an error into an `fmi2Status` plus one log line.
//!
//! Raw pointers from the importer become slices and references here and
//! nowhere else; `Box::into_raw`/`Box::from_raw` appear only in this module.

#![allow(non_camel_case_types, non_snake_case, non_upper_case_globals)]

#[doc(hidden)]
pub mod calls;
mod exports;
pub mod raw;
pub mod state_store;

use super::instance::Instance;
use super::logging::Log;
use super::model::Model;
use super::phase::Call;
use super::resources::Resources;
use super::snapshot::Snapshot;
use raw::{out_ref, slice, slice_mut, text, utf8};
use state_store::StateStore;
use super::status::{FmiError, FmiResult, Status};
#[doc(hidden)]
pub use calls::*;
use std::ffi::{c_char, c_int, c_void, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

pub type fmi2Component = *mut c_void;
pub type fmi2ComponentEnvironment = *mut c_void;
pub type fmi2FMUstate = *mut c_void;
pub type fmi2ValueReference = u32;
pub type fmi2Real = f64;
pub type fmi2Integer = c_int;
pub type fmi2Boolean = c_int;
pub type fmi2String = *const c_char;
pub type fmi2Byte = c_char;
/// `fmi2Status`, `fmi2Type` and `fmi2StatusKind` are C enums: taken as plain
/// integers so that an out-of-range value from the importer is not UB.
pub type fmi2Status = c_int;
pub type fmi2Type = c_int;
pub type fmi2StatusKind = c_int;

pub const fmi2ModelExchange: fmi2Type = 0;
pub const fmi2CoSimulation: fmi2Type = 1;
const fmi2Error: fmi2Status = Status::Error as fmi2Status;

/// The logger is variadic in C; this FMU formats its messages itself and
/// passes none of the variadic arguments.
pub type fmi2CallbackLogger = unsafe extern "C" fn(
    fmi2ComponentEnvironment,
    fmi2String,
    fmi2Status,
    fmi2String,
    fmi2String,
    ...
);
pub type fmi2CallbackAllocateMemory = unsafe extern "C" fn(usize, usize) -> *mut c_void;
pub type fmi2CallbackFreeMemory = unsafe extern "C" fn(*mut c_void);
pub type fmi2StepFinished = unsafe extern "C" fn(fmi2ComponentEnvironment, fmi2Status);

#[repr(C)]
pub struct fmi2CallbackFunctions {
    pub logger: Option<fmi2CallbackLogger>,
    pub allocateMemory: Option<fmi2CallbackAllocateMemory>,
    pub freeMemory: Option<fmi2CallbackFreeMemory>,
    pub stepFinished: Option<fmi2StepFinished>,
    pub componentEnvironment: fmi2ComponentEnvironment,
}

#[repr(C)]
#[derive(Default)]
pub struct fmi2EventInfo {
    pub newDiscreteStatesNeeded: fmi2Boolean,
    pub terminateSimulation: fmi2Boolean,
    pub nominalsOfContinuousStatesChanged: fmi2Boolean,
    pub valuesOfContinuousStatesChanged: fmi2Boolean,
    pub nextEventTimeDefined: fmi2Boolean,
    pub nextEventTime: fmi2Real,
}

/// The importer's logger, copied out of `fmi2CallbackFunctions`.
pub struct Logger {
    callback: Option<fmi2CallbackLogger>,
    environment: fmi2ComponentEnvironment,
    instance_name: CString,
}

impl Logger {
    fn new(functions: &fmi2CallbackFunctions, instance_name: &str) -> Self {
        Logger {
            callback: functions.logger,
            environment: functions.componentEnvironment,
            instance_name: c_text(instance_name),
        }
    }
}

impl Log for Logger {
    fn log(&self, status: Status, category: &str, message: &str) {
        let Some(callback) = self.callback else { return };
        // Loggers treat the message as a printf format: escape '%'.
        let message = c_text(&message.replace('%', "%%"));
        let category = c_text(category);
        // SAFETY: the importer handed us this callback for the instance's lifetime.
        unsafe {
            callback(self.environment, self.instance_name.as_ptr(), status as fmi2Status, category.as_ptr(), message.as_ptr())
        }
    }
}

/// A C string with any interior NUL dropped.
fn c_text(s: &str) -> CString {
    CString::new(s.replace('\0', "")).expect("NULs removed")
}

/// Tag at the start of every instance this library hands out ("CONVSPAN").
const TAG: u64 = 0x434f_4e56_5350_414e;

/// What an `fmi2Component` points to: the instance plus the FMU states it
/// has handed out (so that a foreign or freed state is refused, not used).
#[repr(C)]
struct Handle<M: Model> {
    tag: u64,
    instance: Instance<M>,
    states: StateStore<M>,
    /// The texts `fmi2GetString` last returned: they stay valid until the next call.
    strings: Vec<CString>,
    /// Set when a panic was caught inside a call: the instance may be half
    /// updated, so only the calls of `Call::is_allowed_when_poisoned` are
    /// accepted until an `fmi2Reset` succeeds.
    poisoned: bool,
}

impl<M: Model> Handle<M> {
    fn own_state(&self, call: Call, state: fmi2FMUstate) -> FmiResult<&Snapshot<M>> {
        self.states.get(call.name(), state)
    }

    fn keep_state(&mut self, call: Call, slot: *mut fmi2FMUstate, snapshot: Snapshot<M>) -> FmiResult {
        let slot = out_ref(call, slot, "FMUstate")?;
        self.states.keep(call.name(), "FMUstate", slot, snapshot)
    }

    fn free_state(&mut self, call: Call, slot: *mut fmi2FMUstate) -> FmiResult {
        let slot = out_ref(call, slot, "FMUstate")?;
        self.states.free(call.name(), slot)
    }
}

impl<M: Model> Drop for Handle<M> {
    fn drop(&mut self) {
        self.tag = 0;
    }
}

/// `fmi2Instantiate`: no panic crosses the boundary here either.
pub unsafe fn instantiate<M: Model>(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    catch_unwind(|| checked_instance::<M>(instance_name, fmu_type, guid, resource_location, functions, logging_on))
        .unwrap_or(std::ptr::null_mut())
}

/// Checks the FMU type and GUID, copies what it keeps (the resource
/// location as a folder, or why it is none).
unsafe fn checked_instance<M: Model>(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    // Without the callback functions there is no way to report anything.
    let Some(functions) = functions.as_ref() else { return std::ptr::null_mut() };
    let name = text(instance_name).unwrap_or_default();
    let logger = Logger::new(functions, &name);
    let description = M::description();
    let refuse = |message: String| {
        logger.log(Status::Error, "logStatusError", &format!("fmi2Instantiate: {message}"));
        std::ptr::null_mut()
    };
    let model_exchange = match fmu_type {
        fmi2CoSimulation => false,
        fmi2ModelExchange if description.model_exchange => true,
        _ => {
            let offered = if description.model_exchange { "Model Exchange (0) and Co-Simulation (1)" } else { "only Co-Simulation (1)" };
            return refuse(format!("fmuType = {fmu_type} requested, but {} offers {offered}", description.model_identifier));
        }
    };
    match text(guid) {
        Some(g) if g == description.guid => {}
        other => {
            let given = other.map_or("NULL".to_string(), |g| format!("\"{g}\""));
            return refuse(format!(
                "GUID {given} does not match this FMU's {} (the modelDescription.xml and the binary differ)",
                description.guid
            ));
        }
    }
    let resources = Resources::from_location(text(resource_location).as_deref()).for_instance(&name);
    let instance = Instance::<M>::new(Box::new(logger), logging_on != 0, model_exchange, resources);
    Box::into_raw(Box::new(Handle { tag: TAG, instance, states: StateStore::default(), strings: Vec::new(), poisoned: false })) as fmi2Component
}

/// `fmi2FreeInstance`.
pub unsafe fn free_instance<M: Model>(c: fmi2Component) {
    if handle::<M>(c).is_some() {
        let _ = catch_unwind(|| drop(Box::from_raw(c as *mut Handle<M>)));
    }
}

unsafe fn handle<'a, M: Model>(c: fmi2Component) -> Option<&'a mut Handle<M>> {
    let handle = (c as *mut Handle<M>).as_mut()?;
    (handle.tag == TAG).then_some(handle)
}

/// The entry path of every function that takes an instance.
unsafe fn enter<M: Model>(
    c: fmi2Component,
    call: Call,
    body: impl FnOnce(&mut Handle<M>) -> FmiResult<Status>,
) -> fmi2Status {
    let Some(handle) = handle::<M>(c) else { return fmi2Error };
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        if handle.poisoned && !call.is_allowed_when_poisoned() {
            return Err(FmiError::error(format!(
                "{}: refused: an internal error (a panic) in an earlier call may have left the instance \
                 half updated; only fmi2Reset or fmi2FreeInstance are accepted now",
                call.name()
            )));
        }
        handle.instance.begin(call)?;
        body(&mut *handle)
    }));
    let status = match outcome {
        Ok(Ok(status)) => {
            if call == Call::Reset {
                handle.poisoned = false;
            }
            status
        }
        Ok(Err(error)) => handle.instance.fail(error),
        Err(panic) => {
            handle.poisoned = true;
            let what = panic
                .downcast_ref::<&str>()
                .map(|s| s.to_string())
                .or_else(|| panic.downcast_ref::<String>().cloned())
                .unwrap_or_default();
            handle.instance.fail(FmiError::error(format!("{}: internal error: {what}", call.name())))
        }
    };
    status as fmi2Status
}

/// A call that this FMU does not offer.
unsafe fn unsupported<M: Model>(c: fmi2Component, call: Call, why: &str) -> fmi2Status {
    enter::<M>(c, call, |_| Err(FmiError::error(format!("{} is not supported: {why}", call.name()))))
}

