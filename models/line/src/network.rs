//! The parts joined into one system of ODEs: the line's state vector (every
//! part's continuous states, in line order), the connections evaluated in an
//! order where each output is computed after the inputs it depends on, and
//! the Jacobian's band.
//!
//! Two couplings need more than copying an output to an input:
//!
//! * a span with `includeMass` pulls its exit roller with `T + p + m dv_b/dt`,
//!   and `dv_b/dt` is that roller's acceleration, which the pull drives: a
//!   loop, linear in `dv_b/dt`, solved exactly per evaluation from the
//!   roller's own partial derivatives (the effective inertia `J + m r^2`);
//!   where webs merge, every such span into the nip in one solve;
//! * a span with `variableLength` and `includeDamping` reads dL/dt: the rates
//!   of its frame inputs, from the feeding part's state derivatives;
//! * a laminate with `preventNegativeTension` is slack as one (docs/merge-split.md,
//!   [M6]): decided from all its layers once their inputs are set, before any of
//!   their outputs is read.
//!
//! An evaluation goes straight to the parts' fields and functions: each
//! link's output and input are resolved once, when the line is built, to the
//! part's own variable (`Port`), and the states and derivatives are written
//! and read by the parts' own functions, without value references or state
//! vectors copied per part.

use crate::chain::Chain;
use crate::laminate::Laminate;
use crate::part::{Forces, Part};
use crate::port::{Link, LinkKind};
use crate::spec::Spec;
use fmi_core::description::{Causality, ModelDescription};
use fmi_core::{FmiError, FmiResult};
use std::collections::BTreeSet;

/// Most states a part has (its Model Exchange state vector).
pub(crate) const MAX_PART_STATES: usize = roller::parameters::STATES;

/// One span carrying web mass and pulling a roller: its web_b.F into the
/// roller's `input`, its web_b.v (`speed`) fed by the roller's `roller_speed`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pull {
    pub span: usize,
    pub output: u32,
    pub input: u32,
    pub speed: u32,
    pub roller_speed: u32,
}

/// The pulls on one roller (several where webs merge at a nip): linear in
/// the roller's one acceleration, so solved together.
#[derive(Clone, Debug, PartialEq)]
pub struct MassGroup {
    pub roller: usize,
    pub pulls: Vec<Pull>,
}

/// An input whose rate a span reads (its frame, on a moving roller): the
/// rate of `output` of part `from`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RateLink {
    pub span: usize,
    pub input: u32,
    pub from: usize,
    pub output: u32,
}

/// One of the line's states: state `index` of part `part`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StateRef {
    pub part: usize,
    pub index: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Network {
    /// In evaluation order.
    pub links: Vec<Link>,
    pub groups: Vec<MassGroup>,
    pub rates: Vec<RateLink>,
    pub states: Vec<StateRef>,
    /// Per part: its first state in the line's vector, and its integrated states.
    pub first_state: Vec<usize>,
    pub active: Vec<Vec<usize>>,
    /// Per state of the line: held by its part (a roll's radius while its web has no thickness),
    /// its derivative zero whatever the line does. No derivative is taken along it: the
    /// Jacobian's column of a state whose row is zero never reaches the integrator's solutions.
    pub held: Vec<bool>,
    /// Per part: a span's forces as last computed in this evaluation (`Link::fresh`).
    outputs: Vec<Forces>,
    /// Per part: a span whose forces are computed after the last connection into it, so that
    /// their dx/dt is the span's state derivative in this evaluation (in a line without web
    /// mass or moving spans, whose connections carry values only).
    rate_ready: Vec<bool>,
    /// The point of the last evaluation, if it succeeded and nothing has changed the parts
    /// since (`evaluated_at`): the time and the states.
    evaluated: Option<f64>,
    evaluated_x: Vec<f64>,
    /// A span of variable length checks its state against the frames the last
    /// evaluation gave it (and a frame's rate is read before the links run): an
    /// evaluation then depends on the one before, not only on (t, x) and the inputs.
    pub reads_earlier_inputs: bool,
    /// The laminates that may go slack, each with the link before which it decides (after the
    /// last link into its layers: `order`).
    slack: Vec<(Laminate, usize)>,
    /// Per part: the inputs an output read by a connection depends on (None: every input).
    /// Setting another input moves no connection, only the part's own derivatives and
    /// outputs, which the part computes when they are read.
    moving_inputs: Vec<Option<Vec<u32>>>,
    /// The Jacobian chained from the parts' tangents, where every connection carries a value only.
    pub chain: Option<Chain>,
    /// Sub- and super-diagonals of the Jacobian.
    pub kl: usize,
    pub ku: usize,
}

