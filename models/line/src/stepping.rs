//! Time: initialization, a communication step and Model Exchange events.
//!
//! A step runs from event to event (a profile's breakpoint, a `set` entry,
//! a web change: each part names its next one) and Rodas5P integrates the line
//! between them, so every event happens at its exact time whatever the
//! communication step. A failed step leaves the line as it was.

use crate::equilibrium;
use crate::network::Network;
use crate::ode::{LineSystem, Ode, Scratch};
use crate::part::Part;
use crate::spec::Spec;
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

pub fn scratch(ode: &Ode, n: usize) -> Scratch {
    let v = || vec![0.0; n];
    let mut scratch = Scratch { x: v(), f0: v(), f1: v(), y: v(), atol: v(), rtol_scale: vec![0.0; n] };
    tolerances(ode, &mut scratch);
    scratch
}

/// The absolute tolerances and the spans' strain scales for the next step.
pub fn tolerances(ode: &Ode, scratch: &mut Scratch) {
    let Some(net) = &ode.net else { return };
    for (k, s) in net.states.iter().enumerate() {
        scratch.rtol_scale[k] = match ode.parts[s.part].strain() {
            Some(strain) => scratch.rtol_scale[k].max(strain.abs()).max(STRAIN_FLOOR),
            None => 1.0,
        };
        // Absolute tolerance: the relative one of a state of its nominal size.
        scratch.atol[k] = ode.rtol * scratch.rtol_scale[k] * ode.nominal(net, k);
    }
}

/// The parts joined into the line's network, which integrates `integrated` (per part, indices
/// into its state vector). A state a parameter made active outside them is refused, naming the
/// parameter: only Model Exchange, whose description fixes the states, can meet one.
pub fn join(spec: &Spec, parts: &[Part], integrated: &[Vec<usize>]) -> FmiResult<Network> {
    for (p, part) in parts.iter().enumerate() {
        let Some(&i) = part.active_states().iter().find(|i| !integrated[p].contains(i)) else { continue };
        let (d, name) = (part.description(), &spec.parts[p].name);
        let switch = part.state_switch(i);
        let value = d.variable_by_name(switch).map_or_else(String::new, |v| match v.kind {
            fmi_core::description::Kind::Real => part.get_real(v.vr).map_or_else(|_| "?".into(), |x| x.to_string()),
            fmi_core::description::Kind::Integer => part.get_integer(v.vr).map_or_else(|_| "?".into(), |x| x.to_string()),
            _ => part.get_boolean(v.vr).map_or_else(|_| "?".into(), |b| b.to_string()),
        });
        let state = d.variable(d.states[i]).map_or("?", |v| &v.name);
        return Err(FmiError::error(format!(
            "{name}.{switch} = {value} makes {name}.{state} a state, which this FMU's model description does not list: in Model \
             Exchange the description fixes the line's states (give the value in the scene and export the FMU again, or run it \
             in Co-Simulation)"
        )));
    }
    Network::new(spec, parts, integrated).map_err(FmiError::error)
}

