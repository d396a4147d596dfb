//! A part of the line: the span's or the Roller's own model, called through
//! the same `Model` and `Variables` functions its FMU's C API calls, so the
//! line runs the parts' equations and nothing else. Unboxed, so that a copy
//! of the line (to undo a failed step) allocates nothing: the models share
//! their profiles and records by `Arc`.

use converting_span::{ConvertingSpan, Forces};
use fmi_core::description::ModelDescription;
use fmi_core::{Compiled, EventUpdate, Experiment, FmiResult, Jacobian, Model, Resources, StateReader, StateWriter, Variables};
use crate::network::Port;
use roller::Roller;

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
                rows(ds, unknowns, out, |d| at.along(d), |t, d, u| if let Port::Span(u) = u { ConvertingSpan::along(t, d, u) } else { None })
            }
            (Part::Roller(r), Directions::Roller(ds)) => {
                let at = r.linearize();
                rows(ds, unknowns, out, |d| at.along(d), |t, d, u| if let Port::Roller(u) = u { Roller::along(t, d, u) } else { None })
            }
            _ => false,
        }
    }

    /// Whether the part's partials along the line's knowns stay the same until an event or a
    /// parameter changes it (a roller's `tangents_fixed`); a span's move with its strain.
    pub fn tangents_fixed(&self) -> bool {
        matches!(self, Part::Roller(r) if r.tangents_fixed())
    }

    /// The part's continuous states the line integrates (indices into its
    /// Model Exchange state vector): a Roller's radius only on a roll being
    /// wound, its carriage only on a dancer.
    pub fn active_states(&self) -> Vec<usize> {
        match self {
            Part::Span(_) => vec![0],
            Part::Roller(r) => {
                let mut states = vec![0];
                if r.params.winding() {
                    states.push(1);
                }
                if r.params.carriage {
                    states.extend([2, 3]);
                }
                states
            }
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

/// The span's output `var` from its forces computed once: the same fields as its bindings
/// (variables.rs); None for a variable that is not among them.
#[inline]
pub fn span_force_of(f: &Forces, var: converting_span::description::Real) -> Option<f64> {
    use converting_span::description::Real;
    Some(match var {
        Real::web_a_F | Real::summary_Tension => f.tension,
        Real::web_b_F => f.exit_force,
        Real::web_b_eps | Real::summary_Strain => f.strain,
        Real::summary_Length => f.length,
        _ => return None,
    })
}

/// Per direction, the tangents (`along`) and from them each unknown's partial (`pick`), a row
/// of `out` each; false if `pick` knows an unknown not.
fn rows<D, T>(ds: &[D], unknowns: &[Port], out: &mut [f64], along: impl Fn(&D) -> T, pick: impl Fn(&T, &D, Port) -> Option<f64>) -> bool {
    ds.iter().zip(out.chunks_exact_mut(unknowns.len().max(1))).all(|(d, row)| {
        let t = along(d);
        unknowns.iter().zip(row).all(|(&u, o)| pick(&t, d, u).map(|x| *o = x).is_some())
    })
}
