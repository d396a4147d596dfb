//! The converting span's data, one communication step, and the hooks the
//! FMI layer calls (initialization, steps, Model Exchange, FMU states).

use crate::description::{Real, DESCRIPTION};
use crate::parameters::{Inputs, Parameters, Rates};
use crate::physics::{self, Outputs};
use crate::sensor::SensorScale;
use crate::stepping;
use crate::records;
use crate::schedule::{self, WebChange};
use crate::jacobian::{self, Direction, Linearization, Point, Tangents};
use fmi_core::{Compiled, Event, Experiment, FmiError, FmiResult, Jacobian, Model, Resources, StateReader, StateWriter};
use crate::web_state;
use solver::CompensatedSum;
use std::sync::Arc;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct ConvertingSpan {
    pub params: Parameters,
    pub inputs: Inputs,
    /// First derivatives of the inputs over the next step, when the importer
    /// gives them (`fmi2SetRealInputDerivatives`); cleared after each step.
    input_rates: Option<Inputs>,
    /// The state: unstretched length of web in the span, m.
    pub(crate) unstretched: CompensatedSum,
    /// Rates of inputs that enter the outputs (dv_b/dt, dL/dt): the given
    /// derivatives, or backward differences over the last step.
    rates: Rates,
    /// web_b.v and L at the start of the last step, and its length.
    previous: Previous,
    /// The step an adaptive method proposes next, kept between steps.
    adaptive_step: f64,
    /// Derived when initialization ends.
    sensor: SensorScale,
    tolerance: f64,
    /// Where the tension crossed zero inside the last step (slack web).
    slack_event: Option<Event>,
    /// The time now, s, and the profile's web changes (a splice) with the next one due.
    time: f64,
    web_changes: Arc<[WebChange]>,
    next_change: usize,
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Previous {
    speed_b: f64,
    length: f64,
    step: f64,
}

impl ConvertingSpan {
    pub fn unstretched_length(&self) -> f64 {
        self.unstretched.value()
    }

    /// m = rho_l2 * x [E10].
    pub fn web_mass(&self) -> f64 {
        physics::web_mass(&self.params.span_web, self.unstretched.value())
    }

    /// dv_b/dt and dL/dt as the outputs use them [E11]: the importer's input
    /// derivatives when it gave them for this step, otherwise the backward
    /// differences over the last communication step.
    pub fn input_rates(&self) -> Rates {
        match &self.input_rates {
            Some(r) => Rates {
                speed_b: r.speed_b,
                length: physics::length_rate(&self.params, &self.inputs, r),
            },
            None => self.rates,
        }
    }

    /// Every output now. Only the effects that read the input rates
    /// (damping, web mass) pay for them.
    #[inline(always)]
    pub fn outputs(&self) -> Outputs {
        let p = &self.params;
        let rates = if physics::needs_input_rates(&p.effects) { self.input_rates() } else { Rates::default() };
        physics::outputs(p, &self.inputs, self.unstretched, rates, &self.sensor)
    }

    /// d(unknown)/d(known) (docs/directional-derivatives.md): `known` is an input or the state, `unknown`
    /// an output, the state or its derivative; during initialization the
    /// state is the initial state's function of the inputs.
    pub fn partial_derivative(&self, unknown: Real, known: Real, of: Jacobian) -> FmiResult<f64> {
        let mut d = Self::direction(known).ok_or_else(|| FmiError::error(format!("{} is not a known", known.name())))?;
        if of == Jacobian::Initialization {
            d.x = jacobian::initial_state_tangent(&self.params, &self.inputs, &d.u);
        }
        Self::along(&self.tangents(&d), unknown).ok_or_else(|| FmiError::error(format!("{} is not an unknown", unknown.name())))
    }

    /// The unit direction of one known: the state or an input (None: neither).
    pub fn direction(known: Real) -> Option<Direction> {
        let mut d = Direction::default();
        if known == Real::unstretchedLength {
            d.x = 1.0;
        } else {
            *Self::input_field(&mut d.u, known)? = 1.0;
        }
        Some(d)
    }

    /// How everything moves along `d` now, at the input rates the outputs use (held).
    #[inline]
    pub fn tangents(&self, d: &Direction) -> Tangents {
        self.linearize().along(d)
    }

    /// What the tangents along every direction share, now (several directions: `along` each).
    #[inline]
    pub fn linearize(&self) -> Linearization<'_> {
        let p = &self.params;
        let effects = physics::needs_input_rates(&p.effects);
        let point = Point {
            params: p,
            inputs: &self.inputs,
            x: self.unstretched,
            rates: if effects { self.input_rates() } else { Rates::default() },
            given: self.input_rates.as_ref().filter(|_| effects),
            sensor: &self.sensor,
        };
        point.linearize()
    }

    /// The forces and strain at the span's ends and dx/dt, at once (what a line's rollers read).
    #[inline(always)]
    pub fn forces(&self) -> physics::Forces {
        let p = &self.params;
        let rates = if physics::needs_input_rates(&p.effects) { self.input_rates() } else { Rates::default() };
        physics::forces(p, &self.inputs, self.unstretched, rates)
    }

    /// dx/dt [E2] now, with the inputs as they are.
    pub fn unstretched_rate(&self) -> f64 {
        let length = physics::span_length(&self.params, &self.inputs);
        physics::unstretched_rate(&self.inputs, physics::strain(length, self.unstretched, 0.0))
    }

    /// The web's pull before the slack clamp [E5] now.
    pub fn pull(&self) -> f64 {
        let rates = if physics::needs_input_rates(&self.params.effects) { self.input_rates() } else { Rates::default() };
        self.web_force_at(self.unstretched, &self.inputs, rates.length)
    }

    /// The web's pull before the slack clamp [E5] for a state x and inputs u.
    pub(crate) fn web_force_at(&self, x: CompensatedSum, u: &Inputs, length_rate: f64) -> f64 {
        let length = physics::span_length(&self.params, u);
        physics::web_force(&self.params, u, length, x.value(), physics::strain(length, x, 0.0), length_rate)
    }

    /// Advances over one communication step of length h [E3].
    fn advance(&mut self, h: f64) -> FmiResult {
        let rates = self.input_rates.filter(|r| *r != Inputs::default());
        let step = stepping::Step { params: &self.params, start: &self.inputs, rates: rates.as_ref(), x0: self.unstretched, h };
        let (next, adaptive_step) = step.integrate(self.params.solver, self.tolerance, self.adaptive_step)?;
        let start = self.inputs;
        let x = next.value();
        let end = match &rates {
            Some(r) => {
                let end = start.advanced(r, h);
                check_inputs_at_end(&end, r, h)?;
                end
            }
            None => start,
        };
        let length_after = physics::span_length(&self.params, &end);
        if self.params.effects.variable_length && !(length_after >= physics::min_length()) {
            return Err(FmiError::discard(format!(
                "variableLength: the rollers would come {length_after} m apart by the end of the step, closer than \
                 the shortest span L may be ({} m); take a shorter step",
                physics::min_length()
            )));
        }
        if !physics::representable(length_after, x) {
            let why = if start.speed_b < start.speed_a.min(0.0) {
                "web fed in from both ends grows without bound"
            } else if length_after > (1.0 + physics::max_strain()) * x {
                "the strain would pass its physical bound (web pulled out faster than it comes in)"
            } else {
                "the method could not follow the span over this step"
            };
            return Err(FmiError::discard(format!(
                "the unstretched length of web in the span would become {x} m (web_a.v = {}, web_b.v = {}): \
                 {why}; take a shorter step",
                start.speed_a, start.speed_b
            )));
        }
        // Commit: nothing above changed the model.
        self.slack_event = if self.params.effects.prevent_negative_tension {
            self.slack_crossing(&start, rates.as_ref(), next, h)
        } else {
            None
        };
        if physics::needs_input_rates(&self.params.effects) {
            self.update_rates(&start, rates.as_ref(), h);
        }
        if let Some(r) = rates {
            self.inputs = start.advanced(&r, h);
        }
        self.input_rates = None;
        self.unstretched = next;
        self.adaptive_step = adaptive_step;
        Ok(())
    }

    /// The rates the outputs use after a step [E11]: the given derivatives,
    /// or backward differences between the starts of the last two steps.
    /// Only the effects that read them (damping, web mass) pay for this.
    fn update_rates(&mut self, start: &Inputs, given: Option<&Inputs>, h: f64) {
        let p = &self.params;
        let length = physics::span_length(p, start);
        // An estimate from a very short step is held to the inputs' declared
        // maximum rates (given derivatives are checked against them when set).
        let bound = |x: f64, limit: f64| x.clamp(-limit, limit);
        self.rates = match given {
            Some(r) => Rates { speed_b: r.speed_b, length: physics::length_rate(p, &start.advanced(r, h), r) },
            None if self.previous.step > 0.0 => Rates {
                speed_b: bound((start.speed_b - self.previous.speed_b) / self.previous.step, physics::max_rate(Real::web_b_v)),
                // |dL/dt| <= |d(r_b - r_a)/dt| <= 2*sqrt(2) times a coordinate's maximum rate.
                length: bound((length - self.previous.length) / self.previous.step, 2.0 * std::f64::consts::SQRT_2 * physics::max_rate(Real::frame_a_x)),
            },
            None => Rates::default(),
        };
        self.previous = Previous { speed_b: start.speed_b, length, step: h };
    }
}

