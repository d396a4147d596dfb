//! Hard cases through the model core (no FFI): the fast ones of
//! tests/python/test_hard_cases.py, against references written here from the
//! physics (shared/docs/physics.md), independent of the model's code.
//!
//! A case is a schedule: the inputs at t = 0 and a list of communication
//! steps (size, inputs set at the step's start, optional input derivatives).
//! The reference carries the state as xi = x/L0 - 1 (L0 the initial span
//! length), so that rounding is relative to the strain, not to L:
//! * held inputs: the closed form xi_inf + (xi - xi_inf) exp(-lambda h)
//!   (a short Taylor series of (1 - e^-z)/z for lambda h < 1e-2);
//! * inputs moving linearly within a step: the integrating-factor solution
//!   w(h) = int_0^h g(r) exp(-(P(h) - P(r))) dr, P = int lambda, evaluated by
//!   10-point Gauss–Legendre (composite outside, one panel inside), split
//!   where web_a.v changes sign (a kink of the balance);
//! * rk4/euler on held inputs: their exact discrete solution on the linear
//!   balance, xi_inf + (xi - xi_inf) R(-lambda h/n)^n with R the method's
//!   stability polynomial — the truncation error they are allowed.
//!
//! Every case asserts at every point: outputs finite, unstretched length
//! > 0, and |model - reference| <= rel*|ref| + floor, per solver:
//! * auto/exact, held inputs: 1e-12 + 1e-15 of strain (only rounding);
//! * rosenbrock (and auto with input derivatives): tol^(2/3), the global
//!   error of Rosenbrock 2(3) for a local tolerance tol (tests/span_solvers.rs);
//!   the floor is that times the run's largest strain (the error control is
//!   relative to the strain at each step's start);
//! * dopri5: 100 tol, floor likewise;
//! * rk4/euler, held: 1e-12 + 1e-15 plus 1.01 x |prediction - exact|;
//!   rk4 with moving inputs: 1e-9 (lambda h/n <= 0.01 there).
//! with tol = 1e-10 (the `tolerance` parameter) throughout.

use fmi2::{Experiment, Model, Status};
use converting_span::description::Real;
use converting_span::ConvertingSpan;

const TOL: f64 = 1e-10;
const AUTO: i32 = 1;
const EXACT: i32 = 2;
const ROSENBROCK: i32 = 3;
const DOPRI5: i32 = 4;
const RK4: i32 = 5;
const EULER: i32 = 6;
const ALL: [i32; 6] = [AUTO, EXACT, ROSENBROCK, DOPRI5, RK4, EULER];
const MOVING: [i32; 4] = [AUTO, ROSENBROCK, DOPRI5, RK4];

fn name(solver: i32) -> &'static str {
    ["", "auto", "exact", "rosenbrock", "dopri5", "rk4", "euler"][solver as usize]
}

fn limit(solver: i32) -> f64 {
    match solver {
        RK4 => 2.785,
        EULER => 2.0,
        _ => f64::INFINITY,
    }
}

// --------------------------------------------------------------------------
// Inputs and schedules

#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct U {
    va: f64,
    ea: f64,
    vb: f64,
    ax: f64,
    ay: f64,
    bx: f64,
    by: f64,
}

impl U {
    /// A line with the rollers at their start positions (0, 0) and (1, 0).
    fn line(va: f64, ea: f64, vb: f64) -> U {
        U { va, ea, vb, ax: 0.0, ay: 0.0, bx: 1.0, by: 0.0 }
    }

    fn at(&self, r: &U, t: f64) -> U {
        U {
            va: self.va + r.va * t,
            ea: self.ea + r.ea * t,
            vb: self.vb + r.vb * t,
            ax: self.ax + r.ax * t,
            ay: self.ay + r.ay * t,
            bx: self.bx + r.bx * t,
            by: self.by + r.by * t,
        }
    }

    fn values(&self) -> [(Real, f64); 7] {
        [
            (Real::web_a_v, self.va),
            (Real::web_a_eps, self.ea),
            (Real::web_b_v, self.vb),
            (Real::frame_a_x, self.ax),
            (Real::frame_a_y, self.ay),
            (Real::frame_b_x, self.bx),
            (Real::frame_b_y, self.by),
        ]
    }
}

#[derive(Clone, Copy, Debug)]
struct Step {
    h: f64,
    u: U,
    du: Option<U>,
}

/// Held segments: (steps, h, inputs).
fn held(segments: &[(usize, f64, U)]) -> Vec<Step> {
    segments.iter().flat_map(|&(n, h, u)| std::iter::repeat(Step { h, u, du: None }).take(n)).collect()
}

/// n steps of h with the inputs ramping at `rate` from `u0`, given as derivatives.
fn ramp(u0: U, rate: U, n: usize, h: f64) -> Vec<Step> {
    let mut u = u0;
    let mut steps = Vec::new();
    for _ in 0..n {
        steps.push(Step { h, u, du: Some(rate) });
        u = u.at(&rate, h);
    }
    steps
}

// --------------------------------------------------------------------------
// The model under test

fn model(solver: i32, setup: impl FnOnce(&mut ConvertingSpan)) -> ConvertingSpan {
    let mut m = ConvertingSpan::at_start_values();
    m.params.solver = fmi2::IntegerValue::from_i32(solver).expect("a solver");
    m.params.tolerance = TOL;
    setup(&mut m);
    m
}

#[derive(Clone, Copy, Debug, PartialEq)]
struct Out {
    strain: f64,
    tension: f64,
    exit_force: f64,
    length: f64,
    x: f64,
    m_web: f64,
}

