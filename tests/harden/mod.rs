//! The C API as an importer sees it, for the hardening tests (threads, panic
//! boundary) and the fuzz harness (`tests/fuzz`, which includes this file).
//!
//! The test binary links the `converting_span` rlib and declares its
//! `#[no_mangle]` `fmi2*` functions here with the signatures of the FMI 2.0
//! headers, so every call goes through the real C entry points. Each
//! instance logs into its own `Log`, passed as `componentEnvironment`: no
//! global state in the tests either.

#![allow(dead_code, non_snake_case, clippy::missing_safety_doc)]

pub use converting_span::fmi2::ffi::{
    fmi2Boolean, fmi2Byte, fmi2CallbackFunctions, fmi2CallbackLogger, fmi2Component,
    fmi2ComponentEnvironment, fmi2EventInfo, fmi2FMUstate, fmi2Integer, fmi2Real, fmi2Status,
    fmi2StatusKind, fmi2String, fmi2Type, fmi2ValueReference,
};
use std::ffi::{c_char, CStr, CString};
use std::sync::Mutex;

pub const OK: i32 = 0;
pub const WARNING: i32 = 1;
pub const DISCARD: i32 = 2;
pub const ERROR: i32 = 3;
pub const FATAL: i32 = 4;
pub const PENDING: i32 = 5;

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

