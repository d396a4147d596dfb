//! The roller's data, one communication step, and the hooks the FMI layer
//! calls (initialization, steps, Model Exchange, FMU states). Its equations
//! are in `physics`, its drive and tables in `drive`.

use crate::contact;
use crate::control::{self, Kind};
use crate::description::{Real, DESCRIPTION};
use crate::drive::{self, Drive, Key, Loaded};
use crate::jacobian::{Direction, Linearization, Point, Tangents};
use crate::parameters::{Inputs, Parameters, STATES};
use crate::physics::{self, Roll};
use fmi_core::{Compiled, EventUpdate, Experiment, FmiError, FmiResult, Jacobian, Model, Resources, StateReader, StateWriter};
use profiles::Value;
use solver::CompensatedSum;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Roller {
    pub params: Parameters,
    pub inputs: Inputs,
    /// Angular speed, rad/s, a compensated sum: a million tiny steps do not drift.
    omega: CompensatedSum,
    roll: Roll,
    /// Carriage travel y (down positive) and speed.
    pub(crate) carriage: [f64; 2],
    /// The web's speed over the roller [R6] (with traction; else the surface's, unused).
    v_web: f64,
    /// The time now, s: profiles are tables of it.
    time: f64,
    /// The time up to which the profile's breaks and events are applied. Later, a table is read on
    /// the piece that reaches the time now: at a jump not yet applied, its value before the jump.
    events_at: f64,
    /// The profile's next `set` event not yet applied.
    next_event: usize,
    /// The loop's integrator and its motor's lagged torque [R10]-[R11] (0 without a loop).
    integrator: f64,
    motor: f64,
    /// A dancer loop's integrator [R13], a speed trim (0 without one).
    dancer: f64,
    profile: Option<Loaded>,
}

impl Roller {
    /// Sets the Model Exchange states at `active` (indices into (omega, r, y, y', v_web)) to `x`, the
    /// others kept: what `set_continuous_states` does with the full vector, without forming it
    /// where only omega moves (a roller that neither winds nor carries a dancer).
    pub fn set_active_states(&mut self, active: &[usize], x: &[f64]) -> FmiResult {
        if let ([0], &[omega]) = (active, x) {
            self.omega = CompensatedSum::from_parts(omega, 0.0);
            return Ok(());
        }
        let mut full = [0.0; STATES];
        self.get_continuous_states(&mut full)?;
        for (&i, &value) in active.iter().zip(x) {
            full[i] = value;
        }
        self.set_continuous_states(&full)
    }

    pub fn omega(&self) -> f64 {
        self.omega.value()
    }

    pub fn radius(&self) -> f64 {
        self.roll.radius
    }

    #[inline]
    fn drive(&self) -> Drive {
        if self.params.speed_input {
            return Drive::Speed;
        }
        self.profile.as_ref().map_or(Drive::Torque, |l| l.drive)
    }

    /// A speed drive's surface speed and its slope at t (the time now, or a piece's start): its
    /// table's, or `loop.speed` held over the step, slope 0, where `speed.input` is true.
    #[inline]
    fn prescribed(&self, t: f64) -> Option<(f64, f64)> {
        if self.params.speed_input {
            return Some((self.params.loop_speed, 0.0));
        }
        self.table(Key::Speed).filter(|_| self.drive() == Drive::Speed).map(|table| self.read(table, t))
    }

    /// The surface speed follows a speed table (a source, a sink, a speed
    /// drive): forces do not move it.
    pub fn speed_prescribed(&self) -> bool {
        self.drive() == Drive::Speed
    }

    #[inline]
    fn table(&self, key: Key) -> Option<&profiles::Table> {
        self.profile.as_ref().and_then(|l| l.table(key))
    }

    /// A table's value and slope at t (the time now, or a piece's start).
    #[inline]
    fn read(&self, table: &profiles::Table, t: f64) -> (f64, f64) {
        if t > self.events_at {
            let within = profiles::tolerance(t).min(t - self.events_at);
            table.before(t, within)
        } else {
            (table.value(t), table.slope(t))
        }
    }

    /// v [R2]; a speed drive's profile at the time now.
    #[inline]
    pub fn surface_speed(&self) -> f64 {
        match self.prescribed(self.time) {
            Some((v, _)) => v,
            None => physics::surface_speed(self.roll.radius, self.omega.value()),
        }
    }

    /// The web's speed over the roller [R6]: the surface's where the web cannot slip.
    #[inline]
    pub fn web_speed(&self) -> f64 {
        if self.params.traction {
            self.v_web
        } else {
            self.surface_speed()
        }
    }

