//! The roller's right-hand side, written once: its rates (p, u, x) -> x' and its outputs, in any
//! `Number` (f64 for values, `Tangent` for the directional derivatives). Each effect adds its
//! terms from its own file: the drive (`drive`), the roll and its bearings (`roll`), the carriage
//! (`carriage`), the contact (`contact`), the loop (`control`), a brake (`brake`); [R1] sums them
//! (`physics::net_torque`).

use crate::contact::{self, Contact, Dual, Friction};
use crate::number::{Number, Tangent};
use crate::layon::{self, Nip};
use crate::parameters::{Inputs, Parameters, PORTS, UNWINDER};
use crate::physics;
use crate::roll::{self, Roll};
use crate::runout::{self, Runout};
use crate::state::States;
use crate::{brake, carriage, control, drive};

/// What the equations read besides the states and inputs, at one time: the profile's tables
/// (functions of time only, held), the roll's reference, and where the web may slip the contact
/// at the point's values with its gradient (formed once for every direction).
#[derive(Clone, Copy, Debug, Default)]
pub struct Point {
    pub roll: Roll,
    /// A prescribed surface speed and its slope (a speed table, or `speed.input`'s loop.speed).
    pub prescribed: Option<(f64, f64)>,
    pub drive: drive::Read,
    /// A brake's torque B [R12] (None without a brake table).
    pub brake: Option<f64>,
    pub control: control::Reads,
    /// The carriage's load table [R4] (0 without one).
    pub load: f64,
    /// The leaving strain's table, where there is one (an unwinder's web leaves its roll at it).
    pub strain: Option<f64>,
    pub slip: Option<Slip>,
    /// A lay-on roller's load F [R18]: its table's, else layon.F (0 without a lay-on roller).
    pub layon_load: f64,
}

/// Where the web may slip: the contact [R6]-[R8] at the point and what it moves, with gradients.
#[derive(Clone, Copy, Debug, Default)]
pub struct Slip {
    pub state: contact::State,
    pub contact: Contact,
    pub acceleration: Dual,
    /// The share of traction in use, where the outputs are asked for (None: found when needed).
    pub used: Option<Dual>,
}

impl Slip {
    /// The contact at `state` [R6]-[R8], its bristle as `friction` has it.
    pub fn at(p: &Parameters, state: contact::State, friction: Friction) -> Slip {
        let contact = contact::contact(p, &state, friction);
        Slip { state, contact, acceleration: contact::web_acceleration(p, &state, contact.force), used: None }
    }

    fn used(&self, p: &Parameters) -> Dual {
        self.used.unwrap_or_else(|| contact::traction_used(p, &self.state, self.contact.mu_eff))
    }
}

/// The rates of the states and what they are made of.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rates<N> {
    pub derivatives: States<N>,
    /// The drive's torque: its table, loop and brake; a speed drive's, what [R1] needs.
    pub torque: N,
    pub surface_speed: N,
    pub runout: Option<Runout<N>>,
    /// A lay-on roller's nip [R18] where the roll has one.
    pub layon: Option<Nip<N>>,
}

/// What [R1] sums and what it is made of, at the roller's point.
struct Torques<N> {
    inertia: N,
    surface_speed: N,
    /// The friction where the web may slip [R6]-[R7], the web's acceleration it gives, the grip's rate.
    friction: Option<(N, N, N)>,
    web: N,
    bearing: N,
    loop_law: control::Law<N>,
    /// The roll's runout [R15] where it has one: its arm, its span's length and the web's speed.
    runout: Option<Runout<N>>,
    /// A lay-on roller's nip [R18]: its traction's torque is in `web`.
    layon: Option<Nip<N>>,
}

