//! Parameters and inputs of the roller, in SI units.

/// Parameters, SI.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Parameters {
    pub inertia: f64,
    pub radius: f64,
    pub damping: f64,
    pub speed_start: f64,
    /// 0 roller, 1 unwinder, 2 winder.
    pub roll: i32,
    pub wound_thickness: f64,
    pub wound_density: f64,
    pub wound_width: f64,
    pub carriage: bool,
    pub carriage_mass: f64,
    pub carriage_damping: f64,
    pub carriage_stiffness: f64,
    pub carriage_start: f64,
    pub profile: std::sync::Arc<str>,
    /// Webs arriving (web_a, web_a2, ...) and leaving (web_b, web_b2, ...), 1..=4.
    pub inlets: i32,
    pub outlets: i32,
    /// Mass per unstretched length of each arriving web [R5], kg/m (the first also the web's on
    /// the wrap [R6]).
    pub mass_a: [f64; PORTS],
    /// The web may slip: its speed over the roller is a state [R6]–[R8].
    pub traction: bool,
    /// Friction coefficient between web and roller, wrap angle (rad), slip speed scale (m/s) [R7].
    pub traction_mu: f64,
    pub traction_wrap: f64,
    pub traction_v_slip: f64,
    /// The web's speed over the roller at the start minus the surface's [R6], m/s.
    pub traction_slip_start: f64,
    /// The web's width, for the tension per width under the air film [R8], m.
    pub traction_width: f64,
    /// Friction coefficient at a nip (its load is the profile's `nip` table) [R7].
    pub nip_mu: f64,
    /// The surfaces' combined roughness (0: no air film) and the air's viscosity [R8].
    pub air_roughness: f64,
    pub air_viscosity: f64,
    /// The webs stay layers [R9]: each outlet passes one inlet's strain on.
    pub layered: bool,
    /// The drive's loop [R10]: 0 none, 1 force, 2 speed (`control::Kind`).
    pub loop_kind: i32,
    pub loop_set: f64,
    /// A speed loop's reference where the profile has no reference table.
    pub loop_speed: f64,
    pub loop_kp: f64,
    pub loop_ki: f64,
    pub loop_sign: f64,
    pub loop_feedforward: bool,
    /// An ideal speed drive on `loop.speed` (the Line's input v_ref), held over a step.
    pub speed_input: bool,
    /// The wrap angle its load cell sees, rad.
    pub load_cell_wrap: f64,
    /// The loop's motor [R11]: its torque limit (0: none) and lag (0: none).
    pub motor_limit: f64,
    pub motor_lag: f64,
    /// A powder brake's speed scale [R12].
    pub brake_v_slip: f64,
    /// A dancer loop's set point and gains [R13].
    pub dancer_set: f64,
    pub dancer_kp: f64,
    pub dancer_ki: f64,
}

/// The roller's Model Exchange states: (omega, r, y, y', v_web, loop.I, motor.torque, dancer.I).
pub const STATES: usize = 8;

/// The most webs a roller takes in or gives out.
pub const PORTS: usize = 4;

/// A count of ports as an index bound: 1..=PORTS (a count outside it is
/// refused when initialization ends; until then it must not panic).
pub fn ports(count: i32) -> usize {
    count.clamp(1, PORTS as i32) as usize
}

pub const UNWINDER: i32 = 1;
pub const WINDER: i32 = 2;

impl Parameters {
    /// The sign of a tension drive's torque and of the radius change: the
    /// web pulls an unwinder back and a winder forward.
    pub fn roll_sign(&self) -> f64 {
        match self.roll {
            UNWINDER => -1.0,
            WINDER => 1.0,
            _ => 0.0,
        }
    }

    /// [R3] is on: a roll with web of some thickness on it.
    pub fn winding(&self) -> bool {
        self.roll != 0 && self.wound_thickness > 0.0
    }
}

/// Inputs, SI, held over a communication step. Port k's (web_a<k>, web_b<k>)
/// at index k - 1; the ports beyond `inlets` and `outlets` are not read.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Inputs {
    pub force_a: [f64; PORTS],
    pub force_b: [f64; PORTS],
    pub strain_a: [f64; PORTS],
    pub torque: f64,
    pub load: f64,
    /// What a force loop measures [R10].
    pub measured: f64,
    /// The position of the dancer a dancer loop holds [R13].
    pub dancer_y: f64,
}

/// The sum of the first `count` ports' tensions: one port is read as it
/// is (the plain roller, bit for bit), and no loop runs over unused ones.
#[inline]
fn pull(forces: &[f64; PORTS], count: i32) -> f64 {
    match ports(count) {
        1 => forces[0],
        2 => forces[0] + forces[1],
        3 => forces[0] + forces[1] + forces[2],
        _ => forces[0] + forces[1] + forces[2] + forces[3],
    }
}

impl Inputs {
    /// F_a of [R1] and [R4]: every arriving web's tension.
    #[inline]
    pub fn pull_back(&self, p: &Parameters) -> f64 {
        pull(&self.force_a, p.inlets)
    }

    /// F_b of [R1] and [R4]: every leaving web's tension.
    #[inline]
    pub fn pull_forward(&self, p: &Parameters) -> f64 {
        pull(&self.force_b, p.outlets)
    }
}
