//! The sensor outputs `v` and `T` in the units picked with `toUnitV` and
//! `toUnitF` [E7]. The factors come from the unit definitions of
//! modelDescription.xml (see build.rs); per-width units divide by wp2.width.

use crate::description::{FORCE_UNIT, SPEED_UNIT};
use crate::parameters::Parameters;
use fmi_core::description::UnitChoice;

/// The unit that force units per width of web derive from.
const PER_WIDTH: &str = "N/m";

/// Multipliers from SI to the chosen units, fixed once initialization ends.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SensorScale {
    pub speed: f64,
    pub force: f64,
}

fn choice(table: &'static [UnitChoice], value: i32) -> Option<&'static UnitChoice> {
    table.iter().find(|u| u.value == value)
}

impl SensorScale {
    /// `None` if an enumeration value has no unit (the FMI layer rejects
    /// such values before they get here).
    pub fn new(p: &Parameters) -> Option<Self> {
        let speed = choice(&SPEED_UNIT, p.speed_unit)?.factor;
        let force_unit = choice(&FORCE_UNIT, p.force_unit)?;
        let force = if force_unit.base_unit == PER_WIDTH {
            force_unit.factor / p.span_web.width
        } else {
            force_unit.factor
        };
        Some(SensorScale { speed, force })
    }
}
