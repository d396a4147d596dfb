//! The conformance suite of the FMI layer (fmi/testkit), run on the span's
//! library; the span's own C API tests are in span_c_api.rs.

use fmi_testkit::conformance::{Hints, Point};

/// Roller positions off the axes, so that each coordinate changes the span
/// length to first order when `variableLength` is on.
const FRAMES: [(&str, f64); 4] = [("frame_a.x", 0.1), ("frame_a.y", 0.2), ("frame_b.x", 1.3), ("frame_b.y", 0.7)];

/// The 128 operating points where every path of the span's ModelStructure
/// shows: start at equilibrium or not, damping (with a damping coefficient
/// that matters), web mass and variable length on or off, tension in N or
/// N/m, taut or slack web, both webs from a record or not; and the other
/// texts of the String parameters: other records, a user library whose
/// PET-12 differs from the shipped one, a profile (it changes the web later
/// than the start, so no initial value depends on it). A web's value set
/// against a record that selects the web is refused, and may be.
fn hints() -> Hints {
    let mut points = Vec::new();
    for sae in [1.0, 0.0] {
        for damping in [1.0, 0.0] {
            for unit in [1.0, 5.0] {
                for slack in [false, true] {
                    for mass in [0.0, 1.0] {
                        for (variable_length, with_records) in [(0.0, false), (1.0, false), (0.0, true), (1.0, true)] {
                            let mut values = vec![
                                ("wp2.d_r", 0.01),
                                ("startAtEquilibrium", sae),
                                ("includeDamping", damping),
                                ("includeMass", mass),
                                ("variableLength", variable_length),
                                ("toUnitF", unit),
                                ("eps_start", if slack { -2e-3 } else { 2e-3 }),
                                ("web_a.v", 5.0),
                                ("web_b.v", if slack { 4.98 } else { 5.01 }),
                                ("web_a.eps", 1e-3),
                            ];
                            values.extend(FRAMES);
                            let mut texts = Vec::new();
                            if with_records {
                                // The record gives wp2.d_r (0): the point may not set it.
                                values.retain(|(name, _)| !name.starts_with("wp"));
                                texts = vec![("wp1.record", "PET-12".into()), ("wp2.record", "PET-12".into())];
                            }
                            points.push(Point { values, texts });
                        }
                    }
                }
            }
        }
    }
    let records = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/records");
    Hints {
        points,
        texts: vec![
            ("wp1.record", "LDPE-50".into()),
            ("wp2.record", "BOPP-20".into()),
            ("webLibrary", format!("{records}/user_webs.json")),
            ("profile", format!("{records}/splice_profile.json")),
        ],
        refusals: vec!["selects the web"],
    }
}

fmi_testkit::conformance_tests!(converting_span::ConvertingSpan, hints = hints);
