//! A web in an FMU state: its values and its stress–strain table, so that a
//! restored state needs no file (the span's webs, and those of its timed changes).

use crate::parameters::WebProperties;
use crate::stress_strain::StressStrain;
use fmi_core::{FmiError, FmiResult, StateReader, StateWriter};
use std::sync::Arc;

/// A web's values and stress–strain table in an FMU state.
pub fn save_web(web: &WebProperties, out: &mut StateWriter) {
    for x in [web.modulus, web.thickness, web.width, web.density, web.retardation_time] {
        out.f64(x);
    }
    save_curve(web, out);
}

pub fn load_web(r: &mut StateReader, what: &str) -> FmiResult<WebProperties> {
    Ok(WebProperties {
        modulus: r.finite(what)?,
        thickness: r.finite(what)?,
        width: r.finite(what)?,
        density: r.finite(what)?,
        retardation_time: r.finite(what)?,
        curve: load_curve(r, what)?,
    })
}

pub fn save_curve(web: &WebProperties, out: &mut StateWriter) {
    let points: Vec<[f64; 2]> = web.curve.as_ref().map_or_else(Vec::new, |c| c.points().collect());
    out.i32(points.len() as i32);
    for [e, s] in points {
        out.f64(e);
        out.f64(s);
    }
}

pub fn load_curve(r: &mut StateReader, what: &str) -> FmiResult<Option<Arc<StressStrain>>> {
    let n = r.i32(what)?;
    if !(0..=1_000_000).contains(&n) {
        return Err(FmiError::error(format!("{what} has {n} points")));
    }
    let points = (0..n).map(|_| Ok([r.finite(what)?, r.finite(what)?])).collect::<FmiResult<Vec<_>>>()?;
    Ok(match points.is_empty() {
        true => None,
        false => Some(Arc::new(StressStrain::new(&points).map_err(|e| FmiError::error(format!("{what} {e}")))?)),
    })
}
