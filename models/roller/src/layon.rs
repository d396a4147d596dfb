//! A lay-on (contact) roller pressed against a winder [R18]: its carriage, the nip's force, the
//! traction that turns it, and the speed above which it bounces. The winder's axis is at the
//! origin and its surface a circle of radius r whose centre C sits at e from the axis (runout [R15],
//! e = 0 for a round roll); the lay-on roller (radius r_l) rides a carriage guided along the unit
//! line u through the winder's axis, its axis at D = X u. Angles in runout's frame: C = e (sin psi,
//! cos psi), u = (sin beta, cos beta), phi = psi - beta.
//!
//! [R18] d = |D - C| = sqrt(X^2 - 2 X e cos phi + e^2),   delta = r + r_l - d   (the nip's compression)
//!       N = max(0, k delta + c delta')                  (the nip pushes, never pulls)
//!       m X'' = N (X - e cos phi)/d - F(t)              (the carriage: the nip's share along u, the load)
//!       f = mu N tanh((omega a - omega_l r_l)/v_s),  a = r + (X e cos phi - e^2)/d   (Coulomb, regularized)
//!       J_l omega_l' = r_l f - b_l omega_l,           the winder takes -a f
//!
//! In the Roller (its parameters layon.*, states layon.x, layon.v, layon.omega) and so in the Line.

use crate::number::Number;
use crate::parameters::{Parameters, WINDER};

/// The lay-on roller and its carriage, SI.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LayOn {
    /// The carriage's moving mass m (with the roller's), kg.
    pub mass: f64,
    /// The nip's stiffness k (N/m) and damping c (N s/m).
    pub stiffness: f64,
    pub damping: f64,
    /// The roller's radius r_l (m), inertia J_l (kg m^2) and bearing b_l (N m s).
    pub radius: f64,
    pub inertia: f64,
    pub bearing: f64,
    /// The nip's friction coefficient and the slip speed of its tanh law (m/s).
    pub mu: f64,
    pub v_slip: f64,
    /// The carriage's line from the winder's axis, from runout's n axis (rad).
    pub angle: f64,
}

/// The lay-on roller of these parameters, its line in runout's frame of a winder [R15] (mirrored:
/// layon.angle is measured as runout.phase is, in the roll's sense of turning).
pub fn of(p: &Parameters) -> LayOn {
    LayOn {
        mass: p.layon_m,
        stiffness: p.layon_k,
        damping: p.layon_c,
        radius: p.layon_r,
        inertia: p.layon_j,
        bearing: p.layon_b,
        mu: p.layon_mu,
        v_slip: p.layon_v_slip,
        angle: -p.layon_angle,
    }
}

/// Why a lay-on roller cannot be on this roller (None: it can): it presses on a winder whose axis
/// does not move, where the web does not slip, with a smooth radius.
pub fn refusal(p: &Parameters) -> Option<String> {
    if !p.layon {
        return None;
    }
    if p.roll != WINDER || p.carriage || p.traction {
        return Some(format!(
            "layon = true with roll = {}, carriage = {}, includeTraction = {}: a lay-on roller [R18] presses on a winder (roll = 2) \
             whose axis does not move, without slip",
            p.roll, p.carriage, p.traction
        ));
    }
    if p.wound_merge > 0.0 {
        return Some(format!("layon = true with wound.merge = {} rad: a lay-on roller on a stepwise radius [R17] is not modelled; set wound.merge = 0", p.wound_merge));
    }
    None
}

/// Where the carriage starts [R18]: pressed by the load F0 on the roll's surface at the roll's radius r
/// and angle 0 (runout's), at rest along its line, its roller turning with the surface at omega:
/// (X, X', omega_l), X = e cos phi + sqrt((r + r_l - F0/k)^2 - e^2 sin^2 phi).
pub fn start(p: &Parameters, radius: f64, omega: f64, load: f64) -> [f64; 3] {
    let l = of(p);
    let (e, phi) = if p.runout { (p.runout_e, -p.runout_phase - l.angle) } else { (0.0, 0.0) };
    let reach = radius + l.radius - load / l.stiffness;
    let x = e * phi.cos() + (reach * reach - (e * phi.sin()).powi(2)).max(0.0).sqrt();
    [x, 0.0, omega * radius / l.radius]
}

