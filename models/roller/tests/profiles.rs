//! The Roller's drives, rolls and carriage, each against an exact solution,
//! and its profile files (`cargo test -p roller --test profiles`).
//!
//! Tolerances: every piece of a step is a closed form, so agreement with an
//! independent evaluation is a few ulps per step; 1e-12 relative after
//! hundreds of steps leaves room for their accumulation and no more.

use fmi_core::snapshot::Snapshot;
use fmi_core::phase::Phase;
use fmi_core::{Compiled, Experiment, Model, Resources, Variables};
use roller::description::{Boolean, Integer, Real, Text};
use roller::Roller;
use std::f64::consts::PI;
use std::path::PathBuf;

fn profile_file(name: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("roller-profiles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// A roller with the given parameters and a profile (text, or none).
fn roller(reals: &[(Real, f64)], profile: Option<&str>, setup: impl FnOnce(&mut Roller)) -> Result<Roller, String> {
    let mut m = Roller::at_start_values();
    for (var, x) in reals {
        m.set_real(var.vr(), *x).unwrap();
    }
    setup(&mut m);
    if let Some(text) = profile {
        // One file per call: tests run in parallel, and a file another test rewrites reads empty meanwhile.
        static WRITTEN: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        let path = profile_file(&format!("{}.json", WRITTEN.fetch_add(1, std::sync::atomic::Ordering::Relaxed)), text);
        m.set_string(Text::profile.vr(), path.to_str().unwrap()).unwrap();
    }
    m.initialize(&Experiment::default(), &Resources::default()).map_err(|e| e.into_message())?;
    Ok(m)
}

fn get(m: &Roller, var: Real) -> f64 {
    m.get_real(var.vr()).unwrap()
}

fn step_to(m: &mut Roller, t: &mut f64, end: f64, h: f64) {
    while *t < end - 1e-12 {
        let hh = h.min(end - *t);
        m.set_time(*t);
        m.do_step(hh).unwrap();
        *t += hh;
    }
}

#[test]
fn a_speed_drive_follows_its_table_through_kinks_and_jumps() {
    let text = r#"{"speed": [[0, 1], [0.25, 2], [0.5, 2], [0.5, 3]]}"#;
    let mut m = roller(&[(Real::R, 0.1), (Real::J, 0.2), (Real::b, 0.1)], Some(text), |_| {}).unwrap();
    assert_eq!(get(&m, Real::web_a_v), 1.0);
    let mut t = 0.0;
    // Steps of 0.03 s straddle the kink at 0.25 s and the jump at 0.5 s.
    step_to(&mut m, &mut t, 0.24, 0.03);
    assert!((get(&m, Real::web_b_v) - (1.0 + 4.0 * 0.24)).abs() < 1e-14);
    step_to(&mut m, &mut t, 0.51, 0.03);
    assert_eq!(get(&m, Real::web_a_v), 3.0);
    // The torque that holds the speed: J*dv/dt/R + b*omega - R*(F_b - F_a).
    m.set_real(Real::web_a_F.vr(), 50.0).unwrap();
    assert!((get(&m, Real::tau) - (0.1 * 30.0 + 0.1 * 50.0)).abs() < 1e-12, "{}", get(&m, Real::tau));
}

#[test]
fn at_a_break_not_yet_applied_the_table_is_read_before_it() {
    // Model Exchange: at a time event the model shows the values before it until its event
    // update. Co-Simulation: at a communication point on a break the values after it, which the
    // master holds over the next step.
    let text = r#"{"speed": [[0, 1], [0.25, 2], [0.5, 2], [0.5, 3]]}"#;
    let make = || roller(&[(Real::R, 0.1), (Real::J, 0.2), (Real::b, 0.1)], Some(text), |_| {}).unwrap();
    let mut me = make();
    me.set_time(0.25); // the kink: the slope of the piece that ends there, 4 m/s2, then 0
    assert_eq!(me.derivatives()[0], 4.0 / 0.1);
    me.event_update();
    assert_eq!(me.derivatives()[0], 0.0);
    me.set_time(0.5); // the jump: 2 m/s, then 3 m/s
    assert_eq!(get(&me, Real::web_b_v), 2.0);
    me.event_update();
    assert_eq!(get(&me, Real::web_b_v), 3.0);
    for h in [0.1, 0.25] {
        let (mut cs, mut t) = (make(), 0.0);
        step_to(&mut cs, &mut t, 0.5, h); // sums to 0.5 exactly
        assert_eq!(get(&cs, Real::web_b_v), 3.0, "h = {h}, t = {t}");
        assert_eq!(cs.omega(), 2.0 / 0.1, "h = {h}: the roll turns at the speed before the jump until the next step");
    }
}

/// Model Exchange: a table's break is a time event where the right-hand side kinks or jumps; the
/// event update there says the states changed, so that an importer restarts its integrator, and one
/// where nothing was due does not.
#[test]
fn a_time_event_reports_the_states_changed() {
    let text = r#"{"torque": [[0.1, 0], [0.6, 2]]}"#;
    let mut me = roller(&[(Real::J, 0.5), (Real::b, 0.2), (Real::R, 1.0)], Some(text), |_| {}).unwrap();
    let start = me.event_update();
    assert!(!start.states_changed, "nothing is due at the start");
    assert_eq!(start.next_event_time, Some(0.1));
    me.set_time(0.1);
    let at = me.event_update();
    assert!(at.states_changed, "the ramp starts: the torque's slope jumps");
    assert_eq!(at.next_event_time, Some(0.6));
    assert!(!me.event_update().states_changed, "the event was applied");
}

#[test]
fn a_torque_ramp_is_integrated_exactly_across_steps_and_breakpoints() {
    // J w' = tau(t) - b w, tau a ramp from 0 to 2 N.m over [0.1, 0.6] s, then held.
    let (j, b) = (0.5, 0.2);
    let text = r#"{"torque": [[0.1, 0], [0.6, 2]]}"#;
    let mut m = roller(&[(Real::J, j), (Real::b, b), (Real::R, 1.0), (Real::v_start, 3.0)], Some(text), |_| {}).unwrap();
    let mut t = 0.0;
    step_to(&mut m, &mut t, 1.3, 0.07);
    // Independent: integrate piecewise in closed form.
    let k = b / j;
    let free = |w0: f64, h: f64| w0 * (-k * h).exp();
    let ramp = |w0: f64, a0: f64, a1: f64, h: f64| {
        // w' = a0 + a1 s - k w
        let c = w0 - a0 / k + a1 / (k * k);
        a0 / k + a1 * (h / k - 1.0 / (k * k)) + c * (-k * h).exp()
    };
    let w = free(3.0, 0.1);
    let w = ramp(w, 0.0, 4.0 / j, 0.5);
    let w = ramp(w, 2.0 / j, 0.0, 0.7);
    assert!((m.omega() - w).abs() < 1e-12 * w, "{} {w}", m.omega());
}

#[test]
fn an_unwinder_at_constant_speed_loses_radius_as_thickness_times_unstretched_travel_over_pi() {
    // Its web leaves at the strain table's eps: v*t metres of surface are v*t/(1+eps) of unstretched
    // web, so r^2 = r0^2 - h*v*t/(pi*(1+eps)) [R3].
    let (r0, h_w, v, rho, w, eps) = (0.3, 50e-6, 4.0, 1390.0, 1.2, 2e-3);
    let text = r#"{"speed": [[0, 4]], "strain": [[0, 2e-3]]}"#;
    let mut m = roller(
        &[(Real::R, r0), (Real::J, 6.0), (Real::wound_thickness, h_w), (Real::wound_density, rho), (Real::wound_width, w)],
        Some(text),
        |m| m.set_integer(Integer::roll.vr(), 1).unwrap(),
    )
    .unwrap();
    let mut t = 0.0;
    step_to(&mut m, &mut t, 10.0, 0.01);
    let r = (r0 * r0 - h_w * v * 10.0 / (PI * (1.0 + eps))).sqrt();
    // 1000 steps each rounding r^2: 1e-13 of r (the stretched length would be off by 2e-6 m).
    assert!((get(&m, Real::r) - r).abs() < 1e-13 * r, "{} {r}", get(&m, Real::r));
    assert!((m.omega() - v / r).abs() < 1e-12 * v / r);
    // The drive's torque is what J*omega' = tau [R1] needs (no web, no bearings): at a constant v,
    // omega' = -v*r'/r^2 = h*v^2/(2*pi*r^3*(1+eps)), with J(r) of [R3].
    let j = 6.0 + 0.5 * PI * rho * w * (r.powi(4) - r0.powi(4));
    let tau = j * h_w * v * v / (2.0 * PI * r.powi(3) * (1.0 + eps));
    assert!((get(&m, Real::tau) - tau).abs() < 1e-12 * tau, "{} {tau}", get(&m, Real::tau));
}

#[test]
fn a_free_winder_keeps_its_speed_as_its_inertia_grows() {
    // No torque, no damping: J*omega' = 0 [R1], while the radius grows; the web arriving brings the
    // angular momentum J'*omega. So omega stays, and d(r^2)/dt = h*r*omega/(pi*(1+eps)) (the web
    // arriving at strain eps, web_a.eps) makes r linear in t: r = r0 + c*t, c = h*omega/(2*pi*(1+eps)).
    // The exact pieces wind the web at the piece's mean radius, exact for a steady omega: r to
    // rounding over 2000 steps (1e-13 of r).
    let (r0, j0, h, omega, dt, end, eps) = (0.1, 0.05, 1e-3, 50.0, 0.001, 2.0, 1.5e-3);
    let mut m = roller(
        &[(Real::R, r0), (Real::J, j0), (Real::v_start, omega * r0), (Real::wound_thickness, h), (Real::wound_density, 1000.0), (Real::web_a_eps, eps)],
        None,
        |m| m.set_integer(Integer::roll.vr(), 2).unwrap(),
    )
    .unwrap();
    let mut t = 0.0;
    step_to(&mut m, &mut t, end, dt);
    let r = get(&m, Real::r);
    let c = h * omega / (2.0 * PI * (1.0 + eps));
    assert!(r > 0.105, "the roll grew to {r} m");
    assert!((m.omega() - omega).abs() < 1e-15 * omega, "{} {omega}", m.omega());
    let exact = r0 + c * end;
    assert!((r - exact).abs() < 1e-13 * exact, "{r} {exact}");
}

/// A roll that winds with no density keeps J while r moves: legal, but not the web's momentum or
/// mass, so initialization says so (once, naming both parameters), and says nothing with a density.
#[test]
fn a_roll_that_winds_without_density_warns_when_initialized() {
    let warnings = |density: f64| {
        let mut m = Roller::at_start_values();
        m.set_integer(Integer::roll.vr(), 1).unwrap();
        for (var, x) in [(Real::wound_thickness, 1e-4), (Real::wound_density, density)] {
            m.set_real(var.vr(), x).unwrap();
        }
        m.initialize(&Experiment::default(), &Resources::default()).unwrap()
    };
    let said = warnings(0.0);
    assert_eq!(said.len(), 1, "{said:?}");
    assert!(said[0].starts_with("wound.density = 0 with wound.thickness = 0.0001 m"), "{}", said[0]);
    assert!(warnings(1390.0).is_empty());
}

#[test]
fn a_dancer_carriage_follows_the_damped_oscillator() {
    // m y'' = load - F_a - F_b - d y' - k (y - y0); constant forces from rest.
    let (mass, d, k, y0, load) = (5.0, 30.0, 2000.0, 0.5, 500.0);
    let mut m = roller(
        &[(Real::carriage_m, mass), (Real::carriage_d, d), (Real::carriage_k, k), (Real::carriage_y_start, y0), (Real::F_load, load)],
        Some(r#"{"load": [[0, -100]]}"#),
        |m| m.set_boolean(Boolean::carriage.vr(), true).unwrap(),
    )
    .unwrap();
    m.set_real(Real::web_a_F.vr(), 100.0).unwrap();
    m.set_real(Real::web_b_F.vr(), 100.0).unwrap();
    let g = load - 100.0 - 200.0;
    let mut t = 0.0;
    step_to(&mut m, &mut t, 0.3, 0.0007);
    let (alpha, beta) = (d / (2.0 * mass), (k / mass - (d / (2.0 * mass)).powi(2)).sqrt());
    let y = y0 + g / k - g / k * (-alpha * t).exp() * ((beta * t).cos() + alpha / beta * (beta * t).sin());
    assert!((get(&m, Real::y) - y).abs() < 1e-13, "{} {y}", get(&m, Real::y));
    assert_eq!(get(&m, Real::web_a_y), y0 - get(&m, Real::y));
    assert_eq!(get(&m, Real::web_b_x), 2.0 * get(&m, Real::r));
}

#[test]
fn set_events_change_the_roll_at_the_same_surface_speed_and_the_brake_mid_step() {
    let text = r#"{"set": [{"time": 0.25, "b": 2}, {"time": 0.5, "J": 6, "R": 0.3}]}"#;
    let (j, r, w0) = (0.5, 0.1, 40.0);
    let mut m = roller(&[(Real::J, j), (Real::R, r), (Real::v_start, w0 * r)], Some(text), |_| {}).unwrap();
    let mut t = 0.0;
    step_to(&mut m, &mut t, 0.5, 0.1); // the brake engages inside the step [0.2, 0.3]
    let w = w0 * (-2.0 / j * 0.25).exp();
    assert!((m.omega() - w).abs() < 1e-13 * w, "{} {w}", m.omega());
    let v = r * m.omega();
    step_to(&mut m, &mut t, 0.6, 0.1); // the new roll from 0.5 s, braked: J w' = -b w
    let w_new = v / 0.3 * (-2.0f64 / 6.0 * 0.1).exp();
    assert!((m.omega() - w_new).abs() < 1e-13 * w_new, "{} {w_new}", m.omega());
    assert_eq!((get(&m, Real::J), get(&m, Real::R), get(&m, Real::b)), (6.0, 0.3, 2.0));
}

#[test]
fn an_fmu_state_carries_the_profile_and_continues_bit_identically() {
    let text = r#"{"tension": [[0, 200], [0.5, 200], [0.5, 0]], "strain": [[0, 1e-3]], "set": [{"time": 0.7, "b": 20}]}"#;
    let mut m = roller(&[(Real::J, 8.0), (Real::R, 0.35), (Real::v_start, 5.0)], Some(text), |m| m.set_integer(Integer::roll.vr(), 1).unwrap()).unwrap();
    let mut t = 0.0;
    step_to(&mut m, &mut t, 0.3, 0.1);
    assert_eq!(get(&m, Real::web_b_eps), 1e-3);
    let snapshot = Snapshot { phase: Phase::StepComplete, time: t, experiment: Default::default(), model: m.clone() };
    let back = Snapshot::<Roller>::from_bytes(&snapshot.to_bytes(), &Roller::at_start_values()).unwrap();
    let mut copy = back.model;
    let (mut t1, mut t2) = (t, t);
    step_to(&mut m, &mut t1, 1.0, 0.1);
    step_to(&mut copy, &mut t2, 1.0, 0.1);
    assert_eq!(m.omega().to_bits(), copy.omega().to_bits());
    assert_eq!(get(&copy, Real::b), 20.0);
}

#[test]
fn bad_profiles_are_refused_naming_the_file_and_the_problem() {
    let err = |text: &str, roll: i32| roller(&[], Some(text), |m| m.set_integer(Integer::roll.vr(), roll).unwrap()).unwrap_err();
    assert!(err(r#"{"speed": [[0, 1]], "torque": [[0, 1]]}"#, 0).contains("speed and torque tables: a roller has at most one drive"));
    assert!(err(r#"{"tension": [[0, 1]]}"#, 0).contains("a tension drive needs roll = 1 (unwinder) or 2 (winder)"));
    assert!(err(r#"{"load": [[0, 1]]}"#, 0).contains("a load table needs carriage = true"));
    assert!(err(r#"{"sped": [[0, 1]]}"#, 0).contains("unknown key \"sped\""));
    assert!(err(r#"{"set": [{"time": 1, "v_start": 2}]}"#, 0).contains("\"v_start\" cannot change during a run"));
    assert!(err(r#"{"set": [{"time": 1, "J": -2}]}"#, 0).contains("J = -2 is outside"));
    // A lay-on roller [R18]: its load table only with layon, never negative, and no new roll (R) under it.
    assert!(err(r#"{"layon": [[0, 100]]}"#, 2).contains("a layon table needs layon = true"));
    let layon = |text: &str| {
        let setup = |m: &mut Roller| {
            m.set_integer(Integer::roll.vr(), 2).unwrap();
            m.set_boolean(Boolean::layon.vr(), true).unwrap();
        };
        roller(&[], Some(text), setup).map(|_| ()).unwrap_err()
    };
    assert!(layon(r#"{"layon": [[0, 100], [1, -5]]}"#).contains("layon: the load at 1 s is -5 N"));
    assert!(layon(r#"{"set": [{"time": 1, "R": 0.3}]}"#).contains("a set event of R with layon = true"));
    let e = err(r#"{"speed": [[1, 1], [0, 2]]}"#, 0);
    assert!(e.starts_with("profile ") && e.contains(".json: speed: entry 1"), "{e}");
    // A missing file names itself (an absolute path on every platform).
    let missing = std::env::temp_dir().join("no such folder").join("line.json");
    let mut m = Roller::at_start_values();
    m.set_string(Text::profile.vr(), missing.to_str().unwrap()).unwrap();
    let e = m.initialize(&Experiment::default(), &Resources::default()).unwrap_err().into_message();
    assert!(e.contains(&format!("profile {}", missing.display())), "{e}");
    // A name in resources/ with no resource folder says why.
    m.set_string(Text::profile.vr(), "line.json").unwrap();
    let e = m.initialize(&Experiment::default(), &Resources::default()).unwrap_err().into_message();
    assert!(e.contains("profile = \"line.json\": cannot read resources/line.json"), "{e}");
}

#[test]
fn model_exchange_derivatives_match_the_steps() {
    // The ME right-hand side against a difference quotient of the CS step.
    let mut m = roller(
        &[(Real::J, 0.4), (Real::R, 0.2), (Real::b, 0.05), (Real::v_start, 2.0), (Real::wound_thickness, 1e-4), (Real::wound_density, 900.0)],
        Some(r#"{"tension": [[0, 100], [1, 150]]}"#),
        |m| m.set_integer(Integer::roll.vr(), 2).unwrap(),
    )
    .unwrap();
    m.set_real(Real::web_a_F.vr(), 120.0).unwrap();
    let d = m.derivatives();
    let (w0, r0) = (m.omega(), get(&m, Real::r));
    let h = 1e-6;
    m.set_time(0.0);
    m.do_step(h).unwrap();
    let (dw, dr) = ((m.omega() - w0) / h, (get(&m, Real::r) - r0) / h);
    assert!((dw - d[0]).abs() < 1e-5 * d[0].abs(), "{dw} {}", d[0]);
    assert!((dr - d[1]).abs() < 1e-5 * d[1].abs(), "{dr} {}", d[1]);
}

#[test]
fn an_event_a_few_ulps_from_a_communication_point_falls_on_it() {
    // One master computes t = k*h, another adds h up (FMPy): with 0.01 s steps the sum's
    // 19th step ends at 0.19000000000000003, the other's at 0.19. The new roll at 0.19 s
    // must land on the same step in both.
    let text = r#"{"set": [{"time": 0.19, "J": 6, "R": 0.3}], "torque": [[0, 1], [0.19, 1], [0.19, 2]]}"#;
    let make = || roller(&[(Real::J, 0.5), (Real::R, 0.1), (Real::v_start, 4.0)], Some(text), |_| {}).unwrap();
    let (mut exact, mut summed) = (make(), make());
    let mut t_summed = 0.0;
    for k in 0..25 {
        let t = k as f64 * 0.01;
        exact.set_time(t);
        exact.do_step(0.01).unwrap();
        summed.set_time(t_summed);
        summed.do_step(0.01).unwrap();
        t_summed += 0.01;
        let (a, b) = (exact.omega(), summed.omega());
        assert!((a - b).abs() <= 1e-12 * a.abs(), "after step {k}: {a} vs {b}");
        assert_eq!(get(&exact, Real::J), get(&summed, Real::J), "after step {k}");
    }
}

/// A roller holds its profile from a provisional initialization (an output read in
/// initialization mode) while a parameter it was checked against changes: the FMU state then
/// saved restores as it was. Initialization checks the profile again when it ends.
#[test]
fn a_state_saved_after_a_parameter_changed_under_a_provisional_profile_restores() {
    let text = r#"{"load": [[0, 400]]}"#;
    let mut m = roller(&[], Some(text), |m| m.set_boolean(Boolean::carriage.vr(), true).unwrap()).unwrap();
    m.set_boolean(Boolean::carriage.vr(), false).unwrap();
    let snapshot = Snapshot { phase: Phase::InitializationMode, time: 0.0, experiment: Default::default(), model: m.clone() };
    let back = Snapshot::<Roller>::from_bytes(&snapshot.to_bytes(), &Roller::at_start_values()).unwrap_or_else(|e| panic!("{}", e.message));
    assert_eq!(back.model, m);
    let e = back.model.clone().initialize(&Experiment::default(), &Resources::default()).unwrap_err().into_message();
    assert!(e.contains("a load table needs carriage = true"), "{e}");
}

/// A powder brake (B = 10 N.m, [R12]) on a roller at rest holds any torque up to its rating: its grip
/// carries tau_m/B and the surface creeps by at most brake.creep (1e-6 m); past its rating it slides
/// at B, the roller accelerating at (tau_m - B)/J. Loaded to u, the bristle's stiffness is
/// B r (1 - |u|)/delta_b: at 0.99 of its rating it settles at v_slip_b (1 - |u|)/delta_b = 100/s
/// (the overdamped mode; the damping is B r/(v_slip_b J) = 200/s), within the second.
#[test]
fn a_braked_roller_at_rest_holds_any_torque_up_to_its_rating() {
    let (j, r, b) = (0.5, 0.1, 10.0);
    for tau in [-9.9, -3.0, 0.0, 4.0, 9.9, 10.1] {
        let mut m = roller(&[(Real::J, j), (Real::R, r), (Real::b, 0.0), (Real::v_start, 0.0)], Some(r#"{"brake": [[0, 10]]}"#), |_| {}).unwrap();
        m.set_real(Real::tau_m.vr(), tau).unwrap();
        let mut t = 0.0;
        step_to(&mut m, &mut t, 0.5, 1e-3);
        let v_half = get(&m, Real::v);
        step_to(&mut m, &mut t, 1.0, 1e-3);
        let v = get(&m, Real::v);
        if tau.abs() < b {
            assert!(v.abs() < 1e-9, "tau {tau}: v = {v} m/s");
            // The roller's own step is tight to 1e-10 per step: a thousand steps leave 1e-8.
            assert!((get(&m, Real::brake_grip) - tau / b).abs() < 1e-8, "tau {tau}: grip {}", get(&m, Real::brake_grip));
        } else {
            // Sliding at B once the bristle has let go (its breakaway within the first 0.1 s).
            let (rate, expected) = ((v - v_half) / 0.5, r * (tau - b) / j);
            assert!((rate - expected).abs() < 1e-3 * expected, "tau {tau}: dv/dt = {rate} m/s2, expected {expected}");
            assert!((get(&m, Real::brake_grip) - 1.0).abs() < 1e-9);
        }
    }
}

/// A braked roller pulled by a web at 50 N (5 N.m against the brake's 10) slows from 1 m/s to a
/// stop at 1 s, then holds: from 1 s to 10 s after the stop the torque it holds, B times its grip
/// (5 N.m), drifts by less than 1e-6 relative and the surface stays at rest. At 1 and 10 ms.
#[test]
fn a_braked_roller_holds_after_it_stops() {
    let (j, r) = (0.5, 0.1);
    for h in [1e-3, 1e-2] {
        let mut m = roller(&[(Real::J, j), (Real::R, r), (Real::b, 0.0), (Real::v_start, 1.0)], Some(r#"{"brake": [[0, 10]]}"#), |_| {}).unwrap();
        m.set_real(Real::web_b_F.vr(), 50.0).unwrap();
        let mut t = 0.0;
        step_to(&mut m, &mut t, 0.5, h);
        // Sliding: J omega' = r F - B, omega = 10 - 10 t.
        assert!((m.omega() - 5.0).abs() < 1e-6, "h {h}: omega {} at 0.5 s", m.omega());
        step_to(&mut m, &mut t, 2.0, h);
        let held = 10.0 * get(&m, Real::brake_grip);
        assert!((held - 5.0).abs() < 1e-9, "h {h}: holds {held} N.m");
        for end in [4.0, 7.0, 11.0] {
            step_to(&mut m, &mut t, end, h);
            let now = 10.0 * get(&m, Real::brake_grip);
            assert!((now - held).abs() < 1e-6 * held, "h {h}, t {end}: holds {now} N.m, {held} at 2 s");
            assert!(get(&m, Real::v).abs() < 1e-12, "h {h}, t {end}: v {}", get(&m, Real::v));
        }
    }
}

/// The Co-Simulation step takes a table as linear over a piece [R1]'s exact step: a quadratic piece
/// (an S-curve) and a stepwise radius [R17] are refused by name at the step (Model Exchange and the
/// Line run both); a winder's taper [R16] on an unwinder is refused when initialization ends.
#[test]
fn what_the_co_simulation_step_cannot_follow_is_refused_by_name() {
    let curved = r#"{"speed": [[0, 1], [1, 1.5, 1], [2, 2.5, -1]]}"#;
    let mut m = roller(&[(Real::R, 0.1), (Real::J, 0.2)], Some(curved), |_| {}).unwrap();
    m.set_time(0.0);
    let e = m.do_step(0.1).unwrap_err().into_message();
    assert!(e.contains("speed table has a quadratic piece"), "{e}");
    let stepped = [(Real::R, 0.2), (Real::J, 1.0), (Real::wound_thickness, 1e-3), (Real::wound_density, 900.0), (Real::wound_merge, 0.5)];
    let mut m = roller(&stepped, Some(r#"{"tension": [[0, 100]]}"#), |m| m.set_integer(Integer::roll.vr(), 2).unwrap()).unwrap();
    m.set_time(0.0);
    let e = m.do_step(0.1).unwrap_err().into_message();
    assert!(e.contains("wound.merge = 0.5 rad: a stepwise radius [R17] runs in Model Exchange"), "{e}");
    let e = roller(&[(Real::drive_taper, 0.3)], Some(r#"{"tension": [[0, 100]]}"#), |m| m.set_integer(Integer::roll.vr(), 1).unwrap()).unwrap_err();
    assert!(e.contains("drive.taper = 0.3") && e.contains("an unwinder's tension is not tapered"), "{e}");
}
