//! The Line FMU's interface, built from its spec and its parts: every
//! variable is `<part>.<variable>` in SI units and is one of the part's own
//! (so its type, unit and range come from the part's model description) or
//! a load cell. The same table is the runtime description the FMI layer
//! checks calls against and, written as XML by `line-description`, the
//! modelDescription.xml the FMU ships: one builder for both.

use crate::laminate::{Laminate, Quantity};
use crate::part::Part;
use crate::port::Port;
use crate::spec::{PartSpec, Role, Spec};
use fmi_core::description::{
    settable_in, Causality, Dependency, Family, Initial, Kind, ModelDescription, Range, Slot, Start, Variability, Variable,
};
use std::borrow::Cow;

/// What a variable of the line is bound to.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Binding {
    /// Real variable `vr` of part `part`, resolved once to the part's own variable (`port`).
    Real { part: usize, vr: u32, port: Port },
    /// Variable `vr` of part `part` of another type.
    Part { part: usize, vr: u32 },
    /// The resultant of the two web forces on a roller's bearings, for a wrap angle with this cosine.
    LoadCell { part: usize, cos_wrap: f64 },
    /// A laminate span's own `quantity`, made of its layers' (`Interface::laminates[laminate]`).
    Laminate { laminate: usize, quantity: Quantity },
    /// The line integrator's relative tolerance.
    Tolerance,
    /// Whether initialization solves the line's steady state.
    StartAtEquilibrium,
}

/// Part parameters the line does not offer: the line solves and starts the
/// parts itself, and its outputs are SI; a roller's ports, roll, carriage, traction (and its nip's side), runout (and its span's length and its harmonics' orders), a lay-on roller and
/// layers, a drive's loop (its kind, feed-forward and lag decide its states and what it
/// measures) and a span's variable length are the line's structure, which line.json fixes; a feed-forward's
/// loop.acceleration the line sets from its reference (`feed`).
const NOT_OFFERED: [&str; 31] = [
    "startAtEquilibrium",
    "useSensor",
    "toUnitV",
    "toUnitF",
    "solver",
    "tolerance",
    "substeps",
    "profile",
    "roll",
    "inlets",
    "outlets",
    "carriage",
    "includeTraction",
    "layered",
    "variableLength",
    "loop.kind",
    "loop.sign",
    "loop.feedforward",
    "loop.compression",
    "loop.acceleration",
    "motor.lag",
    "speed.input",
    "load_cell.wrap",
    "nip.side",
    "runout",
    "runout.L",
    "runout.h1.k",
    "runout.h2.k",
    "runout.h3.k",
    "runout.h4.k",
    "layon",
];

/// The integrator's relative tolerance unless the user sets `tolerance`.
pub const DEFAULT_TOLERANCE: f64 = 1e-9;

pub struct Interface {
    pub description: ModelDescription,
    /// By value reference (index 0 unused).
    pub bindings: Vec<Binding>,
    /// The laminate spans, whose outputs `Binding::Laminate` computes.
    pub laminates: Vec<Laminate>,
}

struct Builder<'a> {
    parts: &'a [Part],
    variables: Vec<Variable>,
    bindings: Vec<Binding>,
}

