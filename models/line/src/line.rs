//! The Line: the FMI model hooks of a whole line, on top of the house. Built
//! from its spec (`spec`) with its interface (`interface`); its parts and
//! where they stand are an `Ode`, which the hooks call down into: `stepping`
//! for initialization, steps and events, the network for evaluations.

use crate::feed::{self, Feed};
use crate::interface::{self, Binding, Interface};
use crate::laminate::Laminate;
use crate::network::Network;
use crate::ode::{Ode, Scratch};
use crate::part::Part;
use crate::spec::{self, ModelKind, Spec, StartMode, PROFILE_FOLDER, SPEC_FILE};
use crate::stepping;
use fmi_core::description::{Causality, ModelDescription, Variability};
use fmi_core::{EventUpdate, Experiment, FmiError, FmiResult, Jacobian, Model, Resources, StateReader, StateWriter, Variables};
use solver::stiff::Rosenbrock;
use std::sync::Arc;

/// What the line shares among its copies: fixed at instantiation.
#[derive(Debug)]
pub struct Shared {
    pub spec: Spec,
    pub description: ModelDescription,
    pub bindings: Vec<Binding>,
    pub laminates: Vec<Laminate>,
    /// Per part, the states the line integrates (indices into its state vector): in Model
    /// Exchange those the description lists, in Co-Simulation every one a parameter the line
    /// offers may switch on (`Part::possible_states`), held while it is off, so that their
    /// number never changes.
    pub described_states: Vec<Vec<usize>>,
    pub possible_states: Vec<Vec<usize>>,
}

/// One line.json, one GUID: equal GUIDs, equal lines.
impl PartialEq for Shared {
    fn eq(&self, other: &Shared) -> bool {
        self.description.guid == other.description.guid
    }
}

#[derive(Clone, Debug, PartialEq)]
pub struct Line {
    pub shared: Arc<Shared>,
    /// The parts, joined, and where they stand: what the hooks below call down into.
    pub ode: Ode,
    /// The parameters of the line itself.
    tolerance: f64,
    start_equilibrium: bool,
    /// A part follows a profile: time moves the equations.
    profiled: bool,
    /// The importer integrates (Model Exchange): the line's states are the description's.
    model_exchange: bool,
    /// Initialization ended: a tunable parameter set now keeps the network.
    initialized: bool,
    /// The loops that feed forward on another part's input v_ref, and its slope.
    feeds: Vec<Feed>,
}

impl Line {
    /// A line from its spec text (the FMU's resources/line.json).
    pub fn from_spec(text: &str) -> FmiResult<Line> {
        let spec = Spec::parse(text).map_err(FmiError::error)?;
        let mut parts = Vec::with_capacity(spec.parts.len());
        for ps in &spec.parts {
            let mut part = match ps.model {
                ModelKind::ConvertingSpan => Part::span(),
                ModelKind::Roller => Part::roller(),
            };
            apply_start(&mut part, ps).map_err(|e| FmiError::error(format!("line.json: part {}: {e}", ps.name)))?;
            if ps.set_input && !matches!(&part, Part::Roller(r) if r.params.takes_set_input()) {
                return Err(FmiError::error(format!("line.json: part {}: set_input needs a roller whose drive has a force loop (loop.kind = 1)", ps.name)));
            }
            if ps.speed_input && !matches!(&part, Part::Roller(r) if r.params.takes_speed_input()) {
                return Err(FmiError::error(format!("line.json: part {}: speed_input needs a roller whose drive has a speed or dancer loop (loop.kind = 2 or 3) or is an ideal speed drive on it (speed.input = true)", ps.name)));
            }
            // A load cell a connection reads (a drive's loop on it): the roller's own output load_cell.F at
            // the spec's wrap; elsewhere the line's output NAME.F alone, and the roller's tangents stay fixed.
            if spec.connections.iter().any(|c| c.from.0 == ps.name && c.from.1 == "load_cell.F") {
                let w = ps.wrap.unwrap_or(0.0);
                if w <= 0.0 {
                    return Err(FmiError::error(format!("line.json: part {}: a connection reads its load_cell.F, which needs a wrap > 0 degrees (it has {w})", ps.name)));
                }
                let vr = part.description().variable_by_name("load_cell.wrap").expect("a roller has a load cell").vr;
                part.set_real(vr, w.to_radians())?;
            }
            if ps.profile.is_some() {
                let vr = part.description().variable_by_name("profile").expect("parts have a profile").vr;
                part.set_string(vr, &format!("{PROFILE_FOLDER}/{}.json", ps.name))?;
            }
            parts.push(part);
        }
        let feeds = feed::from_spec(&spec, &parts).map_err(FmiError::error)?;
        for f in &feeds {
            feed::follow(&feeds, &mut parts, f.from)?;
        }
                let active: Vec<Vec<usize>> = parts.iter().zip(&spec.parts).map(|(part, ps)| part.described_states(ps)).collect();
        let start_equilibrium = spec.start == StartMode::Equilibrium;
        let Interface { description, bindings, laminates } = interface::build(&spec, &parts, &active, spec::guid(text), start_equilibrium);
        let profiled = spec.parts.iter().any(|p| p.profile.is_some());
        let possible_states = parts.iter().zip(&spec.parts).map(|(part, ps)| part.possible_states(ps)).collect();
        Ok(Line {
            shared: Arc::new(Shared { spec, description, bindings, laminates, described_states: active, possible_states }),
            ode: Ode::new(parts, interface::DEFAULT_TOLERANCE),
            tolerance: interface::DEFAULT_TOLERANCE,
            start_equilibrium,
            profiled,
            model_exchange: false,
            initialized: false,
            feeds,
        })
    }