fn read(m: &ConvertingSpan) -> Out {
    let o = m.outputs();
    Out {
        strain: o.strain,
        tension: o.tension,
        exit_force: o.exit_force,
        length: o.length,
        x: m.unstretched_length(),
        m_web: m.real(Real::m_web),
    }
}

struct Run {
    points: Vec<Out>,
    /// (index of the refused step, message)
    discard: Option<(usize, String)>,
}

fn set_inputs(m: &mut ConvertingSpan, u: &U) {
    for (var, x) in u.values() {
        m.set_real_var(var, x).unwrap();
    }
}

/// Runs the schedule: outputs at t = 0 and after each step. A step refused
/// with Discard ends the run; it must leave the model exactly as it was.
fn run(m: &mut ConvertingSpan, initial: U, steps: &[Step]) -> Run {
    set_inputs(m, &initial);
    m.initialize(&Experiment::default()).unwrap();
    let mut points = vec![read(m)];
    for (k, s) in steps.iter().enumerate() {
        set_inputs(m, &s.u);
        if let Some(du) = s.du {
            for (var, x) in du.values() {
                m.set_input_derivative(var.vr(), x).unwrap();
            }
        }
        let before = m.clone();
        if let Err(e) = m.do_step(s.h) {
            assert_eq!(e.status, Status::Discard, "step {k}: {}", e.message);
            assert_eq!(*m, before, "a refused step changes nothing");
            return Run { points, discard: Some((k, e.message)) };
        }
        points.push(read(m));
    }
    for (i, o) in points.iter().enumerate() {
        for (what, v) in [("strain", o.strain), ("T", o.tension), ("web_b.F", o.exit_force), ("L", o.length), ("m_web", o.m_web)] {
            assert!(v.is_finite(), "{what} not finite at point {i}: {v}");
        }
        assert!(o.x > 0.0 && o.x.is_finite(), "unstretched length {} at point {i}", o.x);
    }
    Run { points, discard: None }
}

// --------------------------------------------------------------------------
// The reference

/// The parameters the reference needs, from the model's parameter values.
#[derive(Clone, Copy, Debug)]
struct P {
    l: f64,
    variable: bool,
    stiffness: f64,
    rho1: f64,
    rho2: f64,
    d_r: f64,
    damping: bool,
    mass: bool,
    slack: bool,
    equilibrium: bool,
    eps_start: f64,
}

fn params_of(m: &ConvertingSpan) -> P {
    let (w1, w2) = (&m.params.incoming, &m.params.span_web);
    P {
        l: m.params.span_length,
        variable: m.params.variable_length,
        stiffness: w2.modulus * w2.thickness * w2.width,
        rho1: w1.density * w1.thickness * w1.width,
        rho2: w2.density * w2.thickness * w2.width,
        d_r: w2.retardation_time,
        damping: m.params.include_damping,
        mass: m.params.include_mass,
        slack: m.params.prevent_negative_tension,
        equilibrium: m.params.start_at_equilibrium,
        eps_start: m.params.strain_start,
    }
}

fn length(p: &P, u: &U) -> f64 {
    if p.variable {
        (u.bx - u.ax).hypot(u.by - u.ay)
    } else {
        p.l
    }
}

/// (a, lambda) of the balance in xi = x/l0 - 1: dxi/dt = a - lambda*xi.
/// Forward flow: dx/dt = v_a/(1+eps_a) - v_b x/L; reverse at a (v_a < 0):
/// web leaves through a with the span's strain, dx/dt = (v_a - v_b) x/L.
fn balance(p: &P, u: &U, l0: f64) -> (f64, f64) {
    let l = length(p, u);
    if u.va >= 0.0 {
        let lam = u.vb / l;
        let c = l0 / l;
        // (q - lambda*l0)/l0 with q = va/(1+ea), formed without cancellation when c = 1
        (((u.va - u.vb * c) - u.vb * c * u.ea) / ((1.0 + u.ea) * l0), lam)
    } else {
        let lam = (u.vb - u.va) / l;
        (-lam, lam)
    }
}

#[derive(Clone, Copy)]
enum Method {
    Exact,
    Rk4(usize),
    Euler(usize),
}

fn held_step(a: f64, lam: f64, xi: f64, h: f64, method: Method) -> f64 {
    let z = lam * h;
    let r = match method {
        Method::Exact => {
            if z.abs() < 1e-2 {
                // (1 - e^-z)/z = 1 - z/2 + z^2/6 - z^3/24 + z^4/120 - z^5/720
                let e = 1.0 - z / 2.0 + z * z / 6.0 - z.powi(3) / 24.0 + z.powi(4) / 120.0 - z.powi(5) / 720.0;
                return xi + (a - lam * xi) * h * e;
            }
            (-z).exp()
        }
        Method::Rk4(n) => {
            let w = -z / n as f64;
            (1.0 + w + w * w / 2.0 + w.powi(3) / 6.0 + w.powi(4) / 24.0).powi(n as i32)
        }
        Method::Euler(n) => (1.0 - z / n as f64).powi(n as i32),
    };
    if lam == 0.0 {
        return xi + a * h;
    }
    let inf = a / lam;
    inf + (xi - inf) * r
}

const GL_X: [f64; 5] = [0.148_874_338_981_631_2, 0.433_395_394_129_247_2, 0.679_409_568_299_024_4, 0.865_063_366_688_984_5, 0.973_906_528_517_171_7];
const GL_W: [f64; 5] = [0.295_524_224_714_752_9, 0.269_266_719_309_996_3, 0.219_086_362_515_982_0, 0.149_451_349_150_580_6, 0.066_671_344_308_688_1];

