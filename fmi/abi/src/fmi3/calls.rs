//! The bodies of the FMI 3.0 functions, generic over the model;
//! [`export_fmi3!`](crate::export_fmi3) exports them under their C names.

use super::*;
use crate::handle::{self, enter, unsupported, Request};
use crate::raw::{out_ref, slice, slice_mut, text, utf8};
use fmi_core::instance::Instance;
use fmi_core::snapshot::Snapshot;
use fmi_core::standard::fmi3::Call;
use fmi_core::standard::fmi3_types::{self as types, Added, Type};
use fmi_core::standard::{Call as _, Standard};
use fmi_core::{FmiError, FmiResult, Model, Resources};
use std::panic::{catch_unwind, AssertUnwindSafe};

pub fn get_version<M: Model>() -> *const c_char {
    c"3.0".as_ptr()
}

/// `fmi3InstantiateModelExchange` and `fmi3InstantiateCoSimulation`: checks
/// the interface and the instantiation token; no panic crosses the boundary.
unsafe fn instantiate<M: Model>(
    model_exchange: bool,
    instance_name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    logging_on: fmi3Boolean,
    environment: fmi3InstanceEnvironment,
    log_message: Option<fmi3LogMessageCallback>,
) -> fmi3Instance {
    let name = text(instance_name).unwrap_or_default();
    let request = Request {
        standard: Standard::Fmi3,
        function: if model_exchange { "fmi3InstantiateModelExchange" } else { "fmi3InstantiateCoSimulation" },
        instance_name: &name,
        model_exchange,
        token: text(token),
        token_name: "instantiationToken",
        // FMI 3.0 passes the resources folder as a path, not a URI.
        resources: Resources::from_path(text(resource_path).as_deref()),
        logging_on: logging_on != 0,
    };
    let logger = Logger { callback: log_message, environment };
    let Some(model) = handle::model_of::<M>(&request, &logger) else { return std::ptr::null_mut() };
    handle::instantiate::<M>(request, Box::new(logger), model)
}

pub unsafe fn set_debug_logging<M: Model>(
    c: fmi3Instance,
    logging_on: fmi3Boolean,
    n_categories: usize,
    categories: *const fmi3String,
) -> fmi3Status {
    let call = Call::SetDebugLogging;
    enter::<M, _>(c, call, |h| {
        let names = slice(call, categories, n_categories, "categories")?;
        let names: Vec<String> = names.iter().map(|&n| text(n).unwrap_or_default()).collect();
        h.instance.set_debug_logging(call.name(), logging_on != 0, &names)
    })
}

#[allow(clippy::too_many_arguments)]
pub unsafe fn instantiate_model_exchange<M: Model>(
    instance_name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    _visible: fmi3Boolean,
    logging_on: fmi3Boolean,
    environment: fmi3InstanceEnvironment,
    log_message: Option<fmi3LogMessageCallback>,
) -> fmi3Instance {
    instantiate::<M>(true, instance_name, token, resource_path, logging_on, environment, log_message)
}

/// `eventModeUsed` is ignored (the standard's rule when `hasEventMode` is
/// false) and early return never happens: steps are not interrupted.
#[allow(clippy::too_many_arguments)]
pub unsafe fn instantiate_co_simulation<M: Model>(
    instance_name: fmi3String,
    token: fmi3String,
    resource_path: fmi3String,
    _visible: fmi3Boolean,
    logging_on: fmi3Boolean,
    _event_mode_used: fmi3Boolean,
    _early_return_allowed: fmi3Boolean,
    required_intermediate_variables: *const fmi3ValueReference,
    n_required_intermediate_variables: usize,
    environment: fmi3InstanceEnvironment,
    log_message: Option<fmi3LogMessageCallback>,
    _intermediate_update: Option<fmi3IntermediateUpdateCallback>,
) -> fmi3Instance {
    if n_required_intermediate_variables > 0 {
        let logger = Logger { callback: log_message, environment };
        let first = required_intermediate_variables.as_ref().map_or("NULL".to_string(), |vr| vr.to_string());
        let _ = catch_unwind(AssertUnwindSafe(|| {
            logger.log(Status::Error, "logStatusError", &format!(
                "fmi3InstantiateCoSimulation: {n_required_intermediate_variables} requiredIntermediateVariables \
                 (the first {first}), but no variable of this FMU has intermediateUpdate"
            ))
        }));
        return std::ptr::null_mut();
    }
    instantiate::<M>(false, instance_name, token, resource_path, logging_on, environment, log_message)
}

