//! Timed changes of the webs (a splice): the `set` events of the span's
//! profile (crate `profiles`). Each event is resolved when initialization
//! ends, records and ranges checked, so a step that reaches one only swaps
//! the webs in: no file, no allocation. The state (the unstretched length,
//! so the strain) carries over.

use crate::description::DESCRIPTION;
use crate::parameters::{Parameters, WebProperties};
use crate::records;
use crate::web_state;
use fmi_core::description::Start;
use fmi_core::{FmiError, FmiResult, Resources, StateReader, StateWriter, Variables};
use profiles::{Profile, Value};
use std::sync::Arc;

/// The webs from a time on.
#[derive(Clone, Debug, PartialEq)]
pub struct WebChange {
    pub time: f64,
    pub incoming: WebProperties,
    pub span_web: WebProperties,
    pub incoming_record: Arc<str>,
    pub span_record: Arc<str>,
}

impl WebChange {
    pub fn apply(&self, p: &mut Parameters) {
        p.incoming = self.incoming.clone();
        p.span_web = self.span_web.clone();
        p.incoming_record = self.incoming_record.clone();
        p.span_record = self.span_record.clone();
    }
}

/// The span's profile file, its events resolved in time order: each event's
/// values are set on a copy of `model` through its bindings, whose
/// parameters `params` reaches. With the warning when the FMU carries other
/// instances' profiles but none for this one.
pub fn load<M: Variables + Clone>(
    model: &M,
    params: fn(&mut M) -> &mut Parameters,
    resources: &Resources,
) -> FmiResult<(Arc<[WebChange]>, Option<String>)> {
    let profile_name = params(&mut model.clone()).profile.clone();
    let located = profiles::locate(&profile_name, resources.folder_or_why(), resources.instance(), &[records::SHIPPED])
        .map_err(FmiError::error)?;
    let Some(path) = located.path else {
        return Ok((Arc::new([]), located.unmatched));
    };
    let text = Profile::read_text(&path).map_err(FmiError::error)?;
    let profile = Profile::parse(&text, &[]).map_err(|e| FmiError::error(format!("profile {}: {e}", path.display())))?;
    let changes = resolve(model, params, &profile, resources).map_err(|e| e.prefixed(&format!("profile {}", path.display())))?;
    Ok((changes, None))
}

fn resolve<M: Variables + Clone>(model: &M, params: fn(&mut M) -> &mut Parameters, profile: &Profile, resources: &Resources) -> FmiResult<Arc<[WebChange]>> {
    let mut scratch = model.clone();
    let mut changes = Vec::with_capacity(profile.events.len());
    for e in &profile.events {
        let at = format!("set at {} s", e.time);
        // A record chosen by the event replaces that side's values: back to their start values.
        for (name, _) in &e.changes {
            if let Some(side) = name.strip_suffix(".record") {
                for v in DESCRIPTION.variables.iter().filter(|v| v.name.starts_with(&format!("{side}.")) && v.name != name.as_str()) {
                    if let Start::Real(x) = v.start {
                        scratch.set_real(v.vr, x)?;
                    }
                }
            }
        }
        for (name, value) in &e.changes {
            let v = DESCRIPTION
                .variable_by_name(name)
                .filter(|v| v.name.starts_with("wp1.") || v.name.starts_with("wp2."))
                .ok_or_else(|| FmiError::error(format!("{at}: {name:?} cannot change during a run (the wp1.* and wp2.* parameters can)")))?;
            match (value, v.start) {
                (Value::Number(x), Start::Real(_)) if v.range.contains(*x) => scratch.set_real(v.vr, *x)?,
                (Value::Number(x), Start::Real(_)) => return Err(FmiError::error(format!("{at}: {name} = {x} is outside {}", v.range))),
                (Value::Text(t), Start::String(_)) => scratch.set_string(v.vr, t)?,
                _ => return Err(FmiError::error(format!("{at}: {name} takes a {}", if matches!(v.start, Start::String(_)) { "text" } else { "number" }))),
            }
        }
        let p = params(&mut scratch);
        records::apply(p, resources).map_err(|err| err.prefixed(&at))?;
        crate::parameters::check_derived(p).map_err(|err| err.prefixed(&at))?;
        changes.push(WebChange {
            time: e.time,
            incoming: p.incoming.clone(),
            span_web: p.span_web.clone(),
            incoming_record: p.incoming_record.clone(),
            span_record: p.span_record.clone(),
        });
    }
    Ok(changes.into())
}

/// Events in an FMU state: their resolved webs, so a restore needs no file.
pub fn save(changes: &[WebChange], out: &mut StateWriter) {
    out.i32(changes.len() as i32);
    for c in changes {
        out.f64(c.time);
        for web in [&c.incoming, &c.span_web] {
            web_state::save_web(web, out);
        }
        out.str(&c.incoming_record);
        out.str(&c.span_record);
    }
}

pub fn load_saved(r: &mut StateReader) -> FmiResult<Arc<[WebChange]>> {
    let n = r.i32("web changes")?;
    if !(0..=100_000).contains(&n) {
        return Err(FmiError::error(format!("the FMU state has {n} web changes")));
    }
    let mut changes = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let time = r.finite("web change time")?;
        let incoming = web_state::load_web(r, "wp1 of a web change")?;
        let span_web = web_state::load_web(r, "wp2 of a web change")?;
        let (incoming_record, span_record) = (r.string("wp1.record of a web change")?.into(), r.string("wp2.record of a web change")?.into());
        changes.push(WebChange { time, incoming, span_web, incoming_record, span_record });
    }
    Ok(changes.into())
}
