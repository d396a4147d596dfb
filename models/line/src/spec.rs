//! `resources/line.json`: the line an FMU holds, as `webline export --fmu`
//! writes it from a scene. Its parts are the span's and the Roller's models
//! with their start values and profiles; the connections say which output
//! feeds which input, as in the line's SSP of parts. Unknown fields are
//! refused, so a misspelt key is an error and not a silent default.

use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

/// Where a line's spec sits in the FMU (resources/).
pub const SPEC_FILE: &str = "line.json";
/// Where each part's profile sits (resources/), by part name.
pub const PROFILE_FOLDER: &str = "profiles";

/// The format this binary reads; another is refused with both named.
pub const FORMAT: &str = "converting-span-line 1";

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Spec {
    pub format: String,
    pub name: String,
    #[serde(default)]
    pub description: String,
    pub experiment: ExperimentSpec,
    /// How the line starts: in equilibrium with its drives (the default),
    /// or from the parts' start values as given.
    #[serde(default)]
    pub start: StartMode,
    /// In line order (the web's path): the states follow it, so the line's
    /// Jacobian is banded.
    pub parts: Vec<PartSpec>,
    pub connections: Vec<Connection>,
    /// Spans that carry a laminate: each a span part per layer, side by side; the line offers the
    /// laminate's own outputs (`<name>.T`, `.eps`, `.F_a`, `.F_b`, `.length`, `.T_<label>`).
    #[serde(default)]
    pub laminates: Vec<LaminateSpec>,
}

/// A laminate span: its name (which names its outputs) and its layers, each a span part of the line.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LaminateSpec {
    pub name: String,
    pub layers: Vec<LayerSpec>,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LayerSpec {
    /// The layer's span part.
    pub part: String,
    /// Names its tension output, `<laminate>.T_<label>`.
    pub label: String,
}

/// A laminate's own outputs: a layer label may not be one of them (nor `T_` and another label).
pub const LAMINATE_OUTPUTS: [&str; 5] = ["T", "eps", "F_a", "F_b", "length"];

/// Letters, digits and _: a name that may prefix a variable's.
fn plain(name: &str) -> bool {
    !name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

#[derive(Clone, Copy, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ExperimentSpec {
    #[serde(default)]
    pub start_time: f64,
    pub stop_time: f64,
    /// The communication step the scene was made for.
    pub step: f64,
}

#[derive(Clone, Copy, Debug, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum StartMode {
    #[default]
    Equilibrium,
    Given,
}

#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
pub enum ModelKind {
    ConvertingSpan,
    Roller,
}

/// What a part is in the line: it decides the outputs and inputs the Line
/// FMU offers for it.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub enum Role {
    Span,
    Source,
    Sink,
    Roller,
    Unwinder,
    Winder,
    Dancer,
}

impl Role {
    pub fn name(self) -> &'static str {
        match self {
            Role::Span => "span",
            Role::Source => "source",
            Role::Sink => "sink",
            Role::Roller => "roller",
            Role::Unwinder => "unwinder",
            Role::Winder => "winder",
            Role::Dancer => "dancer",
        }
    }
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PartSpec {
    pub name: String,
    pub model: ModelKind,
    pub role: Role,
    /// Start values by the part's variable name (parameters and inputs).
    #[serde(default)]
    pub start: BTreeMap<String, serde_json::Value>,
    /// The part's profile (tables of time, timed `set` entries), as its own
    /// FMU would read it; shipped as resources/profiles/<name>.json.
    #[serde(default)]
    pub profile: Option<serde_json::Value>,
    /// Whether the Line FMU gives it a motor torque input `<name>.tau_m`
    /// (its speed is not prescribed).
    #[serde(default)]
    pub torque_input: bool,
    /// Whether the Line FMU gives its loop's set point as an input `<name>.T_set` (N) instead of
    /// the tunable parameter `<name>.loop.set`: the scene decides, as an FMU cannot see whether
    /// an input is connected.
    #[serde(default)]
    pub set_input: bool,
    /// Whether the Line FMU gives its speed loop's reference, or its ideal speed drive's speed
    /// (`speed.input`), as an input `<name>.v_ref` (m/s) instead of the tunable parameter `<name>.loop.speed`.
    #[serde(default)]
    pub speed_input: bool,
    /// The part whose input `<part>.v_ref` is this roller's feed-forward reference [R10] (its
    /// loop.speed and loop.acceleration, which the line sets: `feed`), instead of a reference table.
    #[serde(default)]
    pub feedforward_from: Option<String>,
    /// A load cell: the wrap angle of the web on the roller, degrees; the
    /// output `<name>.F` is the resultant of the two web forces on its bearings.
    #[serde(default)]
    pub wrap: Option<f64>,
}

impl PartSpec {
    /// Its profile prescribes its surface speed (a table `speed`), or its input v_ref does
    /// (`speed.input`, an ideal speed drive).
    pub fn speed_driven(&self) -> bool {
        self.has_table("speed") || self.start.get("speed.input").is_some_and(|v| v.as_bool() == Some(true))
    }

    /// Its profile has the table `key`.
    pub fn has_table(&self, key: &str) -> bool {
        self.profile.as_ref().is_some_and(|p| p.get(key).is_some())
    }
}

/// `from` (part, output) feeds `to` (part, input).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Connection {
    pub from: (String, String),
    pub to: (String, String),
}