#[allow(clippy::too_many_arguments)]
pub unsafe fn instantiate_scheduled_execution<M: Model>(
    _instance_name: fmi3String,
    _token: fmi3String,
    _resource_path: fmi3String,
    _visible: fmi3Boolean,
    _logging_on: fmi3Boolean,
    environment: fmi3InstanceEnvironment,
    log_message: Option<fmi3LogMessageCallback>,
    _clock_update: Option<fmi3ClockUpdateCallback>,
    _lock_preemption: Option<fmi3LockPreemptionCallback>,
    _unlock_preemption: Option<fmi3UnlockPreemptionCallback>,
) -> fmi3Instance {
    let logger = Logger { callback: log_message, environment };
    let _ = catch_unwind(AssertUnwindSafe(|| {
        logger.log(
            Status::Error,
            "logStatusError",
            "fmi3InstantiateScheduledExecution: this FMU offers Model Exchange and Co-Simulation, not Scheduled Execution",
        )
    }));
    std::ptr::null_mut()
}

pub unsafe fn free<M: Model>(c: fmi3Instance) {
    handle::free::<M>(c, Standard::Fmi3)
}

pub unsafe fn enter_initialization_mode<M: Model>(
    c: fmi3Instance,
    tolerance_defined: fmi3Boolean,
    tolerance: fmi3Float64,
    start_time: fmi3Float64,
    stop_time_defined: fmi3Boolean,
    stop_time: fmi3Float64,
) -> fmi3Status {
    let call = Call::EnterInitializationMode;
    enter::<M, _>(c, call, |h| {
        let tolerance = (tolerance_defined != 0).then_some(tolerance);
        let stop = (stop_time_defined != 0).then_some(stop_time);
        h.instance.setup_experiment(call.name(), tolerance, start_time, stop)?;
        h.instance.enter_initialization_mode()
    })
}

pub unsafe fn exit_initialization_mode<M: Model>(c: fmi3Instance) -> fmi3Status {
    enter::<M, _>(c, Call::ExitInitializationMode, |h| h.instance.exit_initialization_mode(Call::ExitInitializationMode.name()))
}

pub unsafe fn enter_event_mode<M: Model>(c: fmi3Instance) -> fmi3Status {
    enter::<M, _>(c, Call::EnterEventMode, |h| h.instance.enter_event_mode())
}

pub unsafe fn terminate<M: Model>(c: fmi3Instance) -> fmi3Status {
    enter::<M, _>(c, Call::Terminate, |h| h.instance.terminate())
}

pub unsafe fn reset<M: Model>(c: fmi3Instance) -> fmi3Status {
    enter::<M, _>(c, Call::Reset, |h| h.instance.reset())
}

// ---- Getting and setting variables

pub unsafe fn get_float64<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    let call = Call::GetFloat64;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let (vrs, out) = (slice(call, vr, nvr, "valueReferences")?, slice_mut(call, values, nvr, "values")?);
        if !types::check(h.instance.description(), call, vrs, Type::Float64, true)? {
            return h.instance.get_reals(call.name(), vrs, out);
        }
        let indicators = h.instance.description().number_of_event_indicators;
        for (&vr, value) in vrs.iter().zip(out.iter_mut()) {
            *value = match types::added(h.instance.description(), vr) {
                Some(Added::Time) => h.instance.time(),
                Some(Added::EventIndicator(i)) => {
                    let mut z = vec![0.0; indicators];
                    h.instance.get_event_indicators(call.name(), &mut z)?;
                    z[i]
                }
                None => {
                    let mut x = [0.0];
                    h.instance.get_reals(call.name(), &[vr], &mut x)?;
                    x[0]
                }
            };
        }
        Ok(())
    })
}

