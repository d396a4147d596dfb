//! The span's own tests of its C API, through the real exported `fmi2*`
//! functions (the test kit's safe wrapper): what only the span has (the
//! equilibrium start, a solver whose result depends on the tolerance, its
//! damping term by hand, the ranges its XML declares). What every model
//! must do at the C API is the FMI layer's conformance suite: conformance.rs.

type Fmu = fmi_testkit::Fmu<ConvertingSpan>;

use converting_span::description::{Real, DESCRIPTION};
use converting_span::ConvertingSpan;
use fmi_core::description::{Causality, Kind};
use fmi_testkit::conformance::scene::{assert_one_error, phase_of, run, Phase};
use fmi_testkit::*;

/// Every Real parameter and input with its allowed range as declared in
/// modelDescription.xml (min/max and the ConvertingSpan.range annotation).
const REAL_RANGES: [(&str, &str); 20] = [
    ("L", "[0.000001, 100000]"),
    ("wp1.E", "[1000, 10000000000000]"),
    ("wp1.thickness", "[0.000000001, 1]"),
    ("wp1.width", "[0.000001, 100]"),
    ("wp1.density", "[1, 100000]"),
    ("wp1.d_r", "[0, 1000]"),
    ("wp2.E", "[1000, 10000000000000]"),
    ("wp2.thickness", "[0.000000001, 1]"),
    ("wp2.width", "[0.000001, 100]"),
    ("wp2.density", "[1, 100000]"),
    ("wp2.d_r", "[0, 1000]"),
    ("eps_start", "(-1, 10]"),
    ("web_a.v", "[-1000, 1000]"),
    ("web_a.eps", "(-1, 10]"),
    ("web_b.v", "[-1000, 1000]"),
    ("tolerance", "(0, 0.1]"),
    ("frame_a.x", "[-10000, 10000]"),
    ("frame_a.y", "[-10000, 10000]"),
    ("frame_b.x", "[-10000, 10000]"),
    ("frame_b.y", "[-10000, 10000]"),
];

/// Proves that the ranges the span's modelDescription.xml declares (min/max
/// and the ConvertingSpan.range annotation) are those of the description the
/// FMU checks against, for every Real parameter and input, in XML order (the
/// conformance suite takes its ranges from that description).
#[test]
fn declared_ranges_are_the_spans() {
    let declared: Vec<(&str, String)> = DESCRIPTION
        .variables
        .iter()
        .filter(|v| v.kind == Kind::Real && matches!(v.causality, Causality::Parameter | Causality::Input))
        .map(|v| (&*v.name, v.range.to_string()))
        .collect();
    let listed: Vec<(&str, String)> = REAL_RANGES.iter().map(|(n, r)| (*n, r.to_string())).collect();
    assert_eq!(declared, listed);
}

/// Proves that startAtEquilibrium with speeds of opposite signs (no steady
/// state) is refused when initialization ends, with a message that names
/// the option and the inputs, and that the same inputs initialize with
/// startAtEquilibrium = false.
#[test]
fn start_at_equilibrium_without_steady_state_is_refused() {
    let fmu = Fmu::new();
    fmu.set_all(&[("web_a.v", 1.0), ("web_b.v", -1.0)]);
    assert_eq!(fmu.setup_experiment(0.0), OK);
    assert_eq!(fmu.enter_init(), OK);
    assert_eq!(fmu.exit_init(), ERROR);
    assert_one_error(&fmu.take_logs(), &["startAtEquilibrium", "web_a.v = 1", "web_b.v = -1"]);
    assert_eq!(phase_of(&fmu), Phase::Error);

    let fmu = Fmu::new();
    fmu.set_all(&[("web_a.v", 1.0), ("web_b.v", -1.0), ("startAtEquilibrium", 0.0)]);
    fmu.init(0.0);
}