#[inline(always)]
fn torques<N: Number>(p: &Parameters, at: &Point, x: &States<N>, u: &Inputs<N>) -> Torques<N> {
    let (omega, r) = (x.omega, x.radius);
    let inertia = at.roll.inertia(p, r);
    let v = match at.prescribed {
        Some((v, _)) => N::constant(v),
        None => physics::surface_speed(lever(p, at, r), omega),
    };
    let friction = at.slip.map(|s| {
        let knowns = [x.web_speed, v, u.force_a[0], u.force_b[0], r, x.grip];
        (s.contact.force.lift(&knowns), s.acceleration.lift(&knowns), s.contact.grip_rate.lift(&knowns))
    });
    let runout = p.runout.then(|| runout::at(p, x.angle, omega, r));
    let web = match (friction, runout) {
        (Some((f, _, _)), _) => -(r * f),
        (None, Some(g)) => runout::web_torque(p, r, g.arm, u),
        (None, None) => physics::web_torque(p, lever(p, at, r), u),
    };
    let layon = p.layon.then(|| layon_nip(p, at, x, radius_rate(p, at, u, r, v)));
    let web = layon.map_or(web, |n| web + n.winder_torque);
    Torques { inertia, surface_speed: v, friction, web, bearing: roll::bearing_torque(p, omega), loop_law: loop_law(p, at, x, u, inertia), runout, layon }
}

/// A lay-on roller's nip on the roll [R18] at the roll's radius r growing at `radius_rate`: the
/// roll's surface is runout's circle [R15] (round without runout), the carriage's line at layon.angle
/// measured as runout.phase is (so in runout's mirrored frame of a winder at -layon.angle).
#[inline(always)]
fn layon_nip<N: Number>(p: &Parameters, at: &Point, x: &States<N>, radius_rate: N) -> Nip<N> {
    let (e, psi) = if p.runout { (p.runout_e, -(x.angle + p.runout_phase)) } else { (0.0, N::default()) };
    let winder = layon::Winder { radius: x.radius, radius_rate, eccentricity: e, psi, psi_rate: -x.omega, omega: x.omega };
    layon::nip(&layon::of(p), &winder, x.layon_x, x.layon_speed, x.layon_spin, N::constant(at.layon_load))
}

/// The loop's law [R10]-[R11], [R13] at the roller's point.
#[inline(always)]
fn loop_law<N: Number>(p: &Parameters, at: &Point, x: &States<N>, u: &Inputs<N>, inertia: N) -> control::Law<N> {
    control::law(p, &at.control, &control::Seen {
        omega: x.omega,
        radius: lever(p, at, x.radius),
        inertia,
        strain: roll_strain(p, at.strain, &u.strain_a),
        measured: u.measured,
        dancer_y: u.dancer_y,
        integrator: x.loop_integrator,
        motor: x.motor_torque,
        dancer: x.dancer_integrator,
    })
}

/// The loop's continuous command sat(u) [R11] at the roller's point: what a sampled loop samples [R14].
pub fn loop_command(p: &Parameters, at: &Point, x: &States, u: &Inputs) -> f64 {
    loop_law(p, at, x, u, at.roll.inertia(p, x.radius)).command
}

/// The drive's torque: its table and tau_m, its loop, a brake; where the surface follows a
/// speed, the torque [R1] needs for it.
#[inline(always)]
fn drive_torque<N: Number>(p: &Parameters, at: &Point, x: &States<N>, u: &Inputs<N>, t: &Torques<N>) -> N {
    match at.prescribed {
        Some((_, slope)) => {
            let omega_rate = physics::omega_rate_at_speed(slope, t.surface_speed, x.radius, radius_rate(p, at, u, x.radius, t.surface_speed));
            physics::speed_drive_torque(t.inertia, omega_rate, t.web, t.bearing)
        }
        None => commanded(p, at, x, u, t.loop_law.torque, t.surface_speed),
    }
}

/// The torque a drive that follows no speed gives: its table and tau_m, its loop, a brake.
#[inline(always)]
fn commanded<N: Number>(p: &Parameters, at: &Point, x: &States<N>, u: &Inputs<N>, loop_torque: N, v: N) -> N {
    drive::torque(p, at.drive, u.torque, lever(p, at, x.radius)) + loop_torque + brake_at(p, at, x, v).0
}

