//! ConvertingSpan: an FMI 2.0 co-simulation FMU of a converting web span.
//!
//! * `fmi2`  — the FMI layer, generic over the model; its `ffi` module holds
//!   all unsafe code and the exported C API.
//! * `span`  — the converting-span model: parameters, equations, outputs.
//! * `solver` — numerical building blocks (exact linear steps, compensated sums).

#![deny(unsafe_code)]

pub mod fmi2;
pub mod solver;
pub mod span;

/// The model this library's `fmi2*` functions serve.
pub type ExportedModel = span::ConvertingSpan;