fn vr_of(d: &ModelDescription, name: &str, part: &str) -> Result<u32, String> {
    d.variable_by_name(name).map(|v| v.vr).ok_or_else(|| format!("part {part} ({}) has no variable {name:?}", d.model_identifier))
}

impl Network {
    /// The links of the spec, ordered; the states; the band. `parts` are
    /// initialized (effects and drives known); `integrated`: per part, its states the line
    /// integrates (indices into its state vector, its active ones among them).
    pub fn new(spec: &Spec, parts: &[Part], integrated: &[Vec<usize>]) -> Result<Network, String> {
        let n_parts = parts.len();
        let mut links = Vec::new();
        for c in &spec.connections {
            let part = |name: &str| spec.part(name).ok_or_else(|| format!("connection {}.{} -> {}.{}: no part {name:?}", c.from.0, c.from.1, c.to.0, c.to.1));
            let (from, to) = (part(&c.from.0)?, part(&c.to.0)?);
            let (df, dt) = (parts[from].description(), parts[to].description());
            let output = vr_of(df, &c.from.1, &c.from.0)?;
            let input = vr_of(dt, &c.to.1, &c.to.0)?;
            let out_var = df.variable(output).expect("looked up");
            let in_var = dt.variable(input).expect("looked up");
            if out_var.causality != Causality::Output || in_var.causality != Causality::Input {
                return Err(format!("connection {}.{} -> {}.{}: must go from an output to an input", c.from.0, c.from.1, c.to.0, c.to.1));
            }
            if links.iter().any(|l: &Link| l.to == to && l.input == input) {
                return Err(format!("input {}.{} is connected twice", c.to.0, c.to.1));
            }
            let port = |p: usize, vr: u32, name: &str| {
                parts[p].port(vr).ok_or_else(|| format!("connection {}.{} -> {}.{}: {name} is no Real", c.from.0, c.from.1, c.to.0, c.to.1))
            };
            let (source, target) = (port(from, output, &c.from.1)?, port(to, input, &c.to.1)?);
            links.push(Link { from, output, to, input, kind: LinkKind::Plain, source, target, fresh: true });
        }
        // The web-mass loops: a span's web_b.F into the roller whose web_a.v feeds its web_b.v.
        let mut groups: Vec<MassGroup> = Vec::new();
        for i in 0..links.len() {
            let l = links[i];
            if !parts[l.from].includes_mass() {
                continue;
            }
            let d = parts[l.from].description();
            if l.output != vr_of(d, "web_b.F", "span")? {
                continue;
            }
            let speed = vr_of(d, "web_b.v", "span")?;
            let Some(feed) = links.iter().find(|k| k.to == l.from && k.input == speed) else {
                return Err(format!("part {}: includeMass needs its web_b.v connected", spec.parts[l.from].name));
            };
            if feed.from != l.to {
                return Err(format!(
                    "part {}: includeMass needs web_b.v from the part its web_b.F pulls ({}), not from {}",
                    spec.parts[l.from].name, spec.parts[l.to].name, spec.parts[feed.from].name
                ));
            }
            let pull = Pull { span: l.from, output: l.output, input: l.input, speed, roller_speed: feed.output };
            let group = match groups.iter().position(|g| g.roller == l.to) {
                Some(g) => g,
                None => {
                    groups.push(MassGroup { roller: l.to, pulls: Vec::new() });
                    groups.len() - 1
                }
            };
            groups[group].pulls.push(pull);
            links[i].kind = LinkKind::MassLoop { group, lead: false };
        }
        // Frames whose rates a damped span of variable length reads.
        let mut rates = Vec::new();
        for l in &links {
            if parts[l.to].reads_length_rate() {
                let name = &parts[l.to].description().variable(l.input).expect("looked up").name;
                if name.starts_with("frame_") {
                    rates.push(RateLink { span: l.to, input: l.input, from: l.from, output: l.output });
                }
            }
        }
        let clamping: Vec<Laminate> = Laminate::of(spec, parts).into_iter().filter(|l| l.clamps(parts)).collect();
        let mut links = order(&links, parts, spec, &clamping)?;
        // A group is solved at its first link in evaluation order; the others only mark its inputs.
        for i in 0..links.len() {
            if let LinkKind::MassLoop { group, .. } = links[i].kind {
                let first = !links[..i].iter().any(|k| matches!(k.kind, LinkKind::MassLoop { group: g, .. } if g == group));
                links[i].kind = LinkKind::MassLoop { group, lead: first };
            }
        }
        // Where each span's outputs are computed: at the start of an evaluation every part's
        // states moved; a link moves its target's inputs, a web-mass group's lead the input
        // rates of all its spans and the forces on its roller.
        let mut moved = vec![true; n_parts];
        for l in &mut links {
            l.fresh = moved[l.from];
            moved[l.from] = false;
            moved[l.to] = true;
            if let LinkKind::MassLoop { group, lead } = l.kind {
                moved[l.from] = true;
                if lead {
                    for pull in &groups[group].pulls {
                        moved[pull.span] = true;
                    }
                    moved[groups[group].roller] = true;
                }
            }
        }
        // A laminate decides before the first link that reads one of its layers, directly or in a
        // web-mass group's solve (its lead).
        let reads_layer = |lam: &Laminate, l: &Link| {
            lam.has(l.from)
                || matches!(l.kind, LinkKind::MassLoop { group, lead: true } if groups[group].pulls.iter().any(|p| lam.has(p.span)))
        };
        let slack = clamping
            .into_iter()
            .map(|lam| {
                let at = links.iter().position(|l| reads_layer(&lam, l)).unwrap_or(links.len());
                (lam, at)
            })
            .collect();
        let plain = groups.is_empty() && rates.is_empty();
        let mut read = vec![false; n_parts];
        for l in &links {
            read[l.from] = true;
        }
        let rate_ready: Vec<bool> = (0..n_parts).map(|p| plain && read[p] && !moved[p] && parts[p].rate_with_forces()).collect();
        // States in line order.
        let mut states = Vec::new();
        let mut first_state = Vec::with_capacity(n_parts);
        let mut active = Vec::with_capacity(n_parts);
        for (p, a) in integrated.iter().enumerate() {
            first_state.push(states.len());
            states.extend(a.iter().map(|&index| StateRef { part: p, index }));
            active.push(a.clone());
        }
        if let Some(part) = parts.iter().find(|p| p.state_count() > MAX_PART_STATES) {
            return Err(format!("a part ({}) has more than {MAX_PART_STATES} states", part.description().model_identifier));
        }
        let held = states.iter().map(|s| !parts[s.part].active_states().contains(&s.index)).collect();
        let outputs = vec![Forces::default(); n_parts];
        let evaluated_x = vec![0.0; states.len()];
        let reads_earlier_inputs = parts.iter().any(Part::reads_earlier_inputs);
        let mut moving_inputs: Vec<Option<Vec<u32>>> = vec![Some(Vec::new()); n_parts];
        for l in &links {
            let on = parts[l.from].description().output_dependencies.iter().find(|u| u.vr == l.output).and_then(|u| u.on.clone());
            match (&mut moving_inputs[l.from], on) {
                (Some(list), Some(on)) => list.extend(on.iter().copied()),
                (m, _) => *m = None,
            }
        }
        let mut net = Network {
            links,
            groups,
            rates,
            states,
            first_state,
            active,
            held,
            outputs,
            rate_ready,
            evaluated: None,
            evaluated_x,
            reads_earlier_inputs,
            slack,
            moving_inputs,
            chain: None,
            kl: 0,
            ku: 0,
        };
        let depends;
        (net.kl, net.ku, depends) = net.band(parts);
        if net.groups.is_empty() && net.rates.is_empty() && !net.reads_earlier_inputs {
            let band = solver::band::Band::zeros(net.len(), net.kl, net.ku);
            net.chain = Chain::new(parts, &net.links, &depends, &band, &net.first_state, &net.active, &net.held);
        }
        Ok(net)
    }

