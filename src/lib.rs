//! ConvertingSpan: an FMI 2.0 co-simulation FMU of a converting web span.
//!
//! * `fmi2`  — the FMI layer, generic over the model; its `ffi` module holds
//!   all unsafe code and the exported C API.
//! * `span`  — the converting-span model: parameters, equations, outputs.
//! * `roller` — the roller model of the companion Roller FMU.
//! * `solver` — numerical building blocks (exact linear steps, compensated sums).

#![deny(unsafe_code)]

pub mod fmi2;
pub mod roller;
pub mod solver;
pub mod span;

/// The model this library's `fmi2*` functions serve: ConvertingSpan, or the
/// Roller with the cargo feature `roller` (both models are always compiled,
/// so the Rust tests can use either).
#[cfg(not(feature = "roller"))]
pub type ExportedModel = span::ConvertingSpan;
#[cfg(feature = "roller")]
pub type ExportedModel = roller::Roller;
