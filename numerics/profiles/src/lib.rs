//! Profiles: what a line part does over time, read from a JSON file with
//! serde_json. A profile holds tables (a quantity against time: a roller's
//! speed, torque or tension, the strain of the web entering the line, a
//! dancer's load) and `set` events (parameter changes at a time: a new roll,
//! a brake, a splice). The models decide which keys they accept.
//!
//! ```json
//! {"speed": [[0, 0], [0.2, 0], [0.6, 0.5]], "set": [{"time": 0.5, "b": 20}]}
//! ```
//!
//! A table is `[[time, value], ...]`: times do not decrease, at most two
//! entries share a time (a jump: the value before, then after), linear in
//! between, constant before the first and after the last entry. SI units.
//! An entry `[time, value, curvature]` makes the piece that ends there the
//! quadratic through both entries with that second derivative (S-curves).

mod table;

pub use table::Table;

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Times this close to a communication point (relative to the time, at
/// least 1e-9 s) fall on it: masters that add up their steps land a few ulps
/// off, and an event must not move a whole step for that.
pub fn tolerance(t: f64) -> f64 {
    1e-9 * t.abs().max(1.0)
}

/// Whether an event at `event` is due at `now`.
pub fn due(event: f64, now: f64) -> bool {
    event <= now + tolerance(now)
}

/// The file an FMU carries for itself, used when the `profile` parameter is empty.
pub const OWN_PROFILE: &str = "profile.json";

/// Where a line part's profile is (`path`, `None`: it has none) and, when the
/// FMU carries other instances' profiles but none matched this instance,
/// what to tell the user (`unmatched`): a line then runs without a drive.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Located {
    pub path: Option<PathBuf>,
    pub unmatched: Option<String>,
}

/// The file a `profile` parameter names: an absolute path, a name in the
/// FMU's resources folder, or (empty) the instance's own profile if the FMU
/// carries one: `resources/<instance>.json`, else `resources/profile.json`.
/// `folder` is the resources folder, or why there is none; `not_profiles`
/// are the model's other JSON files there (the span's library of webs). One
/// FMU thus serves a whole line (libcosim unpacks one copy per GUID).
pub fn locate(name: &str, folder: Result<&Path, &str>, instance: &str, not_profiles: &[&str]) -> Result<Located, String> {
    if name.is_empty() {
        let Ok(folder) = folder else { return Ok(Located::default()) };
        let own = own_files(instance).into_iter().map(|f| folder.join(f)).find(|p| p.is_file());
        if let Some(path) = own.or_else(|| Some(folder.join(OWN_PROFILE)).filter(|p| p.is_file())) {
            return Ok(Located { path: Some(path), unmatched: None });
        }
        return Ok(Located { path: None, unmatched: unmatched(folder, instance, not_profiles) });
    }
    let path = Path::new(name);
    if path.is_absolute() {
        return Ok(Located { path: Some(path.to_path_buf()), unmatched: None });
    }
    match folder {
        Ok(f) => Ok(Located { path: Some(f.join(name)), unmatched: None }),
        Err(why) => Err(format!("profile = {name:?}: cannot read resources/{name} of the FMU: {why}")),
    }
}

/// The files an instance may own: `<instance>.json`, and for a name that is a
/// path (some engines name an instance after a file) its last component,
/// with and without its extension. Only plain file names (no path, no dots only).
fn own_files(instance: &str) -> Vec<String> {
    let last = instance.rsplit(['/', '\\']).next().unwrap_or("");
    let stem = last.rsplit_once('.').map_or(last, |(stem, _)| stem);
    let mut names: Vec<String> = Vec::new();
    for candidate in [instance, last, stem] {
        let plain = !candidate.is_empty()
            && candidate.chars().all(|c| c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.'))
            && !candidate.starts_with('.');
        let file = format!("{candidate}.json");
        if plain && !names.contains(&file) {
            names.push(file);
        }
    }
    names
}

/// Why an instance runs without a profile although the FMU carries others' (`None`: it carries none).
fn unmatched(folder: &Path, instance: &str, not_profiles: &[&str]) -> Option<String> {
    let mut carried: Vec<String> = std::fs::read_dir(folder)
        .ok()?
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".json") && n != OWN_PROFILE && !not_profiles.contains(&n.as_str()))
        .collect();
    if carried.is_empty() {
        return None;
    }
    carried.sort();
    Some(format!(
        "the instance name {instance:?} matches none of the profiles this FMU carries ({}), so it runs without one: \
         name the instance after one of them (its component in the line) or set the parameter profile",
        carried.join(", ")
    ))
}

