//! fmi2DoStep's arguments (step size, communication point and its
//! tolerance), the status functions that report on steps, and input
//! derivatives for the next step.

use super::scene::*;
use crate::*;
use crate::Tested;

/// Proves that fmi2DoStep refuses h = 0, -0, h < 0, NaN and inf, and a
/// communication point other than the current time (also NaN), each with
/// fmi2Error and one line naming the argument and value, and that a state
/// saved before the refused step continues exactly like an undisturbed run.
pub fn do_step_refuses_bad_step_size_and_time<M: Tested>() {
    let (_, t) = running::<M>(6);
    let (reference, _) = {
        let (r, t2) = running::<M>(6);
        run(&r, t2, 6, 16)
    };
    let cases: Vec<(f64, f64, String)> = vec![
        (t, 0.0, "communicationStepSize = 0".into()),
        (t, -0.0, "communicationStepSize = -0".into()),
        (t, -0.01, "communicationStepSize = -0.01".into()),
        (t, f64::NAN, "communicationStepSize = NaN".into()),
        (t, f64::INFINITY, "communicationStepSize = inf".into()),
        (t + 0.01, 0.01, format!("currentCommunicationPoint = {}", t + 0.01)),
        (t - 0.01, 0.01, format!("currentCommunicationPoint = {}", t - 0.01)),
        (0.0, 0.01, "currentCommunicationPoint = 0".into()),
        (f64::NAN, 0.01, "currentCommunicationPoint = NaN".into()),
    ];
    for (point, h, needle) in cases {
        let (fmu, t) = running::<M>(6);
        let saved = fmu.get_state().unwrap();
        assert_eq!(fmu.do_step(point, h), ERROR, "fmi2DoStep({point}, {h})");
        assert_one_error(&fmu.take_logs(), &["fmi2DoStep", &needle]);
        assert_eq!(phase_of(&fmu), Phase::Error);
        assert_eq!(fmu.set_state(saved), OK);
        assert_eq!(run(&fmu, t, 6, 16).0, reference, "fmi2DoStep({point}, {h}) must lose nothing");
    }
}

/// Proves that a step the model discards (fmi2Discard: step failed)
/// changes nothing: every value and the time stay as before the step; that
/// the instance may then only be terminated, reset or restored; and that a
/// state saved before the step continues exactly like an undisturbed run.
pub fn a_discarded_step_changes_nothing<M: Tested>() {
    let (vr, x, h) = failing_step::<M>();
    let fmu = drive::<M>(Phase::Complete);
    assert_eq!(fmu.set_reals_vr(&[vr], &[x]), OK);
    let (before, saved) = (all_values(&fmu), fmu.get_state().unwrap());
    let (reference, _) = {
        let twin = drive::<M>(Phase::Complete);
        run(&twin, 0.0, 0, 5)
    };
    assert_eq!(fmu.do_step(0.0, h), DISCARD);
    let lines = fmu.take_logs();
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert_eq!((lines[0].status, lines[0].category.as_str()), (DISCARD, "logStatusDiscard"));
    assert!(lines[0].message.contains("fmi2DoStep"), "{lines:?}");
    assert_eq!(phase_of(&fmu), Phase::Failed);
    assert_eq!(all_values(&fmu), before, "the discarded step changed values");
    assert_eq!(fmu.get_real_status(LAST_SUCCESSFUL_TIME), (OK, 0.0));
    assert_eq!(fmu.do_step(0.0, 0.01), ERROR, "no step after a discarded one");
    fmu.take_logs();
    assert_eq!(fmu.set_state(saved), OK);
    assert_eq!(phase_of(&fmu), Phase::Complete);
    assert_eq!(run(&fmu, 0.0, 0, 5).0, reference);
}

