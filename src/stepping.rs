//! One communication step of the span: which method integrates the balance
//! [E2], and the balance written for the integrators.
//!
//! `auto` takes the exact step [E3] whenever the inputs are held over the
//! step (then L is constant too, even with moving rollers, because the
//! positions are held); with input derivatives it takes Rosenbrock 2(3).

use crate::description::Solver;
use crate::parameters::{Inputs, Parameters};
use crate::physics;
use fmi_core::{FmiError, FmiResult};
use solver::fixed::{self, Method};
use solver::{dopri5, rosenbrock, CompensatedSum, Control, Failure, Ode};

/// The most steps an adaptive method may take in one communication step
/// before the step is discarded: bounded work, never a hang.
pub const MAX_STEPS: usize = 100_000;

/// Floor of the error scale, as a strain: where the strain passes through
/// zero, errors are measured against 1e-6 of strain rather than against 0.
const STRAIN_SCALE_FLOOR: f64 = 1e-6;

/// One communication step of the balance, in the offset y = x - x0 from
/// the state at its start, so that the integrators work on the small
/// quantity that carries the strain.
pub struct Step<'a> {
    pub params: &'a Parameters,
    pub start: &'a Inputs,
    /// Input rates over the step; `None` when the inputs are held.
    pub rates: Option<&'a Inputs>,
    pub x0: CompensatedSum,
    pub h: f64,
}

impl Step<'_> {
    fn inputs_at(&self, t: f64) -> Inputs {
        match self.rates {
            Some(r) => self.start.advanced(r, t),
            None => *self.start,
        }
    }

    /// The state at the end of the step, and the step size an adaptive
    /// method proposes next (`adaptive_step` passed on by the others).
    #[inline]
    pub fn integrate(&self, solver: Solver, tolerance: f64, adaptive_step: f64) -> FmiResult<(CompensatedSum, f64)> {
        let choice = method(solver, self.rates.is_some())?;
        let length = physics::span_length(self.params, self.start);
        if choice == Solver::Exact && length > 0.0 {
            // Held inputs: L is constant too, even with moving rollers,
            // because their positions are held.
            return Ok((physics::exact_step(length, self.start, self.x0, self.h), adaptive_step));
        }
        self.integrate_numerically(choice, tolerance, adaptive_step)
    }

    /// The methods other than the exact step (and a span length that
    /// reaches zero, which `check_length` reports).
    #[inline(never)]
    fn integrate_numerically(&self, choice: Solver, tolerance: f64, adaptive_step: f64) -> FmiResult<(CompensatedSum, f64)> {
        check_length(self.shortest_length())?;
        let h = self.h;
        let length = physics::span_length(self.params, self.start);
        let explicit = |method: Method| -> FmiResult<(CompensatedSum, f64)> {
            let n = self.params.substeps.max(1) as usize;
            let lambda = self.largest_decay_rate();
            let limit = method.stability_limit();
            if lambda * h / n as f64 > limit {
                let needed = (lambda * h / limit).ceil();
                return Err(FmiError::discard(format!(
                    "{} with substeps = {n} is unstable here: lambda*h/substeps = {:.3e} exceeds {limit} \
                     (span time constant {:.3e} s); use substeps >= {needed} or solver = auto, exact or rosenbrock",
                    choice.name(),
                    lambda * h / n as f64,
                    1.0 / lambda
                )));
            }
            let y = fixed::integrate(&method, self, h, [0.0], n).map_err(|f| failure(choice, f))?;
            Ok((self.x0.plus(y[0]), adaptive_step))
        };
        match choice {
            Solver::Rk4 => explicit(Method::Rk4),
            Solver::Euler => explicit(Method::Euler),
            _ => {
                // Absolute tolerance on x so that the *strain* is accurate to
                // `tolerance` relative: an error dx in x is dx/L of strain.
                let scale = (length - self.x0.value()).abs().max(STRAIN_SCALE_FLOOR * length);
                let control = Control {
                    rtol: tolerance,
                    atol: [tolerance * scale],
                    initial_step: if adaptive_step > 0.0 { adaptive_step } else { h },
                    max_steps: MAX_STEPS,
                };
                let solved = if choice == Solver::Rosenbrock {
                    rosenbrock::integrate(self, h, [0.0], &control)
                } else {
                    dopri5::integrate(self, h, [0.0], &control)
                }
                .map_err(|f| failure(choice, f))?;
                Ok((self.x0.plus(solved.y[0]), solved.next_step))
            }
        }
    }

    /// The shortest span length over the step, for linearly moving rollers:
    /// |d0 + d' t| is smallest where t = -(d0 . d')/|d'|^2, clipped to [0, h].
    pub fn shortest_length(&self) -> f64 {
        let p = self.params;
        let now = physics::span_length(p, self.start);
        let Some(rates) = self.rates.filter(|_| p.effects.variable_length) else { return now };
        let end = physics::span_length(p, &self.start.advanced(rates, self.h));
        let [dx, dy] = self.start.span_vector();
        let [rx, ry] = rates.span_vector();
        let speed2 = rx * rx + ry * ry;
        let t = if speed2 > 0.0 { (-(dx * rx + dy * ry) / speed2).clamp(0.0, self.h) } else { 0.0 };
        let inside = (dx + rx * t).hypot(dy + ry * t);
        now.min(end).min(inside)
    }

    /// An upper bound of lambda = (v_b - min(v_a, 0)) / L over the step: with
    /// linear inputs the numerator is convex and piecewise linear, so largest
    /// at an end; L is smallest where `shortest_length` says, possibly inside
    /// the step (a moving roller passing closest).
    fn largest_decay_rate(&self) -> f64 {
        let numerator = |u: &Inputs| u.speed_b - u.speed_a.min(0.0);
        let largest = numerator(self.start).max(numerator(&self.inputs_at(self.h)));
        largest / self.shortest_length()
    }
}

