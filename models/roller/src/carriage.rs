//! A dancer's carriage under the roller [R4], and where the webs touch the roller:
//!
//! [R4]  m*y'' = F_load + load - F_a - F_b - d*y' - k*(y - y_start)

use crate::number::Number;
use crate::parameters::Parameters;
use solver::expm;

/// [R4] over a piece of length h with the force `g0 + g1*s` (load minus the
/// spans' pull), exactly: exp of the augmented matrix acting on (y - y_start, y', 1, s).
pub fn step(p: &Parameters, state: [f64; 2], g0: f64, g1: f64, h: f64) -> [f64; 2] {
    let m = p.carriage_mass;
    let (k, d) = (p.carriage_stiffness / m, p.carriage_damping / m);
    let a = [
        [0.0, h, 0.0, 0.0],
        [-k * h, -d * h, g0 / m * h, g1 / m * h],
        [0.0, 0.0, 0.0, 0.0],
        [0.0, 0.0, h, 0.0],
    ];
    let e = expm(a);
    let z = [state[0] - p.carriage_start, state[1]];
    // (z, 1, s=0) at the start; the fourth column is never needed.
    let y = e[0][0] * z[0] + e[0][1] * z[1] + e[0][2];
    let v = e[1][0] * z[0] + e[1][1] * z[1] + e[1][2];
    [y + p.carriage_start, v]
}

/// The carriage's force [R4]: the load (input and table) minus every web's pull.
#[inline]
pub fn force<N: Number>(load: N, table: f64, pull_back: N, pull_forward: N) -> N {
    load + table - pull_back - pull_forward
}

/// The carriage's (dy/dt, dy'/dt) [R4] with the total force `g` (0 without a carriage, `g` not formed).
#[inline]
pub fn rates<N: Number>(p: &Parameters, y: N, speed: N, g: impl FnOnce() -> N) -> (N, N) {
    if !p.carriage {
        return (N::default(), N::default());
    }
    (speed, (g() - speed * p.carriage_damping - (y - p.carriage_start) * p.carriage_stiffness) / p.carriage_mass)
}

/// Where the webs touch the roller [R4]: web_b's x (web_a's is 0), at the roller's start position.
#[inline]
pub fn contact_b_x<N: Number>(radius: N) -> N {
    radius * 2.0
}

/// The contact points' height [R4], y up from the roller's start position: y_start - y.
#[inline]
pub fn contact_height<N: Number>(p: &Parameters, travel: N) -> N {
    N::constant(p.carriage_start) - travel
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_step_solves_the_damped_oscillator_exactly() {
        let p = Parameters { carriage_mass: 5.0, carriage_stiffness: 2000.0, carriage_damping: 30.0, carriage_start: 0.5, ..Parameters::default() };
        // Constant force g: equilibrium y_e = y_start + g/k; an underdamped approach.
        let (g, h) = (100.0, 0.05);
        let (m, k, d) = (p.carriage_mass, p.carriage_stiffness, p.carriage_damping);
        let (alpha, beta) = (d / (2.0 * m), (k / m - (d / (2.0 * m)).powi(2)).sqrt());
        let y_e = p.carriage_start + g / k;
        // From rest at y_start: y = y_e - (g/k) e^{-alpha t} (cos(beta t) + alpha/beta sin(beta t)).
        let exact = y_e - g / k * (-alpha * h).exp() * ((beta * h).cos() + alpha / beta * (beta * h).sin());
        let [y, _] = step(&p, [p.carriage_start, 0.0], g, 0.0, h);
        assert!((y - exact).abs() < 1e-14, "{y} {exact}");
    }
}
