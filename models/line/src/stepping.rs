//! Time: initialization, a communication step and Model Exchange events.
//!
//! A step runs from event to event (a profile's breakpoint, a `set` entry,
//! a web change: each part names its next one) and Rodas5P integrates the line
//! between them, so every event happens at its exact time whatever the
//! communication step. A failed step leaves the line as it was.

use crate::equilibrium;
use crate::ode::LineSystem;
use crate::interface::Binding;
use crate::network::Network;
use crate::part::Part;
use crate::{Line, Scratch};
use fmi_core::{EventUpdate, Experiment, FmiError, FmiResult, Resources};
use solver::stiff::tableau::{Tableau, RODAS5P};
use solver::stiff::{Control, Rosenbrock};
use solver::Failure;

/// Rounds of copying outputs to inputs and initializing again until the
/// parts agree (a span's start depends on its rollers' speeds, a dancer's
/// spans on its position).
const SETTLE_ROUNDS: usize = 20;

/// The line's integrator: Rodas5P, order 5. At the line's tolerances it takes one step where
/// RODAS4 (order 4) takes 1.6, for 8 evaluations instead of 6 per step; the W-method ROS34PW2
/// keeps its Jacobian over steps but, of order 3, needs 3 to 5 times the steps (docs/line-solver.md).
pub const METHOD: &Tableau = &RODAS5P;

/// Most integrator steps (accepted and rejected) in one communication step.
const MAX_STEPS: usize = 100_000;
/// Below this interval (s) the line is advanced by one explicit Euler step (`integrate`).
const TINY_STEP: f64 = 1e-100;

/// A span's unstretched length x is its length over 1 + strain: the tolerance
/// is meant for the strain (tension is made of it), so on x it is scaled by
/// the largest strain the span has had (at least STRAIN_FLOOR), as if the
/// integrator held the strain itself, relative to its size.
pub const STRAIN_FLOOR: f64 = 1e-7;

pub fn scratch(line: &Line, n: usize) -> Scratch {
    let v = || vec![0.0; n];
    let mut scratch = Scratch { x: v(), f0: v(), f1: v(), y: v(), atol: v(), rtol_scale: vec![0.0; n] };
    tolerances(line, &mut scratch);
    scratch
}

/// The absolute tolerances and the spans' strain scales for the next step.
pub fn tolerances(line: &Line, scratch: &mut Scratch) {
    let Some(net) = &line.net else { return };
    let mut buffer = [0.0; 8];
    for (k, s) in net.states.iter().enumerate() {
        let part = &line.parts[s.part];
        let m = part.state_count();
        let nominal = if part.get_nominals(&mut buffer[..m]).is_ok() && buffer[s.index] != 0.0 { buffer[s.index].abs() } else { 1.0 };
        scratch.rtol_scale[k] = match part {
            Part::Span(span) => scratch.rtol_scale[k].max(span.outputs().strain.abs()).max(STRAIN_FLOOR),
            Part::Roller(_) => 1.0,
        };
        // Absolute tolerance: the relative one of a state of its nominal size.
        scratch.atol[k] = line.rtol * scratch.rtol_scale[k] * nominal;
    }
}

pub fn initialize(line: &mut Line, experiment: &Experiment, resources: &Resources) -> FmiResult<Vec<String>> {
    let spec = line.shared.clone();
    let spec = &spec.spec;
    // The parts are stepped by the line, never by an importer of their own.
    let part_experiment = Experiment { model_exchange: false, ..*experiment };
    let t0 = experiment.start_time;
    // The importer's tolerance counts where it asks for more accuracy than the parameter.
    line.rtol = experiment.tolerance.filter(|&t| t > 0.0 && t < line.tolerance).unwrap_or(line.tolerance);
    let mut warnings = Vec::new();
    let mut net: Option<Network> = None;
    let mut x = Vec::new();
    let mut settled = false;
    for _ in 0..SETTLE_ROUNDS {
        warnings.clear();
        for (p, part) in line.parts.iter_mut().enumerate() {
            let ps = &spec.parts[p];
            let own = resources.clone().for_instance(&ps.name);
            let said = part.initialize(&part_experiment, &own).map_err(|e| e.prefixed(&format!("part {}", ps.name)))?;
            // A part without a profile of its own hears about the others' files: not news in a line.
            if ps.profile.is_some() {
                warnings.extend(said.into_iter().map(|w| format!("part {}: {w}", ps.name)));
            }
        }
        let n = net.get_or_insert(Network::new(spec, &line.parts).map_err(FmiError::error)?);
        x.resize(n.len(), 0.0);
        n.gather(&line.parts, &mut x)?;
        let before = connected_inputs(n, &line.parts)?;
        n.evaluate(&mut line.parts, t0, &x, None).map_err(|e| e.prefixed("the line's start"))?;
        if connected_inputs(n, &line.parts)? == before {
            settled = true;
            break;
        }
    }
    if !settled {
        return Err(FmiError::error(format!("the parts' start values do not settle through the connections in {SETTLE_ROUNDS} rounds")));
    }
    let net = net.expect("built in the first round");
    line.x = x;
    line.time = t0;
    line.ramps.clear();
    line.integrator = Some(Rosenbrock::new(METHOD, net.len(), net.kl, net.ku));
    line.net = Some(net);
    line.scratch = scratch(line, line.x.len());
    apply_events(line)?;
    if line.start_equilibrium {
        if let Err(why) = equilibrium::solve(line) {
            warnings.push(format!("startAtEquilibrium: {why}; the line starts from its parts' start values"));
        }
    }
    line.settle()?;
    Ok(warnings)
}

