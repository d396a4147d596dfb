//! The roller's communication step: the profile's `set` events, and the pieces between the
//! tables' breaks, each stepped exactly where its equations are linear ([R1] with r and J held,
//! [R4]) and by an L-stable Rosenbrock method on the right-hand side (`rhs`) where they are not
//! (the web's slip [R6]-[R7], a loop [R10]-[R11], a brake [R12]).

use crate::parameters::Kind;
use crate::drive::{self, Drive, Key};
use crate::model::Roller;
use crate::rhs::{self, Point};
use crate::roll::{self, Roll};
use crate::state::{State, States};
use crate::{bristle, carriage, physics};
use fmi_core::{FmiError, FmiResult};
use profiles::Value;
use solver::CompensatedSum;

/// The most samples of a sampled loop [R14] one communication step may cross.
const MAX_SAMPLES_PER_STEP: f64 = 1e5;

impl Roller {
    /// Applies the `set` events due at t; whether one changed the roll.
    pub(crate) fn apply_due(&mut self, t: f64) -> bool {
        self.events_at = self.events_at.max(t);
        let Some(loaded) = self.profile.clone() else { return false };
        let mut rolled = false;
        while let Some(event) = loaded.profile.events.get(self.next_event).filter(|e| profiles::due(e.time, t)) {
            let speed = physics::surface_speed(self.roll.radius, self.omega.value());
            let mut new_roll = false;
            for (name, value) in &event.changes {
                let Value::Number(x) = *value else { continue }; // checked when the profile was read
                match name.as_str() {
                    "J" => (self.params.inertia, new_roll) = (x, true),
                    "R" => (self.params.radius, new_roll) = (x, true),
                    _ => self.params.damping = x,
                }
            }
            if new_roll {
                // A new roll at the same web speed.
                self.roll = Roll::new(self.params.radius, self.params.inertia);
                self.omega = CompensatedSum::from_parts(speed / self.roll.radius, 0.0);
                rolled = true;
            }
            self.next_event += 1;
        }
        rolled
    }

    /// One piece of a step, [t, t+h], over which every table is linear.
    fn piece(&mut self, t: f64, h: f64) -> FmiResult {
        let p = &self.params;
        let r = self.roll.radius;
        let prescribed = self.prescribed(t); // at the piece's start, after its events
        let (mut v_web, mut grip) = (self.v_web, self.grip);
        // [R1] is linear in omega without a loop, a brake or bearings whose torque is not -b*omega.
        // Nor with runout [R15]: the web's arm moves with the roll's angle.
        // Nor with a lay-on roller [R18]: its nip.
        let linear = roll::bearing_damping(p).filter(|_| Kind::of(p) == Kind::None && self.table(Key::Brake).is_none() && !p.runout && !p.layon);
        let Some(damping) = linear else {
            // A loop [R10]-[R11] or a brake [R12] (no speed table, no slip: refused), runout [R15] or a lay-on
            // roller [R18]: the loop's integrator, its motor and the roll's own (omega, r, angle), with J moving
            // with r, and the lay-on roller's states where it has one, by the same L-stable method.
            return if p.layon { self.controlled_piece(t, h, &CONTROLLED_LAYON) } else { self.controlled_piece(t, h, &CONTROLLED) };
        };
        // The web's strain at the roll [R3]: the inputs are held, a table read at the piece's middle.
        let strain = rhs::roll_strain(p, self.value(Key::Strain, t + 0.5 * h).map(|(x, _)| x), &self.inputs.strain_a);
        let (omega, travel) = match prescribed {
            _ if p.traction => {
                // [R6]-[R7] are nonlinear and stiff (the friction's slope over the web's small mass):
                // an L-stable Rosenbrock method on (omega, v_web), the inputs held. No roll winds here.
                let y = self.slipping_step(t, h)?;
                (v_web, grip) = (y[1], y[2]);
                (CompensatedSum::from_parts(y[0], 0.0), 0.0)
            }
            Some((v0, slope)) => {
                let v1 = v0 + slope * h; // the left limit at a jump that ends the piece
                (CompensatedSum::from_parts(v1 / r, 0.0), 0.5 * (v0 + v1) * h)
            }
            None => {
                let (tau0, tau1) = self.torque_at(t);
                let next = physics::rotation_step(p, &self.roll, &self.inputs, self.omega, damping, tau0, tau1, h);
                let mean = 0.5 * (self.omega.value() + next.value());
                // At the piece's mean radius: r moves linearly at a steady omega [R3], so that a roll
                // turning steadily winds exactly (one that would empty within the piece: its start's,
                // and `wound_radius` says it ran empty).
                let radius = Some(r + 0.5 * roll::radius_rate(p, r, r * mean, strain) * h).filter(|&m| m > 0.0).unwrap_or(r);
                (next, radius * mean * h)
            }
        };
        let (mut omega, mut roll) = (omega, self.roll);
        if p.winding() {
            let radius = roll::wound_radius(p, r, travel, strain).ok_or_else(|| {
                FmiError::discard(format!("the roll ran empty: its radius {r} m would fall to 0 after {travel} m of web; check R and wound.thickness"))
            })?;
            let inertia = roll.inertia_at(p, radius);
            // A prescribed surface keeps its speed; else [R1] keeps omega across the change of J
            // (the web that left or arrived took its own angular momentum with it).
            if prescribed.is_some() {
                omega = CompensatedSum::from_parts(omega.value() * r / radius, 0.0);
            }
            roll = Roll { radius, inertia, ..roll };
        }
        let carriage = if p.carriage {
            let (g0, g1) = self.carriage_force(t);
            carriage::step(p, self.carriage, g0, g1, h)
        } else {
            self.carriage
        };
        if !(omega.value().is_finite() && physics::surface_speed(roll.radius, omega.value()).is_finite() && carriage.iter().all(|x| x.is_finite())) {
            return Err(FmiError::discard(format!(
                "the roller would reach omega = {} rad/s, carriage (y, y') = ({}, {}) (J = {} kg.m2, web torque {} N.m): \
                 take a shorter step or check the inputs",
                omega.value(),
                carriage[0],
                carriage[1],
                roll.inertia,
                physics::web_torque(p, r, &self.inputs)
            )));
        }
        (self.omega, self.roll, self.carriage, self.v_web, self.grip) = (omega, roll, carriage, v_web, grip);
        Ok(())
    }

