//! ConvertingSpan: an FMU (FMI 2.0 and 3.0) of a converting web span, the free web
//! between two rollers where the web's properties change from wp1
//! (arriving) to wp2 (in the span).
//!
//! * `parameters` — what the user sets, in SI units;
//! * `records` — webs by name from JSON libraries (serde_json);
//! * `stress_strain` — a nonlinear web's curve (monotone cubic, PCHIP);
//! * `physics` — the equations, numbered as in the model documentation,
//!   every output's equation among them;
//! * `stepping` — one communication step: the choice of method, the
//!   balance written for the integrators;
//! * `sensor` — unit conversion of the sensor outputs;
//! * `jacobian` — the partial derivatives of the outputs and of dx/dt;
//! * `slack` — where inside a step a slack web's tension crosses zero;
//! * `variables` — each variable of modelDescription.xml bound to its field;
//! * `description` — the interface generated from modelDescription.xml;
//! * `web_state` — a web in an FMU state (values and stress–strain table);
//! * `model` — the model's data, one step, and the FMI hooks.
//!
//! The FMI standard is `fmi-core`'s and the C API `fmi-abi`'s, which holds all
//! unsafe code; this crate has none.

#![deny(unsafe_code)]

pub mod description;
mod model;
pub mod parameters;
pub mod jacobian;
pub mod physics;
pub mod records;
pub mod schedule;
pub mod sensor;
mod slack;
pub mod stress_strain;
pub mod stepping;
mod variables;
pub mod web_state;

pub use model::{effective_tolerance, ConvertingSpan};
pub use parameters::Rates;
pub use physics::{Forces, Outputs};

// The FMU's C API (feature `fmu`, on by default); the Line FMU links the
// model as a library without it, so that its own API is the only one.
#[cfg(feature = "fmu")]
fmi_abi::export_fmi2!(crate::ConvertingSpan);
// The FMI 3.0 API from the same library: the FMI 3.0 FMU ships this binary too.
#[cfg(feature = "fmu")]
fmi_abi::export_fmi3!(crate::ConvertingSpan);