/// Initializes the parts until they agree through the connections, joins them (`join`) and,
/// where `start_equilibrium`, solves the steady state; the warnings to pass on. `tolerance`: the
/// line's parameter, which the importer's tolerance overrides where it asks for more.
pub fn initialize(
    ode: &mut Ode,
    spec: &Spec,
    integrated: &[Vec<usize>],
    tolerance: f64,
    start_equilibrium: bool,
    experiment: &Experiment,
    resources: &Resources,
) -> FmiResult<Vec<String>> {
    // The parts are stepped by the line, never by an importer of their own.
    let part_experiment = Experiment { model_exchange: false, ..*experiment };
    let t0 = experiment.start_time;
    // The importer's tolerance counts where it asks for more accuracy than the parameter. Its
    // value is compared only once it is known to be given: the payload of a None is
    // uninitialized, and the comparison that `filter` compiled to read it first (valgrind).
    let asked = match experiment.tolerance {
        Some(t) => t,
        None => f64::INFINITY,
    };
    ode.rtol = if asked > 0.0 && asked < tolerance { asked } else { tolerance };
    let mut warnings = Vec::new();
    let mut net: Option<Network> = None;
    let mut x = Vec::new();
    let mut settled = false;
    for _ in 0..SETTLE_ROUNDS {
        warnings.clear();
        for (p, part) in ode.parts.iter_mut().enumerate() {
            let ps = &spec.parts[p];
            let own = resources.clone().for_instance(&ps.name);
            let said = part.initialize(&part_experiment, &own).map_err(|e| e.prefixed(&format!("part {}", ps.name)))?;
            // A part without a profile of its own hears about the others' files: not news in a line.
            if ps.profile.is_some() {
                warnings.extend(said.into_iter().map(|w| format!("part {}: {w}", ps.name)));
            }
        }
        let n = match net.as_mut() {
            Some(n) => n,
            None => net.insert(join(spec, &ode.parts, integrated)?),
        };
        x.resize(n.len(), 0.0);
        n.gather(&ode.parts, &mut x)?;
        let before = connected_inputs(n, &ode.parts)?;
        n.evaluate(&mut ode.parts, t0, &x, None).map_err(|e| e.prefixed("the line's start"))?;
        if connected_inputs(n, &ode.parts)? == before {
            settled = true;
            break;
        }
    }
    if !settled {
        return Err(FmiError::error(format!("the parts' start values do not settle through the connections in {SETTLE_ROUNDS} rounds")));
    }
    let net = net.expect("built in the first round");
    ode.x = x;
    ode.time = t0;
    ode.ramps.clear();
    ode.integrator = Some(Rosenbrock::new(METHOD, net.len(), net.kl, net.ku));
    ode.net = Some(net);
    ode.scratch = scratch(ode, ode.x.len());
    apply_events(ode)?;
    if start_equilibrium {
        // A sampled loop is steady where its continuous one is [R14]: solved continuous, then sampled there.
        sampled_loops_restart(ode, t0);
        match equilibrium::solve(ode, spec) {
            Ok(()) => {}
            Err(equilibrium::NoStart::Search(why)) => warnings.push(format!("startAtEquilibrium: {why}; the line starts from its parts' start values")),
            Err(equilibrium::NoStart::Slides(why)) => return Err(FmiError::error(why)),
        }
        if sampled_loops_restart(ode, t0) {
            apply_events(ode)?;
        }
    }
    ode.settle()?;
    Ok(warnings)
}

/// Every sampled loop starts again at t (`Part::restart_hold`); whether the line has one.
fn sampled_loops_restart(ode: &mut Ode, t: f64) -> bool {
    let mut any = false;
    for part in &mut ode.parts {
        any |= part.restart_hold(t);
    }
    if any {
        if let Some(net) = ode.net.as_mut() {
            net.parts_changed();
        }
    }
    any
}

/// The values of every connected input, to see whether the parts settled.
fn connected_inputs(net: &Network, parts: &[Part]) -> FmiResult<Vec<u64>> {
    net.links.iter().map(|l| parts[l.to].get_real(l.input).map(f64::to_bits)).collect()
}

/// Lets every part apply what is due now; the next event of any part.
fn apply_events(ode: &mut Ode) -> FmiResult {
    let net = ode.net.as_mut().expect("initialized");
    net.evaluate(&mut ode.parts, ode.time, &ode.x, None)?;
    let mut next = f64::INFINITY;
    let mut changed = false;
    net.parts_changed();
    for part in &mut ode.parts {
        let update = part.event_update();
        next = next.min(update.next_event_time.unwrap_or(f64::INFINITY));
        changed |= update.states_changed;
    }
    if changed {
        net.gather(&ode.parts, &mut ode.x)?;
    }
    // What an event applies (a new web, a new roll, a table's kink) changes the Jacobian.
    if let Some(r) = ode.integrator.as_mut() {
        r.renew_jacobian();
    }
    ode.next_event = next;
    Ok(())
}

