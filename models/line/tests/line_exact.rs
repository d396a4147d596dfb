//! The Line model against solutions known in closed form, and its promises:
//! a failed step changes nothing, a restored state continues bit for bit,
//! the start in equilibrium is steady, bad line.json files are refused with
//! the reason. Lines are written here as a user's exporter would write them.

use fmi_core::snapshot::Snapshot;
use fmi_core::phase::Phase;
use fmi_core::{Experiment, FmiResult, Model, Resources, Variables};
use line::Line;
use serde_json::{json, Value};
use solver::band::Band;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A fresh resources folder holding `spec` as line.json and the profiles of its parts.
fn resources(spec: &Value) -> PathBuf {
    static COUNT: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!("line-test-{}-{}", std::process::id(), COUNT.fetch_add(1, Ordering::Relaxed)));
    std::fs::create_dir_all(dir.join("profiles")).unwrap();
    std::fs::write(dir.join("line.json"), serde_json::to_string_pretty(spec).unwrap()).unwrap();
    for part in spec["parts"].as_array().unwrap() {
        if let Some(profile) = part.get("profile") {
            let name = part["name"].as_str().unwrap();
            std::fs::write(dir.join("profiles").join(format!("{name}.json")), profile.to_string()).unwrap();
        }
    }
    dir
}

fn instantiate(spec: &Value) -> FmiResult<(Line, Resources)> {
    let dir = resources(spec);
    let r = Resources::from_path(Some(dir.to_str().unwrap()));
    Ok((Line::instantiate(&r)?, r))
}

fn initialized(spec: &Value) -> Line {
    let (mut line, r) = instantiate(spec).unwrap_or_else(|e| panic!("{}", e.message));
    let warnings = line.initialize(&Experiment::default(), &r).unwrap_or_else(|e| panic!("{}", e.message));
    assert!(warnings.is_empty() || spec["start"] == "equilibrium", "{warnings:?}");
    line
}

fn vr(line: &Line, name: &str) -> u32 {
    line.description().variable_by_name(name).unwrap_or_else(|| panic!("no variable {name}")).vr
}

fn get(line: &Line, name: &str) -> f64 {
    line.get_real(vr(line, name)).unwrap()
}

const PET: [(&str, f64); 5] = [("E", 4.5e9), ("thickness", 50e-6), ("width", 1.0), ("density", 1390.0), ("d_r", 1e-3)];

fn web(side: &str) -> Vec<(String, Value)> {
    PET.iter().map(|(k, v)| (format!("{side}.{k}"), json!(v))).collect()
}

fn span(name: &str, length: f64, eps_start: f64, effects: &[&str]) -> Value {
    let mut start: serde_json::Map<String, Value> = web("wp1").into_iter().chain(web("wp2")).collect();
    start.insert("L".into(), json!(length));
    start.insert("eps_start".into(), json!(eps_start));
    start.insert("startAtEquilibrium".into(), json!(false));
    for e in effects {
        start.insert((*e).into(), json!(true));
    }
    json!({"name": name, "model": "ConvertingSpan", "role": "span", "start": start})
}

/// A roller whose surface speed follows a table.
fn prescribed(name: &str, role: &str, speed: Value) -> Value {
    json!({"name": name, "model": "Roller", "role": role,
           "start": {"J": 0.01, "R": 0.1, "b": 0.0}, "profile": {"speed": speed}})
}

fn roller(name: &str, role: &str, start: Value, profile: Option<Value>) -> Value {
    let mut p = json!({"name": name, "model": "Roller", "role": role, "start": start, "torque_input": true});
    if let Some(profile) = profile {
        p["profile"] = profile;
    }
    p
}

fn connect(from: &str, out: &str, to: &str, input: &str) -> Value {
    json!({"from": [from, out], "to": [to, input]})
}

