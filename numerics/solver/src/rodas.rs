//! RODAS4 (Hairer & Wanner, Solving ODEs II, section VI.4; the coefficients
//! of their code `rodas.f`, METH = 1): a Rosenbrock method of order 4 with an
//! embedded order-3 solution, L-stable and stiffly accurate, so a stiff
//! mode (a web's damping time, a light roller on a stiff span) is damped
//! at any step. One Jacobian and one LU per step, six linear solves, no
//! Newton iterations: the cost of a step is known in advance.
//!
//! For systems whose size is known only at run time (a line read from its
//! FMU's resources); every buffer is allocated when the integrator is made,
//! none in a step. The Jacobian is banded ([`Band`]).

use super::band::{Band, BandLu};
use super::ode::Failure;

const GAMMA: f64 = 0.25;
const C: [f64; 4] = [0.386, 0.21, 0.63, 1.0];
const D: [f64; 4] = [0.25, -0.1043, 0.1035, -0.362_000_000_000_002_3e-1];
const A21: f64 = 1.544;
const A3: [f64; 2] = [0.946_678_528_081_582_6, 0.255_701_169_898_328_4];
const A4: [f64; 3] = [3.314_825_187_068_521, 2.896_124_015_972_201, 0.998_641_913_997_781_7];
const A5: [f64; 4] = [1.221_224_509_226_641, 6.019_134_481_288_629, 12.537_083_329_320_87, -0.687_886_036_105_895];
const C21: f64 = -5.6688;
const C3: [f64; 2] = [-2.430_093_356_833_875, -0.206_359_915_709_191_5];
const C4: [f64; 3] = [-0.107_352_905_815_137_5, -9.594_562_251_023_355, -20.470_286_148_096_16];
const C5: [f64; 4] = [7.496_443_313_967_647, -10.246_804_314_643_52, -33.999_903_528_199_05, 11.708_908_932_061_6];
const C6: [f64; 5] = [8.083_246_795_921_522, -7.981_132_988_064_893, -31.521_594_328_743_71, 16.319_305_431_231_36, -6.058_818_238_834_054];

/// What the integrator asks of the system it integrates.
pub trait System {
    /// dy = f(t, y). `Err` when y is no state the system can take (an
    /// integrator's trial value): the step is retried shorter.
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), ()>;

    /// df/dy at (t, y), written into `jac` (cleared, its band as made).
    fn jacobian(&mut self, t: f64, y: &[f64], jac: &mut Band) -> Result<(), ()>;

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

#[derive(Clone, Debug, PartialEq)]
pub struct Rodas {
    n: usize,
    jac: Band,
    lu: BandLu,
    k: [Vec<f64>; 6],
    stage: Vec<f64>,
    y_now: Vec<f64>,
    f: Vec<f64>,
    f0: Vec<f64>,
    ft: Vec<f64>,
    /// The step to try next, kept between calls (0: not known yet).
    pub next_step: f64,
    pub stats: Stats,
}

impl Rodas {
    /// An integrator for n states whose Jacobian has `kl` sub- and `ku`
    /// super-diagonals.
    pub fn new(n: usize, kl: usize, ku: usize) -> Rodas {
        let v = || vec![0.0; n];
        Rodas {
            n,
            jac: Band::zeros(n, kl, ku),
            lu: BandLu::new(n, kl, ku),
            k: [v(), v(), v(), v(), v(), v()],
            stage: v(),
            y_now: v(),
            f: v(),
            f0: v(),
            ft: v(),
            next_step: 0.0,
            stats: Stats::default(),
        }
    }

    pub fn len(&self) -> usize {
        self.n
    }

