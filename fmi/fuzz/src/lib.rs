//! Fuzz harness of the exported C API.
//!
//! `run(bytes)` reads a sequence of FMI calls out of `bytes` (each byte
//! string is one sequence) and makes them through the real `fmi2*` entry
//! points of the library: random calls in random states with random
//! arguments — NULL pointers, NaN and infinities, huge, negative and
//! denormal values, unknown value references, out-of-range enumeration and
//! Boolean values, FMU states that are foreign, freed or freed twice,
//! serialized states that are random, mutated, truncated or forged (payload
//! changed and the checksum recomputed), instantiate/free cycles, and the
//! test hook that makes a step panic.
//!
//! Half of the sequences are driven: four operations in five are legal moves
//! of an importer (`op_lifecycle_macro`): an instance of Co-Simulation or,
//! two times in three, of Model Exchange through initialization, steps,
//! events and integrator steps (model_exchange.rs), at times with the scene
//! of the fuzz target (scene.rs); the random calls come between them. What a
//! sequence holds and the oracle's rules, below all three, are in sequence.rs.
//!
//! Beside it runs an oracle: an independent model of FMI 2.0's state
//! machines, co-simulation's (section 4.2.4) and model exchange's (3.2.3),
//! and of the argument rules. After every call it checks
//!
//! * the status: a call in a state where the standard does not allow it, or
//!   with an invalid argument, must answer `fmi2Error` (and the instance is
//!   then in the error state); a valid call must answer `fmi2OK`; where the
//!   outcome depends on the model's numbers (ending initialization or a step
//!   after values were changed) the allowed set is `{OK, Discard, Error}`
//!   with the state machine following the answer; never `fmi2Fatal`,
//!   `fmi2Pending` or a value that is no `fmi2Status`;
//! * that every non-OK status is explained by a log line of that status
//!   (while its log category is on), and that the logger only ever gets
//!   well-formed calls with a known category;
//! * that every Real the FMU returns (outputs, parameters, the last
//!   successful time, states, derivatives, event indicators, nominals, the
//!   next event time) is finite, that `fmi2FreeFMUstate` sets the state to
//!   NULL, that a serialized state deserializes to one that serializes to
//!   the same bytes, and that a restored state continues where it was saved
//!   (the last successful time; a Model Exchange instance's continuous states).
//!
//! Where the fuzz target names a contact (`Fuzzed::contact`), its mode is
//! read after every step, and the stick<->slide transitions are counted.
//!
//! `run(Api::Fmi3, bytes)` makes the same calls through the `fmi3*` entry
//! points (see api.rs) with FMI 3.0's own bad inputs beside: value counts that
//! differ from the number of value references, NULL out-arguments of
//! fmi3DoStep, bytes other than 0 and 1 for Booleans, Int64 values beyond the
//! enumerations, the functions this FMU refuses; the oracle is the same, as
//! FMI 3.0's states are FMI 2.0's for these calls (Step Mode is "step complete").
//!
//! Memory errors are not seen by the oracle: run the harness under
//! AddressSanitizer or valgrind for those (tests/integration/hardening.sh does both).
//!
//! A broken rule is a `Violation`. Two kinds of non-finite outputs are
//! counted as `Finding`s rather than violations because they are known
//! product issues (see docs/hardening.md and tests/fuzz_findings.rs):
//! overflow after extreme but accepted values, and forged FMU states.

#![allow(clippy::missing_safety_doc)]

pub mod driver;
mod api;
mod model_exchange;
mod newton;
mod scene;
mod sequence;

pub use api::Api;
use api::{Instance, Int};
use sequence::{
    allowed, computed, fail, family, magnitude, new_slot, own_state, settable, var, Blob, Desc, Family, Fn, Run, Slot, St,
    StateInfo, Values,
};
pub use sequence::{Contact, Finding, Fuzzed, Outcome, Scene, Source, Value, Violation};
use fmi_core::description::{
    Causality, Kind, Variable,
};
use fmi_core::instance::TEST_PANIC_CATEGORY;
use fmi_testkit::*;
use std::ffi::CString;
use std::ptr::null_mut;

/// Reals that break things: specials, extremes, denormals, and ordinary ones.
const NASTY_REALS: [f64; 24] = [
    f64::NAN,
    -f64::NAN,
    f64::INFINITY,
    f64::NEG_INFINITY,
    f64::MAX,
    f64::MIN,
    1e308,
    -1e308,
    1e200,
    1e-200,
    f64::MIN_POSITIVE,
    5e-324,
    -5e-324,
    2.2e-310,
    0.0,
    -0.0,
    1.0,
    -1.0,
    -1e-3,
    1e-3,
    5.0,
    -5.0,
    1e15,
    0.999_999_999,
];

const NASTY_INTS: [i32; 10] = [0, 1, 2, 3, 6, 7, -1, i32::MIN, i32::MAX, 100];

fn real(src: &mut Source) -> f64 {
    match src.pick(4) {
        0 => f64::from_bits(src.u64()),
        _ => NASTY_REALS[src.pick(NASTY_REALS.len())],
    }
}

/// A value near a variable's start value (or 1), inside its range when it
/// has one: keeps sequences on the paths where the model really computes.
fn sane_real(src: &mut Source, v: &Variable) -> f64 {
    use fmi_core::description::Start;
    let base = match v.start {
        Start::Real(x) if x != 0.0 => x,
        _ => 1e-3,
    };
    let x = base * (0.5 + src.u8() as f64 / 170.0);
    if v.range.contains(x) {
        x
    } else {
        base
    }
}

fn integer(src: &mut Source, v: Option<&Variable>) -> i32 {
    match (src.pick(3), v) {
        (0, Some(Variable { kind: Kind::Enumeration { values, .. }, .. })) => values[src.pick(values.len())],
        // An Integer inside its range (the Roller's counts of inlets and outlets,
        // its kind of roll): keeps sequences on the paths where the model computes.
        (0, Some(Variable { kind: Kind::Integer, range, .. })) if range.lo.is_finite() && range.hi - range.lo < 256.0 => {
            range.lo as i32 + src.pick((range.hi - range.lo) as usize + 1) as i32
        }
        (1, _) => NASTY_INTS[src.pick(NASTY_INTS.len())],
        _ => src.u32() as i32,
    }
}

fn boolean(src: &mut Source) -> i32 {
    match src.pick(4) {
        0 | 1 => src.pick(2) as i32,
        2 => [2, -1, i32::MIN, i32::MAX, 255][src.pick(5)],
        _ => src.u32() as i32,
    }
}

/// A value reference: mostly of the wanted kind, sometimes any variable's,
/// sometimes unknown.
fn vr(d: Desc, src: &mut Source, want: impl std::ops::Fn(&Variable) -> bool) -> u32 {
    match src.pick(8) {
        0 => src.u32(),
        1 => [0, u32::MAX, d.by_vr.len() as u32, 1000][src.pick(4)],
        2 => d.variables[src.pick(d.variables.len())].vr,
        _ => {
            let wanted: Vec<&Variable> = d.variables.iter().filter(|v| want(v)).collect();
            if wanted.is_empty() {
                src.u32()
            } else {
                wanted[src.pick(wanted.len())].vr
            }
        }
    }
}

const STEP_TOLERANCE: f64 = 1e-13;

/// The legal moves of a driven sequence (`Run::moves`): enough to take an instance through
/// initialization, events and steps, at a cost near the random calls' (the Line's moves are
/// dear: each initialization solves for its steady state).
const MOVES: u32 = 16;

/// Co-Simulation steps of a scene's instances in one sequence (`Run::scene_steps`).
const SCENE_STEPS: u32 = 16;

/// Runs one sequence on `model` through `api`. `Err` is a broken rule.
pub fn run(model: &Fuzzed, api: Api, bytes: &[u8]) -> Result<Outcome, Violation> {
    let mut r = Run {
        model: model.clone(),
        api,
        slots: [None, None],
        dead_states: Vec::new(),
        blobs: Vec::new(),
        foreign: Box::new([0x5a5a_5a5a_5a5a_5a5a; 8]),
        out: Outcome::default(),
        what: String::new(),
        trace: std::env::var_os("FUZZ_TRACE").is_some(),
        last_log: Vec::new(),
        driven: false,
        moves: MOVES,
        me_steps: model_exchange::STEPS,
        scene_steps: SCENE_STEPS,
    };
    let mut src = Source::new(bytes);
    // Half of the sequences are driven: an importer's calls with random ones between.
    r.driven = src.chance(128);
    let result = (|| {
        let mut ops = 0;
        while !src.is_empty() && ops < 400 {
            ops += 1;
            step(&mut r, &mut src)?;
        }
        Ok(())
    })();
    // Free what is left, whatever happened.
    for slot in r.slots.iter_mut() {
        if let Some(s) = slot.take() {
            unsafe { api.free_instance(s.c) };
        }
    }
    result.map(|()| r.out)
}

/// A component pointer for a call: mostly a live instance of a slot.
enum Target {
    Slot(usize),
    Null,
    Foreign,
}

/// Slot `i` holds an instance in the error state, or poisoned.
fn failed(r: &Run, i: usize) -> bool {
    r.slots[i].as_ref().is_some_and(|s| s.st == St::Error || s.poisoned)
}

fn target(r: &Run, src: &mut Source) -> Target {
    let mut i = src.pick(2);
    // Most calls go to an instance that can still answer them: one in the error state gets a
    // quarter of those it would (whose refusals are checked all the same).
    if failed(r, i) && r.slots[1 - i].is_some() && !failed(r, 1 - i) && src.chance(192) {
        i = 1 - i;
    }
    match src.pick(32) {
        0 => Target::Null,
        1 => Target::Foreign,
        _ if r.slots[i].is_some() => Target::Slot(i),
        _ if r.slots[1 - i].is_some() => Target::Slot(1 - i),
        _ => Target::Null,
    }
}

fn component(r: &Run, t: &Target) -> Instance {
    match t {
        Target::Slot(i) => r.slot(*i).c,
        Target::Null => null_mut(),
        Target::Foreign => r.foreign.as_ptr() as Instance,
    }
}