    /// v_web - v [R6].
    pub fn slip(&self) -> f64 {
        self.web_speed() - self.surface_speed()
    }

    /// The contact's state now [R6]–[R8].
    fn contact_state(&self) -> contact::State {
        self.contact_state_at(self.time, self.omega(), self.v_web)
    }

    /// The contact's state at time t with the roller at omega and the web at v_web (a step's trial point).
    fn contact_state_at(&self, t: f64, omega: f64, v_web: f64) -> contact::State {
        let (u, r) = (&self.inputs, self.roll.radius);
        let v_surface = match self.prescribed(t) {
            Some((v, _)) => v,
            None => physics::surface_speed(r, omega),
        };
        contact::State {
            v_web,
            v_surface,
            t_a: u.force_a[0],
            t_b: u.force_b[0],
            nip_load: self.table(Key::Nip).map_or(0.0, |table| self.read(table, t).0),
            radius: r,
        }
    }

    /// The coefficient of friction after the air film [R8] (0 without traction).
    pub fn mu_eff(&self) -> f64 {
        if self.params.traction {
            contact::contact(&self.params, &self.contact_state()).mu_eff.x
        } else {
            0.0
        }
    }

    /// The air film's thickness [R8] (0 without traction or air).
    pub fn h_air(&self) -> f64 {
        if self.params.traction {
            contact::contact(&self.params, &self.contact_state()).h_air.x
        } else {
            0.0
        }
    }

    /// The share of the available traction in use [R7] (0 without traction).
    pub fn traction_used(&self) -> f64 {
        if !self.params.traction {
            return 0.0;
        }
        let state = self.contact_state();
        contact::traction_used(&self.params, &state, contact::contact(&self.params, &state).mu_eff).x
    }

    /// The webs' torque on the roller: r*(F_b - F_a) [R1], or with traction the friction's, -r*f [R6].
    #[inline]
    fn web_torque(&self) -> f64 {
        let friction = self.params.traction.then(|| {
            let state = self.contact_state();
            (state, contact::contact(&self.params, &state).force)
        });
        self.web_torque_with(friction)
    }

    /// `web_torque` with the friction where the web may slip, as found.
    #[inline]
    fn web_torque_with(&self, friction: Option<(contact::State, contact::Dual)>) -> f64 {
        match friction {
            Some((_, f)) => -self.roll.radius * f.x,
            None => physics::web_torque(&self.params, self.roll.radius, &self.inputs),
        }
    }

    /// Whether the equations depend on time at fixed states and inputs on the
    /// piece of the profile they read at t: one of its tables has a slope there.
    pub fn varies_with_time(&self, t: f64) -> bool {
        self.profile.as_ref().is_some_and(|l| l.tables.iter().flatten().any(|table| self.read(table, t).1 != 0.0))
    }

    /// The strain of the web leaving at outlet `outlet` (0-based): the profile's, else the arriving
    /// web's, merged [R5] when several arrive, or where they stay layers its own inlet's [R9].
    pub fn strain_leaving(&self, outlet: usize) -> f64 {
        match self.table(Key::Strain) {
            Some(t) => self.read(t, self.time).0,
            None if self.params.layered => self.inputs.strain_a[physics::layer_inlet(&self.params, outlet)],
            None => physics::merged_strain(&self.params, &self.inputs.strain_a),
        }
    }

    /// The load cell's reading for a wrap angle with this cosine (the Line's `NAME.F`).
    pub fn load_cell(&self, cos_wrap: f64) -> f64 {
        let (p, u) = (&self.params, &self.inputs);
        physics::load_cell(u.pull_back(p), u.pull_forward(p), cos_wrap)
    }

    /// The output load_cell.F: the load cell at its own wrap `load_cell.wrap` (0: none, F = 0).
    pub fn load_cell_force(&self) -> f64 {
        if self.params.load_cell_wrap > 0.0 {
            self.load_cell(self.params.load_cell_wrap.cos())
        } else {
            0.0
        }
    }

    /// The drive's torque at time t, and its rate (a speed drive: 0, see
    /// `drive_torque`). The profile has at most one drive table.
    #[inline]
    fn torque_at(&self, t: f64) -> (f64, f64) {
        let tau_m = self.inputs.torque;
        if let Some(table) = self.table(Key::Torque) {
            let (x, rate) = self.read(table, t);
            (tau_m + x, rate)
        } else if let Some(table) = self.table(Key::Tension) {
            let s = self.params.roll_sign() * self.roll.radius;
            let (x, rate) = self.read(table, t);
            (tau_m + s * x, s * rate)
        } else {
            (tau_m, 0.0)
        }
    }

