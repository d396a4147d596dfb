//! The Line FMU's ODE integrated by our Rodas5P (the FMU's), RODAS4 and ROS34PW2 and by
//! diffsol's BDF, TR-BDF2 and ESDIRK34 (docs/line-solver.md). Run by hand, prints markdown:
//!
//!     cd bench/diffsol_line && nice cargo run --release --target-dir ../../target/diffsol [-- --all | --ours]
//!
//! `--ours` runs only our three methods (Rodas5P, the FMU's; RODAS4; ROS34PW2, a W-method).
//!
//! Every solver sees the same ODE (`line::ode::rhs_at`), the same banded
//! finite-difference Jacobian (`jacobian_at`: kl + ku + 1 extra evaluations; the FMU
//! chains its parts' tangents instead, which changes no solver's count of steps)
//! and the same driver: the line's events (profile breakpoints, `set`
//! entries) are applied by the Line itself (`event_update`, as in Model
//! Exchange) and each solver integrates between them; diffsol starts a new
//! solver after each event (its history is no longer valid), ours keep their
//! step size as the FMU does.

use diffsol::{NalgebraLU, NalgebraMat, OdeBuilder, OdeSolverMethod, OdeSolverStopReason, Vector};
use fmi_core::{Experiment, Model, Resources};
use line::part::Part;
use line::ode::{jacobian_at, rhs_at};
use line::Line;
use solver::band::Band;
use solver::stiff::tableau::{Tableau, RODAS4, RODAS5P, ROS34PW2};
use solver::stiff::{Control, Rosenbrock, System};
use std::alloc::{GlobalAlloc, Layout, System as Heap};
use std::cell::{Cell, RefCell};
use std::sync::atomic::{AtomicUsize, Ordering::Relaxed};
use std::time::Instant;

/// Counts heap allocations (the rule: none in a step).
struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);
unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        ALLOCS.fetch_add(1, Relaxed);
        unsafe { Heap.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { Heap.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, s: usize) -> *mut u8 {
        ALLOCS.fetch_add(1, Relaxed);
        unsafe { Heap.realloc(p, l, s) }
    }
}
#[global_allocator]
static GLOBAL: Counting = Counting;

const REPEATS: usize = 11;
/// Output points for the error: every OUTPUT s and the end.
const OUTPUT: f64 = 0.1;
/// The FMU's communication steps, for the restart pattern.
const COMM: [f64; 2] = [1e-3, 1e-2];

#[derive(Clone, Copy, PartialEq, Debug)]
enum Method {
    Rodas4,
    /// The Line's integrator since RODAS4: order 5, eight stages.
    Rodas5p,
    /// Our W-method: its Jacobian kept over steps.
    Ros34pw2,
    Bdf,
    TrBdf2,
    Esdirk34,
    /// BDF in the co-simulation pattern without a restart per step: one
    /// solver stopped every step (right only while no input changes).
    BdfKept,
}

impl Method {
    fn name(self) -> &'static str {
        match self {
            Method::Rodas4 => "RODAS4 (ours)",
            Method::Rodas5p => "Rodas5P (ours)",
            Method::Ros34pw2 => "ROS34PW2 (ours)",
            Method::Bdf => "diffsol BDF",
            Method::TrBdf2 => "diffsol TR-BDF2",
            Method::Esdirk34 => "diffsol ESDIRK34",
            Method::BdfKept => "diffsol BDF, no restart",
        }
    }
}

/// A line, initialized, with what the solvers need to know of it.
struct Bench {
    name: &'static str,
    line: Line,
    n: usize,
    kl: usize,
    ku: usize,
    stop: f64,
    time_dependent: bool,
    /// The FMU's tolerance scales (per unit of tolerance): atol/rtol and rtol's factor.
    atol1: Vec<f64>,
    rtol_scale: Vec<f64>,
    /// Change of variables for diffsol (its rtol is one scalar): y = c + d u.
    c: Vec<f64>,
    d: Vec<f64>,
    /// Error weights: a span's length times its strain (relative tension), a roller's speed.
    weight: Vec<f64>,
}