/// Common frame of calls that take an instance: a call on NULL or a
/// foreign pointer must answer fmi2Error; on an instance the expected
/// status comes from `expect` (given the slot), unless the call is not
/// allowed in the current state or the instance is poisoned.
fn call_on<F, E>(
    r: &mut Run,
    t: Target,
    f: Fn,
    name: &str,
    expect: E,
    call: F,
) -> Result<Option<(usize, i32)>, Violation>
where
    F: std::ops::FnOnce(Instance) -> i32,
    E: std::ops::FnOnce(&Slot) -> Vec<i32>,
{
    let c = component(r, &t);
    let i = match t {
        Target::Slot(i) => i,
        _ => {
            r.what = format!(
                "{name} on a {} component",
                if c.is_null() { "NULL" } else { "foreign" }
            );
            let s = call(c);
            r.check_status(s, &[ERROR])?;
            return Ok(None);
        }
    };
    let (st, poisoned) = (r.slot(i).st, r.slot(i).poisoned);
    r.out.by_state[st as usize] += 1;
    r.out.random[0] += 1;
    r.out.random[1] += (st == St::Error) as u64;
    let me = if r.slot(i).me { "ME " } else { "" };
    r.what = format!("{name} [slot {i}, {me}state {st:?}{}]", if poisoned { ", poisoned" } else { "" });
    let slot = r.slot(i);
    let expected = if slot.poisoned && f != Fn::Reset {
        vec![ERROR]
    } else if !own_state(slot.st, slot.me) {
        // Forged bytes put the instance in a state of the other interface: invalid arguments
        // must still give fmi2Error; a valid call may be refused for that state.
        let mut e = expect(slot);
        if !e.contains(&ERROR) {
            e.push(ERROR);
        }
        e
    } else if !allowed(f, slot.st, slot.me) {
        vec![ERROR]
    } else {
        expect(slot)
    };
    let s = call(c);
    if let Err(v) = r.check_status(s, &expected) {
        let log: Vec<String> = r
            .slot(i)
            .log
            .take()
            .into_iter()
            .map(|l| l.message)
            .collect();
        return fail(format!("{}; the FMU logged {log:?}", v.0));
    }
    r.after(i, s)?;
    Ok(Some((i, s)))
}

/// An array of `n` elements for the FMU to read, or NULL.
fn maybe_null<T>(src: &mut Source, v: &[T]) -> *const T {
    if src.chance(12) {
        std::ptr::null()
    } else {
        v.as_ptr()
    }
}

fn step(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    // An instance in the error state is reset at once half of the time (the move picks it): what
    // random calls find there is only refusals, which a few of them check.
    if (failed(r, 0) || failed(r, 1)) && src.chance(128) {
        return op_lifecycle_macro(r, src);
    }
    let op = src.u8();
    // A driven sequence makes a legal move 4 times in 5.
    if r.driven && r.moves > 0 && op < 205 {
        r.moves -= 1;
        return op_lifecycle_macro(r, src);
    }
    // Lifecycle and stepping calls are drawn more often than the rest, so
    // that sequences get past initialization and into stepping.
    match op % 64 {
        0..=1 => op_instantiate(r, src),
        2 => op_free_instance(r, src),
        3 => op_setup(r, src),
        4 => op_simple(r, src, Fn::EnterInit),
        5 => op_simple(r, src, Fn::ExitInit),
        6 => op_simple(r, src, Fn::Terminate),
        7 => op_simple(r, src, Fn::Reset),
        8..=10 => op_get(r, src, Family::Real),
        11 => op_get(r, src, Family::Integer),
        12 => op_get(r, src, Family::Boolean),
        13 => op_get(r, src, Family::String),
        14..=18 => op_set_real(r, src),
        19..=20 => op_set_int(r, src, Family::Integer),
        21..=22 => op_set_int(r, src, Family::Boolean),
        23 => op_set_string(r, src),
        24..=26 => op_get_state(r, src),
        27..=28 => op_set_state(r, src),
        29 => op_free_state(r, src),
        30..=31 => op_serialize(r, src),
        32..=34 => op_deserialize(r, src),
        35..=40 => op_do_step(r, src),
        41..=42 => op_status(r, src),
        43 => op_unsupported(r, src),
        44..=45 => op_input_derivatives(r, src),
        46 => op_debug_logging(r, src),
        47 => op_arm_panic(r, src),
        // A quarter of the operations are legal lifecycle moves.
        _ => op_lifecycle_macro(r, src),
    }
}

fn op_instantiate(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    if r.api == Api::Fmi3 {
        return op_instantiate3(r, src);
    }
    let i = src.pick(2);
    if let Some(old) = r.slots[i].take() {
        unsafe { fmi2FreeInstance(old.c) };
    }
    let log = Box::<Log>::default();
    let functions = Box::new(callbacks(&log));
    let me_offered = r.d().model_exchange;
    let fmu_type = match src.pick(16) {
        0 => [0, 2, -1, i32::MAX][src.pick(4)],
        1..=4 if me_offered => 0,
        _ => 1,
    };
    let right_type = fmu_type == 1 || (fmu_type == 0 && me_offered);
    let guid_kind = src.pick(24);
    let name = format!("fuzz{}", src.u8());
    let name_c = CString::new(name.clone()).unwrap();
    let guid_c = CString::new(match guid_kind {
        0 => "{00000000-0000-0000-0000-000000000000}".to_string(),
        1 => String::new(),
        _ => r.d().guid.to_string(),
    })
    .unwrap();
    let guid_ptr = if guid_kind == 2 && src.chance(128) {
        std::ptr::null()
    } else {
        guid_c.as_ptr()
    };
    let guid_ok = guid_kind >= 2 && !guid_ptr.is_null();
    let null_functions = src.chance(8);
    let null_name = src.chance(8);
    // What the FMU ships, so records load.
    let resources = CString::new(format!("file://{}", r.model.resources)).unwrap();
    let logging_on = boolean(src);
    let null_resources = src.chance(128);
    let c = unsafe {
        fmi2Instantiate(
            if null_name {
                std::ptr::null()
            } else {
                name_c.as_ptr()
            },
            fmu_type,
            guid_ptr,
            if null_resources {
                std::ptr::null()
            } else {
                resources.as_ptr()
            },
            if null_functions {
                std::ptr::null()
            } else {
                &*functions
            },
            boolean(src),
            logging_on,
        )
    };
    r.what = format!(
        "fmi2Instantiate(type {fmu_type}, guid ok {guid_ok}, functions NULL {null_functions}, resources NULL {null_resources})"
    );
    r.out.calls += 1;
    // A model whose interface is in its resources cannot exist without them.
    let resources_ok = !null_resources || !r.model.needs_resources;
    let should = right_type && guid_ok && !null_functions && resources_ok;
    if c.is_null() == should {
        if !c.is_null() {
            unsafe { fmi2FreeInstance(c) };
        }
        return fail(format!("{}: returned {c:?}", r.what));
    }
    let lines = log.take();
    if c.is_null() {
        if !null_functions && !lines.iter().any(|l| l.status == ERROR) {
            return fail(format!("{}: refused without saying why: {lines:?}", r.what));
        }
        return Ok(());
    }
    let name = if null_name { String::new() } else { name };
    if r.trace {
        eprintln!("{} -> slot {i} = {c:?}", r.what);
    }
    let mut slot = new_slot(name, c, log, Some(functions), logging_on != 0);
    slot.me = fmu_type == 0;
    r.slots[i] = Some(slot);
    Ok(())
}

/// FMI 3.0's instantiation: Co-Simulation or Model Exchange, with a wrong or
/// NULL token, NULL strings, required intermediate variables (refused: none
/// has intermediateUpdate), with or without a logger.
fn op_instantiate3(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let i = src.pick(2);
    if let Some(old) = r.slots[i].take() {
        unsafe { r.api.free_instance(old.c) };
    }
    let log = Box::<Log>::default();
    let model_exchange = r.d().model_exchange && src.chance(64);
    let token_kind = src.pick(24);
    let name = format!("fuzz{}", src.u8());
    let name_c = CString::new(name.clone()).unwrap();
    let token_c = CString::new(match token_kind {
        0 => "{00000000-0000-0000-0000-000000000000}".to_string(),
        1 => String::new(),
        _ => r.d().guid.to_string(),
    })
    .unwrap();
    let null_token = token_kind >= 2 && src.chance(16);
    let token_ok = token_kind >= 2 && !null_token;
    // What the FMU ships, as a path (FMI 3.0 passes no URI).
    let resources = CString::new(r.model.resources.as_str()).unwrap();
    let required: Vec<u32> = if src.chance(12) { vec![vr(r.d(), src, |_| true)] } else { Vec::new() };
    let no_logger = src.chance(12);
    let logging_on = src.chance(128);
    let null_name = src.chance(8);
    let null_resources = src.chance(16);
    let args = api::Instantiate3 {
        model_exchange,
        name: if null_name { std::ptr::null() } else { name_c.as_ptr() },
        token: if null_token { std::ptr::null() } else { token_c.as_ptr() },
        resource_path: if null_resources { std::ptr::null() } else { resources.as_ptr() },
        logging_on,
        event_mode_used: src.chance(16),
        required: &required,
        log: (!no_logger).then_some(&*log),
    };
    let c = unsafe { api::instantiate3(&args) };
    r.what = format!(
        "{}(token ok {token_ok}, required {required:?}, logger {}, resources NULL {null_resources})",
        if model_exchange { "fmi3InstantiateModelExchange" } else { "fmi3InstantiateCoSimulation" },
        !no_logger
    );
    r.out.calls += 1;
    let resources_ok = !null_resources || !r.model.needs_resources;
    let should = token_ok && (model_exchange || required.is_empty()) && resources_ok;
    if c.is_null() == should {
        if !c.is_null() {
            unsafe { r.api.free_instance(c) };
        }
        return fail(format!("{}: returned {c:?}", r.what));
    }
    let lines = log.take();
    if c.is_null() {
        if !no_logger && !lines.iter().any(|l| l.status == ERROR) {
            return fail(format!("{}: refused without saying why: {lines:?}", r.what));
        }
        return Ok(());
    }
    if r.trace {
        eprintln!("{} -> slot {i} = {c:?}", r.what);
    }
    let mut slot = new_slot(name, c, log, None, logging_on);
    slot.me = model_exchange;
    slot.silent = no_logger;
    r.slots[i] = Some(slot);
    Ok(())
}

fn op_free_instance(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    match src.pick(6) {
        0 => unsafe { api.free_instance(null_mut()) },
        1 => unsafe { api.free_instance(r.foreign.as_ptr() as Instance) },
        k => {
            if let Some(slot) = r.slots[k % 2].take() {
                // Its states go with it: their pointers are dead from now on.
                r.dead_states.extend(slot.states.iter().map(|s| s.ptr));
                unsafe { api.free_instance(slot.c) };
            }
        }
    }
    r.out.calls += 1;
    Ok(())
}

fn op_setup(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let t = target(r, src);
    let sane = src.chance(160);
    let (tol_def, tol, start, stop_def, stop) = if sane {
        (src.pick(2) as i32, 1e-6, 0.0, src.pick(2) as i32, 10.0)
    } else {
        (boolean(src), real(src), real(src), boolean(src), real(src))
    };
    let bad = !start.is_finite()
        || (stop_def != 0 && !(stop.is_finite() && stop >= start))
        || (tol_def != 0 && !(tol.is_finite() && tol > 0.0));
    // FMI 3.0 sets the experiment in fmi3EnterInitializationMode.
    let api = r.api;
    let (f, name) = match api {
        Api::Fmi2 => (Fn::SetupExperiment, "fmi2SetupExperiment"),
        Api::Fmi3 => (Fn::EnterInit, "fmi3EnterInitializationMode"),
    };
    let res = call_on(
        r,
        t,
        f,
        &format!("{name}({tol_def}, {tol:e}, {start:e}, {stop_def}, {stop:e})"),
        |_| if bad { vec![ERROR] } else { vec![OK] },
        |c| unsafe {
            match api {
                Api::Fmi2 => fmi2SetupExperiment(c, tol_def, tol, start, stop_def, stop),
                Api::Fmi3 => api.enter_init(c, (tol_def, tol, start, stop_def, stop)),
            }
        },
    )?;
    if let Some((i, OK)) = res {
        let slot = r.slot_mut(i);
        slot.time = start;
        if api == Api::Fmi3 {
            slot.st = St::Init;
        }
        if !sane {
            slot.values = slot
                .values
                .worsen(magnitude(start))
                .worsen(Values::Moderate);
            if tol_def != 0 {
                slot.values = slot.values.worsen(magnitude(tol));
            }
        }
    }
    Ok(())
}