    fn binding(&self, vr: u32) -> FmiResult<Binding> {
        self.shared.bindings.get(vr as usize).copied().filter(|_| vr > 0).ok_or_else(|| fmi_core::model::unknown_vr(vr))
    }

    pub fn spec(&self) -> &Spec {
        &self.shared.spec
    }

    /// Per part, the states the line integrates in the interface it was initialized for.
    fn integrated(shared: &Shared, model_exchange: bool) -> &[Vec<usize>] {
        if model_exchange {
            &shared.described_states
        } else {
            &shared.possible_states
        }
    }

    pub fn parts(&self) -> &[Part] {
        &self.ode.parts
    }

    pub fn network(&self) -> Option<&Network> {
        self.ode.net.as_ref()
    }

    pub fn states(&self) -> &[f64] {
        &self.ode.x
    }

    pub fn time(&self) -> f64 {
        self.ode.time
    }

    pub fn integrator(&self) -> Option<&Rosenbrock> {
        self.ode.integrator.as_ref()
    }

    /// The network, once initialization has joined the parts (Model Exchange's vectors are its states).
    fn joined(&self) -> FmiResult<&Network> {
        self.ode.net.as_ref().ok_or_else(|| FmiError::error("the line is not initialized"))
    }

    /// The line's variable `vr` of a part was set. A parameter (which FMI allows only until
    /// initialization ends) undoes a provisional initialization (an output read in
    /// initialization mode): the network it joined may not fit the parameters now (a roll's
    /// radius a state or not), and an FMU state saved with it would not restore.
    fn part_set(&mut self, vr: u32) {
        let input = self.shared.description.variable(vr).is_some_and(|v| v.causality == Causality::Input);
        let tunable = self.shared.description.variable(vr).is_some_and(|v| v.variability == Variability::Tunable);
        // A tunable parameter set between steps (a loop's gain) keeps the line's structure: what was
        // computed from the parts' values is formed again.
        if tunable && self.initialized {
            if let Some(net) = self.ode.net.as_mut() {
                net.parts_changed();
            }
            return;
        }
        if !input && self.ode.net.is_some() {
            self.ode.net = None;
            self.ode.integrator = None;
            self.ode.scratch = Scratch::default();
        }
    }

    /// An ideal speed drive's input v_ref (its `loop.speed`) moves its surface speed at once: its
    /// omega, a state of the line whose rate is the held input's slope 0, jumps with it. In Model
    /// Exchange the importer owns the states: the next event update moves it and says so.
    fn follow_speed_input(&mut self, part: usize) {
        let (Part::Roller(r), Some(net)) = (&self.ode.parts[part], self.ode.net.as_mut()) else { return };
        if !(r.params.speed_input && self.initialized) {
            return;
        }
        if !self.model_exchange {
            self.ode.x[net.first_state[part]] = r.surface_speed() / r.radius();
        }
        // Its speed moves the spans' inputs, though loop.speed is no input of the roller's outputs.
        net.parts_changed();
        let _ = self.ode.settle();
    }

