//! Parameters and inputs of the span, in SI units.

use crate::description::{Effects, Solver};
use crate::stress_strain::StressStrain;
use fmi_core::{FmiError, FmiResult};
use std::sync::Arc;

/// Properties of one web (`wp1`: arriving at a; `wp2`: in the span).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct WebProperties {
    /// Young's modulus E in the machine direction, Pa (with a stress–strain
    /// table: its steepest chord, the stiffest the web gets).
    pub modulus: f64,
    /// Unstrained thickness, m.
    pub thickness: f64,
    /// Unstrained width, m.
    pub width: f64,
    /// Density, kg/m3.
    pub density: f64,
    /// Kelvin–Voigt retardation time d_r, s.
    pub retardation_time: f64,
    /// A nonlinear web's stress–strain curve, from a record; `None`: sigma = E*eps.
    pub curve: Option<Arc<StressStrain>>,
}

impl WebProperties {
    /// Unstrained cross-section A = width * thickness, m2.
    pub fn area(&self) -> f64 {
        self.width * self.thickness
    }

    /// Axial stiffness E*A, N.
    pub fn stiffness(&self) -> f64 {
        self.modulus * self.area()
    }

    /// Mass per unstretched length rho_l = density * A, kg/m.
    pub fn linear_density(&self) -> f64 {
        self.density * self.area()
    }
}

/// Who decides whether a web with `preventNegativeTension` is slack [E5]: the span, by its own
/// pull; or, for a layer of a bonded laminate, the laminate, by the sum of its layers' pulls
/// (docs/merge-split.md, [M6]), which a line decides and sets on each layer.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SlackRule {
    #[default]
    Own,
    Laminate { slack: bool },
}

#[derive(Clone, Debug, Default, PartialEq)]
pub struct Parameters {
    /// L, m (when the length is not taken from the roller positions).
    pub span_length: f64,
    /// wp1: the web arriving at a.
    pub incoming: WebProperties,
    /// wp2: the web in the span, after the conversion.
    pub span_web: WebProperties,
    /// `wp1.record`, `wp2.record`: names of records that give the webs ("": none).
    pub incoming_record: Arc<str>,
    pub span_record: Arc<str>,
    /// `webLibrary`: a user's JSON file of records, searched first ("": none).
    pub web_library: Arc<str>,
    /// The five values (E, thickness, width, density, d_r) a record last wrote into wp1 and wp2:
    /// initialization runs again when a value changes in initialization mode, and these are not the user's.
    pub from_records: [Option<[f64; 5]>; 2],
    /// `profile`: a JSON file of timed web changes ("": the FMU's own, if any).
    pub profile: Arc<str>,
    /// The effects on (one field each, named after their Boolean parameters).
    pub effects: Effects,
    pub start_at_equilibrium: bool,
    /// Initial span strain when not starting at equilibrium.
    pub strain_start: f64,
    pub use_sensor: bool,
    /// Enumeration value of `toUnitV`.
    pub speed_unit: i32,
    /// Enumeration value of `toUnitF`.
    pub force_unit: i32,
    pub solver: Solver,
    /// Relative tolerance of the adaptive solvers, as set by the user.
    pub tolerance: f64,
    /// Sub-steps of the fixed-step solvers.
    pub substeps: i32,
    /// Who decides that the web is slack: the span, or the laminate it is a layer of (set by a line).
    pub slack_rule: SlackRule,
}

/// Inputs at one instant. Within a communication step they are held, or,
/// when the importer gives first derivatives, they move linearly.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Inputs {
    /// v_a: surface speed of the upstream roller, m/s.
    pub speed_a: f64,
    /// eps_a: strain of the web arriving at a.
    pub strain_a: f64,
    /// v_b: surface speed of the downstream roller, m/s.
    pub speed_b: f64,
    /// (x, y) where the web leaves roller a, m.
    pub frame_a: [f64; 2],
    /// (x, y) where the web meets roller b, m.
    pub frame_b: [f64; 2],
}

impl Inputs {
    /// The inputs `tau` seconds later when they change at `rates` per second.
    pub fn advanced(&self, rates: &Inputs, tau: f64) -> Inputs {
        let at = |x: f64, r: f64| x + r * tau;
        Inputs {
            speed_a: at(self.speed_a, rates.speed_a),
            strain_a: at(self.strain_a, rates.strain_a),
            speed_b: at(self.speed_b, rates.speed_b),
            frame_a: [at(self.frame_a[0], rates.frame_a[0]), at(self.frame_a[1], rates.frame_a[1])],
            frame_b: [at(self.frame_b[0], rates.frame_b[0]), at(self.frame_b[1], rates.frame_b[1])],
        }
    }

    /// The roller-to-roller vector r_b - r_a.
    pub fn span_vector(&self) -> [f64; 2] {
        [self.frame_b[0] - self.frame_a[0], self.frame_b[1] - self.frame_a[1]]
    }
}

/// Rates of inputs that enter the outputs [E11].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Rates {
    /// dv_b/dt, m/s2.
    pub speed_b: f64,
    /// dL/dt, m/s.
    pub length: f64,
}

/// Products of parameters that are each in range but together overflow
/// (E*A, rho*A of a web of 1e300 m width) would make outputs infinite. Only
/// the products the equations use: the span web's stiffness and linear
/// density, and the arriving web's linear density with web mass.
pub fn check_derived(p: &Parameters) -> FmiResult {
    let w = &p.span_web;
    let used = [
        Some(("wp2: E*width*thickness", w.stiffness())),
        Some(("wp2: density*width*thickness", w.linear_density())),
        p.effects.include_mass.then(|| ("wp1: density*width*thickness", p.incoming.linear_density())),
    ];
    match used.into_iter().flatten().find(|(_, value)| !value.is_finite()) {
        Some((what, value)) => Err(FmiError::error(format!("{what} = {value} overflows: the parameters are each in range, not together"))),
        None => Ok(()),
    }
}
