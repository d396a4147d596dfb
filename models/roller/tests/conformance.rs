//! The conformance suite of the FMI layer (fmi/testkit), run on the Roller's library.

use fmi_testkit::conformance::{Hints, Point};

/// A speed drive from a profile: the drive's torque then answers the web
/// tensions within the step (tau lists web_a.F and web_b.F).
fn hints() -> Hints {
    let speed_drive = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/speed_drive.json");
    Hints {
        points: vec![Point { values: vec![], texts: vec![("profile", speed_drive.into())] }],
        texts: vec![("profile", speed_drive.into())],
        refusals: vec![],
    }
}

fmi_testkit::conformance_tests!(roller::Roller, hints = hints);
