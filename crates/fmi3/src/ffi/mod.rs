//! The only unsafe code of the crate: the C types of the FMI 3.0 headers,
//! the exported functions (in `calls`, exported by `exports`), and the one
//! entry path every one of them goes through. As in the FMI 2.0 layer, that path
//!
//! * turns the `fmi3Instance` into a reference, refusing NULL and pointers
//!   that do not carry this layer's tag (an FMI 2.0 instance has another),
//! * catches panics and poisons the instance that panicked,
//! * checks the call against the state machine (`call`),
//! * turns an error into an `fmi3Status` plus one log line.
//!
//! Raw pointers become slices and references here and nowhere else;
//! `Box::into_raw`/`Box::from_raw` appear only in this module.

#![allow(non_camel_case_types, non_snake_case, non_upper_case_globals)]

#[doc(hidden)]
pub mod calls;
mod exports;

use crate::call::{state_name, Call};

impl CallName for Call {
    fn name(self) -> &'static str {
        Call::name(self)
    }
}
use fmi2::phase::Phase;
use fmi2::instance::Instance;
use fmi2::logging::Log;
use fmi2::snapshot::Snapshot;
use fmi2::ffi::raw::{out_ref, slice, slice_mut, text, utf8, CallName};
use fmi2::ffi::state_store::StateStore;
use fmi2::{FmiError, FmiResult, Model, Resources, Status};
#[doc(hidden)]
pub use calls::*;
use std::ffi::{c_char, c_int, c_void, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

pub type fmi3Instance = *mut c_void;
pub type fmi3InstanceEnvironment = *mut c_void;
pub type fmi3FMUState = *mut c_void;
pub type fmi3ValueReference = u32;
pub type fmi3Float32 = f32;
pub type fmi3Float64 = f64;
pub type fmi3Int8 = i8;
pub type fmi3UInt8 = u8;
pub type fmi3Int16 = i16;
pub type fmi3UInt16 = u16;
pub type fmi3Int32 = i32;
pub type fmi3UInt32 = u32;
pub type fmi3Int64 = i64;
pub type fmi3UInt64 = u64;
/// C `bool`: taken as a byte, so that a value other than 0 or 1 from the importer is an error, not UB.
pub type fmi3Boolean = u8;
pub type fmi3Char = c_char;
pub type fmi3String = *const c_char;
pub type fmi3Byte = u8;
pub type fmi3Binary = *const u8;
pub type fmi3Clock = u8;
/// `fmi3Status`, `fmi3DependencyKind` and `fmi3IntervalQualifier` are C
/// enums: taken as plain integers so that an out-of-range value is not UB.
pub type fmi3Status = c_int;
pub type fmi3DependencyKind = c_int;
pub type fmi3IntervalQualifier = c_int;

const fmi3Error: fmi3Status = Status::Error as fmi3Status;

pub type fmi3LogMessageCallback =
    unsafe extern "C" fn(fmi3InstanceEnvironment, fmi3Status, fmi3String, fmi3String);
pub type fmi3IntermediateUpdateCallback = unsafe extern "C" fn(
    fmi3InstanceEnvironment,
    fmi3Float64,
    fmi3Boolean,
    fmi3Boolean,
    fmi3Boolean,
    fmi3Boolean,
    *mut fmi3Boolean,
    *mut fmi3Float64,
);
pub type fmi3ClockUpdateCallback = unsafe extern "C" fn(fmi3InstanceEnvironment);
pub type fmi3LockPreemptionCallback = unsafe extern "C" fn();
pub type fmi3UnlockPreemptionCallback = unsafe extern "C" fn();

/// The importer's logger and environment, from the instantiate call.
pub struct Logger {
    callback: Option<fmi3LogMessageCallback>,
    environment: fmi3InstanceEnvironment,
}

impl Log for Logger {
    fn log(&self, status: Status, category: &str, message: &str) {
        let Some(callback) = self.callback else { return };
        // FMI 3.0's logger is not variadic: the message goes as it is.
        let (category, message) = (c_text(category), c_text(message));
        // SAFETY: the importer handed us this callback for the instance's lifetime.
        unsafe { callback(self.environment, status as fmi3Status, category.as_ptr(), message.as_ptr()) }
    }
}

/// A C string with any interior NUL dropped.
fn c_text(s: &str) -> CString {
    CString::new(s.replace('\0', "")).expect("NULs removed")
}

/// Tag at the start of every instance this layer hands out ("CONVSPN3"):
/// differs from the FMI 2.0 layer's, so that neither takes the other's.
const TAG: u64 = 0x434f_4e56_5350_4e33;

/// What an `fmi3Instance` points to: the FMI 2.0 layer's instance (the
/// model, its checks, time and logging), the FMU states it handed out, and
/// which interface it serves.
#[repr(C)]
struct Handle<M: Model> {
    tag: u64,
    instance: Instance<M>,
    model_exchange: bool,
    states: StateStore<M>,
    /// The texts `fmi3GetString` last returned: they stay valid until the next call.
    strings: Vec<CString>,
    /// A panic was caught inside a call: only `fmi3Reset` and `fmi3FreeInstance` now.
    poisoned: bool,
}

impl<M: Model> Handle<M> {
    fn own_state(&self, call: Call, state: fmi3FMUState) -> FmiResult<&Snapshot<M>> {
        self.states.get(call.name(), state)
    }

    fn keep_state(&mut self, call: Call, slot: *mut fmi3FMUState, snapshot: Snapshot<M>) -> FmiResult {
        let slot = out_ref(call, slot, "FMUState")?;
        self.states.keep(call.name(), "FMUState", slot, snapshot)
    }

    fn free_state(&mut self, call: Call, slot: *mut fmi3FMUState) -> FmiResult {
        let slot = out_ref(call, slot, "FMUState")?;
        self.states.free(call.name(), slot)
    }
}

impl<M: Model> Drop for Handle<M> {
    fn drop(&mut self) {
        self.tag = 0;
    }
}

/// `fmi3InstantiateModelExchange` and `fmi3InstantiateCoSimulation`: checks
/// the interface and the instantiation token; no panic crosses the boundary.
unsafe fn instantiate<M: Model>(
    model_exchange: bool,
    instance_name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    logging_on: fmi3Boolean,
    environment: fmi3InstanceEnvironment,
    log_message: Option<fmi3LogMessageCallback>,
) -> fmi3Instance {
    let checked = || {
        let logger = Logger { callback: log_message, environment };
        let description = M::description();
        let name = if model_exchange { "fmi3InstantiateModelExchange" } else { "fmi3InstantiateCoSimulation" };
        let refuse = |message: String| {
            logger.log(Status::Error, "logStatusError", &format!("{name}: {message}"));
            std::ptr::null_mut()
        };
        if model_exchange && !description.model_exchange {
            return refuse(format!("{} offers only Co-Simulation", description.model_identifier));
        }
        match text(token) {
            Some(t) if t == description.guid => {}
            other => {
                let given = other.map_or("NULL".to_string(), |t| format!("\"{t}\""));
                return refuse(format!(
                    "instantiationToken {given} does not match this FMU's {} (the modelDescription.xml and the binary differ)",
                    description.guid
                ));
            }
        }
        // FMI 3.0 passes the resources folder as a path, not a URI; the instance
        // name finds the instance's own profile there.
        let instance_name = text(instance_name).unwrap_or_default();
        let resources = Resources::from_path(text(resource_path).as_deref()).for_instance(&instance_name);
        let instance = Instance::<M>::new(Box::new(logger), logging_on != 0, model_exchange, resources);
        let handle =
            Handle { tag: TAG, instance, model_exchange, states: StateStore::default(), strings: Vec::new(), poisoned: false };
        Box::into_raw(Box::new(handle)) as fmi3Instance
    };
    catch_unwind(AssertUnwindSafe(checked)).unwrap_or(std::ptr::null_mut())
}

/// `fmi3InstantiateScheduledExecution`: this FMU offers no Scheduled Execution.
unsafe fn refuse_scheduled_execution(environment: fmi3InstanceEnvironment, log_message: Option<fmi3LogMessageCallback>) -> fmi3Instance {
    let logger = Logger { callback: log_message, environment };
    let _ = catch_unwind(AssertUnwindSafe(|| {
        logger.log(
            Status::Error,
            "logStatusError",
            "fmi3InstantiateScheduledExecution: this FMU offers Model Exchange and Co-Simulation, not Scheduled Execution",
        )
    }));
    std::ptr::null_mut()
}

/// `fmi3FreeInstance`.
unsafe fn free_instance<M: Model>(c: fmi3Instance) {
    if handle::<M>(c).is_some() {
        let _ = catch_unwind(|| drop(Box::from_raw(c as *mut Handle<M>)));
    }
}

unsafe fn handle<'a, M: Model>(c: fmi3Instance) -> Option<&'a mut Handle<M>> {
    let handle = (c as *mut Handle<M>).as_mut()?;
    (handle.tag == TAG).then_some(handle)
}

/// The entry path of every function that takes an instance.
unsafe fn enter<M: Model>(c: fmi3Instance, call: Call, body: impl FnOnce(&mut Handle<M>) -> FmiResult) -> fmi3Status {
    let Some(handle) = handle::<M>(c) else { return fmi3Error };
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        if handle.poisoned && !call.is_allowed_when_poisoned() {
            return Err(FmiError::error(format!(
                "{}: refused: an internal error (a panic) in an earlier call may have left the instance \
                 half updated; only fmi3Reset or fmi3FreeInstance are accepted now",
                call.name()
            )));
        }
        handle.instance.log(Status::Ok, "logAll", call.name());
        if let Some(why) = call.refusal(handle.instance.phase(), handle.model_exchange) {
            return Err(FmiError::error(why));
        }
        body(&mut *handle)
    }));
    let status = match outcome {
        Ok(Ok(())) => {
            if call == Call::Reset {
                handle.poisoned = false;
            }
            Status::Ok
        }
        Ok(Err(error)) => handle.instance.fail(in_fmi3_words(call, error)),
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
    status as fmi3Status
}

/// The shared instance names its FMI 2.0 function first in a message
/// (`fmi2DoStep at t = ..`, `fmi2SetReal: ..`) and its phases in FMI 2.0's
/// words: the importer sees the fmi3 call and FMI 3.0's states instead.
#[cold]
fn in_fmi3_words(call: Call, mut error: FmiError) -> FmiError {
    if error.message.starts_with("fmi2") {
        let end = error.message.find([':', ' ']).unwrap_or(error.message.len());
        error.message.replace_range(..end, call.name());
    }
    for phase in Phase::ALL {
        error.message = error.message.replace(&format!("the state \"{}\"", phase.name()), state_name(phase));
    }
    error
}

/// A call that this FMU does not offer: refused with the reason.
unsafe fn unsupported<M: Model>(c: fmi3Instance, call: Call, why: &str) -> fmi3Status {
    enter::<M>(c, call, |_| Err(FmiError::error(format!("{} is not supported: {why}", call.name()))))
}