/// The connections of a chain node, span, node, span, ..., node (as webline's compiler makes them).
fn chain(names: &[&str]) -> Vec<Value> {
    let mut c = Vec::new();
    for i in (1..names.len()).step_by(2) {
        let (up, sp, down) = (names[i - 1], names[i], names[i + 1]);
        c.push(connect(up, "web_b.v", sp, "web_a.v"));
        c.push(if i == 1 { connect(up, "web_b.eps", sp, "web_a.eps") } else { connect(names[i - 2], "web_b.eps", sp, "web_a.eps") });
        c.push(connect(down, "web_a.v", sp, "web_b.v"));
        c.push(connect(sp, "web_a.F", up, "web_b.F"));
        c.push(connect(sp, "web_b.F", down, "web_a.F"));
    }
    c
}

fn line_spec(parts: Vec<Value>, connections: Vec<Value>, start: &str) -> Value {
    json!({"format": "converting-span-line 1", "name": "test", "experiment": {"start_time": 0.0, "stop_time": 1.0, "step": 1e-3},
           "start": start, "parts": parts, "connections": connections})
}

/// Source at v_a, span, sink at v_b: with both speeds held the span's
/// unstretched length x obeys x' = v_a/(1+eps_a) - (v_b/L) x, so
/// x(t) = x_eq + (x0 - x_eq) exp(-v_b t / L), x_eq = L v_a / (v_b (1+eps_a)).
#[test]
fn a_span_between_held_speeds_relaxes_as_the_exact_solution() {
    let (va, vb, eps_a, eps0, length) = (5.0, 5.02, 1e-3, 0.0, 1.5);
    let mut src = prescribed("src", "source", json!([[0.0, va]]));
    src["start"]["web_a.eps"] = json!(eps_a);
    let parts = vec![src, span("film", length, eps0, &[]), prescribed("snk", "sink", json!([[0.0, vb]]))];
    for h in [1e-3, 1e-2, 0.1] {
        let mut line = initialized(&line_spec(parts.clone(), chain(&["src", "film", "snk"]), "given"));
        let x_eq = length * va / (vb * (1.0 + eps_a));
        let x0 = length / (1.0 + eps0);
        let mut t = 0.0;
        let mut worst: f64 = 0.0;
        while t < 1.0 - 1e-12 {
            line.do_step(h).unwrap();
            t += h;
            let x = x_eq + (x0 - x_eq) * (-vb * t / length).exp();
            worst = worst.max((get(&line, "film.eps") - (length / x - 1.0)).abs());
        }
        // The integrator's relative tolerance (1e-10) on x of about L; the strain L/x - 1 inherits it.
        assert!(worst < 3e-10, "h = {h}: strain off the exact solution by {worst:e}");
    }
}

/// An idler between two spans fed at equal held speeds: in equilibrium the
/// tensions on both sides differ by its bearing friction, b*omega/r.
fn paper_line(start: &str) -> Value {
    let unwind = roller(
        "unwind",
        "unwinder",
        json!({"J": 8.0, "R": 0.5, "b": 0.1, "v_start": 10.0, "roll": 1, "web_a.eps": 0.0}),
        Some(json!({"tension": [[0.0, 400.0]]})),
    );
    let idler = roller("idler", "roller", json!({"J": 0.05, "R": 0.08, "b": 0.002, "v_start": 10.0}), None);
    let pull = prescribed("pull", "roller", json!([[0.0, 10.0]]));
    let mut parts = vec![unwind, span("entry", 2.0, 0.0, &["includeDamping"]), idler, span("exit", 1.5, 0.0, &["includeDamping"]), pull];
    parts[4]["wrap"] = json!(90.0);
    line_spec(parts, chain(&["unwind", "entry", "idler", "exit", "pull"]), start)
}

