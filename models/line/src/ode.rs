//! The line's ODE x' = f(t, x) and where it stands (`Ode`): its right-hand side
//! through the parts' own equations, and its banded Jacobian, chained from
//! the parts' tangents (`chain`) or, where the line has no chain, by grouped
//! differences. The integrator (`stepping`), the steady state (`equilibrium`)
//! and outside solvers (bench/diffsol_line) all evaluate the line here.

use crate::network::Network;
use crate::part::Part;
use fmi_core::{FmiError, FmiResult};
use solver::band::Band;
use solver::stiff::{Rosenbrock, System};

/// An input an importer moves linearly over a step (fmi2SetRealInputDerivatives):
/// (part, vr, value at the step's start, rate).
pub type Ramp = (usize, u32, f64, f64);

/// The line as one ODE and where it stands: its parts, joined by the network once
/// initialization has built it, the states at a time, and what the integrator keeps.
#[derive(Clone, Debug, PartialEq)]
pub struct Ode {
    pub parts: Vec<Part>,
    /// A copy of the parts to undo a failed step (kept, so a step allocates nothing).
    pub backup: Vec<Part>,
    /// Built when initialization ends (the parts' effects decide the states).
    pub net: Option<Network>,
    /// The line's states (`net.states`), and the time they are at.
    pub x: Vec<f64>,
    pub time: f64,
    /// The integrator's relative tolerance: the line's `tolerance`, or the importer's where smaller.
    pub rtol: f64,
    pub ramps: Vec<Ramp>,
    /// The parts' next event (a profile's breakpoint or set entry, a web change).
    pub next_event: f64,
    pub integrator: Option<Rosenbrock>,
    /// Scratch vectors of the line's size (Jacobians, undo), sized at initialization.
    pub scratch: Scratch,
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

impl Ode {
    /// The parts at their start values, not yet joined.
    pub fn new(parts: Vec<Part>, rtol: f64) -> Ode {
        Ode {
            backup: parts.clone(),
            parts,
            net: None,
            x: Vec::new(),
            time: 0.0,
            rtol,
            ramps: Vec::new(),
            next_event: f64::INFINITY,
            integrator: None,
            scratch: Scratch::default(),
        }
    }

    /// After initialization every change (time, states, an input) is
    /// evaluated at once, so that outputs and derivatives read later are
    /// those of the line as it now is.
    pub fn settle(&mut self) -> FmiResult {
        match self.net.as_mut() {
            Some(net) => net.evaluate(&mut self.parts, self.time, &self.x, None),
            None => Ok(()),
        }
    }

    /// The nominal size of the line's state k (its part's nominal; 1 where that is 0 or unknown).
    #[inline(always)]
    pub fn nominal(&self, net: &Network, k: usize) -> f64 {
        let s = net.states[k];
        let mut buffer = [0.0; crate::network::MAX_PART_STATES];
        let part = &self.parts[s.part];
        let m = part.state_count();
        if part.get_nominals(&mut buffer[..m]).is_ok() && buffer[s.index] != 0.0 {
            buffer[s.index].abs()
        } else {
            1.0
        }
    }
}

/// The line as one ODE for the integrator: inputs an importer ramps move
/// with time; the Jacobian chained from the parts' tangents, else by finite
/// differences over the band, a group of columns (kl + ku + 1 apart, so no
/// row sees two) per evaluation.
pub(crate) struct LineSystem<'a> {
    pub(crate) parts: &'a mut [Part],
    pub(crate) net: &'a mut Network,
    pub(crate) ramps: &'a [Ramp],
    pub(crate) t_start: f64,
    pub(crate) time_dependent: bool,
    pub(crate) f0: &'a mut [f64],
    pub(crate) f1: &'a mut [f64],
    pub(crate) y: &'a mut [f64],
    /// The parts are evaluated at the integrator's first point (`Network::evaluated_at`): its
    /// first f is their derivatives, no evaluation needed.
    pub(crate) evaluated: bool,
    /// The time of the last Jacobian (where `time_dependent` is asked).
    pub(crate) t_jacobian: f64,
    /// Difference the Jacobian even where the line has a chain (to check one against the other).
    pub(crate) differences: bool,
}

impl LineSystem<'_> {
    pub(crate) fn eval(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> FmiResult {
        for &(part, vr, base, rate) in self.ramps {
            self.parts[part].set_real(vr, base + rate * (t - self.t_start))?;
        }
        self.net.evaluate(self.parts, t, y, Some(dy))
    }
}

