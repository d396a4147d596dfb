//! Web records through the C API: the shipped library, a user's file, which
//! value wins, every bad file and name, the resource location, FMU states.

use converting_span::ConvertingSpan;
use fmi_testkit::*;
use serde_json::Value;
use std::path::{Path, PathBuf};

type Fmu = fmi_testkit::Fmu<ConvertingSpan>;

const SHIPPED: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/resources/webs.json");
const USER: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/records/user_webs.json");
/// A record's fields, each also the name of a `wpN.` parameter.
const FIELDS: [&str; 5] = ["E", "thickness", "width", "density", "d_r"];

fn shipped_records() -> Vec<Value> {
    let text = std::fs::read_to_string(SHIPPED).unwrap();
    serde_json::from_str::<Value>(&text).unwrap()["webs"].as_array().unwrap().clone()
}

/// One line, an error, containing every needle.
fn assert_one_error(fmu: &Fmu, needles: &[&str]) {
    let lines = fmu.take_logs();
    assert_eq!(lines.len(), 1, "expected one log line, got {lines:#?}");
    assert_eq!(lines[0].status, ERROR, "{:?}", lines[0]);
    for needle in needles {
        assert!(lines[0].message.contains(needle), "message {:?} lacks {needle:?}", lines[0].message);
    }
}

/// A run with damping and web mass on, inputs changing every step: every
/// output's bits after each of 300 steps.
fn run(fmu: &Fmu) -> Vec<u64> {
    fmu.set_all(&[("includeDamping", 1.0), ("includeMass", 1.0), ("toUnitF", 5.0), ("web_a.v", 5.0), ("web_b.v", 5.01)]);
    fmu.init(0.0);
    let outputs = ["v", "T", "web_a.F", "web_b.F", "web_b.eps", "summary_Stress", "m_web"];
    let mut bits = Vec::new();
    for k in 0..300 {
        let x = k as f64;
        fmu.set_all(&[("web_a.v", 5.0 + 0.1 * (0.9 * x).sin()), ("web_b.v", 5.02 + 0.05 * (0.7 * x).cos())]);
        assert_eq!(fmu.do_step(x * 1e-3, 1e-3), OK, "{:?}", fmu.logs());
        bits.extend(outputs.iter().map(|o| fmu.real(o).to_bits()));
    }
    bits
}

/// A temporary user library holding `text`.
fn user_file(tag: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("converting-span-records-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{tag} webs.json"));
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn every_linear_shipped_record_is_bit_identical_to_its_values_set_one_by_one() {
    let mut compared = 0;
    for record in shipped_records() {
        if record.get("E").is_none() {
            continue; // a table has no individual values to compare with
        }
        let name = record["name"].as_str().unwrap();
        let by_name = Fmu::new();
        assert_eq!(by_name.set_text("wp1.record", name), OK);
        assert_eq!(by_name.set_text("wp2.record", name), OK);
        let one_by_one = Fmu::new();
        for web in ["wp1", "wp2"] {
            for field in FIELDS {
                one_by_one.set_all(&[(&format!("{web}.{field}"), record[field].as_f64().unwrap())]);
            }
        }
        assert_eq!(run(&by_name), run(&one_by_one), "record {name}");
        for field in FIELDS {
            assert_eq!(by_name.real(&format!("wp2.{field}")), record[field].as_f64().unwrap(), "{name}: wp2.{field} reads the record");
        }
        compared += 1;
    }
    assert!(compared >= 12, "only {compared} linear records");
}

#[test]
fn a_table_record_reads_its_steepest_chord_as_e() {
    let fmu = Fmu::new();
    assert_eq!(fmu.set_text("wp2.record", "nonwoven-PP-spunbond"), OK);
    fmu.init(0.0);
    // The chord from 0.01 to 0.02: (1.2e6 - 0.45e6) / 0.01 (rounded as the FMU divides).
    assert_eq!(fmu.real("wp2.E"), (1.2e6 - 0.45e6) / (0.02 - 0.01));
    assert_eq!(fmu.real("wp2.thickness"), 0.25e-3);
    assert_eq!(fmu.text("wp2.record"), "nonwoven-PP-spunbond");
}

#[test]
fn an_individual_value_against_a_record_is_an_error_naming_both_and_reset_recovers() {
    let fmu = Fmu::new();
    assert_eq!(fmu.set_text("wp2.record", "PET-12"), OK);
    fmu.set_all(&[("wp2.thickness", 20e-6)]);
    assert_eq!(fmu.setup_experiment(0.0), OK);
    assert_eq!(fmu.enter_init(), OK);
    assert_eq!(fmu.exit_init(), ERROR);
    assert_one_error(&fmu, &["wp2.thickness = 0.00002", "wp2.record = \"PET-12\"", "0.000012", "start value"]);
    assert_eq!(fmu.reset(), OK);
    assert_eq!(fmu.setup_experiment(0.0), OK);
    assert_eq!(fmu.enter_init(), OK);
    assert_eq!(fmu.text("wp2.record"), "", "reset restores the start values");
    assert_eq!(fmu.exit_init(), OK);
    assert_eq!(fmu.do_step(0.0, 1e-3), OK);
}