pub unsafe fn set_float64<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Float64,
    n_values: usize,
) -> fmi3Status {
    let call = Call::SetFloat64;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let vrs = slice(call, vr, nvr, "valueReferences")?;
        types::check(h.instance.description(), call, vrs, Type::Float64, false)?;
        h.instance.set_reals(call.name(), vrs, slice(call, values, nvr, "values")?)
    })
}

pub unsafe fn get_int32<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    let call = Call::GetInt32;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let vrs = slice(call, vr, nvr, "valueReferences")?;
        types::check(h.instance.description(), call, vrs, Type::Int32, true)?;
        h.instance.get_integers(call.name(), vrs, slice_mut(call, values, nvr, "values")?)
    })
}

pub unsafe fn set_int32<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Int32,
    n_values: usize,
) -> fmi3Status {
    let call = Call::SetInt32;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let vrs = slice(call, vr, nvr, "valueReferences")?;
        types::check(h.instance.description(), call, vrs, Type::Int32, false)?;
        h.instance.set_integers(call.name(), vrs, slice(call, values, nvr, "values")?)
    })
}

/// Enumerations: FMI 3.0 passes them as Int64.
pub unsafe fn get_int64<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Int64,
    n_values: usize,
) -> fmi3Status {
    let call = Call::GetInt64;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let vrs = slice(call, vr, nvr, "valueReferences")?;
        types::check(h.instance.description(), call, vrs, Type::Int64, true)?;
        let out = slice_mut(call, values, nvr, "values")?;
        let mut items = vec![0; nvr];
        h.instance.get_integers(call.name(), vrs, &mut items)?;
        out.iter_mut().zip(items).for_each(|(o, x)| *o = x.into());
        Ok(())
    })
}

pub unsafe fn set_int64<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Int64,
    n_values: usize,
) -> fmi3Status {
    let call = Call::SetInt64;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let vrs = slice(call, vr, nvr, "valueReferences")?;
        let description = h.instance.description();
        types::check(description, call, vrs, Type::Int64, false)?;
        let items = slice(call, values, nvr, "values")?
            .iter()
            .zip(vrs)
            .map(|(&x, &vr)| {
                i32::try_from(x).map_err(|_| {
                    let name = description.variable(vr).map_or("", |v| &v.name);
                    FmiError::error(format!("{}: {name} = {x} is not a value of its enumeration", call.name()))
                })
            })
            .collect::<FmiResult<Vec<i32>>>()?;
        h.instance.set_integers(call.name(), vrs, &items)
    })
}

pub unsafe fn get_boolean<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3Boolean,
    n_values: usize,
) -> fmi3Status {
    let call = Call::GetBoolean;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let vrs = slice(call, vr, nvr, "valueReferences")?;
        types::check(h.instance.description(), call, vrs, Type::Boolean, true)?;
        let out = slice_mut(call, values, nvr, "values")?;
        let mut flags = vec![0; nvr];
        h.instance.get_booleans(call.name(), vrs, &mut flags)?;
        out.iter_mut().zip(flags).for_each(|(o, x)| *o = (x != 0) as fmi3Boolean);
        Ok(())
    })
}

pub unsafe fn set_boolean<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3Boolean,
    n_values: usize,
) -> fmi3Status {
    let call = Call::SetBoolean;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let vrs = slice(call, vr, nvr, "valueReferences")?;
        types::check(h.instance.description(), call, vrs, Type::Boolean, false)?;
        // Bytes other than 0 and 1 reach the instance's check, which names them.
        let flags: Vec<i32> = slice(call, values, nvr, "values")?.iter().map(|&b| b.into()).collect();
        h.instance.set_booleans(call.name(), vrs, &flags)
    })
}

pub unsafe fn get_string<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *mut fmi3String,
    n_values: usize,
) -> fmi3Status {
    let call = Call::GetString;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let vrs = slice(call, vr, nvr, "valueReferences")?;
        types::check(h.instance.description(), call, vrs, Type::String, true)?;
        let out = slice_mut(call, values, nvr, "values")?;
        let mut texts = Vec::with_capacity(vrs.len());
        h.instance.get_strings(call.name(), vrs, |s| texts.push(c_text(s)))?;
        h.hand_out_strings(texts, out);
        Ok(())
    })
}

