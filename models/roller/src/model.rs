//! The roller's data and its effects' glue: what it holds, the tables it reads at a time
//! (`point`), and its outputs, rates and tangents from the right-hand side written once (`rhs`).
//! Its communication step is in `stepping`, the hooks the FMI layer calls in `hooks`.

use crate::description::Real;
use crate::drive::{self, Drive, Key, Loaded};
use crate::jacobian::{Direction, Linearization, Tangents};
use crate::parameters::{Inputs, Parameters, STATES};
use crate::rhs::{self, Point, Slip};
use crate::roll::{self, Roll};
use crate::state::{State, States};
use crate::{carriage, contact, control, physics};
use fmi_core::FmiResult;
use solver::CompensatedSum;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Roller {
    pub params: Parameters,
    pub inputs: Inputs,
    /// Angular speed, rad/s, a compensated sum: a million tiny steps do not drift.
    pub(crate) omega: CompensatedSum,
    pub(crate) roll: Roll,
    /// Carriage travel y (down positive) and speed.
    pub(crate) carriage: [f64; 2],
    /// The web's speed over the roller [R6] (with traction; else the surface's, unused).
    pub(crate) v_web: f64,
    /// The time now, s: profiles are tables of it.
    pub(crate) time: f64,
    /// The time up to which the profile's breaks and events are applied. Later, a table is read on
    /// the piece that reaches the time now: at a jump not yet applied, its value before the jump.
    pub(crate) events_at: f64,
    /// The profile's next `set` event not yet applied.
    pub(crate) next_event: usize,
    /// The loop's integrator and its motor's lagged torque [R10]-[R11] (0 without a loop).
    pub(crate) integrator: f64,
    pub(crate) motor: f64,
    /// A dancer loop's integrator [R13], a speed trim (0 without one).
    pub(crate) dancer: f64,
    /// A sampled loop's hold [R14] (unused by a continuous loop).
    pub(crate) hold: control::Hold,
    /// The contact's grip [R7] and a brake's [R12] (0 without them).
    pub(crate) grip: f64,
    pub(crate) brake_grip: f64,
    /// The roll's angle [R15] (turns only with runout).
    pub(crate) angle: f64,
    /// A lay-on roller's carriage (X, X') and spin [R18] (unused without one).
    pub(crate) layon: [f64; 3],
    /// How the equations take the contact: its bristle, or held while a line solves its steady state.
    pub(crate) friction: contact::Friction,
    pub(crate) profile: Option<Loaded>,
}

impl Roller {
    /// Sets the Model Exchange states at `active` (indices into the state vector) to `x`, the
    /// others kept: what `set_continuous_states` does with the full vector, without forming it
    /// where only omega moves (a roller that neither winds nor carries a dancer).
    pub fn set_active_states(&mut self, active: &[usize], x: &[f64]) -> FmiResult {
        if let ([0], &[omega]) = (active, x) {
            self.omega = CompensatedSum::from_parts(omega, 0.0);
            return Ok(());
        }
        let mut full = self.states();
        for (&i, &value) in active.iter().zip(x) {
            *full.get_mut(State::ALL[i]) = value;
        }
        self.set_states(&full)
    }

    pub fn omega(&self) -> f64 {
        self.omega.value()
    }

    pub fn radius(&self) -> f64 {
        self.roll.radius
    }

    /// The Model Exchange states now (the web's speed the surface's where it cannot slip).
    #[inline]
    pub fn states(&self) -> States {
        self.states_with(self.web_speed())
    }

    /// Sets the Model Exchange states: J moves with r on a roll being wound [R3].
    pub(crate) fn set_states(&mut self, x: &States) -> FmiResult {
        if !(x.radius > 0.0) {
            return Err(fmi_core::FmiError::discard(format!("r = {} m is not a radius (it must be > 0)", x.radius)));
        }
        self.place(x);
        Ok(())
    }

    /// Puts the roller at `x` (J moves with r [R3]), unchecked: a step's trial point, or `set_states`'s.
    pub(crate) fn place(&mut self, x: &States) {
        self.omega = CompensatedSum::from_parts(x.omega, 0.0);
        self.roll = Roll { radius: x.radius, inertia: self.roll.inertia(&self.params, x.radius), ..self.roll };
        self.carriage = [x.carriage_y, x.carriage_speed];
        // Without traction the web's speed is the surface's, not a state of the roller's own.
        if self.params.traction {
            self.v_web = x.web_speed;
        }
        (self.integrator, self.motor, self.dancer) = (x.loop_integrator, x.motor_torque, x.dancer_integrator);
        (self.grip, self.brake_grip, self.angle) = (x.grip, x.brake_grip, x.angle);
        self.layon = [x.layon_x, x.layon_speed, x.layon_spin];
    }