impl Bench {
    fn new(name: &'static str) -> Bench {
        let dir = format!("{}/lines/{name}", env!("CARGO_MANIFEST_DIR"));
        let r = Resources::from_path(Some(&dir));
        let mut line = Line::instantiate(&r).unwrap_or_else(|e| panic!("{name}: {}", e.message));
        line.initialize(&Experiment::default(), &r).unwrap_or_else(|e| panic!("{name}: {}", e.message));
        let text = std::fs::read_to_string(format!("{dir}/line.json")).unwrap();
        let spec: serde_json::Value = serde_json::from_str(&text).unwrap();
        let stop = spec["experiment"]["stop_time"].as_f64().unwrap();
        let net = line.network().unwrap();
        let (n, kl, ku) = (net.len(), net.kl, net.ku);
        let span: Vec<bool> = net.states.iter().map(|s| matches!(line.parts()[s.part], Part::Span(_))).collect();
        let s = line::stepping::scratch(&line.ode, n);
        let mut nominal = vec![0.0; n];
        line.get_nominals(&mut nominal).unwrap();
        let x0 = line.states().to_vec();
        let rtol = s.atol.iter().zip(&s.rtol_scale).zip(&nominal).map(|((a, r), nom)| a / (r * nom.abs().max(1e-300))).fold(0.0, f64::max);
        let atol1: Vec<f64> = s.atol.iter().map(|a| a / rtol).collect();
        let d: Vec<f64> = (0..n).map(|i| if span[i] { s.rtol_scale[i] * nominal[i] } else { 1.0 }).collect();
        let c: Vec<f64> = (0..n).map(|i| if span[i] { x0[i] } else { 0.0 }).collect();
        let weight = (0..n).map(|i| if span[i] { d[i] } else { nominal[i].abs().max(1.0) }).collect();
        let time_dependent = line.spec().parts.iter().any(|p| p.profile.is_some());
        Bench { name, line, n, kl, ku, stop, time_dependent, atol1, rtol_scale: s.rtol_scale, c, d, weight }
    }
}

/// What a run did. Evaluations are counted at the ODE, the same way for all.
#[derive(Default, Clone)]
struct Outcome {
    seconds: f64,
    steps: usize,
    rejected: usize,
    rhs: usize,
    jacobians: usize,
    lu: usize,
    allocs: usize,
    /// States at the output points.
    out: Vec<Vec<f64>>,
}

/// Our RODAS4 on the line through the public ODE.
struct Sys<'a> {
    line: &'a mut Line,
    time_dependent: bool,
    rhs: usize,
    jac: usize,
}

impl System for Sys<'_> {
    fn rhs(&mut self, t: f64, y: &[f64], dy: &mut [f64]) -> Result<(), ()> {
        self.rhs += 1;
        rhs_at(&mut self.line.ode, t, y, dy).map_err(drop)
    }
    fn jacobian(&mut self, t: f64, y: &[f64], f0: &[f64], jac: &mut Band) -> Result<(), ()> {
        self.jac += 1;
        jacobian_at(&mut self.line.ode, t, y, Some(f0), jac, true).map_err(drop)
    }
    fn time_dependent(&self) -> bool {
        self.time_dependent
    }
}

/// The times to stop at: output points, or every communication step `comm` (> 0).
fn stops(b: &Bench, comm: f64) -> Vec<f64> {
    let h = if comm > 0.0 { comm } else { OUTPUT };
    let k = (b.stop / h).round() as usize;
    (1..=k).map(|i| (i as f64 * h).min(b.stop)).collect()
}

fn is_output(t: f64) -> bool {
    let k = (t / OUTPUT).round();
    (t - k * OUTPUT).abs() < 1e-12
}

