//! A part of the line: the span's or the Roller's own model, called through
//! the same `Model` and `Variables` functions its FMU's C API calls, so the
//! line runs the parts' equations and nothing else. Unboxed, so that a copy
//! of the line (to undo a failed step) allocates nothing: the models share
//! their profiles and records by `Arc`.

use crate::port::Port;
use crate::spec::PartSpec;
use converting_span::parameters::SlackRule;
use converting_span::ConvertingSpan;
use fmi_core::description::ModelDescription;
use fmi_core::{Compiled, EventUpdate, Experiment, FmiError, FmiResult, Jacobian, Model, Resources, StateReader, StateWriter, Variables};
use roller::parameters::Structure;
use roller::state::State;
use roller::Roller;

/// What a span computes at once for the rollers at its ends (forces, strain, dx/dt): a line
/// keeps it per span through an evaluation (`Part::read`).
pub use converting_span::Forces;

/// A part's unit directions of its knowns, made once (`Part::directions`).
#[derive(Clone, Debug, PartialEq)]
pub enum Directions {
    Span(Vec<converting_span::jacobian::Direction>),
    Roller(Vec<roller::jacobian::Direction>),
}

impl Directions {
    pub fn len(&self) -> usize {
        match self {
            Directions::Span(d) => d.len(),
            Directions::Roller(d) => d.len(),
        }
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum Part {
    Span(ConvertingSpan),
    Roller(Roller),
}

macro_rules! each {
    ($self:expr, $m:ident => $e:expr) => {
        match $self {
            Part::Span($m) => $e,
            Part::Roller($m) => $e,
        }
    };
}

impl Part {
    pub fn span() -> Part {
        Part::Span(ConvertingSpan::at_start_values())
    }

    pub fn roller() -> Part {
        Part::Roller(Roller::at_start_values())
    }

    /// Variable `vr` of this part as a `Port`; None if it is no Real of the part.
    pub fn port(&self, vr: u32) -> Option<Port> {
        match self {
            Part::Span(_) => converting_span::description::Real::from_vr(vr).map(Port::Span),
            Part::Roller(_) => roller::description::Real::from_vr(vr).map(Port::Roller),
        }
    }

    pub fn description(&self) -> &'static ModelDescription {
        match self {
            Part::Span(_) => ConvertingSpan::compiled(),
            Part::Roller(_) => Roller::compiled(),
        }
    }

    #[inline]
    pub fn get_real(&self, vr: u32) -> FmiResult<f64> {
        each!(self, m => m.get_real(vr))
    }
    #[inline]
    pub fn set_real(&mut self, vr: u32, x: f64) -> FmiResult {
        each!(self, m => m.set_real(vr, x))
    }
    pub fn get_integer(&self, vr: u32) -> FmiResult<i32> {
        each!(self, m => m.get_integer(vr))
    }
    pub fn set_integer(&mut self, vr: u32, x: i32) -> FmiResult {
        each!(self, m => m.set_integer(vr, x))
    }
    pub fn get_boolean(&self, vr: u32) -> FmiResult<bool> {
        each!(self, m => m.get_boolean(vr))
    }
    pub fn set_boolean(&mut self, vr: u32, x: bool) -> FmiResult {
        each!(self, m => m.set_boolean(vr, x))
    }
    pub fn get_string(&self, vr: u32) -> FmiResult<&str> {
        each!(self, m => m.get_string(vr))
    }
    pub fn set_string(&mut self, vr: u32, x: &str) -> FmiResult {
        each!(self, m => m.set_string(vr, x))
    }
    pub fn set_input_derivative(&mut self, vr: u32, x: f64) -> FmiResult {
        each!(self, m => m.set_input_derivative(vr, x))
    }
    pub fn check_real(&self, vr: u32, x: f64) -> FmiResult {
        each!(self, m => m.check_real(vr, x))
    }
    pub fn save_variables(&self, out: &mut StateWriter) {
        each!(self, m => m.save_variables(out))
    }
    pub fn load_variables(&mut self, input: &mut StateReader) -> FmiResult {
        each!(self, m => m.load_variables(input))
    }
    pub fn save_state(&self, out: &mut StateWriter) {
        each!(self, m => m.save_state(out))
    }
    pub fn load_state(&mut self, input: &mut StateReader) -> FmiResult {
        each!(self, m => m.load_state(input))
    }
    pub fn initialize(&mut self, experiment: &Experiment, resources: &Resources) -> FmiResult<Vec<String>> {
        each!(self, m => m.initialize(experiment, resources))
    }
    #[inline]
    pub fn set_time(&mut self, t: f64) {
        each!(self, m => m.set_time(t))
    }
    pub fn event_update(&mut self) -> EventUpdate {
        each!(self, m => m.event_update())
    }
    #[inline]
    pub fn get_states(&self, x: &mut [f64]) -> FmiResult {
        each!(self, m => m.get_continuous_states(x))
    }
    #[inline]
    pub fn set_states(&mut self, x: &[f64]) -> FmiResult {
        each!(self, m => m.set_continuous_states(x))
    }
    #[inline]
    pub fn get_derivatives(&self, dx: &mut [f64]) -> FmiResult {
        each!(self, m => m.get_derivatives(dx))
    }
    pub fn get_nominals(&self, n: &mut [f64]) -> FmiResult {
        each!(self, m => m.get_nominals(n))
    }
    pub fn get_event_indicators(&self, z: &mut [f64]) -> FmiResult {
        each!(self, m => m.get_event_indicators(z))
    }
    pub fn partial_derivative(&self, unknown: u32, known: u32) -> FmiResult<f64> {
        each!(self, m => Model::partial_derivative(m, unknown, known, Jacobian::ContinuousTime))
    }
    pub fn outputs_defined(&self) -> FmiResult {
        each!(self, m => m.outputs_defined())
    }
    pub fn inputs_valid(&self) -> FmiResult {
        each!(self, m => m.inputs_valid())
    }

    /// Moves the part to time t with its integrated states (`active`, indices into its state
    /// vector) at `x`; the others stay.
    #[inline(always)]
    pub fn set_point(&mut self, t: f64, active: &[usize], x: &[f64]) -> FmiResult {
        match self {
            Part::Span(s) => {
                s.set_time(t);
                s.set_continuous_states(x)
            }
            Part::Roller(r) => {
                r.set_time(t);
                r.set_active_states(active, x)
            }
        }
    }

    /// The value of the part's output `port`. A span's comes from its forces, computed into
    /// `held` where `fresh` (its inputs moved since) and read from there otherwise.
    #[inline(always)]
    pub fn read(&self, port: Port, fresh: bool, held: &mut Forces) -> f64 {
        match (self, port) {
            (Part::Span(s), Port::Span(var)) => {
                if fresh {
                    *held = s.forces();
                }
                ConvertingSpan::group_real(held, var).unwrap_or_else(|| s.real(var))
            }
            (Part::Roller(r), Port::Roller(var)) => r.real(var),
            _ => unreachable!("a port is resolved from its own part"),
        }
    }

    /// The value of the part's Real `port`.
    #[inline(always)]
    pub fn real(&self, port: Port) -> f64 {
        match (self, port) {
            (Part::Span(s), Port::Span(var)) => s.real(var),
            (Part::Roller(r), Port::Roller(var)) => r.real(var),
            _ => unreachable!("a port is resolved from its own part"),
        }
    }

    /// Sets the part's input (or parameter) `port`.
    #[inline(always)]
    pub fn write(&mut self, port: Port, value: f64) -> FmiResult {
        match (self, port) {
            (Part::Span(s), Port::Span(var)) => s.set_real_var(var, value),
            (Part::Roller(r), Port::Roller(var)) => r.set_real_var(var, value),
            _ => unreachable!("a port is resolved from its own part"),
        }
    }

    /// The derivatives of the integrated states `active` into `dx` from `first` on, by the
    /// part's own functions; a span's from the forces `held` where they are its current ones.
    #[inline(always)]
    pub fn active_derivatives(&self, active: &[usize], dx: &mut [f64], first: usize, held: Option<&Forces>) {
        match self {
            Part::Span(s) => dx[first] = held.map_or_else(|| s.unstretched_rate(), |f| f.unstretched_rate),
            Part::Roller(r) => {
                let d = r.derivatives();
                for (k, &i) in active.iter().enumerate() {
                    dx[first + k] = d[i];
                }
            }
        }
    }

    /// A span of fixed length: its forces give its dx/dt too (`Part::active_derivatives`).
    pub fn rate_with_forces(&self) -> bool {
        matches!(self, Part::Span(s) if !s.params.effects.variable_length)
    }

    /// A span of variable length checks its state against the frames the last evaluation gave
    /// it: an evaluation then depends on the one before.
    pub fn reads_earlier_inputs(&self) -> bool {
        matches!(self, Part::Span(s) if s.params.effects.variable_length)
    }

    /// A span's pull before its slack clamp now [E5] (a roller: None).
    pub fn pull(&self) -> Option<f64> {
        match self {
            Part::Span(s) => Some(s.pull()),
            Part::Roller(_) => None,
        }
    }

    /// Whether a span keeps its tension from going negative (`preventNegativeTension`).
    pub fn prevents_negative_tension(&self) -> bool {
        matches!(self, Part::Span(s) if s.params.effects.prevent_negative_tension)
    }

    /// Who decides that a span is slack: a laminate's layer is told by its laminate ([M6]).
    pub fn set_slack_rule(&mut self, rule: SlackRule) {
        if let Part::Span(s) = self {
            s.params.slack_rule = rule;
        }
    }

    /// A span's strain now (the integrator scales its tolerance by it); None for a roller.
    pub fn strain(&self) -> Option<f64> {
        match self {
            Part::Span(s) => Some(s.forces().strain),
            Part::Roller(_) => None,
        }
    }

    /// Whether the equations depend on time at fixed states and inputs at t (a profile's slope).
    pub fn varies_with_time(&self, t: f64) -> bool {
        matches!(self, Part::Roller(r) if r.varies_with_time(t))
    }

    /// State `index` keeps its start value in the steady state: a roll's radius (never steady
    /// while web winds), a speed a table prescribes.
    pub fn held_at_steady_state(&self, index: usize) -> bool {
        matches!(self, Part::Roller(r) if r.held_at_steady_state(State::ALL[index]))
    }

    /// Where state `index` is the angular speed of a roll being wound, its radius's state index: a
    /// steady state holds that roll's surface speed, so omega moves with the radius ([R1], [R3]).
    pub fn wound_roll_radius(&self, index: usize) -> Option<usize> {
        match self {
            // A stepwise radius on its plateau (at the start, unless it merges over the whole layer) holds the surface
            // speed at a steady omega [R17]: no correction.
            Part::Roller(r) if r.params.winding() && !r.speed_prescribed() && index == State::Omega.index() && r.contact_moves_with_radius() => {
                Some(State::Radius.index())
            }
            _ => None,
        }
    }

    /// A roller's sampled loop starts again at t: continuous until its first sample, due at t [R14];
    /// whether the part has one.
    pub fn restart_hold(&mut self, t: f64) -> bool {
        match self {
            Part::Roller(r) if r.params.sampled() => {
                r.restart_hold(t);
                true
            }
            _ => false,
        }
    }

    /// A roller's contact held (`Roller::hold_contact`) while the line solves its steady state, or its bristle.
    pub fn hold_contact(&mut self, held: bool) {
        if let Part::Roller(r) = self {
            r.hold_contact(held);
        }
    }

    /// Where a roller's grip has reached its limit, what it needs against what it can give (`Roller::beyond_grip`).
    pub fn beyond_grip(&self) -> Option<String> {
        match self {
            Part::Roller(r) => r.beyond_grip(),
            Part::Span(_) => None,
        }
    }

    /// A roller's load cell for a wrap angle with this cosine.
    pub fn load_cell(&self, cos_wrap: f64) -> FmiResult<f64> {
        match self {
            Part::Roller(r) => Ok(r.load_cell(cos_wrap)),
            Part::Span(_) => Err(FmiError::error("a load cell sits on a roller, not on a span")),
        }
    }

    /// The unit directions of `knowns` (its states and inputs); None if one is neither.
    pub fn directions(&self, knowns: &[Port]) -> Option<Directions> {
        Some(match self {
            Part::Span(_) => Directions::Span(
                knowns.iter().map(|k| if let Port::Span(k) = *k { ConvertingSpan::direction(k) } else { None }).collect::<Option<_>>()?,
            ),
            Part::Roller(_) => Directions::Roller(
                knowns.iter().map(|k| if let Port::Roller(k) = *k { Roller::direction(k) } else { None }).collect::<Option<_>>()?,
            ),
        })
    }

    /// The partials of `unknowns` (its outputs, states, derivatives) along each of its knowns'
    /// `directions` by the part's own tangents, a row of `out` per direction; false if one is
    /// no unknown of the part.
    pub fn partials(&self, directions: &Directions, unknowns: &[Port], out: &mut [f64]) -> bool {
        match (self, directions) {
            (Part::Span(s), Directions::Span(ds)) => {
                let at = s.linearize();
                rows(ds, unknowns, out, |d| at.along(d), |t, u| if let Port::Span(u) = u { ConvertingSpan::along(t, u) } else { None })
            }
            (Part::Roller(r), Directions::Roller(ds)) => {
                // Every direction's tangents from one evaluation of the right-hand side per `along_each`.
                let mut rows = out.chunks_exact_mut(unknowns.len().max(1));
                r.linearize().along_each(ds, |t| {
                    let Some(row) = rows.next() else { return true };
                    unknowns.iter().zip(row).all(|(&u, o)| if let Port::Roller(u) = u { Roller::along(t, u).map(|x| *o = x).is_some() } else { false })
                })
            }
            _ => false,
        }
    }

    /// Whether the part's partials along the line's knowns stay the same until an event or a
    /// parameter changes it (a roller's `tangents_fixed`); a span's move with its strain.
    pub fn tangents_fixed(&self) -> bool {
        matches!(self, Part::Roller(r) if r.tangents_fixed())
    }

    /// The part's continuous states the line integrates (indices into its Model Exchange state
    /// vector): a span's one, the ones a Roller says move (`Roller::active_states`, its profile read).
    pub fn active_states(&self) -> Vec<usize> {
        match self {
            Part::Span(_) => vec![0],
            Part::Roller(r) => r.active_states().into_iter().map(State::index).collect(),
        }
    }

    /// `active_states` as its line.json entry `spec` fixes them before the profile is read (the
    /// line's description): a Roller's brake grip where the entry has a brake table.
    pub fn described_states(&self, spec: &PartSpec) -> Vec<usize> {
        match self {
            Part::Span(_) => self.active_states(),
            Part::Roller(r) => r.params.active_states(spec.has_table("brake")).into_iter().map(State::index).collect(),
        }
    }

    /// Where the web may slip on a roller [R6]: whether, and whether under an air film [R8].
    /// Whether a lay-on roller presses on this part [R18].
    pub fn layon(&self) -> bool {
        matches!(self, Part::Roller(r) if r.params.layon)
    }

    pub fn traction(&self) -> Option<bool> {
        match self {
            Part::Roller(r) if r.params.traction => Some(r.params.air_roughness > 0.0),
            _ => None,
        }
    }

    /// The part's states a line integrates whatever the values of the parameters it offers
    /// (Co-Simulation's states, which keep their number): a span's one, a Roller's
    /// `Parameters::possible_states` as its line.json entry `spec` fixes them (a surface at a
    /// prescribed speed, a brake table).
    pub fn possible_states(&self, spec: &PartSpec) -> Vec<usize> {
        match self {
            Part::Span(_) => self.active_states(),
            Part::Roller(r) => r.params.possible_states(spec.speed_driven(), spec.has_table("brake")).into_iter().map(State::index).collect(),
        }
    }

    /// The parameter that makes the part's state `index` one the line integrates (a span's
    /// state always is one).
    pub fn state_switch(&self, index: usize) -> &'static str {
        match self {
            Part::Span(_) => "L",
            Part::Roller(_) => State::ALL[index].switch(),
        }
    }

