//! Web property records by name: JSON files read with serde_json. The FMU
//! ships a library of common webs in `resources/webs.json`; a user's own
//! file (`webLibrary`) is searched first. A record holds a web's modulus
//! (`E`, or a `stress_strain` table), thickness, width, density and `d_r`.
//! Every record of a file is checked when the file is read, against the
//! allowed ranges of the matching `wp2.*` parameters.

use crate::description::{Real, DESCRIPTION};
use crate::parameters::{Parameters, WebProperties};
use crate::stress_strain::StressStrain;
use fmi_core::description::Start;
use fmi_core::{FmiError, FmiResult, Resources};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The shipped library's file in the FMU's resources/ folder.
pub const SHIPPED: &str = "webs.json";

/// A library file as written: unknown fields are refused.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LibraryFile {
    /// What the file holds (free text).
    #[allow(dead_code)]
    description: Option<String>,
    webs: Vec<RecordFile>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct RecordFile {
    name: String,
    #[allow(dead_code)]
    description: String,
    #[serde(rename = "E")]
    modulus: Option<f64>,
    /// (engineering strain, engineering stress in Pa) pairs.
    stress_strain: Option<Vec<[f64; 2]>>,
    thickness: f64,
    width: f64,
    density: f64,
    d_r: f64,
    /// Where the values come from.
    #[allow(dead_code)]
    source: Option<String>,
}

/// A checked record: the web it describes.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    pub name: String,
    pub web: WebProperties,
}

/// The checked records of one file.
pub struct Library {
    pub path: PathBuf,
    pub records: Vec<Record>,
}

impl Library {
    /// Reads and checks a whole file; the error names the file and, for
    /// JSON, the line and column, otherwise the record and the field.
    pub fn read(path: &Path) -> FmiResult<Library> {
        let at = path.display();
        let text = std::fs::read_to_string(path).map_err(|e| FmiError::error(format!("{at}: cannot read the web library: {e}")))?;
        Self::parse(&text, path)
    }

    pub fn parse(text: &str, path: &Path) -> FmiResult<Library> {
        let at = path.display();
        let file: LibraryFile = serde_json::from_str(text).map_err(|e| FmiError::error(format!("{at}: {e}")))?;
        let mut records: Vec<Record> = Vec::with_capacity(file.webs.len());
        for r in file.webs {
            let fail = |what: String| FmiError::error(format!("{at}: record \"{}\": {what}", r.name));
            if r.name.trim().is_empty() {
                return Err(fail("the name is empty".into()));
            }
            if records.iter().any(|other| other.name == r.name) {
                return Err(fail("the name is used twice in this file".into()));
            }
            let curve = match (r.modulus, &r.stress_strain) {
                (Some(_), Some(_)) => return Err(fail("has both E and stress_strain; give one of them".into())),
                (None, None) => return Err(fail("has neither E nor stress_strain; give one of them".into())),
                (Some(_), None) => None,
                (None, Some(points)) => {
                    Some(Arc::new(StressStrain::new(points).map_err(|e| fail(format!("stress_strain {e}")))?))
                }
            };
            // A table's modulus is its steepest chord (what wpN.E then reads).
            let modulus = r.modulus.unwrap_or_else(|| curve.as_ref().map_or(0.0, |c| c.steepest_chord()));
            for (field, value, var) in [
                ("E", modulus, Real::wp2_E),
                ("thickness", r.thickness, Real::wp2_thickness),
                ("width", r.width, Real::wp2_width),
                ("density", r.density, Real::wp2_density),
                ("d_r", r.d_r, Real::wp2_d_r),
            ] {
                let range = DESCRIPTION.variable(var.vr()).expect("generated").range;
                if !range.contains(value) {
                    let what = if curve.is_some() && field == "E" { "the steepest chord of stress_strain" } else { field };
                    return Err(fail(format!("{what} = {value} is outside the allowed range {range}")));
                }
            }
            let web = WebProperties {
                modulus,
                thickness: r.thickness,
                width: r.width,
                density: r.density,
                retardation_time: r.d_r,
                curve,
            };
            if !(web.stiffness().is_finite() && web.linear_density().is_finite()) {
                return Err(fail("E*width*thickness or density*width*thickness overflows".into()));
            }
            records.push(Record { name: r.name, web });
        }
        Ok(Library { path: path.to_path_buf(), records })
    }