    /// (omega, v_web, grip) after [t, t+h] of a piece [R6]-[R7], the inputs held.
    fn slipping_step(&self, t: f64, h: f64) -> FmiResult<[f64; 3]> {
        let y0 = [self.omega(), self.v_web, self.grip];
        let scale = |x: f64| SLIP_ATOL * x.abs().max(1.0);
        let control = solver::Control { rtol: SLIP_RTOL, atol: y0.map(scale), initial_step: h, max_steps: 100_000 };
        solver::rosenbrock::integrate(&Slipping { roller: self, t0: t }, h, y0, &control)
            .map(|solution| solution.y)
            .map_err(|failure| FmiError::discard(format!("the web's slip on the roller could not be followed over the step ({failure:?}): take a shorter step")))
    }

    /// A piece with a loop [R10]-[R11], [R13], a brake [R12], runout [R15] or a lay-on roller [R18]: `states`
    /// after [t, t+h] by the L-stable method, the inputs held; the carriage of a dancer by its own exact step.
    fn controlled_piece<const N: usize>(&mut self, t: f64, h: f64, states: &[State; N]) -> FmiResult {
        let p = &self.params;
        let y = self.controlled_step(t, h, states)?;
        let carriage = if p.carriage {
            let (g0, g1) = self.carriage_force(t);
            carriage::step(p, self.carriage, g0, g1, h)
        } else {
            self.carriage
        };
        if !(y.iter().all(|x| x.is_finite()) && y[1] > 0.0 && carriage.iter().all(|x| x.is_finite())) {
            return Err(FmiError::discard(format!("the roller's loop would reach {states:?} = {y:?}: take a shorter step or check the inputs")));
        }
        self.take(states, &y);
        self.carriage = carriage;
        Ok(())
    }

    /// `states` after [t, t+h] of a piece with a loop [R10]-[R11], [R13], a brake [R12], runout [R15] or a
    /// lay-on roller [R18], the inputs held.
    fn controlled_step<const N: usize>(&self, t: f64, h: f64, states: &[State; N]) -> FmiResult<[f64; N]> {
        let held = self.held();
        let y0 = states.map(|s| held.get(s));
        let scale = |x: f64| SLIP_ATOL * x.abs().max(1.0);
        let control = solver::Control { rtol: SLIP_RTOL, atol: y0.map(scale), initial_step: h, max_steps: 100_000 };
        solver::rosenbrock::integrate(&Controlled { roller: self, t0: t, states }, h, y0, &control)
            .map(|solution| solution.y)
            .map_err(|failure| FmiError::discard(format!("the roller's loop could not be followed over the step ({failure:?}): take a shorter step")))
    }

