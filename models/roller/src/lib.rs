//! Roller: an FMU (FMI 2.0 and 3.0) of every part of a web line that is not
//! a span — idler, driven roller, source, sink, unwinder, winder, dancer —
//! built like the span, in the same rooms: `fmi-core` and `fmi-abi` do the
//! standard and the C API, this crate only the model.
//!
//! * `parameters` — what the user sets and the inputs, in SI units;
//! * `state` — the continuous states by name;
//! * `number` — the numbers the equations are written in: f64, and `Tangent` for derivatives;
//! * `rhs` — the right-hand side, written once: the rates and the outputs, from the effects:
//!   * `physics` — [R1], [R2], [R5], [R9] and [R1]'s exact step;
//!   * `roll` — the roll being wound and the bearings [R3];
//!   * `carriage` — a dancer's carriage [R4];
//!   * `contact` — where the web may slip: its speed over the roller, friction, air film [R6]–[R8];
//!   * `control` — the drive's loop and its motor [R10]–[R11], [R13];
//!   * `brake` — a powder brake [R12];
//!   * `drive` — the profile: the drive and the tables of time it follows;
//!   * `runout` — a roll with runout [R15], the web tangent to its offset surface;
//!   * `layon` — a lay-on roller against a winder [R18]: its carriage, nip and traction;
//! * `jacobian` — the partial derivatives: `rhs` along a direction;
//! * `model` — the roller's data and the effects' glue;
//! * `stepping` — one communication step;
//! * `hooks` — the hooks the FMI layer calls;
//! * `variables` — each variable of modelDescription.xml bound to its field;
//! * `description` — the interface generated from modelDescription.xml.

#![deny(unsafe_code)]

pub mod brake;
pub mod bristle;
pub mod carriage;
pub mod contact;
pub mod control;
pub mod description;
pub mod drive;
pub mod layon;
mod hooks;
pub mod jacobian;
mod model;
pub mod number;
pub mod parameters;
pub mod physics;
pub mod rhs;
pub mod roll;
pub mod runout;
pub mod state;
mod stepping;
mod variables;

pub use model::Roller;

#[cfg(feature = "fmu")]
fmi_abi::export_fmi2!(crate::model::Roller);
// The FMI 3.0 API from the same library (out/fmi3/Roller.fmu ships it too).
#[cfg(feature = "fmu")]
fmi_abi::export_fmi3!(crate::model::Roller);