/// Profiles are small; a larger file is refused before it is read.
pub const MAX_FILE_BYTES: u64 = 16 << 20;

/// A value a `set` event gives a parameter: a number, or a text (a record name).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Value {
    Number(f64),
    Text(String),
}

/// A table's entry: [time, value], or [time, value, curvature], the second derivative of the piece
/// that ends there (an S-curve's jerk phase: webline writes them).
#[derive(Deserialize)]
#[serde(untagged)]
enum Entry {
    Linear([f64; 2]),
    Curved([f64; 3]),
}

impl Entry {
    fn split(self) -> ([f64; 2], f64) {
        match self {
            Entry::Linear(p) => (p, 0.0),
            Entry::Curved([t, x, q]) => ([t, x], q),
        }
    }
}

/// Parameter changes at one time.
#[derive(Clone, Debug, PartialEq)]
pub struct SetEvent {
    pub time: f64,
    /// (parameter name, value), by name.
    pub changes: Vec<(String, Value)>,
}

/// A profile as checked: the tables by key, and the set events by time.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Profile {
    pub tables: BTreeMap<String, Table>,
    pub events: Vec<SetEvent>,
}

// Every key but `time` is a parameter name: no `deny_unknown_fields` (it cannot
// be combined with `flatten`); the model refuses names it does not have.
#[derive(Deserialize)]
struct EventFile {
    time: f64,
    #[serde(flatten)]
    changes: serde_json::Map<String, serde_json::Value>,
}

impl Profile {
    /// Reads a profile file's text, refusing one larger than a profile can
    /// be; the error names the file.
    pub fn read_text(path: &Path) -> Result<String, String> {
        let file = path.display();
        let size = std::fs::metadata(path).map_err(|e| format!("profile {file}: {e}"))?.len();
        if size > MAX_FILE_BYTES {
            return Err(format!("profile {file}: {size} bytes, more than the {MAX_FILE_BYTES} a profile may have"));
        }
        std::fs::read_to_string(path).map_err(|e| format!("profile {file}: {e}"))
    }

    /// Parses and checks a profile's text.
    pub fn parse(text: &str, tables: &[&str]) -> Result<Profile, String> {
        let root: serde_json::Map<String, serde_json::Value> = serde_json::from_str(text).map_err(|e| e.to_string())?;
        let mut profile = Profile::default();
        for (key, value) in root {
            if key == "set" {
                let events: Vec<EventFile> = serde_json::from_value(value).map_err(|e| format!("set: {e}"))?;
                for (i, e) in events.into_iter().enumerate() {
                    profile.events.push(event(i, e)?);
                }
            } else if tables.contains(&key.as_str()) {
                let entries: Vec<Entry> = serde_json::from_value(value)
                    .map_err(|e| format!("{key}: {e} (a table is [[time, value], ...], or [time, value, curvature] for a quadratic piece)"))?;
                let (points, curvature) = entries.into_iter().map(Entry::split).unzip();
                let table = Table::curved(points, curvature).map_err(|e| format!("{key}: {e}"))?;
                profile.tables.insert(key, table);
            } else {
                let mut allowed: Vec<&str> = tables.to_vec();
                allowed.push("set");
                return Err(format!("unknown key {key:?} (allowed: {})", allowed.join(", ")));
            }
        }
        // A stable sort keeps the file's order for events at one time.
        profile.events.sort_by(|a, b| a.time.total_cmp(&b.time));
        Ok(profile)
    }

    pub fn table(&self, key: &str) -> Option<&Table> {
        self.tables.get(key)
    }

    /// The first table entry or event later than `t`: where a piece of a
    /// step that starts at `t` must end.
    pub fn next_break(&self, t: f64) -> Option<f64> {
        let tables = self.tables.values().filter_map(|table| table.next_break(t));
        let events = self.events.iter().map(|e| e.time).find(|&time| time > t);
        tables.chain(events).reduce(f64::min)
    }
}

