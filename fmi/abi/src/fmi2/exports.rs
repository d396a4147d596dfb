//! The one list of FMI 2.0's C signatures, each with its body in `calls`
//! or, where FMI 3.0 has it too, in `alike` and `fmu_states`. [`fmi2_functions!`](crate::fmi2_functions)
//! hands the list to a macro: [`export_fmi2!`](crate::export_fmi2) defines the
//! exports from it, once per FMU crate (`fmi_abi::export_fmi2!(crate::MyModel);`),
//! and the test kit declares the same functions from it to call them.

/// Calls `$callback! { $model; fmi2 in MODULE; NAME(ARG: TYPE, ...) [-> RETURN] => BODY; ... }`
/// with every function of the FMI 2.0 C API, typed with `fmi_abi::fmi2`'s names.
#[macro_export]
macro_rules! fmi2_functions {
    ($callback:path, $model:ty) => {
        $callback! {
            $model; fmi2 in fmi2_exports;
            fmi2GetTypesPlatform() -> *const ::std::ffi::c_char => get_types_platform::<$model>();
            fmi2GetVersion() -> *const ::std::ffi::c_char => get_version::<$model>();
            fmi2SetDebugLogging(c: fmi2Component, logging_on: fmi2Boolean, n_categories: usize, categories: *const fmi2String) -> fmi2Status => alike::set_debug_logging::<$model, _>(c, Call::SetDebugLogging, logging_on != 0, n_categories, categories);
            fmi2Instantiate(instance_name: fmi2String, fmu_type: fmi2Type, guid: fmi2String, resource_location: fmi2String, functions: *const fmi2CallbackFunctions, visible: fmi2Boolean, logging_on: fmi2Boolean) -> fmi2Component => instantiate::<$model>(instance_name, fmu_type, guid, resource_location, functions, visible, logging_on);
            fmi2FreeInstance(c: fmi2Component) => handle::free::<$model>(c, Standard::Fmi2);
            fmi2SetupExperiment(c: fmi2Component, tolerance_defined: fmi2Boolean, tolerance: fmi2Real, start_time: fmi2Real, stop_time_defined: fmi2Boolean, stop_time: fmi2Real) -> fmi2Status => setup_experiment::<$model>(c, tolerance_defined, tolerance, start_time, stop_time_defined, stop_time);
            fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status => enter_initialization_mode::<$model>(c);
            fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status => alike::exit_initialization_mode::<$model, _>(c, Call::ExitInitializationMode);
            fmi2Terminate(c: fmi2Component) -> fmi2Status => alike::terminate::<$model, _>(c, Call::Terminate);
            fmi2Reset(c: fmi2Component) -> fmi2Status => alike::reset::<$model, _>(c, Call::Reset);
            fmi2GetReal(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *mut fmi2Real) -> fmi2Status => get_real::<$model>(c, vr, nvr, value);
            fmi2GetInteger(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *mut fmi2Integer) -> fmi2Status => get_integer::<$model>(c, vr, nvr, value);
            fmi2GetBoolean(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *mut fmi2Boolean) -> fmi2Status => get_boolean::<$model>(c, vr, nvr, value);
            fmi2GetString(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *mut fmi2String) -> fmi2Status => get_string::<$model>(c, vr, nvr, value);
            fmi2SetReal(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *const fmi2Real) -> fmi2Status => set_real::<$model>(c, vr, nvr, value);
            fmi2SetInteger(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *const fmi2Integer) -> fmi2Status => set_integer::<$model>(c, vr, nvr, value);
            fmi2SetBoolean(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *const fmi2Boolean) -> fmi2Status => set_boolean::<$model>(c, vr, nvr, value);
            fmi2SetString(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *const fmi2String) -> fmi2Status => set_string::<$model>(c, vr, nvr, value);
            fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status => fmu_states::get::<$model, _>(c, Call::GetFMUstate, state, "FMUstate");
            fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status => fmu_states::set::<$model, _>(c, Call::SetFMUstate, state);
            fmi2FreeFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status => fmu_states::free::<$model, _>(c, Call::FreeFMUstate, state, "FMUstate");
            fmi2SerializedFMUstateSize(c: fmi2Component, state: fmi2FMUstate, size: *mut usize) -> fmi2Status => fmu_states::serialized_size::<$model, _>(c, Call::SerializedFMUstateSize, state, size);
            fmi2SerializeFMUstate(c: fmi2Component, state: fmi2FMUstate, serialized: *mut fmi2Byte, size: usize) -> fmi2Status => fmu_states::serialize::<$model, _>(c, Call::SerializeFMUstate, Call::SerializedFMUstateSize, state, serialized as *mut u8, size);
            fmi2DeSerializeFMUstate(c: fmi2Component, serialized: *const fmi2Byte, size: usize, state: *mut fmi2FMUstate) -> fmi2Status => fmu_states::deserialize::<$model, _>(c, Call::DeSerializeFMUstate, serialized as *const u8, size, state, "FMUstate");
            fmi2GetDirectionalDerivative(c: fmi2Component, unknown_refs: *const fmi2ValueReference, n_unknown: usize, known_refs: *const fmi2ValueReference, n_known: usize, dv_known: *const fmi2Real, dv_unknown: *mut fmi2Real) -> fmi2Status => get_directional_derivative::<$model>(c, unknown_refs, n_unknown, known_refs, n_known, dv_known, dv_unknown);
            fmi2EnterEventMode(c: fmi2Component) -> fmi2Status => alike::enter_event_mode::<$model, _>(c, Call::EnterEventMode);
            fmi2NewDiscreteStates(c: fmi2Component, info: *mut fmi2EventInfo) -> fmi2Status => new_discrete_states::<$model>(c, info);
            fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status => alike::enter_continuous_time_mode::<$model, _>(c, Call::EnterContinuousTimeMode);
            fmi2CompletedIntegratorStep(c: fmi2Component, no_set_prior: fmi2Boolean, enter_event_mode: *mut fmi2Boolean, terminate_simulation: *mut fmi2Boolean) -> fmi2Status => alike::completed_integrator_step::<$model, _, _>(c, Call::CompletedIntegratorStep, enter_event_mode, terminate_simulation);
            fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status => alike::set_time::<$model, _>(c, Call::SetTime, time);
            fmi2SetContinuousStates(c: fmi2Component, x: *const fmi2Real, nx: usize) -> fmi2Status => alike::set_continuous_states::<$model, _>(c, Call::SetContinuousStates, x, nx, "x");
            fmi2GetDerivatives(c: fmi2Component, dx: *mut fmi2Real, nx: usize) -> fmi2Status => alike::get_derivatives::<$model, _>(c, Call::GetDerivatives, dx, nx);
            fmi2GetEventIndicators(c: fmi2Component, z: *mut fmi2Real, ni: usize) -> fmi2Status => alike::get_event_indicators::<$model, _>(c, Call::GetEventIndicators, z, ni);
            fmi2GetContinuousStates(c: fmi2Component, x: *mut fmi2Real, nx: usize) -> fmi2Status => alike::get_continuous_states::<$model, _>(c, Call::GetContinuousStates, x, nx, "x");
            fmi2GetNominalsOfContinuousStates(c: fmi2Component, x_nominal: *mut fmi2Real, nx: usize) -> fmi2Status => alike::get_nominals::<$model, _>(c, Call::GetNominalsOfContinuousStates, x_nominal, nx, "x_nominal");
            fmi2SetRealInputDerivatives(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, order: *const fmi2Integer, value: *const fmi2Real) -> fmi2Status => set_real_input_derivatives::<$model>(c, vr, nvr, order, value);
            fmi2GetRealOutputDerivatives(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, order: *const fmi2Integer, value: *mut fmi2Real) -> fmi2Status => get_real_output_derivatives::<$model>(c, vr, nvr, order, value);
            fmi2DoStep(c: fmi2Component, current_communication_point: fmi2Real, communication_step_size: fmi2Real, no_set_fmu_state_prior_to_current_point: fmi2Boolean) -> fmi2Status => do_step::<$model>(c, current_communication_point, communication_step_size, no_set_fmu_state_prior_to_current_point);
            fmi2CancelStep(c: fmi2Component) -> fmi2Status => cancel_step::<$model>(c);
            fmi2GetStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Status) -> fmi2Status => get_status::<$model>(c, kind, value);
            fmi2GetRealStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status => get_real_status::<$model>(c, kind, value);
            fmi2GetIntegerStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Integer) -> fmi2Status => get_integer_status::<$model>(c, kind, value);
            fmi2GetBooleanStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Boolean) -> fmi2Status => get_boolean_status::<$model>(c, kind, value);
            fmi2GetStringStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2String) -> fmi2Status => get_string_status::<$model>(c, kind, value);
        }
    };
}

