//! Timed web changes (a splice) from the span's profile, through the C API:
//! the strain carries over and the tension follows the new web at once, a
//! change reached inside a run equals a span started there with the new web,
//! FMU states carry the changes, and bad profiles are refused naming the file.
//!
//! Tolerance: a change only swaps parameters, so every comparison is exact
//! (bit for bit), except where noted.

use converting_span::ConvertingSpan;
use fmi_testkit::*;
use std::path::PathBuf;

type Fmu = fmi_testkit::Fmu<ConvertingSpan>;

fn profile(tag: &str, text: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("converting-span-profiles-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{tag}.json"));
    std::fs::write(&path, text).unwrap();
    path
}

/// PET at 5 m/s, roller b 0.1 % faster; a profile if given.
fn span(profile: Option<&PathBuf>) -> Fmu {
    let fmu = Fmu::new();
    fmu.set_all(&[("L", 1.2), ("wp1.thickness", 50e-6), ("wp2.thickness", 50e-6), ("web_a.v", 4.0), ("web_b.v", 4.004), ("web_a.eps", 5e-4)]);
    if let Some(p) = profile {
        assert_eq!(fmu.set_text("profile", p.to_str().unwrap()), OK);
    }
    fmu
}

#[test]
fn a_splice_changes_the_web_at_its_time_and_keeps_the_strain() {
    let p = profile("splice", r#"{"set": [{"time": 0.1, "wp1.thickness": 36e-6}, {"time": 0.2, "wp2.thickness": 36e-6}]}"#);
    let fmu = span(Some(&p));
    fmu.init(0.0);
    let h = 1e-3;
    for k in 0..300 {
        let t = k as f64 * h;
        let eps = fmu.real("summary_Strain");
        assert_eq!(fmu.do_step(t, h), OK, "{:?}", fmu.logs());
        if k == 200 {
            // Applied at the start of the step at 0.2 s: the strain carried over (one step
            // of 1 ms moves it by far less than 1e-6), the new web carries it.
            let after = fmu.real("summary_Strain");
            assert!((after - eps).abs() < 1e-6, "strain {eps} -> {after}");
        }
        // The tension is always E*A*eps of the web in the span now.
        let area = fmu.real("wp2.width") * fmu.real("wp2.thickness");
        let want = fmu.real("wp2.E") * area * fmu.real("summary_Strain");
        assert!((fmu.real("web_a.F") - want).abs() <= 1e-12 * want.abs(), "t = {t}");
        assert_eq!(fmu.real("wp2.thickness"), if k >= 200 { 36e-6 } else { 50e-6 }, "t = {t}");
    }
    assert_eq!(fmu.real("wp1.thickness"), 36e-6);
    assert_eq!(fmu.real("wp2.thickness"), 36e-6);
}

#[test]
fn a_change_equals_a_span_started_from_the_same_state_with_the_new_web() {
    let p = profile("switch", r#"{"set": [{"time": 0.05, "wp2.E": 3.5e9, "wp2.d_r": 1e-3}]}"#);
    let changed = span(Some(&p));
    changed.set("includeDamping", 1.0);
    changed.init(0.0);
    let h = 1e-3;
    for k in 0..50 {
        assert_eq!(changed.do_step(k as f64 * h, h), OK);
    }
    let eps = changed.real("summary_Strain");
    // The same span from here with the new web, started at that strain.
    let fresh = span(None);
    fresh.set_all(&[("includeDamping", 1.0), ("wp2.E", 3.5e9), ("wp2.d_r", 1e-3), ("startAtEquilibrium", 0.0), ("eps_start", eps)]);
    fresh.init(0.05);
    for k in 50..120 {
        let t = k as f64 * h;
        assert_eq!(changed.do_step(t, h), OK);
        assert_eq!(fresh.do_step(t, h), OK);
        // The same state up to the strain's round trip through L/(1+eps): a few ulps.
        let (a, b) = (changed.real("web_a.F"), fresh.real("web_a.F"));
        assert!((a - b).abs() <= 1e-12 * a.abs(), "t = {t}: {a} vs {b}");
    }
}

#[test]
fn an_fmu_state_carries_the_changes_still_to_come() {
    let p = profile("state", r#"{"set": [{"time": 0.08, "wp2.thickness": 40e-6}]}"#);
    let fmu = span(Some(&p));
    fmu.init(0.0);
    let h = 1e-3;
    for k in 0..30 {
        assert_eq!(fmu.do_step(k as f64 * h, h), OK);
    }
    let state = fmu.get_state().unwrap();
    let bytes = fmu.serialize(state).unwrap();
    let run = |f: &Fmu| -> Vec<u64> {
        (30..120).map(|k| {
            assert_eq!(f.do_step(k as f64 * h, h), OK);
            f.real("web_b.F").to_bits()
        }).collect()
    };
    let first = run(&fmu);
    // Into a fresh instance that never saw the file.
    std::fs::remove_file(&p).unwrap();
    let other = Fmu::new();
    other.init(0.0);
    let restored = other.deserialize(&bytes).unwrap();
    assert_eq!(other.set_state(restored), OK);
    assert_eq!(run(&other), first);
    assert_eq!(other.real("wp2.thickness"), 40e-6);
}

#[test]
fn bad_profiles_are_refused_naming_the_file_and_the_event() {
    let cases = [
        (r#"{"set": [{"time": 1, "L": 2}]}"#, "set at 1 s: \"L\" cannot change during a run"),
        (r#"{"set": [{"time": 1, "wp2.E": -1}]}"#, "set at 1 s: wp2.E = -1 is outside"),
        (r#"{"set": [{"time": 1, "wp2.record": "PET-99"}]}"#, "PET-99"),
        (r#"{"set": [{"time": 1, "wp2.record": 5}]}"#, "wp2.record takes a text"),
        (r#"{"speed": [[0, 1]]}"#, "unknown key \"speed\" (allowed: set)"),
    ];
    for (i, (text, needle)) in cases.iter().enumerate() {
        let p = profile(&format!("bad{i}"), text);
        let fmu = span(Some(&p));
        fmu.setup_experiment(0.0);
        fmu.enter_init();
        assert_eq!(fmu.exit_init(), ERROR, "{text}");
        let lines = fmu.take_logs();
        let last = &lines.last().unwrap().message;
        assert!(last.contains(needle) && last.contains(p.to_str().unwrap()), "{text}: {last}");
    }
}