/// The winder as the nip sees it: its radius and the rate it grows at, its runout and its turning.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Winder<N> {
    pub radius: N,
    pub radius_rate: N,
    /// e (m) and psi, runout's angle of the centre [R15] (0 and anything for a round roll).
    pub eccentricity: f64,
    pub psi: N,
    /// d(psi)/dt: s*omega [R15].
    pub psi_rate: N,
    /// omega, the winder's speed of rotation (rad/s).
    pub omega: N,
}

/// The nip now [R18].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Nip<N> {
    /// delta, the nip's compression (negative: a gap), m.
    pub compression: N,
    /// N, the nip's force along the line of centres, >= 0.
    pub force: N,
    /// The carriage's acceleration X'' and the roller's omega_l'.
    pub acceleration: N,
    pub spin_rate: N,
    /// The traction's torque on the winder, -a f.
    pub winder_torque: N,
}

/// N = max(0, k delta + c delta') [R18]: a nip only pushes; apart (delta <= 0) it carries nothing,
/// whatever delta' (the damper does not hold the rolls together as they part).
#[inline]
pub fn force<N: Number>(l: &LayOn, compression: N, compression_rate: N) -> N {
    let f = compression * l.stiffness + compression_rate * l.damping;
    if compression.value() > 0.0 && f.value() > 0.0 {
        f
    } else {
        N::default()
    }
}

/// [R18] at the carriage's position X, speed X', the roller's spin omega_l and the load F.
#[inline]
pub fn nip<N: Number>(l: &LayOn, w: &Winder<N>, position: N, speed: N, spin: N, load: N) -> Nip<N> {
    let e = w.eccentricity;
    let phi = w.psi - l.angle;
    let (sin, cos) = (phi.sin(), phi.cos());
    let along = cos * e;
    let d = (position * position - position * along * 2.0 + e * e).sqrt();
    let compression = w.radius + l.radius - d;
    // d' = (X X' - X' e cos phi + X e sin phi phi')/d.
    let d_rate = (position * speed - speed * along + position * sin * w.psi_rate * e) / d;
    let normal = force(l, compression, w.radius_rate - d_rate);
    let arm = w.radius + (position * along - e * e) / d;
    let traction = normal * l.mu * ((w.omega * arm - spin * l.radius) / l.v_slip).tanh();
    Nip {
        compression,
        force: normal,
        acceleration: (normal * (position - along) / d - load) / l.mass,
        spin_rate: (traction * l.radius - spin * l.bearing) / l.inertia,
        winder_torque: -(arm * traction),
    }
}

/// The speed of rotation at which a rigid nip lets go of a roll with runout e under the load F:
/// the carriage following the surface needs m e omega^2, so omega_c = sqrt(F/(m e)) [R18].
pub fn rigid_bounce_omega(l: &LayOn, load: f64, eccentricity: f64) -> f64 {
    (load / (l.mass * eccentricity)).sqrt()
}

