//! A loop's feed-forward whose reference is another part's input v_ref [R10]: the roller that feeds
//! forward reads it as its loop.speed, and its slope as loop.acceleration. The slope is the
//! importer's derivative for the step (fmi2SetRealInputDerivatives) where it gives one, else the
//! reference's difference over the last step taken (the step before: a backward difference, half
//! a step late). Model Exchange has neither, so a line with a feed is refused there.

use crate::part::Part;
use crate::spec::Spec;
use fmi_core::FmiResult;
use roller::description::Real;

/// One roller's feed-forward on another part's input v_ref.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Feed {
    /// The part whose input v_ref (its loop.speed) is the reference.
    pub from: usize,
    /// The roller that feeds forward.
    pub to: usize,
    /// The reference where the last step taken started: (time, value); None before the first.
    pub last: Option<(f64, f64)>,
    /// The importer's derivative of the reference for the step to come.
    pub derivative: Option<f64>,
    /// The reference where the step under way started, and the slope the roller had before it.
    pub start: f64,
    pub slope_before: f64,
}

/// The feeds line.json asks for, checked: the reference a part's input v_ref, the feeding part a
/// roller whose loop feeds forward without a reference table.
pub fn from_spec(spec: &Spec, parts: &[Part]) -> Result<Vec<Feed>, String> {
    let mut feeds = Vec::new();
    for (to, ps) in spec.parts.iter().enumerate() {
        let Some(name) = &ps.feedforward_from else { continue };
        let what = format!("line.json: part {}: feedforward_from {name:?}", ps.name);
        let from = spec.part(name).filter(|&p| spec.parts[p].speed_input).ok_or_else(|| format!("{what} is no part with an input v_ref (speed_input)"))?;
        let feeds_forward = matches!(&parts[to], Part::Roller(r) if r.params.loop_feedforward);
        if !feeds_forward || ps.has_table("reference") {
            return Err(format!("{what}: needs a roller whose loop feeds forward (loop.feedforward = true) and has no reference table"));
        }
        feeds.push(Feed { from, to, last: None, derivative: None, start: 0.0, slope_before: 0.0 });
    }
    Ok(feeds)
}

/// Why a line with feeds cannot run in Model Exchange (None: it has none).
pub fn model_exchange_refusal(spec: &Spec, feeds: &[Feed]) -> Option<String> {
    let f = feeds.first()?;
    Some(format!(
        "{}'s feed-forward takes the slope of its reference, the input {}.v_ref: Model Exchange gives no input derivatives \
         and has no steps to take a difference over, so it would feed forward nothing; run the line in Co-Simulation, \
         or give the reference as a profile",
        spec.parts[f.to].name, spec.parts[f.from].name
    ))
}

/// The reference moved: the feeding rollers read it as their loop.speed.
pub fn follow(feeds: &[Feed], parts: &mut [Part], from: usize) -> FmiResult {
    let vr = Real::loop_speed.vr();
    for f in feeds.iter().filter(|f| f.from == from) {
        let v = parts[from].get_real(vr)?;
        parts[f.to].set_real(vr, v)?;
    }
    Ok(())
}

/// The importer gave the reference's derivative for the step to come: the feeding rollers' loop.speed
/// ramps with it (the ramp of `ramps`, pushed here), and it is their slope.
pub fn derivative(feeds: &mut [Feed], parts: &[Part], ramps: &mut Vec<crate::ode::Ramp>, from: usize, rate: f64) -> FmiResult {
    let vr = Real::loop_speed.vr();
    for f in feeds.iter_mut().filter(|f| f.from == from) {
        f.derivative = Some(rate);
        let base = parts[f.to].get_real(vr)?;
        match ramps.iter_mut().find(|(p, v, _, _)| *p == f.to && *v == vr) {
            Some(r) => *r = (f.to, vr, base, rate),
            None => ramps.push((f.to, vr, base, rate)),
        }
    }
    Ok(())
}

/// At a step's start (time t): each feeding roller's loop.acceleration, the importer's derivative
/// or the difference since the last step's start (0 before the first step, or where the time has
/// not moved); whether one changed.
pub fn slopes(feeds: &mut [Feed], parts: &mut [Part], t: f64) -> FmiResult<bool> {
    let (speed, acceleration) = (Real::loop_speed.vr(), Real::loop_acceleration.vr());
    let mut changed = false;
    for f in feeds.iter_mut() {
        let v = parts[f.from].get_real(speed)?;
        f.start = v;
        let slope = match (f.derivative, f.last) {
            (Some(a), _) => a,
            (None, Some((t0, v0))) if t > t0 => (v - v0) / (t - t0),
            _ => 0.0,
        };
        f.slope_before = parts[f.to].get_real(acceleration)?;
        if f.slope_before != slope {
            parts[f.to].set_real(acceleration, slope)?;
            changed = true;
        }
    }
    Ok(changed)
}

/// A step failed: the feeding rollers' slopes as they were before it (a failed step changes nothing).
pub fn undo(feeds: &[Feed], parts: &mut [Part]) {
    for f in feeds {
        let _ = parts[f.to].set_real(Real::loop_acceleration.vr(), f.slope_before);
    }
}

/// A step from time t succeeded: its start is the last step's, and the importer's derivatives are used.
pub fn stepped(feeds: &mut [Feed], t: f64) {
    for f in feeds.iter_mut() {
        f.last = Some((t, f.start));
        f.derivative = None;
    }
}
