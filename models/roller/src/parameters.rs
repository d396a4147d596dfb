//! Parameters and inputs of the roller, in SI units.

use crate::description::Real;
use crate::number::{Lanes, Number, Tangent};

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
    /// The bristle's static over kinetic friction k_s and presliding displacement delta (m) [R7].
    pub traction_static: f64,
    pub traction_creep: f64,
    /// The web's speed over the roller at the start minus the surface's [R6], m/s.
    pub traction_slip_start: f64,
    /// The web's width, for the tension per width under the air film [R8], m.
    pub traction_width: f64,
    /// Friction coefficient at a nip (its load is the profile's `nip` table) [R7].
    pub nip_mu: f64,
    /// The side of the wrap the nip presses on, for the web running from web_a to web_b: 0 the
    /// entry, 1 the exit (`contact::NipSide`) [R7].
    pub nip_side: i32,
    /// The surfaces' combined roughness (0: no air film) and the air's viscosity [R8].
    pub air_roughness: f64,
    pub air_viscosity: f64,
    /// The webs stay layers [R9]: each outlet passes one inlet's strain on.
    pub layered: bool,
    /// The drive's loop [R10]: 0 none, 1 force, 2 speed, 3 dancer (`Kind`).
    pub loop_kind: i32,
    pub loop_set: f64,
    /// A speed loop's reference where the profile has no reference table.
    pub loop_speed: f64,
    pub loop_kp: f64,
    pub loop_ki: f64,
    pub loop_sign: f64,
    pub loop_feedforward: bool,
    /// A force loop's set point may be <= 0 N: compression is meant.
    pub loop_compression: bool,
    /// The slope of the feed-forward's reference `loop.speed` where no table gives it [R10].
    pub loop_acceleration: f64,
    /// A sampled loop's hold period (0: continuous) and transport delay [R14], s.
    pub loop_sample: f64,
    pub loop_delay: f64,
    /// An ideal speed drive on `loop.speed` (the Line's input v_ref), held over a step.
    pub speed_input: bool,
    /// The wrap angle its load cell sees, rad.
    pub load_cell_wrap: f64,
    /// The loop's motor [R11]: its torque limit (0: none) and lag (0: none).
    pub motor_limit: f64,
    pub motor_lag: f64,
    /// A powder brake's speed scale [R12].
    pub brake_v_slip: f64,
    /// A powder brake's presliding displacement delta_b (m of surface travel) [R12].
    pub brake_creep: f64,
    /// A dancer loop's set point and gains [R13].
    pub dancer_set: f64,
    pub dancer_kp: f64,
    pub dancer_ki: f64,
    /// The roll's runout [R15]: on, its eccentricity (m), its phase (rad), the free length to the
    /// span's fixed end (m).
    pub runout: bool,
    pub runout_e: f64,
    pub runout_phase: f64,
    pub runout_length: f64,
    /// The roll's out-of-round harmonics [R15]: each slot's order k >= 2, amplitude (m, 0: none) and phase (rad).
    pub runout_orders: [i32; HARMONICS],
    pub runout_amplitudes: [f64; HARMONICS],
    pub runout_phases: [f64; HARMONICS],
    /// A winder's taper k: its tension drive holds T0*(1 - k*(1 - R/r)) (`drive::torque`).
    pub drive_taper: f64,
    /// The angle over which a stepwise radius moves by a layer (0: smooth) [R17], rad.
    pub wound_merge: f64,
    /// A lay-on roller on this winder [R18]: on, its carriage's mass, the nip's k and c, the roller's
    /// radius, inertia and bearing, the nip's mu and slip speed, its line's angle, its load.
    pub layon: bool,
    pub layon_m: f64,
    pub layon_k: f64,
    pub layon_c: f64,
    pub layon_r: f64,
    pub layon_j: f64,
    pub layon_b: f64,
    pub layon_mu: f64,
    pub layon_v_slip: f64,
    pub layon_angle: f64,
    pub layon_f: f64,
}

/// What the drive's loop holds (`loop.kind`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    None,
    /// A force (a span's tension, a load cell) at `loop.set` or the profile's setpoint table.
    Force,
    /// The surface speed at the profile's reference table.
    Speed,
    /// The speed loop with its reference trimmed by a PI on a dancer's position [R13].
    Dancer,
}

impl Kind {
    pub fn of(p: &Parameters) -> Kind {
        match p.loop_kind {
            1 => Kind::Force,
            2 => Kind::Speed,
            3 => Kind::Dancer,
            _ => Kind::None,
        }
    }
}

/// The roller's Model Exchange states: (omega, r, y, y', v_web, loop.I, motor.torque, dancer.I,
/// grip, brake.grip, angle, layon.x, layon.v, layon.omega).
pub const STATES: usize = 14;

