//! Banded matrices and their LU factorization with partial pivoting, on
//! buffers sized once: a line is a chain, so the Jacobian of its states
//! (ordered along the web) has few diagonals, and elimination costs
//! O(n * kl * (kl + ku)) instead of O(n^3).
//!
//! Storage is compact and row-major: row i holds columns i - kl ..= i + ku
//! (the LU's rows kl more, for the pivots' fill-in), so nothing outside the
//! band is stored, cleared or copied, and each row's band is one slice.

#[derive(Clone, Debug, PartialEq)]
pub struct Band {
    n: usize,
    /// Sub- and super-diagonals that may be non-zero.
    kl: usize,
    ku: usize,
    /// n rows of kl + ku + 1: entry (i, j) at i * (kl + ku + 1) + j + kl - i.
    a: Vec<f64>,
}

impl Band {
    pub fn zeros(n: usize, kl: usize, ku: usize) -> Band {
        let (kl, ku) = (kl.min(n.saturating_sub(1)), ku.min(n.saturating_sub(1)));
        Band { n, kl, ku, a: vec![0.0; n * (kl + ku + 1)] }
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
    fn index(&self, i: usize, j: usize) -> usize {
        i * (self.kl + self.ku + 1) + j + self.kl - i
    }

    /// Entry (i, j); 0 outside the band.
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        if i < self.n && j < self.n && self.in_band(i, j) {
            self.a[self.index(i, j)]
        } else {
            0.0
        }
    }

    /// Sets an entry; one outside the band is a bug of the caller's structure
    /// (a zero there is no entry, and is dropped).
    #[inline]
    pub fn set(&mut self, i: usize, j: usize, x: f64) {
        debug_assert!(self.in_band(i, j) || x == 0.0, "({i}, {j}) = {x} outside the band ({}, {})", self.kl, self.ku);
        assert!(i < self.n && j < self.n, "({i}, {j}) outside a matrix of {} rows", self.n);
        if self.in_band(i, j) {
            let k = self.index(i, j);
            self.a[k] = x;
        }
    }

