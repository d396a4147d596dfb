//! Dormand–Prince 5(4) (Hairer, Nørsett & Wanner I, II.5): explicit,
//! fifth order with an embedded fourth-order error estimate, first same as
//! last. On a stiff span its step shrinks to the stability limit (about
//! 3.3/lambda), so the work bound in `Control` decides when it gives up.

use super::ode::{all_finite, error_norm, step_factor, too_small, Control, Failure, Ode, Solution};

const C: [f64; 7] = [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0];
const A: [[f64; 6]; 7] = [
    [0.0; 6],
    [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0],
    [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0],
    [19372.0 / 6561.0, -25360.0 / 2187.0, 64448.0 / 6561.0, -212.0 / 729.0, 0.0, 0.0],
    [9017.0 / 3168.0, -355.0 / 33.0, 46732.0 / 5247.0, 49.0 / 176.0, -5103.0 / 18656.0, 0.0],
    [35.0 / 384.0, 0.0, 500.0 / 1113.0, 125.0 / 192.0, -2187.0 / 6784.0, 11.0 / 84.0],
];
/// Fifth-order weights minus fourth-order weights: the error estimate.
const E: [f64; 7] = [
    71.0 / 57600.0,
    0.0,
    -71.0 / 16695.0,
    71.0 / 1920.0,
    -17253.0 / 339200.0,
    22.0 / 525.0,
    -1.0 / 40.0,
];

pub fn integrate<const N: usize>(ode: &impl Ode<N>, t_end: f64, y0: [f64; N], c: &Control<N>) -> Result<Solution<N>, Failure> {
    let mut t = 0.0;
    let mut y = y0;
    let mut h = c.initial_step.min(t_end);
    let (mut accepted, mut rejected) = (0, 0);
    let mut k = [[0.0; N]; 7];
    k[0] = ode.rhs(t, &y);
    while t < t_end {
        if accepted + rejected >= c.max_steps {
            return Err(Failure::TooMuchWork { reached: t, steps: accepted + rejected });
        }
        let last = t + h >= t_end * (1.0 - 4.0 * f64::EPSILON);
        let h_try = if last { t_end - t } else { h };
        if too_small(t, h_try, t_end) && !last {
            return Err(Failure::StepTooSmall { reached: t, step: h_try });
        }
        let mut stage_y = y;
        for s in 1..7 {
            for i in 0..N {
                stage_y[i] = y[i] + h_try * (0..s).map(|j| A[s][j] * k[j][i]).sum::<f64>();
            }
            k[s] = ode.rhs(t + C[s] * h_try, &stage_y);
        }
        // Stage 7 is evaluated at the new solution (FSAL).
        let y_new = stage_y;
        let mut err = [0.0; N];
        for i in 0..N {
            err[i] = h_try * (0..7).map(|j| E[j] * k[j][i]).sum::<f64>();
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
            k[0] = k[6];
            accepted += 1;
            // A clipped last step says nothing about larger steps: keep h then.
            if !(last && h_try < h) {
                h = h_try * step_factor(norm, 5.0);
            }
        } else {
            rejected += 1;
            h = h_try * step_factor(norm, 5.0).min(0.9);
        }
    }
    if !all_finite(&y) {
        return Err(Failure::NotFinite { reached: t });
    }
    Ok(Solution { y, accepted, rejected, next_step: h })
}
