//! The two C APIs the harness drives, FMI 2.0 and FMI 3.0, behind one set of
//! calls shaped like FMI 2.0's: the oracle in lib.rs is written once. Where
//! FMI 3.0 has arguments of its own (the number of values of a get or set,
//! doStep's out-arguments) the call takes them and FMI 2.0 ignores them.
//!
//! FMI 3.0 calls go straight to the `#[no_mangle]` functions that
//! `fmi_abi::export_fmi3!` writes into the fuzzed model's crate: the C entry
//! points, declared by the test kit from the same list of signatures.

use fmi_testkit::fmi3 as c3;
use fmi_testkit::*;
use std::ffi::{c_char, c_void};
use std::ptr::null_mut;

/// An instance of either API (`fmi2Component`, `fmi3Instance`).
pub type Instance = *mut c_void;
pub type State = *mut c_void;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Api {
    Fmi2,
    Fmi3,
}

/// FMI 3.0's integer functions: Int32 for Integer variables, Int64 for enumerations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Int {
    Int32,
    Int64,
}

/// FMI 3.0's logger has no instance name: the lines it records name none.
unsafe extern "C" fn capture3(env: *mut c_void, status: i32, category: *const c_char, message: *const c_char) {
    let Some(log) = (env as *const Log).as_ref() else { return };
    let text = |s: *const c_char| {
        (!s.is_null()).then(|| std::ffi::CStr::from_ptr(s).to_string_lossy().into_owned())
    };
    let (cat, msg) = (text(category), text(message));
    if cat.is_none() || msg.is_none() || !(OK..=PENDING).contains(&status) {
        log.malformed.lock().unwrap().push(format!("status {status}, strings {:?}", (cat.clone(), msg.clone())));
    }
    let line = LogLine {
        instance: String::new(),
        status,
        category: cat.unwrap_or_default(),
        message: msg.unwrap_or_default(),
    };
    log.lines.lock().unwrap().push(line);
}

/// What fmi2NewDiscreteStates (fmi3UpdateDiscreteStates) answers that the harness uses.
#[derive(Clone, Copy, Debug, Default)]
pub struct Discrete {
    /// newDiscreteStatesNeeded (discreteStatesNeedUpdate): iterate again.
    pub needed: bool,
    pub terminate: bool,
    pub next_event: Option<f64>,
}

/// What `fmi3Instantiate*` is called with.
pub struct Instantiate3<'a> {
    pub model_exchange: bool,
    pub name: *const c_char,
    pub token: *const c_char,
    pub resource_path: *const c_char,
    pub logging_on: bool,
    pub event_mode_used: bool,
    pub required: &'a [u32],
    pub log: Option<&'a Log>,
}

pub unsafe fn instantiate3(a: &Instantiate3) -> Instance {
    let env = a.log.map_or(null_mut(), |l| l as *const Log as *mut c_void);
    let logger = a.log.map(|_| capture3 as unsafe extern "C" fn(_, _, _, _));
    if a.model_exchange {
        c3::fmi3InstantiateModelExchange(a.name, a.token, a.resource_path, 0, a.logging_on as u8, env, logger)
    } else {
        let required = if a.required.is_empty() { std::ptr::null() } else { a.required.as_ptr() };
        c3::fmi3InstantiateCoSimulation(
            a.name,
            a.token,
            a.resource_path,
            0,
            a.logging_on as u8,
            a.event_mode_used as u8,
            0,
            required,
            a.required.len(),
            env,
            logger,
            None,
        )
    }
}

