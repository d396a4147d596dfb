//! A table of a quantity against time: linear between entries, with jumps
//! where two entries share a time, constant outside.

/// Entries checked by [`Table::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    points: Vec<[f64; 2]>,
}

impl Table {
    pub fn new(points: Vec<[f64; 2]>) -> Result<Table, String> {
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
        Ok(Table { points })
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
        x0 + (x1 - x0) * ((t - t0) / (t1 - t0))
    }

    /// The value and the slope at `t` on the piece that ends there: at a jump, the value before
    /// it (the left limit), what a model shows at an event it has not yet applied; at a kink, the
    /// slope before it. A break less than `within` before `t` counts as at `t` (a communication
    /// point a few ulps past it). Outside the table: its end values, slope 0.
    pub fn before(&self, t: f64, within: f64) -> (f64, f64) {
        let i = self.reaching(t - within);
        (self.on_piece_ending_at(i, t), self.slope_of_piece_ending_at(i))
    }

    /// The slope of the piece that ends at entry `i` (0 outside the table).
    fn slope_of_piece_ending_at(&self, i: usize) -> f64 {
        if i == 0 || i == self.points.len() {
            return 0.0;
        }
        let ([t0, x0], [t1, x1]) = (self.points[i - 1], self.points[i]);
        (x1 - x0) / (t1 - t0)
    }

    /// The index of the first entry at `t` or later: the end of the piece that reaches `t`.
    fn reaching(&self, t: f64) -> usize {
        self.points.partition_point(|p| p[0] < t)
    }

    /// The slope on the piece that starts at `t` (0 outside the table).
    pub fn slope(&self, t: f64) -> f64 {
        self.slope_of_piece_ending_at(self.after(t))
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

    #[test]
    fn refuses_bad_tables() {
        assert!(Table::new(vec![]).is_err());
        assert!(Table::new(vec![[0.0, f64::NAN]]).unwrap_err().contains("finite"));
        assert!(Table::new(vec![[1.0, 0.0], [1.0, 1.0], [1.0, 2.0]]).unwrap_err().contains("three entries"));
    }
}
