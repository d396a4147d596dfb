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

mod description;
mod emit;
mod fmi3;
pub use description::EFFECT_TOOL;
pub use fmi3::{fmi3_files, WEB_PORT_KIND};

use description::{check, parse};
use emit::emit;
use std::path::Path;

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

#[cfg(test)]
mod tests {
    use crate::description::{parse, RANGE_TOOL};
    use crate::emit::emit;

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