/// The same for the nip's stiffness k and damping c (the carriage on the nip's spring, forced by the
/// surface's first harmonic e cos(omega t)): the force's swing m omega^2 e |k + i c omega| /
/// |k - m omega^2 + i c omega| reaches F. Undamped, omega_c^2 = F/(m (e + F/k)). None: no speed below
/// the nip's resonance sqrt(k/m) reaches it.
pub fn bounce_omega(l: &LayOn, load: f64, eccentricity: f64) -> Option<f64> {
    let (m, k, c) = (l.mass, l.stiffness, l.damping);
    let swing = |w: f64| m * w * w * eccentricity * (k * k + (c * w).powi(2)).sqrt() / ((k - m * w * w).powi(2) + (c * w).powi(2)).sqrt();
    let resonance = (k / m).sqrt();
    if swing(resonance) < load {
        return None;
    }
    // Below the resonance the swing grows with omega at any damping (d ln(swing^2)/d(omega^2) >= 1/omega^2): bisect.
    let (mut lo, mut hi) = (0.0, resonance);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if swing(mid) < load {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

#[cfg(test)]
mod tests {
    use super::*;
    use solver::fixed::{integrate, Method};
    use solver::Ode;

    /// Where the nip let go and for how long, recorded from the force at each sample of a test's run (webline
    /// reports a run's separations from its output samples: summary.py).
    #[derive(Clone, Copy, Debug, Default, PartialEq)]
    struct Separations {
        /// Times it let go, the first time, the longest and the total time apart (s).
        count: u32,
        first: Option<f64>,
        longest: f64,
        total: f64,
        apart_since: Option<f64>,
    }

    impl Separations {
        /// The nip's force `force` at time t (samples in time order).
        fn observe(&mut self, t: f64, force: f64) {
            match (self.apart_since, force > 0.0) {
                (None, false) => {
                    self.apart_since = Some(t);
                    self.count += 1;
                    self.first.get_or_insert(t);
                }
                (Some(since), true) => {
                    self.close(t - since);
                    self.apart_since = None;
                }
                _ => {}
            }
        }

        /// At the end of the record: a separation still open closes at t.
        fn finish(&mut self, t: f64) {
            if let Some(since) = self.apart_since.take() {
                self.close(t - since);
            }
        }

        fn close(&mut self, duration: f64) {
            self.longest = self.longest.max(duration);
            self.total += duration;
        }
    }

    fn roller(stiffness: f64, damping: f64) -> LayOn {
        LayOn { mass: 20.0, stiffness, damping, radius: 0.1, inertia: 0.05, bearing: 1e-3, mu: 0.5, v_slip: 1e-3, angle: 0.3 }
    }

    /// The winder turning at omega with runout e, its radius growing at r'; the states
    /// (X, X', omega_l, psi, r), the load held.
    struct Run {
        l: LayOn,
        e: f64,
        omega: f64,
        radius_rate: f64,
        load: f64,
    }

    impl Run {
        fn at(&self, y: &[f64; 5]) -> Nip<f64> {
            let w = Winder { radius: y[4], radius_rate: self.radius_rate, eccentricity: self.e, psi: y[3], psi_rate: self.omega, omega: self.omega };
            nip(&self.l, &w, y[0], y[1], y[2], self.load)
        }

        /// RK4 from y for `time` in steps of h, the nip's force at each step recorded from t0 on.
        fn simulate(&self, mut y: [f64; 5], time: f64, h: f64, t0: f64) -> ([f64; 5], Separations, f64) {
            let (mut record, mut least) = (Separations::default(), f64::INFINITY);
            let steps = (time / h).round() as usize;
            for k in 1..=steps {
                y = integrate(&Method::Rk4, self, h, y, 1).unwrap();
                let (t, force) = (k as f64 * h, self.at(&y).force);
                if t >= t0 {
                    record.observe(t, force);
                    least = least.min(force);
                }
            }
            record.finish(time);
            (y, record, least)
        }
    }

    impl Ode<5> for Run {
        fn rhs(&self, _: f64, y: &[f64; 5]) -> [f64; 5] {
            let n = self.at(y);
            [y[1], n.acceleration, n.spin_rate, self.omega, self.radius_rate]
        }

        fn jacobian(&self, _: f64, _: &[f64; 5]) -> [[f64; 5]; 5] {
            unreachable!("RK4 asks no Jacobian")
        }

        fn time_derivative(&self, _: f64, _: &[f64; 5]) -> [f64; 5] {
            unreachable!("RK4 asks no time derivative")
        }
    }

    /// Dropped from a 1 mm gap onto a round roll that grows at 0.1 mm/s, the carriage bounces and
    /// settles: the nip's force is then the load to 1e-6 N (m X'' = m r'' = 0), the roller turns
    /// with the winder's surface but for the slip that carries its bearing and spin-up, and the nip never pulled.
    #[test]
    fn the_steady_nip_carries_the_load() {
        let run = Run { l: roller(1e6, 2000.0), e: 0.0, omega: 50.0, radius_rate: 1e-4, load: 300.0 };
        let (r, rl) = (0.3, run.l.radius);
        let (y, record, least) = run.simulate([r + rl + 1e-3, 0.0, 0.0, 0.0, r], 1.0, 1e-5, 0.0);
        let end = run.at(&y);
        eprintln!("steady nip: N - F = {:e} N", end.force - run.load);
        assert!((end.force - run.load).abs() < 1e-6, "N = {} N against the load {} N", end.force, run.load);
        assert!((end.compression - run.load / run.l.stiffness).abs() < 1e-12);
        // r_l f = b_l omega_l + J_l omega_l' (omega_l' = omega r'/r_l as the roll grows), with
        // f = mu N tanh(slip/v_s): the slip is what carries the bearing and the spin-up.
        let torque = run.l.bearing * y[2] + run.l.inertia * run.omega * run.radius_rate / rl;
        let slip = run.l.v_slip * (torque / (rl * run.l.mu * run.load)).atanh();
        assert!((run.omega * y[4] - y[2] * rl - slip).abs() < 1e-9, "{} {}", run.omega * y[4] - y[2] * rl, slip);
        assert!(record.count >= 1 && least >= 0.0, "{record:?} {least}");
    }

    /// What the nip conserves [R18]: on a round roll of fixed radius the carriage's energy with the load's
    /// potential and the spring's, E = m X'^2/2 + F X + k max(0, delta)^2/2, has dE/dt = -c delta'^2 while
    /// pressed and k delta delta' < 0 while parting unpressed: it never grows. Dropped from a 1 mm gap at
    /// 0.2 m/s on a nip of damping ratio 0.2 (a restitution of about 0.5) the carriage bounces (the nip lets
    /// go), and E falls at every RK4 step of 1 us but for the method's error, below 1e-9 of E's swing (h^4
    /// of the nip's period of 0.9 ms: 1e-12); after 0.5 s it rests where the nip carries the load, having lost
    /// what it brought in (to 1e-6 of it).
    #[test]
    fn the_nip_never_gives_back_energy_it_did_not_store() {
        let l = roller(1e6, 0.4 * (1e6_f64 * 20.0).sqrt());
        let run = Run { l, e: 0.0, omega: 30.0, radius_rate: 0.0, load: 300.0 };
        let (r, rl) = (0.3, l.radius);
        let energy = |y: &[f64; 5]| {
            let delta = (r + rl - y[0]).max(0.0);
            0.5 * l.mass * y[1] * y[1] + run.load * y[0] + 0.5 * l.stiffness * delta * delta
        };
        let mut y = [r + rl + 1e-3, -0.2, 0.0, 0.0, r];
        let (start, mut rises, mut apart) = (energy(&y), 0.0f64, 0usize);
        let mut previous = start;
        for _ in 0..500_000 {
            y = integrate(&Method::Rk4, &run, 1e-6, y, 1).unwrap();
            let e = energy(&y);
            rises = rises.max(e - previous);
            apart += (run.at(&y).force == 0.0) as usize;
            previous = e;
        }
        let settled = energy(&[r + rl - run.load / l.stiffness, 0.0, 0.0, 0.0, r]);
        eprintln!("nip energy: from {start} J to {previous} J (settled {settled} J), largest rise {rises:e} J, {apart} steps apart");
        assert!(rises <= 1e-9 * (start - settled), "E rose by {rises} J in a step");
        assert!(apart > 1000, "the carriage must bounce off the nip ({apart} steps apart)");
        assert!((previous - settled).abs() < 1e-6 * (start - settled), "E ends at {previous} J, the settled nip's {settled} J");
    }

    /// The nip pushes or carries nothing: never a negative force, apart or parting.
    #[test]
    fn the_nip_never_pulls() {
        let l = roller(1e6, 2000.0);
        for i in -20..=20 {
            for j in -20..=20 {
                let (delta, rate) = (i as f64 * 1e-5, j as f64 * 1e-2);
                let n = force(&l, delta, rate);
                let pushed = delta > 0.0 && l.stiffness * delta + l.damping * rate > 0.0;
                assert!(n >= 0.0 && (n > 0.0) == pushed, "{delta} {rate} {n}");
                if pushed {
                    assert_eq!(n, l.stiffness * delta + l.damping * rate);
                }
            }
        }
    }

    /// Apart over the last 0.4 s of each second, sampled every 10 ms for 2.8 s: three separations,
    /// the first at 0.6 s, 0.4 s each but the last, still open at the end (0.2 s).
    #[test]
    fn the_separations_are_counted_and_timed() {
        let mut record = Separations::default();
        for k in 0..=280 {
            record.observe(k as f64 * 0.01, if k % 100 >= 60 { 0.0 } else { 50.0 });
        }
        record.finish(2.8);
        assert_eq!((record.count, record.first), (3, Some(0.6)));
        assert!((record.longest - 0.4).abs() < 1e-12 && (record.total - 1.0).abs() < 1e-12, "{record:?}");
    }

    /// Written once, generic over the number: the nip in `Tangent` along (X, X', omega_l, psi, r)
    /// is its central difference (h = 1e-7 of each, the nip pressed), to 1e-6 (its truncation, h^2, is 1e-14).
    #[test]
    fn the_nip_differentiates_as_it_computes() {
        use crate::number::Tangent;
        let run = Run { l: roller(1e6, 2000.0), e: 2e-3, omega: 40.0, radius_rate: 1e-4, load: 300.0 };
        let y = [0.4 + 1e-3 - 3e-4, 0.02, 110.0, 0.7, 0.3];
        let rates = |y: &[f64; 5]| {
            let n = run.at(y);
            [n.force, n.acceleration, n.spin_rate, n.winder_torque]
        };
        for i in 0..5 {
            let at = |v: f64| {
                let mut z = y;
                z[i] += v;
                z
            };
            let h = 1e-7 * y[i].abs().max(1e-3);
            let t = |k: usize| Tangent::new(y[k], if k == i { 1.0 } else { 0.0 });
            let w = Winder { radius: t(4), radius_rate: Tangent::constant(run.radius_rate), eccentricity: run.e, psi: t(3), psi_rate: Tangent::constant(run.omega), omega: Tangent::constant(run.omega) };
            let n = nip(&run.l, &w, t(0), t(1), t(2), Tangent::constant(run.load));
            let tangent = [n.force.d, n.acceleration.d, n.spin_rate.d, n.winder_torque.d];
            let (up, down) = (rates(&at(h)), rates(&at(-h)));
            let scale = rates(&y).map(f64::abs);
            for k in 0..4 {
                let difference = (up[k] - down[k]) / (2.0 * h);
                // Rounding in the difference: 1e-16 of the rate over h, far below 1e-6 of it.
                let floor = 1e-16 * scale[k] / h;
                assert!((tangent[k] - difference).abs() <= 1e-6 * tangent[k].abs() + 1e3 * floor, "state {i}, rate {k}: {} {difference}", tangent[k]);
            }
        }
    }

    /// A 1 mm runout under 100 N on a 20 kg carriage: a rigid nip lets go above
    /// omega_c = sqrt(F/(m e)) = 70.7 rad/s. The stiff nip (F/k = 1e-3 e) keeps contact at 0.99 of
    /// its own threshold and loses it at 1.01 (the surface's second harmonic, e/(r + r_l) = 0.25 % of
    /// the swing, is what the linear threshold leaves out), which is the rigid one to 0.1 %.
    #[test]
    fn it_bounces_above_the_derived_speed() {
        let (e, load) = (1e-3, 100.0);
        let l = roller(1e8, 2.0 * 0.3 * (1e8_f64 * 20.0).sqrt());
        let rigid = rigid_bounce_omega(&l, load, e);
        let exact = bounce_omega(&l, load, e).unwrap();
        eprintln!("bounce: omega_c = {exact} rad/s, rigid {rigid} rad/s");
        assert!((exact / rigid - 1.0).abs() < 1e-3, "{exact} {rigid}");
        let (r, rl) = (0.3, l.radius);
        for (factor, bounces) in [(0.95, false), (0.99, false), (1.01, true), (1.05, true)] {
            let omega = factor * exact;
            let run = Run { l, e, omega, radius_rate: 0.0, load };
            // On the rigid path at psi = 0 (centre towards the carriage's line at phi = -0.3), pressed by F/k.
            let x = e * (-l.angle).cos() + ((r + rl).powi(2) - (e * l.angle.sin()).powi(2)).sqrt() - load / l.stiffness;
            let start = [x, -e * l.angle.sin() * omega, omega * r / rl, 0.0, r];
            let (_, record, least) = run.simulate(start, 0.6, 2e-5, 0.1);
            assert_eq!(record.count > 0, bounces, "at {factor} omega_c: {record:?}");
            assert!(least >= 0.0);
            if bounces {
                let turn = 2.0 * std::f64::consts::PI / omega;
                assert!(record.longest > 0.0 && record.longest < turn && record.total < 0.5, "{record:?}");
            }
        }
    }
}