    /// d(unknown)/d(known) of the line now, by central differences (step 1e-6
    /// of the known's size: truncation ~1e-12, rounding ~1e-10 relative). Known:
    /// a state or an input of the line; unknown: an output or a derivative.
    /// Before initialization has built the network (an instance that failed
    /// before it ended: the error state), only inputs are known, and the parts
    /// answer at their own values, as fmi2GetReal does then.
    fn partial_derivative(&self, unknown: u32, known: u32) -> FmiResult<f64> {
        let state = self.shared.description.states.iter().position(|&vr| vr == known);
        if state.is_some() && self.ode.net.is_none() {
            return Err(FmiError::error("the line is not initialized: it has no states yet"));
        }
        let input = match self.shared.bindings.get(known as usize) {
            Some(&Binding::Real { part, vr, .. }) if state.is_none() => Some((part, vr)),
            _ => None,
        };
        let value = match (state, input) {
            (Some(k), _) => self.ode.x[k],
            (None, Some((part, vr))) => self.ode.parts[part].get_real(vr)?,
            _ => return Err(FmiError::error(format!("value reference {known} is neither a state nor an input of the line"))),
        };
        let scale = match (state, &self.ode.net) {
            (Some(k), Some(net)) => self.ode.nominal(net, k),
            _ => 1.0,
        };
        let d = 1e-6 * value.abs().max(scale);
        let mut probe = self.clone();
        let mut at = |x: f64| -> FmiResult<f64> {
            match (state, input) {
                (Some(k), _) => probe.ode.x[k] = x,
                (None, Some((part, vr))) => probe.ode.parts[part].set_real(vr, x)?,
                _ => unreachable!("checked above"),
            }
            probe.ode.settle()?;
            probe.get_real(unknown)
        };
        let (hi, lo) = (at(value + d)?, at(value - d)?);
        Ok((hi - lo) / (2.0 * d))
    }
}

/// Sets a part's start values from line.json, each through the part's own setter.
fn apply_start(part: &mut Part, ps: &spec::PartSpec) -> Result<(), String> {
    use fmi_core::description::Kind;
    let d = part.description();
    for (name, value) in &ps.start {
        if name == "solver" {
            continue; // the line integrates; the span's own solver is not used
        }
        let v = d.variable_by_name(name).ok_or_else(|| format!("{name}: {} has no such variable", d.model_identifier))?;
        let bad = || format!("{name} = {value}: not a value of its type");
        let r = match v.kind {
            Kind::Real => part.set_real(v.vr, value.as_f64().ok_or_else(bad)?),
            Kind::Integer | Kind::Enumeration { .. } => part.set_integer(v.vr, value.as_i64().and_then(|i| i32::try_from(i).ok()).ok_or_else(bad)?),
            Kind::Boolean => part.set_boolean(v.vr, value.as_bool().ok_or_else(bad)?),
            Kind::String => part.set_string(v.vr, value.as_str().ok_or_else(bad)?),
        };
        r.map_err(|e| format!("{name} = {value}: {}", e.message))?;
    }
    Ok(())
}

