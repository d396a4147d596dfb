//! A winder in the Line: its tapered tension drive [R16], whose torque over its radius is
//! T(r) = T0*(1 - k*(1 - R/r)) while the roll grows, T0 the profile's tension table; and its stepwise
//! radius [R17], which the web meets and which steps by a layer once per layer.

use fmi_core::{Experiment, Model, Resources, Variables};
use line::Line;
use serde_json::{json, Value};

fn span(name: &str, length: f64) -> Value {
    let mut start = serde_json::Map::new();
    for side in ["wp1", "wp2"] {
        for (k, v) in [("E", 4.5e9), ("thickness", 50e-6), ("width", 1.0), ("density", 1390.0), ("d_r", 1e-3)] {
            start.insert(format!("{side}.{k}"), json!(v));
        }
    }
    start.insert("L".into(), json!(length));
    start.insert("eps_start".into(), json!(3e-5));
    start.insert("startAtEquilibrium".into(), json!(false));
    start.insert("includeDamping".into(), json!(true));
    json!({"name": name, "model": "ConvertingSpan", "role": "span", "start": start})
}

fn connect(from: &str, out: &str, to: &str, input: &str) -> Value {
    json!({"from": [from, out], "to": [to, input]})
}

/// A source at 5 m/s, a span, a winder with 2 mm per lap (its radius grows 20 % in about 5 s).
fn tapered_line(taper: f64, tension: Value) -> Value {
    winding_line(json!({"drive.taper": taper}), tension)
}

/// The line above, the winder's parameters `more` added.
fn winding_line(more: Value, tension: Value) -> Value {
    let src = json!({"name": "src", "model": "Roller", "role": "source", "start": {"J": 0.01, "R": 0.1, "b": 0.0},
                     "profile": {"speed": [[0.0, 5.0]]}});
    let wind = json!({"name": "wind", "model": "Roller", "role": "winder", "torque_input": true,
        "start": {"J": 2.0, "R": 0.2, "b": 0.05, "v_start": 5.0, "roll": 2, "wound.thickness": 2e-3, "wound.density": 700.0,
                  "wound.width": 1.0},
        "profile": {"tension": tension}});
    let mut wind = wind;
    for (k, v) in more.as_object().unwrap() {
        wind["start"][k] = v.clone();
    }
    // Speeds and the entering strain into the span, its forces back to the rollers, its strain to the winder [R3].
    let wires = [["src", "web_b.v", "a", "web_a.v"], ["src", "web_b.eps", "a", "web_a.eps"], ["wind", "web_a.v", "a", "web_b.v"],
                 ["a", "web_a.F", "src", "web_b.F"], ["a", "web_b.F", "wind", "web_a.F"], ["a", "web_b.eps", "wind", "web_a.eps"]];
    let c: Vec<Value> = wires.iter().map(|[from, out, to, input]| connect(from, out, to, input)).collect();
    json!({"format": "converting-span-line 1", "name": "taper", "experiment": {"start_time": 0.0, "stop_time": 6.0, "step": 1e-2},
           "start": "given", "parts": [src, span("a", 1.0), wind], "connections": c})
}

fn instantiate(spec: &Value, tag: &str) -> (Line, Resources) {
    let dir = std::env::temp_dir().join(format!("line-taper-{}-{tag}", std::process::id()));
    std::fs::create_dir_all(dir.join("profiles")).unwrap();
    std::fs::write(dir.join("line.json"), serde_json::to_string_pretty(spec).unwrap()).unwrap();
    for part in spec["parts"].as_array().unwrap() {
        if let Some(profile) = part.get("profile") {
            std::fs::write(dir.join("profiles").join(format!("{}.json", part["name"].as_str().unwrap())), profile.to_string()).unwrap();
        }
    }
    let r = Resources::from_path(Some(dir.to_str().unwrap()));
    (Line::instantiate(&r).unwrap_or_else(|e| panic!("{}", e.message)), r)
}

fn get(line: &Line, name: &str) -> f64 {
    line.get_real(line.description().variable_by_name(name).unwrap_or_else(|| panic!("no {name}")).vr).unwrap()
}

/// T0 of the profile below at t: 300 N, ramped to 360 N over 1-3 s.
fn tension_given(t: f64) -> f64 {
    300.0 + 60.0 * ((t - 1.0) / 2.0).clamp(0.0, 1.0)
}

/// tau/r of the winder's drive (tau_m = 0) against T(r) at every communication point, over a run in
/// which r grows by more than 20 %: equal to 1e-9 relative (the law is algebraic in r and T0, so only
/// rounding separates them, 1e-15 of each term).
#[test]
fn a_tapered_winders_torque_over_its_radius_is_the_hyperbolic_law() {
    let (k, r0) = (0.3, 0.2);
    let spec = tapered_line(k, json!([[0.0, 300.0], [1.0, 300.0], [3.0, 360.0]]));
    let (mut line, res) = instantiate(&spec, "law");
    line.initialize(&Experiment::default(), &res).unwrap_or_else(|e| panic!("{}", e.message));
    let mut t = 0.0;
    let mut worst: f64 = 0.0;
    while t < 6.0 - 1e-9 {
        line.do_step(1e-2).unwrap();
        t += 1e-2;
        let r = get(&line, "wind.r");
        let expected = tension_given(t) * (1.0 - k * (1.0 - r0 / r));
        worst = worst.max((get(&line, "wind.tau") / r - expected).abs() / expected);
    }
    let r = get(&line, "wind.r");
    assert!(r > 1.2 * r0, "the roll grew to {r} m only");
    assert!(worst < 1e-9, "tau/r off T(r) by {worst:e} relative");
    // The span follows the tapered tension (the winder's inertia and bearing aside): below T0 at the end.
    let tension = get(&line, "a.T");
    let tapered = 360.0 * (1.0 - k * (1.0 - r0 / r));
    assert!((tension - tapered).abs() < 0.02 * tapered, "the span carries {tension} N, the taper {tapered} N");
}

