//! The bodies of the functions of the FMI 3.0 C API that are its own, generic
//! over the model (those FMI 2.0 shares are in `alike` and `fmu_states`);
//! [`export_fmi3!`](crate::export_fmi3) exports them under their C names.

use super::*;
use crate::alike;
use crate::handle::{self, enter, out_ref, slice, slice_mut, text, unsupported, Request};
use super::logger::Logger;
use fmi_core::standard::fmi3::Call;
use fmi_core::standard::fmi3_types::{self as types, Added, Type};
use fmi_core::standard::{Call as _, Standard};
use fmi_core::{FmiError, FmiResult, Model, Resources};

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
    let logger = Logger::new(log_message, environment);
    let Some(model) = handle::model_of::<M>(&request, &logger) else { return std::ptr::null_mut() };
    handle::instantiate::<M>(request, Box::new(logger), model)
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
        let first = required_intermediate_variables.as_ref().map_or("NULL".to_string(), |vr| vr.to_string());
        let message = format!(
            "fmi3InstantiateCoSimulation: {n_required_intermediate_variables} requiredIntermediateVariables \
             (the first {first}), but no variable of this FMU has intermediateUpdate"
        );
        handle::refuse(&Logger::new(log_message, environment), &message);
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
    let message = "fmi3InstantiateScheduledExecution: this FMU offers Model Exchange and Co-Simulation, not Scheduled Execution";
    handle::refuse(&Logger::new(log_message, environment), message);
    std::ptr::null_mut()
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
        alike::get_strings(h, call, vrs, slice_mut(call, values, nvr, "values")?)
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
        alike::set_strings(h, call, vrs, values, "values")
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

/// FMI 2.0's directional derivatives, after FMI 3.0's counts are checked.
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
        let names = ["unknowns", "knowns", "seed", "sensitivity"];
        alike::directional_derivative(h, call, unknowns, n_unknowns, knowns, n_knowns, seed, sensitivity, names)
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
