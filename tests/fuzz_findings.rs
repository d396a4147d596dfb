//! Product issues the fuzz harness (fmi/fuzz) found, each as a small test.
//! They failed until the product was fixed; now they guard against the
//! same faults coming back.

type Fmu = fmi_testkit::Fmu<converting_span::ConvertingSpan>;

use fmi_testkit::*;

fn output_vrs() -> Vec<u32> {
    use fmi_core::description::{Causality, Kind};
    use fmi_core::Compiled;
    <converting_span::ConvertingSpan as Compiled>::compiled()
        .variables
        .iter()
        .filter(|v| v.causality == Causality::Output && v.kind == Kind::Real)
        .map(|v| v.vr)
        .collect()
}

fn non_finite(fmu: &Fmu) -> Vec<(u32, f64)> {
    let vrs = output_vrs();
    let (status, values) = fmu.get_reals(&vrs);
    if status != OK {
        return Vec::new(); // refusing to answer is fine
    }
    vrs.into_iter().zip(values).filter(|(_, x)| !x.is_finite()).collect()
}

/// fmi2GetReal is legal in the error state. An instance that got there
/// before its initialization ended answers with outputs computed from an
/// unset state: web_a.F, T, summary_Stress ... are inf or NaN. Fix: answer
/// fmi2Error (or start values) for outputs that were never computed.
#[test]
fn outputs_read_in_the_error_state_before_initialization_are_finite() {
    let fmu = Fmu::named("uninitialized");
    assert_eq!(fmu.do_step(0.0, 0.1), ERROR, "a step before initialization is illegal");
    let bad = non_finite(&fmu);
    assert!(bad.is_empty(), "non-finite outputs (value reference, value): {bad:?}");
}

/// Parameters inside their declared ranges (E, thickness, width > 0) but
/// extreme: E*A overflows and the tension is inf. Fix: refuse at the end of
/// initialization when a derived quantity is not finite, or bound the ranges.
#[test]
fn extreme_but_accepted_parameters_are_refused_or_give_finite_outputs() {
    let fmu = Fmu::named("extreme");
    for (name, x) in [("wp2.E", 1e300), ("wp2.width", 1e300), ("wp2.thickness", 1e300)] {
        assert_eq!(fmu.set_real(name, x), OK, "{name} = {x} is inside its range");
    }
    assert_eq!(fmu.set_real("web_b.v", 5.1), OK); // a draw: non-zero strain
    if fmu.initialize() != OK {
        return; // refused: fine
    }
    assert_eq!(fmu.do_step(0.0, 0.1), OK);
    let bad = non_finite(&fmu);
    assert!(bad.is_empty(), "non-finite outputs (value reference, value): {bad:?}");
}

/// The end time of a step, t + h, can overflow to inf with finite t and h;
/// the FMU accepts the step and fmi2GetRealStatus(fmi2LastSuccessfulTime)
/// then answers inf. Fix: refuse a step whose end time is not finite.
#[test]
fn a_step_whose_end_time_overflows_is_refused() {
    let fmu = Fmu::named("time");
    unsafe {
        assert_eq!(fmi2SetupExperiment(fmu.c, 0, 0.0, 1e308, 0, 0.0), OK);
        assert_eq!(fmi2EnterInitializationMode(fmu.c), OK);
        assert_eq!(fmi2ExitInitializationMode(fmu.c), OK);
    }
    let status = fmu.do_step(1e308, 1e308);
    let mut last = 0.0;
    let s = unsafe { fmi2GetRealStatus(fmu.c, 2, &mut last) };
    assert!(status != OK || (s == OK && last.is_finite()), "step accepted, last successful time {last}");
}

/// Fixed (was a finding): the checksum is no signature, so bytes changed by
/// hand (checksum recomputed, as the harness does) with L = -1 m used to be
/// accepted. Since format version 2 the loaded values are range-checked.
/// A regression test now.
#[test]
fn a_forged_state_with_an_out_of_range_parameter_is_refused() {
    let fmu = Fmu::named("forged");
    let marker = 1.234_567_891_011; // a value of L to find in the bytes
    assert_eq!(fmu.set_real("L", marker), OK);
    assert_eq!(fmu.initialize(), OK);
    let mut state: fmi2FMUstate = std::ptr::null_mut();
    let mut size = 0usize;
    unsafe {
        assert_eq!(fmi2GetFMUstate(fmu.c, &mut state), OK);
        assert_eq!(fmi2SerializedFMUstateSize(fmu.c, state, &mut size), OK);
    }
    let mut bytes = vec![0u8; size];
    assert_eq!(unsafe { fmi2SerializeFMUstate(fmu.c, state, bytes.as_mut_ptr() as *mut _, size) }, OK);
    // Reals are stored as their little-endian bits (fmi/core/src/snapshot.rs).
    let l_at = bytes.windows(8).position(|w| w == marker.to_le_bytes()).expect("L in the serialized state");
    bytes[l_at..l_at + 8].copy_from_slice(&(-1.0f64).to_le_bytes());
    let n = bytes.len() - 8;
    let sum = bytes[..n].iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3));
    bytes[n..].copy_from_slice(&sum.to_le_bytes());
    let mut forged: fmi2FMUstate = std::ptr::null_mut();
    let status = unsafe { fmi2DeSerializeFMUstate(fmu.c, bytes.as_ptr() as *const _, size, &mut forged) };
    assert_eq!(status, ERROR, "a state with L = -1 m (allowed: > 0) was accepted");
}