    #[inline(always)]
    pub(crate) fn drive(&self) -> Drive {
        if self.params.speed_input {
            return Drive::Speed;
        }
        self.profile.as_ref().map_or(Drive::Torque, |l| l.drive)
    }

    /// A speed drive's surface speed and its slope at t (the time now, or a piece's start): its
    /// table's, or `loop.speed` held over the step, slope 0, where `speed.input` is true.
    #[inline(always)]
    pub(crate) fn prescribed(&self, t: f64) -> Option<(f64, f64)> {
        if self.params.speed_input {
            return Some((self.params.loop_speed, 0.0));
        }
        self.table(Key::Speed).filter(|_| self.drive() == Drive::Speed).map(|table| self.read(table, t))
    }

    /// State `s` keeps its start value in the steady state: a roll's radius (never steady while
    /// web winds), a speed a table prescribes.
    pub fn held_at_steady_state(&self, s: State) -> bool {
        match s {
            // Never steady while the roll turns: its runout's phase at the start.
            State::Radius | State::Angle => true,
            State::Omega => self.speed_prescribed(),
            State::CarriageY
            | State::CarriageSpeed
            | State::WebSpeed
            | State::LoopIntegrator
            | State::MotorTorque
            | State::DancerIntegrator
            | State::Grip
            | State::BrakeGrip
            | State::LayonX
            | State::LayonSpeed
            | State::LayonSpin => false,
        }
    }

    /// Whether the radius the web meets moves with r now (at r's rate): where it moves smoothly, or a
    /// stepwise radius [R17] within a merge that spans the whole layer; not on a stepwise plateau.
    pub fn contact_moves_with_radius(&self) -> bool {
        !roll::stepped(&self.params) || roll::stepwise(&self.params, self.roll.radius).1 == 1.0
    }

    /// The surface speed follows a speed table (a source, a sink, a speed
    /// drive): forces do not move it.
    #[inline]
    pub fn speed_prescribed(&self) -> bool {
        self.drive() == Drive::Speed
    }

    #[inline(always)]
    pub(crate) fn table(&self, key: Key) -> Option<&profiles::Table> {
        self.profile.as_ref().and_then(|l| l.table(key))
    }

    /// A table's value and slope at t (the time now, or a piece's start).
    #[inline(always)]
    pub(crate) fn read(&self, table: &profiles::Table, t: f64) -> (f64, f64) {
        if t > self.events_at {
            let within = profiles::tolerance(t).min(t - self.events_at);
            table.before(t, within)
        } else {
            (table.value(t), table.slope(t))
        }
    }

    /// A table's value and slope at t, where the profile has it.
    #[inline(always)]
    pub(crate) fn value(&self, key: Key, t: f64) -> Option<(f64, f64)> {
        self.table(key).map(|table| self.read(table, t))
    }

    /// The drive's table at t, its value and its rate.
    #[inline(always)]
    fn drive_read(&self, t: f64) -> (drive::Read, drive::Read) {
        if let Some((x, rate)) = self.value(Key::Torque, t) {
            (drive::Read::Torque(x), drive::Read::Torque(rate))
        } else if let Some((x, rate)) = self.value(Key::Tension, t) {
            (drive::Read::Tension(x), drive::Read::Tension(rate))
        } else {
            (drive::Read::None, drive::Read::None)
        }
    }

    /// What the equations read at time t with the roller at `x`: the tables, and the contact where
    /// the web may slip.
    #[inline(always)]
    pub(crate) fn point_at(&self, t: f64, x: &States) -> Point {
        self.reading(t, Some(x))
    }

    /// What the equations read at time t: the tables (functions of time only), and where the web
    /// may slip the contact with the roller at `contact_at` (None: the contact left out).
    #[inline(always)]
    fn reading(&self, t: f64, contact_at: Option<&States>) -> Point {
        let p = &self.params;
        let prescribed = self.prescribed(t);
        let slip = contact_at.filter(|_| p.traction).map(|x| Slip::at(p, self.contact_state_at(t, prescribed, x.omega, x.web_speed, x.grip), self.friction));
        if self.profile.is_none() {
            // No tables to read (an idler, most rollers of a line): what the parameters give.
            let control = control::Reads { set: p.loop_set, reference: self.given_reference(), held: self.held_command() };
            return Point { roll: self.roll, prescribed, control, slip, layon_load: p.layon_f, ..Point::default() };
        }
        Point {
            roll: self.roll,
            prescribed,
            drive: self.drive_read(t).0,
            brake: self.value(Key::Brake, t).map(|(b, _)| b),
            control: control::Reads {
                set: self.value(Key::Set, t).map_or(p.loop_set, |(x, _)| x),
                reference: self.value(Key::Reference, t).or_else(|| self.given_reference()),
                held: self.held_command(),
            },
            load: self.value(Key::Load, t).map_or(0.0, |(x, _)| x),
            strain: self.value(Key::Strain, t).map(|(x, _)| x),
            slip,
            layon_load: self.value(Key::Layon, t).map_or(p.layon_f, |(x, _)| x),
        }
    }

