//! Banded matrices and their LU factorization with partial pivoting, on
//! buffers sized once: a line is a chain, so the Jacobian of its states
//! (ordered along the web) has few diagonals, and elimination costs
//! O(n * kl * (kl + ku)) instead of O(n^3).
//!
//! Storage is dense row-major (n * n): simple to fill and to read; only the
//! band (widened by kl for the pivots' fill-in) is ever touched.

#[derive(Clone, Debug, PartialEq)]
pub struct Band {
    n: usize,
    /// Sub- and super-diagonals that may be non-zero.
    kl: usize,
    ku: usize,
    a: Vec<f64>,
}

impl Band {
    pub fn zeros(n: usize, kl: usize, ku: usize) -> Band {
        Band { n, kl: kl.min(n.saturating_sub(1)), ku: ku.min(n.saturating_sub(1)), a: vec![0.0; n * n] }
    }

    pub fn n(&self) -> usize {
        self.n
    }

    pub fn lower(&self) -> usize {
        self.kl
    }

    pub fn upper(&self) -> usize {
        self.ku
    }

    /// Whether (i, j) lies in the band.
    #[inline]
    pub fn in_band(&self, i: usize, j: usize) -> bool {
        j + self.kl >= i && i + self.ku >= j
    }

    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.a[i * self.n + j]
    }

    /// Sets an entry; one outside the band is a bug of the caller's structure.
    #[inline]
    pub fn set(&mut self, i: usize, j: usize, x: f64) {
        debug_assert!(self.in_band(i, j) || x == 0.0, "({i}, {j}) = {x} outside the band ({}, {})", self.kl, self.ku);
        self.a[i * self.n + j] = x;
    }

    pub fn clear(&mut self) {
        self.a.fill(0.0);
    }

    /// y = A x.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        for (i, yi) in y.iter_mut().enumerate().take(self.n) {
            let (lo, hi) = (i.saturating_sub(self.kl), (i + self.ku + 1).min(self.n));
            *yi = (lo..hi).map(|j| self.get(i, j) * x[j]).sum();
        }
    }
}

/// The LU factors of a banded matrix (the band widened by kl above for the
/// row exchanges) and the pivot rows.
#[derive(Clone, Debug, PartialEq)]
pub struct BandLu {
    m: Band,
    pivot: Vec<usize>,
}

impl BandLu {
    pub fn new(n: usize, kl: usize, ku: usize) -> BandLu {
        BandLu { m: Band::zeros(n, kl, ku), pivot: vec![0; n] }
    }

    /// Factors `c * I - a` (what an implicit step solves with), in place of
    /// the previous factors. False if it is singular (or not finite).
    pub fn factor_shifted(&mut self, c: f64, a: &Band) -> bool {
        let (n, kl, ku) = (a.n, a.kl, a.ku);
        debug_assert!(self.m.n == n && self.m.kl == kl && self.m.ku == ku);
        // The factors need kl more super-diagonals than the matrix (fill-in of the pivoting).
        let width = kl + ku;
        self.m.a.fill(0.0);
        for i in 0..n {
            for j in i.saturating_sub(kl)..(i + ku + 1).min(n) {
                self.m.a[i * n + j] = -a.get(i, j);
            }
            self.m.a[i * n + i] += c;
        }
        let m = &mut self.m.a;
        for k in 0..n {
            let last_row = (k + kl + 1).min(n);
            let last_col = (k + width + 1).min(n);
            let mut p = k;
            for i in k + 1..last_row {
                if m[i * n + k].abs() > m[p * n + k].abs() {
                    p = i;
                }
            }
            self.pivot[k] = p;
            let d = m[p * n + k];
            if d == 0.0 || !d.is_finite() {
                return false;
            }
            if p != k {
                for j in k..last_col {
                    m.swap(k * n + j, p * n + j);
                }
            }
            for i in k + 1..last_row {
                let f = m[i * n + k] / d;
                m[i * n + k] = f;
                if f != 0.0 {
                    for j in k + 1..last_col {
                        m[i * n + j] -= f * m[k * n + j];
                    }
                }
            }
        }
        true
    }

    /// Solves in place with the last factors.
    pub fn solve(&self, b: &mut [f64]) {
        let (n, kl) = (self.m.n, self.m.kl);
        let width = kl + self.m.ku;
        let m = &self.m.a;
        for k in 0..n {
            let p = self.pivot[k];
            if p != k {
                b.swap(k, p);
            }
            let bk = b[k];
            if bk != 0.0 {
                for i in k + 1..(k + kl + 1).min(n) {
                    b[i] -= m[i * n + k] * bk;
                }
            }
        }
        for k in (0..n).rev() {
            let mut s = b[k];
            for j in k + 1..(k + width + 1).min(n) {
                s -= m[k * n + j] * b[j];
            }
            b[k] = s / m[k * n + k];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A banded matrix from a deterministic pseudo-random sequence.
    fn sample(n: usize, kl: usize, ku: usize, seed: u64) -> Band {
        let mut s = seed;
        let mut next = || {
            s = s.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            ((s >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let mut a = Band::zeros(n, kl, ku);
        for i in 0..n {
            for j in 0..n {
                if a.in_band(i, j) {
                    a.set(i, j, next());
                }
            }
        }
        a
    }

    #[test]
    fn solves_banded_systems_that_need_pivoting() {
        for (n, kl, ku) in [(1, 0, 0), (5, 1, 1), (12, 3, 2), (30, 2, 5), (8, 7, 7)] {
            let a = sample(n, kl, ku, n as u64 + 17);
            let x: Vec<f64> = (0..n).map(|i| 1.0 + i as f64 * 0.25).collect();
            // (c I - a) x = b
            let c = 0.1; // small: pivots are needed
            let mut ax = vec![0.0; n];
            a.mul(&x, &mut ax);
            let mut b: Vec<f64> = (0..n).map(|i| c * x[i] - ax[i]).collect();
            let mut lu = BandLu::new(n, kl, ku);
            assert!(lu.factor_shifted(c, &a));
            lu.solve(&mut b);
            for i in 0..n {
                // Condition numbers of these matrices stay below ~1e4.
                assert!((b[i] - x[i]).abs() < 1e-10 * x[i].abs(), "n {n}: x[{i}] = {} against {}", b[i], x[i]);
            }
        }
    }

    #[test]
    fn reports_a_singular_matrix() {
        let mut a = Band::zeros(3, 1, 1);
        a.set(0, 0, 1.0);
        a.set(1, 1, 1.0);
        let mut lu = BandLu::new(3, 1, 1);
        // I - a has a zero row and column: row 0 and 1 vanish.
        assert!(!lu.factor_shifted(1.0, &a));
    }
}