impl Builder<'_> {
    fn push(&mut self, v: Variable, b: Binding) -> u32 {
        let vr = self.bindings.len() as u32;
        self.variables.push(Variable { vr, ..v });
        self.bindings.push(b);
        vr
    }

    /// The part's variable `name`, offered as `<part>.<label>` with `causality`.
    fn part_variable(&mut self, p: usize, spec: &PartSpec, name: &str, label: &str, causality: Causality) -> u32 {
        let part = &self.parts[p];
        let d = part.description();
        let v = d.variable_by_name(name).unwrap_or_else(|| panic!("{} has {name}", d.model_identifier));
        let start = match (causality, v.kind) {
            (Causality::Parameter | Causality::Input, Kind::Real) => Start::Real(part.get_real(v.vr).expect("a Real")),
            (Causality::Parameter | Causality::Input, Kind::Integer | Kind::Enumeration { .. }) => Start::Integer(part.get_integer(v.vr).expect("an Integer")),
            (Causality::Parameter | Causality::Input, Kind::Boolean) => Start::Boolean(part.get_boolean(v.vr).expect("a Boolean")),
            _ => Start::None,
        };
        let (variability, initial) = match causality {
            // A part's tunable parameter (a loop's gains, set point, limit) stays tunable in the line.
            Causality::Parameter if v.variability == Variability::Tunable => (Variability::Tunable, Initial::Exact),
            Causality::Parameter => (Variability::Fixed, Initial::Exact),
            Causality::Input => (Variability::Continuous, Initial::None),
            _ => (v.variability, if v.initial == Initial::None { Initial::Calculated } else { v.initial }),
        };
        let description = if v.description.is_empty() {
            format!("{} ({})", spec.name, spec.role.name())
        } else {
            format!("{}: {}", spec.name, v.description)
        };
        let row = Variable {
            name: Cow::Owned(format!("{}.{label}", spec.name)),
            vr: 0,
            description: Cow::Owned(description),
            kind: v.kind,
            causality,
            variability,
            initial,
            start,
            range: v.range,
            unit: v.unit,
            max_rate: v.max_rate,
            family: v.family,
            settable_in: settable_in(causality, variability, initial),
        };
        let vr = v.vr;
        let binding = match part.port(vr) {
            Some(port) if v.kind == Kind::Real => Binding::Real { part: p, vr, port },
            _ => Binding::Part { part: p, vr },
        };
        self.push(row, binding)
    }

    fn own(&mut self, name: String, description: &str, kind: Kind, causality: Causality, start: Start, range: Range, b: Binding) -> u32 {
        let (variability, initial) = match causality {
            Causality::Parameter => (Variability::Fixed, Initial::Exact),
            _ => (Variability::Continuous, Initial::Calculated),
        };
        let row = Variable {
            name: Cow::Owned(name),
            vr: 0,
            description: Cow::Owned(description.to_string()),
            kind,
            causality,
            variability,
            initial,
            start,
            range,
            unit: if matches!(b, Binding::LoadCell { .. }) { "N" } else { "" },
            max_rate: f64::INFINITY,
            family: Family::of(kind),
            settable_in: settable_in(causality, variability, initial),
        };
        self.push(row, b)
    }
}

/// Where the line carries the strain past roller `p`, from the span before it straight to the
/// span after (as webline connects a roller of one inlet whose strain is not its own, so the
/// roller's web_a.eps stays unset): that span's exit strain, the strain of the web leaving the
/// roller, which the line then reads for the roller's `eps`.
fn strain_past(spec: &Spec, parts: &[Part], p: usize) -> Option<Binding> {
    let ps = &spec.parts[p];
    let own = ps.profile.as_ref().is_some_and(|profile| profile.get("strain").is_some())
        || matches!(&parts[p], Part::Roller(r) if r.params.inlets > 1)
        || spec.connections.iter().any(|c| c.to.0 == ps.name && c.to.1 == "web_a.eps");
    if own {
        return None;
    }
    let arriving = spec.connections.iter().find(|c| c.from.0 == ps.name && c.from.1 == "web_a.v" && c.to.1 == "web_b.v")?;
    let span = spec.part(&arriving.to.0).filter(|&s| spec.parts[s].role == Role::Span)?;
    let vr = parts[span].description().variable_by_name("web_b.eps")?.vr;
    Some(Binding::Real { part: span, vr, port: parts[span].port(vr)? })
}

fn offered_vr(offered: &[(u32, u32)], part_vr: u32) -> Option<u32> {
    offered.iter().find(|(pv, _)| *pv == part_vr).map(|&(_, lv)| lv)
}

fn any() -> Range {
    Range { min: f64::NEG_INFINITY, min_inclusive: true, max: f64::INFINITY, max_inclusive: true, lo: f64::NEG_INFINITY, hi: f64::INFINITY }
}