/// 10-point Gauss–Legendre of f over [a, b].
fn gauss(a: f64, b: f64, f: impl Fn(f64) -> f64) -> f64 {
    let (mid, half) = (0.5 * (a + b), 0.5 * (b - a));
    let mut sum = 0.0;
    for (x, w) in GL_X.iter().zip(GL_W) {
        sum += w * (f(mid - half * x) + f(mid + half * x));
    }
    half * sum
}

/// xi after a step with inputs moving linearly: w = xi - xi_k obeys
/// dw/dt = g - lambda w, g = a - lambda xi_k; integrating factor by quadrature.
fn moving_step(p: &P, u: &U, du: &U, xi: f64, h: f64, l0: f64) -> f64 {
    let lam = |t: f64| balance(p, &u.at(du, t), l0).1;
    let g = |t: f64| {
        let (a, l) = balance(p, &u.at(du, t), l0);
        a - l * xi
    };
    let mut cuts = vec![0.0, h];
    if du.va != 0.0 {
        let tc = -u.va / du.va;
        if tc > 0.0 && tc < h {
            cuts = vec![0.0, tc, h];
        }
    }
    let mut w = 0.0;
    for piece in cuts.windows(2) {
        let (t0, t1) = (piece[0], piece[1]);
        let total = gauss(t0, t1, lam);
        // exp(-(P(t1) - P(r))) = exp(-(total - int_t0^r lambda))
        let panels = 4;
        let width = (t1 - t0) / panels as f64;
        let mut integral = 0.0;
        for k in 0..panels {
            let a = t0 + k as f64 * width;
            integral += gauss(a, a + width, |r| g(r) * (-(total - gauss(t0, r, lam))).exp());
        }
        w = w * (-total).exp() + integral;
    }
    xi + w
}

#[derive(Clone, Copy, Debug)]
struct Ref {
    strain: f64,
    tension: f64,
    exit_force: f64,
    length: f64,
    m_web: f64,
}

/// Outputs for xi, inputs u and input rates (dv_b/dt, dL/dt).
fn outputs(p: &P, u: &U, xi: f64, l0: f64, rates: (f64, f64)) -> Ref {
    let l = length(p, u);
    let x = l0 * (1.0 + xi);
    let strain = ((l - l0) - l0 * xi) / (l0 * (1.0 + xi));
    let (a, lam) = balance(p, u, l0);
    let dxdt = l0 * (a - lam * xi);
    let mut effective = strain;
    if p.damping {
        let deps = rates.1 / x - (1.0 + strain) * (1.0 + strain) / l * dxdt;
        effective += p.d_r * deps;
    }
    let mut tension = p.stiffness * effective;
    if p.slack {
        tension = tension.max(0.0);
    }
    let mut exit_force = tension;
    if p.mass {
        let (qa, rho_in) = if u.va >= 0.0 { (u.va / (1.0 + u.ea), p.rho1) } else { (u.va * x / l, p.rho2) };
        exit_force += qa * (p.rho2 * u.vb - rho_in * u.va) + p.rho2 * x * rates.0;
    }
    Ref { strain, tension, exit_force, length: l, m_web: p.rho2 * x }
}

fn length_rate(p: &P, u: &U, du: &U) -> f64 {
    if !p.variable {
        return 0.0;
    }
    let (dx, dy) = (u.bx - u.ax, u.by - u.ay);
    (dx * (du.bx - du.ax) + dy * (du.by - du.ay)) / dx.hypot(dy)
}

/// Reference outputs at t = 0 and after each step. The input rates in the
/// outputs: the derivatives given for the step, else backward differences
/// over the previous step (0 after the first), the documented estimate.
fn reference(p: &P, initial: U, steps: &[Step], method: Method) -> Vec<Ref> {
    let l0 = length(p, &initial);
    let eps0 = if p.equilibrium {
        if initial.va == 0.0 {
            initial.ea
        } else {
            (initial.vb - initial.va + initial.vb * initial.ea) / initial.va
        }
    } else {
        p.eps_start
    };
    let mut xi = -eps0 / (1.0 + eps0);
    let mut out = vec![outputs(p, &initial, xi, l0, (0.0, 0.0))];
    let mut prev: Option<(U, f64)> = None;
    for s in steps {
        let moving = s.du.is_some_and(|d| d != U::default());
        xi = if moving {
            assert!(matches!(method, Method::Exact), "fixed-step predictions cover held inputs only");
            moving_step(p, &s.u, &s.du.unwrap(), xi, s.h, l0)
        } else {
            let (a, lam) = balance(p, &s.u, l0);
            held_step(a, lam, xi, s.h, method)
        };
        let end = s.u.at(&s.du.unwrap_or_default(), s.h);
        let rates = match (s.du, prev) {
            (Some(du), _) => (du.vb, length_rate(p, &end, &du)),
            (None, Some((pu, ph))) => ((s.u.vb - pu.vb) / ph, (length(p, &s.u) - length(p, &pu)) / ph),
            (None, None) => (0.0, 0.0),
        };
        prev = Some((s.u, s.h));
        out.push(outputs(p, &end, xi, l0, rates));
    }
    out
}

// --------------------------------------------------------------------------
// Comparison

#[derive(Clone, Copy, Default)]
struct Quantities {
    exit_force: bool,
    m_web: bool,
    length: bool,
}

const TS: Quantities = Quantities { exit_force: false, m_web: false, length: false };
const WITH_FORCES: Quantities = Quantities { exit_force: true, m_web: true, length: false };

