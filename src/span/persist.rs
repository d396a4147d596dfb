//! The model's fields in an FMU state, in a fixed order (see
//! `fmi2::snapshot` for the framing, version and checksum around them).

use super::parameters::{Inputs, Parameters, SolverChoice, WebProperties};
use super::sensor::SensorScale;
use super::{ConvertingSpan, Previous, Rates};
use crate::fmi2::{Persist, StateReader, StateWriter};
use crate::solver::CompensatedSum;

impl Persist for ConvertingSpan {
    fn save(&self, out: &mut StateWriter) {
        let p = &self.params;
        out.f64(p.span_length);
        for web in [&p.incoming, &p.span_web] {
            for x in [web.modulus, web.thickness, web.width, web.density, web.retardation_time] {
                out.f64(x);
            }
        }
        for b in [
            p.include_damping,
            p.prevent_negative_tension,
            p.include_mass,
            p.variable_length,
            p.start_at_equilibrium,
            p.use_sensor,
        ] {
            out.bool(b);
        }
        out.f64(p.strain_start);
        for i in [p.speed_unit, p.force_unit, p.solver, p.substeps] {
            out.i32(i);
        }
        out.f64(p.tolerance);
        save_inputs(out, &self.inputs);
        out.bool(self.input_rates.is_some());
        save_inputs(out, &self.input_rates.unwrap_or_default());
        out.f64(self.unstretched.hi());
        out.f64(self.unstretched.lo());
        for x in [self.rates.speed_b, self.rates.length, self.previous.speed_b, self.previous.length, self.previous.step] {
            out.f64(x);
        }
        out.f64(self.adaptive_step);
        out.f64(self.tolerance);
    }

    fn load(r: &mut StateReader) -> Result<Self, String> {
        let span_length = r.finite("L")?;
        let mut web = |prefix: &str| -> Result<WebProperties, String> {
            Ok(WebProperties {
                modulus: r.finite(&format!("{prefix}.E"))?,
                thickness: r.finite(&format!("{prefix}.thickness"))?,
                width: r.finite(&format!("{prefix}.width"))?,
                density: r.finite(&format!("{prefix}.density"))?,
                retardation_time: r.finite(&format!("{prefix}.d_r"))?,
            })
        };
        let incoming = web("wp1")?;
        let span_web = web("wp2")?;
        let params = Parameters {
            span_length,
            incoming,
            span_web,
            include_damping: r.bool("includeDamping")?,
            prevent_negative_tension: r.bool("preventNegativeTension")?,
            include_mass: r.bool("includeMass")?,
            variable_length: r.bool("variableLength")?,
            start_at_equilibrium: r.bool("startAtEquilibrium")?,
            use_sensor: r.bool("useSensor")?,
            strain_start: r.finite("eps_start")?,
            speed_unit: r.i32("toUnitV")?,
            force_unit: r.i32("toUnitF")?,
            solver: r.i32("solver")?,
            substeps: r.i32("substeps")?,
            tolerance: r.finite("tolerance")?,
        };
        let inputs = load_inputs(r)?;
        let has_rates = r.bool("input derivatives given")?;
        let rates = load_inputs(r)?;
        let unstretched = CompensatedSum::from_parts(r.finite("unstretched length")?, r.finite("unstretched length carry")?);
        let rates_out = Rates { speed_b: r.finite("dv_b/dt")?, length: r.finite("dL/dt")? };
        let previous = Previous {
            speed_b: r.finite("previous web_b.v")?,
            length: r.finite("previous length")?,
            step: r.finite("previous step")?,
        };
        let adaptive_step = r.finite("adaptive step")?;
        let tolerance = r.finite("effective tolerance")?;
        // Derived from the parameters; a state saved before initialization
        // ended gets the scale of its parameters, which initialization recomputes.
        let sensor = SensorScale::new(&params).unwrap_or_default();
        let solver = SolverChoice::from_i32(params.solver).unwrap_or_default();
        Ok(ConvertingSpan {
            params,
            inputs,
            input_rates: has_rates.then_some(rates),
            unstretched,
            rates: rates_out,
            previous,
            adaptive_step,
            sensor,
            tolerance,
            solver,
            // Transient: what happened inside the last step, not state.
            slack_event: None,
        })
    }
}

fn save_inputs(out: &mut StateWriter, u: &Inputs) {
    for x in [u.speed_a, u.strain_a, u.speed_b, u.frame_a[0], u.frame_a[1], u.frame_b[0], u.frame_b[1]] {
        out.f64(x);
    }
}

fn load_inputs(r: &mut StateReader) -> Result<Inputs, String> {
    Ok(Inputs {
        speed_a: r.finite("web_a.v")?,
        strain_a: r.finite("web_a.eps")?,
        speed_b: r.finite("web_b.v")?,
        frame_a: [r.finite("frame_a.x")?, r.finite("frame_a.y")?],
        frame_b: [r.finite("frame_b.x")?, r.finite("frame_b.y")?],
    })
}