#[rustfmt::skip]
extern "C" {
    pub fn fmi2GetTypesPlatform() -> *const c_char;
    pub fn fmi2GetVersion() -> *const c_char;
    pub fn fmi2SetDebugLogging(c: fmi2Component, on: fmi2Boolean, n: usize, categories: *const fmi2String) -> fmi2Status;
    pub fn fmi2Instantiate(name: fmi2String, fmu_type: fmi2Type, guid: fmi2String, resources: fmi2String,
        functions: *const fmi2CallbackFunctions, visible: fmi2Boolean, logging_on: fmi2Boolean) -> fmi2Component;
    pub fn fmi2FreeInstance(c: fmi2Component);
    pub fn fmi2SetupExperiment(c: fmi2Component, tol_defined: fmi2Boolean, tol: fmi2Real, start: fmi2Real,
        stop_defined: fmi2Boolean, stop: fmi2Real) -> fmi2Status;
    pub fn fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status;
    pub fn fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status;
    pub fn fmi2Terminate(c: fmi2Component) -> fmi2Status;
    pub fn fmi2Reset(c: fmi2Component) -> fmi2Status;
    pub fn fmi2GetReal(c: fmi2Component, vr: *const fmi2ValueReference, n: usize, v: *mut fmi2Real) -> fmi2Status;
    pub fn fmi2GetInteger(c: fmi2Component, vr: *const fmi2ValueReference, n: usize, v: *mut fmi2Integer) -> fmi2Status;
    pub fn fmi2GetBoolean(c: fmi2Component, vr: *const fmi2ValueReference, n: usize, v: *mut fmi2Boolean) -> fmi2Status;
    pub fn fmi2GetString(c: fmi2Component, vr: *const fmi2ValueReference, n: usize, v: *mut fmi2String) -> fmi2Status;
    pub fn fmi2SetReal(c: fmi2Component, vr: *const fmi2ValueReference, n: usize, v: *const fmi2Real) -> fmi2Status;
    pub fn fmi2SetInteger(c: fmi2Component, vr: *const fmi2ValueReference, n: usize, v: *const fmi2Integer) -> fmi2Status;
    pub fn fmi2SetBoolean(c: fmi2Component, vr: *const fmi2ValueReference, n: usize, v: *const fmi2Boolean) -> fmi2Status;
    pub fn fmi2SetString(c: fmi2Component, vr: *const fmi2ValueReference, n: usize, v: *const fmi2String) -> fmi2Status;
    pub fn fmi2GetFMUstate(c: fmi2Component, s: *mut fmi2FMUstate) -> fmi2Status;
    pub fn fmi2SetFMUstate(c: fmi2Component, s: fmi2FMUstate) -> fmi2Status;
    pub fn fmi2FreeFMUstate(c: fmi2Component, s: *mut fmi2FMUstate) -> fmi2Status;
    pub fn fmi2SerializedFMUstateSize(c: fmi2Component, s: fmi2FMUstate, size: *mut usize) -> fmi2Status;
    pub fn fmi2SerializeFMUstate(c: fmi2Component, s: fmi2FMUstate, bytes: *mut fmi2Byte, size: usize) -> fmi2Status;
    pub fn fmi2DeSerializeFMUstate(c: fmi2Component, bytes: *const fmi2Byte, size: usize, s: *mut fmi2FMUstate) -> fmi2Status;
    pub fn fmi2GetDirectionalDerivative(c: fmi2Component, u: *const fmi2ValueReference, nu: usize,
        k: *const fmi2ValueReference, nk: usize, dk: *const fmi2Real, du: *mut fmi2Real) -> fmi2Status;
    pub fn fmi2EnterEventMode(c: fmi2Component) -> fmi2Status;
    pub fn fmi2NewDiscreteStates(c: fmi2Component, info: *mut fmi2EventInfo) -> fmi2Status;
    pub fn fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status;
    pub fn fmi2CompletedIntegratorStep(c: fmi2Component, no_prior: fmi2Boolean, enter: *mut fmi2Boolean,
        terminate: *mut fmi2Boolean) -> fmi2Status;
    pub fn fmi2SetTime(c: fmi2Component, t: fmi2Real) -> fmi2Status;
    pub fn fmi2SetContinuousStates(c: fmi2Component, x: *const fmi2Real, n: usize) -> fmi2Status;
    pub fn fmi2GetDerivatives(c: fmi2Component, dx: *mut fmi2Real, n: usize) -> fmi2Status;
    pub fn fmi2GetEventIndicators(c: fmi2Component, z: *mut fmi2Real, n: usize) -> fmi2Status;
    pub fn fmi2GetContinuousStates(c: fmi2Component, x: *mut fmi2Real, n: usize) -> fmi2Status;
    pub fn fmi2GetNominalsOfContinuousStates(c: fmi2Component, x: *mut fmi2Real, n: usize) -> fmi2Status;
    pub fn fmi2SetRealInputDerivatives(c: fmi2Component, vr: *const fmi2ValueReference, n: usize,
        order: *const fmi2Integer, v: *const fmi2Real) -> fmi2Status;
    pub fn fmi2GetRealOutputDerivatives(c: fmi2Component, vr: *const fmi2ValueReference, n: usize,
        order: *const fmi2Integer, v: *mut fmi2Real) -> fmi2Status;
    pub fn fmi2DoStep(c: fmi2Component, t: fmi2Real, h: fmi2Real, no_prior: fmi2Boolean) -> fmi2Status;
    pub fn fmi2CancelStep(c: fmi2Component) -> fmi2Status;
    pub fn fmi2GetStatus(c: fmi2Component, k: fmi2StatusKind, v: *mut fmi2Status) -> fmi2Status;
    pub fn fmi2GetRealStatus(c: fmi2Component, k: fmi2StatusKind, v: *mut fmi2Real) -> fmi2Status;
    pub fn fmi2GetIntegerStatus(c: fmi2Component, k: fmi2StatusKind, v: *mut fmi2Integer) -> fmi2Status;
    pub fn fmi2GetBooleanStatus(c: fmi2Component, k: fmi2StatusKind, v: *mut fmi2Boolean) -> fmi2Status;
    pub fn fmi2GetStringStatus(c: fmi2Component, k: fmi2StatusKind, v: *mut fmi2String) -> fmi2Status;
}

/// One logged message.
#[derive(Clone, Debug)]
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
    pub fn take(&self) -> Vec<LogLine> {
        std::mem::take(&mut *self.lines.lock().unwrap())
    }
}

unsafe fn text(s: fmi2String) -> Option<String> {
    (!s.is_null()).then(|| CStr::from_ptr(s).to_string_lossy().into_owned())
}

/// The logger: non-variadic, because this FMU passes no variadic arguments
/// (its messages are preformatted, '%' escaped as "%%").
unsafe extern "C" fn logger(
    env: fmi2ComponentEnvironment,
    instance: fmi2String,
    status: fmi2Status,
    category: fmi2String,
    message: fmi2String,
) {
    let log = &*(env as *const Log);
    match (text(instance), text(category), text(message)) {
        (Some(instance), Some(category), Some(message)) if (OK..=PENDING).contains(&status) => {
            // The message went through printf escaping: undo it.
            let message = message.replace("%%", "%");
            log.lines.lock().unwrap().push(LogLine {
                instance,
                status,
                category,
                message,
            })
        }
        other => log
            .malformed
            .lock()
            .unwrap()
            .push(format!("status {status}, strings {other:?}")),
    }
}

