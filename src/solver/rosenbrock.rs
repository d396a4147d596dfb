//! Rosenbrock 2(3), the L-stable method of MATLAB's ode23s (Shampine &
//! Reichelt, "The MATLAB ODE Suite", 1997): second order, with a third-order
//! error estimate, one Jacobian and one linear solve per step. L-stability
//! means a stiff span (time constant far below the step) is damped, never
//! amplified, whatever the step.

use super::linalg::solve;
use super::ode::{all_finite, axpy, error_norm, step_factor, too_small, Control, Failure, Ode, Solution};

const D: f64 = 0.292_893_218_813_452_5; // 1/(2 + sqrt 2)
const E32: f64 = 7.414_213_562_373_095; // 6 + sqrt 2

pub fn integrate<const N: usize>(ode: &impl Ode<N>, t_end: f64, y0: [f64; N], c: &Control<N>) -> Result<Solution<N>, Failure> {
    let mut t = 0.0;
    let mut y = y0;
    let mut h = c.initial_step.min(t_end);
    let (mut accepted, mut rejected) = (0, 0);
    let mut f0 = ode.rhs(t, &y);
    while t < t_end {
        if accepted + rejected >= c.max_steps {
            return Err(Failure::TooMuchWork { reached: t, steps: accepted + rejected });
        }
        let last = t + h >= t_end * (1.0 - 4.0 * f64::EPSILON);
        let h_try = if last { t_end - t } else { h };
        if too_small(t, h_try, t_end) && !last {
            return Err(Failure::StepTooSmall { reached: t, step: h_try });
        }
        let jac = ode.jacobian(t, &y);
        let dfdt = ode.time_derivative(t, &y);
        // W = I - h d J
        let mut w = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                w[i][j] = if i == j { 1.0 } else { 0.0 } - h_try * D * jac[i][j];
            }
        }
        let stage = |rhs: [f64; N]| solve(w, rhs).ok_or(Failure::NotFinite { reached: t });
        let k1 = stage(axpy(h_try * D, &dfdt, &f0))?;
        let f1 = ode.rhs(t + 0.5 * h_try, &axpy(0.5 * h_try, &k1, &y));
        let mut k2 = stage(axpy(-1.0, &k1, &f1))?;
        k2 = axpy(1.0, &k1, &k2);
        let y_new = axpy(h_try, &k2, &y);
        let f2 = ode.rhs(t + h_try, &y_new);
        let mut r3 = [0.0; N];
        for i in 0..N {
            r3[i] = f2[i] - E32 * (k2[i] - f1[i]) - 2.0 * (k1[i] - f0[i]) + h_try * D * dfdt[i];
        }
        let k3 = stage(r3)?;
        let mut err = [0.0; N];
        for i in 0..N {
            err[i] = h_try / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]);
        }
        let norm = error_norm(&err, &y, &y_new, c);
        if !(all_finite(&y_new) && norm.is_finite()) {
            rejected += 1;
            h = 0.2 * h_try;
            continue;
        }
        if norm <= 1.0 {
            t = if last { t_end } else { t + h_try };
            y = y_new;
            f0 = f2;
            accepted += 1;
            // A clipped last step says nothing about larger steps: keep h then.
            if !(last && h_try < h) {
                h = h_try * step_factor(norm, 3.0);
            }
        } else {
            rejected += 1;
            h = h_try * step_factor(norm, 3.0).min(0.9);
        }
    }
    Ok(Solution { y, accepted, rejected, next_step: h })
}