pub unsafe fn set_string<M: Model>(
    c: fmi3Instance,
    vr: *const fmi3ValueReference,
    nvr: usize,
    values: *const fmi3String,
    n_values: usize,
) -> fmi3Status {
    let call = Call::SetString;
    enter::<M, _>(c, call, |h| {
        types::check_count(call, nvr, n_values)?;
        let vrs = slice(call, vr, nvr, "valueReferences")?;
        types::check(h.instance.description(), call, vrs, Type::String, false)?;
        let texts = slice(call, values, nvr, "values")?
            .iter()
            .enumerate()
            .map(|(i, &s)| utf8(call, s, "values", i))
            .collect::<FmiResult<Vec<_>>>()?;
        h.instance.set_strings(call.name(), vrs, &texts)
    })
}

/// The get and set functions of types this FMU has no variables of: an
/// empty call is fine, any value reference is refused with the reason.
pub unsafe fn no_such_type<M: Model>(c: fmi3Instance, call: Call, nvr: usize, type_name: &str) -> fmi3Status {
    enter::<M, _>(c, call, |_| {
        if nvr == 0 {
            return Ok(());
        }
        Err(FmiError::error(format!(
            "{}: this FMU has no {type_name} variables (its types: Float64, Int32, Int64 for enumerations, Boolean, String)",
            call.name()
        )))
    })
}

// ---- FMU states (the FMI 2.0 layer's snapshots and their serialized form)

pub unsafe fn get_fmu_state<M: Model>(c: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    let call = Call::GetFMUState;
    enter::<M, _>(c, call, |h| {
        let snapshot = h.instance.snapshot();
        h.keep_state(call, state, "FMUState", snapshot)
    })
}

pub unsafe fn set_fmu_state<M: Model>(c: fmi3Instance, state: fmi3FMUState) -> fmi3Status {
    let call = Call::SetFMUState;
    enter::<M, _>(c, call, |h| {
        let snapshot = h.own_state(call, state)?.clone();
        h.instance.restore(call.name(), &snapshot)
    })
}