/// (rel, floor in strain) of a solver; see the module comment.
fn tolerance(solver: i32, moving: bool, strain_scale: f64) -> (f64, f64) {
    match solver {
        AUTO | EXACT if !moving => (1e-12, 1e-15),
        RK4 | EULER if !moving => (1e-12, 1e-15),
        RK4 => (1e-9, 1e-9 * strain_scale),
        DOPRI5 => (100.0 * TOL, 100.0 * TOL * strain_scale),
        _ => (TOL.powf(2.0 / 3.0), TOL.powf(2.0 / 3.0) * strain_scale),
    }
}

/// Runs and checks a case; returns the worst relative error of T and strain
/// (points at >= 1 % of the run's largest value) and prints it.
fn check(case: &str, solver: i32, mut m: ConvertingSpan, initial: U, steps: &[Step], q: Quantities, force_factor: f64) -> (Run, Vec<Ref>) {
    let p = params_of(&m);
    let r = run(&mut m, initial, steps);
    assert!(r.discard.is_none(), "{case} [{}]: refused: {:?}", name(solver), r.discard);
    let exact = reference(&p, initial, steps, Method::Exact);
    let moving = steps.iter().any(|s| s.du.is_some());
    let predicted = match solver {
        RK4 if !moving => Some(reference(&p, initial, steps, Method::Rk4(m.params.substeps as usize))),
        EULER if !moving => Some(reference(&p, initial, steps, Method::Euler(m.params.substeps as usize))),
        _ => None,
    };
    assert!(!(solver == EULER && moving), "euler is not compared on moving inputs");
    let scale = exact.iter().map(|r| r.strain.abs()).fold(0.0, f64::max);
    let (rel, floor) = tolerance(solver, moving, scale);
    let big_t = exact.iter().map(|r| r.tension.abs()).fold(0.0, f64::max) / 100.0;
    let mut worst: f64 = 0.0;
    for (i, (got, want)) in r.points.iter().zip(&exact).enumerate() {
        let pred = predicted.as_ref().map(|p| p[i]);
        let mut items = vec![
            ("T", got.tension, want.tension, pred.map(|p| p.tension), p.stiffness * force_factor),
            ("strain", got.strain, want.strain, pred.map(|p| p.strain), 1.0),
        ];
        if q.exit_force {
            items.push(("web_b.F", got.exit_force, want.exit_force, pred.map(|p| p.exit_force), p.stiffness * force_factor));
        }
        if q.m_web {
            items.push(("m_web", got.m_web, want.m_web, pred.map(|p| p.m_web), p.rho2 * p.l));
        }
        if q.length {
            items.push(("L", got.length, want.length, pred.map(|p| p.length), p.l));
        }
        for (what, g, w, pr, unit) in items {
            let allowance = pr.map_or(0.0, |pr| 1.01 * (pr - w).abs());
            let tol = rel * w.abs() + floor * unit + allowance;
            assert!(
                (g - w).abs() <= tol,
                "{case} [{}] point {i}: {what} = {g:e}, reference {w:e}, error {:.3e} > tolerance {tol:.3e}",
                name(solver),
                (g - w).abs()
            );
            let significant = if what == "T" { big_t } else { scale / 100.0 };
            if (what == "T" || what == "strain") && w.abs() >= significant && w.abs() > floor * unit {
                worst = worst.max((g - w).abs() / w.abs());
            }
        }
    }
    println!("{case:48} {:11} worst relative error {worst:.2e}", name(solver));
    (r, exact)
}

fn pet(va: f64, vb: f64) -> U {
    U::line(va, 1e-3, vb)
}

// --------------------------------------------------------------------------
// 1. A 5 mm span at 30 m/s

// lambda = 6000/s, lambda*h from 0.06 to 6000: a draw, a release with a new
// eps_a, a change of web_a.v. Each solver agrees with the closed form
// (tolerance per solver, module comment) or, for rk4/euler exactly when
// lambda*h/substeps exceeds the stability limit, refuses the first step with
// Discard and changes nothing (asserted in `run`).
#[test]
fn short_fast_span_5mm_at_30mps_every_solver_steps_1e_5_to_1s() {
    let lam = 30.03 / 5e-3;
    for solver in ALL {
        for h in [1e-5, 1e-4, 1e-3, 3e-3, 1e-2, 0.1, 1.0] {
            let m = model(solver, |m| m.set_real_var(Real::L, 5e-3).unwrap());
            let u0 = pet(30.0, 30.0);
            let steps = held(&[
                (12, h, pet(30.0, 30.03)),
                (12, h, U { ea: 2e-3, ..pet(30.0, 29.97) }),
                (8, h, U { ea: 2e-3, ..pet(29.94, 29.97) }),
            ]);
            let refuse = lam * h / 10.0 > limit(solver);
            if refuse {
                let mut m = m;
                let r = run(&mut m, u0, &steps);
                let (k, message) = r.discard.expect("an unstable explicit step must be refused");
                assert_eq!(k, 0);
                assert!(message.contains("substeps >= "), "{message}");
            } else {
                check(&format!("5 mm at 30 m/s, h = {h:e}"), solver, m, u0, &steps, TS, 1.0);
            }
        }
    }
}

