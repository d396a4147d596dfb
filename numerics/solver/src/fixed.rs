//! Fixed-step explicit methods: `n` equal sub-steps per communication step,
//! the last one ending exactly on the communication point. No error
//! control, so the caller checks stability first (`STABILITY_LIMIT`: the
//! largest `lambda*h` on the negative real axis where the method is stable).

use super::ode::{all_finite, axpy, Failure, Ode};

pub enum Method {
    Euler,
    Rk4,
}

impl Method {
    pub const fn stability_limit(&self) -> f64 {
        match self {
            Method::Euler => 2.0,
            Method::Rk4 => 2.785,
        }
    }
}

pub fn integrate<const N: usize>(method: &Method, ode: &impl Ode<N>, t_end: f64, y0: [f64; N], n: usize) -> Result<[f64; N], Failure> {
    let n = n.max(1);
    let h = t_end / n as f64;
    let mut y = y0;
    for step in 0..n {
        let t = step as f64 * h;
        y = match method {
            Method::Euler => axpy(h, &ode.rhs(t, &y), &y),
            Method::Rk4 => {
                let k1 = ode.rhs(t, &y);
                let k2 = ode.rhs(t + 0.5 * h, &axpy(0.5 * h, &k1, &y));
                let k3 = ode.rhs(t + 0.5 * h, &axpy(0.5 * h, &k2, &y));
                let k4 = ode.rhs(t + h, &axpy(h, &k3, &y));
                let mut next = y;
                for i in 0..N {
                    next[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
                }
                next
            }
        };
        if !all_finite(&y) {
            return Err(Failure::NotFinite { reached: t });
        }
    }
    Ok(y)
}
