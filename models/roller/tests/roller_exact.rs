//! The Roller model: its core against the exact solution of
//! J*dw/dt = R*(F_b - F_a) + tau_m - b*w, state save/load, and the same
//! through its C API (`cargo test -p roller --test roller_exact`).
//! Drives, rolls, carriages and profiles: tests/profiles.rs; the FMI
//! layer's conformance suite on the Roller: tests/conformance.rs.
//!
//! Tolerances: the step is the closed-form solution evaluated with expm1, so
//! one step agrees with an independent evaluation of the closed form to a few
//! ulps; we use 1e-14 relative (about 50 ulps) per step and 1e-12 after many
//! steps, where the reference itself is evaluated in one shot.

use fmi_core::description::Causality;
use fmi_core::phase::Phase;
use fmi_core::snapshot::{fnv1a, Snapshot};
use fmi_core::{Compiled, Experiment, Model, Status, Variables};
use roller::description::{Real, DESCRIPTION};
use roller::parameters::{Inputs, Parameters};
use roller::Roller;

fn roller(j: f64, r: f64, b: f64, omega0: f64) -> Roller {
    let mut m = Roller::at_start_values();
    for (var, x) in [(Real::J, j), (Real::R, r), (Real::b, b), (Real::v_start, omega0 * r)] {
        m.set_real(var.vr(), x).unwrap();
    }
    m.initialize(&Experiment::default(), &Default::default()).unwrap();
    m
}

fn set_inputs(m: &mut Roller, f_up: f64, f_down: f64, tau: f64) {
    for (var, x) in [(Real::web_a_F, f_up), (Real::web_b_F, f_down), (Real::tau_m, tau)] {
        m.set_real(var.vr(), x).unwrap();
    }
}

