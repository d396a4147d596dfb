//! A table of a quantity against time: linear between entries, or quadratic where an entry gives the
//! piece that ends there a second derivative (an S-curve's jerk phase), with jumps where two entries
//! share a time, constant outside.

/// Entries checked by [`Table::new`], and each piece's second derivative (`curvature[i]`: the piece
/// that ends at entry i; 0 linear).
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    points: Vec<[f64; 2]>,
    curvature: Vec<f64>,
}

impl Table {
    pub fn new(points: Vec<[f64; 2]>) -> Result<Table, String> {
        let curvature = vec![0.0; points.len()];
        Table::curved(points, curvature)
    }

    /// A table whose piece ending at entry i has the second derivative `curvature[i]` (its value
    /// x0 + b (t - t0) + q (t - t0)^2/2 through both entries); the first entry and a jump start none.
    pub fn curved(points: Vec<[f64; 2]>, curvature: Vec<f64>) -> Result<Table, String> {
        if curvature.len() != points.len() {
            return Err(format!("{} curvatures for {} entries", curvature.len(), points.len()));
        }
        for (i, q) in curvature.iter().enumerate() {
            if !q.is_finite() {
                return Err(format!("entry {i}: the curvature {q} must be finite"));
            }
            if *q != 0.0 && (i == 0 || points[i - 1][0] == points[i][0]) {
                return Err(format!("entry {i}: a curvature belongs to the piece that ends there, and none does (the first entry, or a jump)"));
            }
        }
        Table::checked(points, curvature)
    }

    fn checked(points: Vec<[f64; 2]>, curvature: Vec<f64>) -> Result<Table, String> {
        if points.is_empty() {
            return Err("a table needs at least one [time, value] entry".into());
        }
        for (i, [t, x]) in points.iter().enumerate() {
            if !(t.is_finite() && x.is_finite()) {
                return Err(format!("entry {i} [{t}, {x}] must hold finite numbers"));
            }
            if i > 0 && *t < points[i - 1][0] {
                return Err(format!("entry {i}: time {t} s comes before {} s (times must not decrease)", points[i - 1][0]));
            }
            if i > 1 && *t == points[i - 2][0] {
                return Err(format!("entry {i}: three entries at {t} s (a jump has two: before and after)"));
            }
        }
        Ok(Table { points, curvature })
    }

    pub fn points(&self) -> &[[f64; 2]] {
        &self.points
    }

    /// The index of the first entry later than `t`.
    fn after(&self, t: f64) -> usize {
        self.points.partition_point(|p| p[0] <= t)
    }

    /// The value at `t`; at a jump, the value after it.
    pub fn value(&self, t: f64) -> f64 {
        self.on_piece_ending_at(self.after(t), t)
    }

    /// The value at `t` on the piece that ends at entry `i` (constant outside the table).
    fn on_piece_ending_at(&self, i: usize, t: f64) -> f64 {
        if i == 0 {
            return self.points[0][1];
        }
        if i == self.points.len() {
            return self.points[i - 1][1];
        }
        let ([t0, x0], [t1, x1]) = (self.points[i - 1], self.points[i]);
        let q = self.curvature[i];
        if q == 0.0 {
            return x0 + (x1 - x0) * ((t - t0) / (t1 - t0));
        }
        let s = t - t0;
        x0 + s * ((x1 - x0) / (t1 - t0) - 0.5 * q * (t1 - t0)) + 0.5 * q * s * s
    }

    /// The value and the slope at `t` on the piece that ends there: at a jump, the value before
    /// it (the left limit), what a model shows at an event it has not yet applied; at a kink, the
    /// slope before it. A break less than `within` before `t` counts as at `t` (a communication
    /// point a few ulps past it). Outside the table: its end values, slope 0.
    pub fn before(&self, t: f64, within: f64) -> (f64, f64) {
        let i = self.reaching(t - within);
        (self.on_piece_ending_at(i, t), self.slope_of_piece_ending_at(i, t))
    }

    /// The slope at `t` of the piece that ends at entry `i` (0 outside the table).
    fn slope_of_piece_ending_at(&self, i: usize, t: f64) -> f64 {
        if i == 0 || i == self.points.len() {
            return 0.0;
        }
        let ([t0, x0], [t1, x1]) = (self.points[i - 1], self.points[i]);
        let q = self.curvature[i];
        (x1 - x0) / (t1 - t0) + q * ((t - t0) - 0.5 * (t1 - t0))
    }

    /// The second derivative on the piece that starts at `t` or reaches it (the larger in size where
    /// they differ): whether the slope moves there.
    pub fn curvature(&self, t: f64) -> f64 {
        let at = |i: usize| self.curvature.get(i).copied().filter(|_| i > 0).unwrap_or(0.0);
        let (a, b) = (at(self.after(t)), at(self.reaching(t)));
        if a.abs() >= b.abs() { a } else { b }
    }

    /// Whether a piece is quadratic.
    pub fn is_curved(&self) -> bool {
        self.curvature.iter().any(|&q| q != 0.0)
    }