    /// A feed-forward's reference where no table gives it [R10]: loop.speed and its slope
    /// loop.acceleration, as the importer sets them (the Line: from a part's input v_ref).
    #[inline(always)]
    fn given_reference(&self) -> Option<(f64, f64)> {
        self.params.loop_feedforward.then_some((self.params.loop_speed, self.params.loop_acceleration))
    }

    /// A sampled loop's command as its hold applies it [R14] (None: continuous, or before its first sample).
    #[inline(always)]
    fn held_command(&self) -> Option<f64> {
        (self.params.sampled() && self.hold.engaged).then_some(self.hold.applied)
    }

    /// Lets a sampled loop's hold apply what is due at t [R14]; whether the command it applies moved.
    pub(crate) fn hold_due(&mut self, t: f64) -> bool {
        if !self.params.sampled() {
            return false;
        }
        let x = self.held();
        let mut hold = self.hold;
        let moved = hold.due(&self.params, t, || rhs::loop_command(&self.params, &self.point_at(t, &x), &x, &self.inputs));
        self.hold = hold;
        moved
    }

    /// A sampled loop's next sample or application [R14] (None: no sampled loop).
    pub(crate) fn next_hold_event(&self) -> Option<f64> {
        self.params.sampled().then(|| self.hold.next_event(&self.params))
    }

    /// A sampled loop starts again at t [R14]: continuous until its first sample, due at t (the Line
    /// solves its steady state with the loop continuous, then samples it).
    pub fn restart_hold(&mut self, t: f64) {
        self.hold = control::Hold::starting(t);
    }

    /// What the equations read now.
    #[inline]
    pub(crate) fn point(&self) -> Point {
        self.point_at(self.time, &self.held())
    }

    /// The states as the roller holds them: the web's speed its own field, which the equations
    /// read only where the web may slip (`states` gives the surface's speed there otherwise).
    #[inline(always)]
    pub(crate) fn held(&self) -> States {
        States { web_speed: self.v_web, ..self.states_with(0.0) }
    }

    #[inline(always)]
    fn states_with(&self, web_speed: f64) -> States {
        States {
            omega: self.omega.value(),
            radius: self.roll.radius,
            carriage_y: self.carriage[0],
            carriage_speed: self.carriage[1],
            web_speed,
            loop_integrator: self.integrator,
            motor_torque: self.motor,
            dancer_integrator: self.dancer,
            grip: self.grip,
            brake_grip: self.brake_grip,
            angle: self.angle,
            layon_x: self.layon[0],
            layon_speed: self.layon[1],
            layon_spin: self.layon[2],
        }
    }