    pub fn is_empty(&self) -> bool {
        self.n == 0
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
        let n = self.n;
        let mut t = t0;
        let mut h = if self.next_step > 0.0 { self.next_step } else { initial_step(t1 - t0) };
        if c.max_step > 0.0 {
            h = h.min(c.max_step);
        }
        let mut attempts = 0;
        let mut fresh_jacobian = false;
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
            let last = t + h >= t1 - 4.0 * f64::EPSILON * t1.abs().max(1.0);
            let h_try = if last { t1 - t } else { h };
            if h_try <= 16.0 * f64::EPSILON * t.abs().max(t1.abs()) && !last {
                break Err(Failure::StepTooSmall { reached: t, step: h_try });
            }
            if !fresh_jacobian {
                self.jac.clear();
                if sys.rhs(t, y, &mut self.f0).is_err() || sys.jacobian(t, y, &mut self.jac).is_err() {
                    break Err(Failure::NotFinite { reached: t });
                }
                self.stats.rhs += 1;
                self.stats.jacobians += 1;
                if sys.time_dependent() {
                    let dt = f64::EPSILON.sqrt() * t.abs().max(h_try);
                    if sys.rhs(t + dt, y, &mut self.ft).is_err() {
                        break Err(Failure::NotFinite { reached: t });
                    }
                    self.stats.rhs += 1;
                    for i in 0..n {
                        self.ft[i] = (self.ft[i] - self.f0[i]) / dt;
                    }
                } else {
                    self.ft.fill(0.0);
                }
                fresh_jacobian = true;
            }
            match self.try_step(sys, t, y, h_try, &mut f, c) {
                Some(norm) if norm <= 1.0 => {
                    y.copy_from_slice(&self.stage);
                    t = if last { t1 } else { t + h_try };
                    self.stats.accepted += 1;
                    fresh_jacobian = false;
                    if !(last && h_try < h) {
                        h = h_try * factor(norm);
                    }
                }
                Some(norm) => {
                    self.stats.rejected += 1;
                    h = h_try * factor(norm).min(0.9);
                }
                None => {
                    self.stats.rejected += 1;
                    h = 0.2 * h_try;
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

    /// One attempt: the new solution in self.stage, and the error norm
    /// (None: a stage left the states the system can take, or the matrix is singular).
    fn try_step<S: System>(&mut self, sys: &mut S, t: f64, y: &[f64], h: f64, f: &mut [f64], c: &Control) -> Option<f64> {
        let n = self.n;
        if !self.lu.factor_shifted(1.0 / (h * GAMMA), &self.jac) {
            return None;
        }
        self.stats.factorizations += 1;
        let [k1, k2, k3, k4, k5, k6] = &mut self.k;
        // Stage 1.
        for i in 0..n {
            k1[i] = self.f0[i] + h * D[0] * self.ft[i];
        }
        self.lu.solve(k1);
        // Stages 2-4: f at y + sum a_ij k_j, plus sum (c_ij/h) k_j and d_i h f_t.
        let stage = &mut self.stage;
        for i in 0..n {
            stage[i] = y[i] + A21 * k1[i];
        }
        sys.rhs(t + C[0] * h, stage, f).ok()?;
        for i in 0..n {
            k2[i] = f[i] + h * D[1] * self.ft[i] + C21 / h * k1[i];
        }
        self.lu.solve(k2);
        for i in 0..n {
            stage[i] = y[i] + A3[0] * k1[i] + A3[1] * k2[i];
        }
        sys.rhs(t + C[1] * h, stage, f).ok()?;
        for i in 0..n {
            k3[i] = f[i] + h * D[2] * self.ft[i] + (C3[0] * k1[i] + C3[1] * k2[i]) / h;
        }
        self.lu.solve(k3);
        for i in 0..n {
            stage[i] = y[i] + A4[0] * k1[i] + A4[1] * k2[i] + A4[2] * k3[i];
        }
        sys.rhs(t + C[2] * h, stage, f).ok()?;
        for i in 0..n {
            k4[i] = f[i] + h * D[3] * self.ft[i] + (C4[0] * k1[i] + C4[1] * k2[i] + C4[2] * k3[i]) / h;
        }
        self.lu.solve(k4);
        // Stage 5 at t + h (no time term), then the embedded solution.
        for i in 0..n {
            stage[i] = y[i] + A5[0] * k1[i] + A5[1] * k2[i] + A5[2] * k3[i] + A5[3] * k4[i];
        }
        sys.rhs(t + h, stage, f).ok()?;
        for i in 0..n {
            k5[i] = f[i] + (C5[0] * k1[i] + C5[1] * k2[i] + C5[2] * k3[i] + C5[3] * k4[i]) / h;
        }
        self.lu.solve(k5);
        for i in 0..n {
            stage[i] += k5[i];
        }
        sys.rhs(t + h, stage, f).ok()?;
        for i in 0..n {
            k6[i] = f[i] + (C6[0] * k1[i] + C6[1] * k2[i] + C6[2] * k3[i] + C6[3] * k4[i] + C6[4] * k5[i]) / h;
        }
        self.lu.solve(k6);
        self.stats.rhs += 5;
        // The order-4 solution; k6 is its difference from the order-3 one.
        let mut sum = 0.0;
        for i in 0..n {
            let y_new = stage[i] + k6[i];
            let rtol = c.rtol * c.rtol_scale.get(i).copied().unwrap_or(1.0);
            let scale = c.atol[i] + rtol * y[i].abs().max(y_new.abs());
            sum += (k6[i] / scale).powi(2);
            stage[i] = y_new;
        }
        let norm = (sum / n.max(1) as f64).sqrt();
        (norm.is_finite() && stage.iter().all(|x| x.is_finite())).then_some(norm)
    }
}

/// The first step of a fresh integrator: a tenth of the interval.
fn initial_step(span: f64) -> f64 {
    0.1 * span
}

/// Step-size factor for an error norm of a local error O(h^4) (safety 0.9,
/// growth at most 6, shrink at most 5 as rodas.f).
fn factor(norm: f64) -> f64 {
    if norm == 0.0 {
        6.0
    } else {
        (0.9 * libm::pow(norm, -0.25)).clamp(0.2, 6.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// y1' = -y2 + t*y1*0 ... a non-autonomous, non-linear test problem with
    /// a known solution: y = (cos t + t^2, sin t), written as
    /// y1' = -y2 + 2t, y2' = y1 - t^2 (linear in y, forced in t).
    struct Forced;

    impl System for Forced {
        fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), ()> {
            dy[0] = -y[1] + 2.0 * t;
            dy[1] = y[0] - t * t;
            Ok(())
        }
        fn jacobian(&mut self, _t: f64, _y: &[f64], jac: &mut Band) -> Result<(), ()> {
            jac.set(0, 1, -1.0);
            jac.set(1, 0, 1.0);
            Ok(())
        }
        fn time_dependent(&self) -> bool {
            true
        }
    }

    /// A non-linear scalar problem: y' = -y^2, y(0) = 1, y = 1/(1+t).
    struct Riccati;

    impl System for Riccati {
        fn rhs(&mut self, _t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), ()> {
            dy[0] = -y[0] * y[0];
            Ok(())
        }
        fn jacobian(&mut self, _t: f64, y: &[f64], jac: &mut Band) -> Result<(), ()> {
            jac.set(0, 0, -2.0 * y[0]);
            Ok(())
        }
        fn time_dependent(&self) -> bool {
            false
        }
    }

    /// Fixed steps (tolerance so loose every step is accepted).
    fn fixed<S: System>(sys: &mut S, n: usize, y0: &[f64], t1: f64, steps: usize) -> Vec<f64> {
        let mut r = Rodas::new(n, n - 1, n - 1);
        let atol = vec![1e300; n];
        let c = Control { rtol: 0.0, atol: &atol, rtol_scale: &[], max_steps: 10 * steps, max_step: t1 / steps as f64 };
        let mut y = y0.to_vec();
        r.next_step = t1 / steps as f64;
        r.integrate(sys, 0.0, t1, &mut y, &c).unwrap();
        assert_eq!(r.stats.accepted, steps);
        y
    }

    #[test]
    fn converges_with_order_four() {
        // Halving h divides the error by 2^4 = 16 (for the smooth problems
        // here within 20 %: the asymptotic range starts at a few steps).
        let exact = |t: f64| [t.cos() + t * t, t.sin()];
        let mut errors = vec![];
        for steps in [8, 16, 32] {
            let y = fixed(&mut Forced, 2, &[1.0, 0.0], 1.0, steps);
            let e = exact(1.0);
            errors.push(((y[0] - e[0]).powi(2) + (y[1] - e[1]).powi(2)).sqrt());
        }
        for w in errors.windows(2) {
            let ratio = w[0] / w[1];
            assert!((13.0..20.0).contains(&ratio), "error ratio {ratio} for halved steps ({errors:?})");
        }
        let mut errors = vec![];
        for steps in [8, 16, 32] {
            let y = fixed(&mut Riccati, 1, &[1.0], 2.0, steps);
            errors.push((y[0] - 1.0 / 3.0).abs());
        }
        for w in errors.windows(2) {
            let ratio = w[0] / w[1];
            assert!((13.0..20.0).contains(&ratio), "error ratio {ratio} for halved steps ({errors:?})");
        }
    }

    /// y' = lambda (y - cos t) - sin t has the solution cos t for y(0) = 1;
    /// with lambda = -1e9 and h = 0.1 an L-stable method follows it, an
    /// A-stable one that is not L-stable would keep an undamped error.
    struct Prothero {
        lambda: f64,
    }

    impl System for Prothero {
        fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), ()> {
            dy[0] = self.lambda * (y[0] - t.cos()) - t.sin();
            Ok(())
        }
        fn jacobian(&mut self, _t: f64, _y: &[f64], jac: &mut Band) -> Result<(), ()> {
            jac.set(0, 0, self.lambda);
            Ok(())
        }
        fn time_dependent(&self) -> bool {
            true
        }
    }

    #[test]
    fn damps_stiff_modes_at_any_step() {
        // Started off the smooth solution by 1, one step must remove the
        // offset: the two results differ by |R(h lambda)| ~ 1/(h |lambda|) = 1e-8
        // (R(inf) = 0). Both stay near cos t (order reduction on this
        // problem allows 1e-6 at h = 0.1).
        let off = fixed(&mut Prothero { lambda: -1e9 }, 1, &[2.0], 0.1, 1)[0];
        let on = fixed(&mut Prothero { lambda: -1e9 }, 1, &[1.0], 0.1, 1)[0];
        assert!((off - on).abs() < 1e-7, "offset left: {}", off - on);
        assert!((on - 0.1f64.cos()).abs() < 1e-6, "{}", on - 0.1f64.cos());
    }

    #[test]
    fn meets_its_tolerance_with_error_control() {
        let mut r = Rodas::new(2, 1, 1);
        let atol = [1e-12, 1e-12];
        let c = Control { rtol: 1e-10, atol: &atol, rtol_scale: &[], max_steps: 10_000, max_step: 0.0 };
        let mut y = [1.0, 0.0];
        let mut t = 0.0;
        for _ in 0..10 {
            r.integrate(&mut Forced, t, t + 0.5, &mut y, &c).unwrap();
            t += 0.5;
        }
        let e = [t.cos() + t * t, t.sin()];
        assert!((y[0] - e[0]).abs() < 1e-8 && (y[1] - e[1]).abs() < 1e-8, "{y:?} {e:?}");
        assert!(r.stats.rejected < r.stats.accepted / 5, "{:?}", r.stats);
    }
}
