//! Dormand–Prince 5(4) (Hairer, Nørsett & Wanner I, II.5): explicit,
//! fifth order with an embedded fourth-order error estimate, first same as
//! last. On a stiff span its step shrinks to the stability limit (about
//! 3.3/lambda), so the work bound in `Control` decides when it gives up.

use super::ode::{drive, Control, Failure, Ode, Solution, Stepper};

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

struct DormandPrince<'a, O, const N: usize> {
    ode: &'a O,
    /// Stage derivatives; k[0] is f at the current point.
    k: [[f64; N]; 7],
}

impl<O: Ode<N>, const N: usize> Stepper<N> for DormandPrince<'_, O, N> {
    const ESTIMATE_ORDER: f64 = 5.0;

    fn try_step(&mut self, t: f64, y: &[f64; N], h: f64) -> Result<([f64; N], [f64; N]), Failure> {
        let k = &mut self.k;
        let mut stage_y = *y;
        for s in 1..7 {
            for i in 0..N {
                stage_y[i] = y[i] + h * (0..s).map(|j| A[s][j] * k[j][i]).sum::<f64>();
            }
            k[s] = self.ode.rhs(t + C[s] * h, &stage_y);
        }
        // The last stage is evaluated at the new solution (FSAL).
        let mut err = [0.0; N];
        for i in 0..N {
            err[i] = h * (0..7).map(|j| E[j] * k[j][i]).sum::<f64>();
        }
        Ok((stage_y, err))
    }

    fn accept(&mut self) {
        self.k[0] = self.k[6];
    }
}

pub fn integrate<const N: usize>(ode: &impl Ode<N>, t_end: f64, y0: [f64; N], c: &Control<N>) -> Result<Solution<N>, Failure> {
    let mut k = [[0.0; N]; 7];
    k[0] = ode.rhs(0.0, &y0);
    let solution = drive(&mut DormandPrince { ode, k }, t_end, y0, c)?;
    if solution.y.iter().all(|v| v.is_finite()) {
        Ok(solution)
    } else {
        Err(Failure::NotFinite { reached: t_end })
    }
}
