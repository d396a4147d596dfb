//! The FMI standard without C, written once for any model that implements
//! [`Model`]: what a call may do in which state, what a value must be, and
//! what an FMU state holds. Safe Rust; `fmi-abi` puts the C API on top.
//!
//! * `instance` — one FMU instance: state machine, checks, time, FMU states;
//! * `standard` — FMI 2.0's and FMI 3.0's functions, the states each is
//!   allowed in, and their words for the phases;
//! * `bind` — [`bind_variables!`]: each variable bound to its field once;
//!   get, set, save and load follow from that binding;
//! * `description` — the types of the table the generator (`fmi-build`)
//!   emits from a modelDescription.xml;
//! * `resources` — the FMU's resources/ folder from the importer's location;
//! * `model`, `persist`, `snapshot`, `phase`, `status`, `logging`.

#![forbid(unsafe_code)]

mod bind;
pub mod description;
pub mod instance;
pub mod logging;
pub mod model;
pub mod persist;
pub mod phase;
pub mod resources;
pub mod snapshot;
pub mod standard;
pub mod status;

pub use model::{Compiled, Event, EventUpdate, Experiment, IntegerValue, Jacobian, Model, Variables};
pub use persist::{StateReader, StateWriter};
pub use resources::Resources;
pub use standard::{Call, Standard};
pub use status::{FmiError, FmiResult, Status};