    /// The drive's torque now; a speed drive's is what [R1] needs to follow its profile.
    pub fn drive_torque(&self) -> f64 {
        match self.prescribed(self.time) {
            Some((_, slope)) => physics::speed_drive_torque(&self.params, &self.roll, self.web_torque(), self.omega.value(), slope),
            None => self.torque_at(self.time).0 + self.motor_torque() + self.brake().0,
        }
    }

    /// Whether the tangents along omega, the carriage and the inputs stay as they are until an event or
    /// a parameter changes them (`jacobian::tangents_fixed`; a brake [R12] is nonlinear in omega).
    pub fn tangents_fixed(&self) -> bool {
        crate::jacobian::tangents_fixed(&self.params) && self.table(Key::Brake).is_none()
    }

    /// A powder brake's torque now and its slope in the surface speed [R12] (0 without a brake table).
    #[inline]
    fn brake(&self) -> (f64, f64) {
        match self.table(Key::Brake) {
            Some(table) => physics::brake_torque(self.read(table, self.time).0, physics::surface_speed(self.roll.radius, self.omega.value()), self.params.brake_v_slip),
            None => (0.0, 0.0),
        }
    }

    /// The loop's integrator [R10] (0 without a loop).
    pub fn loop_integrator(&self) -> f64 {
        self.integrator
    }

    /// A dancer loop's integrator [R13] (0 without one).
    pub fn dancer_integrator(&self) -> f64 {
        self.dancer
    }

    /// The lag's state [R11]: the motor's torque where it lags its command (0 without a lag).
    pub fn motor_state(&self) -> f64 {
        self.motor
    }

    /// The torque the loop's motor gives now [R11] (0 without a loop).
    pub fn motor_torque(&self) -> f64 {
        self.control().map_or(0.0, |c| c.law.torque)
    }

    /// The loop now [R10]-[R11], None without one.
    #[inline]
    fn control(&self) -> Option<control::Point> {
        let p = &self.params;
        let kind = Kind::of(p);
        if kind == Kind::None {
            return None;
        }
        let (r, omega) = (self.roll.radius, self.omega.value());
        let reference = self.table(Key::Reference).map(|t| self.read(t, self.time));
        let v_ref = reference.map_or(p.loop_speed, |(v, _)| v);
        let (mut dancer_rate, mut dancer_rate_dy) = (0.0, 0.0);
        let (e, de) = match kind {
            Kind::Force => {
                let set = self.table(Key::Set).map_or(p.loop_set, |t| self.read(t, self.time).0);
                (p.loop_sign * (set - self.inputs.measured), [-p.loop_sign, 0.0, 0.0, 0.0, 0.0])
            }
            Kind::Dancer => {
                let (e_d, trim) = control::dancer(p, self.inputs.dancer_y, self.dancer);
                (dancer_rate, dancer_rate_dy) = (p.dancer_ki * e_d, p.dancer_ki * p.loop_sign);
                (v_ref + trim - r * omega, [0.0, -r, -omega, p.dancer_kp * p.loop_sign, 1.0])
            }
            _ => (v_ref - r * omega, [0.0, -r, -omega, 0.0, 0.0]),
        };
        let (ff, dff_r) = match reference {
            Some((v, a)) if p.loop_feedforward => control::feedforward(p, r, self.roll.inertia, v, a),
            _ => (0.0, 0.0),
        };
        Some(control::Point { law: control::evaluate(p, e, ff, self.integrator, self.motor), de, dff_r, dancer_rate, dancer_rate_dy })
    }

    /// The carriage's force (load minus every span's pull) [R4] at t, and its rate.
    fn carriage_force(&self, t: f64) -> (f64, f64) {
        let (p, u) = (&self.params, &self.inputs);
        let (load, rate) = self.table(Key::Load).map_or((0.0, 0.0), |l| self.read(l, t));
        (u.load + load - u.pull_back(p) - u.pull_forward(p), rate)
    }

    /// Where the webs touch the roller [R4]: web_a at x = 0, web_b at 2r.
    pub(crate) fn contact_a_x(&self) -> f64 {
        0.0
    }

    pub(crate) fn contact_b_x(&self) -> f64 {
        physics::contact_b_x(self.roll.radius)
    }

