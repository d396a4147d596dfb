//! Every solver against the exact solution, through the model core.
//!
//! Held inputs: the exact step is exact, so the other methods are measured
//! against it. Ramps given as input derivatives: the reference is the
//! integrating-factor solution of the linear balance, evaluated by
//! composite Gauss–Legendre quadrature (independent of every integrator).

use fmi_core::{Compiled, Experiment, Model};
use converting_span::description::Real;
use converting_span::ConvertingSpan;

fn span(solver: i32) -> ConvertingSpan {
    let mut m = ConvertingSpan::at_start_values();
    m.set_real_var(Real::L, 1.0).unwrap();
    m.set_real_var(Real::web_a_v, 5.0).unwrap();
    m.set_real_var(Real::web_a_eps, 1e-3).unwrap();
    m.set_real_var(Real::web_b_v, 5.0).unwrap();
    m.params.solver = fmi_core::IntegerValue::from_i32(solver).expect("a solver");
    m
}

/// Runs a draw step (web_b.v 5 -> 5.005) for 1 s with communication step h;
/// returns the worst relative strain error against the exact solver.
fn held_error(solver: i32, h: f64, tolerance: f64, substeps: i32) -> f64 {
    let mut reference = span(2);
    let mut m = span(solver);
    m.params.tolerance = tolerance;
    m.params.substeps = substeps;
    reference.initialize(&Experiment::default(), &Default::default()).unwrap();
    m.initialize(&Experiment::default(), &Default::default()).unwrap();
    for model in [&mut reference, &mut m] {
        model.set_real_var(Real::web_b_v, 5.005).unwrap();
    }
    let mut worst: f64 = 0.0;
    for _ in 0..(1.0 / h).round() as usize {
        reference.do_step(h).unwrap();
        m.do_step(h).unwrap();
        let (a, b) = (reference.outputs().forces.strain, m.outputs().forces.strain);
        worst = worst.max((a - b).abs() / a.abs());
    }
    worst
}

/// What the tolerance buys, measured on these scenes. The tolerance bounds
/// the local error per step (as in CVode or MATLAB's solvers), so the
/// global error is larger: dopri5 (order 5) stays within 100 * tol;
/// Rosenbrock 2(3) picks steps with h^3 ~ tol and has global error of
/// order h^2, i.e. about tol^(2/3).
fn global_error_bound(solver: i32, tol: f64) -> f64 {
    match solver {
        3 => tol.powf(2.0 / 3.0),
        _ => 100.0 * tol,
    }
}

#[test]
fn adaptive_solvers_meet_their_tolerance_on_held_inputs() {
    for (solver, name) in [(3, "rosenbrock"), (4, "dopri5")] {
        for tol in [1e-4, 1e-7, 1e-10] {
            let err = held_error(solver, 0.01, tol, 1);
            println!("{name} tol {tol:e}: worst relative strain error {err:.2e}");
            assert!(err <= global_error_bound(solver, tol), "{name} at tol {tol}: {err}");
        }
    }
}

#[test]
fn fixed_step_solvers_converge_at_their_order() {
    for (solver, name, order) in [(5, "rk4", 4.0), (6, "euler", 1.0)] {
        let coarse = held_error(solver, 0.01, 1e-8, 4);
        let fine = held_error(solver, 0.01, 1e-8, 8);
        let observed = (coarse / fine).log2();
        println!("{name}: error {coarse:.2e} -> {fine:.2e} with twice the substeps, order {observed:.2}");
        assert!((observed - order).abs() < 0.3, "{name}: observed order {observed}");
    }
}

