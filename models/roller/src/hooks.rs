//! The hooks the FMI layer calls: instantiation, initialization, steps, Model Exchange, FMU states.

use crate::control;
use crate::description::{Real, DESCRIPTION};
use crate::drive::{self, Drive};
use crate::model::Roller;
use crate::parameters::STATES;
use crate::roll::{self, Roll};
use crate::state::States;
use fmi_core::{Compiled, EventUpdate, Experiment, FmiError, FmiResult, Jacobian, Model, Resources, StateReader, StateWriter};
use solver::CompensatedSum;

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
        for x in [r.radius, r.inertia, r.reference_radius, r.reference_inertia, self.carriage[0], self.carriage[1], self.v_web, self.integrator, self.motor, self.dancer, self.time, self.events_at, self.angle, self.layon[0], self.layon[1], self.layon[2], self.grip, self.brake_grip] {
            out.f64(x);
        }
        let h = &self.hold;
        let (at, waiting) = h.waiting.unwrap_or((0.0, 0.0));
        out.bool(h.engaged);
        out.bool(h.waiting.is_some());
        for x in [h.applied, at, waiting, h.origin, h.next as f64] {
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
        self.angle = r.finite("angle")?;
        self.layon = [r.finite("layon.x")?, r.finite("layon.v")?, r.finite("layon.omega")?];
        (self.grip, self.brake_grip) = (r.finite("grip")?, r.finite("brake.grip")?);
        let (engaged, has_waiting) = (r.bool("hold engaged")?, r.bool("hold waiting")?);
        let (applied, at, waiting) = (r.finite("held command")?, r.finite("waiting's time")?, r.finite("waiting command")?);
        let (origin, next) = (r.finite("samples' origin")?, r.finite("next sample")?);
        if !(next >= 0.0 && next.fract() == 0.0) {
            return Err(FmiError::error(format!("the FMU state's next sample {next} is not a count")));
        }
        self.hold = crate::control::Hold { engaged, applied, waiting: has_waiting.then_some((at, waiting)), origin, next: next as u64 };
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

    fn check_real(&self, vr: u32, value: f64) -> FmiResult {
        match control::set_point_refusal(&self.params, value) {
            Some(why) if vr == Real::loop_set as u32 => Err(FmiError::error(why)),
            _ => Ok(()),
        }
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
        if let Some(why) = crate::runout::refusal(p).or_else(|| crate::layon::refusal(p)) {
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
        if let Some(why) = drive::taper_refusal(&self.params, profile.as_ref().map_or(drive::Drive::Torque, |l| l.drive)) {
            return Err(FmiError::error(why));
        }
        // A start value is only warned about: loop.kind = 1 alone leaves loop.set at its start, 0.
        let set_point = profile.as_ref().is_none_or(|loaded| loaded.table(drive::Key::Set).is_none()).then(|| control::set_point_refusal(p, p.loop_set)).flatten();
        self.profile = profile;
        self.start(experiment.start_time);
        Ok(unmatched.into_iter().chain(roll::massless_roll(&self.params)).chain(set_point).chain(control::unsampled_delay(&self.params)).collect())
    }

    fn provisional_state(&mut self) {
        self.start(0.0);
    }

    fn set_time(&mut self, time: f64) {
        self.time = time;
    }

    fn do_step(&mut self, h: f64) -> FmiResult {
        if self.profile.is_none() {
            // One piece, which changes the roller only once it has succeeded (`piece`): no copy needed.
            return self.advance(h);
        }
        // Work on a copy (no heap: the profile is shared): a failed step changes nothing.
        let mut next = self.clone();
        next.advance(h)?;
        *self = next;
        Ok(())
    }

    // Model Exchange: the importer integrates the states (`State`).

    fn get_continuous_states(&self, x: &mut [f64]) -> FmiResult {
        x.copy_from_slice(&self.states().to_array());
        Ok(())
    }

    fn set_continuous_states(&mut self, x: &[f64]) -> FmiResult {
        let x: &[f64; STATES] = x.try_into().map_err(|_| FmiError::error(format!("{} states given, the roller has {STATES}", x.len())))?;
        self.set_states(&States::from_array(x))
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
        nominals.copy_from_slice(&States { radius: self.params.radius, ..States::from_array(&[1.0; STATES]) }.to_array());
        Ok(())
    }

    fn get_event_indicators(&self, _z: &mut [f64]) -> FmiResult {
        Ok(())
    }

    /// Time events: the profile's entries (a jump, or a kink the integrator
    /// should not step over) and its `set` events. At one the states are reported changed, so that
    /// an importer restarts its integrator there (its history holds the right-hand side before it).
    fn event_update(&mut self) -> EventUpdate {
        let time_event = self.profile.as_ref().and_then(|l| l.profile.next_break(self.events_at)).is_some_and(|b| profiles::due(b, self.time));
        let rolled = self.apply_due(self.time);
        let sampled = self.hold_due(self.time);
        let speed_drive = self.drive() == Drive::Speed;
        if speed_drive {
            self.omega = CompensatedSum::from_parts(self.surface_speed() / self.roll.radius, 0.0);
        }
        EventUpdate {
            next_event_time: self.next_event_after(self.time),
            states_changed: time_event || rolled || speed_drive || sampled,
        }
    }
}