pub unsafe fn free_fmu_state<M: Model>(c: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status {
    let call = Call::FreeFMUState;
    enter::<M, _>(c, call, |h| h.free_state(call, state, "FMUState"))
}

pub unsafe fn serialized_fmu_state_size<M: Model>(c: fmi3Instance, state: fmi3FMUState, size: *mut usize) -> fmi3Status {
    let call = Call::SerializedFMUStateSize;
    enter::<M, _>(c, call, |h| {
        let n = h.own_state(call, state)?.to_bytes().len();
        *out_ref(call, size, "size")? = n;
        Ok(())
    })
}

pub unsafe fn serialize_fmu_state<M: Model>(
    c: fmi3Instance,
    state: fmi3FMUState,
    serialized: *mut fmi3Byte,
    size: usize,
) -> fmi3Status {
    let call = Call::SerializeFMUState;
    enter::<M, _>(c, call, |h| {
        let bytes = h.own_state(call, state)?.to_bytes();
        if size < bytes.len() {
            return Err(FmiError::error(format!(
                "{}: the buffer holds {size} bytes, the state needs {} (ask fmi3SerializedFMUStateSize)",
                call.name(),
                bytes.len()
            )));
        }
        slice_mut(call, serialized, bytes.len(), "serializedState")?.copy_from_slice(&bytes);
        Ok(())
    })
}

pub unsafe fn deserialize_fmu_state<M: Model>(
    c: fmi3Instance,
    serialized: *const fmi3Byte,
    size: usize,
    state: *mut fmi3FMUState,
) -> fmi3Status {
    let call = Call::DeserializeFMUState;
    enter::<M, _>(c, call, |h| {
        let bytes = slice(call, serialized, size, "serializedState")?;
        let snapshot = Snapshot::<M>::from_bytes(bytes, h.instance.start_model())
            .and_then(|s| Instance::<M>::check_snapshot(&s).map(|()| s))
            .map_err(|why| FmiError::error(format!("{}: rejected: {}", call.name(), why.message)))?;
        h.keep_state(call, state, "FMUState", snapshot)
    })
}

// ---- Event mode and Model Exchange

pub unsafe fn update_discrete_states<M: Model>(
    c: fmi3Instance,
    discrete_states_need_update: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    nominals_changed: *mut fmi3Boolean,
    values_changed: *mut fmi3Boolean,
    next_event_time_defined: *mut fmi3Boolean,
    next_event_time: *mut fmi3Float64,
) -> fmi3Status {
    let call = Call::UpdateDiscreteStates;
    enter::<M, _>(c, call, |h| {
        let outs = [
            out_ref(call, discrete_states_need_update, "discreteStatesNeedUpdate")?,
            out_ref(call, terminate_simulation, "terminateSimulation")?,
            out_ref(call, nominals_changed, "nominalsOfContinuousStatesChanged")?,
            out_ref(call, values_changed, "valuesOfContinuousStatesChanged")?,
            out_ref(call, next_event_time_defined, "nextEventTimeDefined")?,
        ];
        let time = out_ref(call, next_event_time, "nextEventTime")?;
        let update = h.instance.new_discrete_states();
        let flags = [
            update.new_discrete_states_needed,
            update.terminate_simulation,
            false,
            update.states_changed,
            update.next_event_time.is_some(),
        ];
        for (out, flag) in outs.into_iter().zip(flags) {
            *out = flag as fmi3Boolean;
        }
        *time = update.next_event_time.unwrap_or(0.0);
        Ok(())
    })
}

pub unsafe fn enter_continuous_time_mode<M: Model>(c: fmi3Instance) -> fmi3Status {
    enter::<M, _>(c, Call::EnterContinuousTimeMode, |h| h.instance.enter_continuous_time_mode())
}

pub unsafe fn completed_integrator_step<M: Model>(
    c: fmi3Instance,
    _no_set_prior: fmi3Boolean,
    enter_event_mode: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
) -> fmi3Status {
    let call = Call::CompletedIntegratorStep;
    enter::<M, _>(c, call, |_| {
        // No step events: the model never asks for event mode or a stop here.
        *out_ref(call, enter_event_mode, "enterEventMode")? = 0;
        *out_ref(call, terminate_simulation, "terminateSimulation")? = 0;
        Ok(())
    })
}

pub unsafe fn set_time<M: Model>(c: fmi3Instance, time: fmi3Float64) -> fmi3Status {
    enter::<M, _>(c, Call::SetTime, |h| h.instance.set_time(Call::SetTime.name(), time))
}

pub unsafe fn set_continuous_states<M: Model>(c: fmi3Instance, x: *const fmi3Float64, nx: usize) -> fmi3Status {
    let call = Call::SetContinuousStates;
    enter::<M, _>(c, call, |h| h.instance.set_continuous_states(call.name(), slice(call, x, nx, "continuousStates")?))
}

pub unsafe fn get_continuous_state_derivatives<M: Model>(c: fmi3Instance, dx: *mut fmi3Float64, nx: usize) -> fmi3Status {
    let call = Call::GetContinuousStateDerivatives;
    enter::<M, _>(c, call, |h| h.instance.get_derivatives(call.name(), slice_mut(call, dx, nx, "derivatives")?))
}

pub unsafe fn get_event_indicators<M: Model>(c: fmi3Instance, z: *mut fmi3Float64, ni: usize) -> fmi3Status {
    let call = Call::GetEventIndicators;
    enter::<M, _>(c, call, |h| h.instance.get_event_indicators(call.name(), slice_mut(call, z, ni, "eventIndicators")?))
}

pub unsafe fn get_continuous_states<M: Model>(c: fmi3Instance, x: *mut fmi3Float64, nx: usize) -> fmi3Status {
    let call = Call::GetContinuousStates;
    enter::<M, _>(c, call, |h| h.instance.get_continuous_states(call.name(), slice_mut(call, x, nx, "continuousStates")?))
}

pub unsafe fn get_nominals_of_continuous_states<M: Model>(c: fmi3Instance, nominals: *mut fmi3Float64, nx: usize) -> fmi3Status {
    let call = Call::GetNominalsOfContinuousStates;
    enter::<M, _>(c, call, |h| h.instance.get_nominals(call.name(), slice_mut(call, nominals, nx, "nominals")?))
}

pub unsafe fn get_number_of_event_indicators<M: Model>(c: fmi3Instance, n: *mut usize) -> fmi3Status {
    let call = Call::GetNumberOfEventIndicators;
    enter::<M, _>(c, call, |h| {
        *out_ref(call, n, "nEventIndicators")? = h.instance.description().number_of_event_indicators;
        Ok(())
    })
}

pub unsafe fn get_number_of_continuous_states<M: Model>(c: fmi3Instance, n: *mut usize) -> fmi3Status {
    let call = Call::GetNumberOfContinuousStates;
    enter::<M, _>(c, call, |h| {
        *out_ref(call, n, "nContinuousStates")? = h.instance.description().states.len();
        Ok(())
    })
}

// ---- Co-Simulation

#[allow(clippy::too_many_arguments)]
pub unsafe fn do_step<M: Model>(
    c: fmi3Instance,
    current_communication_point: fmi3Float64,
    communication_step_size: fmi3Float64,
    _no_set_fmu_state_prior_to_current_point: fmi3Boolean,
    event_handling_needed: *mut fmi3Boolean,
    terminate_simulation: *mut fmi3Boolean,
    early_return: *mut fmi3Boolean,
    last_successful_time: *mut fmi3Float64,
) -> fmi3Status {
    let call = Call::DoStep;
    enter::<M, _>(c, call, |h| {
        // Every out-argument is checked before the step, so a refused call changes nothing.
        let flags = [
            out_ref(call, event_handling_needed, "eventHandlingNeeded")?,
            out_ref(call, terminate_simulation, "terminateSimulation")?,
            out_ref(call, early_return, "earlyReturn")?,
        ];
        let reached = out_ref(call, last_successful_time, "lastSuccessfulTime")?;
        let outcome = h.instance.do_step(call.name(), current_communication_point, communication_step_size);
        // Events (a slack web) are handled inside the step; a step is never cut short.
        for flag in flags {
            *flag = 0;
        }
        *reached = h.instance.time();
        outcome
    })
}

/// The FMI 2.0 layer's directional derivatives: the same checks (which
/// unknowns and knowns each state allows) and the model's partial derivatives.
#[allow(clippy::too_many_arguments)]
pub unsafe fn get_directional_derivative<M: Model>(
    c: fmi3Instance,
    unknowns: *const fmi3ValueReference,
    n_unknowns: usize,
    knowns: *const fmi3ValueReference,
    n_knowns: usize,
    seed: *const fmi3Float64,
    n_seed: usize,
    sensitivity: *mut fmi3Float64,
    n_sensitivity: usize,
) -> fmi3Status {
    let call = Call::GetDirectionalDerivative;
    enter::<M, _>(c, call, |h| {
        // Every variable is a scalar: one seed per known, one sensitivity per unknown.
        types::check_count(call, n_knowns, n_seed)?;
        types::check_count(call, n_unknowns, n_sensitivity)?;
        let unknowns = slice(call, unknowns, n_unknowns, "unknowns")?;
        let knowns = slice(call, knowns, n_knowns, "knowns")?;
        let seed = slice(call, seed, n_seed, "seed")?;
        let out = slice_mut(call, sensitivity, n_sensitivity, "sensitivity")?;
        h.instance.get_directional_derivative(call.name(), unknowns, knowns, seed, out)
    })
}

/// Refusals that depend on nothing but the call: the reason is the FMU's capabilities.
pub mod reasons {
    pub const DEPENDENCIES: &str = "the dependencies are fixed and listed in modelDescription.xml's ModelStructure";
    pub const ADJOINT: &str = "providesAdjointDerivatives is false";
    pub const CONFIGURATION: &str = "this FMU has no structural parameters";
    pub const CLOCKS: &str = "this FMU has no clocks";
    pub const OUTPUT_DERIVATIVES: &str = "maxOutputDerivativeOrder is 0";
    pub const STEP_MODE: &str = "Step Mode follows fmi3ExitInitializationMode directly (hasEventMode is false)";
    pub const SCHEDULED: &str = "this FMU offers no Scheduled Execution";
}

pub unsafe fn refuse<M: Model>(c: fmi3Instance, call: Call, why: &str) -> fmi3Status {
    unsupported::<M, _>(c, call, why)
}
