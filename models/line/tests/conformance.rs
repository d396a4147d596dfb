//! The conformance suite of the FMI layer (fmi/testkit), run on the Line's
//! library over its test line (resources/: an unwinder and a winder under
//! tension control, an idler on a load cell, a dancer between two spans of
//! variable length, a pull roll whose speed steps at 20 ms; README.md there).
//! `TestedLine` (tests/common) stands in for the Line, whose interface the
//! library builds from line.json when it instantiates.

mod common;
use common::TestedLine;
use fmi_testkit::conformance::Hints;

/// The dancer's load comes from a profile table, which only a roller on a
/// carriage can take: perturbing `dancer.carriage` is refused for that reason.
fn hints() -> Hints {
    Hints { refusals: vec!["a load table needs carriage = true"], ..Hints::default() }
}

fmi_testkit::conformance_tests!(TestedLine, hints = hints);
