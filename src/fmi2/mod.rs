//! The FMI 2.0 layer, written once for any model that implements [`Model`].

pub mod description;
#[allow(unsafe_code)]
pub mod ffi;
pub mod instance;
mod logging;
pub mod model;
pub mod phase;
pub mod snapshot;
pub mod status;

pub use model::{Event, Experiment, Model};
pub use snapshot::{Persist, StateReader, StateWriter};
pub use status::{FmiError, FmiResult, Status};
