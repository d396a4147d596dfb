//! No panic crosses the C boundary. With the test-only feature `test-hooks`
//! of the model crate an instance can be armed so that its next
//! `fmi2DoStep` panics inside the step (after the model advanced, before
//! the time did). The importer must get `fmi2Error` and a log line, not an
//! abort; the instance is then poisoned: everything but `fmi2Reset` and
//! `fmi2FreeInstance` is refused, even calls that are legal in the error
//! state (getters, `fmi2SetFMUstate`). `fmi2Reset` makes it fully usable again.
//!
//! `hook`: the category that arms it (`fmi_core::instance::TEST_PANIC_CATEGORY`,
//! which exists only with the feature, so the macro passes it in).

use super::scene::*;
use crate::*;
use crate::Tested;

fn arm<M: Tested>(fmu: &Fmu<M>, hook: &str) -> i32 {
    fmu.set_debug_logging(true, &[hook])
}

fn running<M: Tested>() -> Fmu<M> {
    let fmu = Fmu::<M>::named("panicky");
    assert_eq!(fmu.initialize(), OK, "{:?}", fmu.messages());
    fmu
}

const REFUSAL: &str = "only fmi2Reset or fmi2FreeInstance are accepted";

pub fn a_panic_inside_the_step_becomes_fmi2error_with_a_log_line<M: Tested>(hook: &str) {
    let fmu = running::<M>();
    assert_eq!(fmu.do_step(0.0, 0.1), OK);
    assert_eq!(arm(&fmu, hook), OK);
    // The process is still here after this line: the panic was caught.
    assert_eq!(fmu.do_step(0.1, 0.1), ERROR, "a panic must come back as fmi2Error");
    let log = fmu.log.take();
    let line = log.iter().find(|l| l.status == ERROR).expect("the panic is logged");
    assert_eq!(line.category, "logStatusError");
    assert!(line.message.contains("fmi2DoStep: internal error") && line.message.contains("test hook"), "{line:?}");
}

pub fn a_poisoned_instance_refuses_everything_but_reset_and_free<M: Tested>(hook: &str) {
    let fmu = running::<M>();
    let mut saved = fmu.get_state().unwrap();
    assert_eq!(arm(&fmu, hook), OK);
    assert_eq!(fmu.do_step(0.0, 0.1), ERROR);
    fmu.log.take();

    let (output, input) = (first_real_output::<M>(), first_real_input::<M>());
    let mut other = State::NULL;
    let refused: Vec<(&str, i32)> = vec![
        // Legal in the error state for a healthy instance, refused when poisoned:
        ("fmi2GetReal", fmu.get_reals_vr(&[output.vr]).err().unwrap_or(OK)),
        ("fmi2SetFMUstate", fmu.set_state(saved)),
        ("fmi2GetFMUstate", fmu.get_state_into(&mut other)),
        ("fmi2SerializedFMUstateSize", fmu.serialized_size(saved).err().unwrap_or(OK)),
        ("fmi2SetDebugLogging", fmu.set_debug_logging(false, &[])),
        // Illegal in the error state anyway:
        ("fmi2DoStep", fmu.do_step(0.0, 0.1)),
        ("fmi2SetReal", fmu.set_reals_vr(&[input.vr], &[start_of(input)])),
        ("fmi2Terminate", fmu.terminate()),
        ("fmi2GetBooleanStatus", fmu.get_boolean_status(TERMINATED).0),
    ];
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
    assert_eq!(fmu.reset(), OK);
    assert_eq!(fmu.initialize(), OK, "{:?}", fmu.messages());
    let fresh = running::<M>();
    for k in 0..10 {
        let t = k as f64 * 0.05;
        assert_eq!(fmu.do_step(t, 0.05), OK);
        assert_eq!(fresh.do_step(t, 0.05), OK);
    }
    assert_eq!(all_values(&fmu), all_values(&fresh));
    // The state taken before the panic is usable again after the reset.
    assert_eq!(fmu.set_state(saved), OK);
    assert_eq!(fmu.free_state(&mut saved), OK);
}

pub fn a_poisoned_instance_can_be_freed_and_others_are_untouched<M: Tested>(hook: &str) {
    let healthy = running::<M>();
    for _ in 0..3 {
        let fmu = running::<M>();
        assert_eq!(arm(&fmu, hook), OK);
        assert_eq!(fmu.do_step(0.0, 0.1), ERROR);
        drop(fmu); // fmi2FreeInstance on the poisoned instance
    }
    assert_eq!(healthy.do_step(0.0, 0.1), OK, "{:?}", healthy.messages());
}

pub fn without_arming_the_hook_does_nothing<M: Tested>(_hook: &str) {
    let fmu = running::<M>();
    for k in 0..100 {
        assert_eq!(fmu.do_step(k as f64 * 0.01, 0.01), OK);
    }
}
