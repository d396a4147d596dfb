//! Banded Rosenbrock methods with error control, for systems whose size is
//! known only at run time (a line read from its FMU's resources): every
//! buffer is allocated when the integrator is made, none in a step. A step
//! solves a few linear systems with one matrix and needs no Newton
//! iterations, so its cost is known in advance; L-stable methods damp a stiff
//! mode (a web's damping time, a light roller on a stiff span) at any step.
//!
//! Two methods ([`tableau`]): RODAS4 forms the Jacobian at every step, as its
//! order needs; ROS34PW2, a W-method, keeps its order with any matrix, so the
//! Jacobian and its LU are kept over steps and calls and renewed only when a
//! step fails with them, they grow old, or the caller says the system changed.

pub mod tableau;
#[cfg(test)]
mod tests;

use super::band::{Band, BandLu};
use super::ode::Failure;
use tableau::{Tableau, MAX_STAGES};

/// What the integrator asks of the system it integrates.
pub trait System {
    /// dy = f(t, y). `Err` when y is no state the system can take (an
    /// integrator's trial value): the step is retried shorter.
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), ()>;

    /// df/dy at (t, y), where f is `f0`, written into `jac` (cleared, its band as made).
    fn jacobian(&mut self, t: f64, y: &[f64], f0: &[f64], jac: &mut Band) -> Result<(), ()>;

    /// Whether f depends on t at fixed y (profiles, ramped inputs): then
    /// df/dt enters the stages, by a forward difference.
    fn time_dependent(&self) -> bool;
}

/// Error control and the bound on work of one call.
#[derive(Clone, Copy, Debug)]
pub struct Control<'a> {
    pub rtol: f64,
    pub atol: &'a [f64],
    /// Per state, a factor on `rtol` (a state whose meaningful part is a
    /// small difference from a large value: a span's unstretched length, whose
    /// strain is what tension is made of); empty: 1 for all.
    pub rtol_scale: &'a [f64],
    /// Most step attempts in one call.
    pub max_steps: usize,
    /// Largest step (0: none).
    pub max_step: f64,
}

/// Work done, summed over calls.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    pub accepted: usize,
    pub rejected: usize,
    pub rhs: usize,
    pub jacobians: usize,
    pub factorizations: usize,
}

/// A W-method renews a Jacobian this many accepted steps old, so that it never
/// drifts far from the system's (its stability is that of the matrix it uses).
pub const MAX_JACOBIAN_AGE: usize = 50;

/// The LU of (1/(h gamma) I - W) is kept for a step within this relative
/// distance of the one it was made for: the method then runs with W + delta I,
/// delta h gamma below this, which a W-method allows (communication steps
/// that differ by rounding share one LU).
const SAME_STEP: f64 = 1e-6;

/// The steps to the end of an interval may together be this fraction of a
/// proposed step longer than the proposals (which carry a safety factor of
/// 0.9 on the error): an interval of 1.05 steps takes one, not two.
const SLACK: f64 = 0.1;

#[derive(Clone, Debug, PartialEq)]
pub struct Rosenbrock {
    method: &'static Tableau,
    n: usize,
    jac: Band,
    lu: BandLu,
    k: [Vec<f64>; MAX_STAGES],
    stage: Vec<f64>,
    y_now: Vec<f64>,
    f: Vec<f64>,
    f0: Vec<f64>,
    ft: Vec<f64>,
    /// `jac` and `ft` hold a Jacobian the method may use (a W-method's, from an earlier step).
    jacobian_kept: bool,
    /// Accepted steps since `jac` was formed.
    jacobian_age: usize,
    /// The step the LU was made for (0: none).
    lu_step: f64,
    /// The step to try next, kept between calls (0: not known yet).
    pub next_step: f64,
    pub stats: Stats,
}

impl Rosenbrock {
    /// An integrator for n states whose Jacobian has `kl` sub- and `ku`
    /// super-diagonals.
    pub fn new(method: &'static Tableau, n: usize, kl: usize, ku: usize) -> Rosenbrock {
        let v = || vec![0.0; n];
        Rosenbrock {
            method,
            n,
            jac: Band::zeros(n, kl, ku),
            lu: BandLu::new(n, kl, ku),
            k: std::array::from_fn(|_| v()),
            stage: v(),
            y_now: v(),
            f: v(),
            f0: v(),
            ft: v(),
            jacobian_kept: false,
            jacobian_age: 0,
            lu_step: 0.0,
            next_step: 0.0,
            stats: Stats::default(),
        }
    }