/// Inputs moved by their derivatives must still be in their ranges at the
/// end of the step (and so all along it: they move linearly).
#[cold]
fn check_inputs_at_end(end: &Inputs, rates: &Inputs, h: f64) -> FmiResult {
    let mut end = *end;
    let mut rates = *rates;
    for var in Real::ALL {
        let (Some(x), Some(r)) = (ConvertingSpan::input_field(&mut end, var).copied(), ConvertingSpan::input_field(&mut rates, var).copied()) else {
            continue;
        };
        let Some(v) = DESCRIPTION.variable(var.vr()) else { continue };
        if !v.range.contains(x) {
            return Err(FmiError::discard(format!(
                "{} would reach {x} by the end of the step (derivative {r} over {h} s), outside its range {}; take a shorter step",
                v.name, v.range
            )));
        }
    }
    Ok(())
}

impl ConvertingSpan {
    /// Swaps in the webs of the changes due now; the strain carries over.
    fn apply_due_changes(&mut self) {
        while let Some(change) = self.web_changes.get(self.next_change).filter(|c| profiles::due(c.time, self.time)) {
            change.apply(&mut self.params);
            // Checked when the profile was read: the scale exists.
            self.sensor = SensorScale::new(&self.params).unwrap_or(self.sensor);
            self.next_change += 1;
        }
    }

