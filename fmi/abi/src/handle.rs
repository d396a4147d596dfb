//! What an instance pointer points to, for FMI 2.0 and FMI 3.0 alike, and
//! the one entry path of every export that takes an instance. That path
//!
//! * turns the pointer into a reference, refusing NULL and pointers that do
//!   not carry this standard's tag (an FMI 2.0 instance has another than an
//!   FMI 3.0 one, so neither API takes the other's), and the importer's other
//!   pointers into slices, references and texts (`slice`, `out_ref`, `text`, …)
//!   whose errors name the call and the argument,
//! * catches panics, so that none crosses `extern "C"`, and poisons the
//!   instance that panicked (only the reset and the free are accepted then),
//! * checks the call against the state machine of its standard,
//! * turns an error into a status plus one log line.
//!
//! `Box::into_raw`/`Box::from_raw` of instances happen here and nowhere else.

use crate::library::LibraryRef;
use crate::state_store::StateStore;
use fmi_core::instance::Instance;
use fmi_core::logging::Log;
use fmi_core::snapshot::Snapshot;
use fmi_core::standard::{Call, Standard};
use fmi_core::{FmiError, FmiResult, Model, Resources, Status};
use std::ffi::{c_char, c_int, c_void, CStr, CString};
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The tag at the start of every instance: "CONVSPAN" for FMI 2.0, "CONVSPN3" for FMI 3.0.
const fn tag(standard: Standard) -> u64 {
    match standard {
        Standard::Fmi2 => 0x434f_4e56_5350_414e,
        Standard::Fmi3 => 0x434f_4e56_5350_4e33,
    }
}

/// What an instance pointer points to: the instance plus the FMU states it
/// has handed out (so that a foreign or freed state is refused, not used).
#[repr(C)]
pub struct Handle<M: Model> {
    tag: u64,
    pub instance: Instance<M>,
    states: StateStore<M>,
    /// The texts the last get of Strings returned: valid until the next call.
    strings: Vec<CString>,
    /// Set when a panic was caught inside a call: the instance may be half
    /// updated, so only the reset and the free are accepted until a reset succeeds.
    poisoned: bool,
    /// Keeps this library loaded while the instance lives, whatever the importer unloads.
    _library: LibraryRef,
}

impl<M: Model> Handle<M> {
    /// The state `state` points to, if this instance handed it out.
    pub fn own_state(&self, call: impl Call, state: *mut c_void) -> FmiResult<&Snapshot<M>> {
        self.states.get(call.name(), state)
    }

    /// Stores `snapshot` in the importer's slot `*slot` (`what`: the argument's name).
    pub fn keep_state(&mut self, call: impl Call, slot: *mut *mut c_void, what: &str, snapshot: Snapshot<M>) -> FmiResult {
        let slot = out_ref(call, slot, what)?;
        self.states.keep(call.name(), what, slot, snapshot)
    }

    pub fn free_state(&mut self, call: impl Call, slot: *mut *mut c_void, what: &str) -> FmiResult {
        let slot = out_ref(call, slot, what)?;
        self.states.free(call.name(), slot)
    }

    /// Copies the texts into the handle and the pointers into `out`: they
    /// stay valid until the next call replaces them.
    pub fn hand_out_strings(&mut self, texts: Vec<CString>, out: &mut [*const std::ffi::c_char]) {
        self.strings = texts;
        for (slot, s) in out.iter_mut().zip(&self.strings) {
            *slot = s.as_ptr();
        }
    }
}

impl<M: Model> Drop for Handle<M> {
    fn drop(&mut self) {
        self.tag = 0;
    }
}

/// What instantiation was asked for, copied out of the importer's arguments.
pub struct Request<'a> {
    pub standard: Standard,
    /// The C function, for messages.
    pub function: &'static str,
    pub instance_name: &'a str,
    pub model_exchange: bool,
    /// The GUID (FMI 2.0) or instantiation token (FMI 3.0); `None` for NULL.
    pub token: Option<String>,
    /// What the standard calls the token in messages: "GUID" or "instantiationToken".
    pub token_name: &'static str,
    pub resources: Resources,
    pub logging_on: bool,
}

/// The model an instantiation asks for, at its start values (its interface
/// read from the FMU's resources where it comes with them), or the one line
/// that says why there is none.
pub fn model_of<M: Model>(request: &Request, logger: &dyn Log) -> Option<M> {
    let resources = request.resources.clone().for_instance(request.instance_name);
    match catch_unwind(AssertUnwindSafe(|| M::instantiate(&resources))) {
        Ok(Ok(model)) => Some(model),
        Ok(Err(error)) => {
            refuse(logger, &format!("{}: {}", request.function, error.message));
            None
        }
        Err(_) => None,
    }
}

/// One error line where no instance exists to report it (instantiation refused); no panic
/// of the importer's logger crosses back.
pub fn refuse(logger: &dyn Log, message: &str) {
    let _ = catch_unwind(AssertUnwindSafe(|| logger.log(Status::Error, "logStatusError", message)));
}