    /// Whether the part's Real parameter `vr` acts on the line, as `spec` (its line.json entry)
    /// makes it. The line offers only those: a dancer's span takes its length from the dancer;
    /// a Roller's say its own (`Parameters::acts`).
    pub fn acts(&self, vr: u32, spec: &PartSpec) -> bool {
        use converting_span::description::Real as S;
        match (self, self.port(vr)) {
            (Part::Span(s), Some(Port::Span(S::L))) => !s.params.effects.variable_length,
            (Part::Span(_), Some(Port::Span(_))) => true,
            (Part::Roller(r), Some(Port::Roller(var))) => r.params.acts(var, &structure(spec)),
            // No Real of the part: nothing it could switch off.
            (_, None) => true,
            _ => unreachable!("a port is resolved from its own part"),
        }
    }

    /// Length of the part's Model Exchange state vector.
    pub fn state_count(&self) -> usize {
        self.description().states.len()
    }

    pub fn event_indicator_count(&self) -> usize {
        self.description().number_of_event_indicators
    }

    pub fn includes_mass(&self) -> bool {
        matches!(self, Part::Span(s) if s.params.effects.include_mass)
    }

    /// A span whose length moves and whose tension is damped reads dL/dt.
    pub fn reads_length_rate(&self) -> bool {
        matches!(self, Part::Span(s) if s.params.effects.variable_length && s.params.effects.include_damping)
    }
}

/// What a roller's line.json entry fixes besides its parameters.
fn structure(spec: &PartSpec) -> Structure {
    Structure {
        speed_driven: spec.speed_driven(),
        setpoint_table: spec.has_table("setpoint"),
        reference_table: spec.has_table("reference"),
        brake_table: spec.has_table("brake"),
        tension_table: spec.has_table("tension"),
        layon_table: spec.has_table("layon"),
        set_input: spec.set_input,
        speed_input: spec.speed_input,
    }
}

/// Per direction, the tangents (`along`) and from them each unknown's partial (`pick`), a row
/// of `out` each; false if `pick` knows an unknown not.
fn rows<D, T>(ds: &[D], unknowns: &[Port], out: &mut [f64], along: impl Fn(&D) -> T, pick: impl Fn(&T, Port) -> Option<f64>) -> bool {
    ds.iter().zip(out.chunks_exact_mut(unknowns.len().max(1))).all(|(d, row)| {
        let t = along(d);
        unknowns.iter().zip(row).all(|(&u, o)| pick(&t, u).map(|x| *o = x).is_some())
    })
}
