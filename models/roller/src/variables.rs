//! Each variable of modelDescription.xml bound to its field, once: get,
//! set, the FMU state, input derivatives and the tangents of the computed
//! variables (`along`) follow from this table (see
//! `fmi_core::bind_variables!`). Ranges and types come from the XML; equations
//! for computed variables live in `physics`.

use crate::description::{Boolean, BooleanKind, Integer, Real, Switch, Text, DESCRIPTION};
use crate::jacobian::Tangents;
use crate::model::Roller;
use crate::parameters::Inputs;

fmi_core::bind_variables! {
    model: Roller,
    inputs: Inputs,
    tangents: Tangents,
    real {
        J: param(params.inertia),
        R: param(params.radius),
        b: param(params.damping),
        v_start: param(params.speed_start),
        wound_thickness: param(params.wound_thickness),
        wound_density: param(params.wound_density),
        wound_width: param(params.wound_width),
        carriage_m: param(params.carriage_mass),
        carriage_d: param(params.carriage_damping),
        carriage_k: param(params.carriage_stiffness),
        carriage_y_start: param(params.carriage_start),
        web_a_F: input(force_a[0]),
        web_b_F: input(force_b[0]),
        web_a_eps: input(strain_a[0]),
        tau_m: input(torque),
        F_load: input(load),
        web_a_v: computed(web_speed()),
        web_b_v: computed(web_speed()),
        web_b_eps: computed(strain_leaving(0)),
        omega: computed(omega()),
        r: computed(radius()),
        y: computed(carriage[0]),
        y_dot: computed(carriage[1]),
        tau: computed(drive_torque()),
        web_a_x: computed(contact_a_x()),
        web_a_y: computed(contact_y()),
        web_b_x: computed(contact_b_x()),
        web_b_y: computed(contact_y()),
        der_omega: computed(derivatives()[0]),
        der_r: computed(derivatives()[1]),
        der_y: computed(derivatives()[2]),
        der_y_dot: computed(derivatives()[3]),
        web_a_m: param(params.mass_a[0]),
        web_a2_m: param(params.mass_a[1]),
        web_a3_m: param(params.mass_a[2]),
        web_a4_m: param(params.mass_a[3]),
        web_a2_F: input(force_a[1]),
        web_a2_eps: input(strain_a[1]),
        web_a3_F: input(force_a[2]),
        web_a3_eps: input(strain_a[2]),
        web_a4_F: input(force_a[3]),
        web_a4_eps: input(strain_a[3]),
        web_b2_F: input(force_b[1]),
        web_b3_F: input(force_b[2]),
        web_b4_F: input(force_b[3]),
        web_a2_v: computed(web_speed()),
        web_a3_v: computed(web_speed()),
        web_a4_v: computed(web_speed()),
        web_b2_v: computed(web_speed()),
        web_b2_eps: computed(strain_leaving(1)),
        web_b3_v: computed(web_speed()),
        web_b3_eps: computed(strain_leaving(2)),
        web_b4_v: computed(web_speed()),
        web_b4_eps: computed(strain_leaving(3)),
        traction_mu: param(params.traction_mu),
        traction_wrap: param(params.traction_wrap),
        traction_v_slip: param(params.traction_v_slip),
        traction_width: param(params.traction_width),
        nip_mu: param(params.nip_mu),
        air_roughness: param(params.air_roughness),
        air_viscosity: param(params.air_viscosity),
        v: computed(surface_speed()),
        v_web: computed(web_speed()),
        slip: computed(slip()),
        traction: computed(traction_used()),
        mu_eff: computed(mu_eff()),
        h_air: computed(h_air()),
        der_v_web: computed(derivatives()[4]),
        traction_slip_start: param(params.traction_slip_start),
    }
    integer {
        roll: param(params.roll),
        inlets: param(params.inlets),
        outlets: param(params.outlets),
    }
    boolean {
        carriage: param(params.carriage),
        includeTraction: param(params.traction),
        layered: param(params.layered),
    }
    string {
        profile: param(params.profile),
    }
}