    /// Heights from the dancer's start position, up positive: 0 at the start,
    /// so a master that starts its inputs at 0 (FMPy) still sees a valid span.
    pub(crate) fn contact_y(&self) -> f64 {
        physics::contact_height(&self.params, self.carriage[0])
    }

    /// d/dt of (omega, r, y, y', v_web) now [R1]–[R4], [R6], for Model Exchange.
    pub fn derivatives(&self) -> [f64; STATES] {
        let p = &self.params;
        // The friction where the web may slip, once for both rates it moves.
        let friction = p.traction.then(|| {
            let state = self.contact_state();
            (state, contact::contact(p, &state).force)
        });
        let v = self.surface_speed();
        let control = self.control();
        let (radius_rate, inertia_rate) =
            if p.winding() { (self.roll.radius_rate(p, v), self.roll.inertia_rate(p, v)) } else { (0.0, 0.0) };
        let (omega_rate, surface_rate) = match self.prescribed(self.time) {
            Some((_, slope)) => {
                (physics::omega_rate_at_speed(slope, v, self.roll.radius, radius_rate), slope)
            }
            None => {
                let omega = self.omega.value();
                let torque = self.torque_at(self.time).0 + control.map_or(0.0, |c| c.law.torque) + self.brake().0;
                let rate = physics::omega_rate(p, &self.roll, self.web_torque_with(friction), omega, torque, inertia_rate);
                (rate, self.roll.radius * rate + omega * radius_rate)
            }
        };
        // Without traction the fifth state is the surface's speed, so its rate is the surface's.
        let v_web_rate = friction.map_or(surface_rate, |(state, f)| contact::web_acceleration(p, &state, f).x);
        let carriage = if p.carriage {
            [self.carriage[1], physics::carriage_acceleration(p, self.carriage, self.carriage_force(self.time).0)]
        } else {
            [0.0, 0.0]
        };
        let [integrator_rate, motor_rate] = control.map_or([0.0; 2], |c| c.law.rates);
        let dancer_rate = control.map_or(0.0, |c| c.dancer_rate);
        [omega_rate, radius_rate, carriage[0], carriage[1], v_web_rate, integrator_rate, motor_rate, dancer_rate]
    }

    /// The unit direction of one known: a state or an input (None: neither).
    pub fn direction(known: Real) -> Option<Direction> {
        let mut d = Direction::default();
        match known {
            Real::omega => d.state[0] = 1.0,
            Real::r => d.state[1] = 1.0,
            Real::y => d.state[2] = 1.0,
            Real::y_dot => d.state[3] = 1.0,
            Real::v_web => d.state[4] = 1.0,
            Real::loop_I => d.state[5] = 1.0,
            Real::motor_torque => d.state[6] = 1.0,
            Real::dancer_I => d.state[7] = 1.0,
            k => *Self::input_field(&mut d.u, k)? = 1.0,
        }
        Some(d)
    }

    /// d(everything)/d(direction) now.
    #[inline]
    pub fn tangents(&self, d: &Direction) -> Tangents {
        self.linearize().along(d)
    }