fn op_simple(r: &mut Run, src: &mut Source, f: Fn) -> Result<(), Violation> {
    let t = target(r, src);
    let api = r.api;
    let name = match f {
        Fn::EnterInit => api.name("fmi2EnterInitializationMode", "fmi3EnterInitializationMode"),
        Fn::ExitInit => api.name("fmi2ExitInitializationMode", "fmi3ExitInitializationMode"),
        Fn::Terminate => api.name("fmi2Terminate", "fmi3Terminate"),
        _ => api.name("fmi2Reset", "fmi3Reset"),
    };
    let res = call_on(
        r,
        t,
        f,
        name,
        |slot| match f {
            // Ending initialization computes with the values set so far.
            Fn::ExitInit if slot.values != Values::Pristine => vec![OK, ERROR],
            _ => vec![OK],
        },
        |c| unsafe {
            match f {
                // (FMI 3.0: a plain experiment from time 0.)
                Fn::EnterInit => api.enter_init(c, (0, 0.0, 0.0, 0, 0.0)),
                Fn::ExitInit => api.exit_init(c),
                Fn::Terminate => api.terminate(c),
                _ => api.reset(c),
            }
        },
    )?;
    if let Some((i, OK)) = res {
        let slot = r.slot_mut(i);
        match f {
            Fn::EnterInit => {
                slot.st = St::Init;
                if api == Api::Fmi3 {
                    slot.time = 0.0;
                }
            }
            Fn::ExitInit => {
                // Model Exchange: initialization ends in event mode.
                slot.st = if slot.me { St::Event } else { St::StepComplete };
                slot.initialized = true;
            }
            Fn::Terminate => slot.st = St::Terminated,
            _ => slot.reset(),
        }
    }
    Ok(())
}

/// The number of values an FMI 3.0 get or set is told: mostly `n`, at times
/// one more or one less (refused: every variable is a scalar).
fn count(api: Api, src: &mut Source, n: usize) -> usize {
    match api {
        Api::Fmi3 if src.chance(10) => if n > 0 && src.chance(128) { n - 1 } else { n + 1 },
        _ => n,
    }
}

/// FMI 3.0's integer function for an Integer-family variable: Int64 for
/// enumerations, Int32 for the rest; at times the wrong one.
fn int_type(d: Desc, api: Api, src: &mut Source, vrs: &[u32]) -> Int {
    let enumeration = vrs
        .first()
        .and_then(|&x| var(d, x, Family::Integer))
        .is_some_and(|v| matches!(v.kind, Kind::Enumeration { .. }));
    if enumeration != (api == Api::Fmi3 && src.chance(24)) {
        Int::Int64
    } else {
        Int::Int32
    }
}

/// Does `v` travel through `int` in FMI 3.0 (always, in FMI 2.0)?
fn int_fits(api: Api, int: Int, v: &Variable) -> bool {
    api == Api::Fmi2 || matches!((int, v.kind), (Int::Int64, Kind::Enumeration { .. }) | (Int::Int32, Kind::Integer))
}

fn op_get(r: &mut Run, src: &mut Source, fam: Family) -> Result<(), Violation> {
    let api = r.api;
    let t = target(r, src);
    let n = src.pick(6);
    let d = r.d();
    let mut vrs: Vec<u32> = (0..n).map(|_| vr(r.d(), src, |v| family(v) == fam)).collect();
    if api == Api::Fmi3 && fam == Family::Real && n > 0 && src.chance(48) {
        // FMI 3.0's added Float64 variables: time, and the event indicators.
        let k = src.pick(n);
        vrs[k] = match src.pick(d.number_of_event_indicators + 1) {
            0 => fmi_core::standard::fmi3_types::TIME_VR,
            e => fmi_core::standard::fmi3_types::first_event_indicator(d) + e as u32 - 1,
        };
    }
    let added = |x: u32| api == Api::Fmi3 && fam == Family::Real && fmi_core::standard::fmi3_types::added(d, x).is_some();
    let int = int_type(r.d(), api, src, &vrs);
    let nv = count(api, src, n);
    let null_vr = n > 0 && src.chance(10);
    let null_values = n > 0 && src.chance(10);
    let known = vrs
        .iter()
        .all(|&x| var(r.d(), x, fam).is_some_and(|v| fam != Family::Integer || int_fits(api, int, v)) || added(x));
    let any_indicator = vrs.iter().any(|&x| added(x) && x != fmi_core::standard::fmi3_types::TIME_VR);
    let name = format!(
        "{}({vrs:?}{}{}{})",
        match (fam, api) {
            (Family::Real, Api::Fmi2) => "fmi2GetReal",
            (Family::Integer, Api::Fmi2) => "fmi2GetInteger",
            (Family::Boolean, Api::Fmi2) => "fmi2GetBoolean",
            (Family::String, Api::Fmi2) => "fmi2GetString",
            (Family::Real, Api::Fmi3) => "fmi3GetFloat64",
            (Family::Integer, Api::Fmi3) if int == Int::Int32 => "fmi3GetInt32",
            (Family::Integer, Api::Fmi3) => "fmi3GetInt64",
            (Family::Boolean, Api::Fmi3) => "fmi3GetBoolean",
            (Family::String, Api::Fmi3) => "fmi3GetString",
        },
        if null_vr { ", vr NULL" } else { "" },
        if null_values { ", value NULL" } else { "" },
        if nv != n { format!(", {nv} values") } else { String::new() }
    );
    let mut reals = vec![f64::NAN; n];
    let mut ints = vec![-7i32; n];
    let mut strs: Vec<fmi2String> = vec![std::ptr::null(); n];
    let vr_ptr = if null_vr {
        std::ptr::null()
    } else {
        vrs.as_ptr()
    };
    let res = call_on(
        r,
        t,
        Fn::Get,
        &name,
        |slot| {
            if null_vr || null_values || !known || nv != n {
                vec![ERROR]
            } else if slot.st == St::Init && slot.values != Values::Pristine {
                // In initialization mode the outputs are computed first,
                // which fails if the values set so far are inconsistent.
                vec![OK, ERROR]
            } else if slot.st == St::Error && fam == Family::Real && slot.values != Values::Pristine {
                // In the error state computed values are answered only where
                // the model can compute them (values set before a failed
                // initialization may not allow it); the FMU says why.
                vec![OK, ERROR]
            } else if any_indicator && !slot.me {
                // Event indicators are Model Exchange's.
                vec![OK, ERROR]
            } else {
                vec![OK]
            }
        },
        |c| unsafe {
            match fam {
                Family::Real => api.get_real(c, vr_ptr, n, if null_values { null_mut() } else { reals.as_mut_ptr() }, nv),
                Family::Integer => {
                    api.get_integer(int, c, vr_ptr, n, if null_values { null_mut() } else { ints.as_mut_ptr() }, nv)
                }
                Family::Boolean => api.get_boolean(c, vr_ptr, n, if null_values { null_mut() } else { ints.as_mut_ptr() }, nv),
                Family::String => api.get_string(c, vr_ptr, n, if null_values { null_mut() } else { strs.as_mut_ptr() }, nv),
            }
        },
    )?;
    if let Some((i, OK)) = res {
        for (k, &x) in vrs.iter().enumerate() {
            if added(x) {
                let time = r.slot(i).time;
                if x == fmi_core::standard::fmi3_types::TIME_VR && !r.slot(i).me && reals[k].to_bits() != time.to_bits() {
                    return fail(format!("{}: time = {}, expected {time}", r.what, reals[k]));
                }
                r.finite(i, reals[k], "an added Float64")?;
                continue;
            }
            let v = var(r.d(), x, fam).expect("known");
            match fam {
                Family::Real => r.finite(i, reals[k], &v.name)?,
                Family::Boolean if !(ints[k] == 0 || ints[k] == 1) => {
                    return fail(format!(
                        "{}: {} = {} is not a Boolean",
                        r.what, v.name, ints[k]
                    ))
                }
                Family::Integer => {
                    if let Kind::Enumeration { values, .. } = v.kind {
                        if !values.contains(&ints[k]) && r.slot(i).values != Values::Forged {
                            return fail(format!(
                                "{}: {} = {} is not an enumeration value",
                                r.what, v.name, ints[k]
                            ));
                        }
                    }
                }
                Family::String if strs[k].is_null() => {
                    return fail(format!("{}: {} is a NULL string", r.what, v.name))
                }
                _ => {}
            }
        }
    }
    Ok(())
}

/// Frame of the three numeric setters: checks every (vr, value) pair.
fn op_set_real(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let t = target(r, src);
    let n = src.pick(5);
    let mut vrs = Vec::new();
    let mut values = Vec::new();
    let sane = src.chance(150);
    for _ in 0..n {
        let x = vr(r.d(), src, |v| {
            family(v) == Family::Real
                && matches!(v.causality, Causality::Input | Causality::Parameter)
        });
        let value = match var(r.d(), x, Family::Real) {
            Some(v) if sane => sane_real(src, v),
            _ => real(src),
        };
        vrs.push(x);
        values.push(value);
    }
    let nv = count(api, src, n);
    let null_vr = n > 0 && src.chance(8);
    let null_values = n > 0 && src.chance(8);
    let vr_ptr = if null_vr {
        std::ptr::null()
    } else {
        vrs.as_ptr()
    };
    let value_ptr = if null_values {
        std::ptr::null()
    } else {
        values.as_ptr()
    };
    let pairs: Vec<(u32, f64)> = vrs.iter().copied().zip(values.iter().copied()).collect();
    let d = r.d();
    let res = call_on(
        r,
        t,
        Fn::Set,
        &format!(
            "{}({pairs:?}{}{}, {nv} values)",
            api.name("fmi2SetReal", "fmi3SetFloat64"),
            if null_vr { ", vr NULL" } else { "" },
            if null_values { ", value NULL" } else { "" }
        ),
        |slot| {
            let ok = nv == n
                && !null_vr
                && !null_values
                && pairs.iter().all(|&(x, value)| match var(d, x, Family::Real) {
                    Some(v) => {
                        // Inputs, and tunable parameters once initialized, are range-checked at once;
                        // other parameters when initialization ends.
                        let at_once = v.causality == Causality::Input
                            || (v.causality == Causality::Parameter
                                && matches!(slot.st, St::StepComplete | St::StepFailed | St::Terminated | St::Event | St::Continuous));
                        settable(v, slot.st) && value.is_finite() && (!at_once || v.range.contains(value))
                    }
                    None => false,
                });
            // A model may refuse an in-range value by a rule of its own (fmi_core's value check: the
            // Roller's loop.set <= 0 without loop.compression): fmi2Error with its log line.
            if ok { vec![OK, ERROR] } else { vec![ERROR] }
        },
        |c| unsafe { api.set_real(c, vr_ptr, n, value_ptr, nv) },
    )?;
    if let Some((i, OK)) = res {
        let slot = r.slot_mut(i);
        for &(_, value) in &pairs {
            slot.values = slot
                .values
                .worsen(Values::Moderate)
                .worsen(magnitude(value));
        }
    }
    Ok(())
}

