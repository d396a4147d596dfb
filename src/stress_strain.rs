//! A nonlinear web: engineering stress as a function of engineering strain,
//! from a table. Between the nodes the curve is the monotone cubic of
//! Fritsch–Carlson in the form SciPy's `PchipInterpolator` uses (weighted
//! harmonic means of the chords, shape-preserving end slopes), so the slope
//! (the tangent modulus) is continuous; beyond the table it goes on along the
//! end tangent.

/// The nodes, their slopes and the coefficients of each interval's cubic.
#[derive(Clone, Debug, PartialEq)]
pub struct StressStrain {
    strain: Vec<f64>,
    stress: Vec<f64>,
    /// dsigma/deps at each node.
    slope: Vec<f64>,
}

impl StressStrain {
    /// Checks a table of (strain, stress) pairs; the error says which rule it breaks.
    pub fn new(points: &[[f64; 2]]) -> Result<Self, String> {
        if points.len() < 2 {
            return Err(format!("has {} point(s); at least 2 are needed, one of them (0, 0)", points.len()));
        }
        for (i, [e, s]) in points.iter().enumerate() {
            if !(e.is_finite() && s.is_finite()) {
                return Err(format!("point {i} ({e}, {s}) is not finite"));
            }
            if *e <= -1.0 {
                return Err(format!("point {i}: strain {e} must be > -1"));
            }
        }
        for (i, w) in points.windows(2).enumerate() {
            if !(w[1][0] > w[0][0]) {
                return Err(format!("strain must increase strictly: point {} has {} after {}", i + 1, w[1][0], w[0][0]));
            }
            if w[1][1] < w[0][1] {
                return Err(format!("stress must not decrease: point {} has {} Pa after {} Pa", i + 1, w[1][1], w[0][1]));
            }
        }
        if !points.iter().any(|&[e, s]| e == 0.0 && s == 0.0) {
            return Err("does not pass through the origin: it needs the point (0, 0)".into());
        }
        if points.first().map(|p| p[1]) == points.last().map(|p| p[1]) {
            return Err("carries no load: the stress never rises".into());
        }
        let strain: Vec<f64> = points.iter().map(|p| p[0]).collect();
        let stress: Vec<f64> = points.iter().map(|p| p[1]).collect();
        let slope = node_slopes(&strain, &stress);
        Ok(StressStrain { strain, stress, slope })
    }

    /// The table as (strain, stress) pairs.
    pub fn points(&self) -> impl Iterator<Item = [f64; 2]> + '_ {
        self.strain.iter().zip(&self.stress).map(|(&e, &s)| [e, s])
    }

    /// sigma(eps) and dsigma/deps, Pa. No allocation: a binary search and a cubic.
    #[inline]
    pub fn at(&self, eps: f64) -> (f64, f64) {
        let n = self.strain.len();
        let (first, last) = (self.strain[0], self.strain[n - 1]);
        if !(eps > first) {
            return (self.stress[0] + self.slope[0] * (eps - first), self.slope[0]);
        }
        if eps >= last {
            return (self.stress[n - 1] + self.slope[n - 1] * (eps - last), self.slope[n - 1]);
        }
        let Cubic { k, t, d0, c2, c3 } = self.cubic(eps);
        let sigma = ((c3 * t + c2) * t + d0) * t + self.stress[k];
        let tangent = (3.0 * c3 * t + 2.0 * c2) * t + d0;
        (sigma, tangent)
    }

    /// d2sigma/deps2, Pa: 0 beyond the table (linear there). The PCHIP's
    /// curvature jumps at a node: there the interval that starts at it is taken.
    pub fn curvature(&self, eps: f64) -> f64 {
        let n = self.strain.len();
        if !(eps > self.strain[0]) || eps >= self.strain[n - 1] {
            return 0.0;
        }
        let Cubic { t, c2, c3, .. } = self.cubic(eps);
        6.0 * c3 * t + 2.0 * c2
    }

    /// The cubic of the interval [k, k+1] that holds `eps` (inside the table),
    /// in powers of t = eps - eps_k, as SciPy stores it: sigma_k + d0*t + c2*t^2 + c3*t^3.
    fn cubic(&self, eps: f64) -> Cubic {
        let k = self.strain.partition_point(|&e| e <= eps) - 1;
        let h = self.strain[k + 1] - self.strain[k];
        let chord = (self.stress[k + 1] - self.stress[k]) / h;
        let (d0, d1) = (self.slope[k], self.slope[k + 1]);
        Cubic {
            k,
            t: eps - self.strain[k],
            d0,
            c2: (3.0 * chord - 2.0 * d0 - d1) / h,
            c3: (d0 + d1 - 2.0 * chord) / (h * h),
        }
    }

    /// The steepest chord of the table, Pa: the stiffest the web gets, which
    /// `wpN.E` reports for a table record.
    pub fn steepest_chord(&self) -> f64 {
        self.strain
            .windows(2)
            .zip(self.stress.windows(2))
            .map(|(e, s)| (s[1] - s[0]) / (e[1] - e[0]))
            .fold(0.0, f64::max)
    }
}

