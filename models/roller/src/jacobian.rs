//! The roller's partial derivatives (`fmi2GetDirectionalDerivative`, the Line's chained
//! Jacobian): the right-hand side (`rhs`) evaluated in `Tangent` along a direction in the states
//! and the inputs. The profile's tables are functions of time only, so they and their slopes are held.

use crate::number::Tangent;
use crate::parameters::{Inputs, Kind, Parameters};
use crate::roll;
use crate::rhs::{self, Modes, Outputs, Point};
use crate::state::States;

/// A direction in the knowns: d(states) and d(inputs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Direction {
    pub state: States,
    pub u: Inputs,
}

/// The derivatives along a `Direction` of everything the roller computes (`rhs::Outputs`).
pub type Tangents = Outputs<f64>;

/// Whether the tangents along omega, the carriage's y and y' and every input are the same at
/// every state, input and time, for as long as the parameters and the roll stay: [R1], [R2]
/// and [R4] are then linear with coefficients made of parameters. So for a roller that winds
/// no roll (J and r fixed) and merges no webs ([R5] with one inlet passes the strain on, and so do
/// layers [R9], each its own). Not where the web may slip: [R7] is nonlinear; nor where a drive has a
/// loop: its limit [R11] is nonlinear, and its gains and limit are tunable; nor with a load cell, a
/// root of the forces; nor where the bearings' torque is not linear in omega.
pub fn tangents_fixed(p: &Parameters) -> bool {
    !p.winding() && (p.inlets <= 1 || p.layered) && !p.traction && Kind::of(p) == Kind::None && p.load_cell_wrap == 0.0 && roll::bearing_damping(p).is_some()
}

/// The roller at one point, for the tangents along any direction there (`Roller::linearize`).
pub struct Linearization<'a> {
    pub(crate) params: &'a Parameters,
    pub(crate) inputs: &'a Inputs,
    pub(crate) point: Point,
    pub(crate) states: States,
}

impl Linearization<'_> {
    /// d(everything)/d(direction).
    #[inline]
    pub fn along(&self, d: &Direction) -> Tangents {
        let x = self.states.along(&d.state);
        let u = self.inputs.along(&d.u);
        rhs::outputs::<Tangent>(self.params, &self.point, &x, &u, &Modes::default()).tangents()
    }
}