    pub fn method(&self) -> &'static Tableau {
        self.method
    }

    pub fn len(&self) -> usize {
        self.n
    }

    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The system changed (an event, new parameters): the next step forms a new Jacobian.
    pub fn renew_jacobian(&mut self) {
        self.jacobian_kept = false;
        self.lu_step = 0.0;
    }

    /// The Jacobian kept for the next step, and its age (an FMU state holds them).
    pub fn kept_jacobian(&self) -> Option<(&Band, &[f64], usize)> {
        (self.jacobian_kept && self.method.w_method).then_some((&self.jac, &self.ft[..], self.jacobian_age))
    }

    /// Restores a kept Jacobian (as `kept_jacobian` gave it); the LU follows when needed.
    pub fn keep_jacobian(&mut self, jac: &Band, ft: &[f64], age: usize) {
        self.jac.clone_from(jac);
        self.ft.copy_from_slice(ft);
        self.jacobian_age = age;
        self.jacobian_kept = self.method.w_method;
        self.lu_step = 0.0;
    }

    /// Integrates y from t0 to t1 in place. On failure y is unchanged.
    pub fn integrate<S: System>(&mut self, sys: &mut S, t0: f64, t1: f64, y: &mut [f64], c: &Control) -> Result<(), Failure> {
        debug_assert_eq!(y.len(), self.n);
        let span = t1 - t0;
        if !(span > 0.0) {
            return Ok(());
        }
        // The solution so far: y stays intact until the call succeeds.
        let mut y_now = std::mem::take(&mut self.y_now);
        y_now.copy_from_slice(y);
        let result = self.run(sys, t0, t1, &mut y_now, c);
        if result.is_ok() {
            y.copy_from_slice(&y_now);
        }
        self.y_now = y_now;
        result
    }

    fn run<S: System>(&mut self, sys: &mut S, t0: f64, t1: f64, y: &mut [f64], c: &Control) -> Result<(), Failure> {
        let w_method = self.method.w_method;
        let mut t = t0;
        let mut h = if self.next_step > 0.0 { self.next_step } else { initial_step(t1 - t0) };
        if c.max_step > 0.0 {
            h = h.min(c.max_step);
        }
        let mut attempts = 0;
        // f0 holds f(t, y) (after a rejected step: the same point).
        let mut have_f0 = false;
        // The Jacobian was formed at (t, y): a rejection cannot be its fault.
        let mut fresh = false;
        // Scratch for f at the stages (taken out of self for the borrow; no allocation).
        let mut f = std::mem::take(&mut self.f);
        let result = loop {
            if t >= t1 {
                break Ok(());
            }
            if attempts >= c.max_steps {
                break Err(Failure::TooMuchWork { reached: t, steps: attempts });
            }
            attempts += 1;
            // Equal steps to the end, each about the proposal: they end exactly there and share one LU.
            let remaining = t1 - t;
            let pieces = (remaining / h - SLACK).ceil().max(1.0);
            let last = pieces <= 1.0 || remaining <= 4.0 * f64::EPSILON * t1.abs().max(1.0);
            let h_try = if last { remaining } else { remaining / pieces };
            if h_try <= 16.0 * f64::EPSILON * t.abs().max(t1.abs()) && !last {
                break Err(Failure::StepTooSmall { reached: t, step: h_try });
            }
            if !have_f0 {
                if sys.rhs(t, y, &mut self.f0).is_err() {
                    break Err(Failure::NotFinite { reached: t });
                }
                self.stats.rhs += 1;
                have_f0 = true;
            }
            let renew = !w_method || !self.jacobian_kept || self.jacobian_age >= MAX_JACOBIAN_AGE;
            if renew && !fresh {
                if self.form_jacobian(sys, t, y, h_try).is_err() {
                    break Err(Failure::NotFinite { reached: t });
                }
                fresh = true;
            }
            // None: the matrix is singular, or a stage left the states the system can take.
            let outcome = if self.factor(h_try) { self.try_step(sys, t, y, h_try, &mut f, c) } else { None };
            match outcome {
                Some(norm) if norm <= 1.0 => {
                    y.copy_from_slice(&self.stage);
                    t = if last { t1 } else { t + h_try };
                    self.stats.accepted += 1;
                    self.jacobian_age += 1;
                    have_f0 = false;
                    fresh = false;
                    let proposal = h_try * self.step_factor(norm);
                    // A step shortened to end the interval says nothing against the longer one.
                    h = if h_try < h { h.max(proposal) } else { proposal };
                }
                rejected => {
                    self.stats.rejected += 1;
                    h = match rejected {
                        Some(norm) => h_try * self.step_factor(norm).min(0.9),
                        None => 0.2 * h_try,
                    };
                    // A W-method's old Jacobian may be why: the retry forms one here.
                    if !fresh {
                        self.jacobian_kept = false;
                    }
                }
            }
            if c.max_step > 0.0 {
                h = h.min(c.max_step);
            }
        };
        self.f = f;
        if result.is_ok() {
            self.next_step = h;
        }
        result
    }

    /// The LU of (1/(h gamma) I - W) for a step h (kept if made for about h); false if singular.
    fn factor(&mut self, h: f64) -> bool {
        if (h - self.lu_step).abs() <= SAME_STEP * h {
            return true;
        }
        self.lu_step = 0.0;
        if !self.lu.factor_shifted(1.0 / (h * self.method.gamma), &self.jac) {
            return false;
        }
        self.stats.factorizations += 1;
        self.lu_step = h;
        true
    }

    /// J and df/dt at (t, y), f0 = f(t, y) given; the LU must follow.
    fn form_jacobian<S: System>(&mut self, sys: &mut S, t: f64, y: &[f64], h: f64) -> Result<(), ()> {
        self.jac.clear();
        self.lu_step = 0.0;
        self.jacobian_kept = false;
        sys.jacobian(t, y, &self.f0, &mut self.jac)?;
        self.stats.jacobians += 1;
        if sys.time_dependent() {
            let dt = f64::EPSILON.sqrt() * t.abs().max(h);
            sys.rhs(t + dt, y, &mut self.ft)?;
            self.stats.rhs += 1;
            for (ft, f0) in self.ft.iter_mut().zip(&self.f0) {
                *ft = (*ft - f0) / dt;
            }
        } else {
            self.ft.fill(0.0);
        }
        self.jacobian_kept = true;
        self.jacobian_age = 0;
        Ok(())
    }

    /// One attempt with the LU made: the new solution in self.stage, and the
    /// error norm (None: a stage left the states the system can take).
    fn try_step<S: System>(&mut self, sys: &mut S, t: f64, y: &[f64], h: f64, f: &mut [f64], c: &Control) -> Option<f64> {
        let (n, m) = (self.n, self.method);
        let stage = &mut self.stage;
        // Every sum below runs over the earlier stages in order, a vector at a time.
        for i in 0..m.stages {
            let (done, rest) = self.k.split_at_mut(i);
            let ki = &mut rest[0];
            let (a, cc) = (&m.a[i], &m.c[i]);
            // Stage 1 is f at (t, y) itself.
            let fi: &[f64] = if i == 0 {
                &self.f0
            } else {
                stage.copy_from_slice(y);
                for (&aj, kj) in a.iter().zip(done.iter()) {
                    for (s, k) in stage.iter_mut().zip(kj) {
                        *s += aj * k;
                    }
                }
                sys.rhs(t + m.alpha[i] * h, stage, f).ok()?;
                self.stats.rhs += 1;
                f
            };
            let dh = m.d[i] * h;
            ki.fill(0.0);
            for (&cj, kj) in cc.iter().zip(done.iter()) {
                for (s, k) in ki.iter_mut().zip(kj) {
                    *s += cj * k;
                }
            }
            for ((x, fr), ft) in ki.iter_mut().zip(fi).zip(&self.ft) {
                *x = fr + dh * ft + *x / h;
            }
            self.lu.solve(ki);
        }
        // The new solution in stage, the error estimate in f.
        stage.copy_from_slice(y);
        f.fill(0.0);
        for ((&mj, &ej), kj) in m.m.iter().zip(&m.e).zip(&self.k[..m.stages]) {
            for ((s, e), k) in stage.iter_mut().zip(f.iter_mut()).zip(kj) {
                *s += mj * k;
                *e += ej * k;
            }
        }
        let mut sum = 0.0;
        for r in 0..n {
            let rtol = c.rtol * c.rtol_scale.get(r).copied().unwrap_or(1.0);
            let scale = c.atol[r] + rtol * y[r].abs().max(stage[r].abs());
            sum += (f[r] / scale).powi(2);
        }
        let norm = (sum / n.max(1) as f64).sqrt();
        (norm.is_finite() && stage.iter().all(|x| x.is_finite())).then_some(norm)
    }

    /// Step-size factor for an error norm (safety 0.9, growth at most 6,
    /// shrink at most 5, as rodas.f).
    fn step_factor(&self, norm: f64) -> f64 {
        if norm == 0.0 {
            6.0
        } else {
            (0.9 * libm::pow(norm, -1.0 / self.method.estimate_order)).clamp(0.2, 6.0)
        }
    }
}

/// The first step of a fresh integrator: a tenth of the interval.
fn initial_step(span: f64) -> f64 {
    0.1 * span
}