/// The radius the web meets, [R1]'s lever and v = r_w*omega [R17]: r, or a roll's stepwise radius where
/// the surface follows no speed (a speed drive's surface follows its table at r).
#[inline(always)]
fn lever<N: Number>(p: &Parameters, at: &Point, radius: N) -> N {
    if at.prescribed.is_some() {
        radius
    } else {
        roll::contact_radius(p, radius)
    }
}

/// A brake's torque and its grip's rate [R12] (0 and 0 without a brake table).
#[inline(always)]
fn brake_at<N: Number>(p: &Parameters, at: &Point, x: &States<N>, v: N) -> (N, N) {
    at.brake.map_or_else(Default::default, |b| brake::torque(p, b, v, x.brake_grip))
}

/// The drive's torque at the roller's point (`Rates::torque` alone): without a prescribed
/// speed, what the drive commands alone (no web, bearing or friction to form).
#[inline]
pub fn torque<N: Number>(p: &Parameters, at: &Point, x: &States<N>, u: &Inputs<N>) -> N {
    if at.prescribed.is_some() {
        return drive_torque(p, at, x, u, &torques(p, at, x, u));
    }
    let loop_torque = loop_law(p, at, x, u, at.roll.inertia(p, x.radius)).torque;
    commanded(p, at, x, u, loop_torque, physics::surface_speed(lever(p, at, x.radius), x.omega))
}

/// d(states)/dt [R1]-[R4], [R6], [R10]-[R13].
#[inline(always)]
pub fn rates<N: Number>(p: &Parameters, at: &Point, x: &States<N>, u: &Inputs<N>) -> Rates<N> {
    let (omega, r) = (x.omega, x.radius);
    let t = torques(p, at, x, u);
    let (v, torque) = (t.surface_speed, drive_torque(p, at, x, u, &t));
    let radius_rate = radius_rate(p, at, u, r, v);
    let (omega_rate, surface_rate) = match at.prescribed {
        Some((_, slope)) => (physics::omega_rate_at_speed(slope, v, r, radius_rate), N::constant(slope)),
        None => {
            let rate = physics::net_torque(t.web, torque, t.bearing) / t.inertia;
            // v = r_w*omega: r_w moves with r at its slope (1 where it moves smoothly) [R17].
            let slope = if roll::stepped(p) { roll::stepwise(p, r.value()).1 } else { 1.0 };
            (rate, lever(p, at, r) * rate + omega * radius_rate * slope)
        }
    };
    let (y_rate, y_speed_rate) = carriage::rates(p, x.carriage_y, x.carriage_speed, || carriage::force(u.load, at.load, u.pull_back(p), u.pull_forward(p)));
    let derivatives = States {
        omega: omega_rate,
        radius: radius_rate,
        carriage_y: y_rate,
        carriage_speed: y_speed_rate,
        // Without traction the web's speed is the surface's, and so is its rate.
        web_speed: t.friction.map_or(surface_rate, |(_, a, _)| a),
        loop_integrator: t.loop_law.integrator_rate,
        motor_torque: t.loop_law.motor_rate,
        dancer_integrator: t.loop_law.dancer_rate,
        grip: t.friction.map_or_else(N::default, |(_, _, rate)| rate),
        // A speed drive has no brake (refused): its surface speed is the table's.
        brake_grip: if at.prescribed.is_some() { N::default() } else { brake_at(p, at, x, v).1 },
        angle: if p.runout { omega } else { N::default() },
        layon_x: if p.layon { x.layon_speed } else { N::default() },
        layon_speed: t.layon.map_or_else(N::default, |n| n.acceleration),
        layon_spin: t.layon.map_or_else(N::default, |n| n.spin_rate),
    };
    Rates { derivatives, torque, surface_speed: v, runout: t.runout, layon: t.layon }
}

