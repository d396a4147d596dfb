//! The conformance suite of the FMI layer (fmi/testkit), run on the Roller's library.

use fmi_testkit::conformance::{Hints, Point};

/// A speed drive from a profile: the drive's torque then answers the web
/// tensions within the step (tau lists web_a.F and web_b.F); the same with
/// every inlet and outlet in use, where the extra ports' tensions reach tau
/// and their strains the merged web_b.eps [R5].
fn hints() -> Hints {
    let speed_drive = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/scenes/speed_drive.json");
    let all_ports = vec![("inlets", 4.0), ("outlets", 4.0)];
    Hints {
        points: vec![
            Point { values: vec![], texts: vec![("profile", speed_drive.into())] },
            Point { values: all_ports, texts: vec![("profile", speed_drive.into())] },
        ],
        texts: vec![("profile", speed_drive.into())],
        refusals: vec![],
    }
}

fmi_testkit::conformance_tests!(roller::Roller, hints = hints);
