//! The bodies of the functions of the FMI 2.0 C API that are its own, generic
//! over the model (those FMI 3.0 shares are in `alike` and `fmu_states`);
//! [`export_fmi2!`](crate::export_fmi2) exports them under their C names.

use super::*;
use crate::alike;
use crate::handle::{self, enter, out_ref, slice, slice_mut, text, unsupported, Request};
use super::logger::Logger;
use fmi_core::instance::unavailable_status;
use fmi_core::standard::fmi2::Call;
use fmi_core::standard::{Call as _, Standard};
use fmi_core::{FmiResult, Model, Resources};

const OK: FmiResult = Ok(());

pub fn get_types_platform<M: Model>() -> *const c_char {
    c"default".as_ptr()
}

pub fn get_version<M: Model>() -> *const c_char {
    c"2.0".as_ptr()
}

/// `fmi2Instantiate`: the FMU type and GUID checked, what is kept copied.
pub unsafe fn instantiate<M: Model>(
    instance_name: fmi2String,
    fmu_type: fmi2Type,
    guid: fmi2String,
    resource_location: fmi2String,
    functions: *const fmi2CallbackFunctions,
    _visible: fmi2Boolean,
    logging_on: fmi2Boolean,
) -> fmi2Component {
    // Without the callback functions there is no way to report anything.
    let Some(functions) = functions.as_ref() else { return std::ptr::null_mut() };
    let name = text(instance_name).unwrap_or_default();
    let logger = Logger::new(functions, &name);
    let mut request = Request {
        standard: Standard::Fmi2,
        function: "fmi2Instantiate",
        instance_name: &name,
        model_exchange: false,
        token: text(guid),
        token_name: "GUID",
        resources: Resources::from_location(text(resource_location).as_deref()),
        logging_on: logging_on != 0,
    };
    let Some(model) = handle::model_of::<M>(&request, &logger) else { return std::ptr::null_mut() };
    let description = model.description();
    request.model_exchange = match fmu_type {
        fmi2CoSimulation => false,
        fmi2ModelExchange if description.model_exchange => true,
        _ => {
            let offered = if description.model_exchange { "Model Exchange (0) and Co-Simulation (1)" } else { "only Co-Simulation (1)" };
            let message = format!("fmi2Instantiate: fmuType = {fmu_type} requested, but {} offers {offered}", description.model_identifier);
            handle::refuse(&logger, &message);
            return std::ptr::null_mut();
        }
    };
    handle::instantiate::<M>(request, Box::new(logger), model)
}

pub unsafe fn setup_experiment<M: Model>(
    c: fmi2Component,
    tolerance_defined: fmi2Boolean,
    tolerance: fmi2Real,
    start_time: fmi2Real,
    stop_time_defined: fmi2Boolean,
    stop_time: fmi2Real,
) -> fmi2Status {
    enter::<M, _>(c, Call::SetupExperiment, |h| {
        let tolerance = (tolerance_defined != 0).then_some(tolerance);
        let stop = (stop_time_defined != 0).then_some(stop_time);
        h.instance.setup_experiment(Call::SetupExperiment.name(), tolerance, start_time, stop)?;
        OK
    })
}

pub unsafe fn enter_initialization_mode<M: Model>(c: fmi2Component) -> fmi2Status {
    enter::<M, _>(c, Call::EnterInitializationMode, |h| h.instance.enter_initialization_mode().and(OK))
}

pub unsafe fn get_real<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Real,
) -> fmi2Status {
    let call = Call::GetReal;
    enter::<M, _>(c, call, |h| {
        let vrs = slice(call, vr, nvr, "vr")?;
        h.instance.get_reals(call.name(), vrs, slice_mut(call, value, nvr, "value")?)?;
        OK
    })
}

pub unsafe fn get_integer<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Integer,
) -> fmi2Status {
    let call = Call::GetInteger;
    enter::<M, _>(c, call, |h| {
        let vrs = slice(call, vr, nvr, "vr")?;
        h.instance.get_integers(call.name(), vrs, slice_mut(call, value, nvr, "value")?)?;
        OK
    })
}

pub unsafe fn get_boolean<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    let call = Call::GetBoolean;
    enter::<M, _>(c, call, |h| {
        let vrs = slice(call, vr, nvr, "vr")?;
        h.instance.get_booleans(call.name(), vrs, slice_mut(call, value, nvr, "value")?)?;
        OK
    })
}

