//! The Model Exchange functions: time, continuous states, derivatives,
//! event indicators and the event-mode transitions.

use super::*;

impl<M: Model> Instance<M> {
    pub fn set_time(&mut self, call: CallName, time: f64) -> FmiResult {
        if !time.is_finite() {
            return Err(FmiError::error(format!("{call}: time = {time} must be finite")));
        }
        self.time = time;
        self.model.set_time(time);
        self.settled = false;
        Ok(())
    }

    fn check_count(call: CallName, what: &str, given: usize, declared: usize) -> FmiResult {
        if given == declared {
            Ok(())
        } else {
            Err(FmiError::error(format!("{}: {given} {what} given, the model has {declared}", call)))
        }
    }

    /// Before a computed vector is read: the length the importer gives, the
    /// initial values during initialization, computability after an error.
    fn prepare_computed(&mut self, call: CallName, what: &str, given: usize, declared: usize) -> FmiResult {
        Self::check_count(call, what, given, declared)?;
        self.prepare_get(call)?;
        self.check_computable(call)
    }

    pub fn set_continuous_states(&mut self, call: CallName, x: &[f64]) -> FmiResult {
        Self::check_count(call, "states", x.len(), self.model.description().states.len())?;
        if let Some(bad) = x.iter().find(|v| !v.is_finite()) {
            return Err(FmiError::error(format!("{}: a state value is {bad}", call)));
        }
        self.settled = false;
        self.model.set_continuous_states(x).map_err(|e| e.prefixed(call))
    }

    pub fn get_continuous_states(&mut self, call: CallName, x: &mut [f64]) -> FmiResult {
        let n = self.model.description().states.len();
        self.prepare_computed(call, "states", x.len(), n)?;
        self.model.get_continuous_states(x).map_err(|e| e.prefixed(call))
    }

    pub fn get_derivatives(&mut self, call: CallName, dx: &mut [f64]) -> FmiResult {
        let n = self.model.description().states.len();
        self.prepare_computed(call, "derivatives", dx.len(), n)?;
        self.model.get_derivatives(dx).map_err(|e| e.prefixed(call))
    }

    pub fn get_event_indicators(&mut self, call: CallName, z: &mut [f64]) -> FmiResult {
        let n = self.model.description().number_of_event_indicators;
        self.prepare_computed(call, "event indicators", z.len(), n)?;
        self.model.get_event_indicators(z).map_err(|e| e.prefixed(call))
    }

    pub fn get_nominals(&mut self, call: CallName, nominals: &mut [f64]) -> FmiResult {
        Self::check_count(call, "nominals", nominals.len(), self.model.description().states.len())?;
        self.model.get_nominals(nominals).map_err(|e| e.prefixed(call))
    }

    pub fn enter_event_mode(&mut self) -> FmiResult {
        self.phase = Phase::EventMode;
        Ok(())
    }

    /// The model applies what is due now (a profile's jumps and parameter
    /// changes) and names its next time event; no discrete states otherwise.
    pub fn new_discrete_states(&mut self) -> DiscreteUpdate {
        self.model.set_time(self.time);
        let update = self.model.event_update();
        DiscreteUpdate { next_event_time: update.next_event_time, states_changed: update.states_changed, ..DiscreteUpdate::default() }
    }

    pub fn enter_continuous_time_mode(&mut self) -> FmiResult {
        self.phase = Phase::ContinuousTimeMode;
        Ok(())
    }
}
