//! Getting and setting variables: value reference, type, causality, phase
//! and value are checked against the model description; a rejected set
//! changes nothing.

use super::*;

/// Looks up a value reference and checks that it is of the family the
/// function handles.
#[inline(always)]
fn slot_in(d: &ModelDescription, call: CallName, vr: u32, family: Family) -> FmiResult<&Slot> {
    match d.slot(vr) {
        Some(s) if s.family == family => Ok(s),
        _ => Err(wrong_variable(call, vr, d.variable(vr), family)),
    }
}

impl<M: Model> Instance<M> {
    #[inline(always)]
    fn variable(&self, call: CallName, vr: u32, family: Family) -> FmiResult<&Variable> {
        let d = self.model.description();
        let slot = slot_in(d, call, vr, family)?;
        Ok(&d.variables[slot.row as usize])
    }

    /// In initialization mode the outputs follow the parameters and inputs
    /// set so far, so they are computed before they are read.
    #[inline]
    pub(super) fn prepare_get(&mut self, call: CallName) -> FmiResult {
        if self.phase == Phase::InitializationMode {
            return self.settle_for_get(call);
        }
        Ok(())
    }

    #[cold]
    #[inline(never)]
    fn settle_for_get(&mut self, call: CallName) -> FmiResult {
        if self.settled {
            return Ok(());
        }
        // Warnings are logged once, when initialization ends.
        self.settle_initial_values().map(drop).map_err(|e| e.prefixed(call))?;
        self.settled = true;
        Ok(())
    }

    /// Parameters and inputs are always there, but computed values only where
    /// the model can compute them: after an error the parameters may never
    /// have passed initialization, and inputs set since the last step may
    /// leave no valid configuration (rollers moved onto each other).
    #[inline]
    pub(super) fn check_computable(&self, call: CallName) -> FmiResult {
        if self.phase == Phase::Error {
            return self.check_computable_after_error(call);
        }
        match self.model.inputs_valid() {
            Ok(()) => Ok(()),
            Err(e) => Err(prefixed(e, call)),
        }
    }

    #[cold]
    fn check_computable_after_error(&self, call: CallName) -> FmiResult {
        self.check_parameter_ranges().map_err(|e| e.prefixed(&format!("{call}: outputs are not defined")))?;
        self.model.outputs_defined().and_then(|()| self.model.inputs_valid()).map_err(|e| prefixed(e, call))
    }

