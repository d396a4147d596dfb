//! The modelDescription.xml of a line (FMI 2.0), written from the same
//! interface the binary builds at instantiation, so the two cannot differ.
//! Units are the parts' own definitions, taken from their model descriptions.

use crate::spec::Spec;
use crate::line::Line;
use fmi_core::description::{Causality, Initial, Kind, Start, Variability};
use fmi_core::Model;
use quick_xml::escape::escape;
use quick_xml::events::Event;
use quick_xml::Reader;
use std::collections::BTreeMap;
use std::fmt::Write as _;

const PART_DESCRIPTIONS: [&str; 2] = [include_str!("../../../modelDescription.xml"), include_str!("../../roller/modelDescription.xml")];

/// Tool of the range annotation the parts use for strict bounds (fmi-build's RANGE_TOOL).
const RANGE_TOOL: &str = "ConvertingSpan.range";

/// Unit name -> its `<Unit>` element, from the parts' descriptions.
fn unit_definitions() -> BTreeMap<String, String> {
    let mut units = BTreeMap::new();
    for xml in PART_DESCRIPTIONS {
        let mut reader = Reader::from_str(xml);
        loop {
            let start = reader.buffer_position() as usize;
            match reader.read_event() {
                Ok(Event::Start(e)) if e.name().as_ref() == b"Unit" => {
                    let name = unit_name(&e);
                    reader.read_to_end(e.name()).expect("the parts' descriptions are well formed");
                    let end = reader.buffer_position() as usize;
                    units.entry(name).or_insert_with(|| xml[start..end].trim().to_string());
                }
                Ok(Event::Empty(e)) if e.name().as_ref() == b"Unit" => {
                    let end = reader.buffer_position() as usize;
                    units.entry(unit_name(&e)).or_insert_with(|| xml[start..end].trim().to_string());
                }
                Ok(Event::Eof) => break,
                Ok(_) => {}
                Err(e) => panic!("a part's model description does not parse: {e}"),
            }
        }
    }
    units
}

fn unit_name(e: &quick_xml::events::BytesStart) -> String {
    e.attributes()
        .flatten()
        .find(|a| a.key.as_ref() == b"name")
        .map(|a| String::from_utf8_lossy(&a.value).into_owned())
        .unwrap_or_default()
}

fn number(x: f64) -> String {
    if x == f64::INFINITY {
        "INF".into()
    } else if x == f64::NEG_INFINITY {
        "-INF".into()
    } else {
        format!("{x:?}")
    }
}