    /// The stored band, row by row: entry (i, j) at i * (kl + ku + 1) + j + kl - i.
    #[inline]
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.a
    }

    /// Row i's band, column i - kl first (entries for columns outside the matrix are kept 0
    /// by the caller).
    #[inline]
    pub fn row_mut(&mut self, i: usize) -> &mut [f64] {
        let w = self.kl + self.ku + 1;
        &mut self.a[i * w..(i + 1) * w]
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

/// Calls `$f(kl, ku)` with kl and ku as constants for the bands lines have (a chain of
/// parts: a few diagonals), so that the compiler unrolls the rows' short loops; any other
/// band runs the same code with them as variables.
macro_rules! small_bands {
    ($kl:expr, $ku:expr, |$l:ident, $u:ident| $f:expr) => {
        match ($kl, $ku) {
            (1, 1) => { let ($l, $u) = (1, 1); $f }
            (2, 1) => { let ($l, $u) = (2, 1); $f }
            (2, 2) => { let ($l, $u) = (2, 2); $f }
            (3, 2) => { let ($l, $u) = (3, 2); $f }
            (3, 3) => { let ($l, $u) = (3, 3); $f }
            (4, 3) => { let ($l, $u) = (4, 3); $f }
            (4, 4) => { let ($l, $u) = (4, 4); $f }
            ($l, $u) => $f,
        }
    };
}

/// The LU factors of a banded matrix (the band widened by kl above for the
/// row exchanges) and the pivot rows.
#[derive(Clone, Debug, PartialEq)]
pub struct BandLu {
    n: usize,
    kl: usize,
    ku: usize,
    /// n rows of 2 kl + ku + 1: entry (i, j) at i * (2 kl + ku + 1) + j + kl - i
    /// (row i holds columns i - kl ..= i + ku + kl).
    m: Vec<f64>,
    /// The multipliers of column k (rows k + 1 ..= k + kl) at k * kl: the forward solve reads them in a row.
    low: Vec<f64>,
    /// 1 / U's diagonal (U's rows are stored divided by it, the diagonal aside).
    inverse: Vec<f64>,
    pivot: Vec<usize>,
}

impl BandLu {
    pub fn new(n: usize, kl: usize, ku: usize) -> BandLu {
        let (kl, ku) = (kl.min(n.saturating_sub(1)), ku.min(n.saturating_sub(1)));
        BandLu { n, kl, ku, m: vec![0.0; n * (2 * kl + ku + 1)], low: vec![0.0; n * kl], inverse: vec![0.0; n], pivot: vec![0; n] }
    }

    /// Factors `c * I - a` (what an implicit step solves with), in place of
    /// the previous factors. False if it is singular (or not finite).
    pub fn factor_shifted(&mut self, c: f64, a: &Band) -> bool {
        debug_assert!(self.n == a.n && self.kl == a.kl && self.ku == a.ku);
        small_bands!(self.kl, self.ku, |kl, ku| self.factor_with(c, a, kl, ku))
    }

    /// `factor_shifted` for kl and ku (constants where `small_bands!` calls it).
    #[inline(always)]
    fn factor_with(&mut self, c: f64, a: &Band, kl: usize, ku: usize) -> bool {
        let n = a.n;
        let wa = kl + ku + 1;
        // The factors need kl more super-diagonals than the matrix (fill-in of the pivoting).
        let w = wa + kl;
        let m = &mut self.m;
        // Row i of both starts at column i - kl: the same offsets.
        for (row, arow) in m.chunks_exact_mut(w).zip(a.a.chunks_exact(wa)) {
            let (band, fill) = row.split_at_mut(wa);
            for (x, y) in band.iter_mut().zip(arow) {
                *x = -y;
            }
            for x in fill {
                *x = 0.0;
            }
            band[kl] += c;
        }
        // A row's columns k ..= k + kl + ku, whole even past the matrix's last column (its storage
        // has them, zeros that stay zeros): loops of one length, unrolled for small bands.
        let span = kl + ku + 1;
        for k in 0..n {
            let last_row = (k + kl + 1).min(n);
            // (i, k) sits at i * w + k + kl - i.
            let mut p = k;
            let mut best = m[k * w + kl].abs();
            for i in k + 1..last_row {
                let x = m[i * w + k + kl - i].abs();
                if x > best {
                    (p, best) = (i, x);
                }
            }
            self.pivot[k] = p;
            let (upper, lower) = m.split_at_mut((k + 1) * w);
            let row_k = &mut upper[k * w + kl..k * w + kl + span];
            if p != k {
                let q = (p - k - 1) * w + kl + k - p;
                row_k.swap_with_slice(&mut lower[q..q + span]);
            }
            let d = row_k[0];
            if d == 0.0 || !d.is_finite() {
                return false;
            }
            let inverse = 1.0 / d;
            self.inverse[k] = inverse;
            // U's row k over its diagonal: in the back substitution a row then waits on the one
            // before for one multiply and one subtraction.
            for y in &mut row_k[1..] {
                *y *= inverse;
            }
            let low = &mut self.low[k * kl..(k + 1) * kl];
            for (i, l) in (k + 1..last_row).zip(low.iter_mut()) {
                // Row i's columns k ..= k + kl + ku.
                let q = (i - k - 1) * w + kl + k - i;
                let row_i = &mut lower[q..q + span];
                let g = row_i[0];
                row_i[0] = g * inverse;
                *l = row_i[0];
                if g != 0.0 {
                    for (x, y) in row_i[1..].iter_mut().zip(&row_k[1..]) {
                        *x -= g * y;
                    }
                }
            }
        }
        true
    }

    /// Solves in place with the last factors.
    pub fn solve(&self, b: &mut [f64]) {
        small_bands!(self.kl, self.ku, |kl, ku| self.solve_with(b, kl, ku))
    }

    /// `solve` for kl and ku (constants where `small_bands!` calls it).
    #[inline(always)]
    fn solve_with(&self, b: &mut [f64], kl: usize, ku: usize) {
        let n = self.n;
        let w = 2 * kl + ku + 1;
        let b = &mut b[..n];
        for (k, (&p, low)) in self.pivot.iter().zip(self.low.chunks_exact(kl.max(1))).enumerate() {
            if p != k {
                b.swap(k, p);
            }
            let (head, tail) = b.split_at_mut(k + 1);
            let bk = head[k];
            for (x, l) in tail.iter_mut().zip(&low[..kl]) {
                *x -= l * bk;
            }
        }
        if (1..=WINDOW).contains(&(kl + ku)) {
            // The unknowns a row reads (the next kl + ku, 0 past the end) carried in registers.
            let mut win = [0.0; WINDOW];
            for (k, (row, inverse)) in self.m.chunks_exact(w).zip(&self.inverse).enumerate().rev() {
                let row = &row[kl + 1..];
                let mut s = 0.0;
                for j in 1..kl + ku {
                    s += row[j] * win[j];
                }
                let x = (b[k] * inverse - s) - row[0] * win[0];
                for j in (1..kl + ku).rev() {
                    win[j] = win[j - 1];
                }
                win[0] = x;
                b[k] = x;
            }
            return;
        }
        // Wider bands read the unknowns from b.
        for (k, (row, inverse)) in self.m.chunks_exact(w).zip(&self.inverse).enumerate().rev() {
            // U's row k: columns k ..= k + kl + ku. The next unknown, solved just before, is
            // added last: the sum over the farther ones does not wait for it (a solve is a chain
            // of rows, each waiting on the one before).
            let (head, tail) = b.split_at_mut(k + 1);
            let (next, far) = row[kl + 1..].split_first().unwrap_or((&0.0, &[]));
            let mut s = 0.0;
            for (x, y) in far.iter().zip(tail.iter().skip(1)) {
                s += x * y;
            }
            let first = tail.first().map_or(0.0, |y| next * y);
            head[k] = (head[k] * inverse - s) - first;
        }
    }
}

/// The most unknowns a row of U reads that `solve` carries in registers.
const WINDOW: usize = 8;

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
