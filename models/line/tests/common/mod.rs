//! The stand-in for the Line in the testkit's suites: its interface is not
//! compiled in but built by the library from line.json at instantiation, so
//! the description is the one the library builds from the same resources.

use fmi_core::description::ModelDescription;
use fmi_testkit::Tested;
use std::sync::OnceLock;

/// The Line under test: its library, over the test line in resources/.
pub struct TestedLine;

impl Tested for TestedLine {
    fn description() -> &'static ModelDescription {
        static DESCRIPTION: OnceLock<&'static ModelDescription> = OnceLock::new();
        DESCRIPTION.get_or_init(|| fmi_testkit::description_from_resources::<line::Line>(&Self::resources()))
    }

    fn resources() -> String {
        concat!(env!("CARGO_MANIFEST_DIR"), "/resources/").replace('\\', "/")
    }

    fn library() -> &'static str {
        "line"
    }

    fn needs_resources() -> bool {
        true
    }

    fn skipped(test: &str) -> Option<&'static str> {
        let just_above_minus_one = test.ends_with(".eps_start = -0.9999999999999999");
        if test.starts_with("values::parameter_out_of_range_is_refused_at_exit_initialization: ") && just_above_minus_one {
            // The span takes it and refuses only its outputs; the Line evaluates every span when it starts.
            return Some("the Line refuses a start strain 1 ulp above -1 (an unstretched length beyond L*2^52) when it starts");
        }
        if test == "stepping::set_real_input_derivatives_validates_its_arguments: dancer.y_dot a little" {
            return Some("the carriage's speed is near 0 there (-0.023 m/s, on its spring): a relative bound says nothing");
        }
        if test == "stepping::set_real_input_derivatives_validates_its_arguments: idler.grip a little" {
            return Some("the idler's grip is the share of its traction its bearing and inertia need, 0.005 there: the rate moves it by 4e-5, a relative bound on a near-zero share says nothing");
        }
        None
    }
}
