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
    let spec = line.spec().clone();
    let why = line::equilibrium::solve(&mut line.ode, &spec).expect_err("this line has no steady state");
    assert!(matches!(&why, line::equilibrium::NoStart::Search(w) if w.starts_with("no steady state")), "{why:?}");
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

/// A winder (its radius a state, reading the strain of the web it winds) taking web from a source
/// through an idler and a nip where a second web from another source merges (two inlets), spans
/// slack-clamped and damped.
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
    // The winder reads the strain it winds at [R3] (as webline connects a wound roll).
    c.push(connect("d", "web_b.eps", "wind", "web_a.eps"));
    line_spec(parts, c, "given")
}

/// A source at 5 m/s, two spans of variable length that hang from a dancer without a spring (5 kg, 400 N),
/// a pull roll whose speed loop on a real motor (its reference 5 -> 5.05 m/s at 20-30 ms) is trimmed by a
/// dancer loop [R13] on the dancer's y, wired from the dancer's output y into the pull roll's dancer.y.
fn dancer_looped_line() -> Value {
    let mut down = span("down_leg", 0.5, 8.9e-4, &["variableLength", "includeDamping"]);
    for (k, v) in [("frame_a.x", 0.0), ("frame_a.y", 0.5), ("frame_b.x", 0.0), ("frame_b.y", 0.0)] {
        down["start"][k] = json!(v);
    }
    let mut up = span("up_leg", 0.5, 8.9e-4, &["variableLength", "includeDamping"]);
    for (k, v) in [("frame_a.x", 0.1), ("frame_a.y", 0.0), ("frame_b.x", 0.1), ("frame_b.y", 0.5)] {
        up["start"][k] = json!(v);
    }
    let dancer = roller(
        "dancer",
        "dancer",
        json!({"J": 0.01, "R": 0.05, "b": 0.001, "v_start": 5.0, "carriage": true, "carriage.m": 5.0, "carriage.d": 300.0,
               "carriage.k": 0.0, "carriage.y_start": 0.5}),
        Some(json!({"load": [[0.0, 400.0]]})),
    );
    let pull = roller(
        "pull",
        "roller",
        json!({"J": 0.05, "R": 0.1, "b": 0.01, "v_start": 5.0, "loop.kind": 3, "loop.sign": 1.0, "loop.kp": 50.0, "loop.ki": 500.0,
               "motor.lag": 0.002, "dancer.set": 0.5, "dancer.kp": 10.0, "dancer.ki": 25.0}),
        Some(json!({"reference": [[0.0, 5.0], [0.02, 5.0], [0.03, 5.05]]})),
    );
    let parts = vec![prescribed("src", "source", json!([[0.0, 5.0]])), down, dancer, up, pull];
    let mut c = chain(&["src", "down_leg", "dancer", "up_leg", "pull"]);
    c.push(connect("dancer", "web_a.y", "down_leg", "frame_b.y"));
    c.push(connect("dancer", "web_b.y", "up_leg", "frame_a.y"));
    c.push(connect("dancer", "y", "pull", "dancer.y"));
    line_spec(parts, c, "equilibrium")
}

/// A dancer loop holds a dancer without a spring: the equilibrium start puts it at its set point (its
/// loop's integral is the one thing that holds it there), and after the pull roll's reference steps
/// 5 -> 5.05 m/s the trim takes the step back (-0.05 m/s) and the dancer returns to 0.5 m to 1e-6 m.
#[test]
fn a_dancer_loop_holds_a_springless_dancer_at_its_set_point() {
    let mut line = initialized(&dancer_looped_line());
    assert!((get(&line, "dancer.y") - 0.5).abs() < 1e-9, "starts at {}", get(&line, "dancer.y"));
    let trim = get(&line, "pull.dancer.I");
    let mut worst: f64 = 0.0;
    for _ in 0..500 {
        line.do_step(0.01).unwrap();
        worst = worst.max((get(&line, "dancer.y") - 0.5).abs());
    }
    assert!(worst > 1e-4, "the step must move the dancer (worst {worst} m)");
    assert!((get(&line, "dancer.y") - 0.5).abs() < 1e-6, "{} m off after 5 s", get(&line, "dancer.y") - 0.5);
    let change = get(&line, "pull.dancer.I") - trim;
    assert!((change + 0.05).abs() < 1e-4, "the trim takes the step up: it moved by {change} m/s");
}

/// The Jacobian chained from the parts' tangents against the line's own grouped differences,
/// off equilibrium (a torque step, a line started unsteady): every entry within 1e-5 of its
/// row's largest. Forward differences are good to about 1e-7 of it, less in a row of small
/// entries (a roll's radius rate: 2e-6); a connection left out of the chain costs a whole entry.
#[test]
fn the_chained_jacobian_is_the_lines_own() {
    let pull = |start: &str| {
        let ([v0, v1, v2], _) = mass_balance(1.0, 100.0, 200.0);
        let pull = slipping("pull", json!({"J": 0.05, "R": 0.1, "b": 0.0, "traction.wrap": std::f64::consts::PI}), Some(json!({"speed": [[0.0, v1]]})));
        let mut spec = drawn(pull, v0, v2);
        spec["start"] = json!(start);
        spec
    };
    let idler = slipping("idler", json!({"J": 0.01, "R": 0.05, "b": 0.0, "v_start": 0.0, "traction.slip_start": 5.0, "traction.static": 1.2}), None);
    // The least entries the differences find (0: two per state); a speed a table holds has none. The
    // contacts: a pull roll sticking, an idler sliding with a static peak (its grip in the chain).
    for (name, spec, least) in [
        ("sticking pull", pull("given"), 11),
        ("sliding idler", through(idler, 5.0 * 1.002 / 1.001, "given"), 14),
        ("paper line", paper_line("equilibrium"), 0),
        ("winding merge", winding_merge_line(), 0),
        ("load cell loop", load_cell_looped_line(json!([[0.0, 10.0]])), 0),
    ] {
        let mut line = initialized(&spec);
        if name == "paper line" {
            let tau = vr(&line, "idler.tau_m");
            line.set_real(tau, 2.0).unwrap();
        }
        line.do_step(0.02).unwrap();
        let (chained, checked) = chained_against_differences(&mut line, name);
        let n = line.states().len();
        let least = if least == 0 { 2 * n } else { least };
        assert!(checked >= least, "{name}: only {checked} entries");
        if name == "winding merge" {
            // The winder's r' = h*omega/(2*pi*(1 + eps)) [R3] (v = r*omega) reads the arriving span d's
            // strain eps = L/x - 1: dr'/domega = h/(2*pi*(1 + eps)), dr'/dx = h*omega/(2*pi*L), so
            // their ratio is omega*(1 + eps)/L, to rounding in the chain.
            let net = line.network().unwrap();
            let at = |part: usize, index: usize| net.states.iter().position(|s| s.part == part && s.index == index).unwrap();
            let (r, omega, x) = (at(8, 1), at(8, 0), at(7, 0));
            let expected = get(&line, "wind.omega") * (1.0 + get(&line, "d.eps")) / 1.5;
            let ratio = chained.get(r, x) / chained.get(r, omega);
            assert!((ratio - expected).abs() < 1e-12 * expected, "dr'/dx over dr'/domega: {ratio}, expected {expected}");
        }
    }
}

