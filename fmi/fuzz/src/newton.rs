//! The matrix of the Newton iteration in the Model Exchange driver's implicit Euler steps
//! (model_exchange.rs), kept with the instance it is formed for (sequence.rs: `Integration`).

use solver::band::{Band, BandLu};

/// A Newton iteration's matrix, 1/h I - J, with J by finite differences: kept while the
/// iteration converges (factored again for another h), formed again where it does not.
pub(crate) struct Newton {
    pub(crate) jacobian: Band,
    pub(crate) lu: BandLu,
    /// The step size the factors are for (0: none).
    pub(crate) h: f64,
    /// `jacobian` holds J (false: form it at the next step).
    pub(crate) fresh: bool,
}

impl Newton {
    pub(crate) fn new(n: usize) -> Newton {
        let w = n.saturating_sub(1);
        Newton { jacobian: Band::zeros(n, w, w), lu: BandLu::new(n, w, w), h: 0.0, fresh: false }
    }
}