// rk4/euler accepted at (1 - 1e-6) x their limit (tolerance: their stability
// polynomial's truncation error, module comment) and refused at (1 + 1e-6) x;
// dopri5 accepts a 10 s step of the 5 mm span (~2e4 internal steps, 100 tol)
// and refuses 1e4 s (~2e7 steps, beyond its 1e5 bound).
#[test]
fn explicit_solvers_refuse_just_beyond_their_limit_and_dopri5_beyond_its_work_bound() {
    let lam = 30.03 / 5e-3;
    let u0 = pet(30.0, 30.0);
    for solver in [RK4, EULER, DOPRI5] {
        let (ok, refused) = if solver == DOPRI5 {
            (10.0, 1e4)
        } else {
            let edge = limit(solver) * 10.0 / lam;
            (edge * (1.0 - 1e-6), edge * (1.0 + 1e-6))
        };
        let m = model(solver, |m| m.set_real_var(Real::L, 5e-3).unwrap());
        check("edge of stability", solver, m.clone(), u0, &held(&[(6, ok, pet(30.0, 30.03))]), TS, 1.0);
        let mut m = m;
        let r = run(&mut m, u0, &held(&[(1, refused, pet(30.0, 30.03))]));
        assert!(r.discard.is_some(), "{}: h = {refused} accepted", name(solver));
    }
}

#[test]
fn explicit_solvers_refuse_when_lambda_peaks_inside_the_step() {
    // frame_b crosses the span's line in one step: L = 0.583 m at both ends,
    // 0.3 m in the middle; lambda*h/substeps at the ends 0.72 (rk4) / 0.74
    // (euler) of the limit, 1.94x that mid-step.
    for (solver, fraction) in [(RK4, 0.72), (EULER, 0.74)] {
        let l_end = 0.3f64.hypot(0.5);
        let h = fraction * limit(solver) * 10.0 * l_end / 30.03;
        let mut m = model(solver, |m| m.params.variable_length = true);
        let u0 = U { bx: 0.3, by: -0.5, ..pet(30.0, 30.03) };
        let r = run(&mut m, u0, &[Step { h, u: u0, du: Some(U { by: 1.0 / h, ..U::default() }) }]);
        assert!(r.discard.is_some(), "{}: accepted with strain {}", name(solver), r.points.last().unwrap().strain);
    }
}

// --------------------------------------------------------------------------
// 2. Stopped line, stop and restart, speeds through zero, reverse

// Both speeds 0, damping on, from eps_start = 5e-3, steps 1e-6 .. 1e3 s:
// dx/dt = 0 exactly, so the state and the tension hold bit for bit
// (tolerance 0) for every solver.
#[test]
fn stopped_line_holds_its_state_bit_for_bit_for_every_solver() {
    for solver in ALL {
        let m = model(solver, |m| {
            m.params.include_damping = true;
            m.params.start_at_equilibrium = false;
            m.set_real_var(Real::eps_start, 5e-3).unwrap();
        });
        let u0 = U::line(0.0, 2e-3, 0.0);
        let steps: Vec<Step> = [1e-6, 1e-4, 1e-2, 1.0, 1e3].iter().flat_map(|&h| held(&[(3, h, u0)])).collect();
        let (r, _) = check("stopped line", solver, m, u0, &steps, TS, 1.0);
        assert!(r.points.iter().all(|o| o.x.to_bits() == r.points[0].x.to_bits() && o.tension.to_bits() == r.points[0].tension.to_bits()));
    }
}

// Held: decelerating in steps to a stop, 0.3 s standing, restart to 3 m/s.
// Ramps (derivatives, web mass): 5 -> 0 m/s in 0.5 s, 0.2 s standing (held),
// 0 -> 4 m/s; web_b.F switches between given and estimated dv_b/dt.
// Tolerance per solver (module comment).
#[test]
fn line_stops_and_restarts() {
    for solver in ALL {
        let m = model(solver, |_| {});
        let mut segs = vec![(50, 1e-3, pet(5.0, 5.005))];
        for v in [4.0, 3.0, 2.0, 1.0, 0.5, 0.1] {
            segs.push((20, 1e-3, pet(v, v * 1.001)));
        }
        segs.push((30, 1e-2, pet(0.0, 0.0)));
        segs.push((200, 1e-3, pet(3.0, 3.0 * 1.002)));
        check("line stops and restarts (held)", solver, m, pet(5.0, 5.0), &held(&segs), TS, 1.0);
    }
    for solver in MOVING {
        let m = model(solver, mass);
        let u0 = pet(5.0, 5.005);
        let mut steps = ramp(u0, U { va: -10.0, vb: -10.01, ..U::default() }, 50, 0.01);
        steps.extend(held(&[(20, 0.01, pet(0.0, 0.0))]));
        steps.extend(ramp(pet(0.0, 0.0), U { va: 8.0, vb: 8.016, ..U::default() }, 50, 0.01));
        check("line stops and restarts (ramps)", solver, m, u0, &steps, WITH_FORCES, 1.0);
    }
}

// web_a.v = 0.5 m/s, web_b.v 0.5 -> -0.5 and -0.5 -> 1.5 m/s: held in nine
// steps including v_b = 0 exactly, and as ramps. With v_b < 0 web enters from
// both ends (lambda < 0): strains down to -0.33. Tolerance per solver.
#[test]
fn web_b_speed_through_zero_in_both_directions() {
    for (from, to) in [(0.5, -0.5), (-0.5, 1.5)] {
        let u0 = U::line(0.5, 1e-3, from);
        let setup = |m: &mut ConvertingSpan| {
            m.set_real_var(Real::L, 2.0).unwrap();
            m.params.start_at_equilibrium = false;
            m.set_real_var(Real::eps_start, 1e-3).unwrap();
        };
        let segs: Vec<(usize, f64, U)> = (0..9).map(|k| (50, 4e-3, U { vb: from + (to - from) * k as f64 / 8.0, ..u0 })).collect();
        assert!(segs.iter().any(|s| s.2.vb == 0.0));
        for solver in ALL {
            let (r, _) = check(&format!("v_b {from} -> {to} (held)"), solver, model(solver, setup), u0, &held(&segs), TS, 1.0);
            assert!(r.points.iter().any(|o| o.strain < -0.05), "web fed from both ends: the strain falls");
        }
        for solver in MOVING {
            let steps = ramp(u0, U { vb: to - from, ..U::default() }, 100, 0.01);
            check(&format!("v_b {from} -> {to} (ramp)"), solver, model(solver, setup), u0, &steps, TS, 1.0);
        }
    }
}