fn op_set_int(r: &mut Run, src: &mut Source, fam: Family) -> Result<(), Violation> {
    let api = r.api;
    let t = target(r, src);
    let n = src.pick(4);
    let mut vrs = Vec::new();
    let mut values: Vec<i64> = Vec::new();
    for _ in 0..n {
        let x = vr(r.d(), src, |v| {
            family(v) == fam && v.causality == Causality::Parameter
        });
        vrs.push(x);
        values.push(if fam == Family::Boolean {
            boolean(src) as i64
        } else if api == Api::Fmi3 && src.chance(16) {
            // Beyond any Int32 (FMI 3.0 gives enumerations 64 bits).
            [i64::MAX, i64::MIN, 1 << 32, -(1 << 31) - 1][src.pick(4)]
        } else {
            integer(src, var(r.d(), x, fam)) as i64
        });
    }
    let int = int_type(r.d(), api, src, &vrs);
    let nv = count(api, src, n);
    let null_vr = n > 0 && src.chance(8);
    let null_values = n > 0 && src.chance(8);
    let vr_ptr = if null_vr {
        std::ptr::null()
    } else {
        vrs.as_ptr()
    };
    let narrow: Vec<i32> = values.iter().map(|&x| x as i32).collect();
    let (value_ptr, narrow_ptr) = if null_values {
        (std::ptr::null(), std::ptr::null())
    } else {
        (values.as_ptr(), narrow.as_ptr())
    };
    let pairs: Vec<(u32, i64)> = vrs.iter().copied().zip(values.iter().copied()).collect();
    let name = match (fam, api, int) {
        (Family::Boolean, _, _) => api.name("fmi2SetBoolean", "fmi3SetBoolean"),
        (_, Api::Fmi2, _) => "fmi2SetInteger",
        (_, _, Int::Int32) => "fmi3SetInt32",
        _ => "fmi3SetInt64",
    };
    let d = r.d();
    let res = call_on(
        r,
        t,
        Fn::Set,
        &format!(
            "{name}({pairs:?}{}{}, {nv} values)",
            if null_vr { ", vr NULL" } else { "" },
            if null_values { ", value NULL" } else { "" }
        ),
        |slot| {
            let ok = nv == n
                && !null_vr
                && !null_values
                && pairs.iter().all(|&(x, value)| match var(d, x, fam) {
                    Some(v) => {
                        // What the FMU is given: FMI 2.0's Integer is 32 bits; FMI 3.0's Boolean a byte.
                        let value = match (fam, api, int) {
                            (Family::Boolean, _, _) => api.boolean_value(value as i32) as i64,
                            (_, Api::Fmi3, Int::Int64) => value,
                            _ => value as i32 as i64,
                        };
                        settable(v, slot.st)
                            && (fam == Family::Boolean || int_fits(api, int, v))
                            && match v.kind {
                                Kind::Boolean => value == 0 || value == 1,
                                Kind::Enumeration { values, .. } => values.iter().any(|&e| e as i64 == value),
                                _ => true,
                            }
                    }
                    None => false,
                });
            vec![if ok { OK } else { ERROR }]
        },
        |c| unsafe {
            if fam == Family::Boolean {
                api.set_boolean(c, vr_ptr, n, narrow_ptr, nv)
            } else {
                api.set_integer(int, c, vr_ptr, n, value_ptr, nv)
            }
        },
    )?;
    if let Some((i, OK)) = res {
        if n > 0 {
            let slot = r.slot_mut(i);
            slot.values = slot.values.worsen(Values::Moderate);
        }
    }
    Ok(())
}

fn op_set_string(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let t = target(r, src);
    let n = src.pick(3);
    let vrs: Vec<u32> = (0..n)
        .map(|_| vr(r.d(), src, |v| family(v) == Family::String))
        .collect();
    // Record names of the shipped library (a linear web, a curve), none, and an unknown name.
    let texts: Vec<CString> = ["PET-12", "nonwoven-PP-spunbond", "steel-1.0", "", "a string"]
        .iter()
        .map(|t| CString::new(*t).unwrap())
        .collect();
    let values: Vec<fmi2String> = (0..n)
        .map(|_| {
            if src.chance(64) {
                std::ptr::null()
            } else {
                texts[src.pick(texts.len())].as_ptr()
            }
        })
        .collect();
    let vr_ptr = maybe_null(src, &vrs);
    let value_ptr = maybe_null(src, &values);
    let nv = count(api, src, n);
    let ok_args = nv == n && (n == 0 || (!vr_ptr.is_null() && !value_ptr.is_null()));
    let known = vrs
        .iter()
        .all(|&x| var(r.d(), x, Family::String).is_some_and(|v| v.causality != Causality::Output));
    let res = call_on(
        r,
        t,
        Fn::Set,
        &format!("{}({vrs:?}, {nv} values)", api.name("fmi2SetString", "fmi3SetString")),
        |_| {
            if ok_args && (n == 0 || known) {
                vec![OK, ERROR]
            } else {
                vec![ERROR]
            }
        },
        |c| unsafe { api.set_string(c, vr_ptr, n, value_ptr, nv) },
    )?;
    // A record (or a library path) may fail initialization, like any changed value.
    if let Some((i, OK)) = res {
        if n > 0 {
            let slot = r.slot_mut(i);
            slot.values = slot.values.worsen(Values::Moderate);
        }
    }
    Ok(())
}

/// A state pointer to hand to the FMU: one of this slot's, another slot's,
/// a freed one, NULL, or garbage (never dereferenced unless it is a live
/// state of the instance: the FMU looks it up first).
fn any_state(r: &Run, src: &mut Source, i: Option<usize>) -> usize {
    let own: Vec<usize> = i
        .and_then(|i| r.slots[i].as_ref())
        .map(|s| s.states.iter().map(|x| x.ptr).collect())
        .unwrap_or_default();
    let other: Vec<usize> = i
        .and_then(|i| r.slots[1 - i].as_ref())
        .map(|s| s.states.iter().map(|x| x.ptr).collect())
        .unwrap_or_default();
    match src.pick(10) {
        0 => 0,
        1 => r.foreign.as_ptr() as usize,
        2 if !other.is_empty() => other[src.pick(other.len())],
        3 if !r.dead_states.is_empty() => r.dead_states[src.pick(r.dead_states.len())],
        4 => src.u64() as usize | 1,
        _ if !own.is_empty() => own[src.pick(own.len())],
        _ => 0,
    }
}

fn slot_of(t: &Target) -> Option<usize> {
    match t {
        Target::Slot(i) => Some(*i),
        _ => None,
    }
}

fn owns(r: &Run, i: usize, p: usize) -> Option<usize> {
    r.slot(i).states.iter().position(|s| s.ptr == p && p != 0)
}

fn op_get_state(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let t = target(r, src);
    let i = slot_of(&t);
    let initial = if src.chance(180) {
        0
    } else {
        any_state(r, src, i)
    };
    let null_slot = src.chance(8);
    let mut slot_value = initial as api::State;
    let slot_ptr: *mut api::State = if null_slot {
        null_mut()
    } else {
        &mut slot_value
    };
    let owned = i.and_then(|i| owns(r, i, initial));
    let res = call_on(
        r,
        t,
        Fn::StateOp,
        &format!(
            "{}(*state = {initial:#x}{})",
            api.name("fmi2GetFMUstate", "fmi3GetFMUState"),
            if null_slot { ", state NULL" } else { "" }
        ),
        |_| {
            vec![if !null_slot && (initial == 0 || owned.is_some()) {
                OK
            } else {
                ERROR
            }]
        },
        |c| unsafe { api.get_state(c, slot_ptr) },
    )?;
    if let Some((i, s)) = res {
        let got = slot_value as usize;
        if s != OK {
            if got != initial {
                return fail(format!("{}: failed but changed *state to {got:#x}", r.what));
            }
            return Ok(());
        }
        if got == 0 || (initial != 0 && got != initial) {
            return fail(format!("{}: returned state {got:#x}", r.what));
        }
        if r.trace {
            eprintln!("  state {got:#x} to slot {i}");
        }
        let x = model_exchange::saved_states(r, i)?;
        let slot = r.slot_mut(i);
        let info = StateInfo {
            ptr: got,
            st: slot.st,
            time: slot.time,
            values: slot.values,
            initialized: slot.initialized,
            me: slot.me,
            x,
        };
        match owned {
            Some(k) => slot.states[k] = info,
            None => {
                r.dead_states.retain(|&p| p != got);
                r.slot_mut(i).states.push(info);
            }
        }
    }
    Ok(())
}

fn op_set_state(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let t = target(r, src);
    let i = slot_of(&t);
    let p = any_state(r, src, i);
    let owned = i.and_then(|i| owns(r, i, p));
    let res = call_on(
        r,
        t,
        Fn::StateOp,
        &format!("{}({p:#x})", api.name("fmi2SetFMUstate", "fmi3SetFMUState")),
        // A state of the other interface (ME/CS) is refused.
        |slot| match owned.map(|k| &slot.states[k]) {
            // A forged state may have any interface byte: either answer.
            Some(state) if state.values == Values::Forged => vec![OK, ERROR],
            Some(state) if state.me == slot.me => vec![OK],
            _ => vec![ERROR],
        },
        |c| unsafe { api.set_state(c, p as api::State) },
    )?;
    if let (Some((i, OK)), Some(k)) = (res, owned) {
        let slot = r.slot_mut(i);
        let info = slot.states[k].clone();
        slot.st = info.st;
        slot.time = info.time;
        slot.values = info.values;
        slot.initialized = info.initialized;
        slot.sliding = None;
        slot.integration = Default::default();
        // (fmi2OK means the interface matched.)
        // A restored state continues where it was saved.
        if let Some(saved) = &info.x {
            model_exchange::check_restored(r, i, saved)?;
        }
        let slot = r.slot_mut(i);
        if !info.me && allowed(Fn::GetStatus, info.st, false) {
            let (s, t) = unsafe { api.last_successful_time(slot.c) };
            slot.log.take();
            if s != OK || t.to_bits() != info.time.to_bits() {
                return fail(format!(
                    "{}: after restoring, last successful time is {t} ({s}), saved {}",
                    r.what, info.time
                ));
            }
        }
    }
    Ok(())
}

