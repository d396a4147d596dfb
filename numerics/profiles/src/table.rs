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
        let i = self.after(t);
        if i == 0 {
            return self.points[0][1];
        }
        if i == self.points.len() {
            return self.points[i - 1][1];
        }
        let ([t0, x0], [t1, x1]) = (self.points[i - 1], self.points[i]);
        x0 + (x1 - x0) * ((t - t0) / (t1 - t0))
    }

    /// The slope on the piece that starts at `t` (0 outside the table).
    pub fn slope(&self, t: f64) -> f64 {
        let i = self.after(t);
        if i == 0 || i == self.points.len() {
            return 0.0;
        }
        let ([t0, x0], [t1, x1]) = (self.points[i - 1], self.points[i]);
        (x1 - x0) / (t1 - t0)
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
    fn refuses_bad_tables() {
        assert!(Table::new(vec![]).is_err());
        assert!(Table::new(vec![[0.0, f64::NAN]]).unwrap_err().contains("finite"));
        assert!(Table::new(vec![[1.0, 0.0], [1.0, 1.0], [1.0, 2.0]]).unwrap_err().contains("three entries"));
    }
}
