//! Inlets and outlets (issue 21): a merge at a laminating nip, a split at a
//! slitter (`cargo test -p roller --test ports`). [R1] sums every web's pull,
//! [R4] likewise on a carriage, [R5] merges the arriving strains.
//!
//! Tolerances:
//! * [R5] against its closed form, evaluated exactly in integers and rounded
//!   once: 1e-15 relative. The model computes eps_b as a weighted mean,
//!   sum(q_i eps_i)/sum(q_i) with q_i = m_i/(1+eps_i), whose sums have terms
//!   of one sign for the strains here: about 2n+4 roundings of at most 2^-53
//!   (1.1e-16) each, most of which cancel between the two sums; 1e-15 is nine
//!   of them. The direct form 1/sum(w_i/(1+eps_i)) - 1 loses log10(1/eps)
//!   digits (about 1e-13 at eps ~ 1e-3), and the test shows it misses 1e-15.
//! * One inlet and one outlet: bit for bit the roller before ports existed
//!   (a hash of every output's bits, recorded from that code; the model's
//!   arithmetic is IEEE operations and the pure-Rust libm, no platform's).
//! * Equal webs: halving a tension is exact, so two halves pull as the whole
//!   bit for bit; the merged strain of two equal strains is (q*eps)/q, within
//!   one rounding of eps (2^-52 relative).
//! * The torque balance against the closed form of omega with constant
//!   forces: 1e-13 relative, as tests/roller_exact.rs.

use fmi_core::description::{Causality, Kind};
use fmi_core::phase::Phase;
use fmi_core::snapshot::{fnv1a, Snapshot};
use fmi_core::{Compiled, Experiment, Jacobian, Model, Variables};
use fmi_testkit::{Fmu, ERROR, OK};
use roller::description::DESCRIPTION;
use roller::Roller;

/// Sets a variable of any type by name, through the binding (what an importer's set reaches).
fn set(m: &mut Roller, name: &str, x: f64) {
    let v = DESCRIPTION.variable_by_name(name).unwrap_or_else(|| panic!("no variable {name}"));
    match v.kind {
        Kind::Real => m.set_real(v.vr, x),
        Kind::Integer => m.set_integer(v.vr, x as i32),
        Kind::Boolean => m.set_boolean(v.vr, x != 0.0),
        _ => unreachable!(),
    }
    .unwrap();
}

/// The plain roller's scenes, as the code before inlets and outlets ran them:
/// a damped winder on a dancer's carriage driven by tau_m, and a speed drive
/// (its torque answering the tensions); the bits of every Real output and
/// state derivative after each of 40 steps with changing inputs, and of the
/// partial derivatives of tau, der(omega) and der(y_dot) by the forces.
/// `extra` runs before initialization (a changed parameter).
fn plain_scenes(extra: &dyn Fn(&mut Roller), during: &dyn Fn(&mut Roller)) -> Vec<u64> {
    let speed_drive = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/speed_drive.json");
    let mut bits = Vec::new();
    for scene in 0..2 {
        let mut m = Roller::at_start_values();
        for (name, x) in [("J", 0.05), ("R", 0.1), ("b", 0.02), ("v_start", 5.0)] {
            set(&mut m, name, x);
        }
        if scene == 0 {
            for (name, x) in [("roll", 2.0), ("wound.thickness", 50e-6), ("wound.density", 1390.0), ("carriage", 1.0), ("carriage.m", 2.0), ("carriage.d", 5.0), ("carriage.k", 300.0)] {
                set(&mut m, name, x);
            }
        } else {
            let text = DESCRIPTION.variable_by_name("profile").unwrap().vr;
            m.set_string(text, speed_drive).unwrap();
        }
        extra(&mut m);
        m.initialize(&Experiment::default(), &Default::default()).unwrap();
        let outputs: Vec<u32> = DESCRIPTION.variables.iter().filter(|v| v.vr <= PLAIN_LAST_VR && v.kind == Kind::Real && matches!(v.causality, Causality::Output | Causality::Local)).map(|v| v.vr).collect();
        let vr = |name: &str| DESCRIPTION.variable_by_name(name).unwrap().vr;
        for k in 0..40 {
            let s = (k as f64 * 0.7).sin();
            for (name, x) in [("web_a.F", 800.0 + 90.0 * s), ("web_b.F", 650.0 - 40.0 * s), ("web_a.eps", 1.2e-3 + 3e-4 * s), ("tau_m", 3.0 * s), ("F_load", 1400.0 + 10.0 * s)] {
                set(&mut m, name, x);
            }
            during(&mut m);
            m.set_time(k as f64 * 1e-3);
            m.do_step(1e-3).unwrap();
            bits.extend(outputs.iter().map(|&o| m.get_real(o).unwrap().to_bits()));
            for (unknown, known) in [("tau", "web_a.F"), ("der(omega)", "web_b.F"), ("der(y_dot)", "web_a.F"), ("web_b.eps", "web_a.eps")] {
                bits.push(m.partial_derivative(vr(unknown), vr(known), Jacobian::CommunicationPoint).unwrap().to_bits());
            }
        }
    }
    bits
}

