//! The FMI 3.0 layer, written once for any model that implements
//! [`fmi2::Model`]: the same model, instance, checks, FMU states and logging
//! as the FMI 2.0 layer, under the FMI 3.0 C API.
//!
//! * `ffi` — the only unsafe code: the C types, the entry path every export
//!   goes through, and [`export_fmi3!`], which writes the exports for a model;
//! * `call` — every fmi3 function that takes an instance, and the states it
//!   is allowed in;
//! * `types` — FMI 3.0's types of the description's variables, and the two
//!   variables FMI 3.0 adds (the independent `time`, the event indicators).

#![deny(unsafe_code)]

pub mod call;
#[allow(unsafe_code)]
pub mod ffi;
pub mod types;