/// The interface of `spec` with `parts` at their start values; `active`
/// lists each part's integrated states (indices of its state vector).
pub fn build(spec: &Spec, parts: &[Part], active: &[Vec<usize>], guid: String, start_equilibrium: bool) -> Interface {
    let mut b = Builder { parts, variables: Vec::new(), bindings: vec![Binding::Tolerance] };
    let positive = Range { min: 0.0, min_inclusive: false, max: 1e-2, max_inclusive: true, lo: f64::MIN_POSITIVE, hi: 1e-2 };
    b.own(
        "tolerance".into(),
        "relative tolerance of the line's integrator (Rodas5P, error-controlled)",
        Kind::Real,
        Causality::Parameter,
        Start::Real(DEFAULT_TOLERANCE),
        positive,
        Binding::Tolerance,
    );
    b.own(
        "startAtEquilibrium".into(),
        "initialization solves the line's steady state for its drives at the start time",
        Kind::Boolean,
        Causality::Parameter,
        Start::Boolean(start_equilibrium),
        any(),
        Binding::StartAtEquilibrium,
    );
    let mut states = Vec::new();
    let mut derivatives = Vec::new();
    let mut outputs = Vec::new();
    for (p, ps) in spec.parts.iter().enumerate() {
        let d = parts[p].description();
        let mut offered: Vec<(u32, u32)> = Vec::new(); // (part vr, line vr)
        macro_rules! offer {
            ($name:expr, $label:expr, $causality:expr) => {{
                let name: &str = $name;
                let vr = b.part_variable(p, ps, name, $label, $causality);
                offered.push((d.variable_by_name(name).expect("offered").vr, vr));
                vr
            }};
        }
        match ps.role {
            Role::Span => {
                let names = [("summary_Tension", "T"), ("summary_Strain", "eps"), ("web_a.F", "F_a"), ("web_b.F", "F_b"), ("summary_Length", "length")];
                for (name, label) in names {
                    outputs.push(offer!(name, label, Causality::Output));
                }
            }
            role => {
                let mut names = vec![("v", "v"), ("omega", "omega"), ("tau", "tau"), ("web_b.eps", "eps")];
                if let Some(air) = parts[p].traction() {
                    names.extend([("v_web", "v_web"), ("slip", "slip"), ("traction", "traction"), ("mu_eff", "mu_eff")]);
                    if air {
                        names.push(("h_air", "h_air"));
                    }
                }
                if matches!(role, Role::Unwinder | Role::Winder) {
                    names.push(("r", "r"));
                }
                if parts[p].layon() {
                    names.extend([("layon.N", "layon.N"), ("layon.delta", "layon.delta")]);
                }
                if role == Role::Dancer {
                    names.extend([("y", "y"), ("y_dot", "y_dot")]);
                }
                for (name, label) in names {
                    let vr = offer!(name, label, Causality::Output);
                    if let Some(carried) = (label == "eps").then(|| strain_past(spec, parts, p)).flatten() {
                        b.bindings[vr as usize] = carried;
                    }
                    outputs.push(vr);
                }
                if let Some(w) = ps.wrap {
                    let vr = b.own(
                        format!("{}.F", ps.name),
                        &format!("{}: load cell, the resultant of the web forces on the bearings (wrap {w} degrees; the lanes leaving a slitter summed)", ps.name),
                        Kind::Real,
                        Causality::Output,
                        Start::None,
                        any(),
                        Binding::LoadCell { part: p, cos_wrap: w.to_radians().cos() },
                    );
                    outputs.push(vr);
                }
                if ps.torque_input {
                    offer!("tau_m", "tau_m", Causality::Input);
                }
                if ps.set_input {
                    offer!("loop.set", "T_set", Causality::Input);
                }
                if ps.speed_input {
                    offer!("loop.speed", "v_ref", Causality::Input);
                }
                if role == Role::Dancer {
                    offer!("F_load", "F_load", Causality::Input);
                }
            }
        }
        for v in d.variables.iter() {
            let offered = !NOT_OFFERED.contains(&&*v.name)
                && (v.kind != Kind::Real || parts[p].acts(v.vr, ps));
            if v.causality == Causality::Parameter && v.kind != Kind::String && offered {
                offer!(&v.name, &v.name, Causality::Parameter);
            }
        }
        // The integrated states and their derivatives (Model Exchange).
        for &s in &active[p] {
            let state_vr = d.states[s];
            let name = d.variable(state_vr).expect("a state").name.clone();
            let known = offered_vr(&offered, state_vr);
            let line_state = match known {
                Some(lv) => lv,
                None => offer!(&name, &name, Causality::Local),
            };
            let der = d.derivatives[s].vr;
            let der_name = d.variable(der).expect("a derivative").name.clone();
            let inner = der_name.trim_start_matches("der(").trim_end_matches(')');
            let line_der = b.part_variable(p, ps, &der_name, "", Causality::Local);
            b.variables[line_der as usize - 1].name = Cow::Owned(format!("der({}.{inner})", ps.name));
            states.push(line_state);
            derivatives.push(line_der);
        }
    }
    let laminates = Laminate::of(spec, parts);
    offer_laminates(&mut b, spec, &laminates, &mut outputs);
    let n_indicators = parts.iter().map(Part::event_indicator_count).sum();
    let all = |vrs: &[u32]| -> Cow<'static, [Dependency]> { Cow::Owned(vrs.iter().map(|&vr| Dependency { vr, on: None }).collect()) };
    let mut initial: Vec<u32> = outputs.clone();
    initial.extend(&states);
    initial.extend(&derivatives);
    initial.sort_unstable();
    initial.dedup();
    let by_vr = Slot::table(&b.variables);
    let description = ModelDescription {
        model_name: Cow::Owned(format!("Line {}", spec.name)),
        model_identifier: "Line",
        guid: Cow::Owned(guid),
        log_categories: converting_span::description::DESCRIPTION.log_categories,
        variables: Cow::Owned(b.variables),
        by_vr: Cow::Owned(by_vr),
        output_dependencies: all(&outputs),
        initial_dependencies: all(&initial),
        can_handle_variable_communication_step_size: true,
        can_interpolate_inputs: true,
        can_get_and_set_fmu_state: true,
        can_serialize_fmu_state: true,
        provides_directional_derivative: [true, true],
        model_exchange: true,
        states: Cow::Owned(states),
        derivatives: all(&derivatives),
        number_of_event_indicators: n_indicators,
    };
    Interface { description, bindings: b.bindings, laminates }
}