impl System for LineSystem<'_> {
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), ()> {
        if std::mem::take(&mut self.evaluated) && self.net.evaluated_at(t, y) {
            return self.net.derivatives(self.parts, dy).map_err(drop);
        }
        self.eval(t, y, dy).map_err(drop)
    }

    fn jacobian(&mut self, t: f64, y: &[f64], f0: &[f64], jac: &mut Band) -> Result<(), ()> {
        self.t_jacobian = t;
        if !self.differences && self.net.chain.is_some() {
            if !self.net.evaluated_at(t, y) {
                let f1 = std::mem::take(&mut self.f1);
                let r = self.eval(t, y, f1);
                self.f1 = f1;
                r.map_err(drop)?;
            }
            if self.net.chain.as_mut().is_some_and(|c| c.jacobian(self.parts, jac).is_ok()) {
                return Ok(());
            }
            // A partial outside the structure the chain was planned for: differences cover it.
            jac.clear();
        }
        let n = y.len();
        let width = jac.lower() + jac.upper() + 1;
        for group in 0..width.min(n) {
            self.y.copy_from_slice(y);
            let mut j = group;
            while j < n {
                // No derivative along a held state (`Network::held`): its column stays zero.
                if !self.net.held[j] {
                    self.y[j] += delta(y[j]);
                }
                j += width;
            }
            let (yp, f1) = (std::mem::take(&mut self.y), std::mem::take(&mut self.f1));
            let r = self.eval(t, yp, f1);
            self.y = yp;
            self.f1 = f1;
            r.map_err(drop)?;
            let mut j = group;
            while j < n {
                let d = self.y[j] - y[j];
                if !self.net.held[j] {
                    for i in j.saturating_sub(jac.upper())..(j + jac.lower() + 1).min(n) {
                        jac.set(i, j, (self.f1[i] - f0[i]) / d);
                    }
                }
                j += width;
            }
        }
        Ok(())
    }

    /// An interval between the line's events is one piece of every profile table (each
    /// breakpoint is an event), so f depends on t there only through ramped inputs and
    /// tables with a slope on that piece: with none, df/dt is zero and not formed.
    fn time_dependent(&self) -> bool {
        self.time_dependent
            && (!self.ramps.is_empty() || self.parts.iter().any(|p| p.varies_with_time(self.t_jacobian)))
    }
}

/// A forward-difference increment for a state of size |x| (exactly
/// representable: (x + d) - x == d).
fn delta(x: f64) -> f64 {
    let d = f64::EPSILON.sqrt() * x.abs().max(1e-3);
    (x + d) - x
}

/// The line's ODE x' = f(t, x) as the integrator sees it (inputs as set,
/// held), for tools that integrate the line themselves (bench/: other solvers).
pub fn rhs_at(ode: &mut Ode, t: f64, x: &[f64], dx: &mut [f64]) -> FmiResult {
    let Ode { parts, net, ramps, scratch, .. } = ode;
    let net = net.as_mut().ok_or_else(|| FmiError::error("the line is not initialized"))?;
    let Scratch { f0, f1, y, .. } = scratch;
    let mut sys = LineSystem { parts, net, ramps, t_start: t, time_dependent: true, f0, f1, y, evaluated: false, t_jacobian: t, differences: false };
    sys.eval(t, x, dx)
}

/// df/dx at (t, x), banded as the network says (kl, ku); `f0` is f(t, x) if known
/// (else one more evaluation). `differences`: by grouped differences even where the line
/// chains its parts' tangents.
pub fn jacobian_at(ode: &mut Ode, t: f64, x: &[f64], f0: Option<&[f64]>, jac: &mut Band, differences: bool) -> FmiResult {
    let Ode { parts, net, ramps, scratch, .. } = ode;
    let net = net.as_mut().ok_or_else(|| FmiError::error("the line is not initialized"))?;
    let Scratch { f0: own, f1, y, .. } = scratch;
    let mut sys = LineSystem { parts, net, ramps, t_start: t, time_dependent: true, f0: &mut [], f1, y, evaluated: false, t_jacobian: t, differences };
    let f0 = match f0 {
        Some(f0) => f0,
        None => {
            sys.eval(t, x, own)?;
            &own[..]
        }
    };
    jac.clear();
    sys.jacobian(t, x, f0, jac).map_err(|()| FmiError::error("the line cannot be evaluated there"))
}

/// For `equilibrium`: f(t, x) and its Jacobian through the same evaluation the integrator uses.
pub fn residual_and_jacobian(ode: &mut Ode, x: &[f64], f: &mut [f64], jac: Option<&mut Band>) -> FmiResult {
    let t = ode.time;
    let Ode { parts, net, ramps, scratch, .. } = ode;
    let net = net.as_mut().expect("initialized");
    let Scratch { f0, f1, y, .. } = scratch;
    let mut sys = LineSystem { parts, net, ramps, t_start: t, time_dependent: false, f0, f1, y, evaluated: false, t_jacobian: t, differences: false };
    sys.eval(t, x, f)?;
    if let Some(jac) = jac {
        jac.clear();
        sys.jacobian(t, x, f, jac).map_err(|()| FmiError::error("the line cannot be evaluated near its start state"))?;
    }
    Ok(())
}
