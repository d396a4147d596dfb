//! The one C boundary of the project's FMUs, and its only unsafe code: the
//! FMI 2.0 and FMI 3.0 C APIs over [`fmi_core`], for any model. Knows C, not
//! the model.
//!
//! * `handle` — what an instance pointer points to, and the one entry path
//!   every export goes through: tag and pointer check, `catch_unwind`,
//!   poisoning, the state machine, a status plus one log line;
//! * `state_store` — the FMU states an instance has handed out;
//! * `library` — the library's own reference to itself while instances live;
//! * `fmu_states`, `alike` — the bodies of the functions both standards have
//!   alike: the FMU states; the life cycle, Model Exchange, Strings and
//!   directional derivatives;
//! * `fmi2`, `fmi3` — each standard's C types, its logger, the bodies of its own
//!   functions, and the one list of its C signatures (`export_fmi2!`, `export_fmi3!`).

#![allow(non_camel_case_types, non_snake_case, non_upper_case_globals, clippy::missing_safety_doc)]

#[doc(hidden)]
pub mod alike;
mod exports;
pub mod fmi2;
pub mod fmi3;
#[doc(hidden)]
pub mod fmu_states;
#[doc(hidden)]
pub mod handle;
mod library;
mod state_store;

pub use fmi_core;