/// Each laminate span's outputs, after every part's variables: `<name>.T`, `.eps`, `.F_a`, `.F_b`,
/// `.length` (each its first layer's variable of that kind, renamed, bound to the laminate), and
/// each layer's tension, `<name>.T_<label>`.
fn offer_laminates(b: &mut Builder, spec: &Spec, laminates: &[Laminate], outputs: &mut Vec<u32>) {
    for (k, (lam, ls)) in laminates.iter().zip(&spec.laminates).enumerate() {
        let first = lam.layers[0].part;
        for (quantity, name, label) in Quantity::ALL {
            let vr = b.part_variable(first, &spec.parts[first], name, label, Causality::Output);
            let row = &mut b.variables[vr as usize - 1];
            let what = match quantity {
                Quantity::Tension => "tension, the sum of its layers'".to_string(),
                Quantity::Strain => "strain, its layers' weighted by their stiffness E*A (T/sum E*A without damping)".into(),
                Quantity::EntryForce | Quantity::ExitForce => format!("{name} of its layers, summed"),
                Quantity::Length => "length, which its layers share".into(),
            };
            row.name = Cow::Owned(format!("{}.{label}", lam.name));
            row.description = Cow::Owned(format!("{}: the laminate's {what}", lam.name));
            b.bindings[vr as usize] = Binding::Laminate { laminate: k, quantity };
            outputs.push(vr);
        }
        for (layer, ls) in lam.layers.iter().zip(&ls.layers) {
            let ps = &spec.parts[layer.part];
            let vr = b.part_variable(layer.part, ps, "summary_Tension", "", Causality::Output);
            let row = &mut b.variables[vr as usize - 1];
            row.name = Cow::Owned(format!("{}.T_{}", lam.name, ls.label));
            row.description = Cow::Owned(format!("{}: the tension of its layer {} (part {})", lam.name, ls.label, ps.name));
            outputs.push(vr);
        }
    }
}
