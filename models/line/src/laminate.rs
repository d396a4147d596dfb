//! A laminate span: a span part per layer, side by side between the same rollers, each with its
//! own strain (docs/merge-split.md, [M6]). The line offers what the laminate does as one span: its
//! tension, the sum of its layers'; its strain, theirs weighted by their stiffness; the forces at its
//! ends; its length, which its layers share. With `preventNegativeTension` the laminate, bonded, is
//! slack as one: when the sum of its layers' pulls is not positive, every layer carries 0; else each
//! its own pull, a compressed layer's negative one too.

use crate::part::Part;
use crate::port::Port;
use crate::spec::Spec;
use converting_span::parameters::SlackRule;
use fmi_core::{FmiError, FmiResult};

/// What a laminate span offers of its own.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Quantity {
    /// T = sum of the layers' tensions.
    Tension,
    /// sum_i E_i A_i eps_i / sum_i E_i A_i: T / sum_i E_i A_i without damping.
    Strain,
    /// The forces at its ends (entry: its tension), summed.
    EntryForce,
    ExitForce,
    /// The length its layers share.
    Length,
}

impl Quantity {
    /// Each with the layer variable it is made of, and its label in the line (`<laminate>.<label>`).
    pub const ALL: [(Quantity, &'static str, &'static str); 5] = [
        (Quantity::Tension, "summary_Tension", "T"),
        (Quantity::Strain, "summary_Strain", "eps"),
        (Quantity::EntryForce, "web_a.F", "F_a"),
        (Quantity::ExitForce, "web_b.F", "F_b"),
        (Quantity::Length, "summary_Length", "length"),
    ];
}

/// A layer: its span part and the part's variables the laminate reads, resolved once.
#[derive(Clone, Debug, PartialEq)]
pub struct Layer {
    pub part: usize,
    /// By `Quantity::ALL`.
    values: [Port; 5],
    /// wp2.E, wp2.thickness, wp2.width: its stiffness E*A.
    stiffness: [Port; 3],
    length: Port,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Laminate {
    pub name: String,
    pub layers: Vec<Layer>,
}

fn port(parts: &[Part], p: usize, name: &str) -> Port {
    let part = &parts[p];
    let vr = part.description().variable_by_name(name).unwrap_or_else(|| panic!("a span has {name}")).vr;
    part.port(vr).expect("a Real of the span")
}

impl Laminate {
    /// The laminates of a checked spec (`Spec::parse`: their layers are span parts).
    pub fn of(spec: &Spec, parts: &[Part]) -> Vec<Laminate> {
        spec.laminates
            .iter()
            .map(|lam| Laminate {
                name: lam.name.clone(),
                layers: lam
                    .layers
                    .iter()
                    .map(|layer| {
                        let p = spec.part(&layer.part).expect("checked");
                        Layer {
                            part: p,
                            values: Quantity::ALL.map(|(_, name, _)| port(parts, p, name)),
                            stiffness: ["wp2.E", "wp2.thickness", "wp2.width"].map(|name| port(parts, p, name)),
                            length: port(parts, p, "L"),
                        }
                    })
                    .collect(),
            })
            .collect()
    }

    fn read(&self, parts: &[Part], q: Quantity, layer: &Layer) -> f64 {
        let k = Quantity::ALL.iter().position(|(x, _, _)| *x == q).expect("every quantity is listed");
        parts[layer.part].real(layer.values[k])
    }

    /// The laminate's `q` now, from its layers' parts as the last evaluation left them.
    pub fn value(&self, parts: &[Part], q: Quantity) -> f64 {
        match q {
            Quantity::Tension | Quantity::EntryForce | Quantity::ExitForce => self.layers.iter().map(|l| self.read(parts, q, l)).sum(),
            Quantity::Length => self.read(parts, q, &self.layers[0]),
            Quantity::Strain => {
                let (mut weighted, mut total) = (0.0, 0.0);
                for l in &self.layers {
                    let ea: f64 = l.stiffness.iter().map(|&s| parts[l.part].real(s)).product();
                    weighted += ea * self.read(parts, q, l);
                    total += ea;
                }
                weighted / total
            }
        }
    }

    /// Whether part `p` is one of its layers.
    pub fn has(&self, p: usize) -> bool {
        self.layers.iter().any(|l| l.part == p)
    }

    /// Whether the laminate keeps its tension from going negative (its layers' `preventNegativeTension`).
    pub fn clamps(&self, parts: &[Part]) -> bool {
        parts[self.layers[0].part].prevents_negative_tension()
    }

    /// The sum of its layers' pulls before the slack clamp [E5]: the laminate's event indicator.
    pub fn pull(&self, parts: &[Part]) -> f64 {
        self.layers.iter().map(|l| parts[l.part].pull().expect("a layer is a span")).sum()
    }

    /// Tells every layer whether the laminate is slack now (the sum of their pulls is not
    /// positive), from their parts as their inputs now stand.
    pub fn decide_slack(&self, parts: &mut [Part]) {
        let rule = SlackRule::Laminate { slack: !(self.pull(parts) > 0.0) };
        for l in &self.layers {
            parts[l.part].set_slack_rule(rule);
        }
    }

    /// The layers share their span's length and whether it may go slack: a part's `L` or
    /// `preventNegativeTension` set apart from the others' is refused, naming both.
    pub fn check(&self, spec: &Spec, parts: &[Part]) -> FmiResult {
        let first = &self.layers[0];
        let clamps = self.clamps(parts);
        for l in &self.layers[1..] {
            if parts[l.part].prevents_negative_tension() != clamps {
                let name = |p: usize| &spec.parts[p].name;
                return Err(FmiError::error(format!(
                    "{}.preventNegativeTension = {}, but {}.preventNegativeTension = {clamps}: the layers of laminate {} go slack \
                     together (all on or all off)",
                    name(l.part),
                    !clamps,
                    name(first.part),
                    self.name
                )));
            }
        }
        let l0 = parts[first.part].real(first.length);
        for l in &self.layers[1..] {
            let length = parts[l.part].real(l.length);
            if length != l0 {
                let name = |p: usize| &spec.parts[p].name;
                return Err(FmiError::error(format!(
                    "{}.L = {length} m, but {}.L = {l0} m: the layers of laminate {} share their span's length",
                    name(l.part),
                    name(first.part),
                    self.name
                )));
            }
        }
        Ok(())
    }
}
