//! The hard-case catalogue through the model core (no FFI).
//!
//! Every case is defined once in tests/hard_cases/catalogue.json; its
//! schedule, its reference and each solver run's tolerance are computed in one
//! place, tests/hard_cases/reference.py (mpmath closed forms, SciPy's Radau,
//! the stability polynomials of rk4/euler; independent of the model's code),
//! and stored in tests/hard_cases/references.json, which this test replays:
//! the parameters set by name, the inputs at t = 0, then every communication
//! step (the inputs set at its start, the input derivatives given for it).
//! tests/integration/python/test_hard_cases.py replays the same file through the packaged
//! FMU and checks that it equals a fresh computation.
//!
//! At every point: every output finite and the unstretched length > 0; each
//! compared quantity within |model - reference| <= rel*|ref| + floor (+ the
//! rk4/euler truncation allowance), the tolerance rule and its reasons stated
//! in the catalogue. A run the reference says must be refused (rk4/euler past
//! their stability limit, dopri5 past its work bound) must answer
//! fmi2Discard with the catalogue's message and leave the model exactly as it
//! was. Then the case's checks (catalogue.json).

use converting_span::ConvertingSpan;
use fmi_core::description::{Causality, Kind};
use fmi_core::{Compiled, Experiment, Model, Status, Variables};

use serde::Deserialize;
use serde_json::Value;
use std::collections::BTreeMap;

const REFERENCES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/hard_cases/references.json");

/// The groups of the catalogue, one test each.
const GROUPS: [&str; 10] = [
    "short fast span",
    "stopped line",
    "speeds through zero",
    "slack",
    "web mass",
    "dancer",
    "magnitudes",
    "damping",
    "six decades",
    "every input",
];

// --------------------------------------------------------------------------
// references.json

#[derive(Deserialize)]
struct File {
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    name: String,
    group: String,
    parameters: BTreeMap<String, Value>,
    initial: BTreeMap<String, f64>,
    steps: Vec<Entry>,
    quantities: Vec<String>,
    reference: BTreeMap<String, Vec<f64>>,
    runs: Vec<Run>,
    #[serde(default)]
    checks: Vec<Check>,
}

/// `n` steps of `h`; `set` at the first, `du` given for each.
#[derive(Deserialize)]
struct Entry {
    h: f64,
    #[serde(default = "one")]
    n: usize,
    #[serde(default)]
    set: BTreeMap<String, f64>,
    du: Option<BTreeMap<String, f64>>,
}

fn one() -> usize {
    1
}

#[derive(Deserialize)]
struct Run {
    solver: String,
    parameters: BTreeMap<String, Value>,
    refused_at: Option<usize>,
    message: Option<String>,
    rel: Option<f64>,
    floor: Option<BTreeMap<String, f64>>,
    allowance: Option<BTreeMap<String, Vec<f64>>>,
}

#[derive(Deserialize)]
#[serde(tag = "check", rename_all = "snake_case")]
enum Check {
    /// Bit for bit the value at `from`, up to `to`.
    Constant { quantities: Vec<String>, from: usize, to: usize },
    Value { quantity: String, point: usize, equals: f64, rel: f64 },
    Extremes { quantity: String, min_below: Option<f64>, max_above: Option<f64>, last_above: Option<f64> },
    AtLeast { quantity: String, value: f64 },
    /// Exactly 0 at the points.
    ZeroAt { quantity: String, points: Vec<usize> },
    /// Some point is above every `above` and below every `below`.
    SomePoint { above: BTreeMap<String, f64>, below: BTreeMap<String, f64> },
    /// |a - b| at the point is above the value.
    DifferenceAbove { quantities: [String; 2], point: usize, above: f64 },
    /// web_b.F - T - flux = m_web * slope within rel.
    Inertia { points: Vec<usize>, flux: Vec<f64>, slope: f64, rel: f64 },
    /// |T - EA*eps| > factor * |EA*(eps - strain_a)| at the point.
    DampingDominates {
        point: usize,
        factor: f64,
        strain_a: f64,
        #[serde(rename = "EA")]
        ea: f64,
    },
    /// T - EA*eps agrees with the reference's term within rel + of_T*|T|.
    DampingTerm {
        rel: f64,
        #[serde(rename = "of_T")]
        of_t: f64,
        solvers: Vec<String>,
        #[serde(rename = "EA")]
        ea: f64,
        term: Vec<f64>,
    },
}