    /// The span at least as long as the shortest L, and its strain within bounds.
    #[inline]
    fn configuration_valid(&self) -> FmiResult {
        let length = physics::span_length(&self.params, &self.inputs);
        if length >= physics::min_length() && physics::representable(length, self.unstretched.value()) {
            Ok(())
        } else {
            self.why_outputs_undefined(length)
        }
    }

    #[cold]
    fn why_outputs_undefined(&self, length: f64) -> FmiResult {
        Err(FmiError::error(format!(
            "outputs are not defined for a span length of {length} m with {} m of unstretched web \
             (the span is at least {} m long, and its strain at most {})",
            self.unstretched.value(),
            physics::min_length(),
            physics::max_strain()
        )))
    }
}

impl Model for ConvertingSpan {
    fn instantiate(_: &Resources) -> FmiResult<Self> {
        Ok(Self::at_start_values())
    }

    #[inline(always)]
    fn description(&self) -> &'static fmi_core::description::ModelDescription {
        &DESCRIPTION
    }

    fn save_state(&self, out: &mut StateWriter) {
        out.bool(self.input_rates.is_some());
        let mut rates = self.input_rates.unwrap_or_default();
        for var in Real::ALL {
            if let Some(rate) = Self::input_field(&mut rates, var) {
                out.f64(*rate);
            }
        }
        out.f64(self.unstretched.hi());
        out.f64(self.unstretched.lo());
        for x in [self.rates.speed_b, self.rates.length, self.previous.speed_b, self.previous.length, self.previous.step] {
            out.f64(x);
        }
        out.f64(self.adaptive_step);
        out.f64(self.tolerance);
        // The records' stress–strain tables: a state restores without the files.
        for web in [&self.params.incoming, &self.params.span_web] {
            web_state::save_curve(web, out);
        }
        out.f64(self.time);
        out.i32(self.next_change as i32);
        schedule::save(&self.web_changes, out);
    }

    fn load_state(&mut self, r: &mut StateReader) -> FmiResult {
        let given = r.bool("input derivatives given")?;
        let mut rates = Inputs::default();
        for var in Real::ALL {
            if let Some(rate) = Self::input_field(&mut rates, var) {
                *rate = r.finite(var.name())?;
            }
        }
        self.input_rates = given.then_some(rates);
        self.unstretched = CompensatedSum::from_parts(r.finite("unstretched length")?, r.finite("unstretched length carry")?);
        self.rates = Rates { speed_b: r.finite("dv_b/dt")?, length: r.finite("dL/dt")? };
        self.previous = Previous {
            speed_b: r.finite("previous web_b.v")?,
            length: r.finite("previous length")?,
            step: r.finite("previous step")?,
        };
        self.adaptive_step = r.finite("adaptive step")?;
        self.tolerance = r.finite("effective tolerance")?;
        for (web, what) in [(&mut self.params.incoming, "wp1 stress_strain"), (&mut self.params.span_web, "wp2 stress_strain")] {
            web.curve = web_state::load_curve(r, what)?;
        }
        self.time = r.finite("time")?;
        let next = r.i32("next web change")?;
        self.web_changes = schedule::load_saved(r)?;
        if !(0..=self.web_changes.len() as i64).contains(&(next as i64)) {
            return Err(FmiError::error(format!("next web change {next} of {}", self.web_changes.len())));
        }
        self.next_change = next as usize;
        // Derived from the parameters; a state saved before initialization
        // ended gets the scale of its parameters, which initialization recomputes.
        self.sensor = SensorScale::new(&self.params).unwrap_or_default();
        Ok(())
    }

    fn set_input_derivative(&mut self, vr: u32, value: f64) -> FmiResult {
        let var = Real::from_vr(vr).ok_or_else(|| fmi_core::model::unknown_vr(vr))?;
        if value != 0.0 {
            stepping::method(self.params.solver, true).map_err(|e| e.prefixed(&format!("derivative of {} = {value}", var.name())))?;
        }
        let mut rates = self.input_rates.unwrap_or_default();
        *Self::input_field(&mut rates, var).ok_or_else(|| FmiError::error(format!("{} is not an input", var.name())))? = value;
        self.input_rates = Some(rates);
        Ok(())
    }

    fn initialize(&mut self, experiment: &Experiment, resources: &Resources) -> FmiResult<Vec<String>> {
        records::apply(&mut self.params, resources)?;
        let p = &self.params;
        let length = physics::span_length(p, &self.inputs);
        if !(length >= physics::min_length()) {
            return Err(FmiError::error(format!(
                "variableLength: the span length |frame_b - frame_a| = {length} m must be at least {} m, \
                 the shortest span L may be (the rollers nearly coincide)",
                physics::min_length()
            )));
        }
        crate::parameters::check_derived(p)?;
        let strain = if p.start_at_equilibrium {
            physics::equilibrium_strain(&self.inputs).ok_or_else(|| {
                FmiError::error(format!(
                    "startAtEquilibrium: the inputs web_a.v = {} m/s, web_b.v = {} m/s, web_a.eps = {} have no steady state \
                     (1+eps_b) = (v_b/v_a)(1+eps_a) > 0: the speeds must have the same sign, or web_a.v = 0; \
                     or set startAtEquilibrium = false and eps_start",
                    self.inputs.speed_a, self.inputs.speed_b, self.inputs.strain_a
                ))
            })?
        } else {
            p.strain_start
        };
        if strain > physics::max_strain() {
            return Err(FmiError::error(format!(
                "startAtEquilibrium: the inputs web_a.v = {} m/s, web_b.v = {} m/s, web_a.eps = {} give a steady-state \
                 strain of {strain}, beyond the largest strain a web may have ({}); or set startAtEquilibrium = false and eps_start",
                self.inputs.speed_a, self.inputs.speed_b, self.inputs.strain_a, physics::max_strain()
            )));
        }
        if experiment.model_exchange {
            // Model Exchange gives the current inputs only, not their rates.
            if p.effects.include_mass {
                return Err(FmiError::error(
                    "includeMass needs dv_b/dt (web_b.v's rate), which Model Exchange does not provide: \
                     use Co-Simulation (input derivatives or the documented estimate) or set includeMass = false",
                ));
            }
            if p.effects.include_damping && p.effects.variable_length {
                return Err(FmiError::error(
                    "includeDamping with variableLength needs dL/dt (the rollers' speeds), which Model Exchange \
                     does not provide: use Co-Simulation or switch one of them off",
                ));
            }
        }
        stepping::method(p.solver, self.input_rates.is_some_and(|r| r != Inputs::default()))?;
        self.sensor = SensorScale::new(p)
            .ok_or_else(|| FmiError::error(format!("toUnitV = {} or toUnitF = {} has no unit", p.speed_unit, p.force_unit)))?;
        self.tolerance = effective_tolerance(p.tolerance, experiment.tolerance);
        self.unstretched = physics::unstretched_length(length, strain);
        self.rates = Rates::default();
        self.previous = Previous::default();
        self.adaptive_step = 0.0;
        let (web_changes, unmatched) = schedule::load(self, |m| &mut m.params, resources)?;
        self.web_changes = web_changes;
        self.next_change = 0;
        self.time = experiment.start_time;
        Ok(unmatched.into_iter().collect())
    }

    #[inline]
    fn set_time(&mut self, time: f64) {
        self.time = time;
    }

    fn do_step(&mut self, h: f64) -> FmiResult {
        if self.next_change < self.web_changes.len() {
            self.apply_due_changes();
        }
        self.advance(h)
    }

    /// A web change is a time event where the right-hand side jumps: the states are reported changed
    /// there, so that an importer restarts its integrator.
    fn event_update(&mut self) -> fmi_core::EventUpdate {
        let before = self.next_change;
        self.apply_due_changes();
        let changed = self.next_change != before;
        fmi_core::EventUpdate { next_event_time: self.web_changes.get(self.next_change).map(|c| c.time), states_changed: changed }
    }

    /// A state saved with rollers transiently too close is still the model's
    /// own: with a moving span the configuration is the inputs' (`inputs_valid`).
    fn outputs_defined(&self) -> FmiResult {
        crate::parameters::check_derived(&self.params)?;
        if self.params.effects.variable_length {
            Ok(())
        } else {
            self.configuration_valid()
        }
    }

    /// With a fixed length every state the model holds after a step or
    /// initialization is valid; moving rollers can make it invalid.
    #[inline]
    fn inputs_valid(&self) -> FmiResult {
        if self.params.effects.variable_length {
            self.configuration_valid()
        } else {
            Ok(())
        }
    }

    /// Unstrained web in the span until initialization computes the start.
    fn provisional_state(&mut self) {
        self.unstretched = physics::unstretched_length(self.params.span_length, 0.0);
    }

    fn step_events(&self) -> &[Event] {
        self.slack_event.as_slice()
    }

    // Model Exchange [E13]: the importer integrates the unstretched length.

    fn partial_derivative(&self, unknown: u32, known: u32, of: Jacobian) -> FmiResult<f64> {
        let real = |vr| Real::from_vr(vr).ok_or_else(|| fmi_core::model::unknown_vr(vr));
        ConvertingSpan::partial_derivative(self, real(unknown)?, real(known)?, of)
    }

    fn get_continuous_states(&self, x: &mut [f64]) -> FmiResult {
        x[0] = self.unstretched.value();
        Ok(())
    }

    fn set_continuous_states(&mut self, x: &[f64]) -> FmiResult {
        if !physics::representable(physics::span_length(&self.params, &self.inputs), x[0]) {
            // An integrator's trial value, not a web: ask for a smaller step.
            return Err(FmiError::discard(format!(
                "unstretchedLength = {} m is not a length of web this span can hold (0 < x < L/2^-52)",
                x[0]
            )));
        }
        self.unstretched = CompensatedSum::from_parts(x[0], 0.0);
        Ok(())
    }

    fn get_derivatives(&self, dx: &mut [f64]) -> FmiResult {
        dx[0] = self.unstretched_rate();
        Ok(())
    }

    /// The span length: the unstretched length is about that big.
    fn get_nominals(&self, nominals: &mut [f64]) -> FmiResult {
        let length = physics::span_length(&self.params, &self.inputs);
        nominals[0] = if length > 0.0 { length } else { 1.0 };
        Ok(())
    }

    /// The web's pull for a slack web (it crosses zero where the web goes
    /// slack or takes up tension again); a constant 1 (never an event) otherwise.
    fn get_event_indicators(&self, z: &mut [f64]) -> FmiResult {
        z[0] = if self.params.effects.prevent_negative_tension {
            self.web_force_at(self.unstretched, &self.inputs, 0.0)
        } else {
            1.0
        };
        Ok(())
    }
}

/// The tolerance rule [E12]: the parameter `tolerance` when the user set it;
/// left at its start value, the tolerance of fmi2SetupExperiment if the
/// importer gave one.
pub fn effective_tolerance(parameter: f64, experiment: Option<f64>) -> f64 {
    let default = match DESCRIPTION.variable(Real::tolerance.vr()).map(|v| v.start) {
        Some(fmi_core::description::Start::Real(x)) => x,
        _ => parameter,
    };
    match experiment {
        Some(t) if parameter == default => t,
        _ => parameter,
    }
}
