//! One Roller FMU carrying a whole line's profiles (`resources/<component>.json`,
//! as an SSP export writes it), through the C API: an instance finds its own
//! profile by its name, also when an engine names it by a path, and an
//! instance that matches none of them says so instead of running without a
//! drive in silence.

use fmi_testkit::{Fmu, Setup, OK, WARNING};
use roller::Roller;
use std::path::{Path, PathBuf};

/// A resources folder with the profiles of two unwinders' speed drives.
fn line_resources(tag: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("roller-line-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join("unwind.json"), r#"{"speed": [[0, 2.5], [1, 2.5]]}"#).unwrap();
    std::fs::write(dir.join("rewind.json"), r#"{"speed": [[0, 4.0], [1, 4.0]]}"#).unwrap();
    dir
}

fn instance(name: &str, resources: &Path) -> Fmu<Roller> {
    let uri = format!("file://{}/", resources.display()).replace('\\', "/");
    let uri = if uri.starts_with("file:///") { uri } else { uri.replacen("file://", "file:///", 1) };
    Fmu::with(&Setup { name: Some(name.into()), resource_location: Some(uri), ..Setup::default() })
}

#[test]
fn an_instance_named_by_a_path_finds_the_profile_of_its_last_component() {
    let dir = line_resources("path");
    for name in ["unwind", "/opt/engine/line/unwind", "C:\\line\\unwind.fmu"] {
        let fmu = instance(name, &dir);
        assert_eq!(fmu.initialize(), OK, "{name}: {:?}", fmu.logs());
        // The speed drive of unwind.json, not the idle roller's v_start.
        assert_eq!(fmu.real("web_a.v"), 2.5, "{name}");
        assert!(fmu.logs().iter().all(|l| l.status == OK), "{name}: {:?}", fmu.logs());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_instance_that_matches_no_carried_profile_warns_naming_it_and_the_profiles() {
    let dir = line_resources("unmatched");
    let fmu = instance("/engines/cache/Roller.fmu", &dir);
    // Initialization succeeds: the roller runs without a drive, as told.
    assert_eq!(fmu.initialize(), OK);
    let warnings: Vec<_> = fmu.logs().into_iter().filter(|l| l.status == WARNING).collect();
    assert_eq!(warnings.len(), 1, "{:?}", fmu.logs());
    let w = &warnings[0];
    assert_eq!(w.category, "logStatusWarning");
    assert!(w.message.starts_with("fmi2ExitInitializationMode: the instance name \"/engines/cache/Roller.fmu\" matches none"), "{}", w.message);
    assert!(w.message.contains("(rewind.json, unwind.json)"), "{}", w.message);
    // Logged once, though outputs read during initialization initialize too.
    let again = instance("/engines/cache/Roller.fmu", &dir);
    assert_eq!(again.enter_init(), OK);
    let _ = again.get("omega");
    assert_eq!(again.exit_init(), OK);
    assert_eq!(again.logs().iter().filter(|l| l.status == WARNING).count(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn an_fmu_without_other_instances_profiles_stays_silent() {
    let dir = std::env::temp_dir().join(format!("roller-line-empty-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fmu = instance("anything", &dir);
    assert_eq!(fmu.initialize(), OK);
    assert!(fmu.logs().is_empty(), "{:?}", fmu.logs());
    std::fs::remove_dir_all(&dir).unwrap();
}