/// Integrates the line from its time to `end`, no event inside; `profiled`: a part follows a profile.
fn integrate(ode: &mut Ode, end: f64, profiled: bool) -> FmiResult {
    let t = ode.time;
    let time_dependent = !ode.ramps.is_empty() || profiled;
    let Ode { parts, net, x, ramps, integrator, scratch, rtol, .. } = ode;
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
    ode.time = end;
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
/// evaluation depends on the one before (`Network::reads_earlier_inputs`). `profiled`: a part
/// follows a profile (time moves the equations).
pub fn step(ode: &mut Ode, spec: &Spec, h: f64, profiled: bool) -> FmiResult {
    let t0 = ode.time;
    let next_event = ode.next_event;
    let next_step = ode.integrator.as_ref().map_or(0.0, |r| r.next_step);
    ode.scratch.x.copy_from_slice(&ode.x);
    let mut copied = !ode.net.as_ref().is_some_and(|n| n.evaluated_at(t0, &ode.x) && !n.reads_earlier_inputs);
    if copied {
        ode.backup.clone_from(&ode.parts);
    }
    let stepped = advance(ode, t0 + h, profiled, &mut copied).and_then(|()| {
        // The ramped inputs end the step where their derivatives took them.
        for &(part, vr, base, rate) in &ode.ramps {
            ode.parts[part].set_real(vr, base + rate * h)?;
        }
        ode.settle()?;
        within_bounds(ode, spec)
    });
    match stepped {
        Ok(()) => {
            ode.ramps.clear();
            Ok(())
        }
        Err(e) => {
            if copied {
                std::mem::swap(&mut ode.parts, &mut ode.backup);
                if let Some(net) = ode.net.as_mut() {
                    net.parts_changed();
                }
            }
            for &(part, vr, base, _) in &ode.ramps {
                let _ = ode.parts[part].set_real(vr, base);
            }
            ode.x.copy_from_slice(&ode.scratch.x);
            ode.time = t0;
            ode.next_event = next_event;
            if let Some(r) = ode.integrator.as_mut() {
                r.next_step = next_step;
                // Formed along the failed attempt, perhaps far from the line as it is again.
                r.renew_jacobian();
            }
            let _ = ode.settle();
            Err(e)
        }
    }
}

/// The line at the end of a step within the bounds its parts document: every connection's value
/// in the range of the input it feeds, as the parts' own FMUs refuse one outside it when it is set
/// (a speed beyond ±1000 m/s, a strain beyond 10). Outside them the step fails with an error.
fn within_bounds(ode: &Ode, spec: &Spec) -> FmiResult {
    let Some((l, value)) = ode.net.as_ref().and_then(|net| net.out_of_bounds(&ode.parts)) else { return Ok(()) };
    let variable = |p: usize, vr: u32| ode.parts[p].description().variable(vr);
    let name = |p: usize, vr: u32| format!("{}.{}", spec.parts[p].name, variable(p, vr).map_or("?", |v| &v.name));
    let range = variable(l.to, l.input).map(|v| v.range.to_string()).unwrap_or_default();
    Err(FmiError::error(format!(
        "at t = {} s {} = {value} is outside the range of {}, {range}, which it feeds: the line left the bounds its parts \
         hold (check its drives and inputs); the step is undone",
        ode.time,
        name(l.from, l.output),
        name(l.to, l.input)
    )))
}

/// `copied`: the parts were copied to `line.backup` before an event (see `step`).
fn advance(ode: &mut Ode, end: f64, profiled: bool, copied: &mut bool) -> FmiResult {
    let mut scratch = std::mem::take(&mut ode.scratch);
    tolerances(ode, &mut scratch);
    ode.scratch = scratch;
    // An event within rounding of the end belongs to the next step's start.
    let last = end - profiles_tolerance(end);
    loop {
        if ode.next_event <= ode.time + profiles_tolerance(ode.time) {
            if !*copied {
                ode.backup.clone_from(&ode.parts);
                *copied = true;
            }
            apply_events(ode)?;
        }
        let stop = if ode.next_event < last { ode.next_event } else { end };
        if stop > ode.time {
            integrate(ode, stop, profiled)?;
        }
        ode.time = stop;
        if stop >= end {
            return Ok(());
        }
    }
}

/// The parts' tolerance for "due now" (their profiles').
fn profiles_tolerance(t: f64) -> f64 {
    1e-9 * t.abs().max(1.0)
}

/// Model Exchange: the parts apply what is due at the time set. At a time event (a table's break,
/// a `set` entry) the right-hand side jumps or kinks: the update says the states changed, so that
/// an importer restarts its integrator there instead of carrying its history across it.
pub fn event_update(ode: &mut Ode) -> EventUpdate {
    let before = ode.x.clone();
    let time_event = ode.next_event <= ode.time + profiles_tolerance(ode.time);
    if apply_events(ode).is_err() {
        return EventUpdate::default();
    }
    let _ = ode.settle();
    EventUpdate {
        next_event_time: ode.next_event.is_finite().then_some(ode.next_event),
        states_changed: time_event || before != ode.x,
    }
}