// Both speeds -2 m/s (strain held: dx/dt = (v_a - v_b) x/L = 0), a reverse
// draw, v_a through 0 to forward; a ramp of both speeds through 0 (the
// reference splits the step at v_a = 0). Web mass: web leaving through a
// carries rho_l2. Tolerance per solver on T, strain, web_b.F, m_web.
#[test]
fn web_a_speed_negative_reverse_running_line() {
    let setup = |m: &mut ConvertingSpan| {
        m.set_real_var(Real::L, 0.5).unwrap();
        mass(m);
    };
    let u0 = pet(-2.0, -2.0);
    let segs = [
        (40, 5e-3, u0),
        (100, 5e-3, pet(-2.004, -2.0)),
        (40, 5e-3, pet(-0.5, -0.5005)),
        (40, 5e-3, pet(0.0, -5e-4)),
        (100, 5e-3, pet(1.0, 1.001)),
    ];
    for solver in ALL {
        let (r, _) = check("v_a negative (held)", solver, model(solver, setup), u0, &held(&segs), WITH_FORCES, 1.0);
        assert_eq!(r.points[40].strain, r.points[0].strain, "v_a = v_b < 0 holds the strain");
    }
    for solver in MOVING {
        let u1 = pet(-1.0, -1.001);
        let steps = ramp(u1, U { va: 1.5, vb: 1.5015, ..U::default() }, 100, 0.01);
        check("v_a ramp through zero", solver, model(solver, setup), u1, &steps, WITH_FORCES, 1.0);
    }
}

// --------------------------------------------------------------------------
// 3. Slack

// preventNegativeTension: 1 % overfeed takes the strain to -9e-3 (T = 0),
// a 0.3 % draw brings it back; with d_r = 0.05 s the damping term
// re-tensions before the strain is positive. Tolerance per solver.
#[test]
fn slack_and_retension_with_and_without_damping() {
    for damping in [false, true] {
        for solver in ALL {
            let m = model(solver, |m| {
                m.params.prevent_negative_tension = true;
                m.params.include_damping = damping;
                m.set_real_var(Real::wp2_d_r, 0.05).unwrap();
            });
            let steps = held(&[(100, 2e-3, pet(5.0, 4.95)), (250, 2e-3, pet(5.0, 5.015))]);
            // damping: an error in x reaches T through dx/dt too, x (1 + d_r lambda) = 1.25
            let factor = if damping { 1.25 } else { 1.0 };
            let (r, exact) = check(&format!("slack, damping {damping}"), solver, m, pet(5.0, 5.0), &steps, TS, factor);
            assert!(r.points.iter().all(|o| o.tension >= 0.0));
            assert!(r.points.iter().any(|o| o.strain < -5e-3) && r.points.last().unwrap().strain > 1e-3);
            for (o, e) in r.points.iter().zip(&exact) {
                if e.tension == 0.0 && e.strain < -1e-4 && !damping {
                    assert_eq!(o.tension, 0.0);
                }
            }
            if damping {
                assert!(r.points.iter().any(|o| o.tension > 0.0 && o.strain < 0.0), "damping re-tensions first");
            }
        }
    }
}

// --------------------------------------------------------------------------
// 4. Web mass

fn mass(m: &mut ConvertingSpan) {
    m.params.include_mass = true;
    m.set_real_var(Real::wp1_density, 1390.0).unwrap();
    m.set_real_var(Real::wp2_density, 2700.0).unwrap();
    m.set_real_var(Real::wp2_thickness, 80e-6).unwrap();
}

// includeMass, wp2 heavier than wp1: 2 -> 6 m/s in 1 s with 0.2 % draw, as
// derivatives (dv_b/dt given) and sampled-and-held (backward differences =
// the slope from the second step on, checked to 1e-9: the difference of
// ~2e3 N forces resolves ~1e-12 N of a ~1 N inertia). Tolerance per solver.
#[test]
fn web_mass_speed_ramp_with_and_without_input_derivatives() {
    let u0 = pet(2.0, 2.004);
    let rate = U { va: 4.0, vb: 4.008, ..U::default() };
    for solver in MOVING {
        check("web mass, ramp as derivatives", solver, model(solver, mass), u0, &ramp(u0, rate, 100, 0.01), WITH_FORCES, 1.0);
    }
    // sampled and held: dv_b/dt from backward differences, = the slope from the second step on
    let steps: Vec<Step> = (0..100).map(|k| Step { h: 0.01, u: u0.at(&rate, k as f64 * 0.01), du: None }).collect();
    for solver in ALL {
        let (r, _) = check("web mass, held ramp", solver, model(solver, mass), u0, &steps, WITH_FORCES, 1.0);
        let (rho1, rho2) = (1390.0 * 50e-6, 2700.0 * 80e-6);
        for k in [2, 50, 100] {
            let u = steps[k - 1].u;
            let flux = u.va / (1.0 + u.ea) * (rho2 * u.vb - rho1 * u.va);
            let inertia = r.points[k].exit_force - r.points[k].tension - flux;
            let want = r.points[k].m_web * 4.008;
            assert!((inertia - want).abs() <= 1e-9 * want, "point {k}: inertia {inertia}, m dv/dt {want}");
        }
    }
}

