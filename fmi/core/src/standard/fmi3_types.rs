//! The FMI 3.0 view of the model description the generator emits:
//! each variable's FMI 3.0 type, and the variables FMI 3.0 adds. FMI 3.0
//! declares the independent variable `time` and makes event indicators
//! variables; the FMI 3.0 modelDescription.xml (written by `fmi-build` from
//! the FMI 2.0 one) gives `time` value reference 0 and event indicator `i`
//! the value reference `i` past the largest of the FMI 2.0 description.

use crate::description::{Kind, ModelDescription, Variable};
use crate::standard::fmi3::Call;
use crate::status::{FmiError, FmiResult};

/// The value reference of `time` (the FMI 2.0 descriptions leave 0 free).
pub const TIME_VR: u32 = 0;

/// The FMI 3.0 types the variables of an FMI 2.0 description map to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Type {
    Float64,
    Int32,
    /// Enumerations travel through the Int64 functions in FMI 3.0.
    Int64,
    Boolean,
    String,
}

impl Type {
    pub const fn of(kind: Kind) -> Type {
        match kind {
            Kind::Real => Type::Float64,
            Kind::Integer => Type::Int32,
            Kind::Enumeration { .. } => Type::Int64,
            Kind::Boolean => Type::Boolean,
            Kind::String => Type::String,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Type::Float64 => "Float64",
            Type::Int32 => "Int32",
            Type::Int64 => "Int64 (an enumeration)",
            Type::Boolean => "Boolean",
            Type::String => "String",
        }
    }
}

/// A Float64 value reference that is not an FMI 2.0 variable.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Added {
    Time,
    EventIndicator(usize),
}

/// The value reference of the first event indicator.
pub fn first_event_indicator(description: &ModelDescription) -> u32 {
    description.by_vr.len() as u32
}

/// What FMI 3.0 adds at `vr`, if anything.
pub fn added(description: &ModelDescription, vr: u32) -> Option<Added> {
    let first = first_event_indicator(description);
    if vr == TIME_VR && description.variable(vr).is_none() {
        Some(Added::Time)
    } else if vr >= first && ((vr - first) as usize) < description.number_of_event_indicators {
        Some(Added::EventIndicator((vr - first) as usize))
    } else {
        None
    }
}

/// Checks that every value reference is a variable of type `want` (or, for
/// Float64 gets, an added variable); returns whether any is an added one.
/// A refused call names the variable and its type in FMI 3.0's words.
pub fn check(description: &ModelDescription, call: Call, vrs: &[u32], want: Type, get: bool) -> FmiResult<bool> {
    let mut any_added = false;
    for &vr in vrs {
        match description.variable(vr) {
            Some(v) if Type::of(v.kind) == want => {}
            Some(v) => return Err(wrong_type(call, vr, v, want)),
            None => match added(description, vr) {
                Some(_) if want == Type::Float64 && get => any_added = true,
                Some(a) => return Err(not_settable_or_typed(call, vr, a, want)),
                None => return Err(FmiError::error(format!("{}: unknown value reference {vr}", call.c_name()))),
            },
        }
    }
    Ok(any_added)
}

#[cold]
fn wrong_type(call: Call, vr: u32, v: &Variable, want: Type) -> FmiError {
    FmiError::error(format!(
        "{}: {} (value reference {vr}) is of type {}, not {}",
        call.c_name(),
        v.name,
        Type::of(v.kind).name(),
        want.name()
    ))
}

#[cold]
fn not_settable_or_typed(call: Call, vr: u32, added: Added, want: Type) -> FmiError {
    let what = match added {
        Added::Time => "time (the independent variable)".to_string(),
        Added::EventIndicator(i) => format!("event indicator {} (value reference {vr})", i + 1),
    };
    let why = if want == Type::Float64 { "it can only be read".to_string() } else { format!("it is a Float64, not {}", want.name()) };
    FmiError::error(format!("{}: {what}: {why}", call.c_name()))
}

/// The number of values must match the number of value references: every
/// variable is a scalar.
pub fn check_count(call: Call, n_vr: usize, n_values: usize) -> FmiResult {
    if n_vr == n_values {
        Ok(())
    } else {
        Err(FmiError::error(format!(
            "{}: {n_values} values for {n_vr} value references; every variable of this FMU is a scalar",
            call.c_name()
        )))
    }
}