    pub fn find(&self, name: &str) -> Option<&Record> {
        self.records.iter().find(|r| r.name == name)
    }
}

/// Where a span's records come from: the user's file, then the shipped one.
/// Each file is read once, and only when a record is looked up in it.
pub struct Lookup<'a> {
    user: Option<PathBuf>,
    resources: &'a Resources,
    loaded: Vec<Library>,
}

impl<'a> Lookup<'a> {
    /// `web_library` is the `webLibrary` parameter ("" for none).
    pub fn new(web_library: &str, resources: &'a Resources) -> Self {
        Lookup { user: (!web_library.is_empty()).then(|| PathBuf::from(web_library)), resources, loaded: Vec::new() }
    }

    /// The record `name`, selected by the parameter `selected_by`.
    pub fn find(&mut self, name: &str, selected_by: &str) -> FmiResult<Record> {
        let mut searched = Vec::new();
        if let Some(path) = self.user.clone() {
            let library = self.library(&path).map_err(|e| e.prefixed(&format!("{selected_by} = \"{name}\": webLibrary")))?;
            if let Some(r) = library.find(name) {
                return Ok(r.clone());
            }
            searched.push(path);
        }
        let shipped = self.resources.file(SHIPPED).map_err(|e| {
            let after = if searched.is_empty() { String::new() } else { format!(" (not in {})", searched[0].display()) };
            e.prefixed(&format!("{selected_by} = \"{name}\"{after}"))
        })?;
        let library = self.library(&shipped).map_err(|e| e.prefixed(&format!("{selected_by} = \"{name}\"")))?;
        if let Some(r) = library.find(name) {
            return Ok(r.clone());
        }
        searched.push(shipped);
        let names = self.loaded.iter().flat_map(|l| l.records.iter().map(|r| r.name.as_str()));
        let nearest = nearest(name, names);
        let places: Vec<String> = searched.iter().map(|p| p.display().to_string()).collect();
        Err(FmiError::error(format!(
            "{selected_by} = \"{name}\": no web of that name in {}; nearest: {}",
            places.join(" or "),
            nearest.iter().map(|n| format!("\"{n}\"")).collect::<Vec<_>>().join(", ")
        )))
    }

    fn library(&mut self, path: &Path) -> FmiResult<&Library> {
        if let Some(i) = self.loaded.iter().position(|l| l.path == path) {
            return Ok(&self.loaded[i]);
        }
        self.loaded.push(Library::read(path)?);
        Ok(self.loaded.last().expect("just pushed"))
    }
}

/// Gives each web selected by `wp1.record` / `wp2.record` its record's
/// values; a web without a record keeps its `wpN.*` values. An individual
/// value may stay at its start value (importers write every start value
/// back) or equal the record's; anything else is an error naming both.
pub fn apply(p: &mut Parameters, resources: &Resources) -> FmiResult {
    let mut lookup = Lookup::new(&p.web_library, resources);
    let (wp1, wp2) = (p.incoming_record.clone(), p.span_record.clone());
    let from_records = &mut p.from_records;
    for (k, (prefix, name, web, vars)) in [("wp1", wp1, &mut p.incoming, WP1), ("wp2", wp2, &mut p.span_web, WP2)].into_iter().enumerate() {
        if name.is_empty() {
            web.curve = None;
            continue;
        }
        let record = lookup.find(&name, &format!("{prefix}.record"))?;
        let written = from_records[k].unwrap_or([f64::NAN; 5]);
        for (((var, set), given), earlier) in vars.iter().zip(fields(web)).zip(fields(&record.web)).zip(written) {
            let Some(Start::Real(start)) = DESCRIPTION.variable(var.vr()).map(|v| v.start) else { continue };
            if set != start && set != given && set != earlier {
                return Err(FmiError::error(format!(
                    "{0} = {set} was set, but {prefix}.record = \"{name}\" selects the web, and its record gives {given}: \
                     leave {0} at its start value {start} or set {prefix}.record = \"\"",
                    var.name()
                )));
            }
        }
        from_records[k] = Some(fields(&record.web));
        *web = record.web;
    }
    Ok(())
}