#[test]
fn values_at_their_start_or_equal_to_the_record_are_accepted() {
    // Importers write back every start value, and values they read.
    let fmu = Fmu::new();
    assert_eq!(fmu.set_text("wp2.record", "steel-0.3"), OK);
    let start = |name: &str| match converting_span::description::DESCRIPTION.variables.iter().find(|v| v.name == name).unwrap().start {
        fmi_core::description::Start::Real(x) => x,
        _ => unreachable!(),
    };
    fmu.set_all(&[("wp2.E", start("wp2.E")), ("wp2.thickness", 0.3e-3), ("wp2.density", 7850.0)]);
    fmu.init(0.0);
    assert_eq!((fmu.real("wp2.E"), fmu.real("wp2.density")), (200e9, 7850.0));
}

#[test]
fn a_user_library_is_searched_before_the_shipped_one() {
    let fmu = Fmu::new();
    assert_eq!(fmu.set_text("webLibrary", USER), OK);
    assert_eq!(fmu.set_text("wp2.record", "PET-12"), OK);
    assert_eq!(fmu.set_text("wp1.record", "PET-23"), OK);
    fmu.init(0.0);
    assert_eq!((fmu.real("wp2.E"), fmu.real("wp2.width")), (5.0e9, 1.2), "the user's PET-12");
    assert_eq!(fmu.real("wp1.thickness"), 23e-6, "PET-23 from the shipped library");
}

#[test]
fn every_bad_name_and_file_gets_its_message_and_reset_recovers() {
    let good = std::fs::read_to_string(USER).unwrap();
    let missing = Path::new("/nonexistent/dir/webs.json");
    let cases: Vec<(String, &str, Vec<String>)> = vec![
        (USER.into(), "PET-13", vec!["wp2.record = \"PET-13\"".into(), "no web of that name".into(), "nearest: \"PET-12\"".into(), "webs.json".into()]),
        (missing.display().to_string(), "PET-12", vec![missing.display().to_string(), "cannot read the web library".into()]),
        (
            user_file("malformed", &good.replacen("\"E\": 5.0e9,", "\"E\": 5.0e9,,", 1)).display().to_string(),
            "PET-12",
            vec!["malformed webs.json".into(), "line 7 column".into()],
        ),
        (
            user_file("unknown-field", &good.replacen("\"source\"", "\"sorce\"", 1)).display().to_string(),
            "PET-12",
            vec!["unknown field `sorce`".into(), "line 8".into()],
        ),
        (
            user_file("decreasing", &good.replacen("[0.004, 14e6]", "[0.004, 7e6]", 1)).display().to_string(),
            "PET-12",
            vec!["record \"paper-measured\"".into(), "stress_strain".into(), "must not decrease".into()],
        ),
        (
            user_file("short", &good.replacen("[[-0.001, -4e6], [0.0, 0.0], [0.002, 8e6], [0.004, 14e6], [0.008, 20e6]]", "[[0.0, 0.0]]", 1))
                .display()
                .to_string(),
            "PET-12",
            vec!["record \"paper-measured\"".into(), "at least 2".into()],
        ),
        (
            user_file("not-increasing", &good.replacen("[0.004, 14e6]", "[0.002, 14e6]", 1)).display().to_string(),
            "PET-12",
            vec!["record \"paper-measured\"".into(), "strain must increase strictly".into()],
        ),
        (
            user_file("non-finite", &good.replacen("14e6", "1e999", 1)).display().to_string(),
            "PET-12",
            vec!["number out of range".into(), "line".into()],
        ),
        (
            user_file("negative", &good.replacen("\"thickness\": 13e-6", "\"thickness\": -13e-6", 1)).display().to_string(),
            "PET-12",
            vec!["record \"PET-12\"".into(), "thickness = -0.000013".into(), "allowed range".into()],
        ),
        (
            user_file("duplicate", &good.replacen("\"paper-measured\"", "\"PET-12\"", 1)).display().to_string(),
            "PET-12",
            vec!["record \"PET-12\"".into(), "used twice".into()],
        ),
    ];
    for (library, name, needles) in cases {
        let fmu = Fmu::new();
        assert_eq!(fmu.set_text("webLibrary", &library), OK);
        assert_eq!(fmu.set_text("wp2.record", name), OK);
        assert_eq!(fmu.setup_experiment(0.0), OK);
        assert_eq!(fmu.enter_init(), OK);
        assert_eq!(fmu.exit_init(), ERROR, "{library}: {name}");
        let needles: Vec<&str> = needles.iter().map(String::as_str).collect();
        assert_one_error(&fmu, &needles);
        assert!(fmu.logs().is_empty());
        assert_eq!(fmu.reset(), OK);
        fmu.init(0.0);
        assert_eq!(fmu.do_step(0.0, 1e-3), OK, "recovered after {library}");
    }
}

