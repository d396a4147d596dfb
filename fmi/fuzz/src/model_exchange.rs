//! The Model Exchange driver: what an importer with an integrator does with an instance after
//! initialization (FMI 2.0, 3.2.3; FMI 3.0's calls alike, api.rs). In event mode it iterates
//! fmi2NewDiscreteStates until no new iteration is needed and keeps the next time event; in
//! continuous-time mode it takes implicit Euler steps (a Newton iteration on a Jacobian of
//! finite differences, so that stiff contacts stay stable) with fmi2SetTime,
//! fmi2SetContinuousStates, fmi2GetDerivatives, fmi2GetEventIndicators and
//! fmi2CompletedIntegratorStep, and enters event mode at a time event, where an event indicator
//! changes sign, and where the step asks for it. Inputs of the scene change in both modes.
//!
//! Every call is valid, so the oracle expects fmi2OK where the values are the start values or
//! the scene's (a trial state may be discarded), and checks that every number is finite.

use crate::api::{self, Api, Instance};
use crate::newton::Newton;
use crate::scene::{driven, read_contact, vary};
use crate::sequence::{computed, fail, Run, Source, St, Values, Violation};
use fmi_testkit::{DISCARD, OK};


/// The integrator steps of one sequence: enough for an instance to go through events, and for a
/// contact to stick and slide, at a cost near the random calls' (an ME step makes about 12 calls).
pub(crate) const STEPS: u32 = 12;
/// At most this many fmi2NewDiscreteStates in one event iteration.
const ITERATIONS: usize = 100;
/// Relative change of a Newton iteration that counts as converged.
const NEWTON_TOLERANCE: f64 = 1e-6;

/// The kinds of events counted in `Outcome::events`.
const TIME_EVENT: usize = 0;
const STATE_EVENT: usize = 1;
const STEP_EVENT: usize = 2;

/// One move on slot `i` (a Model Exchange instance in event or continuous-time mode): an event
/// iteration where it is in event mode, then up to 4 steps of one size, each event on the way
/// handled as it comes. An instance whose values are extreme or forged is not integrated (where
/// its states overflow, the harness's integrator would be to blame as much as the model).
pub(crate) fn drive(r: &mut Run, i: usize, src: &mut Source) -> Result<(), Violation> {
    if r.me_steps == 0 || matches!(r.slot(i).values, Values::Extreme | Values::Forged) {
        return finish(r, i);
    }
    if r.slot(i).st == St::Event && !(event_iteration(r, i, src)? && enter_continuous(r, i)?) {
        return Ok(());
    }
    let h = [1e-4, 1e-3, 1e-3, 5e-3][src.pick(4)];
    let nx = r.d().states.len();
    let mut newton = r.slot_mut(i).integration.newton.take().unwrap_or_else(|| Newton::new(nx));
    let Ok(nominals) = nominals(r, i)? else { return Ok(()) };
    for _ in 0..1 + src.pick(4) {
        if r.slot(i).st != St::Continuous || r.me_steps == 0 {
            break;
        }
        r.me_steps -= 1;
        match step(r, i, src, h, &nominals, &mut newton)? {
            Some(kind) => {
                r.out.events[kind] += 1;
                let api = r.api;
                let name = api.name("fmi2EnterEventMode", "fmi3EnterEventMode");
                if driven(r, i, name, &[OK], |c| unsafe { api.enter_event_mode(c) })? != OK {
                    break;
                }
                r.slot_mut(i).st = St::Event;
                if !(event_iteration(r, i, src)? && enter_continuous(r, i)?) {
                    break;
                }
            }
            None if r.slot(i).st == St::Continuous => {}
            None => break,
        }
    }
    if let Some(slot) = r.slots[i].as_mut() {
        slot.integration.newton = Some(newton);
    }
    Ok(())
}

/// Once the sequence's steps are taken, or where they are not taken: back to event mode, and
/// terminated (a reset follows).
fn finish(r: &mut Run, i: usize) -> Result<(), Violation> {
    let api = r.api;
    if r.slot(i).st == St::Continuous {
        let name = api.name("fmi2EnterEventMode", "fmi3EnterEventMode");
        if driven(r, i, name, &[OK], |c| unsafe { api.enter_event_mode(c) })? == OK {
            r.slot_mut(i).st = St::Event;
        }
    } else {
        let name = api.name("fmi2Terminate", "fmi3Terminate");
        if driven(r, i, name, &[OK], |c| unsafe { api.terminate(c) })? == OK {
            r.slot_mut(i).st = St::Terminated;
        }
    }
    Ok(())
}