/// Fixed (was a finding): the Model Exchange getters shared the phase
/// table with co-simulation, so a co-simulation instance in the error state
/// answered fmi2GetDerivatives with fmi2OK. A regression test now.
#[test]
fn a_co_simulation_instance_refuses_model_exchange_getters() {
    let fmu = Fmu::named("cs");
    assert_eq!(fmu.do_step(0.0, 0.1), ERROR); // now in the error state
    let mut dx = [0.0f64; 1];
    let status = unsafe { fmi2GetDerivatives(fmu.c, dx.as_mut_ptr(), 1) };
    assert_eq!(status, ERROR, "fmi2GetDerivatives on a co-simulation instance answered {}", status_name(status));
}

/// Before initialization ends a parameter may hold an out-of-range value
/// (it is checked when initialization ends). If the instance then goes into
/// the error state (any illegal call) and a state is saved there, it
/// serializes, but fmi2DeSerializeFMUstate refuses the FMU's own bytes
/// ("rejected: wp2.density = -1, allowed (0, inf)": the check takes every
/// phase after initialization mode, the error state included, as
/// initialized): serialization does not round-trip.
#[test]
fn a_state_saved_before_initialization_round_trips() {
    let fmu = Fmu::named("roundtrip");
    assert_eq!(fmu.set_real("wp2.density", -1.0), OK, "checked when initialization ends");
    assert_eq!(fmu.do_step(0.0, 0.1), ERROR, "illegal before initialization: now in the error state");
    let mut state: fmi2FMUstate = std::ptr::null_mut();
    let mut size = 0usize;
    unsafe {
        assert_eq!(fmi2GetFMUstate(fmu.c, &mut state), OK);
        assert_eq!(fmi2SerializedFMUstateSize(fmu.c, state, &mut size), OK);
    }
    let mut bytes = vec![0u8; size];
    assert_eq!(unsafe { fmi2SerializeFMUstate(fmu.c, state, bytes.as_mut_ptr() as *mut _, size) }, OK);
    let mut copy: fmi2FMUstate = std::ptr::null_mut();
    let status = unsafe { fmi2DeSerializeFMUstate(fmu.c, bytes.as_ptr() as *const _, size, &mut copy) };
    assert_eq!(status, OK, "the FMU refused its own serialized state: {:?}", fmu.messages());
}

/// Physical bounds (issue: 71 of 1,000,000 fuzzed sequences overflowed).
/// An input derivative of 1e308 carried over a step made the inputs and then
/// the outputs infinite (`fuzz_sequences --only 10366`). Fix: derivatives
/// beyond the input's maxRate are refused, and a step that would carry an
/// input out of its range is discarded.
#[test]
fn a_huge_input_derivative_is_refused_and_a_step_that_leaves_the_range_is_discarded() {
    let fmu = Fmu::named("rates");
    assert_eq!(fmu.initialize(), OK);
    let frame = vr::<converting_span::ConvertingSpan>("frame_a.x");
    assert_eq!(fmu.set_real_input_derivatives(&[frame], &[1], &[1e308]), ERROR);
    assert!(fmu.messages().last().unwrap().contains("frame_a.x = 1e308"), "{:?}", fmu.messages());
    assert_eq!(fmu.reset(), OK);
    assert_eq!(fmu.initialize(), OK);
    // Inside the rate bound, but 1e4 m/s over 10 s leaves the +-1e4 m range.
    assert_eq!(fmu.set_real_input_derivatives(&[frame], &[1], &[1e4]), OK);
    assert_eq!(fmu.do_step(0.0, 10.0), DISCARD);
    assert!(fmu.messages().last().unwrap().contains("frame_a.x would reach"), "{:?}", fmu.messages());
    assert!(non_finite(&fmu).is_empty());
}

/// Backward differences over a tiny step (h = 5e-324) estimated dv_b/dt as
/// inf, and the web-mass term made web_b.F infinite. Fix: estimates are held
/// to the input's maxRate.
#[test]
fn rates_estimated_over_a_tiny_step_stay_bounded() {
    let fmu = Fmu::named("tiny step");
    assert_eq!(fmu.set("includeMass", 1.0), OK);
    assert_eq!(fmu.initialize(), OK);
    assert_eq!(fmu.do_step(0.0, 5e-324), OK);
    assert_eq!(fmu.set_real("web_b.v", 900.0), OK);
    assert_eq!(fmu.do_step(5e-324, 5e-324), OK);
    assert_eq!(fmu.do_step(1e-323, 1e-3), OK);
    let bad = non_finite(&fmu);
    assert!(bad.is_empty(), "non-finite outputs (value reference, value): {bad:?}");
}

/// With variableLength, rollers moved onto each other between steps left
/// a state the equations cannot evaluate (strain -1: 0/0 in the rates).
/// Fix: outputs are refused until the configuration is valid again.
#[test]
fn rollers_moved_onto_each_other_make_outputs_refused_not_nan() {
    let fmu = Fmu::named("coincide");
    assert_eq!(fmu.set("variableLength", 1.0), OK);
    assert_eq!(fmu.set("includeDamping", 1.0), OK);
    assert_eq!(fmu.initialize(), OK);
    assert_eq!(fmu.set_real("frame_b.x", 1e-300), OK);
    let (status, _) = fmu.get_reals(&output_vrs());
    assert_eq!(status, ERROR);
    assert!(fmu.messages().last().unwrap().contains("outputs are not defined"), "{:?}", fmu.messages());
}

/// A steady start with web_a.v almost 0 gave a strain of 1e300 and an
/// infinite tension. Fix: a start beyond the largest strain is refused.
#[test]
fn a_steady_start_beyond_the_largest_strain_is_refused() {
    let fmu = Fmu::named("steady");
    fmu.set_real("web_a.v", 1e-300);
    assert_eq!(fmu.initialize(), ERROR);
    assert!(fmu.messages().last().unwrap().contains("beyond the largest strain"), "{:?}", fmu.messages());
}
