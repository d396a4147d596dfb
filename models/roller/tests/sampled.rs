//! A sampled loop [R14]: the loop's command through a zero-order hold of period loop.sample, each
//! sample applied loop.delay after it is taken; the samples and their applications are time events
//! (`cargo test -p roller --test sampled`).
//!
//! Tolerances: the steady state of a loop with integral action is exact whatever the hold, so the
//! speed it holds is checked to 1e-9 m/s (the Rosenbrock step's tolerance, 1e-10 relative, on 5 m/s).

use fmi_core::phase::Phase;
use fmi_core::snapshot::Snapshot;
use fmi_core::{Compiled, Experiment, Model, Resources, Variables};
use roller::description::{Integer, Real};
use roller::Roller;

/// A roller's speed loop on 5 m/s against the webs' pull, crossing over at about 10 Hz (kp*R^2/J =
/// 63 rad/s), sampled at `sample` with `delay`.
fn speed_loop(sample: f64, delay: f64) -> Result<Roller, String> {
    let mut m = Roller::at_start_values();
    for (var, x) in [(Real::J, 0.5), (Real::R, 0.1), (Real::b, 0.05), (Real::v_start, 4.0), (Real::loop_speed, 5.0), (Real::loop_kp, 3150.0),
                     (Real::loop_ki, 40000.0), (Real::loop_sample, sample), (Real::loop_delay, delay), (Real::web_a_F, 100.0), (Real::web_b_F, 150.0)] {
        m.set_real(var.vr(), x).unwrap();
    }
    m.set_integer(Integer::loop_kind.vr(), 2).unwrap();
    m.initialize(&Experiment::default(), &Resources::default()).map_err(|e| e.into_message())?;
    Ok(m)
}

fn get(m: &Roller, var: Real) -> f64 {
    m.get_real(var.vr()).unwrap()
}

/// Steps of h from t to end; the surface speed after each.
fn run(m: &mut Roller, t: &mut f64, end: f64, h: f64) -> Vec<f64> {
    let mut v = Vec::new();
    while *t < end - 1e-12 {
        m.set_time(*t);
        m.do_step(h).unwrap();
        *t += h;
        v.push(get(m, Real::v));
    }
    v
}

#[test]
fn a_sampled_pi_holds_its_set_point_and_its_torque_between_samples() {
    let (mut m, mut t) = (speed_loop(2e-3, 1e-3).unwrap(), 0.0);
    // Steps of 0.5 ms: four within a sample, the command held over them.
    let mut taus = Vec::new();
    while t < 0.1 - 1e-12 {
        m.set_time(t);
        m.do_step(5e-4).unwrap();
        t += 5e-4;
        taus.push(get(&m, Real::tau));
    }
    // taus[k] at (k + 1)*0.5 ms: the command sampled at 10 ms applies from 11 ms until 13 ms (an event
    // at a step's end applies when the next step starts, so 13 ms still shows it).
    for k in 22..25 {
        assert_eq!(taus[k].to_bits(), taus[k + 1].to_bits(), "held over [11, 13] ms: step {k}");
    }
    assert_ne!(taus[21], taus[22], "the sample taken at 10 ms applies at 11 ms");
    assert_ne!(taus[25], taus[26], "the next applies at 13 ms");
    let v = run(&mut m, &mut t, 3.0, 0.01);
    let last: f64 = v[v.len() - 50..].iter().map(|x| (x - 5.0).abs()).fold(0.0, f64::max);
    assert!(last < 1e-9, "the sampled loop holds 5 m/s to {last:e} m/s");

    let (mut continuous, mut tc) = (speed_loop(0.0, 0.0).unwrap(), 0.0);
    let sampled = run(&mut speed_loop(2e-3, 1e-3).unwrap(), &mut 0.0, 0.3, 0.01);
    let smooth = run(&mut continuous, &mut tc, 0.3, 0.01);
    let apart = sampled.iter().zip(&smooth).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(apart > 1e-4, "the hold must change the response ({apart} m/s apart at most)");
}

#[test]
fn in_model_exchange_the_samples_and_their_delays_are_time_events() {
    let mut me = speed_loop(2e-3, 1e-3).unwrap();
    let first = me.event_update();
    assert_eq!(first.next_event_time, Some(2e-3), "the first sample applied at the start, the next at 2 ms");
    let tau = get(&me, Real::tau);
    let mut t = 2e-3;
    for (due_next, moves) in [(3e-3, false), (4e-3, true), (5e-3, false), (6e-3, true)] {
        me.set_time(t);
        let update = me.event_update();
        assert!((update.next_event_time.unwrap() - due_next).abs() < 1e-15, "after {t}: {:?}", update.next_event_time);
        assert_eq!(update.states_changed, moves, "at {t}: the right-hand side jumps where a sample applies");
        t = due_next;
    }
    assert_eq!(get(&me, Real::tau), tau, "states unmoved: every sample commands the start's torque");
    // An importer that moves the time far past the samples: the next sample follows at once, after it.
    me.set_time(1000.0001);
    let update = me.event_update();
    assert!((update.next_event_time.unwrap() - 1000.0011).abs() < 1e-9, "{:?}", update.next_event_time);
    me.set_time(1000.0011);
    assert!((me.event_update().next_event_time.unwrap() - 1000.002).abs() < 1e-9);
}

#[test]
fn an_fmu_state_carries_the_waiting_sample() {
    let (mut m, mut t) = (speed_loop(2e-3, 1e-3).unwrap(), 0.0);
    run(&mut m, &mut t, 0.0105, 5e-4); // a sample taken at 0.010 s waits until 0.011 s
    let bytes = Snapshot { phase: Phase::StepComplete, time: t, experiment: Experiment::default(), model: m.clone() }.to_bytes();
    let ahead = run(&mut m, &mut t.clone(), 0.1, 5e-4);
    let mut copy = Snapshot::<Roller>::from_bytes(&bytes, &m).unwrap().model;
    let again = run(&mut copy, &mut t, 0.1, 5e-4);
    assert_eq!(ahead, again);
}

#[test]
fn a_delay_longer_than_the_period_is_refused() {
    let err = speed_loop(2e-3, 3e-3).unwrap_err();
    assert!(err.contains("loop.delay = 0.003") && err.contains("at most its period"), "{err}");
    let err = speed_loop(1e-6, 0.0).unwrap_err();
    assert!(err.contains("loop.sample = 0.000001 s") && err.contains("at least 0.00001 s"), "{err}");
}

#[test]
fn a_step_over_more_than_1e5_samples_is_refused_and_a_shorter_one_runs() {
    // 10 s over a 10 us sample would be a million solves in one call (the fuzzer's hour-long step).
    let mut m = speed_loop(1e-5, 0.0).unwrap();
    m.set_time(0.0);
    let err = m.do_step(10.0).unwrap_err().into_message();
    assert!(err.contains("holds 1000000 samples of loop.sample = 0.00001 s") && err.contains("take a shorter step"), "{err}");
    let v = get(&m, Real::v);
    m.set_time(0.0);
    m.do_step(1e-3).unwrap();
    assert!(get(&m, Real::v) != v, "a step of 100 samples runs");
}