impl Api {
    /// The C name of a call in this API.
    pub fn name(self, fmi2: &'static str, fmi3: &'static str) -> &'static str {
        match self {
            Api::Fmi2 => fmi2,
            Api::Fmi3 => fmi3,
        }
    }

    pub unsafe fn free_instance(self, c: Instance) {
        match self {
            Api::Fmi2 => fmi2FreeInstance(c),
            Api::Fmi3 => c3::fmi3FreeInstance(c),
        }
    }

    pub unsafe fn set_debug_logging(self, c: Instance, on: i32, n: usize, cats: *const *const c_char) -> i32 {
        match self {
            Api::Fmi2 => fmi2SetDebugLogging(c, on, n, cats),
            Api::Fmi3 => c3::fmi3SetDebugLogging(c, (on != 0) as u8, n, cats),
        }
    }

    /// FMI 2.0's fmi2EnterInitializationMode; FMI 3.0's with the experiment
    /// `(tolerance, start, stop)` that FMI 2.0 sets in fmi2SetupExperiment.
    pub unsafe fn enter_init(self, c: Instance, experiment: (i32, f64, f64, i32, f64)) -> i32 {
        let (tol_def, tol, start, stop_def, stop) = experiment;
        match self {
            Api::Fmi2 => fmi2EnterInitializationMode(c),
            Api::Fmi3 => c3::fmi3EnterInitializationMode(c, (tol_def != 0) as u8, tol, start, (stop_def != 0) as u8, stop),
        }
    }

    pub unsafe fn exit_init(self, c: Instance) -> i32 {
        match self {
            Api::Fmi2 => fmi2ExitInitializationMode(c),
            Api::Fmi3 => c3::fmi3ExitInitializationMode(c),
        }
    }

    pub unsafe fn terminate(self, c: Instance) -> i32 {
        match self {
            Api::Fmi2 => fmi2Terminate(c),
            Api::Fmi3 => c3::fmi3Terminate(c),
        }
    }

    pub unsafe fn reset(self, c: Instance) -> i32 {
        match self {
            Api::Fmi2 => fmi2Reset(c),
            Api::Fmi3 => c3::fmi3Reset(c),
        }
    }

    pub unsafe fn get_real(self, c: Instance, vr: *const u32, n: usize, v: *mut f64, nv: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2GetReal(c, vr, n, v),
            Api::Fmi3 => c3::fmi3GetFloat64(c, vr, n, v, nv),
        }
    }

    pub unsafe fn set_real(self, c: Instance, vr: *const u32, n: usize, v: *const f64, nv: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2SetReal(c, vr, n, v),
            Api::Fmi3 => c3::fmi3SetFloat64(c, vr, n, v, nv),
        }
    }

    /// Integers: FMI 3.0 through `int`, the values widened to Int64 there.
    pub unsafe fn get_integer(self, int: Int, c: Instance, vr: *const u32, n: usize, v: *mut i32, nv: usize) -> i32 {
        match (self, int) {
            (Api::Fmi2, _) => fmi2GetInteger(c, vr, n, v),
            (Api::Fmi3, Int::Int32) => c3::fmi3GetInt32(c, vr, n, v, nv),
            (Api::Fmi3, Int::Int64) => {
                let mut wide = vec![i64::MIN; n];
                let out = if v.is_null() { null_mut() } else { wide.as_mut_ptr() };
                let s = c3::fmi3GetInt64(c, vr, n, out, nv);
                if !v.is_null() {
                    for (k, x) in wide.iter().enumerate() {
                        // Out of range shows as i32::MIN, which no enumeration has.
                        *v.add(k) = i32::try_from(*x).unwrap_or(i32::MIN);
                    }
                }
                s
            }
        }
    }

    pub unsafe fn set_integer(self, int: Int, c: Instance, vr: *const u32, n: usize, v: *const i64, nv: usize) -> i32 {
        match (self, int) {
            (Api::Fmi2, _) => {
                let narrow: Vec<i32> = (0..n).map(|k| if v.is_null() { 0 } else { *v.add(k) as i32 }).collect();
                fmi2SetInteger(c, vr, n, if v.is_null() { std::ptr::null() } else { narrow.as_ptr() })
            }
            (Api::Fmi3, Int::Int32) => {
                let narrow: Vec<i32> = (0..n).map(|k| if v.is_null() { 0 } else { *v.add(k) as i32 }).collect();
                c3::fmi3SetInt32(c, vr, n, if v.is_null() { std::ptr::null() } else { narrow.as_ptr() }, nv)
            }
            (Api::Fmi3, Int::Int64) => c3::fmi3SetInt64(c, vr, n, v, nv),
        }
    }

    /// Booleans come back as 0 or 1 in an i32 (FMI 3.0's bytes widened).
    pub unsafe fn get_boolean(self, c: Instance, vr: *const u32, n: usize, v: *mut i32, nv: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2GetBoolean(c, vr, n, v),
            Api::Fmi3 => {
                let mut bytes = vec![0xa5u8; n];
                let out = if v.is_null() { null_mut() } else { bytes.as_mut_ptr() };
                let s = c3::fmi3GetBoolean(c, vr, n, out, nv);
                if !v.is_null() {
                    for (k, b) in bytes.iter().enumerate() {
                        *v.add(k) = *b as i32;
                    }
                }
                s
            }
        }
    }

    /// Booleans as given: FMI 3.0 passes the low byte (what a C caller's
    /// `bool` holding garbage looks like).
    pub unsafe fn set_boolean(self, c: Instance, vr: *const u32, n: usize, v: *const i32, nv: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2SetBoolean(c, vr, n, v),
            Api::Fmi3 => {
                let bytes: Vec<u8> = (0..n).map(|k| if v.is_null() { 0 } else { *v.add(k) as u8 }).collect();
                c3::fmi3SetBoolean(c, vr, n, if v.is_null() { std::ptr::null() } else { bytes.as_ptr() }, nv)
            }
        }
    }

    /// What a Boolean value means to the FMU: FMI 3.0 sees only its low byte.
    pub fn boolean_value(self, x: i32) -> i32 {
        match self {
            Api::Fmi2 => x,
            Api::Fmi3 => x as u8 as i32,
        }
    }

    pub unsafe fn get_string(self, c: Instance, vr: *const u32, n: usize, v: *mut *const c_char, nv: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2GetString(c, vr, n, v),
            Api::Fmi3 => c3::fmi3GetString(c, vr, n, v, nv),
        }
    }

    pub unsafe fn set_string(self, c: Instance, vr: *const u32, n: usize, v: *const *const c_char, nv: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2SetString(c, vr, n, v),
            Api::Fmi3 => c3::fmi3SetString(c, vr, n, v, nv),
        }
    }

    pub unsafe fn get_state(self, c: Instance, s: *mut State) -> i32 {
        match self {
            Api::Fmi2 => fmi2GetFMUstate(c, s),
            Api::Fmi3 => c3::fmi3GetFMUState(c, s),
        }
    }

    pub unsafe fn set_state(self, c: Instance, s: State) -> i32 {
        match self {
            Api::Fmi2 => fmi2SetFMUstate(c, s),
            Api::Fmi3 => c3::fmi3SetFMUState(c, s),
        }
    }

    pub unsafe fn free_state(self, c: Instance, s: *mut State) -> i32 {
        match self {
            Api::Fmi2 => fmi2FreeFMUstate(c, s),
            Api::Fmi3 => c3::fmi3FreeFMUState(c, s),
        }
    }

    pub unsafe fn state_size(self, c: Instance, s: State, size: *mut usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2SerializedFMUstateSize(c, s, size),
            Api::Fmi3 => c3::fmi3SerializedFMUStateSize(c, s, size),
        }
    }

    pub unsafe fn serialize(self, c: Instance, s: State, bytes: *mut u8, size: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2SerializeFMUstate(c, s, bytes as *mut c_char, size),
            Api::Fmi3 => c3::fmi3SerializeFMUState(c, s, bytes, size),
        }
    }

    pub unsafe fn deserialize(self, c: Instance, bytes: *const u8, size: usize, s: *mut State) -> i32 {
        match self {
            Api::Fmi2 => fmi2DeSerializeFMUstate(c, bytes as *const c_char, size, s),
            Api::Fmi3 => c3::fmi3DeserializeFMUState(c, bytes, size, s),
        }
    }

    /// A step; FMI 3.0 also answers the flags (eventHandlingNeeded,
    /// terminateSimulation, earlyReturn) and lastSuccessfulTime, or is given
    /// NULL for them when `null_outs`.
    pub unsafe fn do_step(self, c: Instance, t: f64, h: f64, no_prior: i32, null_outs: bool) -> (i32, Option<([u8; 3], f64)>) {
        match self {
            Api::Fmi2 => (fmi2DoStep(c, t, h, no_prior), None),
            Api::Fmi3 => {
                let (mut flags, mut reached) = ([0xa5u8; 3], f64::NAN);
                let [a, b, e] = &mut flags;
                let (a, b, e, t_out) = if null_outs {
                    (null_mut(), null_mut(), null_mut(), null_mut())
                } else {
                    (a as *mut u8, b as *mut u8, e as *mut u8, &mut reached as *mut f64)
                };
                let s = c3::fmi3DoStep(c, t, h, (no_prior != 0) as u8, a, b, e, t_out);
                (s, Some((flags, reached)))
            }
        }
    }

    // Model Exchange, for the harness's integrator (model_exchange.rs).

    pub unsafe fn enter_event_mode(self, c: Instance) -> i32 {
        match self {
            Api::Fmi2 => fmi2EnterEventMode(c),
            Api::Fmi3 => c3::fmi3EnterEventMode(c),
        }
    }

    /// fmi2NewDiscreteStates (fmi3UpdateDiscreteStates): the status and what it answered.
    pub unsafe fn new_discrete_states(self, c: Instance) -> (i32, Discrete) {
        match self {
            Api::Fmi2 => {
                let mut info = fmi2EventInfo::default();
                let s = fmi2NewDiscreteStates(c, &mut info);
                let d = Discrete {
                    needed: info.newDiscreteStatesNeeded != 0,
                    terminate: info.terminateSimulation != 0,
                    next_event: (info.nextEventTimeDefined != 0).then_some(info.nextEventTime),
                };
                (s, d)
            }
            Api::Fmi3 => {
                let (mut flags, mut next) = ([0xa5u8; 5], f64::NAN);
                let [a, b, e, d, g] = &mut flags;
                let s = c3::fmi3UpdateDiscreteStates(c, a, b, e, d, g, &mut next);
                (s, Discrete { needed: flags[0] != 0, terminate: flags[1] != 0, next_event: (flags[4] != 0).then_some(next) })
            }
        }
    }

    pub unsafe fn enter_continuous_time_mode(self, c: Instance) -> i32 {
        match self {
            Api::Fmi2 => fmi2EnterContinuousTimeMode(c),
            Api::Fmi3 => c3::fmi3EnterContinuousTimeMode(c),
        }
    }

    pub unsafe fn set_time(self, c: Instance, t: f64) -> i32 {
        match self {
            Api::Fmi2 => fmi2SetTime(c, t),
            Api::Fmi3 => c3::fmi3SetTime(c, t),
        }
    }

    pub unsafe fn set_continuous_states(self, c: Instance, x: *const f64, n: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2SetContinuousStates(c, x, n),
            Api::Fmi3 => c3::fmi3SetContinuousStates(c, x, n),
        }
    }

    pub unsafe fn get_continuous_states(self, c: Instance, x: *mut f64, n: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2GetContinuousStates(c, x, n),
            Api::Fmi3 => c3::fmi3GetContinuousStates(c, x, n),
        }
    }

    pub unsafe fn get_derivatives(self, c: Instance, dx: *mut f64, n: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2GetDerivatives(c, dx, n),
            Api::Fmi3 => c3::fmi3GetContinuousStateDerivatives(c, dx, n),
        }
    }

    pub unsafe fn get_nominals(self, c: Instance, x: *mut f64, n: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2GetNominalsOfContinuousStates(c, x, n),
            Api::Fmi3 => c3::fmi3GetNominalsOfContinuousStates(c, x, n),
        }
    }

    pub unsafe fn get_event_indicators(self, c: Instance, z: *mut f64, n: usize) -> i32 {
        match self {
            Api::Fmi2 => fmi2GetEventIndicators(c, z, n),
            Api::Fmi3 => c3::fmi3GetEventIndicators(c, z, n),
        }
    }

    /// The status, and the flags enterEventMode and terminateSimulation.
    pub unsafe fn completed_integrator_step(self, c: Instance) -> (i32, bool, bool) {
        match self {
            Api::Fmi2 => {
                let mut flags = [7i32; 2];
                let [a, b] = &mut flags;
                let s = fmi2CompletedIntegratorStep(c, 1, a, b);
                (s, flags[0] != 0, flags[1] != 0)
            }
            Api::Fmi3 => {
                let mut flags = [0xa5u8; 2];
                let [a, b] = &mut flags;
                let s = c3::fmi3CompletedIntegratorStep(c, 1, a, b);
                (s, flags[0] != 0, flags[1] != 0)
            }
        }
    }

    /// The last successful time: fmi2GetRealStatus, or FMI 3.0's `time` (value reference 0).
    pub unsafe fn last_successful_time(self, c: Instance) -> (i32, f64) {
        let mut t = f64::NAN;
        let s = match self {
            Api::Fmi2 => fmi2GetRealStatus(c, LAST_SUCCESSFUL_TIME, &mut t),
            Api::Fmi3 => c3::fmi3GetFloat64(c, &fmi_core::standard::fmi3_types::TIME_VR, 1, &mut t, 1),
        };
        (s, t)
    }
}