/// The callback functions that log into `log`, which must outlive every
/// instance created with them.
pub fn callbacks(log: &Log) -> fmi2CallbackFunctions {
    // SAFETY: a non-variadic function with the fixed arguments of the
    // variadic logger type: the x86-64 and AArch64 C ABIs pass the fixed
    // arguments identically, and the FMU never passes variadic ones.
    let logger: fmi2CallbackLogger = unsafe {
        std::mem::transmute::<
            unsafe extern "C" fn(
                fmi2ComponentEnvironment,
                fmi2String,
                fmi2Status,
                fmi2String,
                fmi2String,
            ),
            fmi2CallbackLogger,
        >(logger)
    };
    fmi2CallbackFunctions {
        logger: Some(logger),
        allocateMemory: None,
        freeMemory: None,
        stepFinished: None,
        componentEnvironment: log as *const Log as fmi2ComponentEnvironment,
    }
}

pub fn guid() -> &'static str {
    <converting_span::ExportedModel as converting_span::fmi2::Model>::description().guid
}

pub fn vr_of(name: &str) -> u32 {
    <converting_span::ExportedModel as converting_span::fmi2::Model>::description()
        .variable_by_name(name)
        .unwrap_or_else(|| panic!("no variable {name}"))
        .vr
}

/// An instance with its own log, freed on drop.
pub struct Fmu {
    pub c: fmi2Component,
    pub log: Box<Log>,
    _functions: Box<fmi2CallbackFunctions>,
}

impl Fmu {
    pub fn new(name: &str) -> Fmu {
        let log = Box::<Log>::default();
        let functions = Box::new(callbacks(&log));
        let name = CString::new(name).unwrap();
        let guid = CString::new(guid()).unwrap();
        let c = unsafe {
            fmi2Instantiate(
                name.as_ptr(),
                1,
                guid.as_ptr(),
                std::ptr::null(),
                &*functions,
                0,
                0,
            )
        };
        assert!(!c.is_null(), "fmi2Instantiate failed: {:?}", log.take());
        Fmu {
            c,
            log,
            _functions: functions,
        }
    }

    pub fn set_real(&self, name: &str, x: f64) -> i32 {
        unsafe { fmi2SetReal(self.c, &vr_of(name), 1, &x) }
    }

    pub fn get_real(&self, name: &str) -> (i32, f64) {
        let mut x = f64::NAN;
        let status = unsafe { fmi2GetReal(self.c, &vr_of(name), 1, &mut x) };
        (status, x)
    }

    pub fn get_reals(&self, vrs: &[u32]) -> (i32, Vec<f64>) {
        let mut x = vec![f64::NAN; vrs.len()];
        let status = unsafe { fmi2GetReal(self.c, vrs.as_ptr(), vrs.len(), x.as_mut_ptr()) };
        (status, x)
    }

    /// setupExperiment at t = 0, enter and exit initialization mode.
    pub fn initialize(&self) -> i32 {
        unsafe {
            let s = fmi2SetupExperiment(self.c, 0, 0.0, 0.0, 0, 0.0);
            if s != OK {
                return s;
            }
            let s = fmi2EnterInitializationMode(self.c);
            if s != OK {
                return s;
            }
            fmi2ExitInitializationMode(self.c)
        }
    }

    pub fn do_step(&self, t: f64, h: f64) -> i32 {
        unsafe { fmi2DoStep(self.c, t, h, 1) }
    }

    pub fn messages(&self) -> Vec<String> {
        self.log
            .lines
            .lock()
            .unwrap()
            .iter()
            .map(|l| l.message.clone())
            .collect()
    }
}

impl Drop for Fmu {
    fn drop(&mut self) {
        unsafe { fmi2FreeInstance(self.c) }
    }
}

// SAFETY: an instance is used by one thread at a time (the `Fmu` is moved,
// not shared), which is what FMI 2.0 asks of importers.
unsafe impl Send for Fmu {}