    #[inline(always)]
    pub fn get_reals(&mut self, call: CallName, vrs: &[u32], values: &mut [f64]) -> FmiResult {
        self.prepare_get(call)?;
        let mut checked = false;
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            let slot = slot_in(self.model.description(), call, *vr, Family::Real)?;
            if !checked && slot.computed {
                self.check_computable(call)?;
                checked = true;
            }
            *value = self.model.get_real(*vr)?;
        }
        Ok(())
    }

    pub fn get_integers(&mut self, call: CallName, vrs: &[u32], values: &mut [i32]) -> FmiResult {
        self.prepare_get(call)?;
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            self.variable(call, *vr, Family::Integer)?;
            *value = self.model.get_integer(*vr)?;
        }
        Ok(())
    }

    pub fn get_booleans(&mut self, call: CallName, vrs: &[u32], values: &mut [i32]) -> FmiResult {
        self.prepare_get(call)?;
        for (vr, value) in vrs.iter().zip(values.iter_mut()) {
            self.variable(call, *vr, Family::Boolean)?;
            *value = self.model.get_boolean(*vr)? as i32;
        }
        Ok(())
    }

    /// Each value is handed to `put`, which copies it out.
    pub fn get_strings(&mut self, call: CallName, vrs: &[u32], mut put: impl FnMut(&str)) -> FmiResult {
        self.prepare_get(call)?;
        for &vr in vrs {
            self.variable(call, vr, Family::String)?;
            put(self.model.get_string(vr)?);
        }
        Ok(())
    }

    /// `None` is a NULL pointer, which FMI does not allow as a value.
    pub fn set_strings(&mut self, call: CallName, vrs: &[u32], values: &[Option<&str>]) -> FmiResult {
        self.set_all(
            call,
            Family::String,
            vrs,
            values,
            |v, x| match x {
                Some(_) => Ok(()),
                None => Err(FmiError::error(format!("{} = NULL: a String value must be a text (\"\" for none)", v.name))),
            },
            |m, vr, x| m.set_string(vr, x.unwrap_or_default()),
        )
    }

    /// May `v` be set now? FMI 2.0, section 2.2.7 (the table of when a
    /// variable may be set) for co-simulation.
    #[inline(always)]
    fn check_settable(&self, call: CallName, v: &Variable) -> FmiResult {
        if v.settable_in & self.phase.bit() != 0 {
            Ok(())
        } else {
            Err(not_settable(call, v, self.phase, self.standard.state(self.phase)))
        }
    }

    /// Validates every value before it applies any, so a rejected call
    /// changes nothing.
    #[inline(always)]
    fn set_all<T: Copy>(
        &mut self,
        call: CallName,
        family: Family,
        vrs: &[u32],
        values: &[T],
        check: impl Fn(&Variable, T) -> FmiResult,
        apply: impl Fn(&mut M, u32, T) -> FmiResult,
    ) -> FmiResult {
        for (&vr, &value) in vrs.iter().zip(values) {
            let v = self.variable(call, vr, family)?;
            self.check_settable(call, v)?;
            check(v, value).map_err(|e| e.prefixed(call))?;
        }
        self.settled = false;
        for (&vr, &value) in vrs.iter().zip(values) {
            apply(&mut self.model, vr, value)?;
        }
        Ok(())
    }

    /// The hottest set of a co-simulation step, written out: the same checks
    /// as `set_all`, every value before any is applied.
    #[inline(always)]
    pub fn set_reals(&mut self, call: CallName, vrs: &[u32], values: &[f64]) -> FmiResult {
        let d = self.model.description();
        for (&vr, &x) in vrs.iter().zip(values) {
            let slot = slot_in(d, call, vr, Family::Real)?;
            if slot.settable_in & self.phase.bit() == 0 {
                return Err(not_settable(call, &d.variables[slot.row as usize], self.phase, self.standard.state(self.phase)));
            }
            // Parameters are range-checked when initialization ends (they
            // may pass through odd values while a user sets them one by
            // one); inputs take effect at once, so they are checked now.
            if !(slot.set_lo <= x && x <= slot.set_hi) {
                return Err(out_of_range(&d.variables[slot.row as usize], x).prefixed(call));
            }
            // A tunable parameter set after initialization takes effect at once, as an input
            // does: no later check would see it (an FMU state saved then would not restore).
            let v = &d.variables[slot.row as usize];
            if self.phase.initialized() && v.causality == Causality::Parameter && !v.range.contains(x) {
                return Err(out_of_range(v, x).prefixed(call));
            }
            if self.phase.initialized() {
                self.model.check_real(vr, x).map_err(|e| e.prefixed(call))?;
            }
        }
        self.settled = false;
        for (&vr, &x) in vrs.iter().zip(values) {
            self.model.set_real(vr, x)?;
        }
        Ok(())
    }

    pub fn set_integers(&mut self, call: CallName, vrs: &[u32], values: &[i32]) -> FmiResult {
        self.set_all(
            call,
            Family::Integer,
            vrs,
            values,
            |v, x| match v.kind {
                Kind::Enumeration { type_name, values } if !values.contains(&x) => Err(FmiError::error(format!(
                    "{} = {x} is not a value of the enumeration {type_name} (allowed {}..{})",
                    v.name,
                    values.iter().min().unwrap_or(&0),
                    values.iter().max().unwrap_or(&0)
                ))),
                _ => Ok(()),
            },
            |m, vr, x| m.set_integer(vr, x),
        )
    }

    pub fn set_booleans(&mut self, call: CallName, vrs: &[u32], values: &[i32]) -> FmiResult {
        self.set_all(
            call,
            Family::Boolean,
            vrs,
            values,
            |v, x| {
                if x == 0 || x == 1 {
                    Ok(())
                } else {
                    Err(FmiError::error(format!("{} = {x} is not a Boolean (allowed 0 = false, 1 = true)", v.name)))
                }
            },
            |m, vr, x| m.set_boolean(vr, x != 0),
        )
    }

    /// `fmi2SetRealInputDerivatives`: first derivatives of Real inputs.
    pub fn set_input_derivatives(&mut self, call: CallName, vrs: &[u32], orders: &[i32], values: &[f64]) -> FmiResult {
        if !self.model.description().can_interpolate_inputs {
            return Err(FmiError::error(format!("{}: canInterpolateInputs is false", call)));
        }
        for ((&vr, &order), &value) in vrs.iter().zip(orders).zip(values) {
            let v = self.variable(call, vr, Family::Real)?;
            if v.causality != Causality::Input {
                return Err(FmiError::error(format!("{}: {} is not an input", call, v.name)));
            }
            if order != 1 {
                return Err(FmiError::error(format!(
                    "{}: order {order} for {}: only first derivatives (order 1) are supported",
                    call,
                    v.name
                )));
            }
            // Finite always: an input without a maxRate has an infinite one.
            if !(value.is_finite() && value.abs() <= v.max_rate) {
                let unit = match v.unit {
                    "" | "1" => "1/s".to_string(),
                    "m/s" => "m/s2".to_string(),
                    u => format!("{u}/s"),
                };
                return Err(FmiError::error(format!(
                    "{}: derivative of {} = {value:?} {unit} is outside its allowed range [-{2:?}, {2:?}]",
                    call,
                    v.name,
                    v.max_rate
                )));
            }
        }
        let mut model = self.model.clone();
        for (&vr, &value) in vrs.iter().zip(values) {
            model.set_input_derivative(vr, value).map_err(|e| FmiError::error(format!("{}: {}", call, e.message)))?;
        }
        self.model = model;
        self.settled = false;
        Ok(())
    }
}

#[cold]
fn prefixed(e: FmiError, call: CallName) -> FmiError {
    e.prefixed(call)
}

#[cold]
fn wrong_variable(call: CallName, vr: u32, found: Option<&Variable>, family: Family) -> FmiError {
    FmiError::error(match found {
        None => format!("{}: unknown value reference {vr}", call),
        Some(v) => format!(
            "{}: {} (value reference {vr}) is of type {}, not {}",
            call,
            v.name,
            v.family.name(),
            family.name()
        ),
    })
}

#[cold]
fn not_settable(call: CallName, v: &Variable, phase: Phase, state: String) -> FmiError {
    let why = match v.causality {
        Causality::Parameter if phase == Phase::ContinuousTimeMode => {
            format!("it is a tunable parameter and cannot be set in {state} (in Model Exchange only in event mode)")
        }
        Causality::Input => format!("it is an input of variability {:?} and cannot be set in {state} (only continuous inputs can)", v.variability),
        Causality::Parameter => format!(
            "it is a {} parameter and cannot be set in {state} (only before initialization ends)",
            if v.variability == Variability::Fixed { "fixed" } else { "tunable" },
        ),
        other => format!("its causality is {other:?}; only parameters and inputs can be set"),
    };
    FmiError::error(format!("{}: cannot set {}: {why}", call, v.name))
}
