//! The roller's profile: which drive it has and the tables of time it
//! follows, read from the JSON file `profile` names (crate `profiles`).

use crate::description::{Real, DESCRIPTION};
use crate::number::Number;
use crate::parameters::Parameters;
use fmi_core::{FmiError, FmiResult, Resources};
use profiles::{Profile, Table, Value};
use std::sync::Arc;

/// The table keys a roller's profile may have.
pub const TABLES: [&str; 10] = ["speed", "torque", "tension", "strain", "load", "nip", "setpoint", "reference", "brake", "layon"];

/// A table of `TABLES` by position: looked up on every evaluation, so by index, not by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Key {
    Speed,
    Torque,
    Tension,
    Strain,
    Load,
    /// A nip's load N [R7].
    Nip,
    /// A force loop's set point [R10].
    Set,
    /// A loop's reference speed: a speed loop's set point, the inertia feed-forward's speed [R10].
    Reference,
    /// A powder brake's torque, N m >= 0 [R12].
    Brake,
    /// A lay-on roller's load F, N >= 0 [R18].
    Layon,
}

/// How the roller is driven: at most one of the profile's drive tables.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Drive {
    /// No drive table: tau_m only (0 for an idler).
    Torque,
    /// The torque table, plus tau_m.
    TorqueTable,
    /// A tension drive: -/+ r*T (unwinder/winder), plus tau_m.
    Tension,
    /// The surface speed follows the table exactly.
    Speed,
}

/// What the drive's table gives at a time: a torque table's torque, a tension table's tension.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum Read {
    #[default]
    None,
    Torque(f64),
    Tension(f64),
}

/// The drive's torque [R1]: tau_m, plus a torque table's, or a tension drive's -/+ r*T
/// (unwinder/winder: the web pulls an unwinder back and a winder forward).
#[inline]
pub fn torque<N: Number>(p: &Parameters, read: Read, tau_m: N, radius: N) -> N {
    match read {
        Read::None => tau_m,
        Read::Torque(x) => tau_m + x,
        Read::Tension(x) => tau_m + tapered_lever(p, radius) * (p.roll_sign() * x),
    }
}

/// r*T(r)/T0 of a tension drive with the hyperbolic taper [R16], T(r) = T0*(1 - k*(1 - R/r)):
/// (1 - k)*r + k*R, R the roll's start radius (a `set` event's new roll: its R); r without taper.
#[inline]
pub fn tapered_lever<N: Number>(p: &Parameters, radius: N) -> N {
    if p.drive_taper == 0.0 {
        return radius;
    }
    radius * (1.0 - p.drive_taper) + p.drive_taper * p.radius
}

/// A checked profile and its text (kept for FMU states, which restore
/// without the file).
#[derive(Clone, Debug, PartialEq)]
pub struct Loaded {
    pub profile: Arc<Profile>,
    pub text: Arc<str>,
    pub drive: Drive,
    /// The profile's tables in the order of `TABLES`, found once.
    pub tables: Arc<[Option<Table>; 10]>,
}

impl Loaded {
    #[inline]
    pub fn table(&self, key: Key) -> Option<&Table> {
        self.tables[key as usize].as_ref()
    }
}

/// The roller's profile, if it has one; else, when the FMU carries other
/// instances' profiles but none for this one, the warning that says so.
pub fn load(p: &Parameters, resources: &Resources) -> FmiResult<Result<Loaded, Option<String>>> {
    let located = profiles::locate(&p.profile, resources.folder_or_why(), resources.instance(), &[]).map_err(FmiError::error)?;
    let Some(path) = located.path else { return Ok(Err(located.unmatched)) };
    let text = Profile::read_text(&path).map_err(FmiError::error)?;
    parse(p, &text).map(Ok).map_err(|e| FmiError::error(format!("profile {}: {e}", path.display())))
}

/// Why drive.taper is refused (None: it acts, or is 0, or has nothing to act on, as `Parameters::acts`
/// says): on an unwinder's tension drive it would mean tapering an unwind, which is not a taper (the
/// roll's wound-in stresses are set; its tension is what the process needs).
pub fn taper_refusal(p: &Parameters, drive: Drive) -> Option<String> {
    (p.drive_taper != 0.0 && drive == Drive::Tension && p.roll == crate::parameters::UNWINDER).then(|| {
        format!(
            "drive.taper = {}: a taper acts on a winder's tension drive (roll = 2), this is an unwinder's (roll = 1): an unwinder's \
             tension is not tapered (its roll's wound-in stresses are set); give drive.taper = 0",
            p.drive_taper
        )
    })
}

