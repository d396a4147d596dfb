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
    fn sin(self) -> Self {
        let x = self.value();
        self.map(x.sin(), x.cos())
    }
    #[inline]
    fn cos(self) -> Self {
        let x = self.value();
        self.map(x.cos(), -x.sin())
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

/// A value `x` and its derivatives `d` along L directions at once: one evaluation of the
/// right-hand side gives a whole set of tangents (a Jacobian's columns). Each lane follows
/// `Tangent`'s rules operation for operation, so each is bit for bit the `Tangent` along its direction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lanes<const L: usize> {
    pub x: f64,
    pub d: [f64; L],
}

impl<const L: usize> Default for Lanes<L> {
    #[inline(always)]
    fn default() -> Self {
        Lanes { x: 0.0, d: [0.0; L] }
    }
}

impl<const L: usize> Lanes<L> {
    /// The value x with derivative `d(k)` in lane k.
    #[inline(always)]
    pub fn new(x: f64, d: impl Fn(usize) -> f64) -> Lanes<L> {
        Lanes { x, d: std::array::from_fn(d) }
    }
}

impl<const L: usize> Number for Lanes<L> {
    #[inline(always)]
    fn constant(x: f64) -> Self {
        Lanes { x, d: [0.0; L] }
    }
    #[inline(always)]
    fn value(self) -> f64 {
        self.x
    }
    #[inline(always)]
    fn map(self, value: f64, slope: f64) -> Self {
        Lanes { x: value, d: self.d.map(|d| slope * d) }
    }
    #[inline]
    fn chain<const K: usize>(value: f64, gradient: &[f64; K], knowns: &[Self; K]) -> Self {
        Lanes::new(value, |l| gradient.iter().zip(knowns).map(|(g, k)| g * k.d[l]).sum())
    }
}

/// `Lanes`' arithmetic, lane by lane as `Tangent`'s.
macro_rules! lanes_op {
    ($trait:ident, $f:ident, |$a:ident, $b:ident| $x:expr, |$da:ident, $db:ident, $q:ident| $d:expr) => {
        impl<const L: usize> $trait for Lanes<L> {
            type Output = Lanes<L>;
            #[inline(always)]
            fn $f(self, o: Lanes<L>) -> Lanes<L> {
                let ($a, $b) = (self.x, o.x);
                let $q = $x;
                Lanes { x: $q, d: std::array::from_fn(|l| {
                    let ($da, $db) = (self.d[l], o.d[l]);
                    $d
                }) }
            }
        }
    };
}
lanes_op!(Add, add, |a, b| a + b, |da, db, _q| da + db);
lanes_op!(Sub, sub, |a, b| a - b, |da, db, _q| da - db);
lanes_op!(Mul, mul, |a, b| a * b, |da, db, _q| da * b + a * db);
lanes_op!(Div, div, |a, b| a / b, |da, db, q| (da - q * db) / b);

impl<const L: usize> Neg for Lanes<L> {
    type Output = Lanes<L>;
    #[inline(always)]
    fn neg(self) -> Lanes<L> {
        Lanes { x: -self.x, d: self.d.map(|d| -d) }
    }
}
impl<const L: usize> Add<f64> for Lanes<L> {
    type Output = Lanes<L>;
    #[inline(always)]
    fn add(self, o: f64) -> Lanes<L> {
        Lanes { x: self.x + o, d: self.d }
    }
}
impl<const L: usize> Sub<f64> for Lanes<L> {
    type Output = Lanes<L>;
    #[inline(always)]
    fn sub(self, o: f64) -> Lanes<L> {
        Lanes { x: self.x - o, d: self.d }
    }
}
impl<const L: usize> Mul<f64> for Lanes<L> {
    type Output = Lanes<L>;
    #[inline(always)]
    fn mul(self, o: f64) -> Lanes<L> {
        Lanes { x: self.x * o, d: self.d.map(|d| d * o) }
    }
}
impl<const L: usize> Div<f64> for Lanes<L> {
    type Output = Lanes<L>;
    #[inline(always)]
    fn div(self, o: f64) -> Lanes<L> {
        Lanes { x: self.x / o, d: self.d.map(|d| d / o) }
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

    /// Each lane is bit for bit the `Tangent` along its direction.
    #[test]
    fn lanes_are_tangents_side_by_side() {
        fn f<N: Number>(x: N, y: N) -> N {
            let z = x * y / (x + 1.0) - y * 0.5 + 3.0;
            (z.sqrt() + (x * 0.1).tanh() - y.powi(3) / 7.0) / (x - y * 2.0) - (-x) + N::chain(2.0, &[0.3, -1.1], &[x, y])
        }
        let (x, y) = (1.3, -0.4);
        let lanes = f(Lanes::<3>::new(x, |l| [1.0, 0.0, 0.25][l]), Lanes::<3>::new(y, |l| [0.0, 1.0, -2.0][l]));
        for (l, (dx, dy)) in [(1.0, 0.0), (0.0, 1.0), (0.25, -2.0)].into_iter().enumerate() {
            let t = f(Tangent::new(x, dx), Tangent::new(y, dy));
            assert_eq!((lanes.x.to_bits(), lanes.d[l].to_bits()), (t.x.to_bits(), t.d.to_bits()), "lane {l}");
        }
    }
}