/// fmi2NewDiscreteStates until no new iteration is needed; the scene's inputs may change first.
/// False if the instance left event mode (an error, or the model asked to terminate).
fn event_iteration(r: &mut Run, i: usize, src: &mut Source) -> Result<bool, Violation> {
    if src.chance(128) {
        vary(r, i, src)?;
    }
    let api = r.api;
    let name = api.name("fmi2NewDiscreteStates", "fmi3UpdateDiscreteStates");
    for _ in 0..ITERATIONS {
        let mut answer = api::Discrete::default();
        let s = driven(r, i, name, &[OK], |c| unsafe {
            let (s, d) = api.new_discrete_states(c);
            answer = d;
            s
        })?;
        if s != OK {
            return Ok(false);
        }
        if answer.terminate {
            let name = api.name("fmi2Terminate", "fmi3Terminate");
            if driven(r, i, name, &[OK], |c| unsafe { api.terminate(c) })? == OK {
                r.slot_mut(i).st = St::Terminated;
            }
            return Ok(false);
        }
        if answer.needed {
            continue;
        }
        if let Some(te) = answer.next_event {
            r.finite(i, te, "nextEventTime")?;
            let t = r.slot(i).time;
            if !(te > t) && r.slot(i).values == Values::Pristine {
                return fail(format!("{}: nextEventTime {te} is not after the time {t}", r.what));
            }
        }
        r.slot_mut(i).integration.next_event = answer.next_event.filter(|te| te.is_finite());
        r.out.me_event = true;
        read_contact(r, i)?;
        return Ok(r.slot(i).st == St::Event);
    }
    fail(format!("{}: the event iteration did not end in {ITERATIONS} calls", r.what))
}

fn enter_continuous(r: &mut Run, i: usize) -> Result<bool, Violation> {
    let api = r.api;
    let name = api.name("fmi2EnterContinuousTimeMode", "fmi3EnterContinuousTimeMode");
    if driven(r, i, name, &[OK], |c| unsafe { api.enter_continuous_time_mode(c) })? != OK {
        return Ok(false);
    }
    let slot = r.slot_mut(i);
    slot.st = St::Continuous;
    slot.integration.z.clear();
    Ok(true)
}


/// What the states' calls answered: a value, or the status that stopped the step.
type Answer<T> = Result<Result<T, i32>, Violation>;