fn op_free_state(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let t = target(r, src);
    let i = slot_of(&t);
    let p = any_state(r, src, i);
    let null_slot = src.chance(8);
    let mut slot_value = p as api::State;
    let slot_ptr: *mut api::State = if null_slot {
        null_mut()
    } else {
        &mut slot_value
    };
    let owned = i.and_then(|i| owns(r, i, p));
    let res = call_on(
        r,
        t,
        Fn::StateOp,
        &format!(
            "{}(*state = {p:#x}{})",
            api.name("fmi2FreeFMUstate", "fmi3FreeFMUState"),
            if null_slot { ", state NULL" } else { "" }
        ),
        |_| {
            vec![if !null_slot && (p == 0 || owned.is_some()) {
                OK
            } else {
                ERROR
            }]
        },
        |c| unsafe { api.free_state(c, slot_ptr) },
    )?;
    if let Some((i, s)) = res {
        if s == OK {
            if !slot_value.is_null() {
                return fail(format!(
                    "{}: *state is {slot_value:?} after the free, not NULL",
                    r.what
                ));
            }
            if let Some(k) = owned {
                r.slot_mut(i).states.remove(k);
                r.dead_states.push(p);
            }
        } else if slot_value as usize != p {
            return fail(format!("{}: failed but changed *state", r.what));
        }
    }
    Ok(())
}

fn op_serialize(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let t = target(r, src);
    let i = slot_of(&t);
    let p = any_state(r, src, i);
    let owned = i.and_then(|i| owns(r, i, p));
    let null_size = src.chance(10);
    let mut size = usize::MAX;
    let size_ptr: *mut usize = if null_size { null_mut() } else { &mut size };
    let res = call_on(
        r,
        t,
        Fn::StateOp,
        &format!("{}({p:#x})", api.name("fmi2SerializedFMUstateSize", "fmi3SerializedFMUStateSize")),
        |_| {
            vec![if owned.is_some() && !null_size {
                OK
            } else {
                ERROR
            }]
        },
        |c| unsafe { api.state_size(c, p as api::State, size_ptr) },
    )?;
    let Some((i, OK)) = res else { return Ok(()) };
    if size == 0 || size > 1 << 20 {
        return fail(format!("{}: size {size}", r.what));
    }
    // Serialize into a buffer that is big enough, too small, or NULL.
    let (buf_len, null_buf) = match src.pick(8) {
        0 => (size - 1, false),
        1 => (0, false),
        2 => (size, true),
        3 => (size + 100, false),
        _ => (size, false),
    };
    let mut buf = vec![0xa5u8; buf_len.max(1)];
    let buf_ptr: *mut u8 = if null_buf { null_mut() } else { buf.as_mut_ptr() };
    let (c, poisoned) = (r.slot(i).c, r.slot(i).poisoned);
    r.what = format!(
        "{}(size {buf_len} for {size}{})",
        api.name("fmi2SerializeFMUstate", "fmi3SerializeFMUState"),
        if null_buf { ", NULL buffer" } else { "" }
    );
    let expected = if poisoned || buf_len < size || null_buf {
        ERROR
    } else {
        OK
    };
    let s = unsafe { api.serialize(c, p as api::State, buf_ptr, buf_len) };
    r.check_status(s, &[expected])?;
    r.after(i, s)?;
    if s == OK {
        buf.truncate(size);
        let info = r.slot(i).states[owned.expect("owned")].clone();
        if St::from_byte(buf[24]).is_none() {
            return fail(format!("{}: phase byte {}", r.what, buf[24]));
        }
        r.blobs.push(Blob { bytes: buf, info });
        if r.blobs.len() > 8 {
            r.blobs.remove(0);
        }
    }
    Ok(())
}

/// FNV-1a, 64 bit, as documented in fmi/core/src/snapshot.rs: the harness
/// recomputes the checksum to forge states that get past it.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3)
    })
}

fn fix_checksum(b: &mut [u8]) {
    if b.len() >= 32 {
        let n = b.len() - 8;
        let sum = fnv1a(&b[..n]);
        b[n..].copy_from_slice(&sum.to_le_bytes());
    }
}

#[derive(Debug, PartialEq)]
enum Bytes {
    Genuine,
    /// Changed without fixing the checksum, truncated, or extended: refused.
    Corrupt,
    /// Changed and the checksum recomputed: accepted or refused.
    Forged,
    Random,
}

fn op_deserialize(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let (mut bytes, mut kind, info) = if r.blobs.is_empty() || src.chance(40) {
        let n = src.pick(80);
        (
            (0..n).map(|_| src.u8()).collect::<Vec<u8>>(),
            Bytes::Random,
            None,
        )
    } else {
        let b = r.blobs[src.pick(r.blobs.len())].clone();
        (b.bytes, Bytes::Genuine, Some(b.info))
    };
    if kind == Bytes::Genuine {
        match src.pick(8) {
            0 | 1 => {}
            2 => {
                // Flip bits anywhere; the checksum no longer matches.
                for _ in 0..1 + src.pick(4) {
                    let k = src.pick(256) * bytes.len() / 256;
                    bytes[k] ^= 1 << src.pick(8);
                }
                kind = Bytes::Corrupt;
            }
            3 => {
                let keep = src.pick(256) * bytes.len() / 256;
                bytes.truncate(keep);
                kind = Bytes::Corrupt;
            }
            4 => {
                bytes.extend((0..1 + src.pick(16)).map(|_| src.u8()));
                kind = Bytes::Corrupt;
            }
            _ => {
                // Forge: overwrite some bytes (header or payload), recompute
                // the checksum.
                for _ in 0..1 + src.pick(6) {
                    let k = src.pick(256) * (bytes.len() - 8) / 256;
                    bytes[k] = match src.pick(4) {
                        0 => 0xff,
                        1 => 0,
                        _ => src.u8(),
                    };
                }
                if src.chance(64) {
                    // A whole Real of the payload: NaN, inf, 0, negative...
                    let k = 25 + 8 * src.pick((bytes.len().saturating_sub(41)) / 8 + 1);
                    if k + 8 <= bytes.len() - 8 {
                        bytes[k..k + 8].copy_from_slice(&real(src).to_le_bytes());
                    }
                }
                fix_checksum(&mut bytes);
                kind = Bytes::Forged;
            }
        }
    }
    // Flips that cancel out (the same bit twice) leave genuine bytes.
    if kind != Bytes::Random && r.blobs.iter().any(|b| b.bytes == bytes) {
        kind = Bytes::Genuine;
    }
    let t = target(r, src);
    let i = slot_of(&t);
    let initial = if src.chance(200) {
        0
    } else {
        any_state(r, src, i)
    };
    let owned = i.and_then(|i| owns(r, i, initial));
    let null_bytes = src.chance(8);
    let null_slot = src.chance(8);
    let mut slot_value = initial as api::State;
    let slot_ptr: *mut api::State = if null_slot {
        null_mut()
    } else {
        &mut slot_value
    };
    let bytes_ptr = if null_bytes { std::ptr::null() } else { bytes.as_ptr() };
    let args_ok =
        !null_slot && (initial == 0 || owned.is_some()) && (!null_bytes || bytes.is_empty());
    let slot_me = i.is_some_and(|i| r.slot(i).me);
    let genuine_pristine = info.as_ref().is_some_and(|info| info.values == Values::Pristine);
    let genuine_ok_args = kind == Bytes::Genuine && args_ok;
    // A state of a Model Exchange instance does not fit a co-simulation one
    // (and back): the state carries its interface, and the FMU may refuse it
    // here or when it is set.
    let foreign_interface = info.as_ref().is_some_and(|info| info.me != slot_me);
    let res = call_on(
        r,
        t,
        Fn::StateOp,
        &format!(
            "{}({kind:?}, {} bytes, *state = {initial:#x})",
            api.name("fmi2DeSerializeFMUstate", "fmi3DeserializeFMUState"),
            bytes.len()
        ),
        |_| match (&kind, args_ok) {
            (_, false) | (Bytes::Corrupt, _) => vec![ERROR],
            (Bytes::Genuine, true) if foreign_interface => vec![OK, ERROR],
            (Bytes::Genuine, true) if genuine_pristine => vec![OK],
            // Should be fmi2OK; fmi2Error is a known finding (below).
            (Bytes::Genuine, true) => vec![OK, ERROR],
            _ => vec![OK, ERROR],
        },
        |c| unsafe { api.deserialize(c, bytes_ptr, bytes.len(), slot_ptr) },
    )?;
    let Some((i, s)) = res else { return Ok(()) };
    let got = slot_value as usize;
    if s == ERROR && genuine_ok_args && !r.slot(i).poisoned && !foreign_interface {
        let what = format!("{}: {:?}", r.what, r.last_log);
        r.out.findings.push((Finding::OwnStateRefusedOnDeserialize, what));
    }
    if s != OK {
        if got != initial {
            return fail(format!("{}: failed but changed *state", r.what));
        }
        return Ok(());
    }
    r.out.deserialized_ok += 1;
    if r.trace {
        eprintln!("  state {got:#x} to slot {i} (deserialized)");
    }
    // Bytes that were accepted: a known phase and a finite time.
    let st = St::from_byte(bytes[24]);
    let time = f64::from_le_bytes(bytes[25..33].try_into().unwrap());
    let (Some(st), true) = (st, time.is_finite()) else {
        return fail(format!(
            "{}: accepted phase byte {} and time {time}",
            r.what, bytes[24]
        ));
    };
    let genuine = kind == Bytes::Genuine;
    // Forged bytes keep the interface of the state they were made from.
    let source_me = info.as_ref().map_or(slot_me, |info| info.me);
    let info = match (kind, info) {
        (Bytes::Genuine, Some(info)) => StateInfo { ptr: got, ..info },
        _ => StateInfo {
            ptr: got,
            st,
            time,
            values: Values::Forged,
            initialized: true,
            me: source_me,
            x: None,
        },
    };
    if got == 0 || (initial != 0 && got != initial) {
        return fail(format!("{}: returned state {got:#x}", r.what));
    }
    match owned {
        Some(k) => r.slot_mut(i).states[k] = info,
        None => {
            r.dead_states.retain(|&p| p != got);
            r.slot_mut(i).states.push(info);
        }
    }
    // A genuine state serializes to the same bytes again.
    if let Some(k) = owns(r, i, got) {
        let c = r.slot(i).c;
        let mut size = 0usize;
        let mut again = vec![0u8; bytes.len()];
        let ok = unsafe {
            api.state_size(c, got as api::State, &mut size) == OK
                && size == bytes.len()
                && api.serialize(c, got as api::State, again.as_mut_ptr(), size) == OK
        };
        let poisoned = r.slot(i).poisoned;
        r.slot(i).log.take();
        // (Forged bytes may hold non-canonical fields, e.g. values behind a
        // false flag, which the model does not keep: only genuine ones must
        // come back byte for byte.)
        if !poisoned && (!ok || (genuine && again != bytes)) {
            let diff: Vec<(usize, u8, u8)> = bytes
                .iter()
                .zip(&again)
                .enumerate()
                .filter(|(_, (a, b))| a != b)
                .map(|(k, (a, b))| (k, *a, *b))
                .collect();
            return fail(format!(
                "{}: the state does not serialize to the bytes it came from (size {size}, differing bytes (offset, given, now) {diff:?})",
                r.what
            ));
        }
        let _ = k;
    }
    Ok(())
}