pub unsafe fn get_string<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *mut fmi2String,
) -> fmi2Status {
    let call = Call::GetString;
    enter::<M, _>(c, call, |h| {
        let vrs = slice(call, vr, nvr, "vr")?;
        alike::get_strings(h, call, vrs, slice_mut(call, value, nvr, "value")?)
    })
}

pub unsafe fn set_real<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Real,
) -> fmi2Status {
    let call = Call::SetReal;
    enter::<M, _>(c, call, |h| {
        h.instance.set_reals(call.name(), slice(call, vr, nvr, "vr")?, slice(call, value, nvr, "value")?)?;
        OK
    })
}

pub unsafe fn set_integer<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Integer,
) -> fmi2Status {
    let call = Call::SetInteger;
    enter::<M, _>(c, call, |h| {
        h.instance.set_integers(call.name(), slice(call, vr, nvr, "vr")?, slice(call, value, nvr, "value")?)?;
        OK
    })
}

pub unsafe fn set_boolean<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2Boolean,
) -> fmi2Status {
    let call = Call::SetBoolean;
    enter::<M, _>(c, call, |h| {
        h.instance.set_booleans(call.name(), slice(call, vr, nvr, "vr")?, slice(call, value, nvr, "value")?)?;
        OK
    })
}

pub unsafe fn set_string<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    value: *const fmi2String,
) -> fmi2Status {
    let call = Call::SetString;
    enter::<M, _>(c, call, |h| {
        alike::set_strings(h, call, slice(call, vr, nvr, "vr")?, value, "value")
    })
}

pub unsafe fn get_directional_derivative<M: Model>(
    c: fmi2Component,
    unknown_refs: *const fmi2ValueReference,
    n_unknown: usize,
    known_refs: *const fmi2ValueReference,
    n_known: usize,
    dv_known: *const fmi2Real,
    dv_unknown: *mut fmi2Real,
) -> fmi2Status {
    let call = Call::GetDirectionalDerivative;
    let names = ["vUnknown_ref", "vKnown_ref", "dvKnown", "dvUnknown"];
    enter::<M, _>(c, call, |h| alike::directional_derivative(h, call, unknown_refs, n_unknown, known_refs, n_known, dv_known, dv_unknown, names))
}

// ---- Model Exchange

pub unsafe fn new_discrete_states<M: Model>(c: fmi2Component, info: *mut fmi2EventInfo) -> fmi2Status {
    let call = Call::NewDiscreteStates;
    enter::<M, _>(c, call, |h| {
        let info = out_ref(call, info, "fmi2eventInfo")?;
        let update = h.instance.new_discrete_states();
        *info = fmi2EventInfo {
            newDiscreteStatesNeeded: update.new_discrete_states_needed as fmi2Boolean,
            terminateSimulation: update.terminate_simulation as fmi2Boolean,
            nominalsOfContinuousStatesChanged: 0,
            valuesOfContinuousStatesChanged: update.states_changed as fmi2Boolean,
            nextEventTimeDefined: update.next_event_time.is_some() as fmi2Boolean,
            nextEventTime: update.next_event_time.unwrap_or(0.0),
        };
        OK
    })
}

// ---- Co-Simulation

pub unsafe fn set_real_input_derivatives<M: Model>(
    c: fmi2Component,
    vr: *const fmi2ValueReference,
    nvr: usize,
    order: *const fmi2Integer,
    value: *const fmi2Real,
) -> fmi2Status {
    let call = Call::SetRealInputDerivatives;
    enter::<M, _>(c, call, |h| {
        let vrs = slice(call, vr, nvr, "vr")?;
        let orders = slice(call, order, nvr, "order")?;
        h.instance.set_input_derivatives(call.name(), vrs, orders, slice(call, value, nvr, "value")?)?;
        OK
    })
}

pub unsafe fn get_real_output_derivatives<M: Model>(
    c: fmi2Component,
    _vr: *const fmi2ValueReference,
    _nvr: usize,
    _order: *const fmi2Integer,
    _value: *mut fmi2Real,
) -> fmi2Status {
    unsupported::<M, _>(c, Call::GetRealOutputDerivatives, "maxOutputDerivativeOrder is 0")
}

pub unsafe fn do_step<M: Model>(
    c: fmi2Component,
    current_communication_point: fmi2Real,
    communication_step_size: fmi2Real,
    _no_set_fmu_state_prior_to_current_point: fmi2Boolean,
) -> fmi2Status {
    enter::<M, _>(c, Call::DoStep, |h| {
        h.instance.do_step(Call::DoStep.name(), current_communication_point, communication_step_size).and(OK)
    })
}