#[test]
fn the_equilibrium_start_is_steady_and_has_the_drives_tensions() {
    let mut line = initialized(&paper_line("equilibrium"));
    let (t_entry, t_exit) = (get(&line, "entry.T"), get(&line, "exit.T"));
    // Unwinder: r T = r T_set + b omega (its drive holds 400 N, its bearing drags).
    let omega_unwind = get(&line, "unwind.omega");
    assert!((t_entry - (400.0 + 0.1 * omega_unwind / 0.5)).abs() < 1e-8 * 400.0, "entry.T = {t_entry}");
    let omega_idler = get(&line, "idler.omega");
    assert!((t_exit - t_entry - 0.002 * omega_idler / 0.08).abs() < 1e-8 * 400.0, "exit.T = {t_exit}");
    // Mass flow: each span carries v/(1+eps) unchanged, so v_idler = v_pull (1+eps_entry)/(1+eps_exit).
    let v_idler = 10.0 * (1.0 + get(&line, "entry.eps")) / (1.0 + get(&line, "exit.eps"));
    assert!((get(&line, "idler.v") - v_idler).abs() < 1e-9, "{} vs {v_idler}", get(&line, "idler.v"));
    // Steady: every state derivative vanishes, and a second of running moves nothing.
    let n = line.states().len();
    let mut dx = vec![0.0; n];
    line.get_derivatives(&mut dx).unwrap();
    assert!(dx.iter().all(|d| d.abs() < 1e-7), "{dx:?}");
    for _ in 0..100 {
        line.do_step(0.01).unwrap();
    }
    assert!((get(&line, "entry.T") - t_entry).abs() < 1e-7, "{} drifted from {t_entry}", get(&line, "entry.T"));
    // The load cell at 90 degrees: sqrt(T_a^2 + T_b^2) on the pull roll's bearings (T_b = 0 after the last span).
    assert!((get(&line, "pull.F") - t_exit).abs() < 1e-9 * t_exit);
}

/// The paper line without bearing friction and with its pull roll an undriven
/// roller: the unwinder's 400 N pass the idler unchanged and nothing holds
/// them at the end, so there is no steady state. A failed search leaves the
/// parts as they were (not at its last trial point).
#[test]
fn a_failed_equilibrium_search_leaves_the_parts_as_they_were() {
    let mut spec = paper_line("given");
    spec["parts"][0]["start"]["b"] = json!(0.0);
    spec["parts"][2]["start"]["b"] = json!(0.0);
    spec["parts"][4] = roller("pull", "roller", json!({"J": 0.01, "R": 0.1, "b": 0.0, "v_start": 10.0}), None);
    let mut line = initialized(&spec);
    let (parts, x) = (line.parts().to_vec(), line.states().to_vec());
    let why = line::equilibrium::solve(&mut line.ode).expect_err("this line has no steady state");
    assert!(why.starts_with("no steady state"), "{why}");
    assert_eq!(line.states(), &x[..]);
    assert!(line.parts() == parts, "the parts were left at the search's last trial point");
}

#[test]
fn a_given_start_that_is_not_steady_rings() {
    let mut line = initialized(&paper_line("given"));
    let t0 = get(&line, "entry.T");
    line.do_step(0.05).unwrap();
    assert!((get(&line, "entry.T") - t0).abs() > 10.0, "a line started at zero strain against 400 N drives must move");
}