impl Variables for Line {
    fn get_real(&self, vr: u32) -> FmiResult<f64> {
        match self.binding(vr)? {
            Binding::Real { part, port, .. } => Ok(self.ode.parts[part].real(port)),
            Binding::LoadCell { part, cos_wrap } => self.ode.parts[part].load_cell(cos_wrap),
            Binding::Laminate { laminate, quantity } => Ok(self.shared.laminates[laminate].value(&self.ode.parts, quantity)),
            Binding::Tolerance => Ok(self.tolerance),
            Binding::Part { .. } | Binding::StartAtEquilibrium => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn set_real(&mut self, vr: u32, value: f64) -> FmiResult {
        match self.binding(vr)? {
            Binding::Real { part, vr: part_vr, port } => {
                self.ode.parts[part].write(port, value)?;
                feed::follow(&self.feeds, &mut self.ode.parts, part)?;
                self.part_set(vr);
                self.follow_speed_input(part);
                // An input moves the outputs that depend on it; a failure shows when they are read.
                // One that moves no connection (a motor torque) changes only what its part computes when read.
                if self.ode.net.as_ref().is_none_or(|net| net.input_moves_connections(part, part_vr)) {
                    let _ = self.ode.settle();
                }
                Ok(())
            }
            Binding::Tolerance => {
                self.tolerance = value;
                Ok(())
            }
            _ => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn get_integer(&self, vr: u32) -> FmiResult<i32> {
        match self.binding(vr)? {
            Binding::Part { part, vr } => self.ode.parts[part].get_integer(vr),
            _ => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn set_integer(&mut self, vr: u32, value: i32) -> FmiResult {
        match self.binding(vr)? {
            Binding::Part { part, vr: part_vr } => {
                self.ode.parts[part].set_integer(part_vr, value)?;
                self.part_set(vr);
                Ok(())
            }
            _ => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn get_boolean(&self, vr: u32) -> FmiResult<bool> {
        match self.binding(vr)? {
            Binding::Part { part, vr } => self.ode.parts[part].get_boolean(vr),
            Binding::StartAtEquilibrium => Ok(self.start_equilibrium),
            _ => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn set_boolean(&mut self, vr: u32, value: bool) -> FmiResult {
        match self.binding(vr)? {
            Binding::Part { part, vr: part_vr } => {
                self.ode.parts[part].set_boolean(part_vr, value)?;
                self.part_set(vr);
                Ok(())
            }
            Binding::StartAtEquilibrium => {
                self.start_equilibrium = value;
                Ok(())
            }
            _ => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn get_string(&self, vr: u32) -> FmiResult<&str> {
        Err(fmi_core::model::unknown_vr(vr))
    }

    fn set_string(&mut self, vr: u32, _value: &str) -> FmiResult {
        Err(fmi_core::model::unknown_vr(vr))
    }

    fn save_variables(&self, out: &mut StateWriter) {
        for part in &self.ode.parts {
            part.save_variables(out);
        }
        out.f64(self.tolerance);
        out.bool(self.start_equilibrium);
    }

    fn load_variables(&mut self, input: &mut StateReader) -> FmiResult {
        for (part, spec) in self.ode.parts.iter_mut().zip(&self.shared.spec.parts) {
            // The part's messages name its own variables ("L is ..."): the line's are "<part>.L".
            part.load_variables(input).map_err(|mut e| {
                e.message = format!("{}.{}", spec.name, e.message);
                e
            })?;
        }
        self.tolerance = input.finite("tolerance")?;
        self.start_equilibrium = input.bool("startAtEquilibrium")?;
        Ok(())
    }
}

impl Model for Line {
    fn instantiate(resources: &Resources) -> FmiResult<Self> {
        let path = resources.file(SPEC_FILE)?;
        let text = std::fs::read_to_string(&path)
            .map_err(|e| FmiError::error(format!("cannot read {}: {e} (the Line FMU's line is in resources/{SPEC_FILE})", path.display())))?;
        let line = Line::from_spec(&text)?;
        let folder = path.parent().expect("a file in resources/");
        spec::check_resources(&line.shared.spec, folder).map_err(FmiError::error)?;
        Ok(line)
    }

    fn description(&self) -> &ModelDescription {
        &self.shared.description
    }

    fn save_state(&self, out: &mut StateWriter) {
        for part in &self.ode.parts {
            part.save_state(out);
        }
        out.bool(self.ode.net.is_some());
        out.bool(self.model_exchange);
        out.i32(self.ode.x.len() as i32);
        for &x in &self.ode.x {
            out.f64(x);
        }
        out.f64(self.ode.time);
        out.f64(self.ode.next_event);
        out.f64(self.ode.integrator.as_ref().map_or(0.0, |r| r.next_step));
        out.f64(self.ode.rtol);
        out.i32(self.ode.scratch.rtol_scale.len() as i32);
        for &x in &self.ode.scratch.rtol_scale {
            out.f64(x);
        }
        for f in &self.feeds {
            let (t, v) = f.last.unwrap_or((f64::NAN, f64::NAN));
            out.bool(f.last.is_some());
            out.f64(t);
            out.f64(v);
        }
    }

    fn load_state(&mut self, r: &mut StateReader) -> FmiResult {
        for part in &mut self.ode.parts {
            part.load_state(r)?;
        }
        let initialized = r.bool("initialized")?;
        self.model_exchange = r.bool("interface")?;
        let n = r.i32("number of states")?;
        let mut x = Vec::new();
        for _ in 0..n.max(0) {
            x.push(r.finite("state")?);
        }
        self.ode.time = r.finite("time")?;
        self.ode.next_event = r.f64("next event")?;
        let next_step = r.finite("next step")?;
        self.ode.rtol = r.finite("integrator tolerance")?;
        let scales = r.i32("number of tolerance scales")?;
        let mut rtol_scale = Vec::new();
        for _ in 0..scales.max(0) {
            rtol_scale.push(r.finite("tolerance scale")?);
        }
        for f in &mut self.feeds {
            let stepped = r.bool("feed-forward reference stepped")?;
            let (t, v) = (r.f64("feed-forward reference time")?, r.f64("feed-forward reference")?);
            f.last = stepped.then_some((t, v));
            f.derivative = None;
        }
        if initialized {
            // The parameters set the network (a roll's radius is a state only while it is wound):
            // out of their ranges, say which, before the structure they break.
            fmi_core::instance::states::check_values(self, true)?;
            let shared = &self.shared;
            let net = stepping::join(&shared.spec, &self.ode.parts, Line::integrated(shared, self.model_exchange))?;
            if x.len() != net.len() {
                return Err(FmiError::error(format!("the state holds {} line states, the line has {}", x.len(), net.len())));
            }
            let mut integrator = Rosenbrock::new(stepping::METHOD, net.len(), net.kl, net.ku);
            integrator.next_step = next_step;
            self.ode.integrator = Some(integrator);
            self.ode.net = Some(net);
        } else {
            // Before initialization the line has no integrator, so no tolerance scales to keep.
            if !rtol_scale.is_empty() {
                return Err(FmiError::error(format!("the state holds {} tolerance scales, the line is not initialized", rtol_scale.len())));
            }
            self.ode.net = None;
            self.ode.integrator = None;
        }
        self.ode.x = x;
        self.ode.ramps.clear();
        self.ode.scratch = Scratch::default();
        if let Some(net) = &self.ode.net {
            if rtol_scale.len() != net.len() {
                return Err(FmiError::error(format!("the state holds {} tolerance scales, the line has {} states", rtol_scale.len(), net.len())));
            }
            let mut scratch = stepping::scratch(&self.ode, net.len());
            scratch.rtol_scale = rtol_scale;
            self.ode.scratch = scratch;
        }
        self.ode.settle()
    }

    /// A part's own check of a value its range allows (a roller's T_set <= 0), named as the line names it.
    fn check_real(&self, vr: u32, value: f64) -> FmiResult {
        match self.binding(vr)? {
            Binding::Real { part, vr: part_vr, .. } => self.ode.parts[part].check_real(part_vr, value).map_err(|e| {
                let name = self.shared.description.variable(vr).map_or_else(|| format!("value reference {vr}"), |v| v.name.to_string());
                e.prefixed(&format!("{name} = {value}"))
            }),
            _ => Ok(()),
        }
    }

    fn set_input_derivative(&mut self, vr: u32, value: f64) -> FmiResult {
        let Binding::Real { part, vr: part_vr, .. } = self.binding(vr)? else {
            return Err(FmiError::error(format!("value reference {vr} is not an input")));
        };
        // The roller's speed drive reads its acceleration as 0 (held): a ramped v_ref would move its
        // surface speed with no acceleration to match.
        if value != 0.0 && matches!(&self.ode.parts[part], Part::Roller(r) if r.params.speed_input && part_vr == roller::description::Real::loop_speed.vr()) {
            let name = self.shared.description.variable(vr).map_or_else(|| "v_ref".to_string(), |v| v.name.to_string());
            return Err(FmiError::error(format!("{name}: an ideal speed drive holds its input over a step; its derivative {value} is not taken (only 0)")));
        }
        let base = self.ode.parts[part].get_real(part_vr)?;
        match self.ode.ramps.iter_mut().find(|(p, v, _, _)| *p == part && *v == part_vr) {
            Some(r) => *r = (part, part_vr, base, value),
            None => self.ode.ramps.push((part, part_vr, base, value)),
        }
        if part_vr == roller::description::Real::loop_speed.vr() {
            feed::derivative(&mut self.feeds, &self.ode.parts, &mut self.ode.ramps, part, value)?;
        }
        Ok(())
    }

    fn initialize(&mut self, experiment: &Experiment, resources: &Resources) -> FmiResult<Vec<String>> {
        let shared = self.shared.clone();
        for laminate in &shared.laminates {
            laminate.check(&shared.spec, &self.ode.parts)?;
        }
        if let Some(why) = experiment.model_exchange.then(|| feed::model_exchange_refusal(&shared.spec, &self.feeds)).flatten() {
            return Err(FmiError::error(why));
        }
        let integrated = Line::integrated(&shared, experiment.model_exchange);
        let warnings = stepping::initialize(&mut self.ode, &shared.spec, integrated, self.tolerance, self.start_equilibrium, experiment, resources)?;
        self.model_exchange = experiment.model_exchange;
        self.initialized = true;
        Ok(warnings)
    }

    fn set_time(&mut self, time: f64) {
        if time != self.ode.time {
            self.ode.time = time;
            // Model Exchange: a failure shows when the states are set or outputs read.
            let _ = self.ode.settle();
        }
    }

    fn do_step(&mut self, h: f64) -> FmiResult {
        let t = self.ode.time;
        if feed::slopes(&mut self.feeds, &mut self.ode.parts, t)? {
            if let Some(net) = self.ode.net.as_mut() {
                net.parts_changed();
            }
        }
        if let Err(e) = stepping::step(&mut self.ode, &self.shared.spec, h, self.profiled) {
            if !self.feeds.is_empty() {
                feed::undo(&self.feeds, &mut self.ode.parts);
                if let Some(net) = self.ode.net.as_mut() {
                    net.parts_changed();
                }
                let _ = self.ode.settle();
            }
            return Err(e);
        }
        feed::stepped(&mut self.feeds, t);
        Ok(())
    }

    fn event_update(&mut self) -> EventUpdate {
        stepping::event_update(&mut self.ode)
    }

    fn get_continuous_states(&self, x: &mut [f64]) -> FmiResult {
        self.joined()?;
        x.copy_from_slice(&self.ode.x);
        Ok(())
    }

    fn set_continuous_states(&mut self, x: &[f64]) -> FmiResult {
        self.joined()?;
        if let Some(bad) = x.iter().position(|v| !v.is_finite()) {
            return Err(FmiError::discard(format!("state {bad} = {} is not finite", x[bad])));
        }
        // The states before, to go back to if the parts refuse these.
        self.ode.scratch.x.copy_from_slice(&self.ode.x);
        self.ode.x.copy_from_slice(x);
        if let Err(e) = self.ode.settle() {
            self.ode.x.copy_from_slice(&self.ode.scratch.x);
            let _ = self.ode.settle();
            return Err(e);
        }
        Ok(())
    }

    fn get_derivatives(&self, dx: &mut [f64]) -> FmiResult {
        self.joined()?.derivatives(&self.ode.parts, dx)
    }

    fn get_nominals(&self, nominals: &mut [f64]) -> FmiResult {
        let net = self.joined()?;
        let mut buffer = [0.0; crate::network::MAX_PART_STATES];
        for (k, s) in net.states.iter().enumerate() {
            let part = &self.ode.parts[s.part];
            let n = part.state_count();
            part.get_nominals(&mut buffer[..n])?;
            nominals[k] = buffer[s.index];
        }
        Ok(())
    }

    /// The parts' own; a laminate that may go slack does so as one ([M6]): each of its layers'
    /// indicator is the sum of their pulls.
    fn get_event_indicators(&self, z: &mut [f64]) -> FmiResult {
        let mut k = 0;
        for part in &self.ode.parts {
            let n = part.event_indicator_count();
            part.get_event_indicators(&mut z[k..k + n])?;
            k += n;
        }
        if let Some(net) = &self.ode.net {
            for lam in net.slack_laminates() {
                let pull = lam.pull(&self.ode.parts);
                for layer in &lam.layers {
                    let first: usize = self.ode.parts[..layer.part].iter().map(Part::event_indicator_count).sum();
                    z[first] = pull;
                }
            }
        }
        Ok(())
    }

    fn partial_derivative(&self, unknown: u32, known: u32, _of: Jacobian) -> FmiResult<f64> {
        self.partial_derivative(unknown, known)
    }

    fn outputs_defined(&self) -> FmiResult {
        self.ode.parts.iter().try_for_each(Part::outputs_defined)
    }

    fn inputs_valid(&self) -> FmiResult {
        self.ode.parts.iter().try_for_each(Part::inputs_valid)
    }

    fn provisional_state(&mut self) {}
}