/// x(t) for dx/dt = a - (vb0 + s t) x / L, x(0) = x0 (forward flow):
/// x(t) = exp(-P(t)) (x0 + a * int_0^t exp(P(r)) dr), P(t) = (vb0 t + s t^2/2)/L.
fn ramp_reference(l: f64, a: f64, vb0: f64, s: f64, x0: f64, t: f64) -> f64 {
    let p = |r: f64| (vb0 * r + 0.5 * s * r * r) / l;
    // 5-point Gauss–Legendre on 2000 panels: far below 1e-14 relative here.
    let nodes = [0.0, -0.538_469_310_105_683_1, 0.538_469_310_105_683_1, -0.906_179_845_938_664, 0.906_179_845_938_664];
    let weights = [0.568_888_888_888_888_9, 0.478_628_670_499_366_5, 0.478_628_670_499_366_5, 0.236_926_885_056_189_1, 0.236_926_885_056_189_1];
    let panels = 2000;
    let w = t / panels as f64;
    let mut integral = 0.0;
    for k in 0..panels {
        let mid = (k as f64 + 0.5) * w;
        for (n, g) in nodes.iter().zip(weights) {
            let r = mid + 0.5 * w * n;
            integral += 0.5 * w * g * (p(r) - p(t)).exp();
        }
    }
    x0 * (-p(t)).exp() + a * integral
}

#[test]
fn input_derivatives_are_followed_by_rosenbrock_and_dopri5() {
    // web_b.v ramps from 5 to 5.05 m/s over 1 s, given as a derivative.
    let (l, va, eps_a, vb0, slope) = (1.0, 5.0, 1e-3, 5.0, 0.05);
    for (solver, tol) in [(1, 1e-10), (3, 1e-10), (4, 1e-10)] {
        let mut m = span(solver);
        m.params.tolerance = tol;
        m.initialize(&Experiment::default(), &Default::default()).unwrap();
        let x0 = m.unstretched_length();
        let h = 0.05;
        let mut worst: f64 = 0.0;
        for k in 1..=20 {
            m.set_input_derivative(Real::web_b_v.vr(), slope).unwrap();
            m.do_step(h).unwrap();
            let t = k as f64 * h;
            assert!((m.real(Real::web_b_v) - (vb0 + slope * t)).abs() < 1e-12, "inputs move along the ramp");
            let x = ramp_reference(l, va / (1.0 + eps_a), vb0, slope, x0, t);
            let exact = l / x - 1.0;
            worst = worst.max((m.outputs().forces.strain - exact).abs() / exact.abs());
        }
        println!("solver {solver}: ramp, worst relative strain error {worst:.2e}");
        assert!(worst <= global_error_bound(if solver == 1 { 3 } else { solver }, tol), "solver {solver}: {worst}");
    }
}

#[test]
fn held_inputs_ignore_the_ramp_and_stay_exact() {
    // The same ramp without derivatives: the exact solver holds web_b.v.
    let mut m = span(1);
    m.initialize(&Experiment::default(), &Default::default()).unwrap();
    m.set_real_var(Real::web_b_v, 5.05).unwrap();
    m.do_step(0.3).unwrap();
    assert_eq!(m.real(Real::web_b_v), 5.05);
}

#[test]
fn explicit_solvers_refuse_unstable_steps_with_discard() {
    // 5 mm at 30 m/s: lambda = 6000/s; a 0.1 s step with 10 substeps is far
    // outside RK4's and Euler's stability regions.
    for solver in [5, 6] {
        let mut m = span(solver);
        m.set_real_var(Real::L, 5e-3).unwrap();
        for speed in [Real::web_a_v, Real::web_b_v] {
            m.set_real_var(speed, 30.0).unwrap();
        }
        m.initialize(&Experiment::default(), &Default::default()).unwrap();
        let before = m.clone();
        let err = m.do_step(0.1).unwrap_err();
        assert_eq!(err.status, fmi_core::Status::Discard);
        assert!(err.message.contains("substeps >= "), "{}", err.message);
        assert_eq!(m, before, "a refused step changes nothing");
    }
}

#[test]
fn dopri5_gives_up_with_discard_when_the_work_is_unbounded() {
    // lambda*h = 6e7: dopri5 would need ~2e7 steps; it must stop at the bound.
    let mut m = span(4);
    m.set_real_var(Real::L, 5e-3).unwrap();
    for speed in [Real::web_a_v, Real::web_b_v] {
        m.set_real_var(speed, 30.0).unwrap();
    }
    m.initialize(&Experiment::default(), &Default::default()).unwrap();
    m.set_real_var(Real::web_b_v, 30.03).unwrap();
    let before = m.clone();
    let err = m.do_step(1e4).unwrap_err();
    assert_eq!(err.status, fmi_core::Status::Discard);
    assert_eq!(m, before);
}

