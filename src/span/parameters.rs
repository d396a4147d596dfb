//! Parameters and inputs of the span, in SI units.

/// Properties of one web (`wp1`: arriving at a; `wp2`: in the span).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WebProperties {
    /// Young's modulus E in the machine direction, Pa.
    pub modulus: f64,
    /// Unstrained thickness, m.
    pub thickness: f64,
    /// Unstrained width, m.
    pub width: f64,
    /// Density, kg/m3.
    pub density: f64,
    /// Kelvin–Voigt retardation time d_r, s.
    pub retardation_time: f64,
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
}

#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Parameters {
    /// L, m.
    pub span_length: f64,
    /// wp1: the web arriving at a.
    pub incoming: WebProperties,
    /// wp2: the web in the span, after the conversion.
    pub span_web: WebProperties,
    pub include_damping: bool,
    pub prevent_negative_tension: bool,
    pub start_at_equilibrium: bool,
    /// Initial span strain when not starting at equilibrium.
    pub strain_start: f64,
    pub use_sensor: bool,
    /// Enumeration value of `toUnitV`.
    pub speed_unit: i32,
    /// Enumeration value of `toUnitF`.
    pub force_unit: i32,
}

/// Inputs, held constant over each communication step.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Inputs {
    /// v_a: surface speed of the upstream roller, m/s.
    pub speed_a: f64,
    /// eps_a: strain of the web arriving at a.
    pub strain_a: f64,
    /// v_b: surface speed of the downstream roller, m/s.
    pub speed_b: f64,
}