fn event(i: usize, e: EventFile) -> Result<SetEvent, String> {
    if !e.time.is_finite() {
        return Err(format!("set[{i}]: time = {} must be finite", e.time));
    }
    if e.changes.is_empty() {
        return Err(format!("set[{i}] at {} s changes nothing", e.time));
    }
    let mut changes = Vec::with_capacity(e.changes.len());
    for (name, value) in e.changes {
        let value = match value {
            serde_json::Value::Number(n) => Value::Number(n.as_f64().filter(|x| x.is_finite()).ok_or_else(|| format!("set[{i}]: {name} = {n} is not a finite number"))?),
            serde_json::Value::String(s) => Value::Text(s),
            other => return Err(format!("set[{i}]: {name} = {other} must be a number or a text")),
        };
        changes.push((name, value));
    }
    Ok(SetEvent { time: e.time, changes })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_instance_finds_its_own_profile_before_the_shared_one() {
        let dir = std::env::temp_dir().join(format!("profiles-locate-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let found = |instance| locate("", Ok(&dir), instance, &[]).unwrap().path;
        assert_eq!(found("nip"), None);
        std::fs::write(dir.join(OWN_PROFILE), "{}").unwrap();
        assert_eq!(found("nip"), Some(dir.join(OWN_PROFILE)));
        std::fs::write(dir.join("nip.json"), "{}").unwrap();
        assert_eq!(found("nip"), Some(dir.join("nip.json")));
        assert_eq!(found("other"), Some(dir.join(OWN_PROFILE)));
        // A name that is a path: its last component, with or without its extension; never a path.
        std::fs::write(dir.join("..json"), "{}").unwrap();
        assert_eq!(found("."), Some(dir.join(OWN_PROFILE)));
        assert_eq!(found("../nip"), Some(dir.join("nip.json")));
        assert_eq!(found("/opt/line/nip"), Some(dir.join("nip.json")));
        assert_eq!(found("C:\\line\\nip.fmu"), Some(dir.join("nip.json")));
        assert_eq!(found("/opt/line/"), Some(dir.join(OWN_PROFILE)));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_instance_that_matches_none_of_the_carried_profiles_is_told_which_there_are() {
        let dir = std::env::temp_dir().join(format!("profiles-unmatched-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let located = |instance| locate("", Ok(&dir), instance, &["webs.json"]).unwrap();
        std::fs::write(dir.join("webs.json"), "{}").unwrap();
        // Only the model's own data: nothing carried, nothing to say.
        assert_eq!(located("Roller"), Located::default());
        std::fs::write(dir.join("unwind.json"), "{}").unwrap();
        std::fs::write(dir.join("rewind.json"), "{}").unwrap();
        let told = located("/engines/line/Roller.fmu");
        assert_eq!(told.path, None);
        let message = told.unmatched.unwrap();
        assert!(message.contains("\"/engines/line/Roller.fmu\" matches none") && message.contains("(rewind.json, unwind.json)"), "{message}");
        // Matched: silent.
        assert_eq!(located("unwind"), Located { path: Some(dir.join("unwind.json")), unmatched: None });
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn reads_tables_and_events_in_time_order() {
        let p = Profile::parse(
            r#"{"speed": [[0, 1], [1, 2]], "set": [{"time": 2, "b": 1}, {"time": 1, "J": 6, "R": 0.3}]}"#,
            &["speed", "torque"],
        )
        .unwrap();
        assert_eq!(p.table("speed").unwrap().value(0.5), 1.5);
        assert_eq!(p.events[0].time, 1.0);
        assert_eq!(p.events[0].changes, vec![("J".into(), Value::Number(6.0)), ("R".into(), Value::Number(0.3))]);
        assert_eq!(p.events[1].changes, vec![("b".into(), Value::Number(1.0))]);
    }

    #[test]
    fn reads_a_curved_piece() {
        let p = Profile::parse(r#"{"speed": [[0, 0], [1, 0.5, 1], [2, 1.5]]}"#, &["speed"]).unwrap();
        let t = p.table("speed").unwrap();
        assert_eq!((t.value(0.5), t.slope(0.5), t.value(1.5)), (0.125, 0.5, 1.0));
    }

    #[test]
    fn refuses_what_it_cannot_use_and_says_what() {
        let e = |text: &str| Profile::parse(text, &["speed"]).unwrap_err();
        assert!(e(r#"{"torque": [[0, 1]]}"#).contains("unknown key \"torque\" (allowed: speed, set)"));
        assert!(e(r#"{"speed": [[1, 1], [0, 1]]}"#).contains("speed: entry 1"));
        assert!(e(r#"{"speed": [[0, 1, 2]]}"#).contains("speed: entry 0"));
        assert!(e(r#"{"speed": [[0, 1, 2, 3]]}"#).contains("speed:"));
        assert!(e(r#"{"set": [{"time": 1}]}"#).contains("changes nothing"));
        assert!(e(r#"{"set": [{"time": 1, "b": [1]}]}"#).contains("must be a number or a text"));
        assert!(e(r#"{"set": [{"b": 1}]}"#).contains("set:"));
        assert!(e("[1, 2]").contains("invalid type"));
    }
}