const WP1: [Real; 5] = [Real::wp1_E, Real::wp1_thickness, Real::wp1_width, Real::wp1_density, Real::wp1_d_r];
const WP2: [Real; 5] = [Real::wp2_E, Real::wp2_thickness, Real::wp2_width, Real::wp2_density, Real::wp2_d_r];

/// A web's values in the order of `WP1` and `WP2`.
fn fields(w: &WebProperties) -> [f64; 5] {
    [w.modulus, w.thickness, w.width, w.density, w.retardation_time]
}

/// Up to three names closest to `name` (edit distance, ignoring case).
fn nearest<'n>(name: &str, names: impl Iterator<Item = &'n str>) -> Vec<&'n str> {
    let wanted = name.to_lowercase();
    let mut scored: Vec<(usize, &str)> = names.map(|n| (strsim::levenshtein(&wanted, &n.to_lowercase()), n)).collect();
    scored.sort();
    scored.into_iter().take(3).map(|(_, n)| n).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(text: &str) -> FmiResult<Library> {
        Library::parse(text, Path::new("/lib/my webs.json"))
    }

    const PET: &str = r#"{"name": "PET-12", "description": "film", "E": 4.5e9, "thickness": 12e-6, "width": 1.0, "density": 1390, "d_r": 0.0}"#;

    #[test]
    fn a_record_reads_into_its_web() {
        let lib = parse(&format!(r#"{{"webs": [{PET}]}}"#)).unwrap();
        let r = lib.find("PET-12").unwrap();
        assert_eq!(r.web, WebProperties { modulus: 4.5e9, thickness: 12e-6, width: 1.0, density: 1390.0, retardation_time: 0.0, curve: None });
    }

    #[test]
    fn every_bad_file_says_where() {
        for (text, want) in [
            (format!(r#"{{"webs": [{PET},]}}"#), "line 1 column"),
            (String::from("{\"webs\": [\n  {\"name\": \"x\",\n   \"Ee\": 1}]}"), "unknown field `Ee`"),
            (String::from("{\"webs\": [\n  {\"name\": \"x\",\n   \"Ee\": 1}]}"), "line 3 column"),
            (format!(r#"{{"webs": [{PET}, {PET}]}}"#), "record \"PET-12\": the name is used twice"),
            (format!(r#"{{"webs": [{}]}}"#, PET.replace("12e-6", "-12e-6")), "record \"PET-12\": thickness = -0.000012"),
            (format!(r#"{{"webs": [{}]}}"#, PET.replace("\"E\": 4.5e9", "\"stress_strain\": [[0, 0], [0.01, 1e6], [0.005, 2e6]]")), "stress_strain strain must increase strictly"),
            (format!(r#"{{"webs": [{}]}}"#, PET.replace("\"E\": 4.5e9", "\"stress_strain\": [[0, 0]]")), "at least 2"),
            (format!(r#"{{"webs": [{}]}}"#, PET.replace("\"E\": 4.5e9, ", "")), "neither E nor stress_strain"),
            (format!(r#"{{"webs": [{}]}}"#, PET.replace("\"E\": 4.5e9", "\"E\": 4.5e9, \"stress_strain\": [[0, 0], [1, 1]]")), "both E and stress_strain"),
            (format!(r#"{{"webs": [{}]}}"#, PET.replace("1390", "1e999")), "number out of range"),
        ] {
            let e = parse(&text).err().unwrap_or_else(|| panic!("accepted: {text}"));
            assert!(e.message.contains("/lib/my webs.json"), "{}", e.message);
            assert!(e.message.contains(want), "{text}\n  gave: {}\n  want: {want}", e.message);
        }
    }

    #[test]
    fn unknown_names_suggest_the_nearest() {
        let names = ["PET-12", "PET-23", "BOPP-20", "steel-0.3"];
        assert_eq!(nearest("pet-13", names.into_iter()), vec!["PET-12", "PET-23", "BOPP-20"]);
    }
}
