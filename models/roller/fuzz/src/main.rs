//! The Roller's fuzz target: the harness's driver on the Roller, with the
//! resources its FMU ships (see fmi/fuzz), the web's contact followed through
//! its output `traction`, and a scene in which it slides and sticks again.

use fmi_fuzz::{Contact, Fuzzed, Scene, Value};

/// The share of the traction in use at which the web slides: the output is the friction the
/// tensions need over what the wrap can give, which passes 1 where they cross the capstan limit.
const SLIDING: f64 = 1.0 - 1e-6;

fn main() {
    let resources = concat!(env!("CARGO_MANIFEST_DIR"), "/../resources/");
    let roller = Fuzzed {
        contact: Some(Contact { output: "traction", sliding: |share| share.abs() >= SLIDING }),
        // A web slipping over half a turn (mu 0.3): at 5 m/s, with web_a.F about 100 N, its capstan
        // limit holds web_b.F up to about 217 N (the web's 1 kg/m takes 25 N off both tensions), so
        // web_b.F drawn between 150 N and 300 N makes it stick and slide by turns.
        scene: Some(Scene {
            parameters: vec![
                ("includeTraction", Value::Boolean(true)),
                ("traction.mu", Value::Real(0.3)),
                ("traction.wrap", Value::Real(std::f64::consts::PI)),
            ],
            inputs: vec![("web_a.F", 100.0, 80.0, 120.0), ("web_b.F", 150.0, 150.0, 300.0)],
        }),
        ..Fuzzed::of::<roller::Roller>(resources)
    };
    fmi_fuzz::driver::main(&roller);
}
