//! Rosenbrock 2(3), the L-stable method of MATLAB's ode23s (Shampine &
//! Reichelt, "The MATLAB ODE Suite", 1997): second order, with a third-order
//! error estimate, one Jacobian and one linear solve per stage. L-stability
//! means a stiff span (time constant far below the step) is damped, never
//! amplified, whatever the step.

use super::linalg::solve;
use super::ode::{axpy, drive, Control, Failure, Ode, Solution, Stepper};

const D: f64 = 0.292_893_218_813_452_5; // 1/(2 + sqrt 2)
const E32: f64 = 7.414_213_562_373_095; // 6 + sqrt 2

struct Rosenbrock23<'a, O, const N: usize> {
    ode: &'a O,
    /// f at the current point; f at the trial point once a step is tried.
    f0: [f64; N],
    f_new: [f64; N],
}

impl<O: Ode<N>, const N: usize> Stepper<N> for Rosenbrock23<'_, O, N> {
    const ESTIMATE_ORDER: f64 = 3.0;

    fn try_step(&mut self, t: f64, y: &[f64; N], h: f64) -> Result<([f64; N], [f64; N]), Failure> {
        let (ode, f0) = (self.ode, self.f0);
        let jac = ode.jacobian(t, y);
        let dfdt = ode.time_derivative(t, y);
        // W = I - h d J
        let mut w = [[0.0; N]; N];
        for i in 0..N {
            for j in 0..N {
                w[i][j] = if i == j { 1.0 } else { 0.0 } - h * D * jac[i][j];
            }
        }
        let stage = |rhs: [f64; N]| solve(w, rhs).ok_or(Failure::NotFinite { reached: t });
        let k1 = stage(axpy(h * D, &dfdt, &f0))?;
        let f1 = ode.rhs(t + 0.5 * h, &axpy(0.5 * h, &k1, y));
        let k2 = axpy(1.0, &k1, &stage(axpy(-1.0, &k1, &f1))?);
        let y_new = axpy(h, &k2, y);
        let f2 = ode.rhs(t + h, &y_new);
        let mut r3 = [0.0; N];
        for i in 0..N {
            r3[i] = f2[i] - E32 * (k2[i] - f1[i]) - 2.0 * (k1[i] - f0[i]) + h * D * dfdt[i];
        }
        let k3 = stage(r3)?;
        let mut err = [0.0; N];
        for i in 0..N {
            err[i] = h / 6.0 * (k1[i] - 2.0 * k2[i] + k3[i]);
        }
        self.f_new = f2;
        Ok((y_new, err))
    }

    fn accept(&mut self) {
        self.f0 = self.f_new;
    }
}

pub fn integrate<const N: usize>(ode: &impl Ode<N>, t_end: f64, y0: [f64; N], c: &Control<N>) -> Result<Solution<N>, Failure> {
    let f0 = ode.rhs(0.0, &y0);
    drive(&mut Rosenbrock23 { ode, f0, f_new: f0 }, t_end, y0, c)
}
