//! The bodies of the calls FMI 2.0 and FMI 3.0 make alike (the rest of each
//! standard's is in its `calls`): the life cycle, Model Exchange, Strings and
//! directional derivatives. Each takes its standard's `call` (for the state
//! mask and the messages) and, where an argument is named in a message, the
//! standard's name of it.

use crate::handle::{enter, out_ref, slice, slice_mut, Handle};
use fmi_core::standard::Call;
use fmi_core::{FmiError, FmiResult, Model};
use std::ffi::{c_char, c_int, c_void};

pub unsafe fn set_debug_logging<M: Model, C: Call>(c: *mut c_void, call: C, on: bool, n: usize, categories: *const *const c_char) -> c_int {
    enter::<M, C>(c, call, |h| {
        let names: Vec<String> = slice(call, categories, n, "categories")?.iter().map(|&n| crate::handle::text(n).unwrap_or_default()).collect();
        h.instance.set_debug_logging(call.name(), on, &names)
    })
}

pub unsafe fn exit_initialization_mode<M: Model, C: Call>(c: *mut c_void, call: C) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.exit_initialization_mode(call.name()))
}

pub unsafe fn terminate<M: Model, C: Call>(c: *mut c_void, call: C) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.terminate())
}

pub unsafe fn reset<M: Model, C: Call>(c: *mut c_void, call: C) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.reset())
}

// ---- Model Exchange

pub unsafe fn enter_event_mode<M: Model, C: Call>(c: *mut c_void, call: C) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.enter_event_mode())
}

pub unsafe fn enter_continuous_time_mode<M: Model, C: Call>(c: *mut c_void, call: C) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.enter_continuous_time_mode())
}

/// No step events: the model never asks for event mode or a stop here (`B`: the standard's Boolean).
pub unsafe fn completed_integrator_step<M: Model, C: Call, B: Default>(c: *mut c_void, call: C, enter_event_mode: *mut B, terminate_simulation: *mut B) -> c_int {
    enter::<M, C>(c, call, |_| {
        *out_ref(call, enter_event_mode, "enterEventMode")? = B::default();
        *out_ref(call, terminate_simulation, "terminateSimulation")? = B::default();
        Ok(())
    })
}

pub unsafe fn set_time<M: Model, C: Call>(c: *mut c_void, call: C, time: f64) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.set_time(call.name(), time))
}

pub unsafe fn set_continuous_states<M: Model, C: Call>(c: *mut c_void, call: C, x: *const f64, nx: usize, what: &str) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.set_continuous_states(call.name(), slice(call, x, nx, what)?))
}

pub unsafe fn get_continuous_states<M: Model, C: Call>(c: *mut c_void, call: C, x: *mut f64, nx: usize, what: &str) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.get_continuous_states(call.name(), slice_mut(call, x, nx, what)?))
}

pub unsafe fn get_derivatives<M: Model, C: Call>(c: *mut c_void, call: C, dx: *mut f64, nx: usize) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.get_derivatives(call.name(), slice_mut(call, dx, nx, "derivatives")?))
}

pub unsafe fn get_event_indicators<M: Model, C: Call>(c: *mut c_void, call: C, z: *mut f64, ni: usize) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.get_event_indicators(call.name(), slice_mut(call, z, ni, "eventIndicators")?))
}

pub unsafe fn get_nominals<M: Model, C: Call>(c: *mut c_void, call: C, nominals: *mut f64, nx: usize, what: &str) -> c_int {
    enter::<M, C>(c, call, |h| h.instance.get_nominals(call.name(), slice_mut(call, nominals, nx, what)?))
}

// ---- Strings and directional derivatives, after each standard's own checks of its arguments

/// The Strings of `vrs` into `out`: their texts stay the handle's until the next call.
pub fn get_strings<M: Model, C: Call>(h: &mut Handle<M>, call: C, vrs: &[u32], out: &mut [*const c_char]) -> FmiResult {
    let mut texts = Vec::with_capacity(vrs.len());
    h.instance.get_strings(call.name(), vrs, |s| texts.push(crate::handle::c_text(s)))?;
    h.hand_out_strings(texts, out);
    Ok(())
}

/// Sets the Strings of `vrs` to the `n` texts at `values` (`what`: the argument's name).
pub unsafe fn set_strings<M: Model, C: Call>(h: &mut Handle<M>, call: C, vrs: &[u32], values: *const *const c_char, what: &str) -> FmiResult {
    let texts = slice(call, values, vrs.len(), what)?
        .iter()
        .enumerate()
        .map(|(i, &s)| crate::handle::utf8(call, s, what, i))
        .collect::<FmiResult<Vec<_>>>()?;
    h.instance.set_strings(call.name(), vrs, &texts)
}

/// The directional derivative: `names` of the unknowns, the knowns, the seed and the result,
/// as the standard names them. The seed and the result must not share memory (it would be
/// read after it is written, and alias in Rust).
#[allow(clippy::too_many_arguments)]
pub unsafe fn directional_derivative<M: Model, C: Call>(
    h: &mut Handle<M>,
    call: C,
    unknowns: *const u32,
    n_unknown: usize,
    knowns: *const u32,
    n_known: usize,
    seed: *const f64,
    out: *mut f64,
    names: [&str; 4],
) -> FmiResult {
    let [unknowns_name, knowns_name, seed_name, out_name] = names;
    let unknowns = slice(call, unknowns, n_unknown, unknowns_name)?;
    let knowns = slice(call, knowns, n_known, knowns_name)?;
    if overlap(seed, n_known, out, n_unknown) {
        return Err(FmiError::error(format!("{}: {seed_name} and {out_name} overlap; pass separate arrays", call.name())));
    }
    let seed = slice(call, seed, n_known, seed_name)?;
    let out = slice_mut(call, out, n_unknown, out_name)?;
    h.instance.get_directional_derivative(call.name(), unknowns, knowns, seed, out)
}

/// Whether two arrays of f64 share memory (empty and NULL ones never do).
fn overlap(a: *const f64, na: usize, b: *mut f64, nb: usize) -> bool {
    let (a, b) = (a as usize, b as usize);
    let size = std::mem::size_of::<f64>();
    na > 0 && nb > 0 && a != 0 && b != 0 && a < b.saturating_add(nb.saturating_mul(size)) && b < a.saturating_add(na.saturating_mul(size))
}
