//! A state kept as an unevaluated sum `hi + lo` (Knuth's TwoSum).
//!
//! Tiny increments added to a large value lose their low bits; over a
//! million small communication steps those losses would stall the state a
//! few parts in 1e11 short of its steady state. Carrying the rounding error
//! in `lo` keeps the state accurate to about one ulp of the increment.

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CompensatedSum {
    hi: f64,
    lo: f64,
}

impl CompensatedSum {
    /// `a + b` without rounding: the exact sum as `hi + lo`.
    pub fn two_sum(a: f64, b: f64) -> Self {
        let hi = a + b;
        let b_virtual = hi - a;
        let lo = (a - (hi - b_virtual)) + (b - b_virtual);
        CompensatedSum { hi, lo }
    }

    pub fn from_parts(hi: f64, lo: f64) -> Self {
        CompensatedSum { hi, lo }
    }

    pub fn hi(self) -> f64 {
        self.hi
    }

    pub fn lo(self) -> f64 {
        self.lo
    }

    /// The value rounded to one float.
    pub fn value(self) -> f64 {
        self.hi + self.lo
    }

    pub fn plus(self, increment: f64) -> Self {
        let sum = Self::two_sum(self.hi, increment);
        // Renormalize so that |lo| stays below half an ulp of hi.
        Self::two_sum(sum.hi, sum.lo + self.lo)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_increments_a_plain_sum_loses() {
        let mut plain = 1.0_f64;
        let mut compensated = CompensatedSum::from_parts(1.0, 0.0);
        for _ in 0..1_000_000 {
            plain += 1e-17;
            compensated = compensated.plus(1e-17);
        }
        assert_eq!(plain, 1.0, "a plain sum drops increments below half an ulp");
        let gained = (compensated.hi() - 1.0) + compensated.lo();
        assert!((gained - 1e-11).abs() < 1e-22, "compensated sum kept {gained}");
    }
}