#[test]
fn a_restored_state_continues_bit_for_bit_and_a_failed_step_changes_nothing() {
    let mut line = initialized(&paper_line("equilibrium"));
    let tau = vr(&line, "idler.tau_m");
    line.set_real(tau, 0.5).unwrap();
    line.do_step(0.013).unwrap();
    let saved = Snapshot { phase: Phase::StepComplete, time: 0.013, experiment: Experiment::default(), model: line.clone() };
    let bytes = saved.to_bytes();
    line.do_step(0.05).unwrap();
    let back = Snapshot::<Line>::from_bytes(&bytes, &line).unwrap();
    let mut copy = back.model;
    copy.do_step(0.05).unwrap();
    assert_eq!(copy.states(), line.states());
    assert_eq!(get(&copy, "exit.T").to_bits(), get(&line, "exit.T").to_bits());

    // A sink twenty times faster than the source stretches the web past any strain a span takes.
    let mut src = prescribed("src", "source", json!([[0.0, 1.0]]));
    src["start"]["web_a.eps"] = json!(0.0);
    let parts = vec![src, span("film", 1.0, 0.0, &[]), prescribed("snk", "sink", json!([[0.0, 20.0]]))];
    let mut line = initialized(&line_spec(parts, chain(&["src", "film", "snk"]), "given"));
    line.do_step(0.01).unwrap();
    let before = (line.states().to_vec(), line.time(), get(&line, "film.T"));
    let err = line.do_step(10.0).unwrap_err();
    assert!(err.message.contains("line"), "{}", err.message);
    assert_eq!((line.states().to_vec(), line.time(), get(&line, "film.T")), before);
    line.do_step(0.01).unwrap();
}

/// A failed step leaves every part exactly as it was, whether or not an
/// event was applied inside it (here the sink's bearing friction set at
/// 0.02 s, and a breakpoint of its speed table): the parts are copied only
/// before an event, and otherwise evaluated again where the step began.
#[test]
fn a_failed_step_leaves_every_part_as_it_was_with_or_without_an_event_inside() {
    for event in [false, true] {
        let mut src = prescribed("src", "source", json!([[0.0, 1.0]]));
        src["start"]["web_a.eps"] = json!(0.0);
        let mut snk = prescribed("snk", "sink", json!([[0.0, 20.0]]));
        if event {
            snk["profile"] = json!({"speed": [[0.0, 20.0], [0.03, 20.0], [1.0, 20.5]], "set": [{"time": 0.02, "b": 0.5}]});
        }
        let parts = vec![src, span("film", 1.0, 0.0, &["includeDamping"]), snk];
        let mut line = initialized(&line_spec(parts, chain(&["src", "film", "snk"]), "given"));
        line.do_step(0.01).unwrap();
        let (parts, x, t) = (line.parts().to_vec(), line.states().to_vec(), line.time());
        line.do_step(10.0).unwrap_err();
        assert_eq!((line.states(), line.time()), (&x[..], t), "event {event}");
        assert!(line.parts() == parts, "event {event}: a part changed in a failed step");
        line.do_step(0.01).unwrap();
    }
}

#[test]
fn a_torque_input_ramped_over_the_step_is_integrated_exactly() {
    // The paper line's idler: tau_m ramped over one step against the same
    // ramp held at its midpoints over 200 short steps.
    let mut ramped = initialized(&paper_line("equilibrium"));
    let mut halves = ramped.clone();
    let tau = vr(&ramped, "idler.tau_m");
    ramped.set_real(tau, 0.0).unwrap();
    ramped.set_input_derivative(tau, 20.0).unwrap();
    ramped.do_step(0.02).unwrap();
    assert!((get(&ramped, "idler.tau_m") - 0.4).abs() < 1e-15, "the input ends where its derivative took it");
    for k in 0..200 {
        halves.set_real(tau, 20.0 * (k as f64 + 0.5) * 1e-4).unwrap();
        halves.do_step(1e-4).unwrap();
    }
    // The held midpoints are second-order accurate in 1e-4 s: the two agree to that.
    let (a, b) = (get(&ramped, "idler.omega"), get(&halves, "idler.omega"));
    assert!((a - b).abs() < 1e-8 * a.abs(), "{a} vs {b}");
}