/// Integrates the whole line with `method` at tolerance `tol`. With `comm` > 0,
/// as the FMU is called in co-simulation: a new integration every `comm` s
/// (diffsol: a new solver each time; RODAS4: the FMU's way, its step kept).
fn run(b: &Bench, method: Method, tol: f64, comm: f64) -> Result<Outcome, String> {
    let line = RefCell::new(b.line.clone());
    let grid = stops(b, comm);
    let (rhs_count, jac_count) = (Cell::new(0usize), Cell::new(0usize));
    let clock = Instant::now();
    let mut o = Outcome::default();
    let n = b.n;
    let mut t = line.borrow().time();
    let mut x = line.borrow().states().to_vec();

    // diffsol: the problem in u (y = c + d u), its Jacobian from the band at (t, y), cached.
    let start = RefCell::new(vec![0.0; n]);
    let cache = RefCell::new((f64::NAN, vec![f64::NAN; n], Band::zeros(n, b.kl, b.ku), vec![0.0; n], vec![0.0; n]));
    let to_y = |u: &[f64], y: &mut [f64]| {
        for i in 0..n {
            y[i] = b.c[i] + b.d[i] * u[i];
        }
    };
    let ybuf = RefCell::new(vec![0.0; n]);
    let rhs = |u: &[f64], _p: &[f64], t: f64, du: &mut [f64]| {
        rhs_count.set(rhs_count.get() + 1);
        let mut y = ybuf.borrow_mut();
        to_y(u, &mut y);
        if rhs_at(&mut line.borrow_mut().ode, t, &y, du).is_err() {
            du.fill(f64::NAN);
        }
        for i in 0..n {
            du[i] /= b.d[i];
        }
    };
    let jvp = |u: &[f64], _p: &[f64], t: f64, v: &[f64], out: &mut [f64]| {
        let mut guard = cache.borrow_mut();
        let (ct, cu, band, yv, jv) = &mut *guard;
        if *ct != t || cu.as_slice() != u {
            jac_count.set(jac_count.get() + 1);
            let mut y = ybuf.borrow_mut();
            to_y(u, &mut y);
            if jacobian_at(&mut line.borrow_mut().ode, t, &y, None, band, true).is_err() {
                band.clear();
            }
            *ct = t;
            cu.copy_from_slice(u);
        }
        for i in 0..n {
            yv[i] = b.d[i] * v[i];
        }
        band.mul(yv, jv);
        for i in 0..n {
            out[i] = jv[i] / b.d[i];
        }
    };
    let atol_u: Vec<f64> = (0..n).map(|i| if b.d[i] != 1.0 { 2.0 * tol } else { tol * b.atol1[i] }).collect();
    let mut problem = OdeBuilder::<NalgebraMat<f64>>::new()
        .rtol(tol)
        .atol(atol_u)
        .rhs_implicit(rhs, jvp)
        .init(|_p, _t, u: &mut [f64]| u.copy_from_slice(&start.borrow()), n)
        .build()
        .map_err(|e| e.to_string())?;

    // Ours as the FMU runs it.
    let tableau: &'static Tableau = match method {
        Method::Ros34pw2 => &ROS34PW2,
        Method::Rodas5p => &RODAS5P,
        _ => &RODAS4,
    };
    let mut rodas = Rosenbrock::new(tableau, n, b.kl, b.ku);
    let atol: Vec<f64> = b.atol1.iter().map(|a| a * tol).collect();
    let control = Control { rtol: tol, atol: &atol, rtol_scale: &b.rtol_scale, max_steps: 1_000_000, max_step: 0.0 };

    // diffsol: the step a new solver starts with, its last one before (as RODAS4 keeps its own).
    let mut h_next = 0.0;
    let mut k = 0;
    while k < grid.len() {
        // Events due now, by the Line; the next one ends the segment.
        let event = {
            let mut l = line.borrow_mut();
            let next = l.event_update().next_event_time.unwrap_or(f64::INFINITY);
            x.copy_from_slice(l.states());
            next
        };
        // The stops of this segment: grid points before the event, then the event.
        let mut seg: Vec<f64> = Vec::new();
        while k < grid.len() && grid[k] < event - 1e-12 {
            seg.push(grid[k]);
            k += 1;
        }
        if k < grid.len() && (grid[k] - event).abs() <= 1e-12 {
            seg.push(grid[k]);
            k += 1;
        } else if event > t && event < b.stop {
            seg.push(event);
        }
        let restart = comm > 0.0 && method != Method::BdfKept;
        if seg.is_empty() {
            break;
        }
        match method {
            Method::Rodas4 | Method::Rodas5p | Method::Ros34pw2 => {
                let mut l = line.borrow_mut();
                let mut sys = Sys { line: &mut l, time_dependent: b.time_dependent, rhs: 0, jac: 0 };
                for &s in &seg {
                    let a = ALLOCS.load(Relaxed);
                    rodas.integrate(&mut sys, t, s, &mut x, &control).map_err(|f| format!("{f:?}"))?;
                    // An event follows the segment's end: the line's Jacobian may change there.
                    if s == *seg.last().unwrap() {
                        rodas.renew_jacobian();
                    }
                    o.allocs += ALLOCS.load(Relaxed) - a;
                    t = s;
                    if is_output(s) || s == b.stop {
                        o.out.push(x.clone());
                    }
                }
                rhs_count.set(rhs_count.get() + sys.rhs);
                jac_count.set(jac_count.get() + sys.jac);
            }
            _ => {
                let pieces: Vec<Vec<f64>> = if restart { seg.iter().map(|&s| vec![s]).collect() } else { vec![seg.clone()] };
                for piece in pieces {
                    for i in 0..n {
                        start.borrow_mut()[i] = (x[i] - b.c[i]) / b.d[i];
                    }
                    problem.t0 = t;
                    let a = ALLOCS.load(Relaxed);
                    let (u, stats) = match method {
                        Method::Bdf | Method::BdfKept => drive(problem.bdf::<NalgebraLU<f64>>(), t, &mut h_next, &piece, b, &mut o, a)?,
                        Method::TrBdf2 => drive(problem.tr_bdf2::<NalgebraLU<f64>>(), t, &mut h_next, &piece, b, &mut o, a)?,
                        Method::Esdirk34 => drive(problem.esdirk34::<NalgebraLU<f64>>(), t, &mut h_next, &piece, b, &mut o, a)?,
                        Method::Rodas4 | Method::Rodas5p | Method::Ros34pw2 => unreachable!(),
                    };
                    to_y(&u, &mut x);
                    t = *piece.last().unwrap();
                    o.steps += stats.0;
                    o.rejected += stats.1;
                    o.lu += stats.2;
                }
            }
        }
        // The Line at the segment's end, for its events.
        let mut l = line.borrow_mut();
        l.set_time(t);
        l.set_continuous_states(&x).map_err(|e| e.message.clone())?;
    }
    o.seconds = clock.elapsed().as_secs_f64();
    if matches!(method, Method::Rodas4 | Method::Rodas5p | Method::Ros34pw2) {
        o.steps = rodas.stats.accepted;
        o.rejected = rodas.stats.rejected;
        o.lu = rodas.stats.factorizations;
    }
    o.rhs = rhs_count.get();
    o.jacobians = jac_count.get();
    drop(problem);
    Ok(o)
}

