//! The number type the roller's equations are written in (`rhs`): plain `f64` for values, so that
//! `derivatives` pays nothing, and `Tangent` (a value and its derivative along one direction) for
//! the directional derivatives. A law written once for `Number` gives both.

use std::ops::{Add, Div, Mul, Neg, Sub};

/// A real number the equations can be evaluated in.
pub trait Number:
    Copy
    + Default
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Div<Output = Self>
    + Neg<Output = Self>
    + Add<f64, Output = Self>
    + Sub<f64, Output = Self>
    + Mul<f64, Output = Self>
    + Div<f64, Output = Self>
{
    fn constant(x: f64) -> Self;
    fn value(self) -> f64;
    /// f(self), given f's value and slope at `self.value()` (the chain rule).
    fn map(self, value: f64, slope: f64) -> Self;
    /// A function of K knowns, given its value and gradient there (the chain rule).
    fn chain<const K: usize>(value: f64, gradient: &[f64; K], knowns: &[Self; K]) -> Self;

    #[inline]
    fn sqrt(self) -> Self {
        let s = self.value().sqrt();
        self.map(s, 0.5 / s)
    }
    #[inline]
    fn tanh(self) -> Self {
        let t = self.value().tanh();
        self.map(t, 1.0 - t * t)
    }
    #[inline]
    fn powi(self, n: i32) -> Self {
        let x = self.value();
        self.map(x.powi(n), n as f64 * x.powi(n - 1))
    }
}

impl Number for f64 {
    #[inline(always)]
    fn constant(x: f64) -> f64 {
        x
    }
    #[inline(always)]
    fn value(self) -> f64 {
        self
    }
    #[inline(always)]
    fn map(self, value: f64, _: f64) -> f64 {
        value
    }
    #[inline(always)]
    fn chain<const K: usize>(value: f64, _: &[f64; K], _: &[f64; K]) -> f64 {
        value
    }
    // Without the slope f64 never needs: what `derivatives` runs.
    #[inline(always)]
    fn sqrt(self) -> f64 {
        f64::sqrt(self)
    }
    #[inline(always)]
    fn tanh(self) -> f64 {
        f64::tanh(self)
    }
    #[inline(always)]
    fn powi(self, n: i32) -> f64 {
        f64::powi(self, n)
    }
}

/// A value `x` and its derivative `d` along one direction.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Tangent {
    pub x: f64,
    pub d: f64,
}

impl Tangent {
    pub const fn new(x: f64, d: f64) -> Tangent {
        Tangent { x, d }
    }
}

impl Number for Tangent {
    #[inline(always)]
    fn constant(x: f64) -> Tangent {
        Tangent { x, d: 0.0 }
    }
    #[inline(always)]
    fn value(self) -> f64 {
        self.x
    }
    #[inline(always)]
    fn map(self, value: f64, slope: f64) -> Tangent {
        Tangent { x: value, d: slope * self.d }
    }
    #[inline]
    fn chain<const K: usize>(value: f64, gradient: &[f64; K], knowns: &[Tangent; K]) -> Tangent {
        Tangent { x: value, d: gradient.iter().zip(knowns).map(|(g, k)| g * k.d).sum() }
    }
}

impl Add for Tangent {
    type Output = Tangent;
    #[inline(always)]
    fn add(self, o: Tangent) -> Tangent {
        Tangent { x: self.x + o.x, d: self.d + o.d }
    }
}
impl Sub for Tangent {
    type Output = Tangent;
    #[inline(always)]
    fn sub(self, o: Tangent) -> Tangent {
        Tangent { x: self.x - o.x, d: self.d - o.d }
    }
}
impl Mul for Tangent {
    type Output = Tangent;
    #[inline(always)]
    fn mul(self, o: Tangent) -> Tangent {
        Tangent { x: self.x * o.x, d: self.d * o.x + self.x * o.d }
    }
}
impl Div for Tangent {
    type Output = Tangent;
    #[inline(always)]
    fn div(self, o: Tangent) -> Tangent {
        let q = self.x / o.x;
        Tangent { x: q, d: (self.d - q * o.d) / o.x }
    }
}
impl Neg for Tangent {
    type Output = Tangent;
    #[inline(always)]
    fn neg(self) -> Tangent {
        Tangent { x: -self.x, d: -self.d }
    }
}
impl Add<f64> for Tangent {
    type Output = Tangent;
    #[inline(always)]
    fn add(self, o: f64) -> Tangent {
        Tangent { x: self.x + o, d: self.d }
    }
}
impl Sub<f64> for Tangent {
    type Output = Tangent;
    #[inline(always)]
    fn sub(self, o: f64) -> Tangent {
        Tangent { x: self.x - o, d: self.d }
    }
}
impl Mul<f64> for Tangent {
    type Output = Tangent;
    #[inline(always)]
    fn mul(self, o: f64) -> Tangent {
        Tangent { x: self.x * o, d: self.d * o }
    }
}
impl Div<f64> for Tangent {
    type Output = Tangent;
    #[inline(always)]
    fn div(self, o: f64) -> Tangent {
        Tangent { x: self.x / o, d: self.d / o }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rules against a central difference of a function that uses each of them.
    #[test]
    fn tangents_follow_the_chain_rule() {
        fn f<N: Number>(x: N) -> N {
            let y = x * x / (x + 1.0) - x * 0.5 + 3.0;
            (y.sqrt() + (x * 0.1).tanh() - x.powi(3) / 7.0) / 2.0 - (-x)
        }
        let (x, h) = (1.3, 1e-6);
        let fd = (f(x + h) - f(x - h)) / (2.0 * h);
        let t = f(Tangent::new(x, 1.0));
        assert_eq!(t.x, f(x));
        assert!((t.d - fd).abs() < 1e-8, "{} vs {fd}", t.d);
    }
}