/// The line's Jacobian chained from its parts' tangents against its own differences, where it
/// stands: every entry within 1e-5 of its row's largest. The chained band, and how many entries
/// the differences found nonzero.
fn chained_against_differences(line: &mut Line, name: &str) -> (Band, usize) {
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
    (chained, checked)
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

// Traction [R6]-[R8]: the closed forms of docs/physics.md ("Rollers that slip"), in lines whose
// spans carry the web's Kelvin-Voigt damping (the wrap's mode needs it). PET as above: EA = 225 kN.

const MU: f64 = 0.3;
const WRAP: f64 = std::f64::consts::FRAC_PI_2;
const V_SLIP: f64 = 1e-3;
/// The web's mass per length: density * width * thickness.
const WEB_MASS: f64 = 1390.0 * 1.0 * 50e-6;

/// A roller the web may slip on; `start` (over these defaults) and `profile` as `roller`.
fn slipping(name: &str, start: Value, profile: Option<Value>) -> Value {
    let mut p = roller(name, "roller", start, profile);
    for (k, v) in [("includeTraction", json!(true)), ("traction.mu", json!(MU)), ("traction.wrap", json!(WRAP)), ("web_a.m", json!(WEB_MASS))] {
        if p["start"].get(k).is_none() {
            p["start"][k] = v;
        }
    }
    p
}

/// src (5 m/s, strain 1e-3) - a - node - b - snk, the spans damped.
fn through(node: Value, v_sink: f64, start: &str) -> Value {
    let mut src = prescribed("src", "source", json!([[0.0, 5.0]]));
    src["start"]["web_a.eps"] = json!(1e-3);
    let name = node["name"].as_str().unwrap().to_string();
    let parts = vec![src, span("a", 1.0, 1e-3, &["includeDamping"]), node, span("b", 1.0, 1e-3, &["includeDamping"]), prescribed("snk", "sink", json!([[0.0, v_sink]]))];
    line_spec(parts, chain(&["src", "a", &name, "b", "snk"]), start)
}

/// A roll driven 10 % slower than the web drags on it: the web slides (s = 0.5 m/s = 500 v_slip),
/// so T_b - m v_w^2 = (T_a - m v_w^2) exp(mu theta) (the wrap's pressure less the web's centripetal
/// force); the strains follow from the mass balance: 1 + eps_b = (v_snk/v_src)(1 + eps_src) for the
/// span after it, EA eps_a = m v_w^2 + (EA eps_b - m v_w^2) exp(-mu theta) before it (one web), and
/// the web crosses the roll at v_w = v_src (1 + eps_a)/(1 + eps_src): the two solved by iteration,
/// each step shrinking the error by 2 m v_w^2/EA. From a given start (an equilibrium start is
/// refused: the contact cannot stick), once the line has settled (8 s; at 3 s eps_a is still 4e-5
/// off: the web's speed over the sliding roll follows span a's strain, a slower mode than L/v), at 1 and 10 ms.
#[test]
fn a_drag_roll_slides_at_the_capstan_ratio() {
    let drag = slipping("drag", json!({"J": 0.05, "R": 0.1, "b": 0.0}), Some(json!({"speed": [[0.0, 4.5]]})));
    let spec = through(drag, 5.005, "given");
    let ea = 4.5e9 * 50e-6;
    let eps_b = 5.005 / 5.0 * 1.001 - 1.0;
    let (mut eps_a, mut v_w) = (eps_b, 5.0);
    for _ in 0..10 {
        v_w = 5.0 * (1.0 + eps_a) / 1.001;
        let relief = WEB_MASS * v_w * v_w;
        eps_a = (relief + (ea * eps_b - relief) * (-MU * WRAP).exp()) / ea;
    }
    let relief = WEB_MASS * v_w * v_w;
    for h in [1e-3, 1e-2] {
        let mut line = initialized(&spec);
        while line.time() < 8.0 - 1e-9 {
            line.do_step(h).unwrap();
        }
        for step in 0..=20 {
            if step > 0 {
                line.do_step(h).unwrap();
            }
            let (t_a, t_b) = (get(&line, "a.T"), get(&line, "b.T"));
            let ratio = (t_b - relief) / (t_a - relief);
            assert!((ratio.ln() / (MU * WRAP) - 1.0).abs() < 1e-6, "h = {h}, step {step}: ratio {ratio}");
            assert!((get(&line, "a.eps") - eps_a).abs() < 1e-6 * eps_b, "eps_a {} vs {eps_a}", get(&line, "a.eps"));
            assert!((get(&line, "b.eps") - eps_b).abs() < 1e-6 * eps_b);
            assert!((get(&line, "drag.v_web") - v_w).abs() < 1e-6 * 5.0, "v_web {} vs {v_w}", get(&line, "drag.v_web"));
            assert!(get(&line, "drag.slip") > 50.0 * V_SLIP && get(&line, "drag.traction") > 0.99);
            assert!((get(&line, "drag.grip") - 1.0).abs() < 1e-9, "grip {}", get(&line, "drag.grip"));
        }
    }
}

/// An idler at rest on a running line is spun up by friction: while the web slides, its surface
/// accelerates at R^2 (T_a - m v_w^2)(exp(mu theta) - 1)/J (b = 0); then it sticks, at zero slip
/// once the grip has settled.
#[test]
fn an_idler_at_rest_is_spun_up_by_friction_then_sticks() {
    let (j, r) = (0.01, 0.05);
    let idler = slipping("idler", json!({"J": j, "R": r, "b": 0.0, "v_start": 0.0, "traction.slip_start": 5.0}), None);
    let mut line = initialized(&through(idler, 5.0 * 1.002 / 1.001, "given"));
    let (mut slid, mut stuck) = (0, 0);
    for _ in 0..400 {
        line.do_step(1e-3).unwrap();
        let slip = get(&line, "idler.slip");
        let acceleration = r * get(&line, "der(idler.omega)");
        // After the sudden start's transient (the wrap's mode, damped within a few ms).
        if slip > 50.0 * V_SLIP && line.time() > 0.02 {
            let pressing = get(&line, "a.T") - WEB_MASS * get(&line, "idler.v_web").powi(2);
            let expected = r * r * pressing * ((MU * WRAP).exp() - 1.0) / j;
            assert!((acceleration / expected - 1.0).abs() < 1e-6, "t = {}: {acceleration} vs {expected}", line.time());
            slid += 1;
        } else if get(&line, "idler.grip").abs() <= 0.9 {
            stuck += 1;
        }
    }
    assert!(slid > 50 && stuck > 100, "slid {slid} steps, stuck {stuck}");
    assert!(get(&line, "idler.slip").abs() <= 1e-9, "still slipping at {} m/s", get(&line, "idler.slip"));
}

/// A nip alone (no wrap) on a roll driven slower than the web: T_b - T_a = mu_nip N while it slides
/// (from a given start, once the transport has settled).
#[test]
fn a_sliding_nip_passes_mu_n() {
    let mut nip = slipping("nip", json!({"J": 0.05, "R": 0.1, "b": 0.0, "traction.wrap": 0.0, "nip.mu": 0.5}), None);
    nip["profile"] = json!({"speed": [[0.0, 4.5]], "nip": [[0.0, 200.0]]});
    let mut line = initialized(&through(nip, 5.005, "given"));
    while line.time() < 3.0 - 1e-9 {
        line.do_step(1e-2).unwrap();
    }
    for _ in 0..20 {
        line.do_step(1e-2).unwrap();
        let (t_a, t_b) = (get(&line, "a.T"), get(&line, "b.T"));
        assert!((t_b - t_a - 100.0).abs() < 1e-6 * t_b, "T_b - T_a = {}", t_b - t_a);
        assert!(get(&line, "nip.slip") > 50.0 * V_SLIP);
    }
}

/// src (v0, strain 1e-3) - a - node - b - snk, the spans damped, 1 m each; the node a speed drive
/// at v1 and the sink at v2.
fn drawn(node: Value, v0: f64, v2: f64) -> Value {
    let mut src = prescribed("src", "source", json!([[0.0, v0]]));
    src["start"]["web_a.eps"] = json!(1e-3);
    let name = node["name"].as_str().unwrap().to_string();
    let parts = vec![src, span("a", 1.0, 1e-3, &["includeDamping"]), node, span("b", 1.0, 1e-3, &["includeDamping"]), prescribed("snk", "sink", json!([[0.0, v2]]))];
    line_spec(parts, chain(&["src", "a", &name, "b", "snk"]), "equilibrium")
}

/// The speeds of src, node and snk that draw the web from the source's strain 1e-3 to T_a and T_b
/// where it sticks, and the tensions the mass balance gives back for them: each span carries
/// v/(1 + eps) unchanged and sticks to its rollers' surfaces, 1 + eps_a = (v1/v0)(1 + eps_src),
/// 1 + eps_b = (v2/v1)(1 + eps_a), T = EA eps.
fn mass_balance(v0: f64, t_a: f64, t_b: f64) -> ([f64; 3], [f64; 2]) {
    let ea = 4.5e9 * 50e-6;
    let (v1, v2) = (v0 * (1.0 + t_a / ea) / 1.001, v0 * (1.0 + t_b / ea) / 1.001);
    let eps_a = v1 / v0 * 1.001 - 1.0;
    let eps_b = v2 / v1 * (1.0 + eps_a) - 1.0;
    ([v0, v1, v2], [ea * eps_a, ea * eps_b])
}

/// Sticking draws: a pull roll (mu 0.3 over 180 deg) holding 100 N against 200 N, and a nip (500 N,
/// mu 0.5, no wrap) holding 100 N against 300 N, each a speed drive between two more, at 0.1, 1 and
/// 10 m/s: the tensions are the mass balance's to 1e-6 (the contact holds at zero slip), at the
/// equilibrium start and over a second of Co-Simulation steps of 1 and 10 ms; the grip is the share
/// the force balance needs, 2 sqrt(T'_a T'_b) sinh(mu theta g/2) = T_b - T_a on the wrap
/// (T' = T - m v^2), (T_b - T_a)/(mu N) = 0.8 at the nip. Model Exchange starts steady: its
/// derivatives vanish there.
#[test]
fn sticking_draws_give_the_mass_balances_tensions() {
    let pi = std::f64::consts::PI;
    for (what, (t_a, t_b)) in [("pull", (100.0, 200.0)), ("nip", (100.0, 300.0))] {
        for v0 in [0.1, 1.0, 10.0] {
            let ([_, v1, v2], [ta, tb]) = mass_balance(v0, t_a, t_b);
            let mut node = slipping(what, json!({"J": 0.05, "R": 0.1, "b": 0.0, "traction.wrap": pi}), Some(json!({"speed": [[0.0, v1]]})));
            let share = if what == "nip" {
                node["start"]["traction.wrap"] = json!(0.0);
                node["start"]["nip.mu"] = json!(0.5);
                node["profile"]["nip"] = json!([[0.0, 500.0]]);
                (tb - ta) / 250.0
            } else {
                let relief = WEB_MASS * v1 * v1;
                let k = 2.0 * ((ta - relief) * (tb - relief)).sqrt();
                2.0 * ((tb - ta) / k).asinh() / (MU * pi)
            };
            let spec = drawn(node, v0, v2);
            for h in [1e-3, 1e-2] {
                let mut line = initialized(&spec);
                for step in 0..=(1.0f64 / h).round() as usize {
                    if step > 0 {
                        line.do_step(h).unwrap();
                    }
                    let (a, b) = (get(&line, "a.T"), get(&line, "b.T"));
                    assert!((a - ta).abs() < 1e-6 * ta && (b - tb).abs() < 1e-6 * tb, "{what} at {v0} m/s, h = {h}, step {step}: T_a {a} vs {ta}, T_b {b} vs {tb}");
                }
                let grip = get(&line, &format!("{what}.grip"));
                assert!((grip - share).abs() < 1e-6, "{what} at {v0} m/s: grip {grip} vs {share}");
                assert!(get(&line, &format!("{what}.slip")).abs() < 1e-12 * v0, "{what} at {v0} m/s: slip {}", get(&line, &format!("{what}.slip")));
            }
            let (mut me, r) = instantiate(&spec).unwrap();
            me.initialize(&Experiment { model_exchange: true, ..Experiment::default() }, &r).unwrap();
            let mut dx = vec![0.0; me.states().len()];
            me.get_derivatives(&mut dx).unwrap();
            let (a, b) = (get(&me, "a.T"), get(&me, "b.T"));
            assert!((a - ta).abs() < 1e-6 * ta && (b - tb).abs() < 1e-6 * tb, "ME {what} at {v0} m/s: T_a {a}, T_b {b}");
            // The grip's rate s/delta: a slip of 1e-15 m/s moves it by 2e-8/s.
            assert!(dx.iter().all(|d| d.abs() < 1e-6), "ME {what} at {v0} m/s: {dx:?}");
        }
    }
}

/// The issue's pull roll at 0.2 m/s (PET 50 um, m v^2 = 3e-3 N): holding 100 N against 200 N it sticks
/// at a grip of 0.7355 (2 sqrt(100*200) sinh(0.3 pi g/2) = 100); against 300 N, more than its capstan
/// limit 100 exp(0.3 pi) = 256.6 N, an equilibrium start is refused in words.
#[test]
fn a_pull_roll_holds_within_its_capstan_limit_and_is_refused_beyond_it() {
    let pi = std::f64::consts::PI;
    for (t_b, holds) in [(200.0, true), (300.0, false)] {
        let ([v0, v1, v2], _) = mass_balance(0.2, 100.0, t_b);
        let pull = slipping("pull", json!({"J": 0.05, "R": 0.1, "b": 0.0, "traction.wrap": pi}), Some(json!({"speed": [[0.0, v1]]})));
        let spec = drawn(pull, v0, v2);
        if holds {
            let line = initialized(&spec);
            assert!((get(&line, "a.T") - 100.0).abs() < 1e-6 * 100.0, "T_a {}", get(&line, "a.T"));
            assert!((get(&line, "pull.grip") - 0.7355).abs() < 5e-5, "grip {}", get(&line, "pull.grip"));
            continue;
        }
        let (mut line, r) = instantiate(&spec).unwrap();
        let why = line.initialize(&Experiment::default(), &r).expect_err("the web cannot stick").message.clone();
        assert_eq!(why, "pull: needs 300 N downstream, its capstan limit is 256.6 N (mu 0.3, 180 deg): the web slides from the start; use a given start (\"start\": \"given\")");
    }
}

/// A laminate of PET and foil: each layer a span part, sources at their own speeds and strains, a
/// speed-driven nip and pull roll (`layered`: each passes its layers' strains on at their ports),
/// a sink. Layer i arrives at 1+eps_i = (v_n/v_i)(1+eps_src,i) and, in a span drawn by r = v_out/v_n,
/// carries E_i A_i ((1+eps_i) r - 1) ([M6]).
fn laminate_line(start: &str) -> Value {
    let al = [("E", 69e9), ("thickness", 20e-6), ("width", 1.0), ("density", 2700.0), ("d_r", 1e-3)];
    let layer = |name: &str, web: &[(&str, f64); 5]| {
        let mut s = span(name, 0.6, 0.0, &[]);
        for (side, (k, v)) in ["wp1", "wp2"].iter().flat_map(|side| web.iter().map(move |kv| (side, kv))) {
            s["start"][format!("{side}.{k}")] = json!(v);
        }
        s
    };
    let mut film_in = prescribed("film_in", "source", json!([[0.0, 4.99]]));
    film_in["start"]["web_a.eps"] = json!(1e-3);
    let mut foil_in = prescribed("foil_in", "source", json!([[0.0, 4.998]]));
    foil_in["start"]["web_a.eps"] = json!(2e-4);
    let mut nip = prescribed("nip", "roller", json!([[0.0, 5.0]]));
    let mut pull = prescribed("pull", "roller", json!([[0.0, 5.01]]));
    for r in [&mut nip, &mut pull] {
        for (k, v) in [("inlets", json!(2)), ("outlets", json!(2)), ("layered", json!(true))] {
            r["start"][k] = v;
        }
    }
    let mut out = prescribed("out", "sink", json!([[0.0, 5.03]]));
    out["start"]["inlets"] = json!(2);
    out["start"]["layered"] = json!(true);
    let parts = vec![film_in, layer("film", &PET), foil_in, layer("foil", &al), nip, layer("lam.PET", &PET), layer("lam.Al", &al), pull,
                     layer("rew.PET", &PET), layer("rew.Al", &al), out];
    let mut c = chain(&["film_in", "film", "nip"]);
    c.extend(chain(&["foil_in", "foil", "nip"]).into_iter().map(|mut k| {
        for end in ["from", "to"] {
            if k[end][0] == "nip" {
                k[end][1] = json!(k[end][1].as_str().unwrap().replace("web_a", "web_a2"));
            }
        }
        k
    }));
    c.push(connect("film", "web_b.eps", "nip", "web_a.eps"));
    c.push(connect("foil", "web_b.eps", "nip", "web_a2.eps"));
    for (up, down, spans) in [("nip", "pull", ["lam.PET", "lam.Al"]), ("pull", "out", ["rew.PET", "rew.Al"])] {
        for (k, sp) in spans.iter().enumerate() {
            let (a, b) = (["web_b", "web_b2"][k], ["web_a", "web_a2"][k]);
            c.extend([connect(up, &format!("{a}.v"), sp, "web_a.v"), connect(up, &format!("{a}.eps"), sp, "web_a.eps"),
                      connect(down, &format!("{b}.v"), sp, "web_b.v"), connect(sp, "web_b.eps", down, &format!("{b}.eps")),
                      connect(sp, "web_a.F", up, &format!("{a}.F")), connect(sp, "web_b.F", down, &format!("{b}.F"))]);
        }
    }
    let mut spec = line_spec(parts, c, start);
    spec["laminates"] = json!([{"name": "lam", "layers": [{"part": "lam.PET", "label": "PET"}, {"part": "lam.Al", "label": "Al"}]},
                               {"name": "rew", "layers": [{"part": "rew.PET", "label": "PET"}, {"part": "rew.Al", "label": "Al"}]}]);
    spec
}

/// The laminate's outputs against the closed form from an equilibrium start (Newton's steady state:
/// 1e-12 of each value) and after 40 time constants L/v (0.12 s) from a given one (what is left of
/// three lags in a row, t^2/2 e^(-t), and the integrator's tolerance: 1e-9); a laminate of one web at
/// the mass-weighted strain [M2] would be 1e-4 off.
#[test]
fn a_laminates_layers_keep_their_strains_and_their_tensions_add() {
    let (ea_pet, ea_al) = (4.5e9 * 50e-6, 69e9 * 20e-6);
    let eps = [5.0 / 4.99 * 1.001 - 1.0, 5.0 / 4.998 * 1.0002 - 1.0];
    let layers = |r: f64| [ea_pet * ((1.0 + eps[0]) * r - 1.0), ea_al * ((1.0 + eps[1]) * r - 1.0)];
    for (start, tolerance, steps) in [("equilibrium", 1e-12, 0), ("given", 1e-9, 500)] {
        let mut line = initialized(&laminate_line(start));
        for _ in 0..steps {
            line.do_step(0.01).unwrap();
        }
        for (name, r) in [("lam", 5.01 / 5.0), ("rew", 5.03 / 5.0)] {
            let [t_pet, t_al] = layers(r);
            let total = t_pet + t_al;
            for (output, want) in [("T", total), ("T_PET", t_pet), ("T_Al", t_al), ("F_a", total), ("F_b", total), ("eps", total / (ea_pet + ea_al)), ("length", 0.6)] {
                let got = get(&line, &format!("{name}.{output}"));
                assert!((got - want).abs() <= tolerance * want.abs(), "{start}: {name}.{output} = {got}, closed form {want}");
            }
            assert_eq!(get(&line, &format!("{name}.T_PET")), get(&line, &format!("{name}.PET.T")));
        }
        let m = [1390.0 * 50e-6, 2700.0 * 20e-6];
        let merged = (m[0] + m[1]) / (m[0] / (1.0 + eps[0]) + m[1] / (1.0 + eps[1])) - 1.0;
        let one_web = (ea_pet + ea_al) * ((1.0 + merged) * 5.01 / 5.0 - 1.0);
        assert!((one_web - get(&line, "lam.T")).abs() > 1e-4 * one_web, "{start}: the merged web is as far");
    }
}

/// A laminate whose span stands still is steady at any strains of its layers that pull as one: the
/// equilibrium start moves them together from their start (Newton's Jacobian is singular otherwise).
/// The line at rest, its webs from tension-driven unwinders (100 N, 50 N), the pull roll driven by
/// 30 N m, a winder holding 200 N: the laminate after the pull roll carries 200 N, the one before it
/// 200 N + 30 N m / 0.1 m, each with its layers at one strain (they started at one: eps_start 0).
#[test]
fn a_laminate_at_rest_starts_with_its_layers_moved_together() {
    let mut spec = laminate_line("equilibrium");
    let unwinder = |name: &str, tension: f64| {
        roller(name, "unwinder", json!({"J": 0.5, "R": 0.1, "v_start": 0.0, "roll": 1}), Some(json!({"tension": [[0.0, tension]]})))
    };
    spec["parts"][0] = unwinder("film_in", 100.0);
    spec["parts"][2] = unwinder("foil_in", 50.0);
    spec["parts"][4]["profile"]["speed"] = json!([[0.0, 0.0]]);
    spec["parts"][7] = roller("pull", "roller", json!({"J": 0.01, "R": 0.1, "v_start": 0.0, "inlets": 2, "outlets": 2, "layered": true}),
                              Some(json!({"torque": [[0.0, 30.0]]})));
    spec["parts"][10] = roller("out", "winder", json!({"J": 0.5, "R": 0.1, "v_start": 0.0, "roll": 2, "inlets": 2, "layered": true}),
                               Some(json!({"tension": [[0.0, 200.0]]})));
    let line = initialized(&spec);
    let (ea_pet, ea_al) = (4.5e9 * 50e-6, 69e9 * 20e-6);
    for (name, tension) in [("film", 100.0), ("foil", 50.0), ("lam", 500.0), ("rew", 200.0)] {
        let got = get(&line, &format!("{name}.T"));
        assert!((got - tension).abs() < 1e-9 * tension, "{name}.T = {got}, not {tension}");
    }
    for name in ["lam", "rew"] {
        let (pet, al) = (get(&line, &format!("{name}.T_PET")) / ea_pet, get(&line, &format!("{name}.T_Al")) / ea_al);
        assert!((pet - al).abs() < 1e-12 * pet, "{name}: the layers' strains {pet} and {al}");
    }
}

/// `laminate_line` with both laminates free to go slack (`preventNegativeTension` on every layer),
/// drawn by nothing (nip, pull and sink at 5 m/s), the foil arriving at `foil_strain` off its source.
fn slack_laminate_line(foil_strain: f64) -> Value {
    let mut spec = laminate_line("given");
    spec["parts"][0]["start"]["web_a.eps"] = json!(5e-3);
    spec["parts"][2]["start"]["web_a.eps"] = json!(foil_strain);
    for (k, speed) in [(7, 5.0), (10, 5.0)] {
        spec["parts"][k]["profile"]["speed"] = json!([[0.0, speed]]);
    }
    for k in [5, 6, 8, 9] {
        spec["parts"][k]["start"]["preventNegativeTension"] = json!(true);
    }
    spec
}

/// A bonded laminate goes slack as one ([M6]). At zero draw each layer keeps the strain it arrived
/// at, 1+eps_i = (v_n/v_src,i)(1+eps_src,i), and pulls E_i A_i eps_i (Kelvin–Voigt at rest in
/// strain rate). PET from 4.99 m/s at 5e-3 pulls +1578 N; the foil from 4.998 m/s at -1e-3 is
/// compressed, -828 N: the sum, 750 N, is positive, so each layer carries its own pull, the
/// compressed one too (a clamp per layer would give 1578 N). At -3e-3 the foil pushes -3588 N,
/// the sum is negative, and every layer's tension and end forces are exactly 0. After 40 time
/// constants L/v (0.12 s) from a given start: 1e-9, as the closed-form test above.
#[test]
fn a_laminate_goes_slack_as_one() {
    let (ea_pet, ea_al) = (4.5e9 * 50e-6, 69e9 * 20e-6);
    for (foil_strain, slack) in [(-1e-3, false), (-3e-3, true)] {
        let mut line = initialized(&slack_laminate_line(foil_strain));
        for _ in 0..500 {
            line.do_step(0.01).unwrap();
        }
        let eps = [5.0 / 4.99 * 1.005 - 1.0, 5.0 / 4.998 * (1.0 + foil_strain) - 1.0];
        let pulls = [ea_pet * eps[0], ea_al * eps[1]];
        assert_eq!(pulls[0] + pulls[1] <= 0.0, slack, "the case is as named");
        let carried = if slack { [0.0, 0.0] } else { pulls };
        for name in ["lam", "rew"] {
            let total = carried[0] + carried[1];
            let mut outputs = vec![("T".to_string(), total), ("F_a".into(), total), ("F_b".into(), total)];
            for (label, t) in ["PET", "Al"].iter().zip(carried) {
                outputs.extend([(format!("T_{label}"), t), (format!("{label}.T"), t), (format!("{label}.F_a"), t), (format!("{label}.F_b"), t)]);
            }
            for (output, want) in outputs {
                let got = get(&line, &format!("{name}.{output}"));
                assert!((got - want).abs() <= 1e-9 * pulls[0].abs(), "foil at {foil_strain}: {name}.{output} = {got}, closed form {want}");
                if slack {
                    assert_eq!(got, 0.0, "{name}.{output}: a slack laminate carries exactly 0");
                }
            }
            // The layers still carry their own strains: slack takes the tension, not the material.
            let strain = get(&line, &format!("{name}.Al.eps"));
            assert!((strain - eps[1]).abs() <= 1e-9 * eps[1].abs(), "{name}: the foil's strain {strain}, not {}", eps[1]);
        }
        // Its layers' event indicator is the laminate's: the sum of their pulls.
        let mut z = vec![0.0; line.description().number_of_event_indicators];
        Model::get_event_indicators(&line, &mut z).unwrap();
        let al = line.shared.spec.part("lam.Al").unwrap();
        let k: usize = line.ode.parts[..al].iter().map(|p| p.event_indicator_count()).sum();
        assert!((z[k] - (pulls[0] + pulls[1])).abs() <= 1e-9 * pulls[0], "indicator {} for the sum {}", z[k], pulls[0] + pulls[1]);
    }
}

/// The chained Jacobian through a laminate that may go slack, against the line's differences (as
/// `the_chained_jacobian_is_the_lines_own`, 1e-5 of a row's largest): the pull roll a free roller
/// that both laminates turn, so its row reads every layer's force, on the carrying side (each
/// layer's own tangent, a compressed one's too) and on the slack side (none).
#[test]
fn the_chained_jacobian_follows_a_laminates_slack() {
    for foil_strain in [-1e-3, -3e-3] {
        let mut spec = slack_laminate_line(foil_strain);
        spec["parts"][7] = roller("pull", "roller", json!({"J": 0.01, "R": 0.1, "b": 0.0, "v_start": 5.0, "inlets": 2, "outlets": 2, "layered": true}), None);
        let mut line = initialized(&spec);
        line.do_step(0.02).unwrap();
        let (chained, _) = chained_against_differences(&mut line, &format!("foil at {foil_strain}"));
        // The pull's omega reads the foil layer before it while the laminate carries, not when slack.
        let net = line.network().unwrap();
        let (omega, foil) = (net.global(7, 0).unwrap(), net.global(6, 0).unwrap());
        let slack = foil_strain < -2e-3;
        assert_eq!(chained.get(omega, foil) == 0.0, slack, "foil at {foil_strain}: d(omega')/d(x_Al) = {}", chained.get(omega, foil));
    }
}

#[test]
fn bad_laminates_are_refused_with_the_reason() {
    let good = laminate_line("given");
    let cases: Vec<(Value, &str)> = vec![
        ({ let mut s = good.clone(); s["laminates"][0]["layers"][1]["label"] = json!("eps"); s }, "layer label \"eps\" must be plain"),
        ({ let mut s = good.clone(); s["laminates"][0]["layers"][1]["label"] = json!("T_PET"); s }, "layer label \"T_PET\""),
        ({ let mut s = good.clone(); s["laminates"][0]["layers"][1]["part"] = json!("pull"); s }, "layer \"pull\" is no span part"),
        ({ let mut s = good.clone(); s["laminates"][1]["layers"][0]["part"] = json!("lam.PET"); s }, "part \"lam.PET\" is a layer twice"),
        ({ let mut s = good.clone(); s["laminates"][1]["name"] = json!("lam"); s }, "laminate \"lam\": its name"),
        ({ let mut s = good.clone(); s["laminates"][0]["layers"] = json!([{"part": "lam.PET", "label": "PET"}]); s }, "at least two layers"),
        ({ let mut s = good.clone(); s["parts"][5]["name"] = json!("lam..PET"); s }, "part name \"lam..PET\""),
        ({ let mut s = good.clone(); s["parts"][6]["start"]["L"] = json!(0.7); s }, "lam.Al.L = 0.7 m, but lam.PET.L = 0.6 m"),
        ({ let mut s = good.clone(); s["parts"][6]["start"]["preventNegativeTension"] = json!(true); s }, "lam.Al.preventNegativeTension = true, but lam.PET"),
    ];
    for (spec, expected) in cases {
        let err = match instantiate(&spec) {
            Ok((mut line, r)) => line.initialize(&Experiment::default(), &r).unwrap_err(),
            Err(e) => e,
        };
        assert!(err.message.contains(expected), "expected {expected:?} in: {}", err.message);
    }
}

/// The paper line with its unwinder's tension held by a PI loop on the entry span [R10] (no tension
/// table): `gains` (kp, ki), `limit` and `lag` of its motor [R11]; the pull roll's speed `pull`.
fn looped_line(pull: Value, limit: f64, lag: f64) -> Value {
    let mut spec = paper_line("equilibrium");
    spec["parts"][0] = roller(
        "unwind",
        "unwinder",
        json!({"J": 8.0, "R": 0.5, "b": 0.1, "v_start": 10.0, "roll": 1, "loop.kind": 1, "loop.sign": -1.0, "loop.set": 400.0,
               "loop.kp": 0.2, "loop.ki": 2.0, "motor.limit": limit, "motor.lag": lag}),
        None,
    );
    spec["parts"][4]["profile"]["speed"] = pull;
    spec["connections"].as_array_mut().unwrap().push(connect("entry", "summary_Tension", "unwind", "loop.measured"));
    spec
}

/// A PI loop holds its set point against the bearing friction: the equilibrium start puts the
/// torque the drive needs, -r*T_set + b*omega, in the integrator (no error to begin with), and after
/// the pull roll speeds up 10 -> 11 m/s (b*omega grows by 0.2 N.m) the integral takes the friction's
/// change up: the tension is back at 400 N to 1e-6 N (the loop rings lightly: the span's transport
/// damps it, at v/L), where the integrator held at its start would leave b*d(omega)/(r + kp) = 0.29 N.
#[test]
fn a_pi_loop_holds_its_set_point_against_bearing_friction() {
    for lag in [0.0, 0.002] {
        let mut line = initialized(&looped_line(json!([[0.0, 10.0], [0.5, 10.0], [1.5, 11.0]]), 0.0, lag));
        assert!((get(&line, "entry.T") - 400.0).abs() < 1e-8, "lag {lag}: starts at {}", get(&line, "entry.T"));
        let omega = get(&line, "unwind.omega");
        let needed = -0.5 * 400.0 + 0.1 * omega;
        assert!((get(&line, "unwind.loop.I") - needed).abs() < 1e-8, "lag {lag}: loop.I = {} vs {needed}", get(&line, "unwind.loop.I"));
        let mut worst: f64 = 0.0;
        for _ in 0..3000 {
            line.do_step(0.01).unwrap();
            worst = worst.max((get(&line, "entry.T") - 400.0).abs());
        }
        assert!(worst > 0.1, "lag {lag}: the ramp must move the tension (worst {worst} N)");
        let error = get(&line, "entry.T") - 400.0;
        assert!(error.abs() < 1e-6, "lag {lag}: {error} N off after 30 s");
        let needed = -0.5 * 400.0 + 0.1 * get(&line, "unwind.omega");
        assert!((get(&line, "unwind.tau") - needed).abs() < 1e-6, "lag {lag}: tau {} vs {needed}", get(&line, "unwind.tau"));
    }
}

/// The looped line whose unwinder holds the idler's load cell (wrap 90 degrees) at 500 N: the
/// roller's output load_cell.F wired into loop.measured. Its spans start strained (F = 500 N at
/// 1.6e-3): a load cell has no slope where both forces are 0, so the steady state is sought from there.
fn load_cell_looped_line(pull: Value) -> Value {
    let mut spec = looped_line(pull, 0.0, 0.0);
    spec["parts"][1]["start"]["eps_start"] = json!(1.6e-3);
    spec["parts"][3]["start"]["eps_start"] = json!(1.6e-3);
    spec["parts"][2]["wrap"] = json!(90.0);
    spec["parts"][0]["start"]["loop.set"] = json!(500.0);
    let connections = spec["connections"].as_array_mut().unwrap();
    connections.pop();
    connections.push(connect("idler", "load_cell.F", "unwind", "loop.measured"));
    spec
}

/// A PI loop on a load cell [R10] (physics, "A load cell"): it starts at its set point, and after the
/// pull roll's 10 -> 11 m/s ramp its integral brings F = sqrt(T_a^2 + T_b^2) (cos 90 degrees = 0) back
/// to 500 N to 1e-6 N; the line's own output idler.F is the same force. A connection that reads the
/// load cell of a roller without a wrap is refused by name.
#[test]
fn a_pi_loop_on_a_load_cell_holds_its_set_point() {
    let mut line = initialized(&load_cell_looped_line(json!([[0.0, 10.0], [0.5, 10.0], [1.5, 11.0]])));
    let cell = |line: &Line| get(line, "entry.T").hypot(get(line, "exit.T"));
    assert!((cell(&line) - 500.0).abs() < 1e-8, "starts at {}", cell(&line));
    let mut worst: f64 = 0.0;
    for _ in 0..2000 {
        line.do_step(0.01).unwrap();
        worst = worst.max((cell(&line) - 500.0).abs());
    }
    assert!(worst > 0.1, "the ramp must move the load cell (worst {worst} N)");
    assert!((cell(&line) - 500.0).abs() < 1e-6, "{} N off after 20 s", cell(&line) - 500.0);
    assert!((get(&line, "idler.F") - cell(&line)).abs() < 1e-9, "idler.F {} vs {}", get(&line, "idler.F"), cell(&line));
    let mut spec = load_cell_looped_line(json!([[0.0, 10.0]]));
    spec["parts"][2].as_object_mut().unwrap().remove("wrap");
    let err = instantiate(&spec).err().expect("refused");
    assert!(err.message.contains("reads its load_cell.F, which needs a wrap > 0"), "{}", err.message);
}

/// A loop's set point as the line's input `unwind.T_set` (the scene's switch): the line moves to it;
/// and a tunable gain set between steps changes the response (the same step with another kp).
#[test]
fn a_set_point_input_moves_the_line_and_a_tunable_gain_changes_its_response() {
    let mut spec = looped_line(json!([[0.0, 10.0]]), 0.0, 0.0);
    spec["parts"][0]["set_input"] = json!(true);
    let runs: Vec<Vec<f64>> = [0.2, 0.6]
        .iter()
        .map(|&kp| {
            let mut line = initialized(&spec);
            assert!(line.description().variable_by_name("unwind.loop.set").is_none(), "the set point is the input");
            line.do_step(0.1).unwrap();
            line.set_real(vr(&line, "unwind.loop.kp"), kp).unwrap();
            line.set_real(vr(&line, "unwind.T_set"), 450.0).unwrap();
            (0..600).map(|_| {
                line.do_step(0.01).unwrap();
                get(&line, "entry.T")
            })
            .collect()
        })
        .collect();
    for (kp, run) in [0.2, 0.6].iter().zip(&runs) {
        assert!((run[run.len() - 1] - 450.0).abs() < 1e-2, "kp {kp}: the line settles at the new set point ({})", run[run.len() - 1]);
    }
    let apart = runs[0].iter().zip(&runs[1]).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(apart > 1.0, "another gain must give another response (they differ by {apart} N at most)");
}

/// An ideal speed drive on the line's input `pull.v_ref` (speed.input): in Co-Simulation its omega
/// jumps with the input, the damping of the span into it sees the new speed at once, and the spans follow by transport; in Model Exchange the event update that
/// follows moves omega to v/r and reports the states changed.
#[test]
fn an_ideal_speed_drive_follows_its_input_in_both_interfaces() {
    let mut spec = paper_line("equilibrium");
    spec["parts"][4].as_object_mut().unwrap().remove("profile");
    spec["parts"][4]["start"] = json!({"J": 0.01, "R": 0.1, "b": 0.0, "speed.input": true, "loop.speed": 10.0});
    spec["parts"][4]["speed_input"] = json!(true);
    let mut line = initialized(&spec);
    assert!((get(&line, "pull.v") - 10.0).abs() < 1e-12 && (get(&line, "pull.omega") - 100.0).abs() < 1e-9);
    let before = get(&line, "exit.T");
    line.set_real(vr(&line, "pull.v_ref"), 10.5).unwrap();
    assert_eq!((get(&line, "pull.v"), get(&line, "pull.omega")), (10.5, 105.0));
    // The span's damping sees the new speed at once: d_r*EA*(1 + eps)*dv/L = 1e-3*225e3*0.5/1.5 = 75 N.
    let jump = get(&line, "exit.T") - before;
    assert!((jump - 75.0).abs() < 0.5, "exit.T jumps by {jump} N");
    line.do_step(0.01).unwrap();
    assert_eq!(get(&line, "pull.omega"), 105.0, "held: no slope within the step");
    let (mut me, r) = instantiate(&spec).unwrap();
    me.initialize(&Experiment { model_exchange: true, ..Experiment::default() }, &r).unwrap();
    me.set_real(vr(&me, "pull.v_ref"), 10.5).unwrap();
    assert_eq!(get(&me, "pull.v"), 10.5);
    assert!(me.event_update().states_changed, "the event update moves omega");
    assert!((get(&me, "pull.omega") - 105.0).abs() < 1e-12, "omega {}", get(&me, "pull.omega"));
}

/// The looped paper line whose unwinder feeds its inertia forward on the pull roll's input v_ref (an
/// ideal speed drive on it; line.json's feedforward_from).
fn fed_forward_on_an_input() -> Value {
    let mut spec = looped_line(json!([[0.0, 10.0]]), 0.0, 0.0);
    spec["parts"][0]["start"]["loop.feedforward"] = json!(true);
    spec["parts"][0]["start"]["loop.speed"] = json!(10.0);
    spec["parts"][0]["feedforward_from"] = json!("pull");
    spec["parts"][4].as_object_mut().unwrap().remove("profile");
    spec["parts"][4]["start"] = json!({"J": 0.01, "R": 0.1, "b": 0.0, "speed.input": true, "loop.speed": 10.0});
    spec["parts"][4]["speed_input"] = json!(true);
    spec
}

/// A feed-forward on another part's input v_ref [R10]: in Co-Simulation the feeding roller reads the
/// input as its loop.speed and, without an input derivative, the input's difference over the last step
/// as its loop.acceleration (0 on the first step); Model Exchange, which has neither, is refused, naming
/// the input. With the feed-forward the unwinder's torque changes by J*a/r the step the ramp starts.
#[test]
fn a_feedforward_on_an_input_reference_takes_its_difference_over_the_last_step() {
    let spec = fed_forward_on_an_input();
    let mut line = initialized(&spec);
    let acceleration = |line: &Line| match &line.parts()[0] {
        line::part::Part::Roller(r) => (r.params.loop_speed, r.params.loop_acceleration),
        _ => unreachable!("the unwinder is a roller"),
    };
    let h = 0.01;
    line.do_step(h).unwrap();
    assert_eq!(acceleration(&line), (10.0, 0.0), "a constant reference has no slope");
    let tau = get(&line, "unwind.tau");
    line.set_real(vr(&line, "pull.v_ref"), 10.02).unwrap(); // 2 m/s2 over the last step
    line.do_step(h).unwrap();
    let (v, a) = acceleration(&line);
    assert_eq!(v, 10.02);
    assert!((a - 2.0).abs() < 1e-9, "the difference over the last step: {a}");
    // J*a/r = 8*2/0.5 = 32 N.m more torque fed forward to speed the roll up (the loop's own share moves far less).
    let fed = get(&line, "unwind.tau") - tau;
    assert!(fed > 20.0, "the feed-forward moved the torque by {fed} N.m");
    line.do_step(h).unwrap();
    assert_eq!(acceleration(&line).1, 0.0, "the reference held since the last step");

    // An FMU state carries the reference where the last step started: a restored copy takes the same difference.
    line.set_real(vr(&line, "pull.v_ref"), 10.05).unwrap();
    let saved = Snapshot { phase: Phase::StepComplete, time: line.time(), experiment: Experiment::default(), model: line.clone() };
    let bytes = saved.to_bytes();
    line.do_step(h).unwrap();
    let mut copy = Snapshot::<Line>::from_bytes(&bytes, &line).unwrap().model;
    copy.do_step(h).unwrap();
    assert!((acceleration(&copy).1 - 3.0).abs() < 1e-9, "restored: {:?}", acceleration(&copy));
    assert_eq!(copy.states(), line.states());

    let (mut me, r) = instantiate(&spec).unwrap();
    let err = me.initialize(&Experiment { model_exchange: true, ..Experiment::default() }, &r).unwrap_err();
    assert!(err.message.contains("pull.v_ref") && err.message.contains("Model Exchange"), "{}", err.message);
}

/// A sampled loop in the line [R14] (the unwinder's PI sampled at 2 ms, each sample applied 1 ms
/// late): the equilibrium start is steady (solved with the loop continuous, then sampled there) and
/// stays flat, the line's steps stop at the samples, and after the pull roll's ramp the loop takes the
/// tension back to its set point as the continuous loop does, to 1e-6 N. In Model Exchange the samples
/// and their applications are the line's time events.
#[test]
fn a_sampled_loop_in_the_line_starts_steady_and_holds_its_set_point() {
    let mut spec = looped_line(json!([[0.0, 10.0], [0.5, 10.0], [1.5, 11.0]]), 0.0, 0.0);
    spec["parts"][0]["start"]["loop.sample"] = json!(2e-3);
    spec["parts"][0]["start"]["loop.delay"] = json!(1e-3);
    let mut line = initialized(&spec);
    let mut flat: f64 = 0.0;
    for _ in 0..50 {
        line.do_step(0.01).unwrap();
        flat = flat.max((get(&line, "entry.T") - 400.0).abs());
    }
    assert!(flat < 1e-8, "the start moves by {flat} N before the ramp");
    let mut worst: f64 = 0.0;
    for _ in 0..2950 {
        line.do_step(0.01).unwrap();
        worst = worst.max((get(&line, "entry.T") - 400.0).abs());
    }
    assert!(worst > 0.1, "the ramp must move the tension (worst {worst} N)");
    assert!((get(&line, "entry.T") - 400.0).abs() < 1e-6, "{} N off after 30 s", get(&line, "entry.T") - 400.0);

    // The hold acts: through the ramp the sampled loop's tension is not the continuous one's.
    let mut continuous = initialized(&looped_line(json!([[0.0, 10.0], [0.5, 10.0], [1.5, 11.0]]), 0.0, 0.0));
    let mut sampled = initialized(&spec);
    for _ in 0..70 {
        continuous.do_step(0.01).unwrap();
        sampled.do_step(0.01).unwrap();
    }
    let apart = (get(&continuous, "entry.T") - get(&sampled, "entry.T")).abs();
    assert!(apart > 1e-4, "the hold must change the response: {apart} N apart at 0.7 s");

    let (mut me, r) = instantiate(&spec).unwrap();
    me.initialize(&Experiment { model_exchange: true, ..Experiment::default() }, &r).unwrap();
    let mut next = me.event_update().next_event_time;
    for due in [2e-3, 3e-3, 4e-3] {
        assert!((next.unwrap() - due).abs() < 1e-15, "next event {next:?}, expected {due}");
        me.set_time(due);
        next = me.event_update().next_event_time;
    }
}

/// A powder-braked unwinder (5 N.m on R = 0.1 m: 50 N while it turns) feeding a pull roll that stops
/// from 1 m/s over [0.5, 1] s: the unwinder stops with it and its brake holds the span's tension.
/// From 1 s to 10 s after the stop the tension drifts by less than 1e-6 relative and stays within the
/// brake's rating (T r <= B), at 1 and 10 ms. Its grip is the held torque over B.
#[test]
fn a_braked_stopped_line_holds_its_tension() {
    let (b, r) = (5.0, 0.1);
    let unwind = roller("unwind", "unwinder", json!({"J": 0.01, "R": r, "b": 0.0, "v_start": 1.0, "roll": 1, "web_a.eps": 0.0}), Some(json!({"brake": [[0.0, b]]})));
    let pull = prescribed("pull", "roller", json!([[0.0, 1.0], [0.5, 1.0], [1.0, 0.0]]));
    let spec = line_spec(vec![unwind, span("web", 1.0, 0.0, &["includeDamping"]), pull], chain(&["unwind", "web", "pull"]), "equilibrium");
    for h in [1e-3, 1e-2] {
        let mut line = initialized(&spec);
        assert!((get(&line, "web.T") - b / r).abs() < 1e-9 * b / r, "running: T {}", get(&line, "web.T"));
        while line.time() < 2.0 - 1e-9 {
            line.do_step(h).unwrap();
        }
        let held = get(&line, "web.T");
        assert!(held > 0.0 && held * r <= b, "h {h}: holds {held} N");
        assert!((get(&line, "unwind.brake.grip") * b - held * r).abs() < 1e-6 * b, "h {h}: grip {}", get(&line, "unwind.brake.grip"));
        while line.time() < 11.0 - 1e-9 {
            line.do_step(h).unwrap();
            let t = get(&line, "web.T");
            assert!((t - held).abs() < 1e-6 * held, "h {h}, t {}: T {t} N, {held} N at 2 s", line.time());
        }
    }
}

/// A speed-driven unwinder of radius r whose roll runs out by e [R15], a span of length L (its
/// length the moving tangent point's: `variableLength`, its frame_a from the unwinder's web_b.y),
/// a sink at the roll's surface speed, the web leaving the roll at the span's strain eps0 (no draw).
fn runout_line(e: f64, r: f64, length: f64, v: f64, eps0: f64) -> Value {
    let mut unwind = prescribed("unwind", "unwinder", json!([[0.0, v]]));
    for (k, x) in [("R", json!(r)), ("roll", json!(1)), ("runout", json!(true)), ("runout.e", json!(e)), ("runout.phase", json!(0.3)), ("runout.L", json!(length)), ("web_a.eps", json!(eps0))] {
        unwind["start"][k] = x;
    }
    let mut film = span("film", length, eps0, &["variableLength"]);
    for (k, x) in [("wp1.d_r", 0.0), ("wp2.d_r", 0.0), ("frame_a.x", 0.0), ("frame_a.y", 0.0), ("frame_b.x", 0.0), ("frame_b.y", length)] {
        film["start"][k] = json!(x);
    }
    let mut c = chain(&["unwind", "film", "snk"]);
    c.push(connect("unwind", "web_b.y", "film", "frame_a.y"));
    line_spec(vec![unwind, film, prescribed("snk", "sink", json!([[0.0, v]]))], c, "given")
}

/// The tension ripple of a roll with runout [R15] at the roll's rotation frequency, and its
/// amplitude as the span's first-order lag gives it (docs/physics.md, "A roll with runout"): the
/// payout omega*p = omega*(r + e*cos(psi)) forces L eps' + v eps = -(1 + eps0)^2 omega e cos(psi)/(1 + eps_a)
/// to first order, so T ripples by EA (e/L)(1 + eps0)/sqrt(1 + (r/L)^2) with eps_a = eps0, v = omega r.
/// At e/L = 1e-5 the neglected terms are of order e/L: the amplitude to 1e-4, fitted over ten
/// whole turns after thirty time constants L/v; the frequency from the zero crossings to 1e-4.
#[test]
fn a_roll_with_runout_ripples_its_span_at_its_turn_by_the_first_order_lag() {
    let (e, r, length, v, eps0) = (1e-5, 0.5, 1.0, 10.0, 1e-3);
    let ea = 4.5e9 * 50e-6;
    let samples = ripple(&mut initialized(&runout_line(e, r, length, v, eps0)), v / r);
    let (mean, amplitude) = fitted(&samples, v / r);
    let expected = ea * (e / length) * (1.0 + eps0) / (1.0 + (r / length).powi(2)).sqrt();
    assert!((amplitude / expected - 1.0).abs() < 1e-4, "ripple {amplitude} N against {expected} N");
    assert!((mean / (ea * eps0) - 1.0).abs() < 1e-4, "mean tension {mean} N against {} N", ea * eps0);
    let turn = std::f64::consts::TAU * r / v;
    let period = crossing_period(&samples, mean);
    assert!((period / turn - 1.0).abs() < 1e-4, "period {period} s against the turn {turn} s");
}

/// An oval roll [R15] (its support function's second harmonic, a = 1e-5 m, without runout): the payout
/// omega*(r + a cos(2 omega t)) forces the same lag at twice the turn's frequency, so T ripples by
/// EA (a/(2L))(1 + eps0)/sqrt(1 + (r/(2L))^2) there, to 1e-4; its period half a turn, to 1e-4.
#[test]
fn an_oval_roll_ripples_its_span_twice_a_turn_by_the_first_order_lag() {
    let (a, r, length, v, eps0) = (1e-5, 0.5, 1.0, 10.0, 1e-3);
    let ea = 4.5e9 * 50e-6;
    let mut spec = runout_line(0.0, r, length, v, eps0);
    for (k, x) in [("runout.h1.k", json!(2)), ("runout.h1.a", json!(a)), ("runout.h1.phase", json!(0.7))] {
        spec["parts"][0]["start"][k] = x;
    }
    let samples = ripple(&mut initialized(&spec), v / r);
    let (mean, amplitude) = fitted(&samples, 2.0 * v / r);
    let expected = ea * (a / (2.0 * length)) * (1.0 + eps0) / (1.0 + (r / (2.0 * length)).powi(2)).sqrt();
    assert!((amplitude / expected - 1.0).abs() < 1e-4, "ripple {amplitude} N against {expected} N");
    let (_, at_turn) = fitted(&samples, v / r);
    assert!(at_turn < 1e-6 * expected, "an oval without runout ripples at the turn by {at_turn} N");
    let turn = std::f64::consts::TAU * r / v;
    let period = crossing_period(&samples, mean);
    assert!((period / (0.5 * turn) - 1.0).abs() < 1e-4, "period {period} s against half the turn {turn} s");
}

/// The span's tension over ten whole turns of a roll turning at omega, 200 samples a turn, after thirty
/// time constants L/v and more (three seconds): (time from the first sample, T).
fn ripple(line: &mut Line, omega: f64) -> Vec<(f64, f64)> {
    let turn = std::f64::consts::TAU / omega;
    let per_turn = 200;
    let h = turn / per_turn as f64;
    for _ in 0..(3.0 / turn).ceil() as usize * per_turn {
        line.do_step(h).unwrap();
    }
    let start = line.time();
    (0..10 * per_turn)
        .map(|_| {
            line.do_step(h).unwrap();
            (line.time() - start, get(line, "film.T"))
        })
        .collect()
}

/// The mean and the amplitude at the frequency omega by least squares on (1, cos, sin) over whole
/// periods, where the columns are orthogonal.
fn fitted(samples: &[(f64, f64)], omega: f64) -> (f64, f64) {
    let n = samples.len() as f64;
    let mean = samples.iter().map(|s| s.1).sum::<f64>() / n;
    let a = 2.0 / n * samples.iter().map(|&(t, y)| (y - mean) * (omega * t).cos()).sum::<f64>();
    let b = 2.0 / n * samples.iter().map(|&(t, y)| (y - mean) * (omega * t).sin()).sum::<f64>();
    (mean, a.hypot(b))
}

/// The mean spacing of the upward crossings of `level`, linearly interpolated: the ripple's period.
fn crossing_period(samples: &[(f64, f64)], level: f64) -> f64 {
    let crossings: Vec<f64> = samples
        .windows(2)
        .filter(|w| w[0].1 < level && w[1].1 >= level)
        .map(|w| w[0].0 + (level - w[0].1) / (w[1].1 - w[0].1) * (w[1].0 - w[0].0))
        .collect();
    assert!(crossings.len() >= 9, "{} crossings", crossings.len());
    (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64
}

/// A source and a speed-driven winder of radius r at v, with a lay-on roller [R18] pressed on the winder
/// by F on a 20 kg carriage (nip k = 1e7 N/m, damping ratio 0.6), and the winder's runout e [R15] (none at
/// e = 0), its span's length the moving tangent point's (`variableLength`, frame_b from the winder's web_a.y).
fn layon_line(e: f64, r: f64, v: f64, load: f64) -> Value {
    let length = 1.0;
    let mut wind = prescribed("wind", "winder", json!([[0.0, v]]));
    let mut start = vec![("R", json!(r)), ("roll", json!(2)), ("layon", json!(true)), ("layon.F", json!(load)), ("layon.angle", json!(0.4))];
    start.extend([("layon.m", json!(LAYON_MASS)), ("layon.k", json!(LAYON_K)), ("layon.c", json!(LAYON_C)), ("layon.r", json!(0.1))]);
    if e > 0.0 {
        start.extend([("runout", json!(true)), ("runout.e", json!(e)), ("runout.phase", json!(0.3)), ("runout.L", json!(length))]);
    }
    for (k, x) in start {
        wind["start"][k] = x;
    }
    let mut film = span("film", length, 1e-3, if e > 0.0 { &["variableLength"] } else { &[] });
    for (k, x) in [("frame_a.x", 0.0), ("frame_a.y", 0.0), ("frame_b.x", 0.0), ("frame_b.y", length)] {
        film["start"][k] = json!(x);
    }
    let mut c = chain(&["src", "film", "wind"]);
    if e > 0.0 {
        c.push(connect("wind", "web_a.y", "film", "frame_b.y"));
    }
    line_spec(vec![prescribed("src", "source", json!([[0.0, v]])), film, wind], c, "given")
}

const LAYON_MASS: f64 = 20.0;
const LAYON_K: f64 = 1e7;
/// A damping ratio of 0.6: c = 1.2 sqrt(k m).
const LAYON_C: f64 = 1.2 * 14142.135623730951;

/// On a round roll turning steadily the lay-on roller's nip carries its load [R18]: the carriage's
/// balance m X'' = N - F with X'' = 0 once it has settled (its own mode decays as exp(-0.6*707 t): 0.2 s
/// is 85 time constants), to 1e-6 N; its roller turns with the surface but for the slip that carries its
/// bearing (b_l omega_l = mu N tanh(slip/v_s) r_l: 7e-6 m/s here).
#[test]
fn a_layon_nip_carries_its_load_on_a_round_roll() {
    let (r, v, load) = (0.3, 10.0, 300.0);
    let mut line = initialized(&layon_line(0.0, r, v, load));
    for _ in 0..200 {
        line.do_step(1e-3).unwrap();
        assert!(get(&line, "wind.layon.N") > 0.0, "the nip let go at {} s", line.time());
    }
    let force = get(&line, "wind.layon.N");
    assert!((force - load).abs() < 1e-6, "N = {force} N against the load {load} N");
    let slip = v - get(&line, "wind.layon.omega") * 0.1;
    let bearing = 1e-3 * get(&line, "wind.layon.omega");
    let expected = 1e-3 * (bearing / (0.1 * 0.5 * load)).atanh();
    assert!((slip - expected).abs() < 1e-9, "slip {slip} m/s against {expected} m/s");
    assert!((get(&line, "wind.layon.delta") - load / LAYON_K).abs() < 1e-12);
}

/// With 1 mm of runout under 100 N the carriage keeps contact below the derived bounce speed and loses
/// it above [R18]: `layon::bounce_omega` for the nip's k and c (the rigid sqrt(F/(m e)) with F/k added
/// to e: 1 % here), at 0.97 and 1.03 of it, over a second sampled 200 times a turn after 0.3 s of settling.
#[test]
fn a_layon_roller_bounces_above_the_derived_speed() {
    let (e, r, load) = (1e-3, 0.3, 100.0);
    let l = roller::layon::LayOn { mass: LAYON_MASS, stiffness: LAYON_K, damping: LAYON_C, radius: 0.1, inertia: 0.05, bearing: 1e-3, mu: 0.5, v_slip: 1e-3, angle: 0.0 };
    let critical = roller::layon::bounce_omega(&l, load, e).unwrap();
    eprintln!("bounce: omega_c = {critical} rad/s, rigid {}", roller::layon::rigid_bounce_omega(&l, load, e));
    for (factor, bounces) in [(0.97, false), (1.03, true)] {
        let omega = factor * critical;
        let mut line = initialized(&layon_line(e, r, omega * r, load));
        let h = 2.0 * std::f64::consts::PI / omega / 200.0;
        let (mut least, mut apart) = (f64::INFINITY, 0);
        while line.time() < 1.3 {
            line.do_step(h).unwrap();
            if line.time() > 0.3 {
                let force = get(&line, "wind.layon.N");
                least = least.min(force);
                apart += (force <= 0.0) as usize;
            }
        }
        assert_eq!(apart > 0, bounces, "at {factor} omega_c: {apart} samples apart, least N {least} N");
    }
}

/// The line's steady start solves the lay-on roller's states too [R18]: its carriage at rest where the
/// nip carries the load (to 1e-6 N) and its roller turning with the surface but for its bearing's slip.
#[test]
fn a_steady_start_presses_the_layon_roller_with_its_load() {
    let (r, v, load) = (0.3, 10.0, 300.0);
    let mut spec = layon_line(0.0, r, v, load);
    spec["start"] = json!("equilibrium");
    let line = initialized(&spec);
    let force = get(&line, "wind.layon.N");
    assert!((force - load).abs() < 1e-6 && get(&line, "wind.layon.v").abs() < 1e-12, "N = {force} N against {load} N");
    assert!((get(&line, "wind.layon.omega") * 0.1 / v - 1.0).abs() < 1e-5);
}
