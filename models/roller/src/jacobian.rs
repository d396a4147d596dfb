//! The roller's partial derivatives (`fmi2GetDirectionalDerivative`, the Line's chained
//! Jacobian): the right-hand side (`rhs`) evaluated in `Tangent` along a direction in the states
//! and the inputs. The profile's tables are functions of time only, so they and their slopes are held.

use crate::number::{Lanes, Tangent};
use crate::parameters::{Inputs, Kind, Parameters};
use crate::roll;
use crate::rhs::{self, Outputs, Point};
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
/// root of the forces; nor where the bearings' torque is not linear in omega; nor with runout [R15], whose
/// arm moves with the roll's angle.
pub fn tangents_fixed(p: &Parameters) -> bool {
    !p.winding() && (p.inlets <= 1 || p.layered) && !p.traction && Kind::of(p) == Kind::None && p.load_cell_wrap == 0.0 && roll::bearing_damping(p).is_some() && !p.runout && !p.layon
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
        rhs::outputs::<Tangent>(self.params, &self.point, &x, &u).tangents()
    }

    /// d(everything)/d(direction) along each of `ds`, in order, to `each` (false stops: the
    /// answer then): up to `LANES` directions an evaluation, each lane the `along` of its direction.
    #[inline]
    pub fn along_each(&self, ds: &[Direction], mut each: impl FnMut(&Tangents) -> bool) -> bool {
        // Four lanes where four do: a lane costs its share whether or not it has a direction.
        if ds.len() <= 4 {
            self.lanes::<4>(ds, &mut each)
        } else {
            ds.chunks(LANES).all(|chunk| self.lanes::<LANES>(chunk, &mut each))
        }
    }

    /// `along_each` for at most L directions, in one evaluation.
    #[inline]
    fn lanes<const L: usize>(&self, ds: &[Direction], each: &mut impl FnMut(&Tangents) -> bool) -> bool {
        let d: [Direction; L] = std::array::from_fn(|l| ds.get(l).copied().unwrap_or_default());
        let x = self.states.lanes(&d.map(|d| d.state));
        let u = self.inputs.lanes(&d.map(|d| d.u));
        let t = rhs::outputs::<Lanes<L>>(self.params, &self.point, &x, &u);
        (0..ds.len()).all(|l| each(&t.map(|t| t.d[l])))
    }
}

/// The most directions `along_each` evaluates at once: a roller's knowns in a line are its
/// active states and connected inputs, rarely more than eight.
const LANES: usize = 8;