/// Runs a diffsol solver to each stop in turn; the states at the last, and (steps, error-test failures, LU setups).
/// Steps, error-test failures, LU set-ups.
type Work = (usize, usize, usize);

/// A new solver starts with the step h (its own guess if 0) and leaves its last in h.
/// Counts the allocations of making it and of its steps since `a`.
#[allow(clippy::too_many_arguments)]
fn drive<'a, Eqn, S>(
    s: Result<S, diffsol::DiffsolError>,
    t0: f64,
    h: &mut f64,
    stops: &[f64],
    b: &Bench,
    o: &mut Outcome,
    mut a: usize,
) -> Result<(Vec<f64>, Work), String>
where
    Eqn: diffsol::OdeEquations<T = f64> + 'a,
    S: OdeSolverMethod<'a, Eqn>,
{
    let mut s = s.map_err(|e| e.to_string())?;
    if *h > 0.0 {
        *s.state_mut().h = h.min(stops[0] - t0);
    }
    let mut u = Vec::new();
    for &stop in stops {
        s.set_stop_time(stop).map_err(|e| e.to_string())?;
        loop {
            let r = s.step();
            let r = r.map_err(|e| format!("at t = {:.4} s: {}", s.state().t, e.to_string().trim_start_matches("ODE solver error: ").split(" at time").next().unwrap_or_default()))?;
            if matches!(r, OdeSolverStopReason::TstopReached) {
                break;
            }
        }
        o.allocs += ALLOCS.load(Relaxed) - a;
        let y = s.state().y;
        u = (0..b.n).map(|i| y.get_index(i)).collect();
        if is_output(stop) || stop == b.stop {
            o.out.push((0..b.n).map(|i| b.c[i] + b.d[i] * u[i]).collect());
        }
        a = ALLOCS.load(Relaxed);
    }
    *h = s.state().h;
    let st = s.get_statistics();
    Ok((u, (st.number_of_steps, st.number_of_error_test_failures, st.number_of_linear_solver_setups)))
}

/// Largest error over the output points, in the weights' units (of scale).
fn error(o: &Outcome, reference: &Outcome, b: &Bench) -> f64 {
    let mut worst: f64 = 0.0;
    assert_eq!(o.out.len(), reference.out.len(), "{}: output points", b.name);
    for (y, r) in o.out.iter().zip(&reference.out) {
        for i in 0..b.n {
            worst = worst.max((y[i] - r[i]).abs() / b.weight[i]);
        }
    }
    worst
}

/// REPEATS runs, the median time; the work of one.
fn measure(b: &Bench, method: Method, tol: f64, comm: f64) -> Result<Outcome, String> {
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..REPEATS {
        let o = run(b, method, tol, comm)?;
        times.push(o.seconds);
        last = Some(o);
    }
    times.sort_by(f64::total_cmp);
    let mut o = last.unwrap();
    o.seconds = times[REPEATS / 2];
    Ok(o)
}

