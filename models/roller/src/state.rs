//! The roller's continuous states by name: `State` names one (its variable in
//! modelDescription.xml), `States` holds them all, in the number the equations
//! are evaluated in. The Model Exchange state vector is the description's order.

use crate::description::Real;
use crate::number::{Lanes, Number, Tangent};
use crate::parameters::Kind;
use crate::parameters::{Parameters, STATES};

/// One of the roller's continuous states.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum State {
    Omega,
    Radius,
    /// The carriage's travel y and speed y' [R4].
    CarriageY,
    CarriageSpeed,
    /// The web's speed over the roller [R6] (without traction the surface's, no state of its own).
    WebSpeed,
    /// The loop's integrator, its motor's lagged torque [R10]-[R11], a dancer loop's integrator [R13].
    LoopIntegrator,
    MotorTorque,
    DancerIntegrator,
    /// The contact's grip u [R7] and a brake's u_b [R12]: the bristles' share of their limit.
    Grip,
    BrakeGrip,
    /// The roll's angle [R15] (moves only with runout).
    Angle,
    /// A lay-on roller's carriage X and speed X', and its spin [R18].
    LayonX,
    LayonSpeed,
    LayonSpin,
}

impl State {
    /// Every state, in the order of the Model Exchange state vector.
    pub const ALL: [State; STATES] = [
        State::Omega,
        State::Radius,
        State::CarriageY,
        State::CarriageSpeed,
        State::WebSpeed,
        State::LoopIntegrator,
        State::MotorTorque,
        State::DancerIntegrator,
        State::Grip,
        State::BrakeGrip,
        State::Angle,
        State::LayonX,
        State::LayonSpeed,
        State::LayonSpin,
    ];

    /// Its position in the Model Exchange state vector.
    #[inline(always)]
    pub fn index(self) -> usize {
        self as usize
    }

    /// Its variable in modelDescription.xml.
    pub fn variable(self) -> Real {
        match self {
            State::Omega => Real::omega,
            State::Radius => Real::r,
            State::CarriageY => Real::y,
            State::CarriageSpeed => Real::y_dot,
            State::WebSpeed => Real::v_web,
            State::LoopIntegrator => Real::loop_I,
            State::MotorTorque => Real::motor_torque,
            State::DancerIntegrator => Real::dancer_I,
            State::Grip => Real::grip,
            State::BrakeGrip => Real::brake_grip,
            State::Angle => Real::angle,
            State::LayonX => Real::layon_x,
            State::LayonSpeed => Real::layon_v,
            State::LayonSpin => Real::layon_omega,
        }
    }

    /// The state a variable is, if it is one.
    pub fn of(var: Real) -> Option<State> {
        State::ALL.into_iter().find(|s| s.variable() == var)
    }
}

impl Parameters {
    /// The states that move on a roller of these parameters (the others keep their values): omega
    /// always, its radius only on a roll being wound, its carriage only on a dancer, the web's
    /// speed over it and the contact's grip only where the web may slip, a loop's integrator, its
    /// motor's torque where it lags [R10]-[R11], a dancer loop's integrator [R13], a brake's
    /// grip where its profile has a brake table (`brake`) [R12], a roll's angle with runout [R15], and a
    /// lay-on roller's carriage and spin [R18].
    pub fn active_states(&self, brake: bool) -> Vec<State> {
        let kind = Kind::of(self);
        State::ALL
            .into_iter()
            .filter(|s| match s {
                State::Omega => true,
                State::Radius => self.winding(),
                State::CarriageY | State::CarriageSpeed => self.carriage,
                State::WebSpeed | State::Grip => self.traction,
                State::BrakeGrip => brake,
                State::LoopIntegrator => kind != Kind::None,
                State::MotorTorque => kind != Kind::None && self.motor_lag > 0.0,
                State::DancerIntegrator => kind == Kind::Dancer,
                State::Angle => self.runout,
                State::LayonX | State::LayonSpeed | State::LayonSpin => self.layon,
            })
            .collect()
    }

    /// The states a line integrates whatever the values of the parameters it offers (its
    /// Co-Simulation states, which keep their number): the active ones, and a roll's radius
    /// wherever `wound.thickness` may make it one (a roll not driven at a prescribed speed).
    pub fn possible_states(&self, speed_driven: bool, brake: bool) -> Vec<State> {
        let mut states = self.active_states(brake);
        if self.roll != 0 && !speed_driven && !states.contains(&State::Radius) {
            states.push(State::Radius);
            states.sort();
        }
        states
    }
}