    /// What the tangents along every direction share: the roller's values now, its tables read
    /// at the time now.
    #[inline]
    pub fn linearize(&self) -> Linearization<'_> {
        let prescribed = self.prescribed(self.time);
        let tension = match (prescribed, self.drive()) {
            (None, Drive::Tension) => self.table(Key::Tension).map_or(0.0, |t| t.value(self.time)),
            _ => 0.0,
        };
        let point = Point {
            params: &self.params,
            inputs: &self.inputs,
            omega: self.omega(),
            roll: self.roll,
            speed: self.surface_speed(),
            speed_slope: match self.table(Key::Speed).filter(|_| self.drive() == Drive::Speed) {
                Some(t) if !self.params.speed_input => Some(t.slope(self.time)),
                _ => prescribed.map(|(_, slope)| slope),
            },
            tension,
            torque: if prescribed.is_some() { 0.0 } else { self.drive_torque() },
            strain_table: self.table(Key::Strain).is_some(),
            contact: self.params.traction.then(|| self.contact_state()),
            control: self.control(),
            brake_slope: self.brake().1,
        };
        point.linearize()
    }

    /// Applies the `set` events due at t; whether one changed the roll.
    fn apply_due(&mut self, t: f64) -> bool {
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
        let mut v_web = self.v_web;
        if Kind::of(p) != Kind::None || self.table(Key::Brake).is_some() {
            // A loop [R10]-[R11] or a brake [R12] (no speed table, no slip: refused): the loop's integrator,
            // its motor and the roll's own (omega, r), with J moving with r, by the same L-stable method.
            let y = self.controlled_step(t, h)?;
            let carriage = if p.carriage {
                let (g0, g1) = self.carriage_force(t);
                physics::carriage_step(p, self.carriage, g0, g1, h)
            } else {
                self.carriage
            };
            if !(y.iter().all(|x| x.is_finite()) && y[1] > 0.0 && carriage.iter().all(|x| x.is_finite())) {
                return Err(FmiError::discard(format!("the roller's loop would reach (omega, r, loop.I, motor.torque) = {y:?}: take a shorter step or check the inputs")));
            }
            let inertia = if p.winding() { self.roll.inertia_at(p, y[1]) } else { self.roll.inertia };
            self.omega = CompensatedSum::from_parts(y[0], 0.0);
            self.roll = Roll { radius: y[1], inertia, ..self.roll };
            (self.integrator, self.motor, self.dancer, self.carriage) = (y[2], y[3], y[4], carriage);
            return Ok(());
        }
        let (omega, travel) = match prescribed {
            _ if p.traction => {
                // [R6]-[R7] are nonlinear and stiff (the friction's slope over the web's small mass):
                // an L-stable Rosenbrock method on (omega, v_web), the inputs held. No roll winds here.
                let y = self.slipping_step(t, h)?;
                v_web = y[1];
                (CompensatedSum::from_parts(y[0], 0.0), 0.0)
            }
            Some((v0, slope)) => {
                let v1 = v0 + slope * h; // the left limit at a jump that ends the piece
                (CompensatedSum::from_parts(v1 / r, 0.0), 0.5 * (v0 + v1) * h)
            }
            None => {
                let (tau0, tau1) = self.torque_at(t);
                let next = physics::rotation_step(p, &self.roll, &self.inputs, self.omega, tau0, tau1, h);
                (next, 0.5 * r * (self.omega.value() + next.value()) * h)
            }
        };
        let (mut omega, mut roll) = (omega, self.roll);
        if p.winding() {
            let radius = physics::wound_radius(p, r, travel).ok_or_else(|| {
                FmiError::discard(format!("the roll ran empty: its radius {r} m would fall to 0 after {travel} m of web; check R and wound.thickness"))
            })?;
            let inertia = roll.inertia_at(p, radius);
            omega = match prescribed {
                Some(_) => CompensatedSum::from_parts(omega.value() * r / radius, 0.0),
                // [R1] keeps J*omega across the change of J.
                None => CompensatedSum::from_parts(omega.value() * roll.inertia / inertia, 0.0),
            };
            roll = Roll { radius, inertia, ..roll };
        }
        let carriage = if p.carriage {
            let (g0, g1) = self.carriage_force(t);
            physics::carriage_step(p, self.carriage, g0, g1, h)
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
        (self.omega, self.roll, self.carriage, self.v_web) = (omega, roll, carriage, v_web);
        Ok(())
    }

    /// (omega, v_web) after [t, t+h] of a piece [R6]-[R7], the inputs held.
    fn slipping_step(&self, t: f64, h: f64) -> FmiResult<[f64; 2]> {
        let y0 = [self.omega(), self.v_web];
        let scale = |x: f64| SLIP_ATOL * x.abs().max(1.0);
        let control = solver::Control { rtol: SLIP_RTOL, atol: [scale(y0[0]), scale(y0[1])], initial_step: h, max_steps: 100_000 };
        solver::rosenbrock::integrate(&Slipping { roller: self, t0: t }, h, y0, &control)
            .map(|solution| solution.y)
            .map_err(|failure| FmiError::discard(format!("the web's slip on the roller could not be followed over the step ({failure:?}): take a shorter step")))
    }

    /// (omega, r, loop.I, motor.torque, dancer.I) after [t, t+h] of a piece with a loop [R10]-[R11], [R13], the inputs held.
    fn controlled_step(&self, t: f64, h: f64) -> FmiResult<[f64; 5]> {
        let y0 = [self.omega(), self.roll.radius, self.integrator, self.motor, self.dancer];
        let scale = |x: f64| SLIP_ATOL * x.abs().max(1.0);
        let control = solver::Control { rtol: SLIP_RTOL, atol: y0.map(scale), initial_step: h, max_steps: 100_000 };
        solver::rosenbrock::integrate(&Controlled { roller: self, t0: t }, h, y0, &control)
            .map(|solution| solution.y)
            .map_err(|failure| FmiError::discard(format!("the roller's loop could not be followed over the step ({failure:?}): take a shorter step")))
    }

    /// The roller at time t with (omega, r, loop.I, motor.torque, dancer.I) at y, the rest as now (a step's trial point).
    fn at_trial(&self, t: f64, y: &[f64; 5]) -> Roller {
        let mut trial = self.clone();
        let inertia = if self.params.winding() { self.roll.inertia_at(&self.params, y[1]) } else { self.roll.inertia };
        trial.omega = CompensatedSum::from_parts(y[0], 0.0);
        trial.roll = Roll { radius: y[1], inertia, ..self.roll };
        (trial.integrator, trial.motor, trial.dancer, trial.time) = (y[2], y[3], y[4], t);
        trial
    }

    /// A communication step [time, time+h], split where a table kinks or jumps
    /// and where a `set` event falls; one at the end (within the profiles'
    /// tolerance) applies at the start of the next step.
    fn advance(&mut self, h: f64) -> FmiResult {
        let end = self.time + h;
        let last = end - profiles::tolerance(end);
        let mut t = self.time;
        loop {
            self.apply_due(t);
            let stop = self.profile.as_ref().and_then(|l| l.profile.next_break(t)).filter(|&b| b < last).unwrap_or(end);
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

    fn start(&mut self, time: f64) {
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
    }
}

impl Model for Roller {
    fn instantiate(_: &Resources) -> FmiResult<Self> {
        Ok(Self::at_start_values())
    }

    #[inline(always)]
    fn description(&self) -> &'static fmi_core::description::ModelDescription {
        &DESCRIPTION
    }

    fn save_state(&self, out: &mut StateWriter) {
        out.f64(self.omega.hi());
        out.f64(self.omega.lo());
        let r = &self.roll;
        for x in [r.radius, r.inertia, r.reference_radius, r.reference_inertia, self.carriage[0], self.carriage[1], self.v_web, self.integrator, self.motor, self.dancer, self.time, self.events_at] {
            out.f64(x);
        }
        out.i32(self.next_event as i32);
        out.str(self.profile.as_ref().map_or("", |l| &l.text));
    }

    fn load_state(&mut self, r: &mut StateReader) -> FmiResult {
        self.omega = CompensatedSum::from_parts(r.finite("omega")?, r.finite("omega carry")?);
        self.roll = Roll {
            radius: r.finite("r")?,
            inertia: r.finite("J")?,
            reference_radius: r.finite("reference r")?,
            reference_inertia: r.finite("reference J")?,
        };
        self.carriage = [r.finite("y")?, r.finite("y_dot")?];
        self.v_web = r.finite("v_web")?;
        self.integrator = r.finite("loop.I")?;
        self.motor = r.finite("motor.torque")?;
        self.dancer = r.finite("dancer.I")?;
        self.time = r.finite("time")?;
        self.events_at = r.finite("events applied until")?;
        let next = r.i32("next event")?;
        let text = r.string("profile")?;
        self.profile = match text {
            "" => None,
            text => Some(drive::read(text).map_err(|e| FmiError::error(format!("profile in the FMU state: {e}")))?),
        };
        let events = self.profile.as_ref().map_or(0, |l| l.profile.events.len());
        if !(0..=events as i64).contains(&(next as i64)) || !(self.roll.radius > 0.0 && self.roll.inertia > 0.0) {
            return Err(FmiError::error(format!("the FMU state's roll (r = {}, J = {}) or next event ({next} of {events}) is not valid", self.roll.radius, self.roll.inertia)));
        }
        self.next_event = next as usize;
        Ok(())
    }

    /// `canInterpolateInputs="false"`: the layer refuses input derivatives
    /// before they reach the model.
    fn set_input_derivative(&mut self, vr: u32, _value: f64) -> FmiResult {
        Err(FmiError::error(format!(
            "value reference {vr}: the roller holds its inputs over a step (canInterpolateInputs = false)"
        )))
    }

    fn initialize(&mut self, experiment: &Experiment, resources: &Resources) -> FmiResult<Vec<String>> {
        let p = &self.params;
        if let Some(why) = control::refusal(p) {
            return Err(FmiError::error(why));
        }
        if p.traction && (p.roll != 0 || p.inlets > 1 || p.outlets > 1) {
            return Err(FmiError::error(format!(
                "includeTraction = true with roll = {}, inlets = {}, outlets = {}: a web slips only on a roller with one web \
                 in and one out that winds no roll (an idler, a driven roller, a dancer)",
                p.roll, p.inlets, p.outlets
            )));
        }
        let (profile, unmatched) = match drive::load(&self.params, resources)? {
            Ok(loaded) => (Some(loaded), None),
            Err(unmatched) => (None, unmatched),
        };
        self.profile = profile;
        self.start(experiment.start_time);
        Ok(unmatched.into_iter().collect())
    }

    fn provisional_state(&mut self) {
        self.start(0.0);
    }

    fn set_time(&mut self, time: f64) {
        self.time = time;
    }

    fn do_step(&mut self, h: f64) -> FmiResult {
        // Work on a copy (no heap: the profile is shared): a failed step changes nothing.
        let mut next = self.clone();
        next.advance(h)?;
        *self = next;
        Ok(())
    }

    // Model Exchange: the importer integrates (omega, r, y, y').

    fn get_continuous_states(&self, x: &mut [f64]) -> FmiResult {
        x.copy_from_slice(&[self.omega.value(), self.roll.radius, self.carriage[0], self.carriage[1], self.web_speed(), self.integrator, self.motor, self.dancer]);
        Ok(())
    }

    fn set_continuous_states(&mut self, x: &[f64]) -> FmiResult {
        if !(x[1] > 0.0) {
            return Err(FmiError::discard(format!("r = {} m is not a radius (it must be > 0)", x[1])));
        }
        let inertia = if self.params.winding() { self.roll.inertia_at(&self.params, x[1]) } else { self.roll.inertia };
        self.omega = CompensatedSum::from_parts(x[0], 0.0);
        self.roll = Roll { radius: x[1], inertia, ..self.roll };
        self.carriage = [x[2], x[3]];
        // Without traction x[4] is the surface's speed, not a state of the roller's own.
        if self.params.traction {
            self.v_web = x[4];
        }
        (self.integrator, self.motor, self.dancer) = (x[5], x[6], x[7]);
        Ok(())
    }

    fn get_derivatives(&self, dx: &mut [f64]) -> FmiResult {
        dx.copy_from_slice(&self.derivatives());
        Ok(())
    }

    /// The initial state does not depend on the inputs, so every phase has
    /// the same partial derivatives (the layer allows the states as knowns only in ME).
    fn partial_derivative(&self, unknown: u32, known: u32, _of: Jacobian) -> FmiResult<f64> {
        let real = |vr| Real::from_vr(vr).ok_or_else(|| fmi_core::model::unknown_vr(vr));
        let known = real(known)?;
        let d = Self::direction(known).ok_or_else(|| FmiError::error(format!("{} is not a known", known.name())))?;
        let unknown = real(unknown)?;
        Self::along(&self.tangents(&d), unknown).ok_or_else(|| FmiError::error(format!("{} is not an unknown", unknown.name())))
    }

    fn get_nominals(&self, nominals: &mut [f64]) -> FmiResult {
        nominals.copy_from_slice(&[1.0, self.params.radius, 1.0, 1.0, 1.0, 1.0, 1.0, 1.0]);
        Ok(())
    }

    fn get_event_indicators(&self, _z: &mut [f64]) -> FmiResult {
        Ok(())
    }

    /// Time events: the profile's entries (a jump, or a kink the integrator
    /// should not step over) and its `set` events.
    fn event_update(&mut self) -> EventUpdate {
        let rolled = self.apply_due(self.time);
        let speed_drive = self.drive() == Drive::Speed;
        if speed_drive {
            self.omega = CompensatedSum::from_parts(self.surface_speed() / self.roll.radius, 0.0);
        }
        EventUpdate {
            next_event_time: self.profile.as_ref().and_then(|l| l.profile.next_break(self.time)),
            states_changed: rolled || speed_drive,
        }
    }
}

/// The roller's own step where the web may slip: tight, as the Line's tolerance is, so that a
/// co-simulation's error is its coupling's.
const SLIP_RTOL: f64 = 1e-10;
const SLIP_ATOL: f64 = 1e-12;

/// [R6]-[R7] over a piece, as an ODE in (omega, v_web) from the piece's start t0.
struct Slipping<'a> {
    roller: &'a Roller,
    t0: f64,
}