/// Proves that an FMU state saved in
/// initialization mode carries everything needed to continue, including
/// the tolerance given to fmi2SetupExperiment: with solver = rosenbrock
/// (whose result depends on the tolerance), restoring such a state into
/// another instance, or into the same instance after fmi2Reset, and
/// continuing must give exactly what the original run gave (before
/// 848d16f the experiment was not saved and the restored run integrated
/// with the default tolerance, which the control identifies).
#[test]
fn fmu_state_saved_in_initialization_mode_keeps_the_experiment_tolerance() {
    let prepare = |fmu: &Fmu, tolerance: Option<f64>| {
        fmu.set_all(&[("solver", 3.0), ("startAtEquilibrium", 0.0), ("eps_start", 2e-3)]);
        assert_eq!(fmu.setup_experiment_full(tolerance, 0.0, None), OK);
        assert_eq!(fmu.enter_init(), OK);
    };
    let a = Fmu::new();
    prepare(&a, Some(1e-3));
    let s = a.get_state().unwrap();
    let bytes = a.serialize(s).unwrap();
    assert_eq!(a.exit_init(), OK);
    let (reference, _) = run(&a, 0.0, 0, 10);
    // The control: without the tolerance the run differs, so the test can tell.
    let control = {
        let c = Fmu::new();
        prepare(&c, None);
        assert_eq!(c.exit_init(), OK);
        run(&c, 0.0, 0, 10).0
    };
    assert_ne!(control, reference, "the tolerance must matter for this test to mean anything");

    let b = Fmu::new();
    let sb = b.deserialize(&bytes).unwrap();
    assert_eq!(b.set_state(sb), OK);
    assert_eq!(b.exit_init(), OK);
    let in_another = run(&b, 0.0, 0, 10).0;

    assert_eq!(a.reset(), OK);
    assert_eq!(a.set_state(s), OK);
    assert_eq!(a.exit_init(), OK);
    let after_reset = run(&a, 0.0, 0, 10).0;

    assert!(
        in_another == reference,
        "restored in another instance: {}",
        if in_another == control { "ran with the default tolerance" } else { "differs" }
    );
    assert!(
        after_reset == reference,
        "restored after fmi2Reset: {}",
        if after_reset == control { "ran with the default tolerance" } else { "differs" }
    );
}

/// Values off the start values, among them those the damping term by hand uses.
const CONFIG: &[(&str, f64)] =
    &[("L", 1.5), ("wp2.E", 2e10), ("wp2.d_r", 0.02), ("includeDamping", 1.0), ("toUnitF", 3.0), ("web_a.v", 5.2)];

/// Proves that fmi2GetDirectionalDerivative gives the span's partial
/// derivatives summed with the seed: d(web_a.F) along web_b.v and web_a.eps
/// is the damping term, computed here by hand; d(v)/d(web_b.v) = 1; the sum
/// with a seed is exact to rounding. (Its agreement with the values and the
/// refusals of bad arguments: the conformance suite's dependencies module.)
#[test]
fn directional_derivatives_are_the_damping_term_by_hand() {
    let (f, vb, ea) = (Real::web_a_F.vr(), Real::web_b_v.vr(), Real::web_a_eps.vr());
    let fmu = Fmu::new();
    fmu.set_all(CONFIG);
    fmu.init(0.0);
    let (s1, column_b) = fmu.directional_derivative(&[f, Real::v.vr()], &[vb], &[1.0]);
    let (s2, column_e) = fmu.directional_derivative(&[f], &[ea], &[1.0]);
    let (s3, both) = fmu.directional_derivative(&[f], &[vb, ea], &[2.0, -3.0]);
    assert_eq!((s1, s2, s3), (OK, OK, OK), "{:?}", fmu.logs());
    // T = EA*(eps + d_r*deps/dt), deps/dt = -(1+eps)^2/L * (v_a/(1+eps_a) - v_b/(1+eps)): by hand.
    let (ea_stiff, d_r, length) = (2e10 * 59e-6, 0.02, 1.5);
    let stretch = 1.0 + fmu.real("summary_Strain");
    let (va, eps_a) = (fmu.real("web_a.v"), fmu.real("web_a.eps"));
    let by_hand =
        [ea_stiff * d_r * stretch / length, ea_stiff * d_r * stretch * stretch / length * va / ((1.0 + eps_a) * (1.0 + eps_a))];
    for (got, want) in [(column_b[0], by_hand[0]), (column_e[0], by_hand[1])] {
        assert!((got - want).abs() <= 1e-12 * want.abs(), "{got} vs {want} (by hand)");
    }
    assert_eq!(column_b[1], 1.0, "v = web_b.v in m/s");
    let sum = 2.0 * column_b[0] - 3.0 * column_e[0];
    assert!((both[0] - sum).abs() <= 1e-15 * sum.abs().max(column_b[0].abs()), "{} vs {sum}", both[0]);
}