fn cases() -> Vec<Case> {
    let text = std::fs::read_to_string(REFERENCES).expect("tests/hard_cases/references.json");
    serde_json::from_str::<File>(&text).expect("references.json parses").cases
}

// --------------------------------------------------------------------------
// The model under test, driven by variable names

fn vr(name: &str) -> u32 {
    ConvertingSpan::compiled().variable_by_name(name).unwrap_or_else(|| panic!("no variable {name}")).vr
}

fn set(m: &mut ConvertingSpan, name: &str, value: &Value) {
    let v = ConvertingSpan::compiled().variable_by_name(name).unwrap_or_else(|| panic!("no variable {name}"));
    let result = match (v.kind, value) {
        (Kind::Real, Value::Number(x)) => m.set_real(v.vr, x.as_f64().unwrap()),
        (Kind::Boolean, Value::Bool(b)) => m.set_boolean(v.vr, *b),
        (Kind::Integer | Kind::Enumeration { .. }, Value::Number(x)) => m.set_integer(v.vr, x.as_i64().unwrap() as i32),
        _ => panic!("{name} = {value}: not a value of its type"),
    };
    result.unwrap_or_else(|e| panic!("{name} = {value}: {}", e.message));
}

/// The Real outputs and the state, by name.
fn observed() -> Vec<(&'static str, u32)> {
    ConvertingSpan::compiled()
        .variables
        .iter()
        .filter(|v| v.kind == Kind::Real && (v.causality == Causality::Output || v.name == "unstretchedLength"))
        .map(|v| (&*v.name, v.vr))
        .collect()
}

struct Outcome {
    /// name -> value at t = 0 and after each accepted step
    out: BTreeMap<&'static str, Vec<f64>>,
    /// (index of the refused step, message)
    discard: Option<(usize, String)>,
}

impl Outcome {
    fn get(&self, q: &str) -> &[f64] {
        self.out.get(q).unwrap_or_else(|| panic!("{q} is not an output"))
    }
}

fn run(case: &Case, r: &Run) -> Outcome {
    let mut m = ConvertingSpan::at_start_values();
    for (name, value) in case.parameters.iter().chain(&r.parameters) {
        set(&mut m, name, value);
    }
    for (name, x) in &case.initial {
        m.set_real(vr(name), *x).unwrap();
    }
    m.initialize(&Experiment::default(), &Default::default()).unwrap_or_else(|e| panic!("initialize: {}", e.message));
    let observed = observed();
    let mut out: BTreeMap<&'static str, Vec<f64>> = observed.iter().map(|(n, _)| (*n, Vec::new())).collect();
    let read = |m: &ConvertingSpan, out: &mut BTreeMap<&'static str, Vec<f64>>| {
        for (name, vr) in &observed {
            out.get_mut(name).unwrap().push(m.get_real(*vr).unwrap());
        }
    };
    read(&m, &mut out);
    let mut k = 0;
    for e in &case.steps {
        for i in 0..e.n {
            if i == 0 {
                for (name, x) in &e.set {
                    m.set_real(vr(name), *x).unwrap();
                }
            }
            for (name, x) in e.du.iter().flatten() {
                m.set_input_derivative(vr(name), *x).unwrap();
            }
            let before = m.clone();
            if let Err(err) = m.do_step(e.h) {
                assert_eq!(err.status, Status::Discard, "step {k}: {}", err.message);
                assert!(m == before, "a refused step changes nothing");
                return Outcome { out, discard: Some((k, err.into_message())) };
            }
            read(&m, &mut out);
            k += 1;
        }
    }
    Outcome { out, discard: None }
}