/// Everything the roller computes, each named as the roller's own (`t.x` for `Roller::x()`): the
/// outputs, the states and their rates. In `Tangent`'s derivatives, the directional derivatives;
/// the binding (variables.rs) reads them by the same names.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outputs<N = f64> {
    pub surface_speed: N,
    pub web_speed: N,
    pub slip: N,
    pub traction_used: N,
    pub mu_eff: N,
    pub h_air: N,
    /// The strain leaving at each outlet (`strain_leaving`).
    pub outlet_strains: [N; PORTS],
    pub drive_torque: N,
    pub loop_integrator: N,
    pub motor_state: N,
    pub dancer_integrator: N,
    pub grip: N,
    pub brake_grip: N,
    pub rates: States<N>,
    pub omega: N,
    pub radius: N,
    /// The carriage's (y, y').
    pub carriage: [N; 2],
    pub contact_a_x: N,
    pub contact_b_x: N,
    /// Where the webs touch, along the span: a dancer's height [R4], a roll's end of its span [R15].
    pub contact_a_y: N,
    pub contact_b_y: N,
    /// The web's speed at each side: the surface's, or the moving tangent point's on a roll with runout [R15].
    pub arriving_speed: N,
    pub leaving_speed: N,
    pub angle: N,
    pub load_cell_force: N,
    /// A lay-on roller's (X, X', omega_l) [R18], its nip force and compression (0 without one).
    pub layon: [N; 3],
    pub layon_force: N,
    pub layon_compression: N,
}

impl<N: Copy> Outputs<N> {
    /// `Roller::strain_leaving(outlet)`'s.
    #[inline]
    pub fn strain_leaving(&self, outlet: usize) -> N {
        self.outlet_strains[outlet]
    }
}

/// The strain of the web leaving at outlet `outlet` (0-based): the profile's table, else the
/// arriving web's, merged [R5] when several arrive, or where they stay layers its own inlet's [R9].
#[inline]
pub fn strain_leaving<N: Number>(p: &Parameters, table: Option<f64>, strain: &[N; PORTS], outlet: usize) -> N {
    match table {
        Some(x) => N::constant(x),
        None if p.layered => strain[physics::layer_inlet(p, outlet)],
        None => physics::merged_strain(p, strain),
    }
}

/// The strain of the web where it meets the roll [R3] (0 where no roll winds): an unwinder's
/// leaving strain (its table, else its inlet's), a winder's arriving web's, merged [R5] where several
/// arrive, layers [R9] too: 1/(1+eps) is then the mass-weighted mean of the webs' 1/(1+eps_i), so the
/// roll gains exactly their mass.
#[inline]
pub fn roll_strain<N: Number>(p: &Parameters, table: Option<f64>, strain: &[N; PORTS]) -> N {
    match p.roll {
        _ if !p.winding() => N::default(),
        UNWINDER => strain_leaving(p, table, strain, 0),
        _ => physics::merged_strain(p, strain),
    }
}

/// dr/dt [R3] at the roller's point, radius r and surface speed v.
#[inline(always)]
fn radius_rate<N: Number>(p: &Parameters, at: &Point, u: &Inputs<N>, radius: N, speed: N) -> N {
    // Both are 0 where no roll winds, and roll_strain returns before it merges anything.
    roll::radius_rate(p, radius, speed, roll_strain(p, at.strain, &u.strain_a))
}

/// The load cell's reading, load_cell.F: at its own wrap `load_cell.wrap` (0: none, F = 0).
#[inline]
pub fn load_cell_force<N: Number>(p: &Parameters, u: &Inputs<N>) -> N {
    if p.load_cell_wrap > 0.0 {
        physics::load_cell(u.pull_back(p), u.pull_forward(p), p.load_cell_wrap.cos())
    } else {
        N::default()
    }
}