/// A taper on an unwinder's tension drive is refused by name; a winder driven by torque does not offer it
/// (it would not act there).
#[test]
fn a_taper_on_an_unwinder_is_refused_and_off_a_tension_drive_is_not_offered() {
    let mut spec = tapered_line(0.3, json!([[0.0, 300.0]]));
    spec["parts"][2]["start"]["roll"] = json!(1);
    let (mut line, res) = instantiate(&spec, "refused");
    let e = line.initialize(&Experiment::default(), &res).map(|_| ()).unwrap_err();
    assert!(e.message.contains("drive.taper = 0.3") && e.message.contains("an unwinder's tension is not tapered"), "{}", e.message);
    let mut torque = tapered_line(0.0, json!([[0.0, 300.0]]));
    torque["parts"][2]["profile"] = json!({"torque": [[0.0, 60.0]]});
    let (line, _) = instantiate(&torque, "torque");
    assert!(line.description().variable_by_name("wind.drive.taper").is_none());
    let (line, _) = instantiate(&tapered_line(0.3, json!([[0.0, 300.0]])), "offered");
    assert!(line.description().variable_by_name("wind.drive.taper").is_some());
}

/// The stepwise radius [R17] of the test, written out: h = 2 mm, R = 0.2 m, a merge of 30 degrees.
fn stepwise(r: f64) -> f64 {
    let (h, r0, m) = (2e-3, 0.2, 30.0 / 360.0);
    let u = (r - r0) / h;
    let n = u.floor();
    r0 + h * (n + ((u - n - (1.0 - m)) / m).max(0.0))
}

/// A winder with `wound.merge` = 30 deg: the radius the web meets, v/omega, is the stepwise law of the
/// smooth radius r at every communication point (to 1e-12 relative: both are computed from r, rounding
/// apart), lies within a layer below r, and holds each layer's radius R + n*h in turn (the run sees
/// every plateau of the 20 layers it winds), so it steps once per layer.
#[test]
fn a_stepwise_radius_holds_each_layer_and_merges_to_the_next() {
    let spec = winding_line(json!({"wound.merge": 30f64.to_radians()}), json!([[0.0, 300.0]]));
    let (mut line, res) = instantiate(&spec, "stepwise");
    line.initialize(&Experiment::default(), &res).unwrap_or_else(|e| panic!("{}", e.message));
    let (mut worst, mut plateaus) = (0.0f64, std::collections::BTreeSet::new());
    for _ in 0..600 {
        line.do_step(1e-2).unwrap();
        let (r, contact) = (get(&line, "wind.r"), get(&line, "wind.v") / get(&line, "wind.omega"));
        worst = worst.max((contact - stepwise(r)).abs() / r);
        assert!(contact <= r + 1e-12 && contact > r - 2e-3, "r = {r}, the web meets {contact}");
        let layer = (contact - 0.2) / 2e-3;
        if (layer - layer.round()).abs() < 1e-9 {
            plateaus.insert(layer.round() as i64);
        }
    }
    let layers = ((get(&line, "wind.r") - 0.2) / 2e-3).floor() as i64;
    assert!(layers >= 20, "wound {layers} layers only");
    assert!(worst < 1e-12, "v/omega off the stepwise law by {worst:e}");
    assert_eq!(plateaus, (0..=layers).collect(), "the plateaus seen");
}

/// An S-curve in a winder's tension table: the entries [t, T, curvature] make its jerk phases quadratic
/// (300 -> 200 N over 0.5-1.5 s at 400 N/s^2), and the drive's tau/r is that tension at every
/// communication point to 1e-12 relative (algebraic: rounding only), its end value at its end time.
#[test]
fn an_scurve_tension_reaches_the_winder_as_given() {
    let spec = winding_line(json!({}), json!([[0.0, 300.0], [0.5, 300.0], [1.0, 250.0, -400.0], [1.5, 200.0, 400.0]]));
    let (mut line, res) = instantiate(&spec, "scurve");
    line.initialize(&Experiment::default(), &res).unwrap_or_else(|e| panic!("{}", e.message));
    let tension = |t: f64| match t {
        t if t <= 0.5 => 300.0,
        t if t <= 1.0 => 300.0 - 200.0 * (t - 0.5) * (t - 0.5),
        t if t <= 1.5 => 200.0 + 200.0 * (1.5 - t) * (1.5 - t),
        _ => 200.0,
    };
    let (mut t, mut worst) = (0.0, 0.0f64);
    for _ in 0..200 {
        line.do_step(1e-2).unwrap();
        t += 1e-2;
        worst = worst.max((get(&line, "wind.tau") / get(&line, "wind.r") - tension(t)).abs() / tension(t));
        if (t - 1.5).abs() < 1e-9 {
            assert!((get(&line, "wind.tau") / get(&line, "wind.r") - 200.0).abs() < 1e-10);
        }
    }
    assert!(worst < 1e-12, "tau/r off the S-curve by {worst:e}");
}
