//! A model description read and checked: the parsed form the generator
//! writes from (`emit`) and that `fmi3` turns into FMI 3.0's, and every check
//! a description must pass.

use quick_xml::events::{BytesStart, Event};
use quick_xml::Reader;
use std::collections::{BTreeMap, BTreeSet};

/// Tool of the model-level `<VendorAnnotations>` that carries strict bounds
/// the XML `min`/`max` cannot say: `<Ranges>` (the schema allows a Tool one
/// child) holding one `<Range variable=".." greaterThan=".."/>` per variable.
/// An input's entry may also bound its rate: `maxRate` is the largest
/// |derivative| (per second) the FMU accepts or estimates for it.
/// Model-level because importers with a strict schema (rust-fmi) refuse
/// `<Annotations>` inside a `ScalarVariable`.
pub(crate) const RANGE_TOOL: &str = "ConvertingSpan.range";

/// Tool of the model-level `<VendorAnnotations>` that names the model's
/// effects: `<Effects>` holding one `<Effect variable=".."/>` per fixed
/// Boolean parameter that switches a part of the physics on. The generator
/// gives them an `Effect` enum and an `Effects` set, bound without a line of
/// code per effect; webline and the documentation read the same list.
pub const EFFECT_TOOL: &str = "ConvertingSpan.effects";

#[derive(Default)]
pub(crate) struct ModelDescription {
    pub(crate) attrs: BTreeMap<String, String>,
    pub(crate) co_simulation: Option<BTreeMap<String, String>>,
    pub(crate) model_exchange: Option<BTreeMap<String, String>>,
    /// Unit name -> [(unit or display unit name, factor from the unit to it)].
    pub(crate) units: Vec<(String, Vec<(String, f64)>)>,
    /// Enumeration type name -> items (name, value).
    pub(crate) enumerations: BTreeMap<String, Vec<(String, i32)>>,
    pub(crate) log_categories: Vec<String>,
    pub(crate) variables: Vec<Variable>,
    /// The `RANGE_TOOL` entries: (line, variable name, attributes).
    pub(crate) strict_ranges: Vec<(usize, String, BTreeMap<String, String>)>,
    /// The `EFFECT_TOOL` entries: (line, variable name), in the XML's order.
    pub(crate) effects: Vec<(usize, String)>,
    pub(crate) outputs: Vec<Unknown>,
    pub(crate) derivatives: Vec<Unknown>,
    pub(crate) initial_unknowns: Vec<Unknown>,
}

#[derive(Default)]
pub(crate) struct Variable {
    pub(crate) line: usize,
    pub(crate) attrs: BTreeMap<String, String>,
    /// "Real", "Integer", "Boolean", "String" or "Enumeration".
    pub(crate) kind: String,
    pub(crate) type_attrs: BTreeMap<String, String>,
    pub(crate) greater_than: Option<f64>,
    pub(crate) less_than: Option<f64>,
    pub(crate) max_rate: Option<f64>,
}

pub(crate) struct Unknown {
    pub(crate) line: usize,
    pub(crate) index: usize,
    pub(crate) dependencies: Option<Vec<usize>>,
}

impl Variable {
    pub(crate) fn name(&self) -> &str {
        self.attrs.get("name").map(String::as_str).unwrap_or("?")
    }
    pub(crate) fn causality(&self) -> &str {
        self.attrs.get("causality").map(String::as_str).unwrap_or("local")
    }
    pub(crate) fn variability(&self) -> &str {
        self.attrs.get("variability").map(String::as_str).unwrap_or("continuous")
    }
    pub(crate) fn vr(&self) -> u32 {
        self.attrs.get("valueReference").and_then(|s| s.parse().ok()).unwrap_or(u32::MAX)
    }
    /// The FMI 2.0 default for a missing `initial` attribute (spec table in 2.2.7).
    pub(crate) fn initial(&self) -> &str {
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
    pub(crate) fn rust_name(&self) -> String {
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
pub(crate) fn line_of(reader: &Reader<&[u8]>, xml: &str) -> usize {
    let pos = (reader.buffer_position() as usize).min(xml.len());
    1 + xml.as_bytes()[..pos].iter().filter(|&&b| b == b'\n').count()
}

pub(crate) fn number(s: &str, what: &str, line: usize) -> Result<f64, String> {
    s.trim().parse::<f64>().map_err(|_| format!("line {line}: {what} \"{s}\" is not a number"))
}

pub(crate) fn parse(xml: &str) -> Result<ModelDescription, String> {
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

pub(crate) fn check(md: &ModelDescription) -> Vec<String> {
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
