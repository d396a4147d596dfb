//! Logging: the categories of fmi2SetDebugLogging and loggingOn, what each
//! switches, and messages a printf-style logger prints as written.

use super::scene::*;
use crate::*;
use crate::Tested;

/// The message as a printf-style logger prints it; `None` if it holds a
/// '%' that is not part of "%%" (which such a logger would misread).
fn printf_unescape(message: &str) -> Option<String> {
    let mut out = String::new();
    let mut chars = message.chars();
    while let Some(c) = chars.next() {
        if c == '%' && chars.next() != Some('%') {
            return None;
        }
        out.push(c);
    }
    Some(out)
}

/// The lifecycle category the layer logs events in; the description must declare it.
fn events<M: Tested>() -> &'static str {
    let category = "logEvents";
    assert!(M::description().log_categories.contains(&category), "{category} is not among the LogCategories");
    category
}

/// Proves that fmi2SetDebugLogging refuses an unknown category with
/// fmi2Error and one line naming it, and applies nothing of a list that
/// holds an unknown name (logEvents stays off).
pub fn set_debug_logging_refuses_unknown_categories<M: Tested>() {
    let fmu = Fmu::<M>::new();
    assert_eq!(fmu.set_debug_logging(true, &["logNoSuchCategory"]), ERROR);
    assert_one_error(&fmu.take_logs(), &["fmi2SetDebugLogging", "logNoSuchCategory"]);

    let fmu = Fmu::<M>::new();
    assert_eq!(fmu.set_debug_logging(true, &[events::<M>(), "bogus"]), ERROR);
    assert_one_error(&fmu.take_logs(), &["bogus"]);
    assert_eq!(fmu.reset(), OK);
    fmu.init(0.0);
    assert!(fmu.logs().is_empty(), "logEvents must still be off: {:?}", fmu.logs());
}

/// Proves that error messages are on by default, that switching
/// logStatusError off silences them (the status is still returned), and
/// that switching it on again brings them back.
pub fn log_status_error_can_be_switched_off<M: Tested>() {
    let fmu = Fmu::<M>::new();
    assert_eq!(fmu.do_step(0.0, 1.0), ERROR);
    assert_eq!(fmu.take_logs().len(), 1, "on by default");
    assert_eq!(fmu.set_debug_logging(false, &["logStatusError"]), OK);
    assert_eq!(fmu.do_step(0.0, 1.0), ERROR);
    assert_eq!(fmu.exit_init(), ERROR);
    assert!(fmu.logs().is_empty(), "{:?}", fmu.logs());
    assert_eq!(fmu.set_debug_logging(true, &["logStatusError"]), OK);
    assert_eq!(fmu.do_step(0.0, 1.0), ERROR);
    assert_one_error(&fmu.take_logs(), &["fmi2DoStep"]);
}

/// Proves that loggingOn = fmi2True at instantiation turns on event lines
/// (logEvents, fmi2OK) from the first moment, that loggingOn = fmi2False
/// gives none, and that fmi2SetDebugLogging(on, "logEvents") turns them on
/// later.
pub fn event_logging_follows_logging_on_and_set_debug_logging<M: Tested>() {
    let on = Fmu::<M>::logging(true);
    on.init(0.0);
    assert_eq!(on.terminate(), OK);
    let lines = on.take_logs();
    assert!(lines.len() >= 4, "{lines:?}");
    assert!(lines.iter().all(|l| l.status == OK && l.category == events::<M>()), "{lines:?}");
    assert!(lines[0].message.contains("instantiated"), "{lines:?}");
    assert!(lines.iter().any(|l| l.message.contains("terminated")), "{lines:?}");

    let off = Fmu::<M>::logging(false);
    off.init(0.0);
    assert!(off.logs().is_empty(), "{:?}", off.logs());
    assert_eq!(off.set_debug_logging(true, &[events::<M>()]), OK);
    assert_eq!(off.terminate(), OK);
    let lines = off.take_logs();
    assert_eq!(lines.len(), 1, "{lines:?}");
    assert_eq!((lines[0].category.as_str(), lines[0].message.contains("terminated")), (events::<M>(), true));
}

/// Proves that nCategories = 0 switches every category: on, each call is
/// traced (logAll) and events are logged; off, even error messages are
/// silent.
pub fn no_categories_switches_all<M: Tested>() {
    let fmu = Fmu::<M>::new();
    assert_eq!(fmu.set_debug_logging(true, &[]), OK);
    fmu.take_logs();
    assert_eq!(fmu.setup_experiment(0.0), OK);
    assert_eq!(fmu.enter_init(), OK);
    let lines = fmu.take_logs();
    assert!(lines.iter().any(|l| l.category == "logAll" && l.message.contains("fmi2SetupExperiment")), "{lines:?}");
    assert!(lines.iter().any(|l| l.category == "logAll" && l.message.contains("fmi2EnterInitializationMode")), "{lines:?}");
    assert!(lines.iter().any(|l| l.category == events::<M>()), "{lines:?}");

    assert_eq!(fmu.set_debug_logging(false, &[]), OK);
    fmu.take_logs();
    assert_eq!(fmu.exit_init(), OK);
    assert_eq!(fmu.do_step(1.0, 1.0), ERROR);
    assert!(fmu.logs().is_empty(), "all off, errors included: {:?}", fmu.logs());
}

/// Proves that a '%' in a message reaches the logger escaped as "%%", so a
/// printf-style logger prints it literally: provoked with an unknown log
/// category and a GUID that contain printf directives.
pub fn percent_in_messages_is_escaped_for_printf_loggers<M: Tested>() {
    let fmu = Fmu::<M>::new();
    assert_eq!(fmu.set_debug_logging(true, &["100%s%n"]), ERROR);
    let lines = fmu.take_logs();
    assert_eq!(lines.len(), 1);
    assert!(lines[0].message.contains("100%%s%%n"), "{:?}", lines[0].message);
    let printed = printf_unescape(&lines[0].message).expect("every % doubled");
    assert!(printed.contains("100%s%n"), "{printed}");

    let Err(lines) = instantiate(&Setup::<M> { guid: Some("{%d-%s}".into()), ..Setup::default() }) else {
        panic!("a wrong GUID accepted")
    };
    assert_eq!(lines.len(), 1);
    let printed = printf_unescape(&lines[0].message).expect("every % doubled");
    assert!(printed.contains("{%d-%s}"), "{printed}");
}