// --------------------------------------------------------------------------
// 5. Dancer

fn dancer(f: f64, t: f64) -> U {
    let w = 2.0 * std::f64::consts::PI * f;
    U { ax: 0.0, ay: 0.01 * (w * t).sin(), bx: 1.0 + 0.2 * (w * t).sin(), by: 0.05 * (1.0 - (w * t).cos()), ..pet(5.0, 5.005) }
}

fn dancer_steps(f: f64, derivatives: bool) -> Vec<Step> {
    let h = 2.0 / f / 200.0;
    (0..200)
        .map(|k| {
            let (a, b) = (dancer(f, k as f64 * h), dancer(f, (k + 1) as f64 * h));
            let du = U { ax: (b.ax - a.ax) / h, ay: (b.ay - a.ay) / h, bx: (b.bx - a.bx) / h, by: (b.by - a.by) / h, ..U::default() };
            Step { h, u: a, du: derivatives.then_some(du) }
        })
        .collect()
}

// variableLength: roller b swings 0.2 m (L 0.8 .. 1.2 m) at 1, 5, 20 Hz;
// positions held (L steps at communication points) or moving along chords
// (derivatives, with damping: dL/dt feeds the tension). Tolerance per solver
// on T, strain, L.
#[test]
fn dancer_1_to_20_hz_length_plus_minus_20_percent() {
    let q = Quantities { length: true, ..TS };
    for f in [1.0, 5.0, 20.0] {
        for solver in ALL {
            let m = model(solver, |m| m.params.variable_length = true);
            let (r, _) = check(&format!("dancer {f} Hz (held)"), solver, m, dancer(f, 0.0), &dancer_steps(f, false), q, 1.0);
            let (lo, hi) = r.points.iter().fold((f64::MAX, 0.0f64), |(lo, hi), o| (lo.min(o.length), hi.max(o.length)));
            assert!(lo < 0.81 && hi > 1.19);
        }
        for solver in MOVING {
            let m = model(solver, |m| {
                m.params.variable_length = true;
                m.params.include_damping = true;
                m.set_real_var(Real::wp2_d_r, 1e-3).unwrap();
            });
            check(&format!("dancer {f} Hz (derivatives, damping)"), solver, m, dancer(f, 0.0), &dancer_steps(f, true), q, 1.0);
        }
    }
}

// --------------------------------------------------------------------------
// 6. Magnitudes

fn web(m: &mut ConvertingSpan, e: f64, thickness: f64, width: f64, density: f64) {
    for (var, x) in [
        (Real::wp1_E, e),
        (Real::wp2_E, e),
        (Real::wp1_thickness, thickness),
        (Real::wp2_thickness, thickness),
        (Real::wp1_width, width),
        (Real::wp2_width, width),
        (Real::wp1_density, density),
        (Real::wp2_density, density),
    ] {
        m.set_real_var(var, x).unwrap();
    }
}

// Steel EA = 1e8 N drawn to strains 1e-6 .. 1e-3, nonwoven EA = 1e3 N to
// 1e-4 .. 5e-2 and an eps_a step. Tolerance per solver; the floor 1e-15 of
// strain is 1e-9 of the smallest strain.
#[test]
fn steel_strip_and_nonwoven_strains_1e_6_to_5e_2() {
    for solver in ALL {
        // steel: EA = 1e8 N, 2 m at 10 m/s
        let m = model(solver, |m| {
            web(m, 2.0e11, 5e-4, 1.0, 7850.0);
            m.set_real_var(Real::L, 2.0).unwrap();
        });
        let u0 = U::line(10.0, 0.0, 10.0);
        let segs: Vec<_> = [1e-6, 1e-5, 1e-4, 1e-3].iter().map(|&e| (100, 0.01, U { vb: 10.0 * (1.0 + e), ..u0 })).collect();
        let (r, _) = check("steel strip, EA = 1e8 N", solver, m, u0, &held(&segs), TS, 1.0);
        assert!((r.points[100].tension - 100.0).abs() < 1.0);
        // nonwoven: EA = 1e3 N, 0.5 m at 2 m/s
        let m = model(solver, |m| {
            web(m, 7.0e7, 2.5e-4, 1e3 / (7.0e7 * 2.5e-4), 100.0);
            m.set_real_var(Real::L, 0.5).unwrap();
        });
        let u0 = U::line(2.0, 0.0, 2.0);
        let mut segs: Vec<_> = [1e-4, 1e-3, 1e-2, 5e-2].iter().map(|&e| (100, 0.01, U { vb: 2.0 * (1.0 + e), ..u0 })).collect();
        segs.push((100, 0.01, U { vb: 2.1, ea: 2e-2, ..u0 }));
        let (r, _) = check("nonwoven, EA = 1e3 N", solver, m, u0, &held(&segs), TS, 1.0);
        assert!((r.points[400].tension - 50.0).abs() < 1.5);
    }
}

// --------------------------------------------------------------------------
// 7. Damping

