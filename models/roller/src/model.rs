//! The roller's data, one communication step, and the hooks the FMI layer
//! calls (initialization, steps, Model Exchange, FMU states). Its equations
//! are in `physics`, its drive and tables in `drive`.

use crate::description::{Real, DESCRIPTION};
use crate::drive::{self, Drive, Key, Loaded};
use crate::jacobian::{Direction, Linearization, Point, Tangents};
use crate::parameters::{Inputs, Parameters};
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
    /// The time now, s: profiles are tables of it.
    time: f64,
    /// The time up to which the profile's breaks and events are applied. Later, a table is read on
    /// the piece that reaches the time now: at a jump not yet applied, its value before the jump.
    events_at: f64,
    /// The profile's next `set` event not yet applied.
    next_event: usize,
    profile: Option<Loaded>,
}

impl Roller {
    /// Sets the Model Exchange states at `active` (indices into (omega, r, y, y')) to `x`, the
    /// others kept: what `set_continuous_states` does with the full vector, without forming it
    /// where only omega moves (a roller that neither winds nor carries a dancer).
    pub fn set_active_states(&mut self, active: &[usize], x: &[f64]) -> FmiResult {
        if let ([0], &[omega]) = (active, x) {
            self.omega = CompensatedSum::from_parts(omega, 0.0);
            return Ok(());
        }
        let mut full = [0.0; 4];
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
        self.profile.as_ref().map_or(Drive::Torque, |l| l.drive)
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
        match (self.drive(), self.table(Key::Speed)) {
            (Drive::Speed, Some(t)) => self.read(t, self.time).0,
            _ => physics::surface_speed(self.roll.radius, self.omega.value()),
        }
    }

    /// Whether the equations depend on time at fixed states and inputs on the
    /// piece of the profile they read at t: one of its tables has a slope there.
    pub fn varies_with_time(&self, t: f64) -> bool {
        self.profile.as_ref().is_some_and(|l| l.tables.iter().flatten().any(|table| self.read(table, t).1 != 0.0))
    }

    /// The strain of the leaving web (at every outlet): the profile's, else
    /// the arriving web's, merged [R5] when several arrive.
    pub fn strain_leaving(&self) -> f64 {
        self.table(Key::Strain).map_or_else(|| physics::merged_strain(&self.params, &self.inputs.strain_a), |t| self.read(t, self.time).0)
    }

    /// The load cell's reading for a wrap angle with this cosine (the Line's `NAME.F`).
    pub fn load_cell(&self, cos_wrap: f64) -> f64 {
        let (p, u) = (&self.params, &self.inputs);
        physics::load_cell(u.pull_back(p), u.pull_forward(p), cos_wrap)
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
        match (self.drive(), self.table(Key::Speed)) {
            (Drive::Speed, Some(t)) => physics::speed_drive_torque(&self.params, &self.roll, &self.inputs, self.omega.value(), self.read(t, self.time).1),
            _ => self.torque_at(self.time).0,
        }
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

    /// d/dt of (omega, r, y, y') now [R1]–[R4], for Model Exchange.
    pub fn derivatives(&self) -> [f64; 4] {
        let p = &self.params;
        let v = self.surface_speed();
        let (radius_rate, inertia_rate) =
            if p.winding() { (self.roll.radius_rate(p, v), self.roll.inertia_rate(p, v)) } else { (0.0, 0.0) };
        let omega_rate = match (self.drive(), self.table(Key::Speed)) {
            (Drive::Speed, Some(t)) => physics::omega_rate_at_speed(self.read(t, self.time).1, v, self.roll.radius, radius_rate),
            _ => physics::omega_rate(p, &self.roll, &self.inputs, self.omega.value(), self.torque_at(self.time).0, inertia_rate),
        };
        let carriage = if p.carriage {
            [self.carriage[1], physics::carriage_acceleration(p, self.carriage, self.carriage_force(self.time).0)]
        } else {
            [0.0, 0.0]
        };
        [omega_rate, radius_rate, carriage[0], carriage[1]]
    }

    /// The unit direction of one known: a state or an input (None: neither).
    pub fn direction(known: Real) -> Option<Direction> {
        let mut d = Direction::default();
        match known {
            Real::omega => d.state[0] = 1.0,
            Real::r => d.state[1] = 1.0,
            Real::y => d.state[2] = 1.0,
            Real::y_dot => d.state[3] = 1.0,
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
        let speed_table = self.table(Key::Speed).filter(|_| self.drive() == Drive::Speed);
        let tension = match (speed_table, self.drive()) {
            (None, Drive::Tension) => self.table(Key::Tension).map_or(0.0, |t| t.value(self.time)),
            _ => 0.0,
        };
        let point = Point {
            params: &self.params,
            inputs: &self.inputs,
            omega: self.omega(),
            roll: self.roll,
            speed: self.surface_speed(),
            speed_slope: speed_table.map(|t| t.slope(self.time)),
            tension,
            torque: if speed_table.is_some() { 0.0 } else { self.drive_torque() },
            strain_table: self.table(Key::Strain).is_some(),
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
        let speed_table = self.table(Key::Speed).filter(|_| self.drive() == Drive::Speed);
        let (omega, travel) = match &speed_table {
            Some(table) => {
                let (v0, slope) = self.read(table, t); // at the piece's start, after its events
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
            omega = match &speed_table {
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
        (self.omega, self.roll, self.carriage) = (omega, roll, carriage);
        Ok(())
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
            (Drive::Speed, Some(t)) => t.value(time),
            _ => p.speed_start,
        };
        self.omega = CompensatedSum::from_parts(speed / p.radius, 0.0);
        self.carriage = [p.carriage_start, 0.0];
        self.time = time;
        self.events_at = time;
        self.next_event = 0;
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
        for x in [r.radius, r.inertia, r.reference_radius, r.reference_inertia, self.carriage[0], self.carriage[1], self.time, self.events_at] {
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
        x.copy_from_slice(&[self.omega.value(), self.roll.radius, self.carriage[0], self.carriage[1]]);
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
        nominals.copy_from_slice(&[1.0, self.params.radius, 1.0, 1.0]);
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
