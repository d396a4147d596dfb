//! Each variable of modelDescription.xml bound to its field, once: get,
//! set, the FMU state, input derivatives, the tangents of the outputs
//! (`along`) and the forces a line's rollers read (`group_real`) follow from
//! this table (see `fmi_core::bind_variables!`). Ranges and types come from
//! the XML; equations for computed variables live in `physics`.

use crate::description::{Boolean, BooleanKind, Effect, Integer, Real, Switch, Text, DESCRIPTION};
use crate::jacobian::Tangents;
use crate::model::ConvertingSpan;
use crate::parameters::Inputs;
use crate::physics::Forces;

fmi_core::bind_variables! {
    model: ConvertingSpan,
    inputs: Inputs,
    // The forces at the span's ends and dx/dt, computed together (what a line's rollers read).
    group: (outputs().forces): Forces,
    tangents: Tangents,
    real {
        L: param(params.span_length),
        wp1_E: param(params.incoming.modulus),
        wp1_thickness: param(params.incoming.thickness),
        wp1_width: param(params.incoming.width),
        wp1_density: param(params.incoming.density),
        wp1_d_r: param(params.incoming.retardation_time),
        wp2_E: param(params.span_web.modulus),
        wp2_thickness: param(params.span_web.thickness),
        wp2_width: param(params.span_web.width),
        wp2_density: param(params.span_web.density),
        wp2_d_r: param(params.span_web.retardation_time),
        eps_start: param(params.strain_start),
        tolerance: param(params.tolerance),
        web_a_v: input(speed_a),
        web_a_eps: input(strain_a),
        web_b_v: input(speed_b),
        frame_a_x: input(frame_a[0]),
        frame_a_y: input(frame_a[1]),
        frame_b_x: input(frame_b[0]),
        frame_b_y: input(frame_b[1]),
        v: computed(outputs().sensor_speed),
        T: computed(outputs().sensor_tension),
        web_a_F: group(tension),
        web_b_F: group(exit_force),
        web_b_eps: group(strain),
        summary_Tension: group(tension),
        summary_Length: group(length),
        summary_Strain: group(strain),
        summary_Stress: computed(outputs().stress),
        unstretchedLength: computed(unstretched_length()),
        m_web: computed(web_mass()),
        der_unstretchedLength: group(unstretched_rate),
    }
    integer {
        toUnitV: param(params.speed_unit),
        toUnitF: param(params.force_unit),
        solver: param(params.solver),
        substeps: param(params.substeps),
    }
    boolean {
        @effects(params.effects),
        startAtEquilibrium: param(params.start_at_equilibrium),
        useSensor: param(params.use_sensor),
    }
    string {
        wp1_record: param(params.incoming_record),
        wp2_record: param(params.span_record),
        webLibrary: param(params.web_library),
        profile: param(params.profile),
    }
}