/// The values of every connected input, to see whether the parts settled.
fn connected_inputs(net: &Network, parts: &[Part]) -> FmiResult<Vec<u64>> {
    net.links.iter().map(|l| parts[l.to].get_real(l.input).map(f64::to_bits)).collect()
}

/// Lets every part apply what is due now; the next event of any part.
fn apply_events(line: &mut Line) -> FmiResult {
    let net = line.net.as_mut().expect("initialized");
    net.evaluate(&mut line.parts, line.time, &line.x, None)?;
    let mut next = f64::INFINITY;
    let mut changed = false;
    net.parts_changed();
    for part in &mut line.parts {
        let update = part.event_update();
        next = next.min(update.next_event_time.unwrap_or(f64::INFINITY));
        changed |= update.states_changed;
    }
    if changed {
        net.gather(&line.parts, &mut line.x)?;
    }
    // What an event applies (a new web, a new roll, a table's kink) changes the Jacobian.
    if let Some(r) = line.integrator.as_mut() {
        r.renew_jacobian();
    }
    line.next_event = next;
    Ok(())
}

/// Integrates the line from its time to `end`, no event inside.
fn integrate(line: &mut Line, end: f64) -> FmiResult {
    let t = line.time;
    let time_dependent = !line.ramps.is_empty() || line.shared.spec.parts.iter().any(|p| p.profile.is_some());
    let Line { parts, net, x, ramps, integrator, scratch, rtol, .. } = line;
    let (net, integrator) = (net.as_mut().expect("initialized"), integrator.as_mut().expect("initialized"));
    let Scratch { f0, f1, y, atol, rtol_scale, .. } = scratch;
    // The parts enter a step evaluated where it begins (every change is evaluated at once), unless an
    // event changed them since; where an evaluation depends on the one before, the integrator's own is kept.
    let evaluated = net.evaluated_at(t, x) && !net.reads_earlier_inputs;
    let mut sys = LineSystem { parts, net, ramps, t_start: t, time_dependent, f0, f1, y, evaluated, t_jacobian: t, differences: false };
    if end - t < TINY_STEP {
        // An interval no dynamics of a line can resolve (a denormal h from an importer), where
        // the integrator's step control underflows: one explicit Euler step, exact to rounding there.
        let dx = std::mem::take(&mut sys.f0); // the scratch's buffer: no allocation in a step
        sys.eval(t, x, dx)?;
        for (xi, di) in x.iter_mut().zip(dx.iter()) {
            *xi += (end - t) * di;
        }
        if x.iter().any(|xi| !xi.is_finite()) {
            return Err(failure(Failure::NotFinite { reached: t }, t, end));
        }
    } else {
        let control = Control { rtol: *rtol, atol, rtol_scale, max_steps: MAX_STEPS, max_step: 0.0 };
        integrator.integrate(&mut sys, t, end, x, &control).map_err(|f| failure(f, t, end))?;
    }
    line.time = end;
    Ok(())
}

fn failure(f: Failure, t: f64, end: f64) -> FmiError {
    FmiError::discard(match f {
        Failure::TooMuchWork { reached, steps } => {
            format!("the line's integrator took {steps} steps from t = {t} s and reached only {reached} s of {end} s: take a shorter step or loosen tolerance")
        }
        Failure::StepTooSmall { reached, step } => format!("the line's integrator needed a step of {step} s at t = {reached} s: the line cannot be followed there"),
        Failure::NotFinite { reached } => {
            format!("the line left the states its parts can take at t = {reached} s (a span with no web, a roll run empty): check the inputs and drives")
        }
    })
}

