//! No panic crosses the C boundary. With the test-only feature `test-hooks`
//! an instance can be armed so that its next `fmi2DoStep` panics inside the
//! step (after the model advanced, before the time did). The importer must
//! get `fmi2Error` and a log line, not an abort; the instance is then
//! poisoned: everything but `fmi2Reset` and `fmi2FreeInstance` is refused,
//! even calls that are legal in the error state (getters, `fmi2SetFMUstate`).
//! `fmi2Reset` makes it fully usable again.
//!
//! Run: `cargo test --release --features test-hooks --test panic_boundary`
//! (tests/run.sh uses a separate target directory, so that the feature never
//! reaches the library that fmu/package.py ships).

type Fmu = fmi_testkit::Fmu<converting_span::ConvertingSpan>;

use fmi_core::instance::TEST_PANIC_CATEGORY;
use fmi_testkit::*;
use std::ffi::CString;

fn arm(fmu: &Fmu) -> i32 {
    let category = CString::new(TEST_PANIC_CATEGORY).unwrap();
    unsafe { fmi2SetDebugLogging(fmu.c, 1, 1, &category.as_ptr()) }
}

fn running() -> Fmu {
    let fmu = Fmu::named("panicky");
    assert_eq!(fmu.initialize(), OK, "{:?}", fmu.messages());
    fmu
}

const REFUSAL: &str = "only fmi2Reset or fmi2FreeInstance are accepted";

#[test]
fn a_panic_inside_the_step_becomes_fmi2error_with_a_log_line() {
    let fmu = running();
    assert_eq!(fmu.do_step(0.0, 0.1), OK);
    assert_eq!(arm(&fmu), OK);
    // The process is still here after this line: the panic was caught.
    assert_eq!(fmu.do_step(0.1, 0.1), ERROR, "a panic must come back as fmi2Error");
    let log = fmu.log.take();
    let line = log.iter().find(|l| l.status == ERROR).expect("the panic is logged");
    assert_eq!(line.category, "logStatusError");
    assert!(line.message.contains("fmi2DoStep: internal error") && line.message.contains("test hook"), "{line:?}");
}

#[test]
fn a_poisoned_instance_refuses_everything_but_reset_and_free() {
    let fmu = running();
    let mut saved: fmi2FMUstate = std::ptr::null_mut();
    assert_eq!(unsafe { fmi2GetFMUstate(fmu.c, &mut saved) }, OK);
    assert_eq!(arm(&fmu), OK);
    assert_eq!(fmu.do_step(0.0, 0.1), ERROR);
    fmu.log.take();

    let vr = vr::<converting_span::ConvertingSpan>("T");
    let mut x = 0.0;
    let mut size = 0usize;
    let mut other: fmi2FMUstate = std::ptr::null_mut();
    let mut flag = 0;
    let all_off: [fmi2String; 0] = [];
    let refused: Vec<(&str, i32)> = unsafe {
        vec![
            // Legal in the error state for a healthy instance, refused when poisoned:
            ("fmi2GetReal", fmi2GetReal(fmu.c, &vr, 1, &mut x)),
            ("fmi2SetFMUstate", fmi2SetFMUstate(fmu.c, saved)),
            ("fmi2GetFMUstate", fmi2GetFMUstate(fmu.c, &mut other)),
            ("fmi2SerializedFMUstateSize", fmi2SerializedFMUstateSize(fmu.c, saved, &mut size)),
            ("fmi2SetDebugLogging", fmi2SetDebugLogging(fmu.c, 0, 0, all_off.as_ptr())),
            // Illegal in the error state anyway:
            ("fmi2DoStep", fmi2DoStep(fmu.c, 0.0, 0.1, 1)),
            ("fmi2SetReal", fmi2SetReal(fmu.c, &fmi_testkit::vr::<converting_span::ConvertingSpan>("web_b.v"), 1, &5.0)),
            ("fmi2Terminate", fmi2Terminate(fmu.c)),
            ("fmi2GetBooleanStatus", fmi2GetBooleanStatus(fmu.c, 3, &mut flag)),
        ]
    };
    for (name, status) in &refused {
        assert_eq!(*status, ERROR, "{name} on a poisoned instance answered {}", status_name(*status));
    }
    let log = fmu.log.take();
    for (name, _) in &refused {
        assert!(
            log.iter().any(|l| l.message.starts_with(name) && l.message.contains(REFUSAL)),
            "no refusal logged for {name}: {log:?}"
        );
    }
    assert!(other.is_null(), "a refused fmi2GetFMUstate handed out a state");

    // fmi2Reset clears the poison: the instance runs like a new one.
    assert_eq!(unsafe { fmi2Reset(fmu.c) }, OK);
    assert_eq!(fmu.initialize(), OK, "{:?}", fmu.messages());
    let fresh = running();
    for k in 0..10 {
        let t = k as f64 * 0.05;
        assert_eq!(fmu.do_step(t, 0.05), OK);
        assert_eq!(fresh.do_step(t, 0.05), OK);
    }
    assert_eq!(fmu.get_real("T").1.to_bits(), fresh.get_real("T").1.to_bits());
    // The state taken before the panic is usable again after the reset.
    assert_eq!(unsafe { fmi2SetFMUstate(fmu.c, saved) }, OK);
    assert_eq!(unsafe { fmi2FreeFMUstate(fmu.c, &mut saved) }, OK);
}

#[test]
fn a_poisoned_instance_can_be_freed_and_others_are_untouched() {
    let healthy = running();
    for _ in 0..3 {
        let fmu = running();
        assert_eq!(arm(&fmu), OK);
        assert_eq!(fmu.do_step(0.0, 0.1), ERROR);
        drop(fmu); // fmi2FreeInstance on the poisoned instance
    }
    assert_eq!(healthy.do_step(0.0, 0.1), OK, "{:?}", healthy.messages());
}

#[test]
fn without_arming_the_hook_does_nothing() {
    let fmu = running();
    for k in 0..100 {
        assert_eq!(fmu.do_step(k as f64 * 0.01, 0.01), OK);
    }
}