/// A motor torque moves no connection (no output a span reads depends on it): setting it
/// does not evaluate the line, yet derivatives, outputs and the next step are exactly
/// those of a line evaluated after the set.
#[test]
fn a_torque_set_without_evaluating_the_line_acts_as_one_evaluated() {
    let mut lazy = initialized(&paper_line("equilibrium"));
    let tau = vr(&lazy, "idler.tau_m");
    let n = lazy.states().len();
    let (mut before, mut after, mut settled) = (vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    lazy.get_derivatives(&mut before).unwrap();
    lazy.set_real(tau, 0.5).unwrap();
    let mut evaluated = lazy.clone();
    let x = evaluated.states().to_vec();
    evaluated.set_continuous_states(&x).unwrap(); // evaluates the line
    lazy.get_derivatives(&mut after).unwrap();
    evaluated.get_derivatives(&mut settled).unwrap();
    assert_eq!(after, settled);
    // The idler's speed gains tau/J; nothing else moves.
    let idler = lazy.network().unwrap().global(lazy.spec().part("idler").unwrap(), 0).unwrap();
    assert!((after[idler] - before[idler] - 0.5 / 0.05).abs() < 1e-9, "{} -> {}", before[idler], after[idler]);
    for k in (0..n).filter(|&k| k != idler) {
        assert_eq!(after[k], before[k], "state {k}");
    }
    for name in ["entry.T", "exit.T", "idler.v", "pull.F"] {
        assert_eq!(get(&lazy, name).to_bits(), get(&evaluated, name).to_bits(), "{name}");
    }
    lazy.do_step(0.01).unwrap();
    evaluated.do_step(0.01).unwrap();
    assert_eq!(lazy.states(), evaluated.states());
    assert!((get(&lazy, "idler.omega") - get(&initialized(&paper_line("equilibrium")), "idler.omega")).abs() > 1e-3);
}

/// A winder (its radius a state) taking web from a source through an idler and a nip where a
/// second web from another source merges (two inlets), spans slack-clamped and damped.
fn winding_merge_line() -> Value {
    let mut src = prescribed("src", "source", json!([[0.0, 8.0]]));
    src["start"]["web_a.eps"] = json!(5e-4);
    let mut side = prescribed("side", "source", json!([[0.0, 8.0]]));
    side["start"]["web_a.eps"] = json!(2e-4);
    let idler = roller("idler", "roller", json!({"J": 0.03, "R": 0.07, "b": 0.001, "v_start": 8.0}), None);
    let nip = roller("nip", "roller", json!({"J": 0.2, "R": 0.1, "b": 0.01, "v_start": 8.0, "inlets": 2}), None);
    let wind = roller(
        "wind",
        "winder",
        json!({"J": 2.0, "R": 0.2, "b": 0.05, "v_start": 8.0, "roll": 2, "wound.thickness": 1e-4, "wound.density": 900.0, "wound.width": 1.0}),
        Some(json!({"tension": [[0.0, 150.0]]})),
    );
    let effects = ["includeDamping", "preventNegativeTension"];
    let parts = vec![
        src,
        span("a", 1.2, 1e-3, &effects),
        idler,
        span("b", 0.8, 1e-3, &effects),
        side,
        span("c", 1.0, 8e-4, &["includeDamping"]),
        nip,
        span("d", 1.5, 1e-3, &effects),
        wind,
    ];
    // The main path into the nip, the side path into its second inlet, the laminate out of it.
    let mut c = chain(&["src", "a", "idler", "b", "nip"]);
    c.extend([
        connect("side", "web_b.v", "c", "web_a.v"),
        connect("side", "web_b.eps", "c", "web_a.eps"),
        connect("nip", "web_a2.v", "c", "web_b.v"),
        connect("c", "web_a.F", "side", "web_b.F"),
        connect("c", "web_b.F", "nip", "web_a2.F"),
        connect("c", "web_b.eps", "nip", "web_a2.eps"),
        connect("b", "web_b.eps", "nip", "web_a.eps"),
    ]);
    c.extend(chain(&["nip", "d", "wind"]));
    line_spec(parts, c, "given")
}

/// The Jacobian chained from the parts' tangents against the line's own grouped differences,
/// off equilibrium (a torque step, a line started unsteady): every entry within 1e-5 of its
/// row's largest. Forward differences are good to about 1e-7 of it, less in a row of small
/// entries (a roll's radius rate: 2e-6); a connection left out of the chain costs a whole entry.
#[test]
fn the_chained_jacobian_is_the_lines_own() {
    for (name, spec) in [("paper line", paper_line("equilibrium")), ("winding merge", winding_merge_line())] {
        let mut line = initialized(&spec);
        if name == "paper line" {
            let tau = vr(&line, "idler.tau_m");
            line.set_real(tau, 2.0).unwrap();
        }
        line.do_step(0.02).unwrap();
        let net = line.network().unwrap();
        assert!(net.chain.is_some(), "{name}: no chain");
        let (t, x, kl, ku) = (line.time(), line.states().to_vec(), net.kl, net.ku);
        let n = x.len();
        let (mut chained, mut differenced) = (Band::zeros(n, kl, ku), Band::zeros(n, kl, ku));
        line::ode::jacobian_at(&mut line.ode, t, &x, None, &mut chained, false).unwrap();
        line::ode::jacobian_at(&mut line.ode, t, &x, None, &mut differenced, true).unwrap();
        let mut checked = 0;
        for i in 0..n {
            let scale = (0..n).map(|j| differenced.get(i, j).abs()).fold(0.0, f64::max);
            for j in 0..n {
                let (a, b) = (chained.get(i, j), differenced.get(i, j));
                assert!((a - b).abs() <= 1e-5 * scale, "{name}: J[{i}][{j}] chained {a}, differenced {b} (row scale {scale})");
                checked += (b != 0.0) as usize;
            }
        }
        assert!(checked >= 2 * n, "{name}: only {checked} entries");
    }
}

#[test]
fn bad_line_files_are_refused_with_the_reason() {
    let good = paper_line("equilibrium");
    let cases: Vec<(Value, &str)> = vec![
        ({ let mut s = good.clone(); s["format"] = json!("v0"); s }, "format \"v0\""),
        ({ let mut s = good.clone(); s["colour"] = json!(1); s }, "unknown field `colour`"),
        ({ let mut s = good.clone(); s["parts"][2]["name"] = json!("unwind"); s }, "two parts are named \"unwind\""),
        ({ let mut s = good.clone(); s["parts"][2]["name"] = json!("line"); s }, "may not be named \"line\""),
        ({ let mut s = good.clone(); s["parts"][1]["start"]["L"] = json!("long"); s }, "part entry: L = \"long\""),
        ({ let mut s = good.clone(); s["parts"][1]["start"]["colour"] = json!(1); s }, "part entry: colour"),
        ({ let mut s = good.clone(); s["connections"][0]["from"] = json!(["nobody", "web_b.v"]); s }, "no part \"nobody\""),
        ({ let mut s = good.clone(); s["connections"][0]["to"] = json!(["entry", "web_a.speed"]); s }, "no variable \"web_a.speed\""),
        ({ let mut s = good.clone(); s["connections"][0]["to"] = json!(["entry", "web_b.v"]); s }, "connected twice"),
        ({ let mut s = good.clone(); s["connections"][0]["from"] = json!(["entry", "web_a.v"]); s }, "from an output to an input"),
    ];
    for (spec, expected) in cases {
        let err = match instantiate(&spec) {
            Ok((mut line, r)) => line.initialize(&Experiment::default(), &r).unwrap_err(),
            Err(e) => e,
        };
        assert!(err.message.contains(expected), "expected {expected:?} in: {}", err.message);
    }
    // Without resources there is no line to read.
    let err = Line::instantiate(&Resources::from_path(None)).unwrap_err();
    assert!(err.message.contains("resources/line.json"), "{}", err.message);
}

#[test]
fn the_guid_is_the_line_files_hash() {
    let a = line::spec::guid("{\"a\": 1}");
    assert_eq!(a, line::spec::guid("{\"a\": 1}"));
    assert_ne!(a, line::spec::guid("{\"a\": 2}"));
    assert_eq!(a.len(), 38, "{a}");
}
