//! The drive's loop [R10] and the motor it commands [R11]: a PI controller
//! whose integrator is a state, a smooth torque limit with back-calculation
//! anti-windup, an inertia feed-forward and a first-order torque lag.
//!
//! [R10] e = s*(set - F_measured) (force loop), e = v_ref - v (speed loop; v_ref: the reference table, else loop.speed);
//!       u = kp*e + I + tau_ff;   dI/dt = ki*e + (sat(u) - u)/T_t,  T_t = kp/ki (1 s if a gain is 0);
//!       tau_ff = J*d(v_ref/r)/dt = J*a_ref/r - J*r'*v_ref/r^2   (r' of [R3] at v_ref and the roll's strain;
//!       (v_ref, a_ref) the reference table's, else loop.speed and loop.acceleration)
//! [R11] motor.torque = sat(u) (no lag), or d(motor.torque)/dt = (sat(u) - motor.torque)/T_m;
//!       sat(u) = u for |u| <= L - w, else sign(u)*(L - w*exp(-(|u| - L + w)/w)),  w = L/20.
//! [R13] a dancer loop: the speed loop of [R10] with v_ref + trim for v_ref,
//!       e_d = loop.sign*(dancer.y - dancer.set);  trim = dancer.kp*e_d + dancer.I;  d(dancer.I)/dt = dancer.ki*e_d.
//! [R14] a sampled loop (loop.sample = T > 0): sat(u) of [R11] is sampled at t_k = t_0 + k*T and applied,
//!       held, from t_k + loop.delay on; the integrator integrates the continuous error exactly between.

use crate::number::Number;
use crate::parameters::{Kind, Parameters};
use crate::roll;

/// The shortest sample period [R14]: a drive's loop samples at some kHz; periods far shorter would only
/// cut the steps into pieces.
pub const MIN_SAMPLE: f64 = 1e-5;

/// The share of the limit over which the torque bends into it: smooth (C1), so that Newton's
/// method in the Line's implicit steps sees a slope everywhere, and exact inside.
const BEND: f64 = 0.05;

/// sat(u) of [R11] and its slope.
#[inline]
pub fn limit(p: &Parameters, u: f64) -> (f64, f64) {
    let l = p.motor_limit;
    if l <= 0.0 {
        return (u, 1.0);
    }
    let w = BEND * l;
    let over = u.abs() - (l - w);
    if over <= 0.0 {
        return (u, 1.0);
    }
    let decay = (-over / w).exp();
    (u.signum() * (l - w * decay), decay)
}

/// The feed-forward torque J*d(v_ref/r)/dt [R10] at radius r, inertia j (moving with r on a roll
/// being wound [R3]), reference speed v and acceleration a, the web at the roll at strain `strain`:
/// what [R1] needs for omega = v_ref/r.
#[inline]
pub fn feedforward<N: Number>(p: &Parameters, r: N, j: N, strain: N, v: f64, a: f64) -> N {
    if !p.winding() {
        return j * a / r;
    }
    let v = N::constant(v);
    j * a / r - j * roll::radius_rate(p, r, v, strain) * v / (r * r)
}

/// What the loop reads from the profile at a time: a force loop's set point (its table's, else
/// `loop.set`) and the reference's speed and slope where a table gives one.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Reads {
    pub set: f64,
    pub reference: Option<(f64, f64)>,
    /// A sampled loop's held command [R14] (None: the loop's own, continuous).
    pub held: Option<f64>,
}

/// A sampled loop's zero-order hold and delay [R14]: the command applied, a sample waiting out the
/// delay (when it applies, its command), and the samples' clock t_0 + k*T (no drift over many).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Hold {
    /// A sample was taken: `applied` holds; before the first the loop is continuous.
    pub engaged: bool,
    pub applied: f64,
    pub waiting: Option<(f64, f64)>,
    pub origin: f64,
    pub next: u64,
}

impl Hold {
    /// A hold whose first sample is due at t.
    pub fn starting(t: f64) -> Hold {
        Hold { origin: t, ..Hold::default() }
    }

    /// The time of its next sample.
    pub fn next_sample(&self, p: &Parameters) -> f64 {
        self.origin + self.next as f64 * p.loop_sample
    }

    /// Its next event: a sample, or a waiting sample's application.
    pub fn next_event(&self, p: &Parameters) -> f64 {
        let sample = self.next_sample(p);
        self.waiting.map_or(sample, |(at, _)| at.min(sample))
    }