/// Proves that fmi2DoStep accepts a communication point 1 ulp above or below
/// the current time t = 1 (importers sum their time in their own way) and
/// continues from the importer's point, and refuses points 1e-6 off.
pub fn communication_point_tolerance<M: Tested>() {
    let at_one = || {
        let fmu = Fmu::<M>::new();
        fmu.init(0.0);
        assert_eq!(fmu.do_step(0.0, 1.0), OK, "{:?}", fmu.logs());
        assert_eq!(fmu.time(), 1.0);
        fmu
    };
    for point in [1.0f64.next_up(), 1.0f64.next_down()] {
        let fmu = at_one();
        assert_eq!(fmu.do_step(point, 0.01), OK, "{point:e}: {:?}", fmu.logs());
        assert_eq!(fmu.time(), point + 0.01);
    }
    for point in [1.0 + 1e-6, 1.0 - 1e-6] {
        let fmu = at_one();
        assert_eq!(fmu.do_step(point, 0.01), ERROR, "{point}");
        assert_one_error(&fmu.take_logs(), &["fmi2DoStep", &format!("currentCommunicationPoint = {point}"), "current time 1"]);
    }
}

/// Proves the status functions: fmi2GetRealStatus(fmi2LastSuccessfulTime)
/// is the current time (bit-identical with the importer's t + h sums, from
/// a start time other than 0), fmi2GetBooleanStatus(fmi2Terminated) is OK
/// and false, and the kinds the FMU does not provide (fmi2GetStatus,
/// fmi2GetIntegerStatus, fmi2GetStringStatus, other kinds) return
/// fmi2Discard with one logStatusDiscard line and leave the instance usable.
pub fn status_functions<M: Tested>() {
    let fmu = Fmu::<M>::new();
    fmu.init(0.25);
    assert_eq!(fmu.get_real_status(LAST_SUCCESSFUL_TIME), (OK, 0.25));
    let mut t = 0.25;
    for h in [0.1, 0.01, 0.3, 1e-4] {
        assert_eq!(fmu.do_step(t, h), OK);
        t += h;
        assert_eq!(fmu.get_real_status(LAST_SUCCESSFUL_TIME), (OK, t));
    }
    assert_eq!(fmu.get_boolean_status(TERMINATED), (OK, 0));
    assert!(fmu.take_logs().is_empty());

    let discards: Vec<(&str, i32)> = vec![
        ("fmi2GetStatus", fmu.get_status(DO_STEP_STATUS).0),
        ("fmi2GetStatus", fmu.get_status(PENDING_STATUS).0),
        ("fmi2GetRealStatus", fmu.get_real_status(DO_STEP_STATUS).0),
        ("fmi2GetIntegerStatus", fmu.get_integer_status(DO_STEP_STATUS).0),
        ("fmi2GetBooleanStatus", fmu.get_boolean_status(DO_STEP_STATUS).0),
        ("fmi2GetStringStatus", fmu.get_string_status(PENDING_STATUS)),
    ];
    let lines = fmu.take_logs();
    assert_eq!(lines.len(), discards.len(), "{lines:?}");
    for ((name, status), line) in discards.iter().zip(&lines) {
        assert_eq!(*status, DISCARD, "{name}");
        assert_eq!((line.status, line.category.as_str()), (DISCARD, "logStatusDiscard"), "{line:?}");
        assert!(line.message.contains(name), "{line:?}");
    }
    assert_eq!(fmu.do_step(t, 0.01), OK, "a discarded status query leaves the instance usable");
    assert_eq!(fmu.terminate(), OK);
    assert_eq!(fmu.get_boolean_status(TERMINATED), (OK, 0));
    assert_eq!(fmu.get_real_status(LAST_SUCCESSFUL_TIME), (OK, t + 0.01));
}