pub unsafe fn cancel_step<M: Model>(c: fmi2Component) -> fmi2Status {
    unsupported::<M, _>(c, Call::CancelStep, "steps are synchronous (canRunAsynchronuously is false)")
}

pub unsafe fn get_status<M: Model>(c: fmi2Component, kind: fmi2StatusKind, _value: *mut fmi2Status) -> fmi2Status {
    enter::<M, _>(c, Call::GetStatus, |_| Err(unavailable_status(Call::GetStatus.name(), kind)))
}

pub unsafe fn get_real_status<M: Model>(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status {
    let call = Call::GetRealStatus;
    enter::<M, _>(c, call, |h| {
        let status = h.instance.real_status(call.name(), kind)?;
        *out_ref(call, value, "value")? = status;
        OK
    })
}

pub unsafe fn get_integer_status<M: Model>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    _value: *mut fmi2Integer,
) -> fmi2Status {
    enter::<M, _>(c, Call::GetIntegerStatus, |_| Err(unavailable_status(Call::GetIntegerStatus.name(), kind)))
}

pub unsafe fn get_boolean_status<M: Model>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    value: *mut fmi2Boolean,
) -> fmi2Status {
    let call = Call::GetBooleanStatus;
    enter::<M, _>(c, call, |h| {
        let status = h.instance.boolean_status(call.name(), kind)?;
        *out_ref(call, value, "value")? = status as fmi2Boolean;
        OK
    })
}

pub unsafe fn get_string_status<M: Model>(
    c: fmi2Component,
    kind: fmi2StatusKind,
    _value: *mut fmi2String,
) -> fmi2Status {
    enter::<M, _>(c, Call::GetStringStatus, |_| Err(unavailable_status(Call::GetStringStatus.name(), kind)))
}

// ---- An extension beyond the standard (`export_fmi2_steps!`): many Co-Simulation steps in one call

/// `convertingSpanDoSteps`: what an importer's loop of `fmi2DoStep` and `fmi2GetReal` does, in one
/// call. The outputs `vr` are read into row 0 of `values`, then for each `k < n_steps` the step
/// from `times[k]` to `times[k + 1]` is taken (`fmi2DoStep(c, times[k], times[k + 1] - times[k])`)
/// and the outputs read into row `k + 1`. `times` holds `n_steps + 1` points, `values`
/// `(n_steps + 1) * nvr`; `*steps_done` counts the steps taken, `*rows_done` the rows written. Each
/// step and read is the instance's own, as through the standard's functions: the same numbers,
/// statuses and log lines. The call stops at the first that fails and returns its status (a step's
/// or a read's: `*steps_done` and `*rows_done` say which); the state check is fmi2DoStep's, once.
#[allow(clippy::too_many_arguments)]
pub unsafe fn do_steps<M: Model>(
    c: fmi2Component,
    times: *const fmi2Real,
    n_steps: usize,
    vr: *const fmi2ValueReference,
    nvr: usize,
    values: *mut fmi2Real,
    steps_done: *mut usize,
    rows_done: *mut usize,
) -> fmi2Status {
    let call = Call::DoStep;
    enter::<M, _>(c, call, |h| {
        let steps = out_ref(call, steps_done, "stepsDone")?;
        let rows = out_ref(call, rows_done, "rowsDone")?;
        (*steps, *rows) = (0, 0);
        let too_many = || fmi_core::FmiError::error(format!("convertingSpanDoSteps: nSteps = {n_steps} with nvr = {nvr} is too large"));
        let points = n_steps.checked_add(1).ok_or_else(too_many)?;
        let times = slice(call, times, points, "times")?;
        let vrs = slice(call, vr, nvr, "vr")?;
        let values = slice_mut(call, values, points.checked_mul(nvr).ok_or_else(too_many)?, "values")?;
        let read = Call::GetReal.name();
        h.instance.get_reals(read, vrs, &mut values[..nvr])?;
        *rows = 1;
        for k in 0..n_steps {
            h.instance.do_step(call.name(), times[k], times[k + 1] - times[k])?;
            *steps = k + 1;
            h.instance.get_reals(read, vrs, &mut values[(k + 1) * nvr..(k + 2) * nvr])?;
            *rows = k + 2;
        }
        OK
    })
}
