//! `convertingSpanDoSteps`, the Line library's one function beyond FMI (webline's native loop for
//! studies): through the C API, on the test line, against an importer's loop of fmi2DoStep and
//! fmi2GetReal on a second instance: the same outputs bit for bit and the same log; refused, through
//! the one entry path, where fmi2DoStep is refused (before initialization, a NULL argument, a step
//! that does not go forward), saying where it stopped.

mod common;
use common::TestedLine;
use fmi_testkit::{vr, Fmu, ERROR, OK};

const OUTPUTS: [&str; 4] = ["unwind.v", "entry.T", "rewind.r", "dancer.y"];

fn started() -> Fmu<TestedLine> {
    let fmu = Fmu::<TestedLine>::new();
    fmu.init(0.0);
    fmu
}

fn outputs() -> Vec<u32> {
    OUTPUTS.iter().map(|name| vr::<TestedLine>(name)).collect()
}

/// The points an importer steps through: 1 ms apart, then a shorter last step (the stop time
/// between two points), across the pull roll's speed step at 20 ms.
fn times() -> Vec<f64> {
    let mut t: Vec<f64> = (0..30).map(|k| k as f64 * 1e-3).collect();
    t.push(0.0295);
    t
}

#[test]
fn the_steps_in_one_call_are_an_importers_loop_bit_for_bit() {
    let (times, vrs) = (times(), outputs());
    let n = times.len() - 1;
    let ours = started();
    let (status, values, taken, rows) = ours.do_steps(Some(&times), n, &vrs);
    assert_eq!((status, taken, rows), (OK, n, n + 1), "{:?}", ours.logs());
    let loop_ = started();
    let mut expected = loop_.get_reals_vr(&vrs).unwrap();
    for k in 0..n {
        assert_eq!(loop_.do_step(times[k], times[k + 1] - times[k]), OK);
        expected.extend(loop_.get_reals_vr(&vrs).unwrap());
    }
    assert_eq!(values.iter().map(|v| v.to_bits()).collect::<Vec<_>>(), expected.iter().map(|v| v.to_bits()).collect::<Vec<_>>());
    assert_eq!(ours.messages(), loop_.messages());
    // It ends where the loop ends: the next step goes on from there alike.
    assert_eq!(ours.do_step(times[n], 1e-3), OK);
    assert_eq!(loop_.do_step(times[n], 1e-3), OK);
    assert_eq!(ours.get_reals_vr(&vrs).unwrap().iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
               loop_.get_reals_vr(&vrs).unwrap().iter().map(|v| v.to_bits()).collect::<Vec<_>>());
}

#[test]
fn it_is_refused_where_fmi2_do_step_is_saying_where_it_stopped() {
    let vrs = outputs();
    // Before initialization: fmi2DoStep's state check, nothing done.
    let fmu = Fmu::<TestedLine>::new();
    let (status, _, taken, rows) = fmu.do_steps(Some(&[0.0, 1e-3]), 1, &vrs);
    assert_eq!((status, taken, rows), (ERROR, usize::MAX, usize::MAX));
    assert!(fmu.messages().last().unwrap().contains("fmi2DoStep: illegal call sequence"), "{:?}", fmu.messages());
    // A NULL argument, named.
    let fmu = started();
    let (status, _, taken, rows) = fmu.do_steps(None, 2, &vrs);
    assert_eq!((status, taken, rows), (ERROR, 0, 0));
    assert!(fmu.messages().last().unwrap().contains("times is NULL"), "{:?}", fmu.messages());
    // A step that does not go forward: the steps before it taken and read, then fmi2DoStep's own refusal.
    let fmu = started();
    let (status, values, taken, rows) = fmu.do_steps(Some(&[0.0, 1e-3, 2e-3, 2e-3, 3e-3]), 4, &vrs);
    assert_eq!((status, taken, rows), (ERROR, 2, 3), "{:?}", fmu.messages());
    assert!(values[..3 * vrs.len()].iter().all(|v| v.is_finite()) && values[3 * vrs.len()..].iter().all(|v| v.is_nan()));
    let refused = fmu.messages().last().unwrap().clone();
    let alone = started();
    assert_eq!(alone.do_step(0.0, 1e-3), OK);
    assert_eq!(alone.do_step(1e-3, 1e-3), OK);
    assert_eq!(alone.do_step(2e-3, 0.0), ERROR);
    assert_eq!(alone.messages().last().unwrap(), &refused);
}