/// One communication step of length h.
///
/// A failed step is undone without copying the parts in advance when they
/// enter it evaluated at (time, x), as every change leaves them: evaluations
/// change only what an evaluation at (time, x) sets again (times, states,
/// connected inputs, input rates) and the inputs an importer ramps. An event
/// applies more (a web, a roll, a table's next entry): the parts are copied
/// before the first. They are copied before the step where an evaluation
/// failed on them (an input an importer set that they refuse) or where an
/// evaluation depends on the one before (`Network::reads_earlier_inputs`).
pub fn step(line: &mut Line, h: f64) -> FmiResult {
    let t0 = line.time;
    let next_event = line.next_event;
    let next_step = line.integrator.as_ref().map_or(0.0, |r| r.next_step);
    line.scratch.x.copy_from_slice(&line.x);
    let mut copied = !line.net.as_ref().is_some_and(|n| n.evaluated_at(t0, &line.x) && !n.reads_earlier_inputs);
    if copied {
        line.backup.clone_from(&line.parts);
    }
    match advance(line, t0 + h, &mut copied) {
        Ok(()) => {
            // The ramped inputs end the step where their derivatives took them.
            for &(part, vr, base, rate) in &line.ramps {
                line.parts[part].set_real(vr, base + rate * h)?;
            }
            line.ramps.clear();
            line.settle()
        }
        Err(e) => {
            if copied {
                std::mem::swap(&mut line.parts, &mut line.backup);
                if let Some(net) = line.net.as_mut() {
                    net.parts_changed();
                }
            }
            for &(part, vr, base, _) in &line.ramps {
                let _ = line.parts[part].set_real(vr, base);
            }
            line.x.copy_from_slice(&line.scratch.x);
            line.time = t0;
            line.next_event = next_event;
            if let Some(r) = line.integrator.as_mut() {
                r.next_step = next_step;
                // Formed along the failed attempt, perhaps far from the line as it is again.
                r.renew_jacobian();
            }
            let _ = line.settle();
            Err(e)
        }
    }
}

/// `copied`: the parts were copied to `line.backup` before an event (see `step`).
fn advance(line: &mut Line, end: f64, copied: &mut bool) -> FmiResult {
    let mut scratch = std::mem::take(&mut line.scratch);
    tolerances(line, &mut scratch);
    line.scratch = scratch;
    // An event within rounding of the end belongs to the next step's start.
    let last = end - profiles_tolerance(end);
    loop {
        if line.next_event <= line.time + profiles_tolerance(line.time) {
            if !*copied {
                line.backup.clone_from(&line.parts);
                *copied = true;
            }
            apply_events(line)?;
        }
        let stop = if line.next_event < last { line.next_event } else { end };
        if stop > line.time {
            integrate(line, stop)?;
        }
        line.time = stop;
        if stop >= end {
            return Ok(());
        }
    }
}

/// The parts' tolerance for "due now" (their profiles').
fn profiles_tolerance(t: f64) -> f64 {
    1e-9 * t.abs().max(1.0)
}

/// Model Exchange: the parts apply what is due at the time set.
pub fn event_update(line: &mut Line) -> EventUpdate {
    let before = line.x.clone();
    if apply_events(line).is_err() {
        return EventUpdate::default();
    }
    let _ = line.settle();
    EventUpdate {
        next_event_time: line.next_event.is_finite().then_some(line.next_event),
        states_changed: before != line.x,
    }
}

/// d(unknown)/d(known) of the line now, by central differences (step 1e-6
/// of the known's size: truncation ~1e-12, rounding ~1e-10 relative). Known:
/// a state or an input of the line; unknown: an output or a derivative.
/// Before initialization has built the network (an instance that failed
/// before it ended: the error state), only inputs are known, and the parts
/// answer at their own values, as fmi2GetReal does then.
pub fn partial_derivative(line: &Line, unknown: u32, known: u32) -> FmiResult<f64> {
    let state = line.shared.description.states.iter().position(|&vr| vr == known);
    if state.is_some() && line.net.is_none() {
        return Err(FmiError::error("the line is not initialized: it has no states yet"));
    }
    let input = match line.shared.bindings.get(known as usize) {
        Some(&Binding::Part { part, vr }) if state.is_none() => Some((part, vr)),
        _ => None,
    };
    let value = match (state, input) {
        (Some(k), _) => line.x[k],
        (None, Some((part, vr))) => line.parts[part].get_real(vr)?,
        _ => return Err(FmiError::error(format!("value reference {known} is neither a state nor an input of the line"))),
    };
    let scale = match (state, &line.net) {
        (Some(k), Some(net)) => nominal(line, net, k),
        _ => 1.0,
    };
    let d = 1e-6 * value.abs().max(scale);
    let mut probe = line.clone();
    let mut at = |x: f64| -> FmiResult<f64> {
        match (state, input) {
            (Some(k), _) => probe.x[k] = x,
            (None, Some((part, vr))) => probe.parts[part].set_real(vr, x)?,
            _ => unreachable!("checked above"),
        }
        probe.settle()?;
        use fmi_core::Variables;
        probe.get_real(unknown)
    };
    let (hi, lo) = (at(value + d)?, at(value - d)?);
    Ok((hi - lo) / (2.0 * d))
}

fn nominal(line: &Line, net: &Network, k: usize) -> f64 {
    let s = net.states[k];
    let mut buffer = [0.0; 8];
    let part = &line.parts[s.part];
    let m = part.state_count();
    if part.get_nominals(&mut buffer[..m]).is_ok() && buffer[s.index] != 0.0 {
        buffer[s.index].abs()
    } else {
        1.0
    }
}