// d_r = 10 s (1e4 steps) and d_r = 1e-9 s; tolerances in the body.
#[test]
fn large_and_tiny_damping() {
    let steps = held(&[(100, 1e-3, pet(5.0, 5.005)), (100, 1e-3, pet(5.01, 5.005)), (100, 1e-3, U::line(5.01, 0.0, 5.005))]);
    for solver in ALL {
        // d_r = 10 s = 1e4 steps: the damping term is 50x the elastic one;
        // an error in x reaches T through dx/dt amplified by d_r*lambda = 50: floor x 51
        let m = model(solver, |m| {
            m.params.include_damping = true;
            m.set_real_var(Real::wp2_d_r, 10.0).unwrap();
        });
        let p = params_of(&m);
        let (r, _) = check("large damping d_r = 10 s", solver, m, pet(5.0, 5.0), &steps, TS, 51.0);
        let o = r.points[1];
        assert!((o.tension - p.stiffness * o.strain).abs() > 10.0 * (p.stiffness * (o.strain - 1e-3)).abs());
        // d_r = 1e-9 s: the term is ~1e-8 of T, far above the tolerance
        let m = model(solver, |m| {
            m.params.include_damping = true;
            m.set_real_var(Real::wp2_d_r, 1e-9).unwrap();
        });
        let tiny = held(&[(100, 1e-3, pet(5.0, 5.01)), (100, 1e-3, pet(5.0, 4.99))]);
        let (r, exact) = check("tiny damping d_r = 1e-9 s", solver, m, pet(5.0, 5.0), &tiny, TS, 1.0);
        if solver == AUTO || solver == EXACT {
            for (o, e) in r.points.iter().zip(&exact).skip(1) {
                let (got, want) = (o.tension - p.stiffness * o.strain, e.tension - p.stiffness * e.strain);
                assert!((got - want).abs() <= 1e-4 * want.abs() + 1e-12 * o.tension.abs(), "damping term {got} vs {want}");
            }
        }
    }
}

// --------------------------------------------------------------------------
// 8. Variable steps over six decades

/// 300 steps log-uniform in [1e-6, 1] s; held inputs jumping at random steps,
/// or (derivatives) speeds ramping with slopes that change at random steps.
fn six_decades(derivatives: bool) -> Vec<Step> {
    // a fixed linear congruential sequence: reproducible without a crate
    let mut state: u64 = 0x2545_f491_4f6c_dd1d;
    let mut uniform = move || {
        state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut u = pet(5.0, 5.0);
    let mut rate = U::default();
    let mut steps = Vec::new();
    for _ in 0..300 {
        if uniform() < 0.1 {
            let va = 4.5 + uniform();
            if derivatives {
                let a = uniform() - 0.5;
                rate = U { va: a, vb: a * (1.0 - 5e-4 + 3.5e-3 * uniform()) + 0.02 * (uniform() - 0.5), ..U::default() };
            } else {
                u = U::line(va, 2e-3 * uniform(), va * (1.0 - 5e-4 + 3.5e-3 * uniform()));
            }
        }
        let h = 10f64.powf(-6.0 + 6.0 * uniform());
        steps.push(Step { h, u, du: derivatives.then_some(rate) });
        if derivatives {
            u = u.at(&rate, h);
        }
    }
    let (lo, hi) = steps.iter().fold((1.0f64, 0.0f64), |(lo, hi), s| (lo.min(s.h), hi.max(s.h)));
    assert!(lo < 3e-6 && hi > 0.3);
    steps
}

#[test]
fn variable_steps_spanning_six_decades_in_one_run() {
    // With damping and web mass: web_b.F sees backward differences over steps
    // of very different sizes. lambda = 5/s: lambda*h/10 <= 0.55 for rk4/euler;
    // with derivatives rk4 gets 1000 substeps (lambda*h/n <= 0.005, its
    // moving-input tolerance). Tolerance per solver (module comment).
    let setup = |m: &mut ConvertingSpan| {
        mass(m);
        m.params.include_damping = true;
    };
    let held_steps = six_decades(false);
    for solver in ALL {
        check("variable steps 1e-6 .. 1 s (held)", solver, model(solver, setup), pet(5.0, 5.0), &held_steps, WITH_FORCES, 1.0);
    }
    let ramps = six_decades(true);
    for solver in MOVING {
        let m = model(solver, |m| {
            setup(m);
            m.params.substeps = 1000;
        });
        check("variable steps 1e-6 .. 1 s (ramps)", solver, m, pet(5.0, 5.0), &ramps, WITH_FORCES, 1.0);
    }
}

// --------------------------------------------------------------------------
// 9. A large step in every input at once

// Damping, web mass, variable length; every input steps at once (speeds
// 5 -> 20/21 m/s, eps_a -> 4e-2, L 1 -> 1.57 m), later back down (0.5 m/s,
// L = 0.9 m). Strain jumps with L; damping and mass terms see one-step spikes
// of the backward differences. Tolerance per solver on every output.
#[test]
fn large_step_change_in_every_input_at_once() {
    let u0 = pet(5.0, 5.005);
    let big = U { va: 20.0, ea: 4e-2, vb: 21.0, ax: 0.1, ay: -0.2, bx: 1.5, by: 0.4 };
    let back = U { va: 0.5, ea: 0.0, vb: 0.5005, ax: 0.0, ay: 0.0, bx: 0.9, by: 0.0 };
    let steps = held(&[(50, 2e-3, u0), (200, 2e-3, big), (200, 2e-3, back)]);
    let q = Quantities { exit_force: true, m_web: true, length: true };
    for solver in ALL {
        let m = model(solver, |m| {
            mass(m);
            m.params.include_damping = true;
            m.params.variable_length = true;
        });
        // damping (d_r = 1e-3 s, lambda up to 14/s) adds 1.4 % to T's sensitivity to x: floor x 2
        check("step in every input at once", solver, m, u0, &steps, q, 2.0);
    }
}