/// One implicit Euler step from the instance's time, of size `h` or up to the next time event;
/// on a Newton iteration that does not converge, the Jacobian is formed again and the step
/// shortened (3 times at most), else the step is not taken. The event it ends at, if any.
fn step(r: &mut Run, i: usize, src: &mut Source, h: f64, nominals: &[f64], newton: &mut Newton) -> Result<Option<usize>, Violation> {
    let t = r.slot(i).time;
    let mut h = h;
    let mut kind = None;
    if let Some(te) = r.slot(i).integration.next_event {
        if te <= t {
            return Ok(Some(TIME_EVENT));
        }
        if t + h >= te {
            (h, kind) = (te - t, Some(TIME_EVENT));
        }
    }
    if src.chance(40) {
        vary(r, i, src)?;
    }
    let nx = r.d().states.len();
    let Ok(x0) = states(r, i)? else { return Ok(None) };
    let mut x = x0.clone();
    let mut converged = false;
    // A kept J that fails is formed again for the same step; a new one that fails, for a shorter one.
    for _ in 0..6 {
        if !set_time(r, i, t + h)? {
            return Ok(None);
        }
        if nx == 0 {
            converged = true;
            break;
        }
        x.copy_from_slice(&x0);
        let kept = newton.fresh;
        match solve(r, i, &x0, nominals, h, newton, &mut x)? {
            Ok(true) => {
                converged = true;
                break;
            }
            Err(_) if r.slot(i).st != St::Continuous => return Ok(None),
            _ if kept => newton.fresh = false,
            _ => (h, kind) = (0.25 * h, None),
        }
    }
    if !converged {
        // Back to where the step began.
        set_time(r, i, t)?;
        let _ = set_states(r, i, &x0)?;
        return Ok(None);
    }
    // The step's end: its derivatives, event indicators, and the step completed.
    if nx > 0 && !matches!(set_states(r, i, &x)?, Ok(())) {
        return Ok(None);
    }
    if derivatives(r, i)?.is_err() {
        return Ok(None);
    }
    let Ok(z) = indicators(r, i)? else { return Ok(None) };
    let before = std::mem::replace(&mut r.slot_mut(i).integration.z, z.clone());
    if kind.is_none() && before.iter().zip(&z).any(|(a, b)| (*a > 0.0) != (*b > 0.0)) {
        kind = Some(STATE_EVENT);
    }
    let api = r.api;
    let (mut enter, mut terminate) = (false, false);
    let name = api.name("fmi2CompletedIntegratorStep", "fmi3CompletedIntegratorStep");
    let s = driven(r, i, name, &[OK], |c| unsafe {
        let (s, e, t) = api.completed_integrator_step(c);
        (enter, terminate) = (e, t);
        s
    })?;
    if s != OK {
        return Ok(None);
    }
    r.out.me_step = true;
    r.out.steps_ok += 1;
    read_contact(r, i)?;
    if terminate {
        let name = api.name("fmi2Terminate", "fmi3Terminate");
        if driven(r, i, name, &[OK], |c| unsafe { api.terminate(c) })? == OK {
            r.slot_mut(i).st = St::Terminated;
        }
        return Ok(None);
    }
    Ok(kind.or(enter.then_some(STEP_EVENT)))
}

/// Newton's iteration on x - x0 - h f(t + h, x) = 0 from `x` (= x0): Ok(true) once converged,
/// Ok(false) if not in 8 iterations; Err(status) where a call did not answer OK.
fn solve(r: &mut Run, i: usize, x0: &[f64], nominals: &[f64], h: f64, newton: &mut Newton, x: &mut [f64]) -> Answer<bool> {
    let n = x.len();
    if !newton.fresh {
        // J at x0, by forward differences scaled by the nominals.
        let f0 = match at(r, i, x)? {
            Ok(f) => f,
            Err(s) => return Ok(Err(s)),
        };
        let mut xj = x.to_vec();
        for j in 0..n {
            let delta = 1e-7 * x[j].abs().max(nominals[j].abs()).max(1e-12);
            xj[j] = x[j] + delta;
            let fj = match at(r, i, &xj)? {
                Ok(f) => f,
                Err(s) => return Ok(Err(s)),
            };
            xj[j] = x[j];
            for k in 0..n {
                newton.jacobian.set(k, j, (fj[k] - f0[k]) / delta);
            }
        }
        (newton.h, newton.fresh) = (0.0, true);
    }
    if newton.h != h {
        if !newton.lu.factor_shifted(1.0 / h, &newton.jacobian) {
            newton.fresh = false;
            return Ok(Ok(false));
        }
        newton.h = h;
    }
    // The largest change over its tolerance, which must fall by half in every iteration.
    let mut before = f64::INFINITY;
    for _ in 0..8 {
        let f = match at(r, i, x)? {
            Ok(f) => f,
            Err(s) => return Ok(Err(s)),
        };
        // (1/h - J) dx = (x0 - x)/h + f(x)
        let mut dx: Vec<f64> = (0..n).map(|k| (x0[k] - x[k]) / h + f[k]).collect();
        newton.lu.solve(&mut dx);
        let mut change = 0.0f64;
        for k in 0..n {
            x[k] += dx[k];
            change = change.max(dx[k].abs() / (NEWTON_TOLERANCE * x[k].abs().max(nominals[k].abs())));
        }
        if change <= 1.0 {
            return Ok(Ok(true));
        }
        if !(change < 0.5 * before) {
            break;
        }
        before = change;
    }
    Ok(Ok(false))
}

/// The derivatives at the states `x` (set first).
fn at(r: &mut Run, i: usize, x: &[f64]) -> Answer<Vec<f64>> {
    if let Err(s) = set_states(r, i, x)? {
        return Ok(Err(s));
    }
    derivatives(r, i)
}