impl Slipping<'_> {
    /// The rates at time t0 + s, the roller at y, and their partials in (omega, v_web).
    fn at(&self, s: f64, y: &[f64; 2]) -> ([f64; 2], [[f64; 2]; 2]) {
        use contact::{V_SURFACE, V_WEB};
        let (roller, t) = (self.roller, self.t0 + s);
        let (p, r) = (&roller.params, roller.roll.radius);
        let prescribed = roller.prescribed(t);
        let state = roller.contact_state_at(t, y[0], y[1]);
        let f = contact::contact(p, &state).force;
        // d(surface speed)/d(omega): r, or 0 where the surface follows a table.
        let dv = if prescribed.is_some() { 0.0 } else { r };
        let (df_domega, df_dv_web) = (f.d[V_SURFACE] * dv, f.d[V_WEB]);
        let (omega_rate, d_omega_rate) = match prescribed {
            Some((_, slope)) => (slope / r, [0.0, 0.0]),
            None => {
                let j = roller.roll.inertia;
                ((-r * f.x + roller.torque_at(t).0 - p.damping * y[0]) / j, [(-r * df_domega - p.damping) / j, -r * df_dv_web / j])
            }
        };
        let a = contact::web_acceleration(p, &state, f);
        ([omega_rate, a.x], [d_omega_rate, [a.d[V_SURFACE] * dv, a.d[V_WEB]]])
    }
}