// --------------------------------------------------------------------------
// The comparison and the checks

/// Checks one run; returns the failures and the worst relative error of T and
/// strain (at points >= 1 % of the run's largest value).
fn check_run(case: &Case, r: &Run) -> (Vec<String>, f64) {
    let o = run(case, r);
    let mut failures = Vec::new();
    let mut fail = |s: String| failures.push(format!("{} [{}]: {s}", case.name, r.solver));
    for (name, values) in &o.out {
        if let Some(i) = values.iter().position(|v| !v.is_finite()) {
            fail(format!("{name} not finite at point {i}: {}", values[i]));
        }
    }
    if let Some(i) = o.get("unstretchedLength").iter().position(|x| !(*x > 0.0)) {
        fail(format!("unstretched length {} at point {i}", o.get("unstretchedLength")[i]));
    }
    match (r.refused_at, &o.discard) {
        (Some(k), Some((at, message))) => {
            let want = r.message.as_deref().unwrap_or_default();
            if *at != k || !message.contains(want) {
                fail(format!("refused step {at} ({message}), expected step {k} with \"{want}\""));
            }
            return (failures, 0.0);
        }
        (Some(k), None) => {
            fail(format!("step {k} must be refused (stability limit or work bound), was accepted"));
            return (failures, 0.0);
        }
        (None, Some((at, message))) => {
            fail(format!("step {at} refused: {message}"));
            return (failures, 0.0);
        }
        (None, None) => {}
    }
    let (rel, floors) = (r.rel.unwrap(), r.floor.as_ref().unwrap());
    let mut worst: f64 = 0.0;
    for q in &case.quantities {
        let (got, want) = (o.get(q), &case.reference[q]);
        assert_eq!(got.len(), want.len(), "{}: points", case.name);
        let significant = want.iter().fold(0.0f64, |a, w| a.max(w.abs())) / 100.0;
        let allowance = r.allowance.as_ref().map(|a| &a[q]);
        for (i, (g, w)) in got.iter().zip(want).enumerate() {
            let err = (g - w).abs();
            let tol = rel * w.abs() + floors[q] + allowance.map_or(0.0, |a| a[i]);
            if !(err <= tol) {
                fail(format!("{q} at point {i}: {g:e}, reference {w:e}, error {err:.3e} > tolerance {tol:.3e}"));
            }
            if (q == "T" || q == "summary_Strain") && w.abs() >= significant && w.abs() > floors[q] {
                worst = worst.max(err / w.abs());
            }
        }
    }
    for c in &case.checks {
        if let Err(s) = check(c, &o, &r.solver) {
            fail(s);
        }
    }
    (failures, worst)
}

