//! The Line's fuzz target: the harness's driver on the Line with its test line
//! (models/line/resources/README.md; see fmi/fuzz).

use fmi_core::description::ModelDescription;
use fmi_testkit::{description_from_resources, Tested};

const RESOURCES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../resources/");

/// The Line as the harness sees it: its interface is not compiled in but
/// built from line.json at instantiation, so it is read once from the test
/// line the harness instantiates with.
struct FuzzedLine;

impl Tested for FuzzedLine {
    fn description() -> &'static ModelDescription {
        static DESCRIPTION: std::sync::OnceLock<&'static ModelDescription> = std::sync::OnceLock::new();
        DESCRIPTION.get_or_init(|| description_from_resources::<line::Line>(RESOURCES))
    }
    fn resources() -> String {
        RESOURCES.into()
    }
    fn library() -> &'static str {
        "line"
    }
    fn needs_resources() -> bool {
        true
    }
}

fn main() {
    // The idler the web may slip over (wrap 120 degrees, mu 0.3): its share of traction in use,
    // sliding from 1 - 1e-6 on, as the Roller's fuzz target reads it.
    let contact = fmi_fuzz::Contact { output: "idler.traction", sliding: |share| share.abs() >= 1.0 - 1e-6 };
    fmi_fuzz::driver::main(&fmi_fuzz::Fuzzed { contact: Some(contact), ..fmi_fuzz::Fuzzed::of::<FuzzedLine>(RESOURCES) });
}