    /// v [R2]; a speed drive's profile at the time now.
    #[inline]
    pub fn surface_speed(&self) -> f64 {
        match self.prescribed(self.time) {
            Some((v, _)) => v,
            None => physics::surface_speed(roll::contact_radius(&self.params, self.roll.radius), self.omega.value()),
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

    /// The contact's state at time t (a speed drive's `prescribed` speed there) with the roller at omega,
    /// the web at v_web and the grip at `grip` (a step's trial point).
    pub(crate) fn contact_state_at(&self, t: f64, prescribed: Option<(f64, f64)>, omega: f64, v_web: f64, grip: f64) -> contact::State {
        let (u, r) = (&self.inputs, self.roll.radius);
        let v_surface = match prescribed {
            Some((v, _)) => v,
            None => physics::surface_speed(r, omega),
        };
        contact::State {
            v_web,
            v_surface,
            t_a: u.force_a[0],
            t_b: u.force_b[0],
            nip_load: self.value(Key::Nip, t).map_or(0.0, |(n, _)| n),
            radius: r,
            grip,
        }
    }

    /// The contact now [R6]-[R8] (None without traction).
    fn slip_now(&self) -> Option<Slip> {
        self.params.traction.then(|| Slip::at(&self.params, self.contact_state_at(self.time, self.prescribed(self.time), self.omega(), self.v_web, self.grip), self.friction))
    }

    /// The coefficient of friction after the air film [R8] (0 without traction).
    pub fn mu_eff(&self) -> f64 {
        self.slip_now().map_or(0.0, |s| s.contact.mu_eff.x)
    }

    /// The air film's thickness [R8] (0 without traction or air).
    pub fn h_air(&self) -> f64 {
        self.slip_now().map_or(0.0, |s| s.contact.h_air.x)
    }

    /// The share of the available traction in use [R7] (0 without traction).
    pub fn traction_used(&self) -> f64 {
        self.slip_now().map_or(0.0, |s| contact::traction_used(&self.params, &s.state, s.contact.mu_eff).x)
    }

    /// Whether the equations depend on time at fixed states and inputs on the
    /// piece of the profile they read at t: one of its tables has a slope there, or a curvature.
    pub fn varies_with_time(&self, t: f64) -> bool {
        self.profile.as_ref().is_some_and(|l| l.tables.iter().flatten().any(|table| self.read(table, t).1 != 0.0 || table.curvature(t) != 0.0))
    }

    /// The strain of the web leaving at outlet `outlet` (0-based) (`rhs::strain_leaving`).
    pub fn strain_leaving(&self, outlet: usize) -> f64 {
        rhs::strain_leaving(&self.params, self.value(Key::Strain, self.time).map(|(x, _)| x), &self.inputs.strain_a, outlet)
    }

    /// The load cell's reading for a wrap angle with this cosine (the Line's `NAME.F`).
    pub fn load_cell(&self, cos_wrap: f64) -> f64 {
        let (p, u) = (&self.params, &self.inputs);
        physics::load_cell(u.pull_back(p), u.pull_forward(p), cos_wrap)
    }

    /// The output load_cell.F (`rhs::load_cell_force`).
    pub fn load_cell_force(&self) -> f64 {
        rhs::load_cell_force(&self.params, &self.inputs)
    }

    /// The drive's table torque at time t with tau_m, and its rate (the exact piece's forcing).
    #[inline]
    pub(crate) fn torque_at(&self, t: f64) -> (f64, f64) {
        let (value, rate) = self.drive_read(t);
        let r = self.roll.radius;
        (drive::torque(&self.params, value, self.inputs.torque, r), drive::torque(&self.params, rate, 0.0, r))
    }

    /// The carriage's force (load minus every span's pull) [R4] at t, and its rate.
    pub(crate) fn carriage_force(&self, t: f64) -> (f64, f64) {
        let (p, u) = (&self.params, &self.inputs);
        let (load, rate) = self.value(Key::Load, t).unwrap_or((0.0, 0.0));
        (carriage::force(u.load, load, u.pull_back(p), u.pull_forward(p)), rate)
    }

    /// The rates and the drive's torque now (`rhs::rates`).
    #[inline(always)]
    fn evaluate(&self) -> rhs::Rates<f64> {
        let x = self.held();
        rhs::rates(&self.params, &self.point_at(self.time, &x), &x, &self.inputs)
    }

    /// The drive's torque now; a speed drive's is what [R1] needs to follow its profile.
    pub fn drive_torque(&self) -> f64 {
        let x = self.held();
        // The contact only where [R1] gives a speed drive's torque: a commanded one does not read it.
        let point = self.reading(self.time, self.speed_prescribed().then_some(&x));
        rhs::torque(&self.params, &point, &x, &self.inputs)
    }

    /// Whether the tangents along omega, the carriage and the inputs stay as they are until an event or
    /// a parameter changes them (`jacobian::tangents_fixed`; a brake [R12] is nonlinear in omega).
    pub fn tangents_fixed(&self) -> bool {
        crate::jacobian::tangents_fixed(&self.params) && !self.braked()
    }

    /// The contact's grip [R7] (0 without traction).
    pub fn grip(&self) -> f64 {
        self.grip
    }

    /// A brake's grip [R12] (0 without a brake).
    pub fn brake_grip(&self) -> f64 {
        self.brake_grip
    }

    /// The states that move on this roller (`Parameters::active_states`, a brake's grip where its
    /// profile has a brake table).
    pub fn active_states(&self) -> Vec<State> {
        self.params.active_states(self.braked())
    }

    /// Whether the profile has a brake table [R12].
    pub(crate) fn braked(&self) -> bool {
        self.table(Key::Brake).is_some()
    }

    /// Where the contact's grip has reached its limit, what it needs against what it can give
    /// (`contact::demand`); None while it sticks, or without traction.
    pub fn beyond_grip(&self) -> Option<String> {
        self.slip_now().and_then(|s| contact::demand(&self.params, &s.state))
    }

    /// The contact held while a line solves the steady state it starts in (`Friction::Held`), or its bristle.
    pub fn hold_contact(&mut self, held: bool) {
        self.friction = if held { contact::Friction::Held } else { contact::Friction::Bristle };
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

    /// Where the webs touch the roller [R4]: web_a at x = 0, web_b at 2r.
    pub(crate) fn contact_a_x(&self) -> f64 {
        0.0
    }

    pub(crate) fn contact_b_x(&self) -> f64 {
        carriage::contact_b_x(self.roll.radius)
    }

    /// Heights from the dancer's start position, up positive: 0 at the start,
    /// so a master that starts its inputs at 0 (FMPy) still sees a valid span. A roll with runout
    /// gives its end of its span there [R15].
    pub(crate) fn contact_a_y(&self) -> f64 {
        self.runout_outputs().map_or_else(|| carriage::contact_height(&self.params, self.carriage[0]), |o| o.contact_a_y)
    }

    pub(crate) fn contact_b_y(&self) -> f64 {
        self.runout_outputs().map_or_else(|| carriage::contact_height(&self.params, self.carriage[0]), |o| o.contact_b_y)
    }

    /// The web's speed where it arrives and where it leaves: the web's over the roller, or the
    /// moving tangent point's on a roll with runout [R15].
    pub fn arriving_speed(&self) -> f64 {
        self.runout_outputs().map_or_else(|| self.web_speed(), |o| o.arriving_speed)
    }

    pub fn leaving_speed(&self) -> f64 {
        self.runout_outputs().map_or_else(|| self.web_speed(), |o| o.leaving_speed)
    }

    /// The roll's angle [R15].
    pub fn angle(&self) -> f64 {
        self.angle
    }

    /// A lay-on roller's nip force [R18] (0 without one).
    pub fn layon_force(&self) -> f64 {
        self.params.layon.then(|| self.outputs_now().layon_force).unwrap_or(0.0)
    }

    /// A lay-on roller's nip compression [R18] (0 without one).
    pub fn layon_compression(&self) -> f64 {
        self.params.layon.then(|| self.outputs_now().layon_compression).unwrap_or(0.0)
    }

    /// Everything the roller computes now, where its roll has runout (its ends move with the angle).
    fn runout_outputs(&self) -> Option<rhs::Outputs> {
        self.params.runout.then(|| self.outputs_now())
    }

    /// Everything the roller computes now (`rhs::outputs`).
    fn outputs_now(&self) -> rhs::Outputs {
        let x = self.held();
        rhs::outputs(&self.params, &self.point_at(self.time, &x), &x, &self.inputs)
    }

    /// d/dt of the states now, by name.
    #[inline]
    pub fn rates(&self) -> States {
        self.evaluate().derivatives
    }

    /// d/dt of the states now, in the order of the Model Exchange state vector.
    pub fn derivatives(&self) -> [f64; STATES] {
        self.rates().to_array()
    }

    /// d(rates)/d(`states`) at `point` with the roller at `x` (the inputs held): the rates in
    /// `Lanes`, a lane along each state, one evaluation for every column.
    #[inline]
    pub(crate) fn rate_jacobian<const N: usize>(&self, point: &Point, x: &States, states: [State; N]) -> [[f64; N]; N] {
        let units = states.map(|j| {
            let mut d = States::default();
            *d.get_mut(j) = 1.0;
            d
        });
        let rates = rhs::rates(&self.params, point, &x.lanes(&units), &self.inputs.lanes(&[Inputs::default(); N])).derivatives;
        std::array::from_fn(|i| rates.get(states[i]).d)
    }

    /// The unit direction of one known: a state or an input (None: neither).
    pub fn direction(known: Real) -> Option<Direction> {
        let mut d = Direction::default();
        match State::of(known) {
            Some(s) => *d.state.get_mut(s) = 1.0,
            None => *Self::input_field(&mut d.u, known)? = 1.0,
        }
        Some(d)
    }

    /// d(everything)/d(direction) now.
    #[inline]
    pub fn tangents(&self, d: &Direction) -> Tangents {
        self.linearize().along(d)
    }

    /// What the tangents along every direction share: the roller's values now, its tables read
    /// at the time now, the contact with its gradient.
    #[inline]
    pub fn linearize(&self) -> Linearization<'_> {
        let x = self.held();
        let mut point = self.point_at(self.time, &x);
        if let Some(s) = point.slip.as_mut() {
            s.used = Some(contact::traction_used(&self.params, &s.state, s.contact.mu_eff));
        }
        Linearization { params: &self.params, inputs: &self.inputs, point, states: x }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use fmi_core::Compiled;

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