fn check(c: &Check, o: &Outcome, solver: &str) -> Result<(), String> {
    let ensure = |ok: bool, what: String| if ok { Ok(()) } else { Err(what) };
    match c {
        Check::Constant { quantities, from, to } => {
            for q in quantities {
                let v = &o.get(q)[*from..=*to];
                ensure(v.iter().all(|x| x.to_bits() == v[0].to_bits()), format!("{q} moved over points {from}..={to}"))?;
            }
        }
        Check::Value { quantity, point, equals, rel } => {
            let v = o.get(quantity)[*point];
            ensure((v - equals).abs() <= rel * equals.abs(), format!("{quantity} at point {point} = {v}, not {equals} within {rel}"))?;
        }
        Check::Extremes { quantity, min_below, max_above, last_above } => {
            let v = o.get(quantity);
            let (lo, hi) = v.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), x| (l.min(*x), h.max(*x)));
            if let Some(b) = min_below {
                ensure(lo < *b, format!("{quantity}: smallest {lo}, not below {b}"))?;
            }
            if let Some(a) = max_above {
                ensure(hi > *a, format!("{quantity}: largest {hi}, not above {a}"))?;
            }
            if let Some(a) = last_above {
                ensure(v[v.len() - 1] > *a, format!("{quantity}: last {}, not above {a}", v[v.len() - 1]))?;
            }
        }
        Check::AtLeast { quantity, value } => {
            ensure(o.get(quantity).iter().all(|x| x >= value), format!("{quantity} below {value}"))?;
        }
        Check::ZeroAt { quantity, points } => {
            let v = o.get(quantity);
            ensure(points.iter().all(|&i| v[i] == 0.0), format!("{quantity} not exactly 0 where the reference is well slack"))?;
        }
        Check::SomePoint { above, below } => {
            let n = o.get("T").len();
            let hit = (0..n).any(|i| above.iter().all(|(q, a)| o.get(q)[i] > *a) && below.iter().all(|(q, b)| o.get(q)[i] < *b));
            ensure(hit, format!("no point above {above:?} and below {below:?}"))?;
        }
        Check::DifferenceAbove { quantities: [a, b], point, above } => {
            let d = (o.get(a)[*point] - o.get(b)[*point]).abs();
            ensure(d > *above, format!("|{a} - {b}| at point {point} = {d}, not above {above}"))?;
        }
        Check::Inertia { points, flux, slope, rel } => {
            for (&k, f) in points.iter().zip(flux) {
                let inertia = o.get("web_b.F")[k] - o.get("T")[k] - f;
                let want = o.get("m_web")[k] * slope;
                ensure((inertia - want).abs() <= rel * want.abs(), format!("point {k}: inertia {inertia}, m dv/dt {want}"))?;
            }
        }
        Check::DampingDominates { point, factor, strain_a, ea } => {
            let (t, eps) = (o.get("T")[*point], o.get("summary_Strain")[*point]);
            let ok = (t - ea * eps).abs() > factor * (ea * (eps - strain_a)).abs();
            ensure(ok, format!("the damping term does not dominate at point {point}"))?;
        }
        Check::DampingTerm { rel, of_t, solvers, ea, term } => {
            if solvers.iter().any(|s| s == solver) {
                let (t, eps) = (o.get("T"), o.get("summary_Strain"));
                for i in 1..t.len() {
                    let got = t[i] - ea * eps[i];
                    let ok = (got - term[i]).abs() <= rel * term[i].abs() + of_t * t[i].abs();
                    ensure(ok, format!("damping term at point {i}: {got} vs {}", term[i]))?;
                }
            }
        }
    }
    Ok(())
}

fn run_group(group: &str) {
    let cases: Vec<Case> = cases().into_iter().filter(|c| c.group == group).collect();
    assert!(!cases.is_empty(), "no case in group {group}");
    let mut failures = Vec::new();
    for case in &cases {
        for r in &case.runs {
            let (f, worst) = check_run(case, r);
            println!("{:56} {:11} worst relative error {worst:.2e}", case.name, r.solver);
            failures.extend(f);
        }
    }
    assert!(failures.is_empty(), "{} failures:\n{}", failures.len(), failures.join("\n"));
}

#[test]
fn every_case_is_in_a_group_that_runs() {
    for case in cases() {
        assert!(GROUPS.contains(&case.group.as_str()), "{}: group {}", case.name, case.group);
    }
}

#[test]
fn short_fast_span() {
    run_group("short fast span");
}

#[test]
fn stopped_line() {
    run_group("stopped line");
}

#[test]
fn speeds_through_zero() {
    run_group("speeds through zero");
}

#[test]
fn slack() {
    run_group("slack");
}

#[test]
fn web_mass() {
    run_group("web mass");
}

#[test]
fn dancer() {
    run_group("dancer");
}

#[test]
fn magnitudes() {
    run_group("magnitudes");
}

#[test]
fn damping() {
    run_group("damping");
}

#[test]
fn six_decades() {
    run_group("six decades");
}

#[test]
fn every_input() {
    run_group("every input");
}
