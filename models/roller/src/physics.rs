//! The equations of a line part that is not a span (the Roller FMU's
//! documentation numbers them):
//!
//! [R1]  J*domega/dt = r*(F_b - F_a) + tau - b*omega       (F_a: sum of web_a*.F, F_b: sum of web_b*.F)
//! [R2]  v = r*omega
//! [R5]  1/(1+eps_b) = sum_i (m_i/M)/(1+eps_i), M = sum_i m_i          (several inlets: the merge)
//!       evaluated as eps_b = sum_i q_i*eps_i / sum_i q_i, q_i = m_i/(1+eps_i)
//! [R9]  eps_b,k = eps_a,((k-1) mod n)+1                                 (layered: each outlet one inlet's)
//!
//! [R3] (the roll) is in `roll`, [R4] (the carriage) in `carriage`, [R12] (a brake) in `brake`.
//! Over a piece of a communication step where the inputs are held and the
//! profiles are linear in time, [R1] with r and J held is a linear ODE with
//! forcing linear in time, stepped exactly here. [R3] moves r and J after the
//! piece, keeping omega: the web that leaves or arrives carries its own angular momentum.

use crate::number::Number;
use crate::parameters::{ports, Inputs, Parameters, PORTS};
use crate::roll::Roll;
use solver::{decay_integral, ramp_integral, CompensatedSum};

/// The strain of the web leaving the nip [R5]: with one inlet the arriving
/// strain itself; with several, the mean of their strains weighted by
/// q_i = m_i/(1+eps_i) (each web's share of the mass flowing in). Both sums
/// have terms of one sign where the strains do, so nothing cancels
/// (1/(1+eps_b) - 1 would lose digits for small strains).
pub fn merged_strain<N: Number>(p: &Parameters, strain: &[N; PORTS]) -> N {
    let n = ports(p.inlets);
    if n == 1 {
        return strain[0];
    }
    let (mut weighted, mut total) = (N::default(), N::default());
    for (i, &eps) in strain[..n].iter().enumerate() {
        let q = N::constant(p.mass_a[i]) / (eps + 1.0);
        weighted = weighted + q * eps;
        total = total + q;
    }
    weighted / total
}

/// The inlet (0-based) whose strain outlet `outlet` (0-based) passes on where the webs stay layers [R9]:
/// (outlet mod inlets), so that n inlets pass to n outlets one by one, and one inlet's layers to as
/// many outlets per lane after a slitter, lane after lane.
#[inline]
pub fn layer_inlet(p: &Parameters, outlet: usize) -> usize {
    outlet % ports(p.inlets)
}

/// v [R2].
#[inline]
pub fn surface_speed<N: Number>(radius: N, omega: N) -> N {
    radius * omega
}

/// The webs' torque on the roller, r*(F_b - F_a) [R1], N m.
#[inline]
pub fn web_torque<N: Number>(p: &Parameters, radius: N, u: &Inputs<N>) -> N {
    radius * (u.pull_forward(p) - u.pull_back(p))
}

/// The torque sum of [R1], J*omega': the webs' torque `web` ([R1]'s r*(F_b - F_a), or [R6]'s
/// -r*f where the web may slip), the drive's `drive` (its table, loop, brake) and the bearings'
/// `bearing`. No J'*omega: on a roll being wound that is the angular momentum the web carries off
/// or brings (physics docs, "Winders and unwinders").
#[inline]
pub fn net_torque<N: Number>(web: N, drive: N, bearing: N) -> N {
    web + drive + bearing
}

/// d(omega)/dt of a surface that follows a speed v(t) with slope v' [R2]: omega = v/r, r moving at r'.
#[inline]
pub fn omega_rate_at_speed<N: Number>(slope: f64, speed: N, radius: N, radius_rate: N) -> N {
    N::constant(slope) / radius - speed * radius_rate / (radius * radius)
}

/// The drive torque [R1] that makes the surface follow a speed table: `net_torque` = J*omega'
/// solved for the drive's share, omega' the surface's (`omega_rate_at_speed`).
#[inline]
pub fn speed_drive_torque<N: Number>(inertia: N, omega_rate: N, web: N, bearing: N) -> N {
    inertia * omega_rate - bearing - web
}

/// [R1] with r and J held over a piece of length h, the bearings' torque -b*omega
/// (`roll::bearing_damping`): the drive torque is `tau0 + tau1*s` (s from the piece's start). Exact:
/// omega(h) = omega + (a0 - (b/J)*omega)*int e^{-(b/J)(h-s)} ds + a1*int s e^{-(b/J)(h-s)} ds.
#[allow(clippy::too_many_arguments)]
pub fn rotation_step(p: &Parameters, roll: &Roll, u: &Inputs, omega: CompensatedSum, damping: f64, tau0: f64, tau1: f64, h: f64) -> CompensatedSum {
    let j = roll.inertia;
    let decay = damping / j;
    let a0 = (web_torque(p, roll.radius, u) + tau0) / j;
    let a1 = tau1 / j;
    omega.plus((a0 - decay * omega.value()) * decay_integral(decay, h) + a1 * ramp_integral(decay, h))
}

/// A load cell under the roller's bearings: the resultant of the webs pulling back (`back`, every
/// arriving web) and forward (`forward`, every leaving one, as parallel webs do) at a wrap
/// angle with cosine `cos_wrap`, by the law of cosines: sqrt(a^2 + b^2 - 2 a b cos(wrap)).
pub fn load_cell<N: Number>(back: N, forward: N, cos_wrap: f64) -> N {
    let square = back * back + forward * forward - back * 2.0 * forward * cos_wrap;
    // At 0, a cusp: the slope a central difference gives there, 0.
    if square.value() > 0.0 {
        square.sqrt()
    } else {
        N::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> Parameters {
        Parameters { inertia: 2.0, radius: 0.2, damping: 0.5, ..Parameters::default() }
    }

    #[test]
    fn rotation_step_solves_linear_forcing_exactly() {
        // J w' = tau0 + tau1 s - b w, from w0: w(h) against the closed form.
        let p = params();
        let roll = Roll::new(p.radius, p.inertia);
        let (tau0, tau1, h, w0) = (3.0, -7.0, 0.4, 10.0);
        let k = p.damping / p.inertia;
        let (a0, a1) = (tau0 / p.inertia, tau1 / p.inertia);
        // w(t) = a0/k + a1*(t/k - 1/k^2) + C e^{-kt}
        let c = w0 - a0 / k + a1 / (k * k);
        let exact = a0 / k + a1 * (h / k - 1.0 / (k * k)) + c * (-k * h).exp();
        let got = rotation_step(&p, &roll, &Inputs::default(), CompensatedSum::from_parts(w0, 0.0), p.damping, tau0, tau1, h).value();
        assert!((got - exact).abs() < 1e-13 * exact.abs(), "{got} {exact}");
    }

}