impl solver::Ode<2> for Slipping<'_> {
    fn rhs(&self, s: f64, y: &[f64; 2]) -> [f64; 2] {
        self.at(s, y).0
    }

    fn jacobian(&self, s: f64, y: &[f64; 2]) -> [[f64; 2]; 2] {
        self.at(s, y).1
    }

    /// Tables of time (a drive's ramp, the nip's load) move f at fixed y: a central difference.
    fn time_derivative(&self, s: f64, y: &[f64; 2]) -> [f64; 2] {
        if !self.roller.varies_with_time(self.t0 + s) {
            return [0.0; 2];
        }
        let e = 1e-7 * (self.t0 + s).abs().max(1e-3);
        let (hi, lo) = (self.rhs(s + e, y), self.rhs(s - e, y));
        [(hi[0] - lo[0]) / (2.0 * e), (hi[1] - lo[1]) / (2.0 * e)]
    }
}

/// [R1], [R3], [R10]-[R11], [R13] over a piece, as an ODE in (omega, r, loop.I, motor.torque, dancer.I) from the
/// piece's start t0; its Jacobian from the roller's own tangents.
struct Controlled<'a> {
    roller: &'a Roller,
    t0: f64,
}

/// The states (indices into the roller's) the loop's step integrates.
const CONTROLLED: [usize; 5] = [0, 1, 5, 6, 7];