    /// Sets `states` to y (J moves with r [R3]); the others as they are.
    fn take<const N: usize>(&mut self, states: &[State; N], y: &[f64; N]) {
        let mut x = self.held();
        for (&s, &value) in states.iter().zip(y) {
            *x.get_mut(s) = value;
        }
        self.place(&x);
    }

    /// The roller at time t with `states` at y, the rest as now (a step's trial point).
    fn at_trial<const N: usize>(&self, t: f64, states: &[State; N], y: &[f64; N]) -> Roller {
        let mut trial = self.clone();
        trial.take(states, y);
        trial.time = t;
        trial
    }

    /// A communication step [time, time+h], split where a table kinks or jumps
    /// and where a `set` event falls; one at the end (within the profiles'
    /// tolerance) applies at the start of the next step.
    pub(crate) fn advance(&mut self, h: f64) -> FmiResult {
        let curved = |l: &drive::Loaded| l.tables.iter().zip(drive::TABLES).find_map(|(t, key)| t.as_ref().filter(|t| t.is_curved()).map(|_| key));
        if let Some(key) = self.profile.as_ref().and_then(curved) {
            return Err(FmiError::error(format!(
                "the profile's {key} table has a quadratic piece (an S-curve): this Co-Simulation step takes a table as linear \
                 over a piece; run the line as one Line FMU, or in Model Exchange"
            )));
        }
        if roll::stepped(&self.params) {
            return Err(FmiError::error(format!(
                "wound.merge = {} rad: a stepwise radius [R17] runs in Model Exchange and in the Line FMU; this Co-Simulation \
                 step holds the radius over a piece (give wound.merge = 0, or run the line as one Line FMU)",
                self.params.wound_merge
            )));
        }
        // A sampled loop's holds are time events: bound the pieces one step may take (the fuzzer found a
        // step of many seconds over a microsecond sample that ran for hours).
        if self.params.sampled() && h / self.params.loop_sample > MAX_SAMPLES_PER_STEP {
            return Err(FmiError::discard(format!(
                "a step of {h} s holds {:.0} samples of loop.sample = {} s, more than {MAX_SAMPLES_PER_STEP} in one step: take a shorter step",
                h / self.params.loop_sample,
                self.params.loop_sample
            )));
        }
        let end = self.time + h;
        let last = end - profiles::tolerance(end);
        let mut t = self.time;
        loop {
            self.apply_due(t);
            self.hold_due(t);
            let stop = self.next_event_after(t).filter(|&b| b < last).unwrap_or(end);
            if stop > t {
                self.piece(t, stop - t)?;
            }
            t = stop;
            if t >= end {
                break;
            }
        }
        self.time = end;
        // A master holds the outputs over the next step: at its end, read the tables after a break
        // there (its `set` events still apply when the next step starts).
        self.events_at = end;
        Ok(())
    }

    /// The next time event after t: a profile's break or `set` event, a sampled loop's sample or
    /// application [R14].
    pub(crate) fn next_event_after(&self, t: f64) -> Option<f64> {
        self.profile.as_ref().and_then(|l| l.profile.next_break(t)).into_iter().chain(self.next_hold_event()).reduce(f64::min)
    }

    pub(crate) fn start(&mut self, time: f64) {
        let p = &self.params;
        self.roll = Roll::new(p.radius, p.inertia);
        let speed = match (self.drive(), self.table(Key::Speed)) {
            _ if p.speed_input => p.loop_speed,
            (Drive::Speed, Some(t)) => t.value(time),
            _ => p.speed_start,
        };
        self.omega = CompensatedSum::from_parts(speed / p.radius, 0.0);
        self.carriage = [p.carriage_start, 0.0];
        self.v_web = speed + p.traction_slip_start;
        self.time = time;
        self.events_at = time;
        self.next_event = 0;
        (self.integrator, self.motor, self.dancer) = (0.0, 0.0, 0.0);
        // A web that starts slipping, a brake that starts turning, start sliding: their bristles at
        // their sliding deflection (at u = 0 their damping would carry |s|/v_slip times the limit).
        self.grip = if p.traction { bristle::sliding(p.traction_slip_start, p.traction_static, p.traction_v_slip) } else { 0.0 };
        self.brake_grip = if self.braked() { bristle::sliding(speed, 1.0, p.brake_v_slip) } else { 0.0 };
        self.angle = 0.0;
        // Pressed by its load at the start on the roll as it stands, at rest, turning with the surface [R18].
        let load = self.value(Key::Layon, time).map_or(p.layon_f, |(f, _)| f);
        self.layon = if p.layon { crate::layon::start(p, p.radius, speed / p.radius, load) } else { [0.0; 3] };
        self.restart_hold(time);
    }
}


