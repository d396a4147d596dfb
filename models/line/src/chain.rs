//! The line's Jacobian chained from its parts' own tangents (their
//! directional derivatives, the ones their FMUs give importers): each part's
//! partial derivatives along each of its knowns (its states, its connected
//! inputs), then the chain rule through the connections in evaluation order.
//! Exact to rounding, and no evaluation of the line.
//!
//! The chain rule is compiled when the line is built into terms `c * window`:
//! a connection's value depends on the states in a window (the band's
//! structure), and so does every known of a part (a state: a window of one).
//! Where a connection carries more than a value (a web-mass loop, a length's
//! rate), the line keeps its difference quotient: no chain is made.

use crate::part::{Directions, Part};
use crate::port::{Link, Port};
use solver::band::Band;
use std::ops::Range;

/// One part's knowns and unknowns: its partials, a row of `unknowns.len()` per known.
#[derive(Clone, Debug, PartialEq)]
struct PartPlan {
    directions: Directions,
    /// Its partials stay until an event or a parameter changes the part (`Part::tangents_fixed`).
    fixed: bool,
    /// The outputs its connections read, then its active states' derivatives.
    unknowns: Vec<Port>,
    /// Its first partial in `Chain::partials`.
    offset: usize,
}

/// `dest[to..to + len] += partials[partial] * totals[from..from + len]`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Term {
    partial: usize,
    from: usize,
    to: usize,
    len: usize,
}

#[derive(Clone, Debug, PartialEq)]
pub struct Chain {
    plans: Vec<PartPlan>,
    partials: Vec<f64>,
    /// d(value)/d(states) of each connection over its window; `totals[0]` is 1, the window of
    /// every state (a state's derivative by itself).
    totals: Vec<f64>,
    /// Per connection, in evaluation order: its window in `totals` and its terms.
    links: Vec<(Range<usize>, Range<usize>)>,
    /// The terms of the band's rows, all at once (their `to` index the band's storage).
    rows: Range<usize>,
    terms: Vec<Term>,
    /// The fixed parts' partials are formed (cleared by `renew`).
    formed: bool,
}