/// The last value reference of the roller before ports existed: the new
/// variables come after it, and no old one was renumbered.
const PLAIN_LAST_VR: u32 = 35;

/// `plain_scenes` as the code before ports computed it: 1600 values (2 scenes,
/// 40 steps, 16 outputs and state derivatives and 4 partial derivatives each),
/// FNV-1a of their bits (recorded at commit f55ee9f; recorded again when [R1] became
/// J*omega' = sum of torques and the exact pieces wound at their mean radius, and when [R3] wound
/// the web's unstretched length (the winder's r' reads web_a.eps): each moves the winder's scene,
/// and no port changed in those commits).
const BEFORE: (usize, u64) = (1600, 17803195908915702303);

fn fingerprint(bits: &[u64]) -> (usize, u64) {
    let bytes: Vec<u8> = bits.iter().flat_map(|b| b.to_le_bytes()).collect();
    (bits.len(), fnv1a(&bytes))
}

/// A roller of the given ports, set by name, initialized without a profile.
fn roller(settings: &[(&str, f64)]) -> Roller {
    let mut m = Roller::at_start_values();
    for &(name, x) in settings {
        set(&mut m, name, x);
    }
    m.initialize(&Experiment::default(), &Default::default()).unwrap();
    m
}

fn get(m: &Roller, name: &str) -> f64 {
    m.get_real(DESCRIPTION.variable_by_name(name).unwrap().vr).unwrap()
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

#[test]
fn the_new_variables_come_after_the_old_ones() {
    let names: Vec<&str> = DESCRIPTION.variables.iter().filter(|v| v.vr > PLAIN_LAST_VR).map(|v| &*v.name).collect();
    // The ports' variables right after the plain roller's (a variable added later comes after them).
    #[rustfmt::skip]
    assert_eq!(names[..24.min(names.len())], [
        "inlets", "outlets", "web_a.m", "web_a2.m", "web_a3.m", "web_a4.m",
        "web_a2.F", "web_a2.eps", "web_a3.F", "web_a3.eps", "web_a4.F", "web_a4.eps", "web_b2.F", "web_b3.F", "web_b4.F",
        "web_a2.v", "web_a3.v", "web_a4.v", "web_b2.v", "web_b2.eps", "web_b3.v", "web_b3.eps", "web_b4.v", "web_b4.eps",
    ]);
    // Value reference = position: the ModelStructure's indices are the value references.
    assert!(DESCRIPTION.variables.iter().enumerate().all(|(i, v)| v.vr == i as u32 + 1));
    let range = |n: &str| DESCRIPTION.variable_by_name(n).unwrap().range;
    assert!(range("inlets").contains(1.0) && range("inlets").contains(4.0) && !range("inlets").contains(0.0) && !range("inlets").contains(5.0));
    assert!(!range("web_a3.m").contains(0.0) && range("web_a3.m").contains(1e-9));
    assert!(!range("web_a4.eps").contains(-1.0) && range("web_a4.eps").contains(-0.999));
}

#[test]
fn one_inlet_and_one_outlet_are_the_roller_before_ports_bit_for_bit() {
    assert_eq!(fingerprint(&plain_scenes(&|_| {}, &|_| {})), BEFORE);
    // The unused ports' inputs and masses are not read, whatever they hold.
    let unused = |m: &mut Roller| {
        for (name, x) in [("web_a2.F", 3e4), ("web_a3.eps", 0.3), ("web_a4.F", -7.0), ("web_b2.F", 1e5), ("web_b4.F", 2.0), ("web_a2.eps", -0.5)] {
            set(m, name, x);
        }
    };
    let masses = |m: &mut Roller| {
        for (name, x) in [("web_a.m", 0.37), ("web_a2.m", 9.0)] {
            set(m, name, x);
        }
    };
    assert_eq!(fingerprint(&plain_scenes(&masses, &unused)), BEFORE);
    // And the check can fail: a second outlet's tension does move the roller.
    let two_outlets = |m: &mut Roller| set(m, "outlets", 2.0);
    assert_ne!(fingerprint(&plain_scenes(&two_outlets, &unused)), BEFORE);
}

/// Exact integer arithmetic for [R5]'s closed form.
mod exact {
    /// p/q correctly rounded to f64 (q > 0, p != 0): 64 quotient bits by long
    /// division and a sticky bit for what remains.
    pub fn ratio(p: i128, q: i128) -> f64 {
        let (negative, mut r, mut q) = (p < 0, p.unsigned_abs(), q as u128);
        let mut e = 0i32;
        while r < q {
            r <<= 1;
            e -= 1;
        }
        while r >= 2 * q {
            q <<= 1;
            e += 1;
        }
        let mut bits = 0u64;
        for _ in 0..64 {
            bits <<= 1;
            if r >= q {
                bits |= 1;
                r -= q;
            }
            r <<= 1;
        }
        let x = (bits | (r != 0) as u64) as f64 * 2f64.powi(e - 63);
        if negative { -x } else { x }
    }

    /// eps_b of [R5] for strains k_i/4096 and integer masses m_i:
    /// 1 + eps_b = M / (4096 * sum m_i/a_i) with a_i = 4096 + k_i, so
    /// eps_b = (M*P - 4096*sum m_i*P/a_i) / (4096*sum m_i*P/a_i), P = prod a_j.
    pub fn merged(k: &[i128], m: &[i128]) -> f64 {
        let a: Vec<i128> = k.iter().map(|k| 4096 + k).collect();
        let p: i128 = a.iter().product();
        let total: i128 = m.iter().sum();
        let inflow: i128 = m.iter().zip(&a).map(|(m, a)| m * (p / a)).sum();
        ratio(total * p - 4096 * inflow, 4096 * inflow)
    }
}

#[test]
fn the_merged_strain_is_the_closed_form_to_1e_15() {
    let k = [3i128, 11, 5, 40];
    let masses = [3i128, 1, 2, 7];
    let names = ["", "2", "3", "4"];
    let mut direct_worst = 0.0f64;
    for n in 2..=4 {
        let mut settings = vec![("inlets", n as f64)];
        let mass_names: Vec<String> = names.iter().map(|s| format!("web_a{s}.m")).collect();
        let strain_names: Vec<String> = names.iter().map(|s| format!("web_a{s}.eps")).collect();
        for i in 0..n {
            settings.push((mass_names[i].as_str(), masses[i] as f64));
            settings.push((strain_names[i].as_str(), k[i] as f64 / 4096.0));
        }
        let m = roller(&settings);
        let want = exact::merged(&k[..n], &masses[..n]);
        for outlet in ["web_b.eps", "web_b2.eps", "web_b3.eps", "web_b4.eps"] {
            let got = get(&m, outlet);
            assert!(rel(got, want) <= 1e-15, "{n} inlets, {outlet}: {got:e} vs {want:e}: {:e}", rel(got, want));
        }
        // The direct form of [R5], for contrast.
        let total = masses[..n].iter().sum::<i128>() as f64;
        let sum: f64 = (0..n).map(|i| masses[i] as f64 / total / (1.0 + k[i] as f64 / 4096.0)).sum();
        direct_worst = direct_worst.max(rel(1.0 / sum - 1.0, want));
    }
    assert!(direct_worst > 1e-15, "the direct form is as accurate ({direct_worst:e}): the tolerance has no teeth");
    // The reference itself: 1/3 rounded correctly, and a strain whose closed form is exact.
    assert_eq!(exact::ratio(1, 3), 1.0 / 3.0);
    assert_eq!(exact::merged(&[8, 8], &[1, 5]), 8.0 / 4096.0);
}

#[test]
fn two_equal_half_webs_merge_into_the_one_full_web() {
    let (eps, m_full, f_full) = (1.7e-3, 0.084, 950.0);
    let common = [("J", 0.05), ("R", 0.1), ("b", 0.02), ("v_start", 5.0), ("web_b.F", 700.0), ("tau_m", 2.0)];
    let mut one = roller(&[&common[..], &[("web_a.m", m_full), ("web_a.eps", eps), ("web_a.F", f_full)]].concat());
    #[rustfmt::skip]
    let halves = [("inlets", 2.0), ("web_a.m", m_full / 2.0), ("web_a2.m", m_full / 2.0), ("web_a.eps", eps), ("web_a2.eps", eps),
                  ("web_a.F", f_full / 2.0), ("web_a2.F", f_full / 2.0)];
    let mut two = roller(&[&common[..], &halves[..]].concat());
    assert_eq!(get(&one, "web_b.eps"), eps);
    assert!(rel(get(&two, "web_b.eps"), eps) <= f64::EPSILON, "{:e}", rel(get(&two, "web_b.eps"), eps));
    for _ in 0..100 {
        one.do_step(0.01).unwrap();
        two.do_step(0.01).unwrap();
    }
    assert_eq!(one.omega().to_bits(), two.omega().to_bits());
    // A slitter: one web split into two halves pulling half each.
    #[rustfmt::skip]
    let split = [("outlets", 2.0), ("web_b.F", 350.0), ("web_b2.F", 350.0), ("web_a.m", m_full), ("web_a.eps", eps), ("web_a.F", f_full)];
    let mut slit = roller(&[&common[..], &split[..]].concat());
    for _ in 0..100 {
        slit.do_step(0.01).unwrap();
    }
    assert_eq!(one.omega().to_bits(), slit.omega().to_bits());
    assert_eq!((get(&slit, "web_b.eps"), get(&slit, "web_b2.eps")), (eps, eps));
}

#[test]
fn several_webs_drive_the_roller_as_the_closed_form_of_the_torque_balance() {
    // J w' = r*(sum F_b - sum F_a) + tau_m - b*w with the forces held: w_inf + (w0 - w_inf) e^(-b t/J).
    let (j, r, b, w0, tau) = (0.05, 0.1, 0.02, 50.0, 3.0);
    let f_a = [300.0, 250.0, 120.0];
    let f_b = [150.0, 210.0, 90.0, 170.0];
    #[rustfmt::skip]
    let mut m = roller(&[("J", j), ("R", r), ("b", b), ("v_start", w0 * r), ("tau_m", tau), ("inlets", 3.0), ("outlets", 4.0),
        ("web_a.F", f_a[0]), ("web_a2.F", f_a[1]), ("web_a3.F", f_a[2]), ("web_a4.F", 1e6),
        ("web_b.F", f_b[0]), ("web_b2.F", f_b[1]), ("web_b3.F", f_b[2]), ("web_b4.F", f_b[3])]);
    let a = (r * (f_b.iter().sum::<f64>() - f_a.iter().sum::<f64>()) + tau) / j;
    let (k, mut t) = (b / j, 0.0);
    for h in [1e-6, 1e-3, 0.01, 0.37, 1.0, 10.0] {
        m.do_step(h).unwrap();
        t += h;
        let want = a / k + (w0 - a / k) * (-k * t).exp();
        assert!(rel(m.omega(), want) < 1e-13, "t = {t}: {} vs {want}", m.omega());
        for port in ["web_a.v", "web_a2.v", "web_a3.v", "web_a4.v", "web_b.v", "web_b2.v", "web_b3.v", "web_b4.v"] {
            assert_eq!(get(&m, port), get(&m, "web_b.v"), "{port}");
        }
    }
    assert!(rel(m.derivatives()[0], a - k * m.omega()) < 1e-12);
}

#[test]
fn a_carriage_is_pulled_up_by_every_web() {
    // [R4] with several webs: the same carriage as one web pulling with their sum, bit for bit.
    let base = [("carriage", 1.0), ("carriage.m", 2.0), ("carriage.d", 5.0), ("carriage.k", 300.0), ("F_load", 1500.0)];
    #[rustfmt::skip]
    let ports = [("inlets", 2.0), ("outlets", 3.0), ("web_a.F", 300.0), ("web_a2.F", 250.0),
                 ("web_b.F", 200.0), ("web_b2.F", 150.0), ("web_b3.F", 180.0)];
    let summed = [("web_a.F", 300.0 + 250.0), ("web_b.F", 200.0 + 150.0 + 180.0)];
    let mut many = roller(&[&base[..], &ports[..]].concat());
    let mut one = roller(&[&base[..], &summed[..]].concat());
    assert_eq!(many.derivatives(), one.derivatives());
    for _ in 0..50 {
        many.do_step(0.01).unwrap();
        one.do_step(0.01).unwrap();
    }
    assert_eq!((get(&many, "y").to_bits(), get(&many, "y_dot").to_bits()), (get(&one, "y").to_bits(), get(&one, "y_dot").to_bits()));
    assert!((get(&many, "y") - get(&many, "carriage.y_start")).abs() > 1e-3, "the carriage moved");
}

/// Every partial derivative of every Real output and state derivative by
/// every input against central differences of the values, at operating points
/// with unused ports (their derivatives exactly 0), a winder and an unwinder among them
/// (r' reads the web's strain at the roll [R3]); every nonzero one is among the
/// dependencies modelDescription.xml declares (the Line chains only those).
#[test]
fn directional_derivatives_agree_with_central_differences() {
    let speed_drive = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/speed_drive.json");
    let reference = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/reference_ramp.json");
    #[rustfmt::skip]
    let inputs = [("web_a.F", 300.0), ("web_a2.F", 250.0), ("web_a3.F", 120.0), ("web_a4.F", 80.0),
        ("web_b.F", 150.0), ("web_b2.F", 210.0), ("web_b3.F", 90.0), ("web_b4.F", 170.0),
        ("web_a.eps", 1.1e-3), ("web_a2.eps", 4.2e-3), ("web_a3.eps", -2e-4), ("web_a4.eps", 0.05), ("tau_m", 1.5), ("F_load", 1e3)];
    #[rustfmt::skip]
    let points: [(&[(&str, f64)], Option<&str>); 4] = [
        (&[("inlets", 3.0), ("outlets", 2.0), ("carriage", 1.0), ("b", 0.3), ("web_a.m", 0.2), ("web_a2.m", 0.05), ("web_a3.m", 0.7)], Some(speed_drive)),
        (&[("inlets", 4.0), ("outlets", 4.0), ("roll", 2.0), ("wound.thickness", 1e-3), ("wound.density", 1000.0), ("web_a4.m", 3.0)], None),
        (&[("inlets", 2.0), ("outlets", 4.0), ("layered", 1.0), ("web_a.m", 0.2)], None),
        (&[("roll", 1.0), ("wound.thickness", 1e-3), ("wound.density", 1000.0), ("loop.kind", 2.0), ("loop.kp", 0.2), ("loop.feedforward", 1.0)], Some(reference)),
    ];
    let declared = |unknown: u32, known: u32| {
        let d = DESCRIPTION.output_dependencies.iter().chain(DESCRIPTION.derivatives.iter()).find(|d| d.vr == unknown);
        d.is_none_or(|d| d.on.as_ref().is_none_or(|on| on.contains(&known)))
    };
    let unknowns: Vec<u32> = DESCRIPTION
        .variables
        .iter()
        .filter(|v| v.kind == Kind::Real && matches!(v.causality, Causality::Output | Causality::Local))
        .map(|v| v.vr)
        .collect();
    let (mut compared, mut zeros) = (0, 0);
    for (settings, profile) in points {
        let mut m = Roller::at_start_values();
        for &(name, x) in settings.iter().chain(&inputs) {
            set(&mut m, name, x);
        }
        if let Some(path) = profile {
            m.set_string(DESCRIPTION.variable_by_name("profile").unwrap().vr, path).unwrap();
        }
        m.initialize(&Experiment::default(), &Default::default()).unwrap();
        m.do_step(0.05).unwrap();
        for &(name, x) in &inputs {
            let known = DESCRIPTION.variable_by_name(name).unwrap().vr;
            let dx = 1e-6 * x.abs();
            for &unknown in &unknowns {
                let at = |y: f64| {
                    let mut n = m.clone();
                    n.set_real(known, y).unwrap();
                    n.get_real(unknown).unwrap()
                };
                let difference = (at(x + dx) - at(x - dx)) / (2.0 * dx);
                let analytic = m.partial_derivative(unknown, known, Jacobian::CommunicationPoint).unwrap();
                let what = DESCRIPTION.variable(unknown).unwrap().name.to_string() + " by " + name;
                assert!(analytic == 0.0 || declared(unknown, known), "d{what} = {analytic:e} is not a declared dependency");
                if difference == 0.0 {
                    assert_eq!(analytic, 0.0, "d{what}");
                    zeros += 1;
                } else {
                    let scale = analytic.abs().max(difference.abs()).max(at(x).abs() / x.abs());
                    assert!((analytic - difference).abs() <= 1e-7 * scale, "d{what}: {analytic:e} vs {difference:e}");
                    compared += 1;
                }
            }
        }
    }
    // The merge's, the ports' and the layers' derivatives were among them (23 + 26 nonzero at the first two
    // points, 12 at the layered one), and the unused ports' zeros.
    assert!(compared >= 55 && zeros > 100, "{compared} compared, {zeros} zero"); // 61 and 989 as written
}

#[test]
fn a_saved_state_with_several_ports_continues_bit_identically() {
    #[rustfmt::skip]
    let mut m = roller(&[("inlets", 3.0), ("outlets", 2.0), ("web_a.F", 300.0), ("web_a2.F", 250.0), ("web_a3.F", 120.0),
        ("web_b.F", 400.0), ("web_b2.F", 310.0), ("web_a2.eps", 2e-3), ("web_a3.m", 4.0)]);
    m.do_step(0.1).unwrap();
    let snapshot = Snapshot { phase: Phase::StepComplete, time: 0.1, experiment: Default::default(), model: m.clone() };
    let mut back = Snapshot::<Roller>::from_bytes(&snapshot.to_bytes(), &Roller::at_start_values()).unwrap().model;
    assert_eq!(back, m);
    m.do_step(0.3).unwrap();
    back.do_step(0.3).unwrap();
    assert_eq!(back.omega().to_bits(), m.omega().to_bits());
    assert_eq!(get(&back, "web_b2.eps").to_bits(), get(&m, "web_b2.eps").to_bits());
}

/// Bad ports and masses, through the C API: fmi2Error when initialization
/// ends, with one line naming the variable, its value and what is allowed.
#[test]
fn bad_ports_and_masses_are_refused_naming_the_variable() {
    for (name, x, allowed) in
        [("inlets", 0.0, "[1, 4]"), ("inlets", 5.0, "[1, 4]"), ("outlets", 5.0, "[1, 4]"), ("web_a2.m", 0.0, "(0"), ("web_a.m", -1.0, "(0")]
    {
        let fmu = Fmu::<Roller>::new();
        assert_eq!(fmu.set(name, x), OK, "{name} = {x}: set before initialization, checked when it ends");
        assert_eq!(fmu.setup_experiment(0.0), OK);
        assert_eq!(fmu.enter_init(), OK);
        assert_eq!(fmu.exit_init(), ERROR, "{name} = {x}");
        let errors: Vec<String> = fmu.logs().into_iter().filter(|l| l.status == ERROR).map(|l| l.message).collect();
        assert_eq!(errors.len(), 1, "{errors:?}");
        assert!(errors[0].contains(&format!("{name} = {x}")) && errors[0].contains(allowed), "{}", errors[0]);
    }
    let fmu = Fmu::<Roller>::new();
    fmu.set_all(&[("inlets", 4.0), ("outlets", 4.0), ("web_a4.m", 1e-9)]);
    assert_eq!(fmu.initialize(), OK, "{:?}", fmu.logs());
    // Strains and tensions of the new ports are checked when set, as web_a's.
    assert_eq!(fmu.set("web_a3.eps", -1.0), ERROR);
    assert!(fmu.messages().last().unwrap().contains("web_a3.eps = -1"), "{:?}", fmu.messages());
}

/// `tangents_fixed`: where a roller says so (an idler, a slitter, a speed drive, a dancer), its
/// tangents along omega, y, y' and every input are the same (to the value: a zero may change
/// sign) at two points with different states, inputs and times; a winder and a nip merging three
/// webs say not, and theirs differ.
#[test]
fn fixed_tangents_are_the_same_at_every_state_input_and_time() {
    use roller::description::Real;
    let speed_drive = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/speed_drive.json");
    #[rustfmt::skip]
    let rollers: [(&[(&str, f64)], Option<&str>, bool); 7] = [
        (&[], None, true),
        (&[("b", 0.3), ("outlets", 2.0)], None, true),
        (&[], Some(speed_drive), true),
        (&[("roll", 2.0), ("wound.thickness", 1e-3), ("wound.density", 1000.0)], None, false),
        (&[("inlets", 3.0), ("web_a.m", 0.2), ("web_a2.m", 0.05), ("web_a3.m", 0.7)], None, false),
        (&[("carriage", 1.0)], None, true),
        (&[("inlets", 3.0), ("outlets", 3.0), ("layered", 1.0)], None, true),
    ];
    #[rustfmt::skip]
    let points: [&[(&str, f64)]; 2] = [
        &[("web_a.F", 300.0), ("web_a2.F", 250.0), ("web_a3.F", 120.0), ("web_b.F", 150.0), ("web_b2.F", 210.0),
          ("web_a.eps", 1.1e-3), ("web_a2.eps", 4.2e-3), ("web_a3.eps", -2e-4), ("tau_m", 1.5), ("F_load", 1e3)],
        &[("web_a.F", 900.0), ("web_a2.F", 20.0), ("web_a3.F", 610.0), ("web_b.F", 40.0), ("web_b2.F", 5.0),
          ("web_a.eps", 3e-3), ("web_a2.eps", 1e-4), ("web_a3.eps", 2e-2), ("tau_m", -4.0), ("F_load", 2e2)],
    ];
    let knowns: Vec<Real> = DESCRIPTION
        .variables
        .iter()
        .filter(|v| v.kind == Kind::Real && (v.causality == Causality::Input || ["omega", "y", "y_dot"].contains(&&*v.name)))
        .filter_map(|v| Real::from_vr(v.vr))
        .collect();
    for (settings, profile, fixed) in rollers {
        let mut m = Roller::at_start_values();
        for &(name, x) in settings {
            set(&mut m, name, x);
        }
        if let Some(path) = profile {
            m.set_string(DESCRIPTION.variable_by_name("profile").unwrap().vr, path).unwrap();
        }
        m.initialize(&Experiment::default(), &Default::default()).unwrap();
        let mut tangents = Vec::new();
        for (inputs, h) in points.iter().zip([0.05, 0.4]) {
            for &(name, x) in inputs.iter() {
                set(&mut m, name, x);
            }
            m.do_step(h).unwrap();
            tangents.push(knowns.iter().map(|&k| m.tangents(&Roller::direction(k).unwrap())).collect::<Vec<_>>());
        }
        assert_eq!(roller::jacobian::tangents_fixed(&m.params), fixed, "{settings:?}");
        assert_eq!(tangents[0] == tangents[1], fixed, "{settings:?}: tangents {:?} and {:?}", tangents[0], tangents[1]);
    }
}

/// [R6]: where the webs stay layers, outlet k passes on the strain of inlet ((k-1) mod inlets) + 1,
/// exactly (a copy), whatever the masses; a nip of three layers passes each to its own outlet, a
/// slitter cutting two layers into two lanes passes each layer to its outlet in every lane. The
/// same rollers without `layered` merge the strains [R5] instead, so the check can fail.
#[test]
fn layers_pass_each_strain_on_at_their_own_port() {
    let strains = [("web_a.eps", 1.1e-3), ("web_a2.eps", 4.2e-3), ("web_a3.eps", -2e-4)];
    let masses = [("web_a.m", 0.2), ("web_a2.m", 0.05), ("web_a3.m", 0.7)];
    for (inlets, outlets) in [(3usize, 3usize), (2, 4), (1, 4)] {
        let ports = [("inlets", inlets as f64), ("outlets", outlets as f64)];
        let layered = roller(&[&ports[..], &strains[..inlets], &masses[..inlets], &[("layered", 1.0)]].concat());
        let merged = roller(&[&ports[..], &strains[..inlets], &masses[..inlets]].concat());
        for (k, outlet) in ["web_b.eps", "web_b2.eps", "web_b3.eps", "web_b4.eps"].iter().enumerate().take(outlets) {
            let want = strains[k % inlets].1;
            assert_eq!(get(&layered, outlet), want, "{inlets} inlets, {outlets} outlets: {outlet}");
            if inlets > 1 {
                assert!(rel(get(&merged, outlet), want) > 0.1, "without layered {outlet} merges: {}", get(&merged, outlet));
            }
        }
    }
}