/// Exports the FMI 2.0 C API of `$model` (a path that resolves from the
/// crate root) under the standard's C names, in the module `fmi2_exports`.
#[macro_export]
macro_rules! export_fmi2 {
    ($model:ty) => { $crate::fmi2_functions!($crate::__export, $model); };
}

/// Calls `$callback!` (as `fmi2_functions!` does) with the one function this layer adds to FMI 2.0
/// for importers that know it (`calls::do_steps`): none needs it, and the FMU stays standard.
#[macro_export]
macro_rules! fmi2_steps_function {
    ($callback:path, $model:ty) => {
        $callback! {
            $model; fmi2 in fmi2_steps_export;
            convertingSpanDoSteps(c: fmi2Component, times: *const fmi2Real, n_steps: usize, vr: *const fmi2ValueReference, nvr: usize, values: *mut fmi2Real, steps_done: *mut usize, rows_done: *mut usize) -> fmi2Status => do_steps::<$model>(c, times, n_steps, vr, nvr, values, steps_done, rows_done);
        }
    };
}

/// Exports `convertingSpanDoSteps` of `$model` beside its FMI 2.0 C API (`export_fmi2!`).
#[macro_export]
macro_rules! export_fmi2_steps {
    ($model:ty) => { $crate::fmi2_steps_function!($crate::__export, $model); };
}
