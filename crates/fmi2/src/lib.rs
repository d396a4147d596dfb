//! The FMI 2.0 layer, written once for any model that implements [`Model`].
//!
//! * `ffi` — the only unsafe code: the C types, the entry path every export
//!   goes through, and [`export_fmi2!`], which writes the 44 exports for a model;
//! * `instance` — one FMU instance: state machine, checks, time, FMU states;
//! * `bind` — [`bind_variables!`]: each variable bound to its field once;
//!   get, set, save and load follow from that binding;
//! * `description` — the types of the table the generator (`fmi2-build`)
//!   emits from a modelDescription.xml;
//! * `resources` — the FMU's resources/ folder from the importer's URI;
//! * `model`, `persist`, `snapshot`, `phase`, `status`, `logging`.

#![deny(unsafe_code)]

mod bind;
pub mod description;
#[allow(unsafe_code)]
pub mod ffi;
pub mod instance;
pub mod logging;
pub mod model;
pub mod persist;
pub mod phase;
pub mod resources;
pub mod snapshot;
pub mod status;

pub use model::{Event, EventUpdate, Experiment, IntegerValue, Jacobian, Model, Variables};
pub use persist::{StateReader, StateWriter};
pub use resources::Resources;
pub use status::{FmiError, FmiResult, Status};