    pub fn len(&self) -> usize {
        self.states.len()
    }

    pub fn is_empty(&self) -> bool {
        self.states.is_empty()
    }

    /// The global index of part p's state `index`, if it is integrated.
    pub fn global(&self, p: usize, index: usize) -> Option<usize> {
        self.active[p].iter().position(|&i| i == index).map(|k| self.first_state[p] + k)
    }

    /// Reads the parts' states into x (after initialization or an event).
    pub fn gather(&mut self, parts: &[Part], x: &mut [f64]) -> FmiResult {
        let mut full = [0.0; MAX_PART_STATES];
        for (p, part) in parts.iter().enumerate() {
            let full = &mut full[..part.state_count()];
            part.get_states(full)?;
            for (k, &i) in self.active[p].iter().enumerate() {
                x[self.first_state[p] + k] = full[i];
            }
        }
        Ok(())
    }

    /// Sets the states x and the time t on the parts, runs the connections,
    /// and writes the state derivatives into dx (if given). Afterwards every
    /// part's outputs are those of (t, x).
    pub fn evaluate(&mut self, parts: &mut [Part], t: f64, x: &[f64], dx: Option<&mut [f64]>) -> FmiResult {
        self.evaluated = None;
        for ((part, active), &first) in parts.iter_mut().zip(&self.active).zip(&self.first_state) {
            part.set_point(t, active, &x[first..first + active.len()])?;
        }
        for i in 0..self.rates.len() {
            let r = self.rates[i];
            let rate = output_rate(parts, r.from, r.output)?;
            parts[r.span].set_input_derivative(r.input, rate)?;
        }
        for (i, l) in self.links.iter().enumerate() {
            decide_slack(&self.slack, i, parts);
            match l.kind {
                LinkKind::Plain => {
                    let v = parts[l.from].read(l.source, l.fresh, &mut self.outputs[l.from]);
                    parts[l.to].write(l.target, v)?;
                }
                LinkKind::MassLoop { group, lead } => {
                    if lead {
                        mass_loop(parts, &self.groups[group])?;
                    }
                }
            }
        }
        decide_slack(&self.slack, self.links.len(), parts);
        if let Some(dx) = dx {
            self.derivatives_from(parts, dx, true)?;
        }
        self.evaluated = Some(t);
        self.evaluated_x.copy_from_slice(x);
        Ok(())
    }

