//! The interface between a model's equations and the integrators: a system
//! of N ODEs on fixed-size arrays (no heap in a step), plus what an
//! adaptive method needs and reports.

/// `dy/dt = f(t, y)` on `[0, t_end]` of one communication step.
pub trait Ode<const N: usize> {
    fn rhs(&self, t: f64, y: &[f64; N]) -> [f64; N];

    /// `df/dy`; Rosenbrock methods need it exactly for their order.
    fn jacobian(&self, t: f64, y: &[f64; N]) -> [[f64; N]; N];

    /// `df/dt` at fixed y; zero for autonomous systems (held inputs).
    fn time_derivative(&self, t: f64, y: &[f64; N]) -> [f64; N];
}

/// Error control and work limits of the adaptive methods.
#[derive(Clone, Copy, Debug)]
pub struct Control<const N: usize> {
    /// Relative tolerance.
    pub rtol: f64,
    /// Absolute tolerance per component.
    pub atol: [f64; N],
    /// Step to try first (the last accepted one of the previous call).
    pub initial_step: f64,
    /// Most steps (accepted and rejected) allowed in one call.
    pub max_steps: usize,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Solution<const N: usize> {
    pub y: [f64; N],
    pub accepted: usize,
    pub rejected: usize,
    /// Step size to start the next call with.
    pub next_step: f64,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Failure {
    /// More than `max_steps` would be needed; `reached` is where it stopped.
    TooMuchWork { reached: f64, steps: usize },
    /// The step size fell below what the time resolution can represent.
    StepTooSmall { reached: f64, step: f64 },
    /// The solution stopped being finite (an explicit method out of its
    /// stability region, or a solution that really blows up).
    NotFinite { reached: f64 },
}

/// One adaptive method: a trial step and what it keeps when the step is
/// accepted (e.g. the derivative at the new point, first same as last).
pub trait Stepper<const N: usize> {
    /// Order of the error estimate, for the step-size controller.
    const ESTIMATE_ORDER: f64;

    /// Attempts a step of size h from (t, y): the new solution and the
    /// error estimate.
    fn try_step(&mut self, t: f64, y: &[f64; N], h: f64) -> Result<([f64; N], [f64; N]), Failure>;

    /// The step to (t + h, y_new) was accepted.
    fn accept(&mut self);
}

/// The adaptive loop shared by the methods: error control, step-size
/// control (kept between calls), the last step clipped to `t_end`, and a
/// bound on the work.
pub fn drive<S: Stepper<N>, const N: usize>(stepper: &mut S, t_end: f64, y0: [f64; N], c: &Control<N>) -> Result<Solution<N>, Failure> {
    let q = S::ESTIMATE_ORDER;
    let mut t = 0.0;
    let mut y = y0;
    let mut h = c.initial_step.min(t_end);
    let (mut accepted, mut rejected) = (0, 0);
    while t < t_end {
        if accepted + rejected >= c.max_steps {
            return Err(Failure::TooMuchWork { reached: t, steps: accepted + rejected });
        }
        let last = t + h >= t_end * (1.0 - 4.0 * f64::EPSILON);
        let h_try = if last { t_end - t } else { h };
        if too_small(t, h_try, t_end) && !last {
            return Err(Failure::StepTooSmall { reached: t, step: h_try });
        }
        let (y_new, err) = stepper.try_step(t, &y, h_try)?;
        let norm = error_norm(&err, &y, &y_new, c);
        if !(all_finite(&y_new) && norm.is_finite()) {
            rejected += 1;
            h = 0.2 * h_try;
            continue;
        }
        if norm <= 1.0 {
            t = if last { t_end } else { t + h_try };
            y = y_new;
            stepper.accept();
            accepted += 1;
            // A clipped last step says nothing about larger steps: keep h then.
            if !(last && h_try < h) {
                h = h_try * step_factor(norm, q);
            }
        } else {
            rejected += 1;
            h = h_try * step_factor(norm, q).min(0.9);
        }
    }
    Ok(Solution { y, accepted, rejected, next_step: h })
}

/// Weighted RMS norm of an error estimate (Hairer–Wanner II, IV.8).
fn error_norm<const N: usize>(err: &[f64; N], y0: &[f64; N], y1: &[f64; N], c: &Control<N>) -> f64 {
    let mut sum = 0.0;
    for i in 0..N {
        let scale = c.atol[i] + c.rtol * y0[i].abs().max(y1[i].abs());
        sum += (err[i] / scale).powi(2);
    }
    (sum / N as f64).sqrt()
}

pub(crate) fn axpy<const N: usize>(a: f64, x: &[f64; N], y: &[f64; N]) -> [f64; N] {
    let mut out = *y;
    for i in 0..N {
        out[i] += a * x[i];
    }
    out
}

pub(crate) fn all_finite<const N: usize>(y: &[f64; N]) -> bool {
    y.iter().all(|v| v.is_finite())
}

/// Step-size factor from an error norm for a method whose error estimate
/// has order `q` (safety 0.9, growth limited to 5, shrink to 0.2).
fn step_factor(norm: f64, q: f64) -> f64 {
    if norm == 0.0 {
        5.0
    } else {
        // libm's pow: the same step sizes on every platform (linear.rs)
        (0.9 * libm::pow(norm, -1.0 / q)).clamp(0.2, 5.0)
    }
}

/// Time resolution: a step below this cannot advance t.
fn too_small(t: f64, h: f64, t_end: f64) -> bool {
    h <= 16.0 * f64::EPSILON * t.abs().max(t_end.abs())
}