impl State {
    /// The parameter that makes this state one that moves, as the line names it.
    pub fn switch(self) -> &'static str {
        match self {
            State::Radius => "wound.thickness",
            State::CarriageY | State::CarriageSpeed => "carriage",
            State::WebSpeed | State::Grip => "includeTraction",
            State::BrakeGrip => "brake",
            State::Angle => "runout",
            State::LayonX | State::LayonSpeed | State::LayonSpin => "layon",
            State::MotorTorque => "motor.lag",
            State::LoopIntegrator | State::DancerIntegrator => "loop.kind",
            // Always a state.
            State::Omega => "J",
        }
    }
}

/// A value for each state (or a rate, or a direction).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct States<N = f64> {
    pub omega: N,
    pub radius: N,
    pub carriage_y: N,
    pub carriage_speed: N,
    pub web_speed: N,
    pub loop_integrator: N,
    pub motor_torque: N,
    pub dancer_integrator: N,
    pub grip: N,
    pub brake_grip: N,
    pub angle: N,
    pub layon_x: N,
    pub layon_speed: N,
    pub layon_spin: N,
}

impl<N: Number> States<N> {
    #[inline(always)]
    pub fn get(&self, s: State) -> N {
        match s {
            State::Omega => self.omega,
            State::Radius => self.radius,
            State::CarriageY => self.carriage_y,
            State::CarriageSpeed => self.carriage_speed,
            State::WebSpeed => self.web_speed,
            State::LoopIntegrator => self.loop_integrator,
            State::MotorTorque => self.motor_torque,
            State::DancerIntegrator => self.dancer_integrator,
            State::Grip => self.grip,
            State::BrakeGrip => self.brake_grip,
            State::Angle => self.angle,
            State::LayonX => self.layon_x,
            State::LayonSpeed => self.layon_speed,
            State::LayonSpin => self.layon_spin,
        }
    }

    #[inline]
    pub fn get_mut(&mut self, s: State) -> &mut N {
        match s {
            State::Omega => &mut self.omega,
            State::Radius => &mut self.radius,
            State::CarriageY => &mut self.carriage_y,
            State::CarriageSpeed => &mut self.carriage_speed,
            State::WebSpeed => &mut self.web_speed,
            State::LoopIntegrator => &mut self.loop_integrator,
            State::MotorTorque => &mut self.motor_torque,
            State::DancerIntegrator => &mut self.dancer_integrator,
            State::Grip => &mut self.grip,
            State::BrakeGrip => &mut self.brake_grip,
            State::Angle => &mut self.angle,
            State::LayonX => &mut self.layon_x,
            State::LayonSpeed => &mut self.layon_speed,
            State::LayonSpin => &mut self.layon_spin,
        }
    }

    /// In the order of the Model Exchange state vector.
    #[inline(always)]
    pub fn to_array(&self) -> [N; STATES] {
        State::ALL.map(|s| self.get(s))
    }

    #[inline(always)]
    pub fn from_array(x: &[N; STATES]) -> States<N> {
        let mut states = States::default();
        for s in State::ALL {
            *states.get_mut(s) = x[s.index()];
        }
        states
    }
}

impl States {
    /// The states with their tangents along `d`.
    pub fn along(&self, d: &States) -> States<Tangent> {
        States::from_array(&State::ALL.map(|s| Tangent::new(self.get(s), d.get(s))))
    }

    /// The states with their tangents along `ds[l]` in lane l.
    #[inline]
    pub fn lanes<const L: usize>(&self, ds: &[States; L]) -> States<Lanes<L>> {
        States::from_array(&State::ALL.map(|s| Lanes::new(self.get(s), |l| ds[l].get(s))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::description::DESCRIPTION;

    /// The names follow the description's state vector, in its order.
    #[test]
    fn the_states_are_the_descriptions() {
        let vrs: Vec<u32> = State::ALL.iter().map(|s| s.variable().vr()).collect();
        assert_eq!(vrs, DESCRIPTION.states.to_vec());
        for s in State::ALL {
            assert_eq!(State::of(s.variable()), Some(s));
        }
    }
}