/// Every output and rate.
pub fn outputs<N: Number>(p: &Parameters, at: &Point, x: &States<N>, u: &Inputs<N>) -> Outputs<N> {
    let rates = rates(p, at, x, u);
    let v = rates.surface_speed;
    let web_speed = if at.slip.is_some() { x.web_speed } else { v };
    let knowns = [x.web_speed, v, u.force_a[0], u.force_b[0], x.radius, x.grip];
    let lift = |d: Dual| d.lift(&knowns);
    let (traction_used, mu_eff, h_air) = at.slip.map_or_else(Default::default, |s| (lift(s.used(p)), lift(s.contact.mu_eff), lift(s.contact.h_air)));
    let height = carriage::contact_height(p, x.carriage_y);
    // The roll's end of its span moves with runout [R15]: an unwinder's leaving side, a winder's arriving one.
    let (ends, speeds) = match rates.runout {
        Some(g) if p.roll == UNWINDER => ((height, runout::frame(p, &g)), (web_speed, g.speed)),
        Some(g) => ((runout::frame(p, &g), height), (g.speed, web_speed)),
        None => ((height, height), (web_speed, web_speed)),
    };
    let merged = match (at.strain, p.layered) {
        (None, false) => Some(physics::merged_strain(p, &u.strain_a)),
        _ => None,
    };
    Outputs {
        surface_speed: v,
        web_speed,
        slip: web_speed - v,
        traction_used,
        mu_eff,
        h_air,
        outlet_strains: std::array::from_fn(|k| merged.unwrap_or_else(|| strain_leaving(p, at.strain, &u.strain_a, k))),
        drive_torque: rates.torque,
        loop_integrator: x.loop_integrator,
        motor_state: x.motor_torque,
        dancer_integrator: x.dancer_integrator,
        grip: x.grip,
        brake_grip: x.brake_grip,
        rates: rates.derivatives,
        omega: x.omega,
        radius: x.radius,
        carriage: [x.carriage_y, x.carriage_speed],
        contact_a_x: N::default(),
        contact_b_x: carriage::contact_b_x(x.radius),
        contact_a_y: ends.0,
        contact_b_y: ends.1,
        arriving_speed: speeds.0,
        leaving_speed: speeds.1,
        angle: x.angle,
        load_cell_force: load_cell_force(p, u),
        layon: [x.layon_x, x.layon_speed, x.layon_spin],
        layon_force: rates.layon.map_or_else(N::default, |n| n.force),
        layon_compression: rates.layon.map_or_else(N::default, |n| n.compression),
    }
}

impl<N: Number> Outputs<N> {
    /// Each output and rate through `f` (a tangent's derivative, one lane's).
    #[inline]
    pub fn map<M: Number>(&self, f: impl Fn(N) -> M) -> Outputs<M> {
        Outputs {
            surface_speed: f(self.surface_speed),
            web_speed: f(self.web_speed),
            slip: f(self.slip),
            traction_used: f(self.traction_used),
            mu_eff: f(self.mu_eff),
            h_air: f(self.h_air),
            outlet_strains: self.outlet_strains.map(&f),
            drive_torque: f(self.drive_torque),
            loop_integrator: f(self.loop_integrator),
            motor_state: f(self.motor_state),
            dancer_integrator: f(self.dancer_integrator),
            grip: f(self.grip),
            brake_grip: f(self.brake_grip),
            rates: States::from_array(&self.rates.to_array().map(&f)),
            omega: f(self.omega),
            radius: f(self.radius),
            carriage: self.carriage.map(&f),
            contact_a_x: f(self.contact_a_x),
            contact_b_x: f(self.contact_b_x),
            contact_a_y: f(self.contact_a_y),
            contact_b_y: f(self.contact_b_y),
            arriving_speed: f(self.arriving_speed),
            leaving_speed: f(self.leaving_speed),
            angle: f(self.angle),
            load_cell_force: f(self.load_cell_force),
            layon: self.layon.map(&f),
            layon_force: f(self.layon_force),
            layon_compression: f(self.layon_compression),
        }
    }
}

impl Outputs<Tangent> {
    /// The derivatives alone.
    pub fn tangents(&self) -> Outputs {
        self.map(|t| t.d)
    }
}