    /// The index of the first entry at `t` or later: the end of the piece that reaches `t`.
    fn reaching(&self, t: f64) -> usize {
        self.points.partition_point(|p| p[0] < t)
    }

    /// The slope on the piece that starts at `t` (0 outside the table).
    pub fn slope(&self, t: f64) -> f64 {
        self.slope_of_piece_ending_at(self.after(t), t)
    }

    /// The first entry time later than `t`: where the piece that starts at `t` ends.
    pub fn next_break(&self, t: f64) -> Option<f64> {
        self.points.get(self.after(t)).map(|p| p[0])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_between_entries_constant_outside_and_right_continuous_at_jumps() {
        let t = Table::new(vec![[0.0, 0.0], [1.0, 2.0], [1.0, 5.0], [3.0, 5.0]]).unwrap();
        assert_eq!(t.value(-1.0), 0.0);
        assert_eq!(t.value(0.25), 0.5);
        assert_eq!(t.slope(0.25), 2.0);
        assert_eq!(t.value(1.0), 5.0);
        assert_eq!(t.slope(1.0), 0.0);
        assert_eq!(t.value(9.0), 5.0);
        assert_eq!(t.next_break(0.5), Some(1.0));
        assert_eq!(t.next_break(1.0), Some(3.0));
        assert_eq!(t.next_break(3.0), None);
        assert_eq!(Table::new(vec![[2.0, 7.0]]).unwrap().value(0.0), 7.0);
    }

    #[test]
    fn before_a_break_the_piece_that_ends_there() {
        let t = Table::new(vec![[0.0, 0.0], [1.0, 2.0], [1.0, 5.0], [3.0, 5.0], [4.0, 7.0]]).unwrap();
        assert_eq!(t.before(1.0, 0.0), (2.0, 2.0)); // the jump, from below
        assert_eq!((t.value(1.0), t.slope(1.0)), (5.0, 0.0));
        assert_eq!(t.before(3.0, 0.0), (5.0, 0.0)); // the kink, from below
        assert_eq!(t.slope(3.0), 2.0);
        assert_eq!(t.before(0.5, 0.0), (t.value(0.5), t.slope(0.5))); // inside a piece: the same
        assert_eq!(t.before(-1.0, 0.0), (0.0, 0.0));
        assert_eq!(t.before(9.0, 0.0), (7.0, 0.0));
        assert_eq!(t.before(4.0, 0.0), (7.0, 2.0));
        // A few ulps past the jump, within the tolerance: still before it.
        let past = 1.0 + 4.0 * f64::EPSILON;
        assert_eq!(t.before(past, 1e-9).1, 2.0);
        assert!((t.before(past, 1e-9).0 - 2.0).abs() < 1e-14);
        assert_eq!(t.before(past, 0.0).0, 5.0);
    }

    /// A quadratic piece: through both its entries, its slope the derivative of its value (central
    /// differences to 1e-9), its second derivative the curvature; the linear pieces as before.
    #[test]
    fn a_curved_piece_is_the_quadratic_through_its_entries() {
        let t = Table::curved(vec![[0.0, 1.0], [2.0, 3.0], [3.0, 4.0]], vec![0.0, 0.5, 0.0]).unwrap();
        assert_eq!(t.value(0.0), 1.0);
        assert!((t.before(2.0, 0.0).0 - 3.0).abs() < 1e-15);
        // x = 1 + b s + s^2/4 with b = 1 - 0.5: the slope 0.5 at 0 and 1.5 at 2.
        assert!((t.slope(0.0) - 0.5).abs() < 1e-15 && (t.before(2.0, 0.0).1 - 1.5).abs() < 1e-15);
        for s in [0.3, 1.0, 1.7] {
            let e = 1e-6;
            let fd = (t.value(s + e) - t.value(s - e)) / (2.0 * e);
            assert!((fd - t.slope(s)).abs() < 1e-9, "{s}: {fd} against {}", t.slope(s));
            assert!((t.value(s) - (1.0 + 0.5 * s + 0.25 * s * s)).abs() < 1e-15);
        }
        assert_eq!((t.curvature(1.0), t.curvature(2.0), t.curvature(2.5)), (0.5, 0.5, 0.0));
        assert_eq!(t.slope(2.5), 1.0);
        assert!(t.is_curved() && !Table::new(vec![[0.0, 1.0], [1.0, 2.0]]).unwrap().is_curved());
        assert!(Table::curved(vec![[0.0, 1.0], [1.0, 2.0]], vec![1.0, 0.0]).unwrap_err().contains("entry 0"));
        assert!(Table::curved(vec![[0.0, 1.0], [1.0, 2.0], [1.0, 3.0]], vec![0.0, 0.0, 1.0]).unwrap_err().contains("jump"));
    }

    #[test]
    fn refuses_bad_tables() {
        assert!(Table::new(vec![]).is_err());
        assert!(Table::new(vec![[0.0, f64::NAN]]).unwrap_err().contains("finite"));
        assert!(Table::new(vec![[1.0, 0.0], [1.0, 1.0], [1.0, 2.0]]).unwrap_err().contains("three entries"));
    }
}
