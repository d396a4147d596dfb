//! The generator behind every FMU's build.rs: reads a model description (the
//! single source of truth for an FMU's interface), checks it, and writes a Rust
//! file into `$OUT_DIR` that the model includes: the GUID, the capability
//! flags, one table row per variable (name, value reference, type, causality,
//! variability, start value, allowed range), the model structure, typed enums
//! of the variables and of the XML's enumeration types, and the
//! unit-conversion tables behind unit enumerations. No value reference or
//! variable name is written anywhere else.
//!
//! A problem in the XML stops the build with a message that names the line.

mod fmi3;
pub use fmi3::{fmi3_files, WEB_PORT_KIND};

use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::path::Path;

/// Tool of the model-level `<VendorAnnotations>` that carries strict bounds
/// the XML `min`/`max` cannot say: `<Ranges>` (the schema allows a Tool one
/// child) holding one `<Range variable=".." greaterThan=".."/>` per variable.
/// An input's entry may also bound its rate: `maxRate` is the largest
/// |derivative| (per second) the FMU accepts or estimates for it.
/// Model-level because importers with a strict schema (rust-fmi) refuse
/// `<Annotations>` inside a `ScalarVariable`.
const RANGE_TOOL: &str = "ConvertingSpan.range";

/// Tool of the model-level `<VendorAnnotations>` that names the model's
/// effects: `<Effects>` holding one `<Effect variable=".."/>` per fixed
/// Boolean parameter that switches a part of the physics on. The generator
/// gives them an `Effect` enum and an `Effects` set, bound without a line of
/// code per effect; webline and the documentation read the same list.
pub const EFFECT_TOOL: &str = "ConvertingSpan.effects";

/// For a build script: checks `source` (a modelDescription.xml, relative to
/// the package) and writes the generated Rust into `$OUT_DIR/generated`.
pub fn generate(source: &str, generated: &str) {
    println!("cargo:rerun-if-changed={source}");
    let xml = std::fs::read_to_string(source).unwrap_or_else(|e| fail(source, &[format!("cannot read {source}: {e}")]));
    let md = parse(&xml).unwrap_or_else(|e| fail(source, &[e]));
    let problems = check(&md);
    if !problems.is_empty() {
        fail(source, &problems);
    }
    let out = Path::new(&std::env::var("OUT_DIR").expect("cargo sets OUT_DIR")).join(generated);
    std::fs::write(&out, emit(&md, source)).expect("cannot write generated model description");
}

/// The checks `generate` makes, for a description written by a program
/// (the Line FMU's): the problems found, none if it is sound.
pub fn check_description(xml: &str) -> Vec<String> {
    match parse(xml) {
        Ok(md) => check(&md),
        Err(e) => vec![e],
    }
}

fn fail(source: &str, problems: &[String]) -> ! {
    eprintln!("\nerror: {source} does not describe a model this crate can build:");
    for p in problems {
        eprintln!("  - {p}");
    }
    eprintln!("Fix {source} (the single source of the interface) and build again.\n");
    std::process::exit(1);
}

// ---------------------------------------------------------------- parsed form

#[derive(Default)]
struct ModelDescription {
    attrs: BTreeMap<String, String>,
    co_simulation: Option<BTreeMap<String, String>>,
    model_exchange: Option<BTreeMap<String, String>>,
    /// Unit name -> [(unit or display unit name, factor from the unit to it)].
    units: Vec<(String, Vec<(String, f64)>)>,
    /// Enumeration type name -> items (name, value).
    enumerations: BTreeMap<String, Vec<(String, i32)>>,
    log_categories: Vec<String>,
    variables: Vec<Variable>,
    /// The `RANGE_TOOL` entries: (line, variable name, attributes).
    strict_ranges: Vec<(usize, String, BTreeMap<String, String>)>,
    /// The `EFFECT_TOOL` entries: (line, variable name), in the XML's order.
    effects: Vec<(usize, String)>,
    outputs: Vec<Unknown>,
    derivatives: Vec<Unknown>,
    initial_unknowns: Vec<Unknown>,
}

#[derive(Default)]
struct Variable {
    line: usize,
    attrs: BTreeMap<String, String>,
    /// "Real", "Integer", "Boolean", "String" or "Enumeration".
    kind: String,
    type_attrs: BTreeMap<String, String>,
    greater_than: Option<f64>,
    less_than: Option<f64>,
    max_rate: Option<f64>,
}

struct Unknown {
    line: usize,
    index: usize,
    dependencies: Option<Vec<usize>>,
}

impl Variable {
    fn name(&self) -> &str {
        self.attrs.get("name").map(String::as_str).unwrap_or("?")
    }
    fn causality(&self) -> &str {
        self.attrs.get("causality").map(String::as_str).unwrap_or("local")
    }
    fn variability(&self) -> &str {
        self.attrs.get("variability").map(String::as_str).unwrap_or("continuous")
    }
    fn vr(&self) -> u32 {
        self.attrs.get("valueReference").and_then(|s| s.parse().ok()).unwrap_or(u32::MAX)
    }
    /// The FMI 2.0 default for a missing `initial` attribute (spec table in 2.2.7).
    fn initial(&self) -> &str {
        if let Some(i) = self.attrs.get("initial") {
            return i;
        }
        match (self.causality(), self.variability()) {
            (_, "constant") | ("parameter", _) => "exact",
            ("calculatedParameter", _) | ("output", _) | ("local", _) => "calculated",
            _ => "none",
        }
    }
    /// `wp1.E` -> `wp1_E`, `der(x)` -> `der_x`: every character a Rust
    /// identifier cannot hold becomes `_`, trailing ones are dropped.
    fn rust_name(&self) -> String {
        let mapped: String = self.name().chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' { c } else { '_' }).collect();
        mapped.trim_end_matches('_').to_string()
    }
}

