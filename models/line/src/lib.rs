//! Line: a whole web line as one FMU (FMI 2.0 and 3.0, Co-Simulation and
//! Model Exchange). The binary is generic: the line it holds — its parts, their
//! start values and profiles, how they connect — is read from
//! `resources/line.json` when it is instantiated, and the interface follows
//! from it. The modules, from the bottom up (each imports only those below it):
//!
//! * `spec` — line.json;
//! * `port` — a part's variable resolved once, and a connection between parts;
//! * `part` — the span's and the Roller's own models, behind one face;
//! * `laminate` — a laminate span: a span part per layer, and the laminate's own outputs;
//! * `chain` — the Jacobian chained from the parts' tangents;
//! * `network` — states, connections, the web-mass loop, the band;
//! * `ode` — the line as one ODE and where it stands; f and its Jacobian;
//! * `equilibrium` — the steady state a line starts in;
//! * `stepping` — initialization, a communication step (events at their times,
//!   Rodas5P between), Model Exchange's events;
//! * `feed` — a loop's feed-forward on another part's input v_ref: its slope at each step;
//! * `interface` — the variables, `<part>.<variable>`, and what each is bound to;
//! * `line` — the `Line`: the FMI model hooks, calling down;
//! * `xml` — its modelDescription.xml (`line-description`).

#![deny(unsafe_code)]

pub mod chain;
pub mod equilibrium;
pub mod feed;
pub mod interface;
pub mod laminate;
pub mod line;
pub mod network;
pub mod ode;
pub mod part;
pub mod port;
pub mod spec;
pub mod stepping;
#[cfg(feature = "cli")]
pub mod xml;

pub use line::{Line, Shared};

#[cfg(feature = "fmu")]
fmi_abi::export_fmi2!(crate::line::Line);
#[cfg(feature = "fmu")]
fmi_abi::export_fmi3!(crate::line::Line);
// One call for a study's whole run (webline's native loop, docs/studies.md); importers never need it.
#[cfg(feature = "fmu")]
fmi_abi::export_fmi2_steps!(crate::line::Line);