fn op_do_step(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let name = api.name("fmi2DoStep", "fmi3DoStep");
    let t = target(r, src);
    let Some(i) = slot_of(&t) else {
        let c = component(r, &t);
        r.what = format!("{name} on NULL/foreign");
        let (s, _) = unsafe { api.do_step(c, 0.0, 0.1, 1, false) };
        return r.check_status(s, &[ERROR]);
    };
    let (time, st_before, poisoned_before) = (r.slot(i).time, r.slot(i).st, r.slot(i).poisoned);
    let (tc, t_exact) = match src.pick(16) {
        0 => (real(src), false),
        1 => (time + time.abs().max(1.0) * 1e-9, false),
        2 => (time * (1.0 + 1e-15), false),
        _ => (time, true),
    };
    let h = match src.pick(8) {
        // A sliding contact costs its model many steps: a scene's instance steps at most 10 ms.
        _ if r.slot(i).scene && src.chance(240) => [1e-3, 0.01][src.pick(2)],
        0 => real(src),
        1 => [1e-9, 1e-6, 1e3, 1e6][src.pick(4)],
        // (Steps of a line cost it in proportion: sequences keep their instances out of the
        // error state, so long steps are rarer than short ones.)
        _ => [1e-3, 0.01, 0.01, 0.1][src.pick(4)],
    };
    let no_prior = boolean(src);
    // FMI 3.0's out-arguments are required.
    let null_outs = api == Api::Fmi3 && src.chance(8);
    let mut answered = None;
    let tol = STEP_TOLERANCE * tc.abs().max(time.abs()).max(1.0);
    let t_ok = tc.is_finite() && (t_exact || (tc - time).abs() <= 0.5 * tol);
    let t_bad = !tc.is_finite() || (tc - time).abs() > 2.0 * tol;
    let h_ok = h.is_finite() && h > 0.0;
    let res = call_on(
        r,
        t,
        Fn::DoStep,
        &format!("{name}({tc:e}, {h:e}{}) at time {time:e}", if null_outs { ", NULL out-arguments" } else { "" }),
        |slot| {
            if !h_ok || t_bad || null_outs {
                vec![ERROR]
            } else if !t_ok {
                vec![OK, DISCARD, ERROR]
            } else if slot.armed {
                // The hook panics once the model has stepped.
                vec![ERROR, DISCARD]
            } else if slot.values == Values::Pristine && h <= 10.0 {
                vec![OK]
            } else {
                vec![OK, DISCARD, ERROR]
            }
        },
        |c| unsafe {
            let (s, outs) = api.do_step(c, tc, h, no_prior, null_outs);
            answered = outs;
            s
        },
    )?;
    let Some((i, s)) = res else { return Ok(()) };
    let slot = r.slot_mut(i);
    match s {
        OK => {
            slot.time = tc + h;
            // A step of extreme length (inputs extrapolated with their
            // derivatives over 1e308 s...) counts as an extreme value.
            if magnitude(h) == Values::Extreme || magnitude(tc + h) == Values::Extreme {
                slot.values = slot.values.worsen(Values::Extreme);
            }
            r.out.steps_ok += 1;
            let c = r.slot(i).c;
            if let Some((flags, reached)) = answered {
                // No event, no stop, no early return: a step is whole.
                if flags != [0; 3] || reached.to_bits() != (tc + h).to_bits() {
                    return fail(format!("{}: answered flags {flags:?}, lastSuccessfulTime {reached}", r.what));
                }
            }
            let (st, last) = unsafe { api.last_successful_time(c) };
            r.slot(i).log.take();
            if st != OK || last.to_bits() != (tc + h).to_bits() {
                // t + h can overflow to infinity: that is a finding of its own.
                if st == OK && !last.is_finite() {
                    r.finite(i, last, "last successful time")?;
                    r.slot_mut(i).values = Values::Extreme;
                } else {
                    return fail(format!(
                        "{}: then last successful time {last} ({st}), expected {}",
                        r.what,
                        tc + h
                    ));
                }
            }
            // Every output is finite after a successful step.
            let reals: Vec<&Variable> = r.d()
                .variables
                .iter()
                .filter(|v| family(v) == Family::Real)
                .collect();
            let vrs: Vec<u32> = reals.iter().map(|v| v.vr).collect();
            let mut values = vec![f64::NAN; vrs.len()];
            let gs = unsafe { api.get_real(c, vrs.as_ptr(), vrs.len(), values.as_mut_ptr(), vrs.len()) };
            r.slot(i).log.take();
            if gs != OK {
                return fail(format!(
                    "{}: then fmi2GetReal of every Real answered {gs}",
                    r.what
                ));
            }
            r.what = format!("{} then fmi2GetReal", r.what);
            for (v, x) in reals.iter().zip(values) {
                r.finite(i, x, &v.name)?;
            }
        }
        DISCARD => {
            if slot.armed {
                // Discarded before the hook fired: still armed.
            }
            slot.st = St::StepFailed;
        }
        ERROR => {
            if slot.armed && !slot.me && h_ok && t_ok && !null_outs && st_before == St::StepComplete && !poisoned_before {
                slot.armed = false;
                slot.poisoned = true;
                r.out.panics_caught += 1;
            }
        }
        _ => {}
    }
    Ok(())
}

fn op_status(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    if r.api == Api::Fmi3 {
        // FMI 3.0 has no status functions.
        return op_unsupported3(r, src);
    }
    let t = target(r, src);
    let which = src.pick(5);
    let kind = match src.pick(4) {
        0 => src.u32() as i32,
        _ => src.pick(5) as i32,
    };
    let null_value = src.chance(16);
    let mut real_v = f64::NAN;
    let mut int_v = -7i32;
    let mut str_v: fmi2String = std::ptr::null();
    let name = [
        "fmi2GetStatus",
        "fmi2GetRealStatus",
        "fmi2GetIntegerStatus",
        "fmi2GetBooleanStatus",
        "fmi2GetStringStatus",
    ][which];
    let res = call_on(
        r,
        t,
        Fn::GetStatus,
        &format!(
            "{name}(kind {kind}{})",
            if null_value { ", value NULL" } else { "" }
        ),
        |_| match (which, kind) {
            (1, 2) | (3, 3) => vec![if null_value { ERROR } else { OK }],
            // Status kinds the FMU does not provide answer fmi2Discard.
            _ if null_value => vec![DISCARD, ERROR],
            _ => vec![DISCARD],
        },
        |c| unsafe {
            let rv = if null_value {
                null_mut()
            } else {
                &mut real_v as *mut f64
            };
            let iv = if null_value {
                null_mut()
            } else {
                &mut int_v as *mut i32
            };
            let sv = if null_value {
                null_mut()
            } else {
                &mut str_v as *mut fmi2String
            };
            match which {
                0 => fmi2GetStatus(c, kind, iv),
                1 => fmi2GetRealStatus(c, kind, rv),
                2 => fmi2GetIntegerStatus(c, kind, iv),
                3 => fmi2GetBooleanStatus(c, kind, iv),
                _ => fmi2GetStringStatus(c, kind, sv),
            }
        },
    )?;
    if let Some((i, OK)) = res {
        match which {
            1 => {
                let expected = r.slot(i).time;
                r.finite(i, real_v, "last successful time")?;
                if real_v.to_bits() != expected.to_bits() {
                    return fail(format!(
                        "{}: last successful time {real_v}, expected {expected}",
                        r.what
                    ));
                }
            }
            3 if int_v != 0 => return fail(format!("{}: terminated = {int_v}", r.what)),
            _ => {}
        }
    }
    Ok(())
}

/// Model Exchange functions, output derivatives and fmi2CancelStep: not
/// offered, so fmi2Error in every state; directional derivatives with one
/// array for dvKnown and dvUnknown: refused unless empty.
fn op_unsupported(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    if r.api == Api::Fmi3 {
        return op_unsupported3(r, src);
    }
    let t = target(r, src);
    let which = src.pick(14);
    let n = me_count(r.d(), src, which);
    let vrs: Vec<u32> = (0..n.min(4)).map(|_| vr(r.d(), src, |_| true)).collect();
    let mut buf = vec![0.0f64; n.max(8)];
    // Values for fmi2SetContinuousStates: nasty ones, or near the start.
    for x in buf.iter_mut() {
        *x = if src.chance(128) { 1.0 - (src.u8() as f64) * 1e-5 } else { real(src) };
    }
    let set_states = buf.clone();
    let mut flags = [0i32; 2];
    let mut info = fmi2EventInfo::default();
    let null = src.chance(64);
    let p = if null { null_mut() } else { buf.as_mut_ptr() };
    let orders = vec![1i32; vrs.len()];
    let x = real(src);
    let (f, name) = match which {
        0 => (Fn::GetDirectionalDerivative, "fmi2GetDirectionalDerivative"),
        11 => (Fn::CancelStep, "fmi2CancelStep"),
        12 | 13 => (Fn::GetRealOutputDerivatives, "fmi2GetRealOutputDerivatives"),
        _ => (me_function(which), "a Model Exchange function"),
    };
    let n_out = vrs.len();
    let d = r.d();
    let states_given = set_states[..n.min(set_states.len())].to_vec();
    let res = call_on(
        r,
        t,
        f,
        &format!("{name} (#{which}, n = {n}{})", if null { ", NULL array" } else { "" }),
        |slot| {
            if f == Fn::GetRealOutputDerivatives {
                vec![OK, ERROR]
            } else if f == Fn::GetDirectionalDerivative && n_out == 0 {
                // Nothing asked: OK, or an error where outputs are not computable.
                vec![OK, ERROR]
            } else if (1..=10).contains(&which) {
                me_expected(d, slot, which, n, null, x, &states_given)
            } else {
                vec![ERROR]
            }
        },
        |c| unsafe {
            let terminate = if null { null_mut() } else { flags.as_mut_ptr().add(1) };
            match which {
                0 => fmi2GetDirectionalDerivative(c, vrs.as_ptr(), n_out, vrs.as_ptr(), n_out, p, p),
                1 => fmi2EnterEventMode(c),
                2 => fmi2NewDiscreteStates(c, if null { null_mut() } else { &mut info }),
                3 => fmi2EnterContinuousTimeMode(c),
                4 => fmi2CompletedIntegratorStep(c, 1, flags.as_mut_ptr(), terminate),
                5 => fmi2SetTime(c, x),
                6 => fmi2SetContinuousStates(c, p, n),
                7 => fmi2GetDerivatives(c, p, n),
                8 => fmi2GetEventIndicators(c, p, n),
                9 => fmi2GetContinuousStates(c, p, n),
                10 => fmi2GetNominalsOfContinuousStates(c, p, n),
                11 => fmi2CancelStep(c),
                _ => fmi2GetRealOutputDerivatives(c, vrs.as_ptr(), n_out, orders.as_ptr(), p),
            }
        },
    )?;
    if let Some((i, OK)) = res {
        if which == 2 && info.nextEventTimeDefined != 0 {
            r.finite(i, info.nextEventTime, "nextEventTime")?;
        }
        let what = match which {
            1..=6 => return me_accepted(r, i, which, &states_given, x),
            7 => "a derivative",
            8 => "an event indicator",
            9 => "a continuous state",
            10 => "a nominal",
            12 | 13 => "an output derivative",
            _ => return Ok(()),
        };
        let count = if (7..=10).contains(&which) { n } else { n_out };
        if !null {
            for &v in &buf[..count] {
                r.finite(i, v, what)?;
            }
        }
    }
    Ok(())
}