/// The out-of-round harmonics a roll with runout may have [R15].
pub const HARMONICS: usize = 4;

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
    /// The loop's command goes through a zero-order hold [R14].
    pub fn sampled(&self) -> bool {
        Kind::of(self) != Kind::None && self.loop_sample > 0.0
    }

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
/// at index k - 1; the ports beyond `inlets` and `outlets` are not read. In `N`, the number the
/// equations are evaluated in (`number`): a value, or a value and its tangent.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Inputs<N = f64> {
    pub force_a: [N; PORTS],
    pub force_b: [N; PORTS],
    pub strain_a: [N; PORTS],
    pub torque: N,
    pub load: N,
    /// What a force loop measures [R10].
    pub measured: N,
    /// The position of the dancer a dancer loop holds [R13].
    pub dancer_y: N,
}

/// The sum of the first `count` ports' tensions: one port is read as it
/// is (the plain roller, bit for bit), and no loop runs over unused ones.
#[inline]
fn pull<N: Number>(forces: &[N; PORTS], count: i32) -> N {
    match ports(count) {
        1 => forces[0],
        2 => forces[0] + forces[1],
        3 => forces[0] + forces[1] + forces[2],
        _ => forces[0] + forces[1] + forces[2] + forces[3],
    }
}

impl<N: Number> Inputs<N> {
    /// F_a of [R1] and [R4]: every arriving web's tension.
    #[inline]
    pub fn pull_back(&self, p: &Parameters) -> N {
        pull(&self.force_a, p.inlets)
    }

    /// F_b of [R1] and [R4]: every leaving web's tension.
    #[inline]
    pub fn pull_forward(&self, p: &Parameters) -> N {
        pull(&self.force_b, p.outlets)
    }
}

impl Inputs {
    /// The inputs with their tangents along `d`.
    pub fn along(&self, d: &Inputs) -> Inputs<Tangent> {
        let zip = |x: &[f64; PORTS], dx: &[f64; PORTS]| std::array::from_fn(|i| Tangent::new(x[i], dx[i]));
        Inputs {
            force_a: zip(&self.force_a, &d.force_a),
            force_b: zip(&self.force_b, &d.force_b),
            strain_a: zip(&self.strain_a, &d.strain_a),
            torque: Tangent::new(self.torque, d.torque),
            load: Tangent::new(self.load, d.load),
            measured: Tangent::new(self.measured, d.measured),
            dancer_y: Tangent::new(self.dancer_y, d.dancer_y),
        }
    }

    /// The inputs with their tangents along `ds[l]` in lane l.
    #[inline]
    pub fn lanes<const L: usize>(&self, ds: &[Inputs; L]) -> Inputs<Lanes<L>> {
        let seed = |x: f64, d: fn(&Inputs) -> f64| Lanes::new(x, |l| d(&ds[l]));
        let zip = |x: &[f64; PORTS], d: fn(&Inputs) -> &[f64; PORTS]| std::array::from_fn(|i| Lanes::new(x[i], |l| d(&ds[l])[i]));
        Inputs {
            force_a: zip(&self.force_a, |u| &u.force_a),
            force_b: zip(&self.force_b, |u| &u.force_b),
            strain_a: zip(&self.strain_a, |u| &u.strain_a),
            torque: seed(self.torque, |u| u.torque),
            load: seed(self.load, |u| u.load),
            measured: seed(self.measured, |u| u.measured),
            dancer_y: seed(self.dancer_y, |u| u.dancer_y),
        }
    }
}

/// What a line's entry fixes for a roller besides its parameters: where its surface speed comes
/// from, which of its profile's tables it has, and which of its values the line gives as inputs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Structure {
    /// A speed table or `speed.input`: the surface follows a speed, not the torques.
    pub speed_driven: bool,
    pub setpoint_table: bool,
    pub reference_table: bool,
    pub brake_table: bool,
    /// A tension drive: the profile's tension table.
    pub tension_table: bool,
    /// A lay-on roller's load table [R18].
    pub layon_table: bool,
    /// The line gives a force loop's set point (`set_input`), a loop's or an ideal speed drive's speed (`speed_input`).
    pub set_input: bool,
    pub speed_input: bool,
}