fn attributes(e: &BytesStart, reader: &Reader<&[u8]>, xml: &str) -> Result<BTreeMap<String, String>, String> {
    let mut map = BTreeMap::new();
    for a in e.attributes() {
        let a = a.map_err(|err| format!("line {}: bad attribute: {err}", line_of(reader, xml)))?;
        let key = String::from_utf8_lossy(a.key.as_ref()).into_owned();
        let value = a
            .unescape_value()
            .map_err(|err| format!("line {}: bad attribute value: {err}", line_of(reader, xml)))?
            .into_owned();
        map.insert(key, value);
    }
    Ok(map)
}

/// The line the reader has reached in `xml` (`get_ref` is only the unread rest).
fn line_of(reader: &Reader<&[u8]>, xml: &str) -> usize {
    let pos = (reader.buffer_position() as usize).min(xml.len());
    1 + xml.as_bytes()[..pos].iter().filter(|&&b| b == b'\n').count()
}

fn number(s: &str, what: &str, line: usize) -> Result<f64, String> {
    s.trim().parse::<f64>().map_err(|_| format!("line {line}: {what} \"{s}\" is not a number"))
}

fn parse(xml: &str) -> Result<ModelDescription, String> {
    let mut reader = Reader::from_str(xml);
    reader.config_mut().trim_text(true);
    let mut md = ModelDescription::default();
    let mut path: Vec<String> = Vec::new();
    let mut current_unit: Option<(String, Vec<(String, f64)>)> = None;
    let mut current_type: Option<String> = None;
    let mut current_var: Option<Variable> = None;
    let mut tool: Option<String> = None;

    loop {
        let event = reader
            .read_event()
            .map_err(|e| format!("line {}: XML error: {e}", line_of(&reader, xml)))?;
        let (e, empty) = match &event {
            Event::Start(e) => (e.clone(), false),
            Event::Empty(e) => (e.clone(), true),
            Event::End(e) => {
                let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
                match name.as_str() {
                    "Unit" => md.units.extend(current_unit.take()),
                    "SimpleType" => current_type = None,
                    "ScalarVariable" => md.variables.extend(current_var.take()),
                    "Tool" => tool = None,
                    _ => {}
                }
                path.pop();
                continue;
            }
            Event::Eof => break,
            _ => continue,
        };
        let name = String::from_utf8_lossy(e.name().as_ref()).into_owned();
        let attrs = attributes(&e, &reader, xml)?;
        let line = line_of(&reader, xml);
        let parent = path.last().map(String::as_str).unwrap_or("");
        match (parent, name.as_str()) {
            ("", "fmiModelDescription") => md.attrs = attrs,
            ("fmiModelDescription", "CoSimulation") => md.co_simulation = Some(attrs),
            ("fmiModelDescription", "ModelExchange") => md.model_exchange = Some(attrs),
            ("UnitDefinitions", "Unit") => {
                let unit = attrs.get("name").cloned().unwrap_or_default();
                let entry = (unit.clone(), vec![(unit, 1.0)]);
                if empty {
                    md.units.push(entry);
                } else {
                    current_unit = Some(entry);
                }
            }
            ("Unit", "DisplayUnit") => {
                let factor = number(attrs.get("factor").map(String::as_str).unwrap_or("1"), "factor", line)?;
                if attrs.get("offset").map(|o| o.parse::<f64>() != Ok(0.0)).unwrap_or(false) {
                    return Err(format!("line {line}: display units with an offset are not supported"));
                }
                if let Some(u) = current_unit.as_mut() {
                    u.1.push((attrs.get("name").cloned().unwrap_or_default(), factor));
                }
            }
            ("TypeDefinitions", "SimpleType") => current_type = attrs.get("name").cloned(),
            ("SimpleType", "Enumeration") => {
                if let Some(t) = &current_type {
                    md.enumerations.insert(t.clone(), Vec::new());
                }
            }
            ("Enumeration", "Item") => {
                let t = current_type.clone().unwrap_or_default();
                let value = attrs
                    .get("value")
                    .and_then(|v| v.parse::<i32>().ok())
                    .ok_or(format!("line {line}: enumeration item needs an integer value"))?;
                md.enumerations
                    .entry(t)
                    .or_default()
                    .push((attrs.get("name").cloned().unwrap_or_default(), value));
            }
            ("LogCategories", "Category") => {
                md.log_categories.push(attrs.get("name").cloned().unwrap_or_default())
            }
            ("ModelVariables", "ScalarVariable") => {
                let v = Variable { line, attrs, ..Default::default() };
                if empty {
                    md.variables.push(v);
                } else {
                    current_var = Some(v);
                }
            }
            ("ScalarVariable", kind @ ("Real" | "Integer" | "Boolean" | "String" | "Enumeration")) => {
                if let Some(v) = current_var.as_mut() {
                    v.kind = kind.to_string();
                    v.type_attrs = attrs;
                }
            }
            ("VendorAnnotations" | "Annotations", "Tool") => tool = attrs.get("name").cloned(),
            ("Tool" | "Ranges", "Range") if tool.as_deref() == Some(RANGE_TOOL) => {
                if current_var.is_some() || parent == "Tool" {
                    return Err(format!(
                        "line {line}: put {RANGE_TOOL} ranges in <VendorAnnotations><Tool name=\"{RANGE_TOOL}\"><Ranges> \
                         as <Range variable=\"...\" .../> (strict importers refuse annotations inside a ScalarVariable)"
                    ));
                }
                let name = attrs.get("variable").cloned().ok_or(format!("line {line}: a {RANGE_TOOL} Range needs variable=\"...\""))?;
                md.strict_ranges.push((line, name, attrs));
            }
            ("Effects", "Effect") if tool.as_deref() == Some(EFFECT_TOOL) => {
                let name = attrs.get("variable").cloned().ok_or(format!("line {line}: an {EFFECT_TOOL} Effect needs variable=\"...\""))?;
                md.effects.push((line, name));
            }
            ("Outputs" | "Derivatives" | "InitialUnknowns", "Unknown") => {
                let index = attrs
                    .get("index")
                    .and_then(|i| i.parse().ok())
                    .ok_or(format!("line {line}: Unknown needs an index"))?;
                let dependencies = match attrs.get("dependencies") {
                    None => None,
                    Some(list) => Some(
                        list.split_whitespace()
                            .map(|d| d.parse().map_err(|_| format!("line {line}: bad dependency \"{d}\"")))
                            .collect::<Result<Vec<usize>, String>>()?,
                    ),
                };
                let u = Unknown { line, index, dependencies };
                match parent {
                    "Outputs" => md.outputs.push(u),
                    "Derivatives" => md.derivatives.push(u),
                    _ => md.initial_unknowns.push(u),
                }
            }
            _ => {}
        }
        if !empty {
            path.push(name);
        }
    }
    apply_strict_ranges(&mut md)?;
    Ok(md)
}

