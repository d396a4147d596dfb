//! The line's Jacobian chained from its parts' own tangents (their
//! directional derivatives, the ones their FMUs give importers): each part's
//! partial derivatives along each of its knowns (its states, its connected
//! inputs), then the chain rule through the connections in evaluation order.
//! Exact to rounding, and cheaper than the kl + ku + 1 evaluations of the
//! line a difference quotient needs.
//!
//! Where a connection carries more than a value (a web-mass loop, a length's
//! rate), the line keeps its difference quotient: no plan is made.

use crate::network::{Link, Port};
use crate::part::Part;
use solver::band::Band;

/// Where a part's known comes from: one of the line's states, or a connection.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Source {
    State(usize),
    Link(usize),
}

/// One part's knowns and unknowns: its partials fill `knowns.len()` rows of `unknowns.len()`.
#[derive(Clone, Debug, PartialEq)]
struct PartPlan {
    knowns: Vec<Port>,
    sources: Vec<Source>,
    /// The outputs its connections read, then its active states' derivatives.
    unknowns: Vec<Port>,
    /// How many of `unknowns` are outputs.
    outputs: usize,
    /// Its first partial in `Chain::partials`.
    offset: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    plans: Vec<PartPlan>,
    partials: Vec<f64>,
    /// Per connection (evaluation order): its part and its place among that part's unknowns.
    slots: Vec<(usize, usize)>,
    /// Per connection: d(value)/d(states) over the states it can depend on, [lo, hi), at `offset`.
    windows: Vec<(usize, usize, usize)>,
    totals: Vec<f64>,
    /// Per part: its first state and the indices of its active states.
    first_state: Vec<usize>,
}

impl Chain {
    /// The plan for `links` (in evaluation order), each depending on the states in
    /// `depends[l]` (the band's structure); None where a part has no tangent for a known.
    pub fn new(parts: &[Part], links: &[Link], depends: &[(usize, usize)], first_state: &[usize], active: &[Vec<usize>]) -> Option<Chain> {
        let mut plans = Vec::with_capacity(parts.len());
        let mut slots = vec![(0, 0); links.len()];
        let mut offset = 0;
        for (p, part) in parts.iter().enumerate() {
            let d = part.description();
            let port = |vr: u32| Port::of(part, vr);
            let (mut knowns, mut sources) = (Vec::new(), Vec::new());
            for (k, &i) in active[p].iter().enumerate() {
                knowns.push(port(d.states[i])?);
                sources.push(Source::State(first_state[p] + k));
            }
            for (l, link) in links.iter().enumerate().filter(|(_, l)| l.to == p) {
                knowns.push(link.target);
                sources.push(Source::Link(l));
            }
            let mut unknowns = Vec::new();
            for (l, link) in links.iter().enumerate().filter(|(_, l)| l.from == p) {
                slots[l] = (p, unknowns.len());
                unknowns.push(link.source);
            }
            let outputs = unknowns.len();
            for &i in &active[p] {
                unknowns.push(port(d.derivatives.get(i)?.vr)?);
            }
            let size = knowns.len() * unknowns.len();
            plans.push(PartPlan { knowns, sources, unknowns, outputs, offset });
            offset += size;
        }
        let mut windows = Vec::with_capacity(links.len());
        let mut total = 0;
        for &(lo, hi) in depends {
            windows.push((total, lo, hi));
            total += hi - lo;
        }
        let chain = Chain { plans, partials: vec![0.0; offset], slots, windows, totals: vec![0.0; total], first_state: first_state.to_vec() };
        // Every known of every part must have a tangent: tried once here, at the parts' start.
        chain.clone().partials(parts).then_some(chain)
    }

    /// Every part's partials at the point the parts are evaluated at.
    fn partials(&mut self, parts: &[Part]) -> bool {
        self.plans.iter().zip(parts).all(|(plan, part)| {
            let size = plan.knowns.len() * plan.unknowns.len();
            part.partials(&plan.knowns, &plan.unknowns, &mut self.partials[plan.offset..plan.offset + size])
        })
    }

    /// df/dx into `jac` (cleared), the parts evaluated at the point. Err where a partial
    /// reaches outside the structure the plan was made for (then the caller differences).
    pub fn jacobian(&mut self, parts: &[Part], jac: &mut Band) -> Result<(), ()> {
        if !self.partials(parts) {
            return Err(());
        }
        // Each connection's value, d/d(states): its source's partials, chained through the
        // connections into that source (earlier in evaluation order).
        for l in 0..self.slots.len() {
            let (p, slot) = self.slots[l];
            let plan = &self.plans[p];
            let (offset, lo, hi) = self.windows[l];
            let (done, rest) = self.totals.split_at_mut(offset);
            let row = &mut rest[..hi - lo];
            row.fill(0.0);
            let width = plan.unknowns.len();
            for (k, &source) in plan.sources.iter().enumerate() {
                let c = self.partials[plan.offset + k * width + slot];
                if c == 0.0 {
                    continue;
                }
                match source {
                    Source::State(g) if (lo..hi).contains(&g) => row[g - lo] += c,
                    Source::Link(m) if m < l => {
                        let (o, mlo, mhi) = self.windows[m];
                        if mlo < lo || mhi > hi {
                            return Err(());
                        }
                        for (x, y) in row[mlo - lo..mhi - lo].iter_mut().zip(&done[o..o + mhi - mlo]) {
                            *x += c * y;
                        }
                    }
                    _ => return Err(()),
                }
            }
        }
        // Each state derivative: its part's partials, chained the same way, into its band row
        // (column j at j + kl - row).
        let kl = jac.lower();
        let w = kl + jac.upper() + 1;
        for (p, plan) in self.plans.iter().enumerate() {
            let width = plan.unknowns.len();
            for r in 0..width - plan.outputs {
                let row = self.first_state[p] + r;
                let band = jac.row_mut(row);
                for (k, &source) in plan.sources.iter().enumerate() {
                    let c = self.partials[plan.offset + k * width + plan.outputs + r];
                    if c == 0.0 {
                        continue;
                    }
                    let (o, lo, hi) = match source {
                        Source::State(g) => (usize::MAX, g, g + 1),
                        Source::Link(m) => self.windows[m],
                    };
                    if lo == hi {
                        continue;
                    }
                    if lo + kl < row || hi + kl > row + w {
                        return Err(());
                    }
                    let cols = &mut band[lo + kl - row..hi + kl - row];
                    if o == usize::MAX {
                        cols[0] += c;
                    } else {
                        for (x, y) in cols.iter_mut().zip(&self.totals[o..o + hi - lo]) {
                            *x += c * y;
                        }
                    }
                }
            }
        }
        Ok(())
    }
}
