//! What a fuzz target hands the harness beyond its model (lib.rs: `Fuzzed::scene`,
//! `Fuzzed::contact`): the scene a driven instance takes (parameters before initialization,
//! inputs set again as it runs) and the contact whose stick/slide mode is read after every step,
//! with the transitions counted between consecutive reads.

use crate::api::Instance;
use crate::sequence::{computed, named, settable, Run, Source, Value, Violation};
use fmi_testkit::{ERROR, OK};

/// One call the harness's drivers make on slot `i` with valid arguments in a state that allows
/// it: counted by that state, its status checked against `expected` and its log lines checked.
pub(crate) fn driven(r: &mut Run, i: usize, name: &str, expected: &[i32], call: impl FnOnce(Instance) -> i32) -> Result<i32, Violation> {
    let (c, st) = (r.slot(i).c, r.slot(i).st);
    r.out.by_state[st as usize] += 1;
    r.what = format!("{name} [slot {i}, {}driven, state {st:?}]", if r.slot(i).me { "ME, " } else { "" });
    let s = call(c);
    r.check_status(s, expected)?;
    r.after(i, s)?;
    Ok(s)
}

/// Sets the scene's parameters and the inputs' start values on an instantiated slot.
pub(crate) fn take(r: &mut Run, i: usize) -> Result<(), Violation> {
    let Some(scene) = r.model.scene.clone() else { return Ok(()) };
    let (api, d) = (r.api, r.d());
    for (name, value) in &scene.parameters {
        let vr = named(d, name).vr;
        let what = format!("{}({name} = {value:?}) of the scene", api.name("fmi2Set", "fmi3Set"));
        driven(r, i, &what, &[OK], |c| unsafe {
            match *value {
                Value::Real(x) => api.set_real(c, &vr, 1, &x, 1),
                Value::Boolean(b) => api.set_boolean(c, &vr, 1, &(b as i32), 1),
            }
        })?;
    }
    for &(name, start, _, _) in &scene.inputs {
        set_input(r, i, name, start)?;
    }
    r.slot_mut(i).scene = true;
    Ok(())
}

/// Sets one of the scene's inputs, drawn in its range (a slot that took the scene, in a state
/// where inputs may be set).
pub(crate) fn vary(r: &mut Run, i: usize, src: &mut Source) -> Result<(), Violation> {
    let Some(scene) = &r.model.scene else { return Ok(()) };
    if scene.inputs.is_empty() || !r.slot(i).scene {
        return Ok(());
    }
    let (name, _, lo, hi) = scene.inputs[src.pick(scene.inputs.len())];
    set_input(r, i, name, lo + (hi - lo) * src.u8() as f64 / 255.0)
}

/// A valid fmi2SetReal of an input: OK wherever the standard lets it be set.
fn set_input(r: &mut Run, i: usize, name: &str, x: f64) -> Result<(), Violation> {
    let api = r.api;
    let v = named(r.d(), name);
    let expected = if settable(v, r.slot(i).st) && v.range.contains(x) { OK } else { ERROR };
    let what = format!("{}({name} = {x}) of the scene", api.name("fmi2SetReal", "fmi3SetFloat64"));
    driven(r, i, &what, &[expected], |c| unsafe { api.set_real(c, &v.vr, 1, &x, 1) })?;
    Ok(())
}

/// Reads the contact's mode (after a step, or an event iteration in Model Exchange) and counts a
/// transition where it differs from the last read.
pub(crate) fn read_contact(r: &mut Run, i: usize) -> Result<(), Violation> {
    let Some(contact) = r.model.contact else { return Ok(()) };
    let (api, vr) = (r.api, named(r.d(), contact.output).vr);
    let mut x = f64::NAN;
    let expected = computed(r.slot(i));
    let what = format!("{}({}) for the contact's mode", api.name("fmi2GetReal", "fmi3GetFloat64"), contact.output);
    if driven(r, i, &what, &expected, |c| unsafe { api.get_real(c, &vr, 1, &mut x, 1) })? != OK {
        return Ok(());
    }
    r.finite(i, x, contact.output)?;
    note_mode(r, i, (contact.sliding)(x));
    Ok(())
}

/// The contact's mode now: a transition if it differs from the last one read.
pub(crate) fn note_mode(r: &mut Run, i: usize, sliding: bool) {
    let slot = r.slot_mut(i);
    let me = slot.me as usize;
    if slot.sliding.is_some_and(|before| before != sliding) {
        r.out.transitions[me] += 1;
    }
    r.slot_mut(i).sliding = Some(sliding);
}