impl Spec {
    /// Parses and checks what needs no model: format, names, experiment.
    pub fn parse(text: &str) -> Result<Spec, String> {
        let spec: Spec = serde_json::from_str(text).map_err(|e| format!("line.json: {e}"))?;
        if spec.format != FORMAT {
            return Err(format!("line.json: format {:?} is not the one this binary reads ({FORMAT:?})", spec.format));
        }
        let e = spec.experiment;
        if !(e.start_time.is_finite() && e.stop_time > e.start_time && e.step > 0.0 && e.step.is_finite()) {
            return Err(format!(
                "line.json: experiment start_time = {}, stop_time = {}, step = {}: needs start < stop and a step > 0",
                e.start_time, e.stop_time, e.step
            ));
        }
        if spec.parts.is_empty() {
            return Err("line.json: a line needs at least one part".into());
        }
        let mut seen = std::collections::BTreeSet::new();
        for p in &spec.parts {
            // A laminate's layer is `<laminate>.<label>`: plain names joined by dots.
            if !p.name.split('.').all(plain) {
                return Err(format!(
                    "line.json: part name {:?}: use letters, digits and _ only, in names joined by dots (it prefixes variable names)",
                    p.name
                ));
            }
            // A part without a profile finds resources/<name>.json as its own: not these.
            if p.name == "line" || p.name == "profile" {
                return Err(format!("line.json: a part may not be named {:?} (a file of the FMU's resources has that name)", p.name));
            }
            if !seen.insert(p.name.as_str()) {
                return Err(format!("line.json: two parts are named {:?}", p.name));
            }
            let span_model = p.model == ModelKind::ConvertingSpan;
            if span_model != (p.role == Role::Span) {
                return Err(format!("line.json: part {}: role {} does not go with model {:?}", p.name, p.role.name(), p.model));
            }
            if let Some(w) = p.wrap {
                if !(0.0..=360.0).contains(&w) {
                    return Err(format!("line.json: part {}: wrap = {w} degrees is outside [0, 360]", p.name));
                }
            }
        }
        spec.check_laminates()?;
        Ok(spec)
    }

    /// Each laminate: a name of its own, at least two layers, each a span part once, labels that
    /// name outputs of their own.
    fn check_laminates(&self) -> Result<(), String> {
        let mut used = std::collections::BTreeSet::new();
        for lam in &self.laminates {
            let what = format!("line.json: laminate {:?}", lam.name);
            if !plain(&lam.name) || self.part(&lam.name).is_some() || self.laminates.iter().filter(|l| l.name == lam.name).count() > 1 {
                return Err(format!("{what}: its name must be plain (letters, digits, _) and no other part's or laminate's"));
            }
            if lam.layers.len() < 2 {
                return Err(format!("{what}: a laminate has at least two layers, not {}", lam.layers.len()));
            }
            for layer in &lam.layers {
                let span = self.part(&layer.part).map(|p| self.parts[p].role == Role::Span);
                if span != Some(true) {
                    return Err(format!("{what}: layer {:?} is no span part of the line", layer.part));
                }
                if !used.insert(layer.part.as_str()) {
                    return Err(format!("{what}: part {:?} is a layer twice", layer.part));
                }
                let label = layer.label.as_str();
                let taken = LAMINATE_OUTPUTS.contains(&label)
                    || lam.layers.iter().filter(|l| l.label == label).count() > 1
                    || label.strip_prefix("T_").is_some_and(|rest| lam.layers.iter().any(|l| l.label == rest));
                if !plain(label) || taken {
                    return Err(format!("{what}: layer label {label:?} must be plain and name an output of its own"));
                }
            }
        }
        Ok(())
    }

    pub fn part(&self, name: &str) -> Option<usize> {
        self.parts.iter().position(|p| p.name == name)
    }
}

/// What the parts read in the FMU's resources/ `folder` beside line.json, which the GUID
/// covers, checked against it: each part's profile is the one line.json holds for it (an edited
/// profile would change the run under the same GUID), and a part without one finds no file it
/// would take as its own (resources/<part>.json, resources/profile.json).
pub fn check_resources(spec: &Spec, folder: &Path) -> Result<(), String> {
    let changed = "the FMU's resources were changed after export (its GUID is the hash of line.json, which holds every \
                   profile): export the scene again";
    for p in &spec.parts {
        match &p.profile {
            Some(profile) => {
                let file = format!("{PROFILE_FOLDER}/{}.json", p.name);
                let text = std::fs::read_to_string(folder.join(&file)).map_err(|e| format!("cannot read resources/{file}, part {}'s profile: {e}", p.name))?;
                let found: serde_json::Value = serde_json::from_str(&text).map_err(|e| format!("resources/{file}: {e}; {changed}"))?;
                if &found != profile {
                    return Err(format!("resources/{file} is not the profile line.json holds for part {}: {changed}", p.name));
                }
            }
            None => {
                if let Some(path) = profiles::locate("", Ok(folder), &p.name, &[])?.path {
                    let file = path.strip_prefix(folder).unwrap_or(&path).display().to_string();
                    return Err(format!("resources/{file} would be part {}'s profile, which line.json does not give it: {changed}", p.name));
                }
            }
        }
    }
    Ok(())
}

/// FNV-1a over the bytes, 64 bit, twice with different offsets: the
/// GUID of a line is the hash of its line.json text, so a description
/// shipped with other resources is refused at instantiation.
pub fn guid(text: &str) -> String {
    let fnv = |offset: u64| text.bytes().fold(offset, |h, b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3));
    let (a, b) = (fnv(0xcbf2_9ce4_8422_2325), fnv(0x8422_2325_cbf2_9ce4));
    format!(
        "{{{:08x}-{:04x}-{:04x}-{:04x}-{:012x}}}",
        a >> 32,
        (a >> 16) & 0xffff,
        a & 0xffff,
        b >> 48,
        b & 0xffff_ffff_ffff
    )
}