/// A new instance of `model`, or NULL after one log line saying why; no panic crosses.
pub fn instantiate<M: Model>(request: Request, logger: Box<dyn Log>, model: M) -> *mut c_void {
    let created = catch_unwind(AssertUnwindSafe(|| {
        let description = model.description();
        let refuse = |message: String| {
            logger.log(Status::Error, "logStatusError", &format!("{}: {message}", request.function));
            None
        };
        if request.model_exchange && !description.model_exchange {
            return refuse(format!("{} offers only Co-Simulation", description.model_identifier));
        }
        match &request.token {
            Some(t) if *t == description.guid => {}
            other => {
                let given = other.as_ref().map_or("NULL".to_string(), |t| format!("\"{t}\""));
                return refuse(format!(
                    "{} {given} does not match this FMU's {} (the modelDescription.xml and the binary differ)",
                    request.token_name, description.guid
                ));
            }
        }
        Some(request.resources.clone().for_instance(request.instance_name))
    }));
    let Ok(Some(resources)) = created else { return std::ptr::null_mut() };
    let made = catch_unwind(AssertUnwindSafe(|| {
        let instance = Instance::<M>::new(logger, request.standard, request.logging_on, request.model_exchange, resources, model);
        Box::new(Handle {
            tag: tag(request.standard),
            instance,
            states: StateStore::default(),
            strings: Vec::new(),
            poisoned: false,
            _library: LibraryRef::acquire(),
        })
    }));
    made.map_or(std::ptr::null_mut(), |handle| Box::into_raw(handle) as *mut c_void)
}

/// Frees an instance of `standard`; anything else is ignored.
pub unsafe fn free<M: Model>(c: *mut c_void, standard: Standard) {
    if handle::<M>(c, standard).is_some() {
        let _ = catch_unwind(|| drop(Box::from_raw(c as *mut Handle<M>)));
    }
}

unsafe fn handle<'a, M: Model>(c: *mut c_void, standard: Standard) -> Option<&'a mut Handle<M>> {
    let handle = (c as *mut Handle<M>).as_mut()?;
    (handle.tag == tag(standard)).then_some(handle)
}

/// The entry path of every function that takes an instance.
#[inline(always)]
pub unsafe fn enter<M: Model, C: Call>(c: *mut c_void, call: C, body: impl FnOnce(&mut Handle<M>) -> FmiResult) -> c_int {
    let Some(handle) = handle::<M>(c, C::STANDARD) else { return Status::Error as c_int };
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        if handle.poisoned && !call.is_allowed_when_poisoned() {
            return Err(poisoned(call, C::STANDARD));
        }
        handle.instance.begin(call)?;
        body(&mut *handle)
    }));
    let status = match outcome {
        Ok(Ok(())) => {
            if call.is_reset() {
                handle.poisoned = false;
            }
            Status::Ok
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
    status as c_int
}

#[cold]
fn poisoned(call: impl Call, standard: Standard) -> FmiError {
    let (reset, free) = match standard {
        Standard::Fmi2 => ("fmi2Reset", "fmi2FreeInstance"),
        Standard::Fmi3 => ("fmi3Reset", "fmi3FreeInstance"),
    };
    FmiError::error(format!(
        "{}: refused: an internal error (a panic) in an earlier call may have left the instance \
         half updated; only {reset} or {free} are accepted now",
        call.name()
    ))
}

/// A call that this FMU does not offer, refused with the reason.
pub unsafe fn unsupported<M: Model, C: Call>(c: *mut c_void, call: C, why: &str) -> c_int {
    enter::<M, C>(c, call, |_| Err(FmiError::error(format!("{} is not supported: {why}", call.name()))))
}

// ---- The importer's other pointers

/// `n` elements from the importer; NULL is fine only for `n == 0`.
#[inline]
pub unsafe fn slice<'a, T>(call: impl Call, ptr: *const T, n: usize, what: &str) -> FmiResult<&'a [T]> {
    if n == 0 {
        Ok(&[])
    } else if ptr.is_null() {
        Err(null_argument(call, what))
    } else {
        Ok(std::slice::from_raw_parts(ptr, n))
    }
}

#[inline]
pub unsafe fn slice_mut<'a, T>(call: impl Call, ptr: *mut T, n: usize, what: &str) -> FmiResult<&'a mut [T]> {
    if n == 0 {
        Ok(&mut [])
    } else if ptr.is_null() {
        Err(null_argument(call, what))
    } else {
        Ok(std::slice::from_raw_parts_mut(ptr, n))
    }
}

#[inline]
pub fn out_ref<'a, T>(call: impl Call, ptr: *mut T, what: &str) -> FmiResult<&'a mut T> {
    // SAFETY: the importer passes a valid pointer or NULL, as the standard requires.
    unsafe { ptr.as_mut() }.ok_or_else(|| null_argument(call, what))
}

#[cold]
pub fn null_argument(call: impl Call, what: &str) -> FmiError {
    FmiError::error(format!("{}: {what} is NULL", call.name()))
}

/// Element `i` of the String array `what`: `Ok(None)` for NULL, an error for bytes that are not UTF-8.
pub unsafe fn utf8<'a>(call: impl Call, s: *const c_char, what: &str, i: usize) -> FmiResult<Option<&'a str>> {
    if s.is_null() {
        return Ok(None);
    }
    CStr::from_ptr(s)
        .to_str()
        .map(Some)
        .map_err(|_| FmiError::error(format!("{}: {what}[{i}] is not UTF-8 text", call.name())))
}

/// A copy of a C string (lossy UTF-8); `None` for NULL.
pub unsafe fn text(s: *const c_char) -> Option<String> {
    (!s.is_null()).then(|| CStr::from_ptr(s).to_string_lossy().into_owned())
}

/// A C string with any interior NUL dropped.
pub fn c_text(s: &str) -> CString {
    CString::new(s.replace('\0', "")).expect("NULs removed")
}