/// Parses and checks a profile against the roller's parameters.
pub fn parse(p: &Parameters, text: &str) -> Result<Loaded, String> {
    let loaded = read(text)?;
    if loaded.drive == Drive::Tension && p.roll_sign() == 0.0 {
        return Err(format!("a tension drive needs roll = 1 (unwinder) or 2 (winder), roll is {}", p.roll));
    }
    if loaded.table(Key::Load).is_some() && !p.carriage {
        return Err("a load table needs carriage = true".into());
    }
    if loaded.table(Key::Brake).is_some() && p.traction {
        return Err("a brake table with includeTraction = true: a brake on a roller where the web may slip is not modelled".into());
    }
    if loaded.table(Key::Layon).is_some() && !p.layon {
        return Err("a layon table needs layon = true (it is the lay-on roller's load [R18])".into());
    }
    if loaded.table(Key::Nip).is_some() && !p.traction {
        return Err("a nip table needs includeTraction = true (a nip acts through the web's friction on the roller)".into());
    }
    if p.layon && loaded.profile.events.iter().any(|e| e.changes.iter().any(|(name, _)| name == "R")) {
        return Err("a set event of R with layon = true: a new roll would move its surface under the lay-on roller's carriage [R18], \
                    which is not modelled (J and b may change)"
            .into());
    }
    let kind = crate::parameters::Kind::of(p);
    if p.speed_input && (loaded.drive != Drive::Torque || kind != crate::parameters::Kind::None || loaded.table(Key::Brake).is_some()) {
        return Err("speed.input = true: the surface speed is loop.speed; the profile may have no speed, torque, tension or brake table and loop.kind must be 0".into());
    }
    if kind != crate::parameters::Kind::None && !matches!(loaded.drive, Drive::Torque | Drive::TorqueTable) {
        return Err(format!("loop.kind = {}: a loop drives by torque; the profile's speed or tension table would override it", p.loop_kind));
    }
    if loaded.table(Key::Set).is_some() && kind != crate::parameters::Kind::Force {
        return Err("a setpoint table needs loop.kind = 1 (a force loop)".into());
    }
    if loaded.table(Key::Reference).is_some() && !(matches!(kind, crate::parameters::Kind::Speed | crate::parameters::Kind::Dancer) || (kind != crate::parameters::Kind::None && p.loop_feedforward)) {
        return Err("a reference table needs loop.kind = 2 or 3 (a speed or dancer loop) or a loop with loop.feedforward = true".into());
    }
    Ok(loaded)
}

/// Parses and checks a profile by its own rules, not against the parameters: an FMU state
/// restores the profile it holds, which a parameter set after a provisional initialization
/// may no longer fit until initialization, which `parse`s it again, ends.
pub fn read(text: &str) -> Result<Loaded, String> {
    let profile = Profile::parse(text, &TABLES)?;
    let drives: Vec<&str> = ["speed", "torque", "tension"].into_iter().filter(|k| profile.table(k).is_some()).collect();
    let drive = match drives.as_slice() {
        [] => Drive::Torque,
        ["speed"] => Drive::Speed,
        ["torque"] => Drive::TorqueTable,
        ["tension"] => Drive::Tension,
        _ => return Err(format!("{} tables: a roller has at most one drive (speed, torque or tension)", drives.join(" and "))),
    };
    if let Some(brake) = profile.table("brake") {
        if drive == Drive::Speed {
            return Err("brake and speed tables: a brake acts on a roller whose speed is free".into());
        }
        if let Some(&[t, b]) = brake.points().iter().find(|&&[_, b]| !(b >= 0.0 && b.is_finite())) {
            return Err(format!("brake: the torque at {t} s is {b} N.m; a brake's torque is >= 0 (it opposes the motion)"));
        }
    }
    for key in ["nip", "layon"] {
        if let Some(&[t, n]) = profile.table(key).and_then(|table| table.points().iter().find(|&&[_, n]| !(n >= 0.0 && n.is_finite()))) {
            return Err(format!("{key}: the load at {t} s is {n} N; a nip presses with a load >= 0"));
        }
    }
    for e in &profile.events {
        for (name, value) in &e.changes {
            let var = match name.as_str() {
                "J" => Real::J,
                "R" => Real::R,
                "b" => Real::b,
                _ => return Err(format!("set at {} s: {name:?} cannot change during a run (J, R and b can)", e.time)),
            };
            let range = &DESCRIPTION.variable(var.vr()).expect("J, R, b are described").range;
            match value {
                Value::Number(x) if range.contains(*x) => {}
                Value::Number(x) => return Err(format!("set at {} s: {name} = {x} is outside {range}", e.time)),
                Value::Text(t) => return Err(format!("set at {} s: {name} = {t:?} must be a number", e.time)),
            }
        }
    }
    let tables = Arc::new(TABLES.map(|k| profile.table(k).cloned()));
    Ok(Loaded { profile: Arc::new(profile), text: text.into(), drive, tables })
}