fn main() {
    let tols = [1e-6, 1e-8, 1e-10];
    // TR-BDF2 (order 2) only with `-- --all`: it is no contender at these tolerances.
    let all = std::env::args().any(|a| a == "--all");
    let ours = std::env::args().any(|a| a == "--ours");
    let methods: Vec<Method> = [Method::Rodas4, Method::Rodas5p, Method::Ros34pw2, Method::Bdf, Method::TrBdf2, Method::Esdirk34]
        .into_iter()
        .filter(|&m| if ours { matches!(m, Method::Rodas4 | Method::Rodas5p | Method::Ros34pw2) } else { all || m != Method::TrBdf2 })
        .collect();
    let mut full = String::new();
    let mut comm = String::new();
    let mut checks = String::new();
    for name in ["lamination", "splice", "ten_spans"] {
        let b = Bench::new(name);
        let reference = run(&b, Method::Rodas4, 1e-12, 0.0).expect("reference");
        // The reference against diffsol at its tightest tolerance that gets through.
        let mut said = format!("- {name} ({} states, kl {}, ku {}): the reference against", b.n, b.kl, b.ku);
        if let Ok(c) = run(&b, Method::Rodas4, 1e-11, 0.0) {
            said.push_str(&format!(" RODAS4 at 1e-11: {:.1e};", error(&c, &reference, &b)));
        }
        let others = if ours { &[][..] } else { &[(Method::Bdf, 1e-12), (Method::Esdirk34, 1e-12), (Method::Bdf, 1e-11), (Method::Esdirk34, 1e-11)][..] };
        for &(m, tol) in others {
            match run(&b, m, tol, 0.0) {
                Ok(c) => {
                    said.push_str(&format!(" {} at {tol:.0e}: {:.1e}", m.name(), error(&c, &reference, &b)));
                    break;
                }
                Err(e) => said.push_str(&format!(" {} at {tol:.0e} fails ({e});", m.name().trim_start_matches("diffsol "))),
            }
        }
        checks.push_str(&said);
        checks.push('\n');
        for tol in tols {
            for &m in &methods {
                full.push_str(&row(&b, m, tol, &reference));
            }
        }
        for m in methods.iter().copied().chain(if ours { None } else { Some(Method::BdfKept) }) {
            comm.push_str(&comm_row(&b, m, &reference));
        }
    }
    println!("Whole run, between the line's events; error: largest over the output points (every {OUTPUT} s) against RODAS4 at 1e-12, of scale; time: median of {REPEATS} runs.\n");
    println!("{HEADER}{full}");
    println!("As in co-simulation: one integration per communication step (diffsol: a new solver each step, but \"no restart\"), tolerance 1e-8.\n");
    println!("{COMM_HEADER}{comm}");
    println!("{checks}");
}

const HEADER: &str = "| line | solver | tol | error | time ms | steps | rejected | f evals | Jacobians | LU | allocations |\n|---|---|---|---|---|---|---|---|---|---|---|\n";

fn row(b: &Bench, m: Method, tol: f64, reference: &Outcome) -> String {
    match measure(b, m, tol, 0.0) {
        Ok(o) => format!(
            "| {} | {} | {:.0e} | {:.1e} | {:.2} | {} | {} | {} | {} | {} | {} |\n",
            b.name,
            m.name(),
            tol,
            error(&o, reference, b),
            o.seconds * 1e3,
            o.steps,
            o.rejected,
            evaluations(b, &o, m),
            o.jacobians,
            o.lu,
            o.allocs
        ),
        Err(e) => format!("| {} | {} | {:.0e} | failed {} | | | | | | | |\n", b.name, m.name(), tol, e.replace('|', "/")),
    }
}

/// f evaluations, those of the Jacobians included: kl + ku + 1 each, and f at the
/// point for diffsol's (ours have it from the step).
fn evaluations(b: &Bench, o: &Outcome, m: Method) -> usize {
    let own_f0 = usize::from(!matches!(m, Method::Rodas4 | Method::Rodas5p | Method::Ros34pw2));
    o.rhs + o.jacobians * ((b.kl + b.ku + 1).min(b.n) + own_f0)
}

/// One row per solver for the co-simulation pattern: each communication step's columns.
fn comm_row(b: &Bench, m: Method, reference: &Outcome) -> String {
    let mut row = format!("| {} | {} |", b.name, m.name());
    for h in COMM {
        row.push_str(&match measure(b, m, 1e-8, h) {
            Ok(o) => format!(" {:.1e} | {:.1} | {} | {} | {} | {} |", error(&o, reference, b), o.seconds * 1e3, evaluations(b, &o, m), o.jacobians, o.lu, o.allocs),
            Err(e) => format!(" failed {} | | | | | |", e.replace('|', "/")),
        });
    }
    row.push('\n');
    row
}

const COMM_HEADER: &str = "| line | solver | 1 ms: error | ms | f evals | Jacobians | LU | allocations | 10 ms: error | ms | f evals | Jacobians | LU | allocations |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