impl Chain {
    /// The chain for `links` (in evaluation order), each depending on the states in
    /// `depends[l]` (the band's structure) and the Jacobian's band; None where a part has no
    /// tangent for one of its knowns or a term would leave the band. A `held` state is no known
    /// (`Network::held`).
    pub fn new(parts: &[Part], links: &[Link], depends: &[(usize, usize)], band: &Band, first_state: &[usize], active: &[Vec<usize>], held: &[bool]) -> Option<Chain> {
        // Each connection's window in `totals`, after the unit at 0.
        let mut windows = Vec::with_capacity(links.len());
        let mut total = 1;
        for &(lo, hi) in depends {
            windows.push((total, lo, hi));
            total += hi - lo;
        }
        // A known's window: (offset in totals, first state, states).
        let state = |g: usize| (0, g, 1);
        let link = |m: usize| (windows[m].0, windows[m].1, windows[m].2 - windows[m].1);
        let mut plans = Vec::with_capacity(parts.len());
        let mut link_terms: Vec<Vec<Term>> = vec![Vec::new(); links.len()];
        let mut row_terms = Vec::new();
        let mut offset = 0;
        let (kl, width) = (band.lower(), band.lower() + band.upper() + 1);
        for (p, part) in parts.iter().enumerate() {
            let d = part.description();
            let port = |vr: u32| part.port(vr);
            let (mut knowns, mut sources, mut known_vrs) = (Vec::new(), Vec::new(), Vec::new());
            for (k, &i) in active[p].iter().enumerate().filter(|&(k, _)| !held[first_state[p] + k]) {
                knowns.push(port(d.states[i])?);
                sources.push(state(first_state[p] + k));
                known_vrs.push(d.states[i]);
            }
            for (m, l) in links.iter().enumerate().filter(|(_, l)| l.to == p) {
                knowns.push(l.target);
                sources.push(link(m));
                known_vrs.push(l.input);
            }
            let outs: Vec<usize> = (0..links.len()).filter(|&l| links[l].from == p).collect();
            // What each unknown depends on, by the part's model structure (None: everything).
            let output_on = |vr: u32| d.output_dependencies.iter().find(|u| u.vr == vr).and_then(|u| u.on.clone());
            let on = |list: &Option<std::borrow::Cow<'static, [u32]>>, vr: u32| list.as_ref().is_none_or(|l| l.contains(&vr));
            let mut unknowns: Vec<Port> = outs.iter().map(|&l| links[l].source).collect();
            for &i in &active[p] {
                unknowns.push(port(d.derivatives.get(i)?.vr)?);
            }
            let n = unknowns.len();
            // The chain rule, each known's window into the unknown's: within it, else the
            // structure is not what the band says and the line differences instead.
            for (k, &(from, lo, len)) in sources.iter().enumerate() {
                if len == 0 {
                    continue;
                }
                for (u, &l) in outs.iter().enumerate() {
                    if !on(&output_on(links[l].output), known_vrs[k]) {
                        continue;
                    }
                    let (to, dlo, dhi) = windows[l];
                    if lo < dlo || lo + len > dhi {
                        return None;
                    }
                    link_terms[l].push(Term { partial: offset + k * n + u, from, to: to + lo - dlo, len });
                }
                for (r, &i) in active[p].iter().enumerate() {
                    if !on(&d.derivatives[i].on, known_vrs[k]) {
                        continue;
                    }
                    let row = first_state[p] + r;
                    if lo + kl < row || lo + len + kl > row + width {
                        return None;
                    }
                    let to = row * width + lo + kl - row;
                    row_terms.push(Term { partial: offset + k * n + outs.len() + r, from, to, len });
                }
            }
            plans.push(PartPlan { directions: part.directions(&knowns)?, fixed: part.tangents_fixed(), unknowns, offset });
            offset += knowns.len() * n;
        }
        let mut terms = Vec::new();
        let mut chained = Vec::with_capacity(links.len());
        for (l, own) in link_terms.into_iter().enumerate() {
            let start = terms.len();
            // A term reads a connection earlier in evaluation order (its value is complete).
            if own.iter().any(|t| t.from >= windows[l].0 && t.from != 0) {
                return None;
            }
            terms.extend(own);
            chained.push((windows[l].0..windows[l].0 + windows[l].2 - windows[l].1, start..terms.len()));
        }
        let rows = terms.len()..terms.len() + row_terms.len();
        terms.extend(row_terms);
        let mut totals = vec![0.0; total];
        totals[0] = 1.0;
        let mut chain = Chain { plans, partials: vec![0.0; offset], totals, links: chained, rows, terms, formed: false };
        // Every known of every part must have a tangent: tried once here, at the parts' start.
        chain.partials(parts).then_some(chain)
    }

    /// Every part's partials at the point the parts are evaluated at (a fixed part's: once).
    fn partials(&mut self, parts: &[Part]) -> bool {
        let (partials, formed) = (&mut self.partials, self.formed);
        self.formed = self.plans.iter().zip(parts).all(|(plan, part)| {
            let size = plan.directions.len() * plan.unknowns.len();
            (plan.fixed && formed) || part.partials(&plan.directions, &plan.unknowns, &mut partials[plan.offset..plan.offset + size])
        });
        self.formed
    }

    /// The parts changed otherwise than by their states, inputs and time (an event): the fixed
    /// parts' partials are formed again.
    pub fn renew(&mut self) {
        self.formed = false;
    }

    /// df/dx into `jac` (cleared, its band the one the chain was made for), the parts
    /// evaluated at the point; Err where a part has no tangent there.
    pub fn jacobian(&mut self, parts: &[Part], jac: &mut Band) -> Result<(), ()> {
        if !self.partials(parts) {
            return Err(());
        }
        let Chain { partials, totals, links, rows, terms, .. } = self;
        for (window, own) in links.iter() {
            totals[window.clone()].fill(0.0);
            for t in &terms[own.clone()] {
                let c = partials[t.partial];
                for i in 0..t.len {
                    totals[t.to + i] += c * totals[t.from + i];
                }
            }
        }
        let band = jac.values_mut();
        for t in &terms[rows.clone()] {
            let c = partials[t.partial];
            for (x, y) in band[t.to..t.to + t.len].iter_mut().zip(&totals[t.from..t.from + t.len]) {
                *x += c * y;
            }
        }
        Ok(())
    }
}
