//! The bodies of the 44 functions of the FMI 2.0 C API, generic over the
//! model; [`export_fmi2!`](crate::export_fmi2) exports them under their C names.

use super::*;
use crate::handle::{self, enter, unsupported, Request};
use crate::raw::{out_ref, slice, slice_mut, text, utf8};
use fmi_core::instance::{unavailable_status, Instance};
use fmi_core::snapshot::Snapshot;
use fmi_core::standard::fmi2::Call;
use fmi_core::standard::{Call as _, Standard};
use fmi_core::{FmiError, FmiResult, Model, Resources};

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
            let _ = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| logger.log(Status::Error, "logStatusError", &message)));
            return std::ptr::null_mut();
        }
    };
    handle::instantiate::<M>(request, Box::new(logger), model)
}

/// `fmi2FreeInstance`.
pub unsafe fn free_instance<M: Model>(c: fmi2Component) {
    handle::free::<M>(c, Standard::Fmi2)
}

pub unsafe fn set_debug_logging<M: Model>(
    c: fmi2Component,
    logging_on: fmi2Boolean,
    n_categories: usize,
    categories: *const fmi2String,
) -> fmi2Status {
    enter::<M, _>(c, Call::SetDebugLogging, |h| {
        let names = slice(Call::SetDebugLogging, categories, n_categories, "categories")?;
        let names: Vec<String> = names.iter().map(|&n| text(n).unwrap_or_default()).collect();
        h.instance.set_debug_logging(Call::SetDebugLogging.name(), logging_on != 0, &names)?;
        OK
    })
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

pub unsafe fn exit_initialization_mode<M: Model>(c: fmi2Component) -> fmi2Status {
    enter::<M, _>(c, Call::ExitInitializationMode, |h| h.instance.exit_initialization_mode(Call::ExitInitializationMode.name()).and(OK))
}

pub unsafe fn terminate<M: Model>(c: fmi2Component) -> fmi2Status {
    enter::<M, _>(c, Call::Terminate, |h| h.instance.terminate().and(OK))
}

pub unsafe fn reset<M: Model>(c: fmi2Component) -> fmi2Status {
    enter::<M, _>(c, Call::Reset, |h| h.instance.reset().and(OK))
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
        let out = slice_mut(call, value, nvr, "value")?;
        let mut texts = Vec::with_capacity(vrs.len());
        h.instance.get_strings(call.name(), vrs, |s| texts.push(c_text(s)))?;
        h.hand_out_strings(texts, out);
        OK
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
        let vrs = slice(call, vr, nvr, "vr")?;
        let texts = slice(call, value, nvr, "value")?
            .iter()
            .enumerate()
            .map(|(i, &s)| utf8(call, s, "value", i))
            .collect::<FmiResult<Vec<_>>>()?;
        h.instance.set_strings(call.name(), vrs, &texts)?;
        OK
    })
}

pub unsafe fn get_fmu_state<M: Model>(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    let call = Call::GetFMUstate;
    enter::<M, _>(c, call, |h| {
        let snapshot = h.instance.snapshot();
        h.keep_state(call, state, "FMUstate", snapshot)?;
        OK
    })
}