impl Parameters {
    /// Whether the Real variable `var` acts on a roller of this structure: a surface that follows
    /// a speed has no inertia, radius, damping, start speed or roll build-up that moves it; only a
    /// roll builds up, only a dancer has a carriage, the arriving webs' masses weigh only where
    /// several merge [R5]; a loop's set point and reference act unless a table or the line's
    /// input gives them [R10]. Inputs and computed variables always act. No fallthrough: a new
    /// variable stops the compiler here.
    pub fn acts(&self, var: Real, s: &Structure) -> bool {
        let kind = Kind::of(self);
        let speed_loop = matches!(kind, Kind::Speed | Kind::Dancer);
        match var {
            Real::J | Real::R | Real::b | Real::v_start => !s.speed_driven,
            Real::wound_thickness | Real::wound_density | Real::wound_width | Real::wound_merge => self.roll != 0 && !s.speed_driven,
            Real::carriage_m | Real::carriage_d | Real::carriage_k | Real::carriage_y_start => self.carriage,
            Real::web_a_m | Real::web_a2_m => self.inlets >= 2,
            Real::web_a3_m => self.inlets >= 3,
            Real::web_a4_m => self.inlets >= 4,
            Real::traction_mu
            | Real::traction_wrap
            | Real::traction_v_slip
            | Real::traction_width
            | Real::traction_slip_start
            | Real::traction_static
            | Real::traction_creep
            | Real::nip_mu
            | Real::air_roughness
            | Real::air_viscosity => self.traction,
            Real::loop_set => kind == Kind::Force && !s.setpoint_table && !s.set_input,
            Real::loop_speed => (speed_loop && !s.reference_table || self.speed_input) && !s.speed_input,
            Real::loop_acceleration => self.loop_feedforward && !s.reference_table,
            Real::loop_sample | Real::loop_delay => kind != Kind::None,
            Real::brake_v_slip | Real::brake_creep => s.brake_table,
            Real::drive_taper => self.roll == WINDER && s.tension_table,
            Real::dancer_set | Real::dancer_kp | Real::dancer_ki => kind == Kind::Dancer,
            Real::loop_kp | Real::loop_ki | Real::motor_limit => kind != Kind::None,
            Real::loop_sign | Real::motor_lag | Real::load_cell_wrap => true,
            Real::runout_e
            | Real::runout_phase
            | Real::runout_L
            | Real::runout_h1_a
            | Real::runout_h1_phase
            | Real::runout_h2_a
            | Real::runout_h2_phase
            | Real::runout_h3_a
            | Real::runout_h3_phase
            | Real::runout_h4_a
            | Real::runout_h4_phase => self.runout,
            Real::layon_m
            | Real::layon_k
            | Real::layon_c
            | Real::layon_r
            | Real::layon_J
            | Real::layon_b
            | Real::layon_mu
            | Real::layon_v_slip
            | Real::layon_angle => self.layon,
            Real::layon_F => self.layon && !s.layon_table,
            // Inputs.
            Real::web_a_F
            | Real::web_b_F
            | Real::web_a_eps
            | Real::tau_m
            | Real::F_load
            | Real::web_a2_F
            | Real::web_a2_eps
            | Real::web_a3_F
            | Real::web_a3_eps
            | Real::web_a4_F
            | Real::web_a4_eps
            | Real::web_b2_F
            | Real::web_b3_F
            | Real::web_b4_F
            | Real::loop_measured
            | Real::dancer_y => true,
            // Computed.
            Real::web_a_v
            | Real::web_b_v
            | Real::web_b_eps
            | Real::omega
            | Real::r
            | Real::y
            | Real::y_dot
            | Real::tau
            | Real::web_a_x
            | Real::web_a_y
            | Real::web_b_x
            | Real::web_b_y
            | Real::der_omega
            | Real::der_r
            | Real::der_y
            | Real::der_y_dot
            | Real::web_a2_v
            | Real::web_a3_v
            | Real::web_a4_v
            | Real::web_b2_v
            | Real::web_b2_eps
            | Real::web_b3_v
            | Real::web_b3_eps
            | Real::web_b4_v
            | Real::web_b4_eps
            | Real::v
            | Real::v_web
            | Real::slip
            | Real::traction
            | Real::mu_eff
            | Real::h_air
            | Real::der_v_web
            | Real::grip
            | Real::der_grip
            | Real::brake_grip
            | Real::der_brake_grip
            | Real::loop_I
            | Real::der_loop_I
            | Real::motor_torque
            | Real::der_motor_torque
            | Real::load_cell_F
            | Real::dancer_I
            | Real::der_dancer_I
            | Real::angle
            | Real::der_angle
            | Real::layon_x
            | Real::der_layon_x
            | Real::layon_v
            | Real::der_layon_v
            | Real::layon_omega
            | Real::der_layon_omega
            | Real::layon_N
            | Real::layon_delta => true,
        }
    }

    /// A line may give a force loop's set point as its input.
    pub fn takes_set_input(&self) -> bool {
        Kind::of(self) == Kind::Force
    }

    /// A line may give a speed or dancer loop's reference, or an ideal speed drive's speed, as its input.
    pub fn takes_speed_input(&self) -> bool {
        match Kind::of(self) {
            Kind::Speed | Kind::Dancer => true,
            Kind::None | Kind::Force => self.speed_input,
        }
    }
}