/// The number of values a Model Exchange call `which` (1 to 10) is given: mostly what the model
/// has (states, event indicators), at times 0 to 3; a directional or output derivative's 0 to 3.
fn me_count(d: Desc, src: &mut Source, which: usize) -> usize {
    let (nx, nz) = (d.states.len(), d.number_of_event_indicators);
    match which {
        6 | 7 | 9 | 10 if src.chance(160) => nx,
        8 if src.chance(160) => nz,
        _ => src.pick(4),
    }
}

/// Model Exchange's functions as the random calls number them (op_unsupported, op_unsupported3).
fn me_function(which: usize) -> Fn {
    match which {
        1 => Fn::EnterEventMode,
        2 => Fn::NewDiscreteStates,
        3 => Fn::EnterContinuousTimeMode,
        4 => Fn::CompletedIntegratorStep,
        5 => Fn::SetTime,
        6 => Fn::SetContinuousStates,
        7..=9 => Fn::GetComputed,
        10 => Fn::GetNominals,
        _ => Fn::Other,
    }
}

/// What Model Exchange's function `which` (1 to 10) answers where the standard allows it: given
/// `n` values (`null`: a NULL array or out-argument), the time `x` (#5), the states `states` (#6).
fn me_expected(d: Desc, slot: &Slot, which: usize, n: usize, null: bool, x: f64, states: &[f64]) -> Vec<i32> {
    let (nx, nz) = (d.states.len(), d.number_of_event_indicators);
    let sized = |count: usize| (!null || n == 0) && n == count;
    match which {
        1 | 3 => vec![OK],
        2 | 4 => vec![if null { ERROR } else { OK }],
        5 => vec![if x.is_finite() { OK } else { ERROR }],
        6 if !sized(nx) || states.iter().any(|v| !v.is_finite()) => vec![ERROR],
        // A state the model cannot hold (no length of web) is discarded, or refused.
        6 => vec![OK, DISCARD, ERROR],
        7 | 9 if !sized(nx) => vec![ERROR],
        8 if !sized(nz) => vec![ERROR],
        7..=9 => computed(slot),
        _ if !sized(nx) => vec![ERROR],
        // (The Line knows its nominals only once its network is joined, in initialization.)
        _ if !slot.initialized => vec![OK, ERROR],
        _ => vec![OK],
    }
}


/// What a Model Exchange call (1 to 6) that answered OK changed: the state, the time, the values.
fn me_accepted(r: &mut Run, i: usize, which: usize, states: &[f64], x: f64) -> Result<(), Violation> {
    let slot = r.slot_mut(i);
    match which {
        1 => slot.st = St::Event,
        3 => slot.st = St::Continuous,
        5 => slot.time = x,
        _ => {}
    }
    if matches!(which, 5 | 6) {
        accepted_set(r, i, which, states, x)?;
    }
    Ok(())
}

/// A time (#5) or continuous states (#6) the FMU accepted, in either
/// interface: states must have been finite; the instance's values now span
/// what was set.
fn accepted_set(r: &mut Run, i: usize, which: usize, states: &[f64], time: f64) -> Result<(), Violation> {
    if which == 6 {
        if let Some(x) = states.iter().find(|x| !x.is_finite()) {
            return fail(format!("{}: accepted the continuous state {x}", r.what));
        }
    }
    let set: &[f64] = if which == 6 { states } else { std::slice::from_ref(&time) };
    let slot = r.slot_mut(i);
    for &x in set {
        slot.values = slot.values.worsen(Values::Moderate).worsen(magnitude(x));
    }
    Ok(())
}

/// FMI 3.0's other functions: Model Exchange's (refused by a co-simulation
/// instance), directional derivatives with value counts, the counts of
/// states and event indicators, and those this FMU refuses in every state
/// (clocks, configuration mode, Step Mode's event mode, output and adjoint
/// derivatives, Scheduled Execution); the types it has no variables of accept
/// only empty calls.
fn op_unsupported3(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    use fmi_testkit::fmi3 as c3;
    let which = src.pick(22);
    if which == 21 {
        let s = unsafe {
            c3::fmi3InstantiateScheduledExecution(
                c"fuzz".as_ptr(),
                std::ptr::null(),
                std::ptr::null(),
                0,
                0,
                null_mut(),
                None,
                None,
                None,
                None,
            )
        };
        r.out.calls += 1;
        if !s.is_null() {
            return fail(format!("fmi3InstantiateScheduledExecution returned {s:?}"));
        }
        return Ok(());
    }
    let t = target(r, src);
    let n = me_count(r.d(), src, which);
    let m = src.pick(4);
    let unknowns: Vec<u32> = (0..n).map(|_| vr(r.d(), src, |v| v.causality == Causality::Output)).collect();
    let knowns: Vec<u32> = (0..m).map(|_| vr(r.d(), src, |v| v.causality == Causality::Input)).collect();
    let (n_seed, n_sens) = (count(Api::Fmi3, src, m), count(Api::Fmi3, src, n));
    let mut buf = vec![0.0f64; n.max(8)];
    for x in buf.iter_mut() {
        *x = if src.chance(128) { 1.0 - (src.u8() as f64) * 1e-5 } else { real(src) };
    }
    let set_states = buf.clone();
    let seed = vec![1.0f64; 8];
    let null = src.chance(64);
    let p = if null { null_mut() } else { buf.as_mut_ptr() };
    let x = real(src);
    let mut flags = [0u8; 6];
    let mut next = f64::NAN;
    let mut number = usize::MAX;
    let (f, name) = match which {
        0 => (Fn::GetDirectionalDerivative, "fmi3GetDirectionalDerivative"),
        16 => (Fn::Get, "fmi3GetFloat32"),
        17 => (Fn::Set, "fmi3SetUInt8"),
        _ => (me_function(which), "another fmi3 function"),
    };
    let (nx, nz) = (r.d().states.len(), r.d().number_of_event_indicators);
    let d = r.d();
    let states_given = set_states[..n.min(set_states.len())].to_vec();
    let res = call_on(
        r,
        t,
        f,
        &format!("{name} (#{which}, n = {n}, m = {m}{})", if null { ", NULL array" } else { "" }),
        |slot| {
            match which {
                0 if n_seed != m || n_sens != n || (null && n > 0) => vec![ERROR],
                // Unknowns and knowns the FMU has no derivative of are refused.
                0 => vec![OK, ERROR],
                1..=10 => me_expected(d, slot, which, n, null, x, &states_given),
                11 | 12 if slot.me && !null => vec![OK],
                16 | 17 if n == 0 => vec![OK],
                _ => vec![ERROR],
            }
        },
        |c| unsafe {
            let [a, b, e, d, g, h] = &mut flags;
            let number = if null { null_mut() } else { &mut number as *mut usize };
            match which {
                0 => c3::fmi3GetDirectionalDerivative(
                    c,
                    unknowns.as_ptr(),
                    n,
                    knowns.as_ptr(),
                    m,
                    seed.as_ptr(),
                    n_seed,
                    p,
                    n_sens,
                ),
                1 => c3::fmi3EnterEventMode(c),
                2 if null => c3::fmi3UpdateDiscreteStates(c, a, b, null_mut(), d, g, &mut next),
                2 => c3::fmi3UpdateDiscreteStates(c, a, b, e, d, g, &mut next),
                3 => c3::fmi3EnterContinuousTimeMode(c),
                4 => c3::fmi3CompletedIntegratorStep(c, 1, a, if null { null_mut() } else { h }),
                5 => c3::fmi3SetTime(c, x),
                6 => c3::fmi3SetContinuousStates(c, p, n),
                7 => c3::fmi3GetContinuousStateDerivatives(c, p, n),
                8 => c3::fmi3GetEventIndicators(c, p, n),
                9 => c3::fmi3GetContinuousStates(c, p, n),
                10 => c3::fmi3GetNominalsOfContinuousStates(c, p, n),
                11 => c3::fmi3GetNumberOfContinuousStates(c, number),
                12 => c3::fmi3GetNumberOfEventIndicators(c, number),
                13 => c3::fmi3EnterStepMode(c),
                14 => c3::fmi3GetOutputDerivatives(c, unknowns.as_ptr(), n, [1i32; 4].as_ptr(), p, n),
                15 => c3::fmi3GetClock(c, unknowns.as_ptr(), n, a),
                16 => c3::fmi3GetFloat32(c, unknowns.as_ptr(), n, [0f32; 4].as_mut_ptr(), n),
                17 => c3::fmi3SetUInt8(c, knowns.as_ptr(), n, [0u8; 4].as_ptr(), n),
                18 => c3::fmi3EnterConfigurationMode(c),
                19 => c3::fmi3GetAdjointDerivative(c, unknowns.as_ptr(), n, knowns.as_ptr(), m, seed.as_ptr(), m, p, n),
                _ => c3::fmi3EvaluateDiscreteStates(c),
            }
        },
    )?;
    if let Some((i, OK)) = res {
        if which == 2 && flags[4] != 0 {
            r.finite(i, next, "nextEventTime")?;
        }
        let what = match which {
            1..=6 => return me_accepted(r, i, which, &states_given, x),
            11 | 12 if number != [nx, nz][which - 11] => {
                return fail(format!("{}: answered {number}", r.what));
            }
            0 => "a directional derivative",
            7 => "a derivative",
            8 => "an event indicator",
            9 => "a continuous state",
            10 => "a nominal",
            _ => return Ok(()),
        };
        if !null {
            for &v in &buf[..n] {
                r.finite(i, v, what)?;
            }
        }
    }
    Ok(())
}

fn op_input_derivatives(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    if r.api == Api::Fmi3 {
        // FMI 3.0 has no input derivatives.
        return op_unsupported3(r, src);
    }
    let t = target(r, src);
    let n = src.pick(4);
    let vrs: Vec<u32> = (0..n)
        .map(|_| {
            vr(r.d(), src, |v| {
                v.causality == Causality::Input && family(v) == Family::Real
            })
        })
        .collect();
    let orders: Vec<i32> = (0..n)
        .map(|_| {
            if src.chance(200) {
                1
            } else {
                integer(src, None)
            }
        })
        .collect();
    let values: Vec<f64> = (0..n)
        .map(|_| {
            if src.chance(128) {
                (src.u8() as f64 - 128.0) / 16.0
            } else {
                real(src)
            }
        })
        .collect();
    let vr_ptr = maybe_null(src, &vrs);
    let order_ptr = maybe_null(src, &orders);
    let value_ptr = maybe_null(src, &values);
    let valid = n == 0
        || (!vr_ptr.is_null() && !order_ptr.is_null() && !value_ptr.is_null())
            && vrs.iter().zip(&orders).zip(&values).all(|((&x, &o), v)| {
                var(r.d(), x, Family::Real).is_some_and(|v| v.causality == Causality::Input)
                    && o == 1
                    && v.is_finite()
            });
    let can = r.d().can_interpolate_inputs;
    let res = call_on(
        r,
        t,
        Fn::SetRealInputDerivatives,
        &format!("fmi2SetRealInputDerivatives({vrs:?}, {orders:?}, {values:?})"),
        // The model may refuse derivatives it cannot use (e.g. with a
        // solver that holds the inputs), which it says in the log.
        // With canInterpolateInputs false every call is refused, an empty one too.
        |_| {
            if valid && can && n > 0 {
                vec![OK, ERROR]
            } else {
                vec![if valid && can { OK } else { ERROR }]
            }
        },
        |c| unsafe { fmi2SetRealInputDerivatives(c, vr_ptr, n, order_ptr, value_ptr) },
    )?;
    if let Some((i, OK)) = res {
        if n > 0 {
            let slot = r.slot_mut(i);
            slot.values = slot.values.worsen(Values::Moderate);
            for v in &values {
                slot.values = slot.values.worsen(magnitude(*v));
            }
        }
    }
    Ok(())
}

