//! The FMI 3.0 files of an FMU, written from its FMI 2.0 modelDescription.xml
//! so that names, units, value references, ranges and start values are the
//! same by construction:
//!
//! * `modelDescription.xml` (fmiVersion 3.0): one element per variable in
//!   FMI 3.0's types (Real → Float64, Integer → Int32, Enumeration keeps its
//!   name and travels as Int64), the capability flags under their FMI 3.0
//!   names, the model structure by value reference, the vendor annotations as
//!   `<Annotations>`, and the two kinds of variables FMI 3.0 adds: the
//!   independent `time` (value reference 0) and one Float64 per event
//!   indicator, numbered on from the largest value reference (the FMI 3.0
//!   layer, crate `fmi3`, answers both by the same rule);
//! * `terminalsAndIcons.xml`: a terminal for every web port, i.e. every
//!   prefix `p` with variables `p.v`, `p.F` and `p.eps`.

use quick_xml::events::Event;
use quick_xml::Reader;
use std::fmt::Write as _;

/// The web port of the web-handling library: one terminal kind, the same
/// in every FMU of the project, so that a tool connects ports of that kind.
pub const WEB_PORT_KIND: &str = "org.convertingspan.WebPort";
/// Its members: (member name, what it is).
const WEB_PORT_MEMBERS: [(&str, &str); 3] = [("v", "web speed"), ("F", "web tension"), ("eps", "web strain")];

/// An element of the FMI 2.0 file, its attributes in document order.
#[derive(Clone, Debug, Default)]
struct Node {
    name: String,
    attrs: Vec<(String, String)>,
    children: Vec<Node>,
}

impl Node {
    fn new(name: &str) -> Self {
        Node { name: name.into(), ..Node::default() }
    }
    fn get(&self, key: &str) -> Option<&str> {
        self.attrs.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
    }
    fn child(&self, name: &str) -> Option<&Node> {
        self.children.iter().find(|c| c.name == name)
    }
    fn attr(mut self, key: &str, value: impl Into<String>) -> Self {
        self.attrs.push((key.into(), value.into()));
        self
    }
    fn push(&mut self, child: Node) {
        self.children.push(child);
    }
}

fn parse_tree(xml: &str) -> Result<Node, String> {
    let mut reader = Reader::from_str(xml);
    reader.config_mut().trim_text(true);
    let mut stack = vec![Node::new("#document")];
    loop {
        let event = reader.read_event().map_err(|e| format!("XML error: {e}"))?;
        let start = |e: &quick_xml::events::BytesStart| -> Result<Node, String> {
            let mut node = Node::new(&String::from_utf8_lossy(e.name().as_ref()));
            for a in e.attributes() {
                let a = a.map_err(|err| format!("bad attribute: {err}"))?;
                let value = a.unescape_value().map_err(|err| format!("bad attribute value: {err}"))?;
                node.attrs.push((String::from_utf8_lossy(a.key.as_ref()).into_owned(), value.into_owned()));
            }
            Ok(node)
        };
        match event {
            Event::Start(e) => stack.push(start(&e)?),
            Event::Empty(e) => {
                let node = start(&e)?;
                stack.last_mut().expect("document").push(node);
            }
            Event::End(_) => {
                let node = stack.pop().expect("balanced");
                stack.last_mut().ok_or("unbalanced XML")?.push(node);
            }
            Event::Eof => break,
            _ => {}
        }
    }
    stack.pop().and_then(|d| d.children.into_iter().next()).ok_or_else(|| "no root element".into())
}

fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

fn write_node(out: &mut String, node: &Node, depth: usize) {
    let indent = "  ".repeat(depth);
    let _ = write!(out, "{indent}<{}", node.name);
    for (k, v) in &node.attrs {
        let _ = write!(out, " {k}=\"{}\"", escape(v));
    }
    if node.children.is_empty() {
        out.push_str("/>\n");
    } else {
        out.push_str(">\n");
        for c in &node.children {
            write_node(out, c, depth + 1);
        }
        let _ = writeln!(out, "{indent}</{}>", node.name);
    }
}