/// The node slopes of SciPy's PCHIP: 0 at a local extremum or a flat chord,
/// otherwise the harmonic mean of the chords weighted by the intervals;
/// the three-point end formula, limited so the curve keeps its shape.
fn node_slopes(x: &[f64], y: &[f64]) -> Vec<f64> {
    let n = x.len();
    let h: Vec<f64> = x.windows(2).map(|w| w[1] - w[0]).collect();
    let m: Vec<f64> = y.windows(2).zip(&h).map(|(w, h)| (w[1] - w[0]) / h).collect();
    if n == 2 {
        return vec![m[0], m[0]];
    }
    let mut d = vec![0.0; n];
    for k in 1..n - 1 {
        let (m0, m1) = (m[k - 1], m[k]);
        if m0.signum() != m1.signum() || m0 == 0.0 || m1 == 0.0 {
            continue;
        }
        let w1 = 2.0 * h[k] + h[k - 1];
        let w2 = h[k] + 2.0 * h[k - 1];
        d[k] = 1.0 / ((w1 / m0 + w2 / m1) / (w1 + w2));
    }
    d[0] = end_slope(h[0], h[1], m[0], m[1]);
    d[n - 1] = end_slope(h[n - 2], h[n - 3], m[n - 2], m[n - 3]);
    d
}

fn end_slope(h0: f64, h1: f64, m0: f64, m1: f64) -> f64 {
    let d = ((2.0 * h0 + h1) * m0 - h0 * m1) / (h0 + h1);
    if sign(d) != sign(m0) {
        0.0
    } else if sign(m0) != sign(m1) && d.abs() > 3.0 * m0.abs() {
        3.0 * m0
    } else {
        d
    }
}

/// NumPy's sign: 0 for 0.
fn sign(x: f64) -> f64 {
    if x == 0.0 {
        0.0
    } else {
        x.signum()
    }
}

/// One interval's cubic, see `StressStrain::cubic`.
struct Cubic {
    k: usize,
    t: f64,
    d0: f64,
    c2: f64,
    c3: f64,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth, strictly increasing curve with a toe, like a nonwoven's:
    /// sigma = E0 * (eps + a*eps^2 + b*eps^3), and its derivatives.
    const E0: f64 = 5e6;
    const A: f64 = 20.0;
    const B: f64 = 400.0;
    fn curve(e: f64) -> f64 {
        E0 * (e + A * e * e + B * e * e * e)
    }
    fn slope(e: f64) -> f64 {
        E0 * (1.0 + 2.0 * A * e + 3.0 * B * e * e)
    }

    fn sampled(n: usize, top: f64) -> StressStrain {
        let points: Vec<[f64; 2]> = (0..n).map(|i| top * i as f64 / (n - 1) as f64).map(|e| [e, curve(e)]).collect();
        StressStrain::new(&points).unwrap()
    }

    #[test]
    fn reproduces_the_table_at_its_nodes_exactly() {
        let table = sampled(11, 0.05);
        for [e, s] in table.points() {
            assert_eq!(table.at(e).0.to_bits(), s.to_bits(), "sigma({e})");
        }
    }