/// Moves each model-level strict range onto its variable.
fn apply_strict_ranges(md: &mut ModelDescription) -> Result<(), String> {
    for (line, name, attrs) in std::mem::take(&mut md.strict_ranges) {
        let v = md
            .variables
            .iter_mut()
            .find(|v| v.name() == name)
            .ok_or(format!("line {line}: {RANGE_TOOL} names \"{name}\", which is not a variable"))?;
        if v.greater_than.is_some() || v.less_than.is_some() || v.max_rate.is_some() {
            return Err(format!("line {line}: {RANGE_TOOL} lists \"{name}\" twice"));
        }
        for (key, value) in attrs.iter().filter(|(key, _)| *key != "variable") {
            let bound = Some(number(value, key, line)?);
            match key.as_str() {
                "greaterThan" => v.greater_than = bound,
                "lessThan" => v.less_than = bound,
                "maxRate" if v.causality() == "input" && bound.is_some_and(|b| b > 0.0) => v.max_rate = bound,
                "maxRate" => return Err(format!("line {line}: maxRate must be > 0, and only an input has one")),
                other => return Err(format!("line {line}: unknown range bound \"{other}\" (use greaterThan, lessThan or maxRate)")),
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------- checks

const RUST_KEYWORDS: &[&str] = &[
    "as", "break", "const", "continue", "crate", "else", "enum", "extern", "false", "fn", "for",
    "if", "impl", "in", "let", "loop", "match", "mod", "move", "mut", "pub", "ref", "return",
    "self", "Self", "static", "struct", "super", "trait", "true", "type", "unsafe", "use", "where",
    "while", "async", "await", "dyn",
];

/// An effect is a fixed Boolean parameter, listed once.
fn check_effects(md: &ModelDescription) -> Vec<String> {
    let mut problems = Vec::new();
    for (k, (line, name)) in md.effects.iter().enumerate() {
        match md.variables.iter().find(|v| v.name() == name) {
            None => problems.push(format!("line {line}: {EFFECT_TOOL} names \"{name}\", which is not a variable")),
            Some(v) if v.kind != "Boolean" || v.causality() != "parameter" || v.variability() != "fixed" => {
                problems.push(format!("line {line}: the effect \"{name}\" must be a fixed Boolean parameter"))
            }
            Some(_) if md.effects[..k].iter().any(|(_, n)| n == name) => {
                problems.push(format!("line {line}: {EFFECT_TOOL} lists \"{name}\" twice"))
            }
            Some(_) => {}
        }
    }
    problems
}

fn check(md: &ModelDescription) -> Vec<String> {
    let mut problems = check_effects(md);
    let attr = |k: &str| md.attrs.get(k).map(String::as_str).unwrap_or("");
    if attr("fmiVersion") != "2.0" {
        problems.push(format!("fmiVersion must be \"2.0\", found \"{}\"", attr("fmiVersion")));
    }
    if attr("guid").is_empty() {
        problems.push("the model has no guid".into());
    }
    match &md.co_simulation {
        None => problems.push("there is no <CoSimulation> element".into()),
        Some(cs) => {
            let id = cs.get("modelIdentifier").map(String::as_str).unwrap_or("");
            if id.is_empty() || !id.chars().all(|c| c.is_ascii_alphanumeric() || c == '_') {
                problems.push(format!("modelIdentifier \"{id}\" must be a C identifier"));
            }
        }
    }

    let unit_names: BTreeSet<&str> = md.units.iter().map(|(u, _)| u.as_str()).collect();
    let mut names = BTreeSet::new();
    let mut rust_names = BTreeSet::new();
    let mut vrs = BTreeSet::new();
    for v in &md.variables {
        let at = format!("line {}: variable \"{}\"", v.line, v.name());
        if !names.insert(v.name()) {
            problems.push(format!("{at}: the name is used twice"));
        }
        let rust = v.rust_name();
        let ident_ok = rust.chars().next().is_some_and(|c| c.is_ascii_alphabetic() || c == '_')
            && rust.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
            && !RUST_KEYWORDS.contains(&rust.as_str());
        if !ident_ok {
            problems.push(format!("{at}: \"{rust}\" is not usable as a Rust identifier"));
        }
        if !rust_names.insert(rust.clone()) {
            problems.push(format!("{at}: \"{rust}\" collides with another variable's Rust name"));
        }
        if v.vr() == u32::MAX || v.vr() > 65_535 {
            problems.push(format!("{at}: valueReference must be an integer below 65536"));
        } else if !vrs.insert(v.vr()) {
            problems.push(format!("{at}: valueReference {} is used twice", v.vr()));
        }
        if v.attrs.get("description").map_or(true, |d| d.trim().is_empty()) {
            problems.push(format!("{at}: every variable needs a description"));
        }
        if v.kind.is_empty() {
            problems.push(format!("{at}: no type element (Real, Integer, Boolean, String, Enumeration)"));
        }
        let needs_start = matches!(v.causality(), "parameter" | "input")
            || matches!(v.initial(), "exact" | "approx");
        let has_start = v.type_attrs.contains_key("start");
        if needs_start && !has_start {
            problems.push(format!("{at}: needs a start value"));
        }
        if v.initial() == "calculated" && has_start {
            problems.push(format!("{at}: initial=\"calculated\" must not have a start value"));
        }
        if let Some(unit) = v.type_attrs.get("unit") {
            if !unit_names.contains(unit.as_str()) {
                problems.push(format!("{at}: unit \"{unit}\" is not in UnitDefinitions"));
            }
        }
        if (v.greater_than.is_some() || v.less_than.is_some()) && v.kind != "Real" {
            problems.push(format!("{at}: a {RANGE_TOOL} range is only supported on Real variables"));
        }
        if v.kind == "Enumeration" {
            match v.type_attrs.get("declaredType").and_then(|t| md.enumerations.get(t)) {
                None => problems.push(format!("{at}: Enumeration needs a declaredType from TypeDefinitions")),
                Some(items) => {
                    let start = v.type_attrs.get("start").and_then(|s| s.parse::<i32>().ok());
                    if has_start && !items.iter().any(|(_, value)| Some(*value) == start) {
                        problems.push(format!("{at}: start is not one of the enumeration's values"));
                    }
                }
            }
        }
        for key in ["start", "min", "max"] {
            if let Some(s) = v.type_attrs.get(key) {
                let ok = match v.kind.as_str() {
                    "Real" => s.parse::<f64>().is_ok_and(f64::is_finite),
                    "Integer" | "Enumeration" => s.parse::<i32>().is_ok(),
                    "Boolean" => matches!(s.as_str(), "true" | "false" | "1" | "0"),
                    _ => true,
                };
                if !ok {
                    problems.push(format!("{at}: {key}=\"{s}\" is not a valid {}", v.kind));
                }
            }
        }
    }

    // ModelStructure: Outputs list every output, in order; Derivatives every
    // variable with a `derivative` attribute; InitialUnknowns every output,
    // state and derivative with initial approx/calculated; dependencies name
    // only knowns (inputs and states; for InitialUnknowns also exact parameters).
    let index_of = |u: &Unknown| md.variables.get(u.index.wrapping_sub(1));
    let derivative_indices: Vec<usize> = (1..=md.variables.len())
        .filter(|&i| md.variables[i - 1].type_attrs.contains_key("derivative"))
        .collect();
    let state_indices: BTreeSet<usize> = derivative_indices
        .iter()
        .filter_map(|&i| md.variables[i - 1].type_attrs["derivative"].parse().ok())
        .collect();
    for &s in &state_indices {
        if md.variables.get(s.wrapping_sub(1)).is_none_or(|v| v.kind != "Real") {
            problems.push(format!("derivative=\"{s}\" does not name a Real variable"));
        }
    }
    let listed_derivatives: Vec<usize> = md.derivatives.iter().map(|u| u.index).collect();
    if listed_derivatives != derivative_indices {
        problems.push(format!(
            "ModelStructure/Derivatives must list the derivatives {derivative_indices:?} in index order, found {listed_derivatives:?}"
        ));
    }
    if md.model_exchange.is_some() {
        let declared: usize = md.attrs.get("numberOfEventIndicators").and_then(|n| n.parse().ok()).unwrap_or(0);
        if state_indices.is_empty() && declared == 0 {
            problems.push("a <ModelExchange> model needs continuous states or event indicators".into());
        }
    }
    let outputs: Vec<usize> = (1..=md.variables.len())
        .filter(|&i| md.variables[i - 1].causality() == "output")
        .collect();
    let listed: Vec<usize> = md.outputs.iter().map(|u| u.index).collect();
    if listed != outputs {
        problems.push(format!(
            "ModelStructure/Outputs must list the outputs {outputs:?} in index order, found {listed:?}"
        ));
    }
    let initial_expected: Vec<usize> = outputs
        .iter()
        .chain(&derivative_indices)
        .chain(&state_indices)
        .copied()
        .filter(|&i| matches!(md.variables[i - 1].initial(), "approx" | "calculated"))
        .chain(
            (1..=md.variables.len())
                .filter(|&i| md.variables[i - 1].causality() == "calculatedParameter"),
        )
        .collect::<BTreeSet<_>>()
        .into_iter()
        .collect();
    let initial_listed: Vec<usize> = md.initial_unknowns.iter().map(|u| u.index).collect();
    if initial_listed != initial_expected {
        problems.push(format!(
            "ModelStructure/InitialUnknowns must list {initial_expected:?} in index order, found {initial_listed:?}"
        ));
    }
    let is_state = |v: &Variable| state_indices.iter().any(|&s| std::ptr::eq(&md.variables[s - 1], v));
    for (unknowns, known_ok) in [
        (&md.outputs, &(|v: &Variable| v.causality() == "input" || is_state(v)) as &dyn Fn(&Variable) -> bool),
        (&md.derivatives, &|v: &Variable| v.causality() == "input" || is_state(v)),
        (&md.initial_unknowns, &|v: &Variable| {
            v.causality() == "input" || (v.causality() == "parameter" && v.initial() == "exact")
        }),
    ] {
        for u in unknowns {
            if index_of(u).is_none() {
                problems.push(format!("line {}: index {} is not a variable", u.line, u.index));
            }
            let deps = u.dependencies.as_deref().unwrap_or(&[]);
            if !deps.windows(2).all(|w| w[0] < w[1]) {
                problems.push(format!("line {}: dependencies must be sorted and unique", u.line));
            }
            for &d in deps {
                match md.variables.get(d.wrapping_sub(1)) {
                    Some(v) if known_ok(v) => {}
                    Some(v) => problems.push(format!(
                        "line {}: dependency {d} (\"{}\") is not a known this unknown may depend on",
                        u.line,
                        v.name()
                    )),
                    None => problems.push(format!("line {}: dependency {d} is not a variable", u.line)),
                }
            }
        }
    }
    problems
}

// ---------------------------------------------------------------- generation

fn rust_f64(x: f64) -> String {
    if x == f64::INFINITY {
        "f64::INFINITY".into()
    } else if x == f64::NEG_INFINITY {
        "f64::NEG_INFINITY".into()
    } else {
        format!("{x:?}")
    }
}

fn screaming(name: &str) -> String {
    let mut out = String::new();
    for (i, c) in name.chars().enumerate() {
        if c.is_ascii_uppercase() && i > 0 {
            out.push('_');
        }
        out.push(c.to_ascii_uppercase());
    }
    out
}

fn emit(md: &ModelDescription, source: &str) -> String {
    let cs = md.co_simulation.as_ref().expect("checked");
    let flag = |k: &str| cs.get(k).map(|v| v == "true").unwrap_or(false);
    let me_flag = |k: &str| md.model_exchange.as_ref().and_then(|me| me.get(k)).is_some_and(|v| v == "true");
    let vr_of_index = |i: usize| md.variables[i - 1].vr();
    let mut s = String::new();
    let w = &mut s;
    writeln!(w, "// @generated by build.rs from {source}: edit the XML, not this file.").unwrap();
    writeln!(w, "use fmi_core::description::*;\nuse std::borrow::Cow;\n").unwrap();

    // Variables table.
    writeln!(w, "pub static VARIABLES: [Variable; {}] = [", md.variables.len()).unwrap();
    for v in &md.variables {
        let causality = match v.causality() {
            "parameter" => "Parameter",
            "calculatedParameter" => "CalculatedParameter",
            "input" => "Input",
            "output" => "Output",
            "independent" => "Independent",
            _ => "Local",
        };
        let variability = match v.variability() {
            "constant" => "Constant",
            "fixed" => "Fixed",
            "tunable" => "Tunable",
            "discrete" => "Discrete",
            _ => "Continuous",
        };
        let initial = match v.initial() {
            "exact" => "Exact",
            "approx" => "Approx",
            "calculated" => "Calculated",
            _ => "None",
        };
        let start = v.type_attrs.get("start");
        let (kind, start) = match v.kind.as_str() {
            "Real" => ("Kind::Real".to_string(), start.map(|s| format!("Start::Real({})", rust_f64(s.parse().unwrap())))),
            "Integer" => ("Kind::Integer".to_string(), start.map(|s| format!("Start::Integer({s})"))),
            "Boolean" => ("Kind::Boolean".to_string(), start.map(|s| format!("Start::Boolean({})", s == "true" || s == "1"))),
            "Enumeration" => {
                let ty = &v.type_attrs["declaredType"];
                let values: Vec<String> = md.enumerations[ty].iter().map(|(_, x)| x.to_string()).collect();
                (
                    format!("Kind::Enumeration {{ type_name: {ty:?}, values: &[{}] }}", values.join(", ")),
                    start.map(|s| format!("Start::Integer({s})")),
                )
            }
            _ => ("Kind::String".to_string(), start.map(|s| format!("Start::String({s:?})"))),
        };
        // Both bounds hold: the XML's inclusive one and the annotation's strict one;
        // the tighter decides (a strict bound at the same value wins).
        let xml = |k: &str| v.type_attrs.get(k).and_then(|x| x.parse::<f64>().ok());
        let (min, min_inclusive) = match (xml("min"), v.greater_than) {
            (Some(m), Some(g)) if m > g => (m, true),
            (_, Some(g)) => (g, false),
            (Some(m), None) => (m, true),
            (None, None) => (f64::NEG_INFINITY, true),
        };
        let (max, max_inclusive) = match (xml("max"), v.less_than) {
            (Some(m), Some(l)) if m < l => (m, true),
            (_, Some(l)) => (l, false),
            (Some(m), None) => (m, true),
            (None, None) => (f64::INFINITY, true),
        };
        // The same bounds, inclusive: a strict bound moves by one ulp.
        let lo = rust_f64(if min_inclusive { min } else { min.next_up() });
        let hi = rust_f64(if max_inclusive { max } else { max.next_down() });
        let (min, max) = (rust_f64(min), rust_f64(max));
        writeln!(
            w,
            "    Variable {{ name: Cow::Borrowed({:?}), vr: {}, description: Cow::Borrowed({:?}), kind: {kind}, causality: Causality::{causality}, \
             variability: Variability::{variability}, initial: Initial::{initial}, start: {}, \
             range: Range {{ min: {min}, min_inclusive: {min_inclusive}, max: {max}, max_inclusive: {max_inclusive}, lo: {lo}, hi: {hi} }}, \
             unit: {:?}, max_rate: {}, family: Family::of({kind}), \
             settable_in: settable_in(Causality::{causality}, Variability::{variability}, Initial::{initial}) }},",
            v.name(),
            v.vr(),
            v.attrs.get("description").cloned().unwrap_or_default(),
            start.unwrap_or_else(|| "Start::None".into()),
            v.type_attrs.get("unit").cloned().unwrap_or_default(),
            rust_f64(v.max_rate.unwrap_or(f64::INFINITY)),
        )
        .unwrap();
    }
    writeln!(w, "];\n").unwrap();

    // vr -> its slot (what a get or set checks, and its row of VARIABLES).
    let max_vr = md.variables.iter().map(Variable::vr).max().unwrap_or(0) as usize;
    let mut by_vr = vec!["Slot::NONE".to_string(); max_vr + 1];
    for (i, v) in md.variables.iter().enumerate() {
        by_vr[v.vr() as usize] = format!("Slot::of({i}, &VARIABLES[{i}])");
    }
    writeln!(w, "static BY_VR: [Slot; {}] = [{}];\n", max_vr + 1, by_vr.join(", ")).unwrap();

    let dependencies = |list: &[Unknown]| -> String {
        let rows: Vec<String> = list
            .iter()
            .map(|u| {
                let on = match &u.dependencies {
                    None => "None".to_string(),
                    Some(d) => format!("Some(Cow::Borrowed(&[{}]))", d.iter().map(|&i| vr_of_index(i).to_string()).collect::<Vec<_>>().join(", ")),
                };
                format!("Dependency {{ vr: {}, on: {on} }}", vr_of_index(u.index))
            })
            .collect();
        format!("Cow::Borrowed(&[{}])", rows.join(", "))
    };
    let categories: Vec<String> = md.log_categories.iter().map(|c| format!("{c:?}")).collect();
    writeln!(
        w,
        "pub static DESCRIPTION: ModelDescription = ModelDescription {{\n    model_name: Cow::Borrowed({:?}),\n    model_identifier: {:?},\n    guid: Cow::Borrowed({:?}),\n    \
         log_categories: &[{}],\n    variables: Cow::Borrowed(&VARIABLES),\n    by_vr: Cow::Borrowed(&BY_VR),\n    output_dependencies: {},\n    initial_dependencies: {},\n    \
         can_handle_variable_communication_step_size: {},\n    can_interpolate_inputs: {},\n    can_get_and_set_fmu_state: {},\n    can_serialize_fmu_state: {},\n    \
         provides_directional_derivative: [{}, {}],\n    model_exchange: {},\n    states: Cow::Borrowed(&[{}]),\n    derivatives: {},\n    number_of_event_indicators: {},\n}};\n",
        md.attrs.get("modelName").cloned().unwrap_or_default(),
        cs["modelIdentifier"],
        md.attrs["guid"],
        categories.join(", "),
        dependencies(&md.outputs),
        dependencies(&md.initial_unknowns),
        flag("canHandleVariableCommunicationStepSize"),
        flag("canInterpolateInputs"),
        flag("canGetAndSetFMUstate"),
        flag("canSerializeFMUstate"),
        flag("providesDirectionalDerivative"),
        me_flag("providesDirectionalDerivative"),
        md.model_exchange.is_some(),
        md.derivatives
            .iter()
            .map(|u| md.variables[u.index - 1].type_attrs["derivative"].parse::<usize>().map_or(0, vr_of_index).to_string())
            .collect::<Vec<_>>()
            .join(", "),
        dependencies(&md.derivatives),
        md.attrs.get("numberOfEventIndicators").and_then(|n| n.parse::<usize>().ok()).unwrap_or(0),
    )
    .unwrap();

    // One typed enum per FMI type family; the discriminant is the value reference.
    // FMI's String family is `Text` here, so that it does not shadow Rust's String.
    for (family, kinds) in
        [("Real", &["Real"][..]), ("Integer", &["Integer", "Enumeration"][..]), ("Boolean", &["Boolean"][..]), ("Text", &["String"][..])]
    {
        let vars: Vec<&Variable> = md.variables.iter().filter(|v| kinds.contains(&v.kind.as_str())).collect();
        writeln!(w, "/// The {family} variables of the model description; the discriminant is the value reference.").unwrap();
        writeln!(w, "#[allow(non_camel_case_types)]\n#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]\npub enum {family} {{").unwrap();
        for v in &vars {
            writeln!(w, "    /// {}", v.attrs.get("description").cloned().unwrap_or_default()).unwrap();
            writeln!(w, "    {} = {},", v.rust_name(), v.vr()).unwrap();
        }
        writeln!(w, "}}\n\nimpl {family} {{").unwrap();
        writeln!(w, "    pub const ALL: [{family}; {}] = [{}];", vars.len(),
            vars.iter().map(|v| format!("{family}::{}", v.rust_name())).collect::<Vec<_>>().join(", ")).unwrap();
        // A table indexed by value reference: one bounds check and one load.
        let slots = vars.iter().map(|v| v.vr() as usize + 1).max().unwrap_or(0);
        let mut table = vec!["None".to_string(); slots];
        for v in &vars {
            table[v.vr() as usize] = format!("Some({family}::{})", v.rust_name());
        }
        writeln!(w, "    const BY_VR: [Option<{family}>; {slots}] = [{}];", table.join(", ")).unwrap();
        writeln!(w, "    #[inline(always)]\n    pub fn from_vr(vr: u32) -> Option<Self> {{\n        match Self::BY_VR.get(vr as usize) {{ Some(&v) => v, None => None }}\n    }}").unwrap();
        if vars.is_empty() {
            // A family without variables is an empty enum, which has no discriminant to cast.
            writeln!(w, "    pub const fn vr(self) -> u32 {{ match self {{}} }}").unwrap();
        } else {
            writeln!(w, "    pub const fn vr(self) -> u32 {{ self as u32 }}").unwrap();
        }
        if vars.is_empty() {
            writeln!(w, "    pub fn name(self) -> &'static str {{ match self {{}} }}").unwrap();
        } else {
            let arms: Vec<String> = vars.iter().map(|v| format!("{family}::{} => {:?}", v.rust_name(), v.name())).collect();
            writeln!(w, "    pub fn name(self) -> &'static str {{\n        match self {{ {} }}\n    }}", arms.join(", ")).unwrap();
        }
        writeln!(w, "}}\n").unwrap();
    }

    effects(w, md);

    // Unit enumerations: every item names a unit or display unit.
    for (ty, items) in &md.enumerations {
        let resolved: Option<Vec<String>> = items
            .iter()
            .map(|(item, value)| {
                md.units.iter().find_map(|(unit, displays)| {
                    displays.iter().find(|(d, _)| d == item).map(|(_, factor)| {
                        format!("UnitChoice {{ value: {value}, name: {item:?}, base_unit: {unit:?}, factor: {} }}", rust_f64(*factor))
                    })
                })
            })
            .collect();
        if let Some(rows) = resolved {
            writeln!(w, "/// Conversions from SI for the enumeration type {ty}, from its unit definitions.").unwrap();
            writeln!(w, "pub static {}: [UnitChoice; {}] = [\n    {},\n];\n", screaming(ty), rows.len(), rows.join(",\n    ")).unwrap();
        } else if items.iter().all(|(item, _)| is_identifier(item)) {
            typed_enumeration(w, ty, items);
        }
    }
    s
}

/// `includeDamping` -> `include_damping`.
fn snake(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_uppercase() {
            out.push('_');
            out.push(c.to_ascii_lowercase());
        } else {
            out.push(if c.is_ascii_alphanumeric() { c } else { '_' });
        }
    }
    out
}

/// The effects (`EFFECT_TOOL`): the `Effect` enum, the `Effects` set (one
/// field each, so physics reads `effects.include_damping`), and the Boolean
/// variables split into effects and the other switches, for the bindings.
fn effects(w: &mut String, md: &ModelDescription) {
    let effect_vars: Vec<&Variable> =
        md.effects.iter().filter_map(|(_, n)| md.variables.iter().find(|v| v.name() == n)).collect();
    let switches: Vec<&Variable> =
        md.variables.iter().filter(|v| v.kind == "Boolean" && !md.effects.iter().any(|(_, n)| n == v.name())).collect();
    let names = |vars: &[&Variable], ty: &str| vars.iter().map(|v| format!("{ty}::{}", v.rust_name())).collect::<Vec<_>>().join(", ");
    writeln!(w, "/// The model's effects ({EFFECT_TOOL} in the model description), in its order.").unwrap();
    writeln!(w, "#[allow(non_camel_case_types)]\n#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]\npub enum Effect {{").unwrap();
    for v in &effect_vars {
        writeln!(w, "    /// {}\n    {},", v.attrs.get("description").cloned().unwrap_or_default(), v.rust_name()).unwrap();
    }
    writeln!(w, "}}\n\nimpl Effect {{").unwrap();
    writeln!(w, "    pub const ALL: [Effect; {}] = [{}];", effect_vars.len(), names(&effect_vars, "Effect")).unwrap();
    writeln!(w, "    /// Its Boolean parameter.\n    pub const fn var(self) -> Boolean {{\n        match self {{").unwrap();
    for v in &effect_vars {
        writeln!(w, "            Effect::{0} => Boolean::{0},", v.rust_name()).unwrap();
    }
    writeln!(w, "        }}\n    }}\n    pub fn name(self) -> &'static str {{ self.var().name() }}\n}}\n").unwrap();
    writeln!(w, "/// Which effects are on: one field per effect.\n#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]\npub struct Effects {{").unwrap();
    for v in &effect_vars {
        writeln!(w, "    pub {}: bool,", snake(v.name())).unwrap();
    }
    writeln!(w, "}}\n\nimpl Effects {{").unwrap();
    writeln!(w, "    #[inline]\n    pub fn get(&self, effect: Effect) -> bool {{\n        match effect {{").unwrap();
    for v in &effect_vars {
        writeln!(w, "            Effect::{} => self.{},", v.rust_name(), snake(v.name())).unwrap();
    }
    writeln!(w, "        }}\n    }}\n    #[inline]\n    pub fn get_mut(&mut self, effect: Effect) -> &mut bool {{\n        match effect {{").unwrap();
    for v in &effect_vars {
        writeln!(w, "            Effect::{} => &mut self.{},", v.rust_name(), snake(v.name())).unwrap();
    }
    writeln!(w, "        }}\n    }}").unwrap();
    writeln!(w, "    /// Every combination of the effects, each once: bit k of the index is `Effect::ALL[k]`.").unwrap();
    writeln!(w, "    pub fn every_combination() -> impl Iterator<Item = Effects> {{").unwrap();
    writeln!(w, "        (0..1u32 << Effect::ALL.len()).map(|bits| {{\n            let mut e = Effects::default();").unwrap();
    writeln!(w, "            for (k, effect) in Effect::ALL.into_iter().enumerate() {{ *e.get_mut(effect) = bits & (1 << k) != 0; }}").unwrap();
    writeln!(w, "            e\n        }})\n    }}\n}}\n").unwrap();
    writeln!(w, "/// The Boolean variables that are not effects.").unwrap();
    writeln!(w, "#[allow(non_camel_case_types)]\n#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]\npub enum Switch {{").unwrap();
    for v in &switches {
        writeln!(w, "    {},", v.rust_name()).unwrap();
    }
    writeln!(w, "}}\n\nimpl Switch {{\n    pub const ALL: [Switch; {}] = [{}];\n}}\n", switches.len(), names(&switches, "Switch")).unwrap();
    writeln!(w, "/// A Boolean variable: an effect or another switch.\n#[derive(Clone, Copy, Debug, PartialEq, Eq)]\npub enum BooleanKind {{\n    Effect(Effect),\n    Switch(Switch),\n}}\n").unwrap();
    writeln!(w, "impl Boolean {{\n    #[inline]\n    pub const fn kind(self) -> BooleanKind {{\n        match self {{").unwrap();
    for v in &effect_vars {
        writeln!(w, "            Boolean::{0} => BooleanKind::Effect(Effect::{0}),", v.rust_name()).unwrap();
    }
    for v in &switches {
        writeln!(w, "            Boolean::{0} => BooleanKind::Switch(Switch::{0}),", v.rust_name()).unwrap();
    }
    writeln!(w, "        }}\n    }}\n}}\n").unwrap();
}

fn is_identifier(s: &str) -> bool {
    s.chars().next().is_some_and(|c| c.is_ascii_alphabetic()) && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
}

/// `dopri5` -> `Dopri5`.
fn camel(s: &str) -> String {
    let mut c = s.chars();
    c.next().map(|f| f.to_ascii_uppercase().to_string() + c.as_str()).unwrap_or_default()
}

/// An enumeration type whose items are names (not units): a Rust enum whose
/// discriminants are the item values; the first item is the default.
fn typed_enumeration(w: &mut String, ty: &str, items: &[(String, i32)]) {
    writeln!(w, "/// The enumeration type {ty} of the model description; the discriminant is the item's value.").unwrap();
    writeln!(w, "#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]\npub enum {ty} {{").unwrap();
    for (i, (item, value)) in items.iter().enumerate() {
        writeln!(w, "    {}{} = {value},", if i == 0 { "#[default]\n    " } else { "" }, camel(item)).unwrap();
    }
    writeln!(w, "}}\n\nimpl {ty} {{").unwrap();
    let all: Vec<String> = items.iter().map(|(item, _)| format!("{ty}::{}", camel(item))).collect();
    writeln!(w, "    pub const ALL: [{ty}; {}] = [{}];", items.len(), all.join(", ")).unwrap();
    writeln!(w, "    /// The item's name in the model description.\n    pub fn name(self) -> &'static str {{\n        match self {{").unwrap();
    for (item, _) in items {
        writeln!(w, "            {ty}::{} => {item:?},", camel(item)).unwrap();
    }
    writeln!(w, "        }}\n    }}\n}}\n").unwrap();
    writeln!(w, "impl fmi_core::IntegerValue for {ty} {{").unwrap();
    writeln!(w, "    fn from_i32(x: i32) -> Option<Self> {{\n        match x {{").unwrap();
    for (item, value) in items {
        writeln!(w, "            {value} => Some({ty}::{}),", camel(item)).unwrap();
    }
    writeln!(w, "            _ => None,\n        }}\n    }}\n    fn to_i32(self) -> i32 {{ self as i32 }}\n}}\n").unwrap();
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A minimal model description with `extra` before ModelVariables and `inside` in variable `x`.
    fn md(extra: &str, inside: &str) -> String {
        format!(
            r#"<fmiModelDescription fmiVersion="2.0" modelName="m" guid="{{1}}">{extra}
            <ModelVariables><ScalarVariable name="x" valueReference="1" causality="parameter" description="x">
            <Real start="1"/>{inside}</ScalarVariable></ModelVariables></fmiModelDescription>"#
        )
    }

    fn tool(ranges: &str) -> String {
        format!(r#"<VendorAnnotations><Tool name="{RANGE_TOOL}"><Ranges>{ranges}</Ranges></Tool></VendorAnnotations>"#)
    }

    /// The emitted Range of variable x for a `min` attribute and a strict annotation.
    fn emitted_range(min: &str, greater_than: &str) -> String {
        let xml = md(&tool(&format!(r#"<Range variable="x" greaterThan="{greater_than}"/>"#)), "")
            .replace(r#"<Real start="1"/>"#, &format!(r#"<Real start="1" min="{min}"/>"#))
            .replace("<ModelVariables>", r#"<CoSimulation modelIdentifier="m"/><ModelVariables>"#);
        let out = emit(&parse(&xml).unwrap(), "test");
        let at = out.find("range: Range").unwrap();
        out[at..at + out[at..].find('}').unwrap() + 1].to_string()
    }

    #[test]
    fn the_tighter_of_an_inclusive_min_and_a_strict_bound_decides() {
        // min 1e-6 and > 0 (the Roller's R once): [1e-6, ..., not (0, ...
        let r = emitted_range("1e-6", "0");
        assert!(r.contains("min_inclusive: true") && !r.contains("min: 0.0"), "{r}");
        // min -1 and > -1: the strict bound at the same value wins.
        assert!(emitted_range("-1", "-1").contains("min_inclusive: false"), "{}", emitted_range("-1", "-1"));
        // min -5 and > -1: the strict one is tighter.
        assert!(emitted_range("-5", "-1").contains("min_inclusive: false"), "{}", emitted_range("-5", "-1"));
    }

    #[test]
    fn a_model_level_range_reaches_its_variable() {
        let parsed = parse(&md(&tool(r#"<Range variable="x" greaterThan="0" lessThan="2"/>"#), "")).unwrap();
        assert_eq!((parsed.variables[0].greater_than, parsed.variables[0].less_than), (Some(0.0), Some(2.0)));
    }

    #[test]
    fn an_unknown_variable_a_repeated_one_or_a_range_outside_ranges_is_refused() {
        let unknown = parse(&md(&tool(r#"<Range variable="y" greaterThan="0"/>"#), "")).err().unwrap();
        assert!(unknown.contains("\"y\", which is not a variable"), "{unknown}");
        let twice = parse(&md(&tool(r#"<Range variable="x" greaterThan="0"/><Range variable="x" lessThan="1"/>"#), ""))
            .err()
            .unwrap();
        assert!(twice.contains("lists \"x\" twice"), "{twice}");
        let inside = format!(r#"<Annotations><Tool name="{RANGE_TOOL}"><Range greaterThan="0"/></Tool></Annotations>"#);
        let refused = parse(&md("", &inside)).err().unwrap();
        assert!(refused.contains("put ConvertingSpan.range ranges in"), "{refused}");
        let bare = tool("").replace("<Ranges></Ranges>", r#"<Range variable="x" greaterThan="0"/>"#);
        let refused = parse(&md(&bare, "")).err().unwrap();
        assert!(refused.contains("put ConvertingSpan.range ranges in"), "{refused}");
    }
}