    /// Whether the parts are as the last evaluation left them, and it was at (t, x): their
    /// derivatives are then f(t, x) with the inputs as they are.
    pub fn evaluated_at(&self, t: f64, x: &[f64]) -> bool {
        self.evaluated == Some(t) && self.evaluated_x == x
    }

    /// The first connection whose value lies outside the range of the input it feeds (the
    /// bounds its part documents and its own FMU holds when the value is set): the link and the value.
    pub fn out_of_bounds(&self, parts: &[Part]) -> Option<(&Link, f64)> {
        self.links.iter().find_map(|l| {
            let value = parts[l.to].real(l.target);
            let range = &parts[l.to].description().variable(l.input)?.range;
            (!range.contains(value)).then_some((l, value))
        })
    }

    /// Whether setting input `vr` of part `part` moves a connection: then the line must be
    /// evaluated again before its outputs are read. Where web mass or a length's rate is
    /// coupled, an acceleration or a rate is carried by the connections: every input moves them.
    pub fn input_moves_connections(&self, part: usize, vr: u32) -> bool {
        !self.groups.is_empty() || !self.rates.is_empty() || self.reads_earlier_inputs || self.moving_inputs[part].as_ref().is_none_or(|list| list.contains(&vr))
    }

    /// Something other than an evaluation changed the parts (an event, a parameter, a failed
    /// step's parts put back).
    pub fn parts_changed(&mut self) {
        self.evaluated = None;
        if let Some(chain) = self.chain.as_mut() {
            chain.renew();
        }
    }

    /// The laminates that may go slack (their layers' event indicator is the sum of their pulls).
    pub fn slack_laminates(&self) -> impl Iterator<Item = &Laminate> {
        self.slack.iter().map(|(lam, _)| lam)
    }

    /// The state derivatives of the parts as last evaluated, by the parts' own
    /// functions (those their `get_derivatives` calls).
    pub fn derivatives(&self, parts: &[Part], dx: &mut [f64]) -> FmiResult {
        self.derivatives_from(parts, dx, false)
    }

    /// `in_evaluation`: right after the connections ran, where a span's dx/dt is the one its
    /// forces computed (`rate_ready`).
    fn derivatives_from(&self, parts: &[Part], dx: &mut [f64], in_evaluation: bool) -> FmiResult {
        let each = self.active.iter().zip(&self.first_state).zip(self.rate_ready.iter().zip(&self.outputs));
        for (part, ((active, &first), (&ready, held))) in parts.iter().zip(each) {
            part.active_derivatives(active, dx, first, (in_evaluation && ready).then_some(held));
        }
        Ok(())
    }