    /// At time t, with the loop's continuous command `command` there: applies a sample whose delay is
    /// over, then takes the sample due (applied at once without a delay); whether the command moved.
    pub fn due(&mut self, p: &Parameters, t: f64, command: impl Fn() -> f64) -> bool {
        let mut moved = false;
        if let Some((_, c)) = self.waiting.filter(|&(at, _)| profiles::due(at, t)) {
            (self.applied, self.waiting, moved) = (c, None, true);
        }
        if profiles::due(self.next_sample(p), t) {
            let c = command();
            if p.loop_delay > 0.0 && self.engaged {
                // Taken now where an importer moved the time past the sample's instant.
                self.waiting = Some((self.next_sample(p).max(t) + p.loop_delay, c));
            } else {
                // The first sample applies at once: the drive ran at it before the start.
                self.applied = c;
                moved = true;
            }
            self.engaged = true;
            // The first sample after t (at once, however far an importer moved the time).
            self.next = ((t - self.origin) / p.loop_sample).floor().max(0.0) as u64;
            while profiles::due(self.next_sample(p), t) {
                self.next += 1;
            }
        }
        moved
    }
}

/// The loop's share of the roller's rates [R10]-[R11], [R13]: the torque its motor gives and the
/// rates of its states (all 0 without a loop).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Law<N> {
    pub torque: N,
    /// The loop's continuous command sat(u) [R11], which a sampled loop samples [R14].
    pub command: N,
    pub integrator_rate: N,
    pub motor_rate: N,
    pub dancer_rate: N,
}

/// What the loop sees of the roller: its speed, radius and inertia, the web's strain at its roll,
/// the inputs it measures (loop.measured, dancer.y) and its own states (loop.I, motor.torque, dancer.I).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Seen<N> {
    pub omega: N,
    pub radius: N,
    pub inertia: N,
    pub strain: N,
    pub measured: N,
    pub dancer_y: N,
    pub integrator: N,
    pub motor: N,
    pub dancer: N,
}

/// [R10]-[R11], [R13] at the roller's point.
#[inline(always)]
pub fn law<N: Number>(p: &Parameters, reads: &Reads, x: &Seen<N>) -> Law<N> {
    let kind = Kind::of(p);
    if kind == Kind::None {
        return Law::default();
    }
    let v_ref = reads.reference.map_or(p.loop_speed, |(v, _)| v);
    let mut dancer_rate = N::default();
    let e = match kind {
        Kind::None => return Law::default(),
        Kind::Force => (N::constant(reads.set) - x.measured) * p.loop_sign,
        Kind::Speed => N::constant(v_ref) - x.radius * x.omega,
        Kind::Dancer => {
            let (e_d, trim) = dancer(p, x.dancer_y, x.dancer);
            dancer_rate = e_d * p.dancer_ki;
            N::constant(v_ref) + trim - x.radius * x.omega
        }
    };
    let ff = match reads.reference {
        Some((v, a)) if p.loop_feedforward => feedforward(p, x.radius, x.inertia, x.strain, v, a),
        _ => N::default(),
    };
    let u = e * p.loop_kp + x.integrator + ff;
    let sat = {
        let (value, slope) = limit(p, u.value());
        u.map(value, slope)
    };
    let integrator_rate = e * p.loop_ki + (sat - u) * tracking(p);
    let applied = reads.held.map_or(sat, N::constant);
    let (torque, motor_rate) = if p.motor_lag > 0.0 { (x.motor, (applied - x.motor) / p.motor_lag) } else { (applied, N::default()) };
    Law { torque, command: sat, integrator_rate, motor_rate, dancer_rate }
}

/// A dancer loop's error e_d = loop.sign*(dancer.y - dancer.set) and speed trim [R13].
#[inline]
pub fn dancer<N: Number>(p: &Parameters, y: N, integrator: N) -> (N, N) {
    let e = (y - p.dancer_set) * p.loop_sign;
    (e, e * p.dancer_kp + integrator)
}

/// 1/T_t of the back-calculation [R10]: ki/kp, or 1/s where either gain is 0 (a pure P or I loop).
#[inline]
pub fn tracking(p: &Parameters) -> f64 {
    if p.loop_kp > 0.0 && p.loop_ki > 0.0 {
        p.loop_ki / p.loop_kp
    } else {
        1.0
    }
}

/// The loop's parameters checked when initialization ends: None if they fit.
pub fn refusal(p: &Parameters) -> Option<String> {
    if Kind::of(p) == Kind::None {
        return None;
    }
    if p.speed_input {
        return Some(format!("loop.kind = {} with speed.input = true: an ideal speed drive has no loop (a speed loop takes loop.speed itself)", p.loop_kind));
    }
    if p.traction {
        return Some("loop.kind > 0 with includeTraction = true: a loop on a roller where the web may slip is not modelled".into());
    }
    if p.loop_sample > 0.0 && p.loop_sample < MIN_SAMPLE {
        return Some(format!("loop.sample = {} s: a sampled loop's period is 0 (continuous) or at least {MIN_SAMPLE} s", p.loop_sample));
    }
    if p.loop_sample > 0.0 && p.loop_delay > p.loop_sample {
        return Some(format!("loop.delay = {} s with loop.sample = {} s: a sampled loop's delay is at most its period", p.loop_delay, p.loop_sample));
    }
    None
}

