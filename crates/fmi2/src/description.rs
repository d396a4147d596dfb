//! The types of the table that build.rs generates from `modelDescription.xml`.
//! The FMI layer checks every call against this table, so causality,
//! variability, types and allowed ranges are enforced in one place for any model.

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Causality {
    Parameter,
    CalculatedParameter,
    Input,
    Output,
    Local,
    Independent,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variability {
    Constant,
    Fixed,
    Tunable,
    Discrete,
    Continuous,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Initial {
    Exact,
    Approx,
    Calculated,
    /// Inputs and independent variables have no `initial` attribute.
    None,
}

/// The FMI type of a variable. Enumerations travel through the Integer functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    Real,
    Integer,
    Boolean,
    String,
    Enumeration { type_name: &'static str, values: &'static [i32] },
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Start {
    Real(f64),
    Integer(i32),
    Boolean(bool),
    None,
}

/// Allowed values of a Real: XML `min`/`max` are inclusive, the
/// `ConvertingSpan.range` annotation adds strict bounds.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    pub min: f64,
    pub min_inclusive: bool,
    pub max: f64,
    pub max_inclusive: bool,
}

impl Range {
    pub fn contains(&self, x: f64) -> bool {
        let above = if self.min_inclusive { x >= self.min } else { x > self.min };
        let below = if self.max_inclusive { x <= self.max } else { x < self.max };
        above && below
    }

    pub fn is_unbounded(&self) -> bool {
        self.min == f64::NEG_INFINITY && self.max == f64::INFINITY
    }
}

impl std::fmt::Display for Range {
    /// Interval notation, e.g. `(0, inf)` or `[0, inf)`.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let open = if self.min_inclusive && self.min.is_finite() { '[' } else { '(' };
        let close = if self.max_inclusive && self.max.is_finite() { ']' } else { ')' };
        write!(f, "{open}{}, {}{close}", self.min, self.max)
    }
}

#[derive(Debug)]
pub struct Variable {
    pub name: &'static str,
    pub vr: u32,
    pub description: &'static str,
    pub kind: Kind,
    pub causality: Causality,
    pub variability: Variability,
    pub initial: Initial,
    pub start: Start,
    pub range: Range,
    pub unit: &'static str,
}

/// One entry of ModelStructure: the unknown `vr` depends on the knowns `on`
/// (`None`: on all knowns).
#[derive(Debug)]
pub struct Dependency {
    pub vr: u32,
    pub on: Option<&'static [u32]>,
}

/// An item of a unit enumeration: value `x` in SI becomes `x * factor` in
/// this unit; `base_unit` names the SI unit it derives from (e.g. "N/m").
#[derive(Debug)]
pub struct UnitChoice {
    pub value: i32,
    pub name: &'static str,
    pub base_unit: &'static str,
    pub factor: f64,
}

#[derive(Debug)]
pub struct ModelDescription {
    pub model_name: &'static str,
    pub model_identifier: &'static str,
    pub guid: &'static str,
    pub log_categories: &'static [&'static str],
    pub variables: &'static [Variable],
    /// Value reference -> 1 + position in `variables`; 0 where there is none.
    pub vr_index: &'static [u16],
    pub output_dependencies: &'static [Dependency],
    pub initial_dependencies: &'static [Dependency],
    pub can_handle_variable_communication_step_size: bool,
    pub can_interpolate_inputs: bool,
    pub can_get_and_set_fmu_state: bool,
    pub can_serialize_fmu_state: bool,
    /// A `<ModelExchange>` element is present.
    pub model_exchange: bool,
    /// Value references of the continuous states, in the order of `derivatives`.
    pub states: &'static [u32],
    /// ModelStructure/Derivatives: the derivative variables and their dependencies.
    pub derivatives: &'static [Dependency],
    pub number_of_event_indicators: usize,
}

impl ModelDescription {
    pub fn variable(&self, vr: u32) -> Option<&'static Variable> {
        let position = *self.vr_index.get(vr as usize)? as usize;
        // `variables` is 'static, so the borrow outlives self.
        let variables: &'static [Variable] = self.variables;
        position.checked_sub(1).and_then(|i| variables.get(i))
    }

    pub fn variable_by_name(&self, name: &str) -> Option<&'static Variable> {
        let variables: &'static [Variable] = self.variables;
        variables.iter().find(|v| v.name == name)
    }
}