fn document(root: &Node) -> String {
    let mut out = String::from("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    out.push_str("<!-- Written by fmi-build from the FMU's FMI 2.0 modelDescription.xml: edit that file, not this one. -->\n");
    write_node(&mut out, root, 0);
    out
}

/// The FMI 3.0 `modelDescription.xml` and `terminalsAndIcons.xml` of the
/// FMU whose FMI 2.0 model description is `fmi2_xml`.
pub fn fmi3_files(fmi2_xml: &str) -> Result<(String, String), Vec<String>> {
    let md = crate::description::parse(fmi2_xml).map_err(|e| vec![e])?;
    let problems = crate::description::check(&md);
    if !problems.is_empty() {
        return Err(problems);
    }
    let root = parse_tree(fmi2_xml).map_err(|e| vec![e])?;
    let description = model_description(&root)?;
    let terminals = terminals(&root);
    Ok((document(&description), document(&terminals)))
}

/// FMI 2.0 attribute names that FMI 3.0 spells differently; `None`: dropped
/// (FMI 3.0 has no such attribute).
fn interface_attribute(name: &str) -> Option<&str> {
    match name {
        "canGetAndSetFMUstate" => Some("canGetAndSetFMUState"),
        "canSerializeFMUstate" => Some("canSerializeFMUState"),
        "providesDirectionalDerivative" => Some("providesDirectionalDerivatives"),
        "completedIntegratorStepNotNeeded" | "canNotUseMemoryManagementFunctions" | "canRunAsynchronuously"
        | "canInterpolateInputs" => None,
        other => Some(other),
    }
}

fn model_description(root: &Node) -> Result<Node, Vec<String>> {
    let mut problems = Vec::new();
    let variables: Vec<&Node> = root.child("ModelVariables").map(|m| m.children.iter().collect()).unwrap_or_default();
    // FMI 2.0 refers to variables by index (1-based position), FMI 3.0 by value reference.
    let vr_of_index = |index: &str| -> Result<String, String> {
        let i: usize = index.parse().map_err(|_| format!("index \"{index}\" is not a number"))?;
        variables
            .get(i.wrapping_sub(1))
            .and_then(|v| v.get("valueReference"))
            .map(str::to_string)
            .ok_or_else(|| format!("index {i} names no variable"))
    };
    let vrs_of_indices = |list: &str| -> Result<String, String> {
        list.split_whitespace().map(vr_of_index).collect::<Result<Vec<_>, _>>().map(|v| v.join(" "))
    };
    let vrs: Vec<u32> = variables.iter().filter_map(|v| v.get("valueReference")?.parse().ok()).collect();
    if vrs.contains(&0) {
        problems.push("value reference 0 is taken; FMI 3.0's `time` needs it".to_string());
    }
    let first_event_indicator = vrs.iter().max().map_or(1, |m| m + 1);
    let event_indicators: usize = root.get("numberOfEventIndicators").and_then(|n| n.parse().ok()).unwrap_or(0);

    let mut out = Node::new("fmiModelDescription").attr("fmiVersion", "3.0");
    for (k, v) in &root.attrs {
        match k.as_str() {
            "fmiVersion" | "numberOfEventIndicators" => {}
            "guid" => out.attrs.push(("instantiationToken".into(), v.clone())),
            _ => out.attrs.push((k.clone(), v.clone())),
        }
    }
    for interface in ["ModelExchange", "CoSimulation"] {
        let Some(node) = root.child(interface) else { continue };
        let mut converted = Node::new(interface);
        for (k, v) in &node.attrs {
            if let Some(name) = interface_attribute(k) {
                converted.attrs.push((name.into(), v.clone()));
            }
        }
        if interface == "CoSimulation" {
            // Events (a slack web) are handled inside fmi3DoStep.
            converted = converted.attr("hasEventMode", "false");
        }
        out.push(converted);
    }
    if let Some(units) = root.child("UnitDefinitions") {
        out.push(units.clone());
    }
    if let Some(types) = root.child("TypeDefinitions") {
        let mut converted = Node::new("TypeDefinitions");
        for simple in &types.children {
            match simple.child("Enumeration") {
                Some(enumeration) => {
                    let mut e = Node::new("EnumerationType");
                    e.attrs = simple.attrs.clone();
                    e.children = enumeration.children.clone();
                    converted.push(e);
                }
                None => problems.push(format!("type {:?}: only enumeration types are converted", simple.get("name"))),
            }
        }
        out.push(converted);
    }
    for copied in ["LogCategories", "DefaultExperiment"] {
        if let Some(node) = root.child(copied) {
            out.push(node.clone());
        }
    }
    let mut model_variables = Node::new("ModelVariables");
    model_variables.push(
        Node::new("Float64")
            .attr("name", "time")
            .attr("valueReference", "0")
            .attr("causality", "independent")
            .attr("variability", "continuous")
            .attr("description", "Simulation time"),
    );
    for v in &variables {
        match variable(v, &vr_of_index) {
            Ok(node) => model_variables.push(node),
            Err(e) => problems.push(format!("{}: {e}", v.get("name").unwrap_or("?"))),
        }
    }
    for i in 0..event_indicators {
        model_variables.push(
            Node::new("Float64")
                .attr("name", format!("eventIndicator{}", i + 1))
                .attr("valueReference", (first_event_indicator + i as u32).to_string())
                .attr("causality", "local")
                .attr("variability", "continuous")
                .attr("initial", "calculated")
                .attr("description", format!("Event indicator {} of Model Exchange: an event where it crosses zero", i + 1)),
        );
    }
    out.push(model_variables);

    let mut structure = Node::new("ModelStructure");
    let fmi2_structure = root.child("ModelStructure");
    for (section, element) in [("Outputs", "Output"), ("Derivatives", "ContinuousStateDerivative"), ("InitialUnknowns", "InitialUnknown")] {
        let Some(unknowns) = fmi2_structure.and_then(|s| s.child(section)) else { continue };
        for u in &unknowns.children {
            let converted = (|| -> Result<Node, String> {
                let mut n = Node::new(element).attr("valueReference", vr_of_index(u.get("index").unwrap_or_default())?);
                if let Some(deps) = u.get("dependencies") {
                    n = n.attr("dependencies", vrs_of_indices(deps)?);
                }
                if let Some(kinds) = u.get("dependenciesKind") {
                    n = n.attr("dependenciesKind", kinds);
                }
                Ok(n)
            })();
            match converted {
                Ok(n) => structure.push(n),
                Err(e) => problems.push(format!("ModelStructure/{section}: {e}")),
            }
        }
    }
    for i in 0..event_indicators {
        structure.push(Node::new("EventIndicator").attr("valueReference", (first_event_indicator + i as u32).to_string()));
    }
    out.push(structure);
    // The vendor annotations (the strict ranges) come last in FMI 3.0.
    if let Some(vendor) = root.child("VendorAnnotations") {
        let mut annotations = Node::new("Annotations");
        for tool in &vendor.children {
            let mut a = Node::new("Annotation").attr("type", tool.get("name").unwrap_or_default());
            a.children = tool.children.clone();
            annotations.push(a);
        }
        out.push(annotations);
    }

    if problems.is_empty() {
        Ok(out)
    } else {
        Err(problems)
    }
}

/// One FMI 2.0 `ScalarVariable` as an FMI 3.0 variable element.
fn variable(v: &Node, vr_of_index: &dyn Fn(&str) -> Result<String, String>) -> Result<Node, String> {
    let typed = v.children.iter().find(|c| c.name != "Annotations").ok_or("no type element")?;
    let name = match typed.name.as_str() {
        "Real" => "Float64",
        "Integer" => "Int32",
        "Boolean" | "String" | "Enumeration" => typed.name.as_str(),
        other => return Err(format!("type {other} is not converted")),
    };
    let mut out = Node::new(name);
    out.attrs = v.attrs.clone();
    let mut start = None;
    for (k, value) in &typed.attrs {
        match (name, k.as_str()) {
            // FMI 3.0 gives a String's start value as a child element.
            ("String", "start") => start = Some(value.clone()),
            ("Float64", "derivative") => out.attrs.push((k.clone(), vr_of_index(value)?)),
            _ => out.attrs.push((k.clone(), value.clone())),
        }
    }
    if let Some(value) = start {
        out.push(Node::new("Start").attr("value", value));
    }
    Ok(out)
}

/// A terminal per web port: every prefix with all of the port's members.
fn terminals(root: &Node) -> Node {
    let names: Vec<&str> = root
        .child("ModelVariables")
        .map(|m| m.children.iter().filter_map(|v| v.get("name")).collect())
        .unwrap_or_default();
    let mut ports: Vec<&str> = names
        .iter()
        .filter_map(|n| n.strip_suffix(".v"))
        .filter(|p| WEB_PORT_MEMBERS.iter().all(|(m, _)| names.contains(&format!("{p}.{m}").as_str())))
        .collect();
    ports.dedup();
    let mut list = Node::new("Terminals");
    for port in ports {
        let what: Vec<&str> = WEB_PORT_MEMBERS.iter().map(|(_, w)| *w).collect();
        let mut t = Node::new("Terminal")
            .attr("name", port)
            .attr("matchingRule", "plug")
            .attr("terminalKind", WEB_PORT_KIND)
            .attr("description", format!("Web port {port}: {}", what.join(", ")));
        for (member, _) in WEB_PORT_MEMBERS {
            t.push(
                Node::new("TerminalMemberVariable")
                    .attr("variableName", format!("{port}.{member}"))
                    .attr("memberName", member)
                    .attr("variableKind", "signal"),
            );
        }
        list.push(t);
    }
    let mut out = Node::new("fmiTerminalsAndIcons").attr("fmiVersion", "3.0");
    out.push(list);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const SPAN: &str = include_str!("../../../modelDescription.xml");

    #[test]
    fn the_span_converts_with_the_same_names_and_value_references() {
        let (md, terminals) = fmi3_files(SPAN).expect("converts");
        let fmi2 = parse_tree(SPAN).unwrap();
        let fmi3 = parse_tree(&md).unwrap();
        let pairs = |root: &Node| -> Vec<(String, String)> {
            root.child("ModelVariables").unwrap().children.iter()
                .map(|v| (v.get("name").unwrap().to_string(), v.get("valueReference").unwrap().to_string()))
                .collect()
        };
        let (two, three) = (pairs(&fmi2), pairs(&fmi3));
        assert_eq!(three[0], ("time".to_string(), "0".to_string()));
        assert_eq!(&three[1..=two.len()], &two[..]);
        assert!(terminals.contains("name=\"web_a\"") && terminals.contains("name=\"web_b\""), "{terminals}");
        assert!(terminals.contains(WEB_PORT_KIND));
    }
}
