//! Where inside a communication step a slack web's tension crosses zero
//! (`preventNegativeTension`), reported as an event for `logEvents`.

use crate::parameters::Inputs;
use crate::{physics, ConvertingSpan};
use fmi_core::Event;
use solver::CompensatedSum;

impl ConvertingSpan {
    /// With a slack web, where inside the step [0, h] the tension crossed
    /// zero: bisection on the step's trajectory (exact for held inputs, a
    /// cubic Hermite interpolant of the integrator's end points otherwise).
    pub(super) fn slack_crossing(&self, start: &Inputs, rates: Option<&Inputs>, next: CompensatedSum, h: f64) -> Option<Event> {
        let p = &self.params;
        let x0 = self.unstretched;
        let zero_rates = Inputs::default();
        let r = rates.unwrap_or(&zero_rates);
        let length_rate = physics::length_rate(p, start, r);
        let tension_at = |tau: f64, x: CompensatedSum| self.web_force_at(x, &start.advanced(r, tau), length_rate);
        let (g0, g1) = (tension_at(0.0, x0), tension_at(h, next));
        if (g0 > 0.0) == (g1 > 0.0) {
            return None;
        }
        let change = (next.hi() - x0.hi()) + (next.lo() - x0.lo());
        let (f0, f1) = (
            physics::unstretched_rate(start, physics::strain(physics::span_length(p, start), x0, 0.0)),
            {
                let u = start.advanced(r, h);
                physics::unstretched_rate(&u, physics::strain(physics::span_length(p, &u), next, 0.0))
            },
        );
        let trajectory = |tau: f64| -> CompensatedSum {
            if rates.is_none() {
                physics::exact_step(physics::span_length(p, start), start, x0, tau)
            } else {
                // Cubic Hermite on [0, h] through (x0, f0) and (x1, f1).
                let s = tau / h;
                let (h10, h01, h11) = (s.powi(3) - 2.0 * s * s + s, -2.0 * s.powi(3) + 3.0 * s * s, s.powi(3) - s * s);
                x0.plus(h10 * h * f0 + h01 * change + h11 * h * f1)
            }
        };
        let (mut lo, mut hi) = (0.0, h);
        for _ in 0..64 {
            let mid = 0.5 * (lo + hi);
            if (tension_at(mid, trajectory(mid)) > 0.0) == (g0 > 0.0) {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let what = if g0 > 0.0 { "the web goes slack (tension reaches 0)" } else { "the web takes up tension again" };
        Some(Event { offset: 0.5 * (lo + hi), what })
    }
}
