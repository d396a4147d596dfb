//! The types of the table that build.rs generates from `modelDescription.xml`,
//! or that a model builds at instantiation from what its FMU carries (a
//! line: its interface comes with the scene). The FMI layer checks every call
//! against this table, so causality, variability, types and allowed ranges
//! are enforced in one place for any model.

use crate::phase::Phase;
use std::borrow::Cow;

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

/// The type family of a get/set function: enumerations travel through the
/// Integer functions.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Family {
    Real,
    Integer,
    Boolean,
    String,
}

impl Family {
    pub const fn of(kind: Kind) -> Family {
        match kind {
            Kind::Real => Family::Real,
            Kind::Integer | Kind::Enumeration { .. } => Family::Integer,
            Kind::Boolean => Family::Boolean,
            Kind::String => Family::String,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Family::Real => "Real",
            Family::Integer => "Integer",
            Family::Boolean => "Boolean",
            Family::String => "String",
        }
    }
}

/// The phases in which `fmi2Set*` may set a variable (FMI 2.0, 2.2.7, the
/// table for co-simulation, and 3.2.3 for model exchange), one bit per `Phase`:
/// inputs always, but in continuous-time mode only continuous ones; parameters
/// before initialization when `initial` is exact or approx, during it when
/// exact, afterwards only when tunable, and never in continuous-time mode;
/// constants and computed values never.
pub const fn settable_in(causality: Causality, variability: Variability, initial: Initial) -> u8 {
    if matches!(variability, Variability::Constant) {
        return 0;
    }
    let continuous = Phase::ContinuousTimeMode.bit();
    match causality {
        Causality::Input if matches!(variability, Variability::Continuous) => u8::MAX,
        Causality::Input => u8::MAX & !continuous,
        Causality::Parameter => {
            let before = if matches!(initial, Initial::Exact | Initial::Approx) { Phase::Instantiated.bit() } else { 0 };
            let during = if matches!(initial, Initial::Exact) { Phase::InitializationMode.bit() } else { 0 };
            let after = if matches!(variability, Variability::Tunable) {
                !(Phase::Instantiated.bit() | Phase::InitializationMode.bit() | continuous)
            } else {
                0
            };
            before | during | after
        }
        _ => 0,
    }
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
    String(&'static str),
    None,
}

/// Allowed values of a Real: XML `min`/`max` are inclusive, the
/// `ConvertingSpan.range` annotation adds strict bounds. `lo` and `hi` are
/// the same set as inclusive bounds (a strict bound moved by one ulp, which
/// is exact for doubles), so that a check is two comparisons.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Range {
    pub min: f64,
    pub min_inclusive: bool,
    pub max: f64,
    pub max_inclusive: bool,
    pub lo: f64,
    pub hi: f64,
}

impl Range {
    /// False for NaN.
    #[inline]
    pub fn contains(&self, x: f64) -> bool {
        self.lo <= x && x <= self.hi
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

#[derive(Clone, Debug)]
pub struct Variable {
    pub name: Cow<'static, str>,
    pub vr: u32,
    pub description: Cow<'static, str>,
    pub kind: Kind,
    pub causality: Causality,
    pub variability: Variability,
    pub initial: Initial,
    pub start: Start,
    pub range: Range,
    pub unit: &'static str,
    /// An input's largest |derivative| per second (`maxRate` of the range
    /// annotation; infinite when not given).
    pub max_rate: f64,
    /// Derived: `Family::of(kind)`, and `settable_in(causality, variability, initial)`.
    pub family: Family,
    pub settable_in: u8,
}

/// One entry of ModelStructure: the unknown `vr` depends on the knowns `on`
/// (`None`: on all knowns).
#[derive(Clone, Debug)]
pub struct Dependency {
    pub vr: u32,
    pub on: Option<Cow<'static, [u32]>>,
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

#[derive(Clone, Debug)]
pub struct ModelDescription {
    pub model_name: Cow<'static, str>,
    pub model_identifier: &'static str,
    pub guid: Cow<'static, str>,
    pub log_categories: &'static [&'static str],
    pub variables: Cow<'static, [Variable]>,
    /// Value reference -> what a get or set checks, and the variable's row.
    pub by_vr: Cow<'static, [Slot]>,
    pub output_dependencies: Cow<'static, [Dependency]>,
    pub initial_dependencies: Cow<'static, [Dependency]>,
    pub can_handle_variable_communication_step_size: bool,
    pub can_interpolate_inputs: bool,
    pub can_get_and_set_fmu_state: bool,
    pub can_serialize_fmu_state: bool,
    /// `providesDirectionalDerivative` of Co-Simulation \[0\] and Model Exchange \[1\].
    pub provides_directional_derivative: [bool; 2],
    /// A `<ModelExchange>` element is present.
    pub model_exchange: bool,
    /// Value references of the continuous states, in the order of `derivatives`.
    pub states: Cow<'static, [u32]>,
    /// ModelStructure/Derivatives: the derivative variables and their dependencies.
    pub derivatives: Cow<'static, [Dependency]>,
    pub number_of_event_indicators: usize,
}

/// What a get or set checks per value, in one row per value reference
/// (derived from the variable in row `row` of `variables`): the hot path
/// reads this row and nothing else; error messages read the variable.
#[derive(Clone, Copy, Debug)]
pub struct Slot {
    /// The variable's row of `variables`; `NO_VARIABLE` for a value
    /// reference that names none.
    pub row: u32,
    pub family: Family,
    pub settable_in: u8,
    /// Neither a parameter nor an input: computed by the model.
    pub computed: bool,
    /// What a set accepts at once, both bounds inclusive and finite (so
    /// that NaN and infinities fail the same comparison): an input's range;
    /// every finite value for others (parameters are checked when
    /// initialization ends).
    pub set_lo: f64,
    pub set_hi: f64,
}

impl Slot {
    pub const NONE: Slot =
        Slot { row: NO_VARIABLE, family: Family::Real, settable_in: 0, computed: false, set_lo: 0.0, set_hi: -0.0 };

    pub const fn of(row: u32, v: &Variable) -> Slot {
        let input = matches!(v.causality, Causality::Input);
        Slot {
            row,
            family: v.family,
            settable_in: v.settable_in,
            computed: !matches!(v.causality, Causality::Parameter | Causality::Input),
            set_lo: if input && v.range.lo > -f64::MAX { v.range.lo } else { -f64::MAX },
            set_hi: if input && v.range.hi < f64::MAX { v.range.hi } else { f64::MAX },
        }
    }

    /// The slots of `variables`, indexed by value reference.
    pub fn table(variables: &[Variable]) -> Vec<Slot> {
        let n = variables.iter().map(|v| v.vr as usize + 1).max().unwrap_or(0);
        let mut slots = vec![Slot::NONE; n];
        for (row, v) in variables.iter().enumerate() {
            slots[v.vr as usize] = Slot::of(row as u32, v);
        }
        slots
    }
}

/// The row of `by_vr` for a value reference that names no variable.
pub const NO_VARIABLE: u32 = u32::MAX;

impl ModelDescription {
    #[inline(always)]
    pub fn variable(&self, vr: u32) -> Option<&Variable> {
        self.variables.get(self.slot(vr)?.row as usize)
    }

    /// The slot of `vr`, if it names a variable.
    #[inline(always)]
    pub fn slot(&self, vr: u32) -> Option<&Slot> {
        self.by_vr.get(vr as usize).filter(|s| s.row != NO_VARIABLE)
    }

    pub fn variable_by_name(&self, name: &str) -> Option<&Variable> {
        self.variables.iter().find(|v| v.name == name)
    }
}