/// The roller's own step where the web may slip: tight, as the Line's tolerance is, so that a
/// co-simulation's error is its coupling's.
const SLIP_RTOL: f64 = 1e-10;
const SLIP_ATOL: f64 = 1e-12;

/// [R6]-[R7] over a piece, as an ODE in (omega, v_web, grip) from the piece's start t0.
struct Slipping<'a> {
    roller: &'a Roller,
    t0: f64,
}

impl Slipping<'_> {
    /// The roller at time t0 + s with (omega, v_web, grip) at y: what the equations read there, its states.
    fn trial(&self, s: f64, y: &[f64; 3]) -> (Point, States) {
        let x = States { omega: y[0], web_speed: y[1], grip: y[2], ..self.roller.held() };
        (self.roller.point_at(self.t0 + s, &x), x)
    }
}

impl solver::Ode<3> for Slipping<'_> {
    fn rhs(&self, s: f64, y: &[f64; 3]) -> [f64; 3] {
        let (point, x) = self.trial(s, y);
        let d = rhs::rates(&self.roller.params, &point, &x, &self.roller.inputs).derivatives;
        SLIPPING.map(|i| d.get(i))
    }

    fn jacobian(&self, s: f64, y: &[f64; 3]) -> [[f64; 3]; 3] {
        let (point, x) = self.trial(s, y);
        self.roller.rate_jacobian(&point, &x, SLIPPING)
    }

    /// Tables of time (a drive's ramp, the nip's load) move f at fixed y: a central difference.
    fn time_derivative(&self, s: f64, y: &[f64; 3]) -> [f64; 3] {
        time_derivative(self, self.roller, self.t0, s, y)
    }
}

/// The states the slip's step integrates.
const SLIPPING: [State; 3] = [State::Omega, State::WebSpeed, State::Grip];

/// df/dt at fixed y of a piece's ODE from t0: where a table of time has a slope, a central difference.
fn time_derivative<const N: usize>(ode: &impl solver::Ode<N>, roller: &Roller, t0: f64, s: f64, y: &[f64; N]) -> [f64; N] {
    if !roller.varies_with_time(t0 + s) {
        return [0.0; N];
    }
    let e = 1e-7 * (t0 + s).abs().max(1e-3);
    let (hi, lo) = (ode.rhs(s + e, y), ode.rhs(s - e, y));
    std::array::from_fn(|i| (hi[i] - lo[i]) / (2.0 * e))
}

/// [R1], [R3], [R10]-[R13], [R15], [R18] over a piece, as an ODE in `states` from the piece's start t0; its
/// Jacobian from the right-hand side's tangents.
struct Controlled<'a, const N: usize> {
    roller: &'a Roller,
    t0: f64,
    states: &'a [State; N],
}

/// The states the loop's step integrates, and with a lay-on roller's.
const CONTROLLED: [State; 7] = [State::Omega, State::Radius, State::LoopIntegrator, State::MotorTorque, State::DancerIntegrator, State::BrakeGrip, State::Angle];
const CONTROLLED_LAYON: [State; 10] = [
    State::Omega,
    State::Radius,
    State::LoopIntegrator,
    State::MotorTorque,
    State::DancerIntegrator,
    State::BrakeGrip,
    State::Angle,
    State::LayonX,
    State::LayonSpeed,
    State::LayonSpin,
];

impl<const N: usize> solver::Ode<N> for Controlled<'_, N> {
    fn rhs(&self, s: f64, y: &[f64; N]) -> [f64; N] {
        let d = self.roller.at_trial(self.t0 + s, self.states, y).rates();
        self.states.map(|i| d.get(i))
    }

    fn jacobian(&self, s: f64, y: &[f64; N]) -> [[f64; N]; N] {
        let trial = self.roller.at_trial(self.t0 + s, self.states, y);
        trial.rate_jacobian(&trial.point(), &trial.held(), *self.states)
    }

    /// Tables of time (a set point's or a reference's ramp) move f at fixed y: a central difference.
    fn time_derivative(&self, s: f64, y: &[f64; N]) -> [f64; N] {
        time_derivative(self, self.roller, self.t0, s, y)
    }
}
