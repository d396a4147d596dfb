//! Line: a whole web line as one FMU (FMI 2.0 and 3.0, Co-Simulation and
//! Model Exchange). The binary is generic: the line it holds — its parts, their
//! start values and profiles, how they connect — is read from
//! `resources/line.json` when it is instantiated, and the interface follows
//! from it (`interface`). The parts are the span's and the Roller's own
//! models (`part`), joined into one ODE (`network`) that one implicit
//! integrator steps (Rodas5P with the line's banded Jacobian, `stepping`).
//!
//! * `spec` — line.json;
//! * `interface` — the variables, `<part>.<variable>`, and what each is bound to;
//! * `network` — states, connections, the web-mass loop, the band;
//! * `chain` — the Jacobian chained from the parts' tangents;
//! * `stepping` — a communication step: events at their times, the integrator between;
//! * `equilibrium` — the steady state a line starts in;
//! * this file — the FMI model hooks.

#![deny(unsafe_code)]

pub mod chain;
pub mod equilibrium;
pub mod interface;
pub mod network;
pub mod ode;
pub mod part;
pub mod spec;
pub mod stepping;
#[cfg(feature = "cli")]
pub mod xml;

use fmi_core::description::{Causality, ModelDescription};
use fmi_core::{EventUpdate, Experiment, FmiError, FmiResult, Jacobian, Model, Resources, StateReader, StateWriter, Variables};
use interface::{Binding, Interface};
use network::Network;
use part::Part;
use solver::stiff::Rosenbrock;
use spec::{ModelKind, Spec, StartMode};
use std::sync::Arc;

#[cfg(feature = "fmu")]
fmi_abi::export_fmi2!(crate::Line);
#[cfg(feature = "fmu")]
fmi_abi::export_fmi3!(crate::Line);

/// Where a line's spec sits in the FMU.
pub const SPEC_FILE: &str = "line.json";
/// Where each part's profile sits, by part name.
pub const PROFILE_FOLDER: &str = "profiles";