    /// The Jacobian's band from the model structures: which states each
    /// derivative can depend on, through the connections.
    /// Also, per link, the states its value can depend on: [lo, hi).
    fn band(&self, parts: &[Part]) -> (usize, usize, Vec<(usize, usize)>) {
        let n_parts = parts.len();
        // Per part and input vr: the global states it depends on.
        let mut input_deps: Vec<Vec<(u32, BTreeSet<usize>)>> = vec![Vec::new(); n_parts];
        let own_states = |p: usize| -> BTreeSet<usize> { (0..self.active[p].len()).map(|k| self.first_state[p] + k).filter(|&g| !self.held[g]).collect() };
        let knowns = |p: usize, on: &Option<std::borrow::Cow<'static, [u32]>>, input_deps: &Vec<Vec<(u32, BTreeSet<usize>)>>| -> BTreeSet<usize> {
            let d = parts[p].description();
            let mut set = BTreeSet::new();
            let all: Vec<u32> = d.variables.iter().filter(|v| v.causality == Causality::Input).map(|v| v.vr).chain(d.states.iter().copied()).collect();
            let list: &[u32] = match on {
                Some(l) => l,
                None => &all,
            };
            for &vr in list {
                if let Some(s) = d.states.iter().position(|&s| s == vr) {
                    if let Some(g) = self.global(p, s).filter(|&g| !self.held[g]) {
                        set.insert(g);
                    }
                } else if let Some((_, deps)) = input_deps[p].iter().find(|(i, _)| *i == vr) {
                    set.extend(deps);
                }
            }
            set
        };
        let mut depends = Vec::with_capacity(self.links.len());
        for l in &self.links {
            let d = parts[l.from].description();
            let on = d.output_dependencies.iter().find(|u| u.vr == l.output).map(|u| u.on.clone()).unwrap_or(None);
            let mut deps = knowns(l.from, &on, &input_deps);
            if let LinkKind::MassLoop { group, .. } = l.kind {
                deps.extend(own_states(l.to));
                for (_, others) in &input_deps[l.to] {
                    deps.extend(others.iter().copied());
                }
                // Through the common acceleration each pull's force depends on the others' spans.
                for pull in &self.groups[group].pulls {
                    let d = parts[pull.span].description();
                    let on = d.output_dependencies.iter().find(|u| u.vr == pull.output).map(|u| u.on.clone()).unwrap_or(None);
                    deps.extend(knowns(pull.span, &on, &input_deps));
                }
            }
            depends.push(deps.first().zip(deps.last()).map_or((0, 0), |(&lo, &hi)| (lo, hi + 1)));
            input_deps[l.to].push((l.input, deps));
        }
        for r in &self.rates {
            let source = own_states(r.from);
            match input_deps[r.span].iter_mut().find(|(i, _)| *i == r.input) {
                Some((_, deps)) => deps.extend(source),
                None => input_deps[r.span].push((r.input, source)),
            }
        }
        let (mut kl, mut ku) = (0, 0);
        for (p, part) in parts.iter().enumerate() {
            let d = part.description();
            for (k, &s) in self.active[p].iter().enumerate() {
                let row = self.first_state[p] + k;
                let on = d.derivatives.get(s).map(|u| u.on.clone()).unwrap_or(None);
                let mut deps = knowns(p, &on, &input_deps);
                // A rate link makes a span's force depend on more than its structure says.
                if self.rates.iter().any(|r| r.span == p) || self.links.iter().any(|l| l.to == p && matches!(l.kind, LinkKind::MassLoop { .. })) {
                    for (_, others) in &input_deps[p] {
                        deps.extend(others.iter().copied());
                    }
                }
                for j in deps {
                    kl = kl.max(row.saturating_sub(j));
                    ku = ku.max(j.saturating_sub(row));
                }
            }
        }
        (kl, ku, depends)
    }
}

/// The laminates due to decide before link `at` (`Network::slack`): whether each is slack.
#[inline(always)]
fn decide_slack(slack: &[(Laminate, usize)], at: usize, parts: &mut [Part]) {
    for (lam, _) in slack.iter().filter(|(_, k)| *k == at) {
        lam.decide_slack(parts);
    }
}

/// d(output)/dt of part p now: sum over its states of d(output)/dx * dx/dt.
fn output_rate(parts: &[Part], p: usize, output: u32) -> FmiResult<f64> {
    let part = &parts[p];
    let mut full = [0.0; MAX_PART_STATES];
    let full = &mut full[..part.state_count()];
    part.get_derivatives(full)?;
    let d = part.description();
    let mut rate = 0.0;
    for (i, &state) in d.states.iter().enumerate() {
        let dx = full[i];
        if dx != 0.0 {
            rate += part.partial_derivative(output, state)? * dx;
        }
    }
    Ok(rate)
}