fn op_debug_logging(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let t = target(r, src);
    let cats = r.d().log_categories;
    let n = src.pick(4);
    let names: Vec<CString> = (0..n)
        .map(|_| match src.pick(8) {
            0 => CString::new("noSuchCategory").unwrap(),
            1 => CString::new("").unwrap(),
            _ => CString::new(cats[src.pick(cats.len())]).unwrap(),
        })
        .collect();
    let mut ptrs: Vec<fmi2String> = names.iter().map(|s| s.as_ptr()).collect();
    if n > 0 && src.chance(12) {
        ptrs[0] = std::ptr::null();
    }
    let array = maybe_null(src, &ptrs);
    let on = boolean(src);
    let strs: Vec<String> = names
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let known =
        !ptrs.contains(&std::ptr::null()) && strs.iter().all(|s| cats.contains(&s.as_str()));
    let ok = n == 0 || (!array.is_null() && known);
    let res = call_on(
        r,
        t,
        Fn::SetDebugLogging,
        &format!("{}({on}, {strs:?})", api.name("fmi2SetDebugLogging", "fmi3SetDebugLogging")),
        |_| vec![if ok { OK } else { ERROR }],
        |c| unsafe { api.set_debug_logging(c, on, n, array) },
    )?;
    if let Some((i, OK)) = res {
        let slot = r.slot_mut(i);
        let on = on != 0;
        let status_cats = ["logStatusWarning", "logStatusDiscard", "logStatusError"];
        if n == 0 {
            slot.status_log = [on; 3];
            slot.log_all = on;
        } else {
            for (k, c) in status_cats.iter().enumerate() {
                if strs.iter().any(|s| s == c) {
                    slot.status_log[k] = on;
                }
            }
            if strs.iter().any(|s| s == "logAll") {
                slot.log_all = on;
            }
        }
    }
    Ok(())
}

fn op_arm_panic(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let t = target(r, src);
    if !src.chance(64) {
        return op_lifecycle_macro(r, src);
    }
    let cat = CString::new(TEST_PANIC_CATEGORY).unwrap();
    let p = cat.as_ptr();
    let api = r.api;
    let res = call_on(
        r,
        t,
        Fn::SetDebugLogging,
        "arm the panic hook",
        |_| vec![OK],
        |c| unsafe { api.set_debug_logging(c, 1, 1, &p) },
    )?;
    if let Some((i, OK)) = res {
        r.slot_mut(i).armed = true;
    }
    Ok(())
}

/// Integer parameters with a small range (the Roller's inlets, outlets and
/// kind of roll): their values in one valid fmi2SetInteger (fmi3SetInt32) in
/// the instantiated state, so that sequences run through the configurations
/// they select (several ports, a roll), which random sets rarely reach.
fn configured_integers(d: Desc) -> Vec<&'static Variable> {
    d
        .variables
        .iter()
        .filter(|v| v.kind == Kind::Integer && v.causality == Causality::Parameter && v.range.lo.is_finite() && v.range.hi - v.range.lo < 256.0)
        .collect()
}

fn configure(r: &mut Run, i: usize, src: &mut Source) -> Result<(), Violation> {
    let vars = configured_integers(r.d());
    if vars.is_empty() {
        return Ok(());
    }
    let vrs: Vec<u32> = vars.iter().map(|v| v.vr).collect();
    let values: Vec<i64> = vars.iter().map(|v| v.range.lo as i64 + src.pick((v.range.hi - v.range.lo) as usize + 1) as i64).collect();
    let (api, c) = (r.api, r.slot(i).c);
    let what = std::mem::replace(&mut r.what, format!("configuration {:?} [slot {i}]", vrs.iter().zip(&values).collect::<Vec<_>>()));
    let s = unsafe { api.set_integer(Int::Int32, c, vrs.as_ptr(), vrs.len(), values.as_ptr(), vrs.len()) };
    r.out.calls += 1;
    r.check_status(s, &[OK])?;
    r.after(i, s)?;
    let slot = r.slot_mut(i);
    slot.values = slot.values.worsen(Values::Moderate);
    r.what = what;
    Ok(())
}

/// A legal move: instantiate, or the next lifecycle call of the state the slot is in, with sane
/// arguments (a reset from the error state, a step of Co-Simulation, the Model Exchange driver's
/// move). Keeps random sequences going deep.
fn op_lifecycle_macro(r: &mut Run, src: &mut Source) -> Result<(), Violation> {
    let mut i = src.pick(2);
    // An instance in the error state is reset first: the random calls meet it there briefly.
    if failed(r, 1 - i) && !failed(r, i) {
        i = 1 - i;
    }
    let api = r.api;
    let Some(slot) = r.slots[i].as_ref() else {
        return instantiate_valid(r, i, src);
    };
    let (c, st, time, poisoned, pristine, me) = (
        slot.c,
        slot.st,
        slot.time,
        slot.poisoned,
        slot.values == Values::Pristine,
        slot.me,
    );
    if !poisoned && me && matches!(st, St::Event | St::Continuous) {
        return model_exchange::drive(r, i, src);
    }
    let label = format!("lifecycle move [slot {i}, {}state {st:?}]", if me { "ME " } else { "" });
    r.what = label.clone();
    r.out.by_state[st as usize] += 1;
    // A step of 10 ms; 1 ms in a scene, whose contact slides (each slide costs the model many steps).
    let h = if slot.scene { 1e-3 } else { 0.01 };
    let (s, expected, next): (i32, Vec<i32>, Option<St>) = unsafe {
        if poisoned || matches!(st, St::Error | St::Terminated | St::StepFailed) || !own_state(st, me) {
            (api.reset(c), vec![OK], Some(St::Instantiated))
        } else {
            match st {
                St::Instantiated => {
                    if src.chance(64) {
                        configure(r, i, src)?;
                    } else if r.scene_steps > 0 && src.chance(128) {
                        scene::take(r, i)?;
                        r.what = label.clone();
                    }
                    if api == Api::Fmi2 {
                        let s = fmi2SetupExperiment(c, 0, 0.0, time, 0, 0.0);
                        r.check_status(s, &[OK])?;
                        r.after(i, s)?;
                    }
                    (api.enter_init(c, (0, 0.0, time, 0, 0.0)), vec![OK], Some(St::Init))
                }
                St::Init => (
                    api.exit_init(c),
                    if pristine { vec![OK] } else { vec![OK, ERROR] },
                    // Model Exchange: initialization ends in event mode.
                    Some(if me { St::Event } else { St::StepComplete }),
                ),
                _ if r.slot(i).scene && r.scene_steps == 0 => (api.terminate(c), vec![OK], Some(St::Terminated)),
                _ => {
                    // A few ordinary steps; the scene's inputs may change before.
                    if r.slot(i).scene {
                        r.scene_steps -= 1;
                    }
                    if src.chance(128) {
                        scene::vary(r, i, src)?;
                        r.what = label.clone();
                    }
                    let armed = r.slot(i).armed;
                    let (s, _) = api.do_step(c, time, h, 1, false);
                    let expected = if armed {
                        vec![ERROR, DISCARD]
                    } else if r.slot(i).values == Values::Pristine {
                        vec![OK]
                    } else {
                        vec![OK, DISCARD, ERROR]
                    };
                    (s, expected, None)
                }
            }
        }
    };
    r.check_status(s, &expected)?;
    r.after(i, s)?;
    let slot = r.slot_mut(i);
    if s == OK {
        match next {
            Some(St::Instantiated) => slot.reset(),
            Some(n) => {
                slot.initialized |= n != St::Init;
                slot.st = n
            }
            None => {
                slot.time = time + h;
                r.out.steps_ok += 1;
                scene::read_contact(r, i)?;
            }
        }
    } else if next.is_none() {
        if s == DISCARD {
            slot.st = St::StepFailed;
        } else if s == ERROR && slot.armed {
            slot.armed = false;
            slot.poisoned = true;
            r.out.panics_caught += 1;
        }
    }
    Ok(())
}

/// An instance with valid arguments in slot `i`: of Model Exchange (where the model offers it)
/// in two thirds of the driven sequences and a quarter of the others, else of Co-Simulation.
fn instantiate_valid(r: &mut Run, i: usize, src: &mut Source) -> Result<(), Violation> {
    let api = r.api;
    let me = r.d().model_exchange && src.chance(if r.driven { 170 } else { 64 });
    let log = Box::<Log>::default();
    let functions = Box::new(callbacks(&log));
    let name = CString::new(format!("fuzz{i}")).unwrap();
    let g = CString::new(r.d().guid.as_ref()).unwrap();
    // No resources where the model can do without (as importers may pass none).
    let (uri, path) = (CString::new(format!("file://{}", r.model.resources)).unwrap(), CString::new(r.model.resources.as_str()).unwrap());
    let (uri, path) = if r.model.needs_resources { (uri.as_ptr(), path.as_ptr()) } else { (std::ptr::null(), std::ptr::null()) };
    let c = unsafe {
        match api {
            Api::Fmi2 => fmi2Instantiate(name.as_ptr(), if me { 0 } else { 1 }, g.as_ptr(), uri, &*functions, 0, 0),
            Api::Fmi3 => api::instantiate3(&api::Instantiate3 {
                model_exchange: me,
                name: name.as_ptr(),
                token: g.as_ptr(),
                resource_path: path,
                logging_on: false,
                event_mode_used: false,
                required: &[],
                log: Some(&*log),
            }),
        }
    };
    r.out.calls += 1;
    if c.is_null() {
        return fail(format!(
            "{} with valid arguments returned NULL: {:?}",
            match (api, me) {
                (Api::Fmi2, _) => "fmi2Instantiate",
                (Api::Fmi3, true) => "fmi3InstantiateModelExchange",
                (Api::Fmi3, false) => "fmi3InstantiateCoSimulation",
            },
            log.take()
        ));
    }
    log.take();
    let functions = (api == Api::Fmi2).then_some(functions);
    let mut slot = new_slot(format!("fuzz{i}"), c, log, functions, false);
    slot.me = me;
    r.slots[i] = Some(slot);
    Ok(())
}