/// A force loop's set point `loop.set` = `value` <= 0 N where `loop.compression` does not say that
/// compression is meant: refused when set after initialization, warned about when it ends. None if it fits.
pub fn set_point_refusal(p: &Parameters, value: f64) -> Option<String> {
    (Kind::of(p) == Kind::Force && !p.loop_compression && !(value > 0.0)).then(|| {
        format!("loop.set = {value} N: a force loop's set point must be > 0 N (a web in compression buckles); loop.compression = true (a scene's \"compression\": true) allows it")
    })
}

/// A warning where a continuous loop is given a delay, which only a sampled one has [R14].
pub fn unsampled_delay(p: &Parameters) -> Option<String> {
    (Kind::of(p) != Kind::None && p.loop_sample == 0.0 && p.loop_delay > 0.0)
        .then(|| format!("loop.delay = {} s is not applied: only a sampled loop (loop.sample > 0) has a delay", p.loop_delay))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::number::Tangent;
    use std::f64::consts::PI;

    fn limited(l: f64) -> Parameters {
        Parameters { motor_limit: l, loop_kp: 0.2, loop_ki: 2.0, ..Default::default() }
    }

    /// The limit is the identity inside its bend, never exceeds L, and its slope is continuous.
    #[test]
    fn limit_is_exact_inside_bounded_and_smooth() {
        let p = limited(50.0);
        assert_eq!(limit(&p, 47.4), (47.4, 1.0));
        assert_eq!(limit(&p, -47.4), (-47.4, 1.0));
        for u in [47.6, 50.0, 60.0, 1e3, 1e9] {
            let (x, s) = limit(&p, u);
            assert!(x <= 50.0 && x > 47.5 && s >= 0.0 && s < 1.0, "u = {u}: {x} {s}");
            let h = 1e-6;
            let fd = (limit(&p, u + h).0 - limit(&p, u - h).0) / (2.0 * h);
            assert!((fd - s).abs() < 1e-6, "u = {u}: slope {s}, difference {fd}");
        }
        let (below, above) = (limit(&p, 47.5 - 1e-9).1, limit(&p, 47.5 + 1e-9).1);
        assert!((below - above).abs() < 1e-9);
        assert_eq!(limit(&limited(0.0), 1e6), (1e6, 1.0));
    }

    /// The feed-forward's slopes in r and in the web's strain against central differences, on a
    /// roll being wound.
    #[test]
    fn feedforward_slopes_in_r_and_strain() {
        let p = Parameters { roll: 1, wound_thickness: 1e-4, wound_density: 800.0, wound_width: 1.2, ..Default::default() };
        let (r, v, a, eps) = (0.6, 6.0, 0.4, 2e-3);
        let j = |r: f64| 40.0 + 0.5 * PI * 800.0 * 1.2 * (r.powi(4) - 0.6f64.powi(4));
        let dj = 4.0 * 0.5 * PI * 800.0 * 1.2 * r.powi(3);
        let d = feedforward(&p, Tangent::new(r, 1.0), Tangent::new(j(r), dj), Tangent::new(eps, 0.0), v, a).d;
        let h = 1e-6;
        let fd = (feedforward(&p, r + h, j(r + h), eps, v, a) - feedforward(&p, r - h, j(r - h), eps, v, a)) / (2.0 * h);
        assert!((d - fd).abs() < 1e-6 * fd.abs().max(1.0), "{d} vs {fd}");
        let d = feedforward(&p, Tangent::new(r, 0.0), Tangent::new(j(r), 0.0), Tangent::new(eps, 1.0), v, a).d;
        let fd = (feedforward(&p, r, j(r), eps + h, v, a) - feedforward(&p, r, j(r), eps - h, v, a)) / (2.0 * h);
        assert!((d - fd).abs() < 1e-6 * fd.abs().max(1e-3), "{d} vs {fd}");
        // -J r' v/r^2 with r' = -h v/(2 pi r (1 + eps)) of an unwinder.
        let expected = j(r) * a / r + j(r) * 1e-4 * v * v / (2.0 * PI * r.powi(3) * (1.0 + eps));
        assert!((feedforward(&p, r, j(r), eps, v, a) - expected).abs() < 1e-12 * expected);
    }
}