pub unsafe fn set_fmu_state<M: Model>(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status {
    let call = Call::SetFMUstate;
    enter::<M, _>(c, call, |h| {
        let snapshot = h.own_state(call, state)?.clone();
        h.instance.restore(call.name(), &snapshot)?;
        OK
    })
}

pub unsafe fn free_fmu_state<M: Model>(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status {
    let call = Call::FreeFMUstate;
    enter::<M, _>(c, call, |h| h.free_state(call, state, "FMUstate").and(OK))
}

pub unsafe fn serialized_fmu_state_size<M: Model>(
    c: fmi2Component,
    state: fmi2FMUstate,
    size: *mut usize,
) -> fmi2Status {
    let call = Call::SerializedFMUstateSize;
    enter::<M, _>(c, call, |h| {
        let n = h.own_state(call, state)?.to_bytes().len();
        *out_ref(call, size, "size")? = n;
        OK
    })
}

pub unsafe fn serialize_fmu_state<M: Model>(
    c: fmi2Component,
    state: fmi2FMUstate,
    serialized: *mut fmi2Byte,
    size: usize,
) -> fmi2Status {
    let call = Call::SerializeFMUstate;
    enter::<M, _>(c, call, |h| {
        let bytes = h.own_state(call, state)?.to_bytes();
        if size < bytes.len() {
            return Err(FmiError::error(format!(
                "{}: the buffer holds {size} bytes, the state needs {} (ask fmi2SerializedFMUstateSize)",
                call.name(),
                bytes.len()
            )));
        }
        let target = slice_mut(call, serialized as *mut u8, bytes.len(), "serializedState")?;
        target.copy_from_slice(&bytes);
        OK
    })
}

pub unsafe fn de_serialize_fmu_state<M: Model>(
    c: fmi2Component,
    serialized: *const fmi2Byte,
    size: usize,
    state: *mut fmi2FMUstate,
) -> fmi2Status {
    let call = Call::DeSerializeFMUstate;
    enter::<M, _>(c, call, |h| {
        let bytes = slice(call, serialized as *const u8, size, "serializedState")?;
        let snapshot = Snapshot::<M>::from_bytes(bytes, h.instance.start_model())
            .and_then(|s| Instance::<M>::check_snapshot(&s).map(|()| s))
            .map_err(|why| FmiError::error(format!("{}: rejected: {}", call.name(), why.message)))?;
        h.keep_state(call, state, "FMUstate", snapshot)?;
        OK
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
    enter::<M, _>(c, call, |h| {
        let unknowns = slice(call, unknown_refs, n_unknown, "vUnknown_ref")?;
        let knowns = slice(call, known_refs, n_known, "vKnown_ref")?;
        // A shared buffer would be read after it is written (and alias in Rust).
        if overlap(dv_known, n_known, dv_unknown, n_unknown) {
            return Err(FmiError::error(format!("{}: dvKnown and dvUnknown overlap; pass separate arrays", call.name())));
        }
        let seed = slice(call, dv_known, n_known, "dvKnown")?;
        let out = slice_mut(call, dv_unknown, n_unknown, "dvUnknown")?;
        h.instance.get_directional_derivative(call.name(), unknowns, knowns, seed, out)?;
        OK
    })
}

/// Whether two arrays of f64 share memory (empty and NULL ones never do).
fn overlap(a: *const f64, na: usize, b: *mut f64, nb: usize) -> bool {
    let (a, b) = (a as usize, b as usize);
    let size = std::mem::size_of::<f64>();
    na > 0 && nb > 0 && a != 0 && b != 0 && a < b.saturating_add(nb.saturating_mul(size)) && b < a.saturating_add(na.saturating_mul(size))
}

// ---- Model Exchange

pub unsafe fn enter_event_mode<M: Model>(c: fmi2Component) -> fmi2Status {
    enter::<M, _>(c, Call::EnterEventMode, |h| h.instance.enter_event_mode().and(OK))
}

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

pub unsafe fn enter_continuous_time_mode<M: Model>(c: fmi2Component) -> fmi2Status {
    enter::<M, _>(c, Call::EnterContinuousTimeMode, |h| h.instance.enter_continuous_time_mode().and(OK))
}

pub unsafe fn completed_integrator_step<M: Model>(
    c: fmi2Component,
    _no_set_prior: fmi2Boolean,
    enter_event_mode: *mut fmi2Boolean,
    terminate_simulation: *mut fmi2Boolean,
) -> fmi2Status {
    let call = Call::CompletedIntegratorStep;
    enter::<M, _>(c, call, |_| {
        // No step events: the model never asks for event mode or a stop here.
        *out_ref(call, enter_event_mode, "enterEventMode")? = 0;
        *out_ref(call, terminate_simulation, "terminateSimulation")? = 0;
        OK
    })
}

pub unsafe fn set_time<M: Model>(c: fmi2Component, time: fmi2Real) -> fmi2Status {
    enter::<M, _>(c, Call::SetTime, |h| h.instance.set_time(Call::SetTime.name(), time).and(OK))
}

pub unsafe fn set_continuous_states<M: Model>(c: fmi2Component, x: *const fmi2Real, nx: usize) -> fmi2Status {
    let call = Call::SetContinuousStates;
    enter::<M, _>(c, call, |h| h.instance.set_continuous_states(call.name(), slice(call, x, nx, "x")?).and(OK))
}

pub unsafe fn get_derivatives<M: Model>(c: fmi2Component, dx: *mut fmi2Real, nx: usize) -> fmi2Status {
    let call = Call::GetDerivatives;
    enter::<M, _>(c, call, |h| h.instance.get_derivatives(call.name(), slice_mut(call, dx, nx, "derivatives")?).and(OK))
}

pub unsafe fn get_event_indicators<M: Model>(c: fmi2Component, z: *mut fmi2Real, ni: usize) -> fmi2Status {
    let call = Call::GetEventIndicators;
    enter::<M, _>(c, call, |h| h.instance.get_event_indicators(call.name(), slice_mut(call, z, ni, "eventIndicators")?).and(OK))
}

pub unsafe fn get_continuous_states<M: Model>(c: fmi2Component, x: *mut fmi2Real, nx: usize) -> fmi2Status {
    let call = Call::GetContinuousStates;
    enter::<M, _>(c, call, |h| h.instance.get_continuous_states(call.name(), slice_mut(call, x, nx, "x")?).and(OK))
}

pub unsafe fn get_nominals_of_continuous_states<M: Model>(
    c: fmi2Component,
    x_nominal: *mut fmi2Real,
    nx: usize,
) -> fmi2Status {
    let call = Call::GetNominalsOfContinuousStates;
    enter::<M, _>(c, call, |h| h.instance.get_nominals(call.name(), slice_mut(call, x_nominal, nx, "x_nominal")?).and(OK))
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