/// Proves fmi2SetRealInputDerivatives as the description declares it. With
/// canInterpolateInputs="true": first derivatives of inputs are accepted,
/// and an order other than 1, a non-input, a non-finite value and an
/// unknown value reference are refused with one line and without applying
/// any value of the call; an accepted derivative is used by the next step
/// (its result differs from a step with held inputs, by a little for a
/// small rate). With "false": every call is refused in every phase where
/// inputs can be set, with one line saying so, and nothing is applied.
pub fn set_real_input_derivatives_validates_its_arguments<M: Tested>() {
    let (reference, _) = {
        let (r, t) = running::<M>(4);
        run(&r, t, 4, 8)
    };
    let inputs = real_inputs::<M>();
    let (a, b) = (inputs[0], *inputs.last().unwrap());
    let output = first_real_output::<M>();
    let unused = unused_vr::<M>();
    if !M::description().can_interpolate_inputs {
        for phase in [Phase::Instantiated, Phase::Init, Phase::Complete] {
            let fmu = drive::<M>(phase);
            assert_eq!(fmu.set_real_input_derivatives(&[a.vr], &[1], &[0.1]), ERROR, "{phase:?}");
            assert_one_error(&fmu.take_logs(), &["fmi2SetRealInputDerivatives", "canInterpolateInputs is false"]);
        }
        let (fmu, t) = running::<M>(4);
        let saved = fmu.get_state().unwrap();
        assert_eq!(fmu.set_real_input_derivatives(&[a.vr], &[1], &[0.1]), ERROR);
        assert_eq!(fmu.set_state(saved), OK);
        assert_eq!(run(&fmu, t, 4, 8).0, reference, "nothing applied");
        return;
    }
    let cases: [(&str, Vec<u32>, Vec<i32>, Vec<f64>, String); 5] = [
        ("order 2", vec![b.vr], vec![2], vec![0.1], format!("order 2 for {}", b.name)),
        ("order 0", vec![b.vr], vec![0], vec![0.1], "order 0".into()),
        ("output", vec![a.vr, output.vr], vec![1, 1], vec![0.1, 0.1], format!("{} is not an input", output.name)),
        ("NaN", vec![a.vr, b.vr], vec![1, 1], vec![0.1, f64::NAN], format!("derivative of {} = NaN", b.name)),
        ("unknown", vec![a.vr, unused], vec![1, 1], vec![0.1, 0.1], format!("unknown value reference {unused}")),
    ];
    for (what, vrs, orders, values, needle) in cases {
        let (fmu, t) = running::<M>(4);
        let saved = fmu.get_state().unwrap();
        assert_eq!(fmu.set_real_input_derivatives(&vrs, &orders, &values), ERROR, "{what}");
        assert_one_error(&fmu.take_logs(), &["fmi2SetRealInputDerivatives", &needle]);
        assert_eq!(fmu.set_state(saved), OK);
        assert_eq!(run(&fmu, t, 4, 8).0, reference, "{what}: nothing applied");
    }
    // An accepted derivative changes the next step: an input the states depend on, at a small rate.
    let d = M::description();
    let driving = inputs
        .iter()
        .find(|v| d.derivatives.iter().any(|u| u.on.as_ref().is_none_or(|on| on.contains(&v.vr))))
        .expect("an input the state derivatives depend on");
    let rate = 0.1 * start_of(driving).abs().max(1.0);
    let (held, t) = running::<M>(4);
    let (moving, _) = running::<M>(4);
    assert_eq!(moving.set_real_input_derivatives(&[driving.vr], &[1], &[rate]), OK, "{:?}", moving.logs());
    let vrs: Vec<u32> = inputs.iter().map(|v| v.vr).collect();
    let u: Vec<f64> = inputs.iter().enumerate().map(|(j, v)| input_at(v, j, 4)).collect();
    for fmu in [&held, &moving] {
        assert_eq!(fmu.set_reals_vr(&vrs, &u), OK);
        assert_eq!(fmu.do_step(t, step_size(4)), OK, "{:?}", fmu.logs());
    }
    let states: Vec<u32> = d.states.to_vec();
    let (x_held, x_moving) = (held.get_reals_vr(&states).unwrap(), moving.get_reals_vr(&states).unwrap());
    assert_ne!(x_held, x_moving, "the derivative of {} is not used by the step", driving.name);
    for ((h, m), vr) in x_held.iter().zip(&x_moving).zip(&states) {
        let name = &d.variable(*vr).unwrap().name;
        let case = format!("stepping::set_real_input_derivatives_validates_its_arguments: {name} a little");
        if let Some(reason) = M::skipped(&case) {
            eprintln!("skipped {case} ({h} vs {m}): {reason}");
            continue;
        }
        assert!(relative_change(*h, *m) < 1e-3, "a small rate of {} changes the state {name} a little: {h} vs {m}", driving.name);
    }
}