impl solver::Ode<5> for Controlled<'_> {
    fn rhs(&self, s: f64, y: &[f64; 5]) -> [f64; 5] {
        let d = self.roller.at_trial(self.t0 + s, y).derivatives();
        CONTROLLED.map(|i| d[i])
    }

    fn jacobian(&self, s: f64, y: &[f64; 5]) -> [[f64; 5]; 5] {
        let trial = self.roller.at_trial(self.t0 + s, y);
        let at = trial.linearize();
        let columns = CONTROLLED.map(|j| {
            let mut d = Direction::default();
            d.state[j] = 1.0;
            at.along(&d).derivatives
        });
        std::array::from_fn(|i| std::array::from_fn(|j| columns[j][CONTROLLED[i]]))
    }

    /// Tables of time (a set point's or a reference's ramp) move f at fixed y: a central difference.
    fn time_derivative(&self, s: f64, y: &[f64; 5]) -> [f64; 5] {
        if !self.roller.varies_with_time(self.t0 + s) {
            return [0.0; 5];
        }
        let e = 1e-7 * (self.t0 + s).abs().max(1e-3);
        let (hi, lo) = (self.rhs(s + e, y), self.rhs(s - e, y));
        std::array::from_fn(|i| (hi[i] - lo[i]) / (2.0 * e))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A roller varies with time on a piece of its profile where a table has a slope, and
    /// only there (the Line forms df/dt only then): the piece it reads, the one that starts
    /// at t once the events there are applied, else the one that reaches t.
    #[test]
    fn varies_with_time_only_where_a_table_has_a_slope() {
        let mut roller = Roller::at_start_values();
        assert!(!roller.varies_with_time(0.0), "no profile");
        roller.profile = Some(drive::parse(&roller.params, r#"{"speed": [[0, 1], [1, 1], [2, 3], [2, 4]]}"#).unwrap());
        for (t, varies) in [(-1.0, false), (0.5, false), (1.0, true), (1.5, true), (2.0, false), (3.0, false)] {
            roller.events_at = t;
            assert_eq!(roller.varies_with_time(t), varies, "t = {t}");
        }
        roller.events_at = 0.5;
        assert!(!roller.varies_with_time(1.0), "the break at 1 s not yet applied");
        assert!(roller.varies_with_time(1.5));
    }
}