/// What the line shares among its copies: fixed at instantiation.
#[derive(Debug)]
pub struct Shared {
    pub spec: Spec,
    pub description: ModelDescription,
    pub bindings: Vec<Binding>,
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
    pub parts: Vec<Part>,
    /// Built when initialization ends (the parts' effects decide the states).
    net: Option<Network>,
    /// The line's states (`net.states`), and the time they are at.
    x: Vec<f64>,
    time: f64,
    tolerance: f64,
    /// The integrator's relative tolerance: `tolerance`, or the importer's where smaller.
    rtol: f64,
    start_equilibrium: bool,
    /// Inputs an importer moves linearly over a step (fmi2SetRealInputDerivatives):
    /// (part, vr, value at the step's start, rate).
    ramps: Vec<(usize, u32, f64, f64)>,
    /// The parts' next event (a profile's breakpoint or set entry, a web change).
    next_event: f64,
    integrator: Option<Rosenbrock>,
    /// A copy of the parts to undo a failed step (kept, so a step allocates nothing).
    backup: Vec<Part>,
    /// Scratch vectors of the line's size (Jacobians, undo), sized at initialization.
    scratch: Scratch,
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scratch {
    pub x: Vec<f64>,
    pub f0: Vec<f64>,
    pub f1: Vec<f64>,
    pub y: Vec<f64>,
    pub atol: Vec<f64>,
    pub rtol_scale: Vec<f64>,
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
            if ps.profile.is_some() {
                let vr = part.description().variable_by_name("profile").expect("parts have a profile").vr;
                part.set_string(vr, &format!("{PROFILE_FOLDER}/{}.json", ps.name))?;
            }
            parts.push(part);
        }
        let active: Vec<Vec<usize>> = parts.iter().map(Part::active_states).collect();
        let start_equilibrium = spec.start == StartMode::Equilibrium;
        let Interface { description, bindings } = interface::build(&spec, &parts, &active, spec::guid(text), start_equilibrium);
        Ok(Line {
            shared: Arc::new(Shared { spec, description, bindings }),
            backup: parts.clone(),
            parts,
            net: None,
            x: Vec::new(),
            time: 0.0,
            tolerance: interface::DEFAULT_TOLERANCE,
            rtol: interface::DEFAULT_TOLERANCE,
            start_equilibrium,
            ramps: Vec::new(),
            next_event: f64::INFINITY,
            integrator: None,
            scratch: Scratch::default(),
        })
    }

    fn binding(&self, vr: u32) -> FmiResult<Binding> {
        self.shared.bindings.get(vr as usize).copied().filter(|_| vr > 0).ok_or_else(|| fmi_core::model::unknown_vr(vr))
    }

    pub fn spec(&self) -> &Spec {
        &self.shared.spec
    }

    pub fn network(&self) -> Option<&Network> {
        self.net.as_ref()
    }

    pub fn states(&self) -> &[f64] {
        &self.x
    }

    pub fn time(&self) -> f64 {
        self.time
    }

    pub fn integrator(&self) -> Option<&Rosenbrock> {
        self.integrator.as_ref()
    }

    /// The line's variable `vr` of a part was set: other than an input (a parameter, which FMI
    /// allows only before the network exists), it changes more than the states and inputs do.
    fn part_set(&mut self, vr: u32) {
        let input = self.shared.description.variable(vr).is_some_and(|v| v.causality == Causality::Input);
        if let (false, Some(net)) = (input, self.net.as_mut()) {
            net.parts_changed();
        }
    }

    /// After initialization every change (time, states, an input) is
    /// evaluated at once, so that outputs and derivatives read later are
    /// those of the line as it now is.
    fn settle(&mut self) -> FmiResult {
        match self.net.as_mut() {
            Some(net) => net.evaluate(&mut self.parts, self.time, &self.x, None),
            None => Ok(()),
        }
    }

    fn load_cell(&self, part: usize, cos_wrap: f64) -> FmiResult<f64> {
        let p = &self.parts[part];
        let d = p.description();
        let vr = |name: &str| d.variable_by_name(name).expect("a roller has web forces and ports").vr;
        // Where webs merge or split, the webs at one side taken as parallel (the lanes of a slitter are).
        let side = |end: &str, ports: &str| -> FmiResult<f64> {
            let n = p.get_integer(vr(ports))?;
            let mut sum = p.get_real(vr(&format!("{end}.F")))?;
            for k in 2..=n {
                sum += p.get_real(vr(&format!("{end}{k}.F")))?;
            }
            Ok(sum)
        };
        let (a, b) = (side("web_a", "inlets")?, side("web_b", "outlets")?);
        Ok((a * a + b * b - 2.0 * a * b * cos_wrap).max(0.0).sqrt())
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
            Binding::Part { part, vr } => self.parts[part].get_real(vr),
            Binding::LoadCell { part, cos_wrap } => self.load_cell(part, cos_wrap),
            Binding::Tolerance => Ok(self.tolerance),
            Binding::StartAtEquilibrium => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn set_real(&mut self, vr: u32, value: f64) -> FmiResult {
        match self.binding(vr)? {
            Binding::Part { part, vr: part_vr } => {
                self.parts[part].set_real(part_vr, value)?;
                self.part_set(vr);
                // An input moves the outputs that depend on it; a failure shows when they are read.
                // One that moves no connection (a motor torque) changes only what its part computes when read.
                if self.net.as_ref().is_none_or(|net| net.input_moves_connections(part, part_vr)) {
                    let _ = self.settle();
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
            Binding::Part { part, vr } => self.parts[part].get_integer(vr),
            _ => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn set_integer(&mut self, vr: u32, value: i32) -> FmiResult {
        match self.binding(vr)? {
            Binding::Part { part, vr: part_vr } => {
                self.parts[part].set_integer(part_vr, value)?;
                self.part_set(vr);
                Ok(())
            }
            _ => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn get_boolean(&self, vr: u32) -> FmiResult<bool> {
        match self.binding(vr)? {
            Binding::Part { part, vr } => self.parts[part].get_boolean(vr),
            Binding::StartAtEquilibrium => Ok(self.start_equilibrium),
            _ => Err(fmi_core::model::unknown_vr(vr)),
        }
    }

    fn set_boolean(&mut self, vr: u32, value: bool) -> FmiResult {
        match self.binding(vr)? {
            Binding::Part { part, vr: part_vr } => {
                self.parts[part].set_boolean(part_vr, value)?;
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
        for part in &self.parts {
            part.save_variables(out);
        }
        out.f64(self.tolerance);
        out.bool(self.start_equilibrium);
    }

    fn load_variables(&mut self, input: &mut StateReader) -> FmiResult {
        for (part, spec) in self.parts.iter_mut().zip(&self.shared.spec.parts) {
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
        Line::from_spec(&text)
    }

    fn description(&self) -> &ModelDescription {
        &self.shared.description
    }

    fn save_state(&self, out: &mut StateWriter) {
        for part in &self.parts {
            part.save_state(out);
        }
        out.bool(self.net.is_some());
        out.i32(self.x.len() as i32);
        for &x in &self.x {
            out.f64(x);
        }
        out.f64(self.time);
        out.f64(self.next_event);
        out.f64(self.integrator.as_ref().map_or(0.0, |r| r.next_step));
        out.f64(self.rtol);
        out.i32(self.scratch.rtol_scale.len() as i32);
        for &x in &self.scratch.rtol_scale {
            out.f64(x);
        }
    }

    fn load_state(&mut self, r: &mut StateReader) -> FmiResult {
        for part in &mut self.parts {
            part.load_state(r)?;
        }
        let initialized = r.bool("initialized")?;
        let n = r.i32("number of states")?;
        let mut x = Vec::new();
        for _ in 0..n.max(0) {
            x.push(r.finite("state")?);
        }
        self.time = r.finite("time")?;
        self.next_event = r.f64("next event")?;
        let next_step = r.finite("next step")?;
        self.rtol = r.finite("integrator tolerance")?;
        let scales = r.i32("number of tolerance scales")?;
        let mut rtol_scale = Vec::new();
        for _ in 0..scales.max(0) {
            rtol_scale.push(r.finite("tolerance scale")?);
        }
        if initialized {
            // The parameters set the network (a roll's radius is a state only while it is wound):
            // out of their ranges, say which, before the structure they break.
            fmi_core::instance::check_values(self, true)?;
            let net = Network::new(&self.shared.spec, &self.parts).map_err(FmiError::error)?;
            if x.len() != net.len() {
                return Err(FmiError::error(format!("the state holds {} line states, the line has {}", x.len(), net.len())));
            }
            let mut integrator = Rosenbrock::new(stepping::METHOD, net.len(), net.kl, net.ku);
            integrator.next_step = next_step;
            self.integrator = Some(integrator);
            self.net = Some(net);
        } else {
            // Before initialization the line has no integrator, so no tolerance scales to keep.
            if !rtol_scale.is_empty() {
                return Err(FmiError::error(format!("the state holds {} tolerance scales, the line is not initialized", rtol_scale.len())));
            }
            self.net = None;
            self.integrator = None;
        }
        self.x = x;
        self.ramps.clear();
        self.scratch = Scratch::default();
        if let Some(net) = &self.net {
            if rtol_scale.len() != net.len() {
                return Err(FmiError::error(format!("the state holds {} tolerance scales, the line has {} states", rtol_scale.len(), net.len())));
            }
            let mut scratch = stepping::scratch(self, net.len());
            scratch.rtol_scale = rtol_scale;
            self.scratch = scratch;
        }
        self.settle()
    }

    fn set_input_derivative(&mut self, vr: u32, value: f64) -> FmiResult {
        let Binding::Part { part, vr: part_vr } = self.binding(vr)? else {
            return Err(FmiError::error(format!("value reference {vr} is not an input")));
        };
        let base = self.parts[part].get_real(part_vr)?;
        match self.ramps.iter_mut().find(|(p, v, _, _)| *p == part && *v == part_vr) {
            Some(r) => *r = (part, part_vr, base, value),
            None => self.ramps.push((part, part_vr, base, value)),
        }
        Ok(())
    }

    fn initialize(&mut self, experiment: &Experiment, resources: &Resources) -> FmiResult<Vec<String>> {
        stepping::initialize(self, experiment, resources)
    }

    fn set_time(&mut self, time: f64) {
        if time != self.time {
            self.time = time;
            // Model Exchange: a failure shows when the states are set or outputs read.
            let _ = self.settle();
        }
    }

    fn do_step(&mut self, h: f64) -> FmiResult {
        stepping::step(self, h)
    }

    fn event_update(&mut self) -> EventUpdate {
        stepping::event_update(self)
    }

    fn get_continuous_states(&self, x: &mut [f64]) -> FmiResult {
        x.copy_from_slice(&self.x);
        Ok(())
    }

    fn set_continuous_states(&mut self, x: &[f64]) -> FmiResult {
        if let Some(bad) = x.iter().position(|v| !v.is_finite()) {
            return Err(FmiError::discard(format!("state {bad} = {} is not finite", x[bad])));
        }
        // The states before, to go back to if the parts refuse these.
        self.scratch.x.copy_from_slice(&self.x);
        self.x.copy_from_slice(x);
        if let Err(e) = self.settle() {
            self.x.copy_from_slice(&self.scratch.x);
            let _ = self.settle();
            return Err(e);
        }
        Ok(())
    }

    fn get_derivatives(&self, dx: &mut [f64]) -> FmiResult {
        let net = self.net.as_ref().ok_or_else(|| FmiError::error("the line is not initialized"))?;
        net.derivatives(&self.parts, dx)
    }

    fn get_nominals(&self, nominals: &mut [f64]) -> FmiResult {
        let Some(net) = &self.net else { return Err(FmiError::error("the line is not initialized")) };
        let mut buffer = [0.0; 8];
        for (k, s) in net.states.iter().enumerate() {
            let part = &self.parts[s.part];
            let n = part.state_count();
            part.get_nominals(&mut buffer[..n])?;
            nominals[k] = buffer[s.index];
        }
        Ok(())
    }

    fn get_event_indicators(&self, z: &mut [f64]) -> FmiResult {
        let mut k = 0;
        for part in &self.parts {
            let n = part.event_indicator_count();
            part.get_event_indicators(&mut z[k..k + n])?;
            k += n;
        }
        Ok(())
    }

    fn partial_derivative(&self, unknown: u32, known: u32, _of: Jacobian) -> FmiResult<f64> {
        stepping::partial_derivative(self, unknown, known)
    }

    fn outputs_defined(&self) -> FmiResult {
        self.parts.iter().try_for_each(Part::outputs_defined)
    }

    fn inputs_valid(&self) -> FmiResult {
        self.parts.iter().try_for_each(Part::inputs_valid)
    }

    fn provisional_state(&mut self) {}
}