    /// Between the nodes the error of a cubic Hermite interpolant is bounded
    /// by the error of its slopes plus that of exact Hermite interpolation:
    /// |err| <= (4/27) h (|d_k - f'_k| + |d_k+1 - f'_k+1|) + h^4/384 max|f''''|
    /// (here f'''' = 0). The measured error must stay inside that bound, and
    /// it must fall as the table gets finer.
    #[test]
    fn stays_within_the_interpolation_error_bound_between_nodes() {
        let mut previous = f64::INFINITY;
        for n in [6, 11, 21, 41] {
            let table = sampled(n, 0.05);
            let nodes: Vec<[f64; 2]> = table.points().collect();
            let mut worst: f64 = 0.0;
            for (k, w) in nodes.windows(2).enumerate() {
                let h = w[1][0] - w[0][0];
                let bound = 4.0 / 27.0 * h * ((table.slope[k] - slope(w[0][0])).abs() + (table.slope[k + 1] - slope(w[1][0])).abs());
                for j in 1..50 {
                    let e = w[0][0] + h * j as f64 / 50.0;
                    let err = (table.at(e).0 - curve(e)).abs();
                    assert!(err <= bound * (1.0 + 1e-9) + 1e-9 * curve(e), "n = {n}, eps = {e}: error {err} > bound {bound}");
                    worst = worst.max(err);
                }
            }
            assert!(worst < previous / 3.0, "n = {n}: error {worst} did not fall from {previous}");
            previous = worst;
        }
    }

    #[test]
    fn slope_is_continuous_at_the_nodes_and_the_ends_go_on_linearly() {
        let table = sampled(9, 0.04);
        for [e, _] in table.points() {
            let below = table.at(e - 1e-12).1;
            let above = table.at(e + 1e-12).1;
            assert!((below - above).abs() <= 1e-6 * above.abs(), "slope jumps at {e}: {below} vs {above}");
        }
        let (s_end, d_end) = table.at(0.04);
        assert_eq!(table.at(0.05), (s_end + d_end * (0.05 - 0.04), d_end));
        let (s0, d0) = table.at(0.0);
        assert_eq!(table.at(-0.01), (s0 + d0 * -0.01, d0));
    }

    /// The curvature is the slope's derivative: central differences of the
    /// tangent (step 1e-7 inside an interval of 5e-3: truncation ~ h^2 * 0 for
    /// a cubic, rounding ~ 1e-16 * E / 1e-7) agree to 1e-6 relative.
    #[test]
    fn curvature_is_the_derivative_of_the_tangent_modulus() {
        let table = sampled(11, 0.05);
        for eps in [0.0013, 0.0121, 0.0248, 0.0377, 0.0499] {
            let h = 1e-7;
            let fd = (table.at(eps + h).1 - table.at(eps - h).1) / (2.0 * h);
            let c = table.curvature(eps);
            assert!((c - fd).abs() <= 1e-6 * c.abs().max(E0), "{eps}: {c} vs {fd}");
        }
        assert_eq!(table.curvature(0.06), 0.0);
        assert_eq!(table.curvature(-0.01), 0.0);
    }

    #[test]
    fn a_linear_table_is_the_linear_law() {
        let e = 4.5e9;
        let table = StressStrain::new(&[[-0.01, -0.01 * e], [0.0, 0.0], [0.02, 0.02 * e]]).unwrap();
        for eps in [-0.02, -0.005, 0.0, 1e-4, 0.01, 0.03] {
            let (s, d) = table.at(eps);
            assert!((s - e * eps).abs() <= 1e-6 * e * 1e-4, "{eps}: {s}");
            assert!((d - e).abs() <= 1e-6 * e, "{eps}: {d}");
        }
        assert_eq!(table.steepest_chord(), e);
    }

    #[test]
    fn bad_tables_say_what_is_wrong() {
        for (points, want) in [
            (vec![[0.0, 0.0]], "at least 2"),
            (vec![[0.0, 0.0], [0.01, 1e6], [0.01, 2e6]], "increase strictly"),
            (vec![[0.0, 0.0], [0.02, 1e6], [0.01, 2e6]], "increase strictly"),
            (vec![[0.0, 0.0], [0.01, 2e6], [0.02, 1e6]], "must not decrease"),
            (vec![[0.001, 0.0], [0.01, 1e6]], "origin"),
            (vec![[0.0, 0.0], [0.01, f64::NAN]], "not finite"),
            (vec![[0.0, 0.0], [0.01, 0.0]], "no load"),
            (vec![[-1.0, -1e6], [0.0, 0.0]], "> -1"),
        ] {
            let e = StressStrain::new(&points).unwrap_err();
            assert!(e.contains(want), "{points:?}: {e}");
        }
    }
}