/// The FMI 2.0 modelDescription.xml of `line` (as instantiated from `spec`).
pub fn model_description(line: &Line, spec: &Spec) -> Result<String, String> {
    let d = line.description();
    let mut w = String::new();
    let attr = |s: &str| escape(s).into_owned();
    writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#).unwrap();
    writeln!(
        w,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="{}" guid="{}" description="{}" generationTool="ConvertingSpan line-description" variableNamingConvention="structured" numberOfEventIndicators="{}">"#,
        attr(&d.model_name),
        attr(&d.guid),
        attr(&format!("A web line as one FMU: {}{}", spec.name, if spec.description.is_empty() { String::new() } else { format!(" ({})", spec.description) })),
        d.number_of_event_indicators
    )
    .unwrap();
    let capabilities = r#"canGetAndSetFMUstate="true" canSerializeFMUstate="true" providesDirectionalDerivative="true""#;
    writeln!(w, r#"  <ModelExchange modelIdentifier="{}" {capabilities}/>"#, d.model_identifier).unwrap();
    writeln!(
        w,
        r#"  <CoSimulation modelIdentifier="{}" canHandleVariableCommunicationStepSize="true" canInterpolateInputs="true" maxOutputDerivativeOrder="0" {capabilities}/>"#,
        d.model_identifier
    )
    .unwrap();
    let units = unit_definitions();
    let used: std::collections::BTreeSet<&str> = d.variables.iter().map(|v| v.unit).filter(|u| !u.is_empty()).collect();
    writeln!(w, "  <UnitDefinitions>").unwrap();
    for u in used {
        match units.get(u) {
            Some(def) => writeln!(w, "    {def}").unwrap(),
            None => writeln!(w, r#"    <Unit name="{}"/>"#, attr(u)).unwrap(),
        }
    }
    writeln!(w, "  </UnitDefinitions>").unwrap();
    writeln!(w, "  <LogCategories>").unwrap();
    for c in d.log_categories {
        writeln!(w, r#"    <Category name="{c}"/>"#).unwrap();
    }
    writeln!(w, "  </LogCategories>").unwrap();
    let e = spec.experiment;
    writeln!(
        w,
        r#"  <DefaultExperiment startTime="{}" stopTime="{}" stepSize="{}" tolerance="{}"/>"#,
        number(e.start_time),
        number(e.stop_time),
        number(e.step),
        number(crate::interface::DEFAULT_TOLERANCE)
    )
    .unwrap();
    // Strict bounds go into the range annotation, as in the parts' descriptions.
    let strict: Vec<String> = d
        .variables
        .iter()
        .filter(|v| v.kind == Kind::Real && ((!v.range.min_inclusive && v.range.min.is_finite()) || (!v.range.max_inclusive && v.range.max.is_finite())))
        .map(|v| {
            let mut s = format!(r#"<Range variable="{}""#, attr(&v.name));
            if !v.range.min_inclusive && v.range.min.is_finite() {
                write!(s, r#" greaterThan="{}""#, number(v.range.min)).unwrap();
            }
            if !v.range.max_inclusive && v.range.max.is_finite() {
                write!(s, r#" lessThan="{}""#, number(v.range.max)).unwrap();
            }
            s + "/>"
        })
        .collect();
    if !strict.is_empty() {
        writeln!(w, r#"  <VendorAnnotations>"#).unwrap();
        writeln!(w, r#"    <Tool name="{RANGE_TOOL}">"#).unwrap();
        writeln!(w, r#"      <Ranges>"#).unwrap();
        for s in strict {
            writeln!(w, "        {s}").unwrap();
        }
        writeln!(w, r#"      </Ranges>"#).unwrap();
        writeln!(w, r#"    </Tool>"#).unwrap();
        writeln!(w, r#"  </VendorAnnotations>"#).unwrap();
    }
    // Index (1-based, in ModelVariables) by value reference.
    let index: BTreeMap<u32, usize> = d.variables.iter().enumerate().map(|(i, v)| (v.vr, i + 1)).collect();
    let state_of_derivative: BTreeMap<u32, u32> = d.derivatives.iter().zip(d.states.iter()).map(|(der, &s)| (der.vr, s)).collect();
    writeln!(w, "  <ModelVariables>").unwrap();
    for v in d.variables.iter() {
        let causality = match v.causality {
            Causality::Parameter => "parameter",
            Causality::CalculatedParameter => "calculatedParameter",
            Causality::Input => "input",
            Causality::Output => "output",
            Causality::Local => "local",
            Causality::Independent => "independent",
        };
        let variability = match v.variability {
            Variability::Constant => "constant",
            Variability::Fixed => "fixed",
            Variability::Tunable => "tunable",
            Variability::Discrete => "discrete",
            Variability::Continuous => "continuous",
        };
        let initial = match v.initial {
            Initial::Exact => r#" initial="exact""#,
            Initial::Approx => r#" initial="approx""#,
            Initial::Calculated => r#" initial="calculated""#,
            Initial::None => "",
        };
        writeln!(
            w,
            r#"    <ScalarVariable name="{}" valueReference="{}" description="{}" causality="{causality}" variability="{variability}"{initial}>"#,
            attr(&v.name),
            v.vr,
            attr(&v.description)
        )
        .unwrap();
        let start = match v.start {
            Start::Real(x) => format!(r#" start="{}""#, number(x)),
            Start::Integer(i) => format!(r#" start="{i}""#),
            Start::Boolean(b) => format!(r#" start="{b}""#),
            Start::String(s) => format!(r#" start="{}""#, attr(s)),
            Start::None => String::new(),
        };
        match v.kind {
            Kind::Real => {
                let mut a = start;
                if v.range.min.is_finite() {
                    write!(a, r#" min="{}""#, number(v.range.min)).unwrap();
                }
                if v.range.max.is_finite() {
                    write!(a, r#" max="{}""#, number(v.range.max)).unwrap();
                }
                if !v.unit.is_empty() {
                    write!(a, r#" unit="{}""#, attr(v.unit)).unwrap();
                }
                if let Some(s) = state_of_derivative.get(&v.vr) {
                    write!(a, r#" derivative="{}""#, index[s]).unwrap();
                }
                writeln!(w, "      <Real{a}/>").unwrap();
            }
            Kind::Integer => writeln!(w, "      <Integer{start}/>").unwrap(),
            Kind::Boolean => writeln!(w, "      <Boolean{start}/>").unwrap(),
            Kind::String => writeln!(w, "      <String{start}/>").unwrap(),
            Kind::Enumeration { type_name, .. } => return Err(format!("{}: enumeration {type_name} is not offered by the Line FMU", v.name)),
        }
        writeln!(w, "    </ScalarVariable>").unwrap();
    }
    writeln!(w, "  </ModelVariables>").unwrap();
    writeln!(w, "  <ModelStructure>").unwrap();
    let list = |w: &mut String, tag: &str, vrs: &mut dyn Iterator<Item = u32>| {
        let mut rows: Vec<usize> = vrs.map(|vr| index[&vr]).collect();
        rows.sort_unstable();
        if rows.is_empty() {
            return;
        }
        writeln!(w, "    <{tag}>").unwrap();
        for i in rows {
            writeln!(w, r#"      <Unknown index="{i}"/>"#).unwrap();
        }
        writeln!(w, "    </{tag}>").unwrap();
    };
    list(&mut w, "Outputs", &mut d.output_dependencies.iter().map(|u| u.vr));
    list(&mut w, "Derivatives", &mut d.derivatives.iter().map(|u| u.vr));
    list(&mut w, "InitialUnknowns", &mut d.initial_dependencies.iter().map(|u| u.vr));
    writeln!(w, "  </ModelStructure>").unwrap();
    writeln!(w, "</fmiModelDescription>").unwrap();
    Ok(w)
}
