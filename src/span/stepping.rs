//! One communication step of the span: which method integrates the balance
//! [2], and the balance written for the integrators.
//!
//! `auto` takes the exact step [3] whenever the inputs are held over the
//! step (then L is constant too, even with moving rollers, because the
//! positions are held); with input derivatives it takes Rosenbrock 2(3).

use super::parameters::{Inputs, Parameters, SolverChoice};
use super::physics;
use crate::fmi2::{FmiError, FmiResult};
use crate::solver::fixed::{self, Method};
use crate::solver::{dopri5, rosenbrock, CompensatedSum, Control, Failure, Ode};

/// The most steps an adaptive method may take in one communication step
/// before the step is discarded: bounded work, never a hang.
pub const MAX_STEPS: usize = 100_000;

/// Floor of the error scale, as a strain: where the strain passes through
/// zero, errors are measured against 1e-6 of strain rather than against 0.
const STRAIN_SCALE_FLOOR: f64 = 1e-6;

/// The balance over one communication step for the integrators, in the
/// offset y = x - x0 from the state at the start of the step, so that the
/// integrators work on the small quantity that carries the strain.
pub struct Balance<'a> {
    pub params: &'a Parameters,
    pub start: Inputs,
    /// Input rates over the step; all zero when the inputs are held.
    pub rates: Inputs,
    pub moving: bool,
    pub x0: CompensatedSum,
    pub step: f64,
}

impl Balance<'_> {
    fn inputs_at(&self, t: f64) -> Inputs {
        if self.moving {
            self.start.advanced(&self.rates, t)
        } else {
            self.start
        }
    }
}

impl Ode<1> for Balance<'_> {
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
        if !self.moving {
            return [0.0];
        }
        // Central difference: the inputs are linear in t, the balance smooth
        // in them except where a speed changes sign.
        let dt = 1e-6 * self.step;
        [(self.rhs(t + dt, y)[0] - self.rhs(t - dt, y)[0]) / (2.0 * dt)]
    }
}

/// The method a step uses, with the reason an explicit choice cannot work.
pub fn method(choice: SolverChoice, moving: bool) -> Result<SolverChoice, String> {
    match choice {
        SolverChoice::Auto if moving => Ok(SolverChoice::Rosenbrock),
        SolverChoice::Auto => Ok(SolverChoice::Exact),
        SolverChoice::Exact if moving => Err(
            "solver = exact holds the inputs over a step, but input derivatives were given \
             (inputs that move within the step): choose solver = auto or rosenbrock"
                .into(),
        ),
        other => Ok(other),
    }
}

/// The shortest span length over the step, for linearly moving rollers:
/// |d0 + d' t| is smallest where t = -(d0 . d')/|d'|^2, clipped to [0, h].
pub fn shortest_length(p: &Parameters, start: &Inputs, rates: &Inputs, h: f64) -> f64 {
    let end = physics::span_length(p, &start.advanced(rates, h));
    let now = physics::span_length(p, start);
    if !p.variable_length {
        return now;
    }
    let [dx, dy] = start.span_vector();
    let [rx, ry] = rates.span_vector();
    let speed2 = rx * rx + ry * ry;
    let t = if speed2 > 0.0 { (-(dx * rx + dy * ry) / speed2).clamp(0.0, h) } else { 0.0 };
    let inside = (dx + rx * t).hypot(dy + ry * t);
    now.min(end).min(inside)
}

/// Integrates the balance over h with the chosen method; the state at the
/// end of the step, and the step size an adaptive method proposes next.
pub fn integrate(
    balance: &Balance,
    choice: SolverChoice,
    tolerance: f64,
    substeps: i32,
    adaptive_step: f64,
) -> FmiResult<(CompensatedSum, f64)> {
    let h = balance.step;
    let p = balance.params;
    let length = physics::span_length(p, &balance.start);
    let explicit = |method: Method| -> FmiResult<(CompensatedSum, f64)> {
        let n = substeps.max(1) as usize;
        let lambda = largest_decay_rate(balance);
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
        let y = fixed::integrate(&method, balance, h, [0.0], n).map_err(|f| failure(choice, f))?;
        Ok((balance.x0.plus(y[0]), adaptive_step))
    };
    match choice {
        SolverChoice::Exact | SolverChoice::Auto => Ok((physics::exact_step(length, &balance.start, balance.x0, h), adaptive_step)),
        SolverChoice::Rk4 => explicit(Method::Rk4),
        SolverChoice::Euler => explicit(Method::Euler),
        SolverChoice::Rosenbrock | SolverChoice::Dopri5 => {
            // Absolute tolerance on x so that the *strain* is accurate to
            // `tolerance` relative: an error dx in x is dx/L of strain.
            let scale = (length - balance.x0.value()).abs().max(STRAIN_SCALE_FLOOR * length);
            let control = Control {
                rtol: tolerance,
                atol: [tolerance * scale],
                initial_step: if adaptive_step > 0.0 { adaptive_step } else { h },
                max_steps: MAX_STEPS,
            };
            let solved = if choice == SolverChoice::Rosenbrock {
                rosenbrock::integrate(balance, h, [0.0], &control)
            } else {
                dopri5::integrate(balance, h, [0.0], &control)
            }
            .map_err(|f| failure(choice, f))?;
            Ok((balance.x0.plus(solved.y[0]), solved.next_step))
        }
    }
}

/// An upper bound of lambda = (v_b - min(v_a, 0)) / L over the step: with
/// linear inputs the numerator is convex and piecewise linear, so largest
/// at an end; L is smallest where `shortest_length` says, possibly inside
/// the step (a moving roller passing closest).
fn largest_decay_rate(balance: &Balance) -> f64 {
    let numerator = |u: &Inputs| u.speed_b - u.speed_a.min(0.0);
    let end = balance.inputs_at(balance.step);
    let largest = numerator(&balance.start).max(numerator(&end));
    largest / shortest_length(balance.params, &balance.start, &balance.rates, balance.step)
}

fn failure(choice: SolverChoice, f: Failure) -> FmiError {
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