#[test]
fn no_resource_location_is_an_error_only_when_a_shipped_record_is_needed() {
    let setup = Setup { resource_location: None, ..Setup::default() };
    let fmu = Fmu::with(&setup);
    fmu.init(0.0);
    assert_eq!(fmu.do_step(0.0, 1e-3), OK, "no record: no resources needed");

    let fmu = Fmu::with(&setup);
    assert_eq!(fmu.set_text("webLibrary", USER), OK);
    assert_eq!(fmu.set_text("wp2.record", "paper-measured"), OK);
    fmu.init(0.0);
    assert_eq!(fmu.real("wp2.width"), 1.0, "found in the user's file");

    let fmu = Fmu::with(&setup);
    assert_eq!(fmu.set_text("wp2.record", "PET-12"), OK);
    assert_eq!(fmu.setup_experiment(0.0), OK);
    assert_eq!(fmu.enter_init(), OK);
    assert_eq!(fmu.exit_init(), ERROR);
    assert_one_error(&fmu, &["wp2.record = \"PET-12\"", "resources/webs.json", "NULL"]);

    let fmu = Fmu::with(&Setup { resource_location: Some("http://example.com/fmu/resources".into()), ..Setup::default() });
    assert_eq!(fmu.set_text("wp2.record", "PET-12"), OK);
    assert_eq!(fmu.setup_experiment(0.0), OK);
    assert_eq!(fmu.enter_init(), OK);
    assert_eq!(fmu.exit_init(), ERROR);
    assert_one_error(&fmu, &["http://example.com/fmu/resources", "is not a file: URI"]);
}

#[test]
fn a_null_string_is_refused_and_changes_nothing() {
    let fmu = Fmu::new();
    let vr = converting_span::description::Text::wp2_record.vr();
    // SAFETY: live instance; one value reference and one (NULL) value.
    let status = unsafe { fmi2SetString(fmu.c, &vr, 1, &std::ptr::null()) };
    assert_eq!(status, ERROR);
    assert_one_error(&fmu, &["wp2.record = NULL"]);
}

#[test]
fn a_table_record_survives_a_serialized_state_in_a_fresh_instance() {
    let fmu = Fmu::new();
    assert_eq!(fmu.set_text("webLibrary", USER), OK);
    assert_eq!(fmu.set_text("wp2.record", "paper-measured"), OK);
    fmu.set_all(&[("includeDamping", 1.0), ("web_a.v", 5.0), ("web_b.v", 5.02)]);
    fmu.init(0.0);
    assert_eq!(fmu.do_step(0.0, 1e-3), OK);
    let bytes = fmu.serialize(fmu.get_state().unwrap()).unwrap();
    let mut continued = Vec::new();
    for k in 1..50 {
        assert_eq!(fmu.do_step(k as f64 * 1e-3, 1e-3), OK);
        continued.push(fmu.real("web_a.F").to_bits());
    }
    // A fresh instance without the user's file: the table travels in the state.
    let other = Fmu::with(&Setup { resource_location: None, ..Setup::default() });
    let state = other.deserialize(&bytes).unwrap();
    assert_eq!(other.set_state(state), OK, "{:?}", other.logs());
    let mut again = Vec::new();
    for k in 1..50 {
        assert_eq!(other.do_step(k as f64 * 1e-3, 1e-3), OK);
        again.push(other.real("web_a.F").to_bits());
    }
    assert_eq!(continued, again);
}

/// With a table the clamp of a slack web, the stress, the per-width sensor
/// unit and the web mass all follow the record: a web pushed into
/// compression by a slower roller b reads 0 N, and the other outputs keep
/// their relations to the tension and the record's cross-section.
#[test]
fn a_table_web_goes_slack_and_every_output_follows_the_record() {
    let fmu = Fmu::new();
    assert_eq!(fmu.set_text("webLibrary", USER), OK);
    assert_eq!(fmu.set_text("wp2.record", "paper-measured"), OK);
    fmu.set_all(&[("preventNegativeTension", 1.0), ("includeMass", 1.0), ("toUnitF", 5.0), ("web_a.v", 5.0), ("web_b.v", 5.0)]);
    fmu.init(0.0);
    let area = 100e-6 * 1.0;
    let mut slack_seen = false;
    for k in 0..400 {
        // roller b slows to 4.99 m/s: the strain falls below 0 and the web goes slack
        fmu.set_all(&[("web_b.v", if k < 10 { 5.0 } else { 4.99 })]);
        assert_eq!(fmu.do_step(k as f64 * 1e-3, 1e-3), OK);
        let (t, eps) = (fmu.real("summary_Tension"), fmu.real("summary_Strain"));
        assert!(t >= 0.0, "clamped: {t}");
        slack_seen |= eps < 0.0 && t == 0.0;
        assert_eq!(fmu.real("summary_Stress"), t / area);
        assert_eq!(fmu.real("T"), t / 1.0, "N/m divides by the record's width");
        assert_eq!(fmu.real("m_web"), 800.0 * area * fmu.real("unstretchedLength"));
    }
    assert!(slack_seen, "the web went slack");
}