impl Ode<1> for Step<'_> {
    fn rhs(&self, t: f64, y: &[f64; 1]) -> [f64; 1] {
        let u = self.inputs_at(t);
        let length = physics::span_length(self.params, &u);
        [physics::unstretched_rate(&u, physics::strain(length, self.x0, y[0]))]
    }

    fn jacobian(&self, t: f64, _y: &[f64; 1]) -> [[f64; 1]; 1] {
        let u = self.inputs_at(t);
        [[-physics::decay_rate(physics::span_length(self.params, &u), &u)]]
    }

    fn time_derivative(&self, t: f64, y: &[f64; 1]) -> [f64; 1] {
        if self.rates.is_none() {
            return [0.0];
        }
        // Central difference: the inputs are linear in t, the balance smooth
        // in them except where a speed changes sign.
        let dt = 1e-6 * self.h;
        [(self.rhs(t + dt, y)[0] - self.rhs(t - dt, y)[0]) / (2.0 * dt)]
    }
}

/// The method a step uses: `auto` is exact for held inputs and Rosenbrock
/// for moving ones; `exact` cannot follow inputs that move within the step.
pub fn method(solver: Solver, moving: bool) -> FmiResult<Solver> {
    match solver {
        Solver::Auto if moving => Ok(Solver::Rosenbrock),
        Solver::Auto => Ok(Solver::Exact),
        Solver::Exact if moving => Err(FmiError::error(
            "solver = exact holds the inputs over a step, but input derivatives were given \
             (inputs that move within the step): choose solver = auto or rosenbrock",
        )),
        other => Ok(other),
    }
}

fn check_length(length: f64) -> FmiResult {
    if length > 0.0 {
        Ok(())
    } else {
        Err(FmiError::error(format!(
            "the span length |frame_b - frame_a| reaches {length} m within the step: the rollers meet"
        )))
    }
}

fn failure(choice: Solver, f: Failure) -> FmiError {
    let name = choice.name();
    FmiError::discard(match f {
        Failure::TooMuchWork { reached, steps } => format!(
            "{name} could not meet its tolerance within {steps} steps (reached {reached} s into the step); \
             retry with a shorter communication step or solver = auto, exact or rosenbrock"
        ),
        Failure::StepTooSmall { reached, step } => {
            format!("{name}: the step size fell to {step:.3e} s at {reached} s into the step")
        }
        Failure::NotFinite { reached } => {
            format!("{name}: the solution stopped being finite {reached} s into the step")
        }
    })
}