/// F_k = F0_k + m_k a for each pull k, a = a0 + sum_k beta_k (F_k - F0_k) (the roller's
/// surface acceleration, linear in the forces on it): a = a0 / (1 - sum_k beta_k m_k), exactly.
fn mass_loop(parts: &mut [Part], group: &MassGroup) -> FmiResult {
    let roller = group.roller;
    let mut sum = 0.0;
    for pull in &group.pulls {
        parts[pull.span].set_input_derivative(pull.speed, 0.0)?;
        let f0 = parts[pull.span].get_real(pull.output)?;
        let mass_vr = parts[pull.span].description().variable_by_name("m_web").map(|v| v.vr).expect("the span has m_web");
        let m = parts[pull.span].get_real(mass_vr)?;
        parts[roller].set_real(pull.input, f0)?;
        let d = parts[roller].description();
        let mut beta = 0.0;
        for (i, &state) in d.states.iter().enumerate() {
            let dv = parts[roller].partial_derivative(pull.roller_speed, state)?;
            if dv != 0.0 {
                beta += dv * parts[roller].partial_derivative(d.derivatives[i].vr, pull.input)?;
            }
        }
        sum += beta * m;
    }
    // Every port of a roller moves with its surface: one acceleration for all the pulls.
    let a0 = output_rate(parts, roller, group.pulls[0].roller_speed)?;
    let a = a0 / (1.0 - sum);
    if !a.is_finite() {
        return Err(FmiError::discard(format!("the web mass loop has no solution (1 - sum beta m = {})", 1.0 - sum)));
    }
    for pull in &group.pulls {
        parts[pull.span].set_input_derivative(pull.speed, a)?;
        let f = parts[pull.span].get_real(pull.output)?;
        parts[roller].set_real(pull.input, f)?;
    }
    Ok(())
}

/// The links in an order where each one's output is computed after every
/// link into the inputs that output depends on (ModelStructure); a web-mass
/// loop after every other link into its roller; a layer of a laminate that may go slack after
/// every link into any of its layers (the laminate decides from all of them).
fn order(links: &[Link], parts: &[Part], spec: &Spec, clamping: &[Laminate]) -> Result<Vec<Link>, String> {
    // The links into the inputs output `l` depends on.
    let feeding = |l: &Link| -> Vec<usize> {
        let d = parts[l.from].description();
        let on = d.output_dependencies.iter().find(|u| u.vr == l.output).and_then(|u| u.on.clone());
        let depends = |vr: u32| on.as_ref().is_none_or(|list| list.contains(&vr));
        let laminate = clamping.iter().find(|lam| lam.has(l.from));
        let feeds = |k: &Link| (k.to == l.from && depends(k.input)) || laminate.is_some_and(|lam| lam.has(k.to));
        links.iter().enumerate().filter(|(_, k)| feeds(k)).map(|(i, _)| i).collect()
    };
    let group_of = |l: &Link| match l.kind {
        LinkKind::MassLoop { group, .. } => Some(group),
        LinkKind::Plain => None,
    };
    let needs: Vec<Vec<usize>> = links
        .iter()
        .map(|l| {
            let Some(group) = group_of(l) else { return feeding(l) };
            // A mass group is solved at once: each pull needs what every pull of its group
            // needs, and every other link into the roller, but not the group's other pulls.
            let mut need = Vec::new();
            for k in links.iter().filter(|k| group_of(k) == Some(group)) {
                need.extend(feeding(k));
            }
            need.extend(links.iter().enumerate().filter(|(_, k)| k.to == l.to && group_of(k) != Some(group)).map(|(i, _)| i));
            need
        })
        .collect();
    let mut done = vec![false; links.len()];
    let mut ordered = Vec::with_capacity(links.len());
    while ordered.len() < links.len() {
        let before = ordered.len();
        for i in 0..links.len() {
            if !done[i] && needs[i].iter().all(|&k| done[k] || k == i) {
                done[i] = true;
                ordered.push(links[i]);
            }
        }
        if ordered.len() == before {
            let stuck: Vec<String> = (0..links.len())
                .filter(|&i| !done[i])
                .map(|i| {
                    let l = &links[i];
                    let name = |p: usize, vr: u32| format!("{}.{}", spec.parts[p].name, parts[p].description().variable(vr).map_or("?", |v| &v.name));
                    format!("{} -> {}", name(l.from, l.output), name(l.to, l.input))
                })
                .collect();
            return Err(format!("the connections form an algebraic loop: {}", stuck.join(", ")));
        }
    }
    Ok(ordered)
}