fn set_time(r: &mut Run, i: usize, t: f64) -> Result<bool, Violation> {
    let api = r.api;
    let s = driven(r, i, api.name("fmi2SetTime", "fmi3SetTime"), &[OK], |c| unsafe { api.set_time(c, t) })?;
    if s == OK {
        r.slot_mut(i).time = t;
    }
    Ok(s == OK)
}

/// An integrator's states: a trial one may be discarded (the span holds no length of web
/// beyond its limits).
fn set_states(r: &mut Run, i: usize, x: &[f64]) -> Answer<()> {
    let api = r.api;
    let mut expected = computed(r.slot(i));
    expected.push(DISCARD);
    let name = api.name("fmi2SetContinuousStates", "fmi3SetContinuousStates");
    let s = driven(r, i, name, &expected, |c| unsafe { api.set_continuous_states(c, x.as_ptr(), x.len()) })?;
    Ok(if s == OK { Ok(()) } else { Err(s) })
}

/// One of the vectors the instance computes, its values checked finite.
fn vector(r: &mut Run, i: usize, n: usize, name: &'static str, get: impl FnOnce(Api, Instance, *mut f64, usize) -> i32) -> Answer<Vec<f64>> {
    let (api, expected) = (r.api, computed(r.slot(i)));
    let mut v = vec![f64::NAN; n];
    let s = driven(r, i, name, &expected, |c| get(api, c, v.as_mut_ptr(), n))?;
    if s != OK {
        return Ok(Err(s));
    }
    for &x in &v {
        r.finite(i, x, name)?;
    }
    Ok(Ok(v))
}

fn states(r: &mut Run, i: usize) -> Answer<Vec<f64>> {
    let (n, name) = (r.d().states.len(), r.api.name("fmi2GetContinuousStates", "fmi3GetContinuousStates"));
    vector(r, i, n, name, |api, c, p, n| unsafe { api.get_continuous_states(c, p, n) })
}

fn derivatives(r: &mut Run, i: usize) -> Answer<Vec<f64>> {
    let (n, name) = (r.d().states.len(), r.api.name("fmi2GetDerivatives", "fmi3GetContinuousStateDerivatives"));
    vector(r, i, n, name, |api, c, p, n| unsafe { api.get_derivatives(c, p, n) })
}

fn nominals(r: &mut Run, i: usize) -> Answer<Vec<f64>> {
    let (n, name) = (r.d().states.len(), r.api.name("fmi2GetNominalsOfContinuousStates", "fmi3GetNominalsOfContinuousStates"));
    vector(r, i, n, name, |api, c, p, n| unsafe { api.get_nominals(c, p, n) })
}

fn indicators(r: &mut Run, i: usize) -> Answer<Vec<f64>> {
    let (n, name) = (r.d().number_of_event_indicators, r.api.name("fmi2GetEventIndicators", "fmi3GetEventIndicators"));
    vector(r, i, n, name, |api, c, p, n| unsafe { api.get_event_indicators(c, p, n) })
}

/// The continuous states of a Model Exchange instance whose state is being saved (event and
/// continuous-time mode, its values the start values or the scene's): a restored state must
/// give them back.
pub(crate) fn saved_states(r: &mut Run, i: usize) -> Result<Option<Vec<f64>>, Violation> {
    let slot = r.slot(i);
    if !slot.me || slot.poisoned || slot.values != Values::Pristine || !matches!(slot.st, St::Event | St::Continuous) {
        return Ok(None);
    }
    Ok(states(r, i)?.ok())
}

/// After a restore: the continuous states are those saved, bit for bit.
pub(crate) fn check_restored(r: &mut Run, i: usize, saved: &[f64]) -> Result<(), Violation> {
    let what = format!("{} then", r.what);
    match states(r, i)? {
        Ok(x) if x.iter().zip(saved).all(|(a, b)| a.to_bits() == b.to_bits()) => Ok(()),
        Ok(x) => fail(format!("{what}: the continuous states are {x:?}, saved {saved:?}")),
        Err(s) => fail(format!("{what}: fmi2GetContinuousStates answered {s}")),
    }
}
