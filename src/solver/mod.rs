//! Numerical building blocks shared by the models.

mod compensated;
mod linear;

pub use compensated::CompensatedSum;
pub use linear::{decay_integral, phi1};