/// omega(t) of [R1] with constant inputs, evaluated independently of the
/// model's code: w_inf + (w0 - w_inf) e^(-kt) for b > 0, w0 + a t for b = 0.
fn exact(j: f64, r: f64, b: f64, w0: f64, f_up: f64, f_down: f64, tau: f64, t: f64) -> f64 {
    let a = (r * (f_down - f_up) + tau) / j;
    if b == 0.0 {
        w0 + a * t
    } else {
        let k = b / j;
        let w_inf = a / k;
        w_inf + (w0 - w_inf) * (-k * t).exp()
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

#[test]
fn description_is_the_roller() {
    assert_eq!(DESCRIPTION.model_identifier, "Roller");
    let span = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../../modelDescription.xml")).unwrap();
    assert!(span.contains("guid=") && !span.contains(&*DESCRIPTION.guid), "the span and the roller share a GUID");
    let names: Vec<&str> = DESCRIPTION.variables.iter().map(|v| &*v.name).collect();
    assert_eq!(&names[..4], ["J", "R", "b", "v_start"]);
    assert_eq!(&names[14..19], ["web_a.F", "web_b.F", "web_a.eps", "tau_m", "F_load"]);
    assert_eq!(&names[19..22], ["web_a.v", "web_b.v", "web_b.eps"]);
    assert!(!DESCRIPTION.can_interpolate_inputs);
    // Inclusive and strict bounds from the XML (min and ConvertingSpan.range), the tighter holding.
    let range = |n: &str| DESCRIPTION.variable_by_name(n).unwrap().range;
    assert!(!range("J").contains(0.0) && !range("J").contains(9.9e-13) && range("J").contains(1e-12));
    assert!(!range("R").contains(0.0) && !range("R").contains(1e-12) && range("R").contains(1e-6));
    assert!(range("b").contains(0.0) && !range("b").contains(-1e-12));
    assert!(!range("web_a.eps").contains(-1.0) && range("web_a.eps").contains(-0.999));
    // Only the strains passed on, the drive's torque and, where the web may slip, the share of
    // traction and the air film (both read the tensions), the load cell and a lay-on roller's nip (its damper reads
    // the roll's growth, which reads the arriving strains) feed through from an input within a step.
    let through: Vec<&str> = DESCRIPTION
        .output_dependencies
        .iter()
        .filter(|d| d.on.as_ref().is_some_and(|on| on.iter().any(|vr| DESCRIPTION.variable(*vr).unwrap().causality == Causality::Input)))
        .map(|d| &*DESCRIPTION.variable(d.vr).unwrap().name)
        .collect();
    assert_eq!(through, ["web_b.eps", "tau", "web_b2.eps", "web_b3.eps", "web_b4.eps", "traction", "mu_eff", "h_air", "load_cell.F", "layon.N"]);
}

#[test]
fn steps_follow_the_exact_solution_with_damping() {
    let (j, r, b, w0) = (0.05, 0.1, 0.02, 50.0);
    let (f_up, f_down, tau) = (800.0, 650.0, 3.0);
    let mut m = roller(j, r, b, w0);
    set_inputs(&mut m, f_up, f_down, tau);
    assert_eq!(m.get_real(Real::omega.vr()).unwrap(), w0);
    assert_eq!(m.get_real(Real::web_a_v.vr()).unwrap(), r * w0);
    let mut t = 0.0;
    // Variable steps, including one far beyond the time constant J/b = 2.5 s.
    for h in [1e-6, 1e-3, 0.01, 0.37, 1.0, 10.0] {
        m.do_step(h).unwrap();
        t += h;
        let want = exact(j, r, b, w0, f_up, f_down, tau, t);
        assert!(rel(m.omega(), want) < 1e-13, "t = {t}: {} vs {want}", m.omega());
        assert!(rel(m.get_real(Real::web_a_v.vr()).unwrap(), r * want) < 1e-13);
    }
}

#[test]
fn without_damping_the_step_is_a_pure_integration() {
    let (j, r, w0) = (0.2, 0.05, 10.0);
    let mut m = roller(j, r, 0.0, w0);
    set_inputs(&mut m, 100.0, 140.0, -1.5);
    let a = (r * 40.0 - 1.5) / j; // 2.5 rad/s2
    let mut t = 0.0;
    for h in [0.1, 0.25, 2.0, 1e-4] {
        m.do_step(h).unwrap();
        t += h;
        assert!(rel(m.omega(), w0 + a * t) < 1e-14, "t = {t}");
    }
    // Balanced inputs hold the speed bit for bit.
    let held = m.omega();
    set_inputs(&mut m, 100.0, 100.0, 0.0);
    for _ in 0..1000 {
        m.do_step(0.01).unwrap();
    }
    assert_eq!(m.omega(), held);
}

#[test]
fn a_stiff_roller_lands_on_its_steady_state_without_overshoot() {
    // b/J*h = 1e9: an explicit method would explode; the exact step is L-stable.
    let (j, r, b) = (1e-6, 0.05, 1.0);
    let mut m = roller(j, r, b, 0.0);
    set_inputs(&mut m, 0.0, 0.0, 2.0);
    m.do_step(1000.0).unwrap();
    assert!(rel(m.omega(), 2.0 / b) < 1e-15, "{}", m.omega());
    for h in [1e-9, 1e-3, 1.0] {
        m.do_step(h).unwrap();
        assert!(rel(m.omega(), 2.0) < 1e-15);
    }
}

#[test]
fn a_million_tiny_steps_do_not_drift() {
    let (j, r, b, w0) = (0.05, 0.1, 0.0, 100.0);
    let mut m = roller(j, r, b, w0);
    set_inputs(&mut m, 0.0, 1e-6, 0.0); // a = 2e-6 rad/s2: increments of 2e-12 on 100
    for _ in 0..1_000_000 {
        m.do_step(1e-6).unwrap();
    }
    let want = exact(j, r, b, w0, 0.0, 1e-6, 0.0, 1.0);
    // A plain sum would lose the increments' low digits (ulp(100) = 1.4e-14).
    assert!((m.omega() - want).abs() < 1e-14, "{} vs {want}", m.omega());
}

#[test]
fn an_overflowing_step_is_discarded_and_changes_nothing() {
    let mut m = roller(1e-12, 1.0, 0.0, 1.0);
    set_inputs(&mut m, 0.0, 1e300, 0.0);
    let before = m.clone();
    let err = m.do_step(1.0).unwrap_err();
    assert_eq!(err.status, Status::Discard);
    assert!(err.message.contains("would reach omega = NaN"), "{}", err.message);
    assert_eq!(m, before);
}

#[test]
fn save_and_load_continue_bit_identically() {
    let mut m = roller(0.05, 0.1, 0.02, 50.0);
    set_inputs(&mut m, 800.0, 650.0, 3.0);
    m.do_step(0.123).unwrap();
    // Through the FMU-state format the layer serializes (magic, version, GUID, checksum).
    let snapshot = Snapshot { phase: Phase::StepComplete, time: 0.123, experiment: Default::default(), model: m.clone() };
    let bytes = snapshot.to_bytes();
    let back = Snapshot::<Roller>::from_bytes(&bytes, &Roller::at_start_values()).unwrap();
    assert_eq!(back, snapshot);
    let mut copy = back.model;
    m.do_step(0.5).unwrap();
    copy.do_step(0.5).unwrap();
    assert_eq!(copy.omega().to_bits(), m.omega().to_bits());
    // A state of another model (another GUID in the header, checksum intact) is refused.
    let mut foreign = bytes.clone();
    foreign[12..20].copy_from_slice(&fnv1a(b"{another model}").to_le_bytes());
    let end = foreign.len() - 8;
    let sum = fnv1a(&foreign[..end]);
    foreign[end..].copy_from_slice(&sum.to_le_bytes());
    let err = Snapshot::<Roller>::from_bytes(&foreign, &Roller::at_start_values()).unwrap_err();
    assert!(err.message.contains("another model"), "{err:?}");
}

/// Every continuous state goes into an FMU state and comes back: each set to its own value, the roller
/// read back equals the one saved (the fuzzer found the contact's and a brake's grips left out).
#[test]
fn an_fmu_state_holds_every_continuous_state() {
    let mut m = roller(0.05, 0.1, 0.02, 50.0);
    let all: Vec<usize> = (0..roller::parameters::STATES).collect();
    let x: Vec<f64> = all.iter().map(|&i| 0.3 + 0.01 * i as f64).collect();
    m.set_active_states(&all, &x).unwrap();
    let snapshot = Snapshot { phase: Phase::StepComplete, time: 0.1, experiment: Default::default(), model: m.clone() };
    let back = Snapshot::<Roller>::from_bytes(&snapshot.to_bytes(), &Roller::at_start_values()).unwrap();
    assert_eq!(back.model, m);
}

#[test]
fn physics_helpers_agree_with_the_equation() {
    let p = Parameters { inertia: 2.0, radius: 0.5, damping: 0.4, ..Parameters::default() };
    let u = Inputs { force_a: [10.0, 0.0, 0.0, 0.0], force_b: [30.0, 0.0, 0.0, 0.0], torque: 1.0, ..Inputs::default() };
    // J w' = R (F_b - F_a) + tau - b w = 0.5*20 + 1 - 0.4*3 = 9.8 at w = 3
    let mut m = roller(p.inertia, p.radius, p.damping, 3.0);
    set_inputs(&mut m, u.force_a[0], u.force_b[0], u.torque);
    assert!((m.derivatives()[0] - 9.8 / 2.0).abs() < 1e-15);
    assert_eq!(roller::physics::surface_speed(0.5, 3.0), 1.5);
}

/// The Roller's own scenes through the C API of its library (what any
/// model must do there: tests/conformance.rs).
mod c_api {
    use super::{exact, rel};
    use fmi_testkit::*;
    use roller::description::{Real, DESCRIPTION};
    use roller::Roller;

    /// One Roller instance through the C API, with the calls these tests use.
    struct Fmu(fmi_testkit::Fmu<Roller>);

    impl std::ops::Deref for Fmu {
        type Target = fmi_testkit::Fmu<Roller>;
        fn deref(&self) -> &Self::Target {
            &self.0
        }
    }

    impl Fmu {
        fn new(guid: &str) -> Result<Fmu, Vec<String>> {
            let setup = Setup { guid: Some(guid.into()), ..Setup::default() };
            instantiate::<Roller>(&setup).map(Fmu).map_err(|log| log.into_iter().map(|l| l.message).collect())
        }
        fn last_log(&self) -> String {
            self.messages().last().cloned().unwrap_or_default()
        }
        fn set(&self, vars: &[(Real, f64)]) -> i32 {
            let vrs: Vec<u32> = vars.iter().map(|(v, _)| v.vr()).collect();
            let xs: Vec<f64> = vars.iter().map(|(_, x)| *x).collect();
            self.set_reals_vr(&vrs, &xs)
        }
        fn get(&self, var: Real) -> (i32, f64) {
            let (status, x) = self.get_reals(&[var.vr()]);
            (status, x[0])
        }
        fn init(&self) -> i32 {
            self.setup_experiment(0.0);
            self.enter_init();
            self.exit_init()
        }
        fn step(&self, t: f64, h: f64) -> i32 {
            self.do_step(t, h)
        }
    }

    #[test]
    fn simulates_through_the_c_api() {
        let fmu = Fmu::new(&DESCRIPTION.guid).unwrap();
        assert_eq!(fmu.set(&[(Real::J, 0.05), (Real::R, 0.1), (Real::b, 0.02), (Real::v_start, 5.0)]), OK);
        assert_eq!(fmu.init(), OK);
        assert_eq!(fmu.get(Real::web_a_v), (OK, 5.0));
        assert_eq!(fmu.set(&[(Real::web_a_F, 800.0), (Real::web_b_F, 650.0), (Real::tau_m, 3.0)]), OK);
        let mut t = 0.0;
        for _ in 0..100 {
            assert_eq!(fmu.step(t, 0.01), OK);
            t += 0.01;
        }
        let want = exact(0.05, 0.1, 0.02, 50.0, 800.0, 650.0, 3.0, 1.0);
        assert!(rel(fmu.get(Real::omega).1, want) < 1e-12);
    }

    #[test]
    fn discard_keeps_the_state_and_a_saved_state_restores_it() {
        let fmu = Fmu::new(&DESCRIPTION.guid).unwrap();
        fmu.set(&[(Real::J, 1e-12), (Real::R, 1.0), (Real::v_start, 1.0)]);
        assert_eq!(fmu.init(), OK);
        let mut state: fmi2FMUstate = std::ptr::null_mut();
        // SAFETY: a live instance; the state is freed below.
        unsafe {
            assert_eq!(fmi2GetFMUstate(fmu.c, &mut state), OK);
            fmu.set(&[(Real::web_b_F, 1e12)]);
            assert_eq!(fmu.step(0.0, 1e300), DISCARD);
            assert!(fmu.last_log().contains("would reach omega ="), "{}", fmu.last_log());
            let mut last = f64::NAN;
            assert_eq!(fmi2GetRealStatus(fmu.c, 2, &mut last), OK);
            assert_eq!(last, 0.0);
            assert_eq!(fmu.get(Real::omega), (OK, 1.0));
            assert_eq!(fmi2SetFMUstate(fmu.c, state), OK);
            fmu.set(&[(Real::web_b_F, 1e-300)]);
            assert_eq!(fmu.step(0.0, 1.0), OK);
            assert_eq!(fmi2FreeFMUstate(fmu.c, &mut state), OK);
        }
    }
}
