//! Numerical building blocks shared by the models: the exact step of a
//! linear ODE, compensated sums, and a family of integrators on fixed-size
//! arrays (no heap allocation in a step), and banded Rosenbrock methods for
//! systems sized at run time (`stiff`).

pub mod band;
mod compensated;
pub mod dopri5;
pub mod fixed;
mod linalg;
mod linear;
pub mod ode;
pub mod stiff;
pub mod rosenbrock;

pub use compensated::CompensatedSum;
pub use linalg::expm;
pub use linear::{decay_integral, phi1, phi2, ramp_integral};
pub use ode::{Control, Failure, Ode, Solution};
