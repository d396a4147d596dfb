//! Roller: an FMU (FMI 2.0 and 3.0) of every part of a web line that is not
//! a span — idler, driven roller, source, sink, unwinder, winder, dancer —
//! built like the span, in the same rooms: `fmi-core` and `fmi-abi` do the
//! standard and the C API, this crate only the model.
//!
//! * `parameters` — what the user sets and the inputs, in SI units;
//! * `physics` — the equations [R1]–[R5], [R9] and their exact steps;
//! * `contact` — where the web may slip: its speed over the roller, friction, air film [R6]–[R8];
//! * `control` — the drive's loop and its motor [R10]–[R11];
//! * `drive` — the profile: the drive and the tables of time it follows;
//! * `jacobian` — the partial derivatives of the outputs and state derivatives;
//! * `variables` — each variable of modelDescription.xml bound to its field;
//! * `description` — the interface generated from modelDescription.xml;
//! * `model` — the roller's data, one step, and the FMI hooks.

#![deny(unsafe_code)]

pub mod contact;
pub mod control;
pub mod description;
pub mod drive;
pub mod jacobian;
mod model;
pub mod parameters;
pub mod physics;
mod variables;

pub use model::Roller;

#[cfg(feature = "fmu")]
fmi_abi::export_fmi2!(crate::model::Roller);
// The FMI 3.0 API from the same library (out/fmi3/Roller.fmu ships it too).
#[cfg(feature = "fmu")]
fmi_abi::export_fmi3!(crate::model::Roller);
