//! The one list of FMI 3.0's C signatures, each with its body in `calls` or,
//! where FMI 2.0 has it too, in `alike` and `fmu_states`:
//! every function of the FMI 3.0 headers, those this FMU does not offer
//! refusing with the reason. [`fmi3_functions!`](crate::fmi3_functions) hands
//! the list to a macro: [`export_fmi3!`](crate::export_fmi3) defines the
//! exports from it (`fmi_abi::export_fmi3!(crate::MyModel);`), and the test
//! kit declares the same functions from it to call them.

/// Calls `$callback! { $model; fmi3 in MODULE; NAME(ARG: TYPE, ...) [-> RETURN] => BODY; ... }`
/// with every function of the FMI 3.0 C API, typed with `fmi_abi::fmi3`'s names.
#[macro_export]
macro_rules! fmi3_functions {
    ($callback:path, $model:ty) => {
        $callback! {
            $model; fmi3 in fmi3_exports;
            fmi3GetVersion() -> *const ::std::ffi::c_char => get_version::<$model>();
            fmi3SetDebugLogging(c: fmi3Instance, logging_on: fmi3Boolean, n_categories: usize, categories: *const fmi3String) -> fmi3Status => alike::set_debug_logging::<$model, _>(c, Call::SetDebugLogging, logging_on != 0, n_categories, categories);
            fmi3InstantiateModelExchange(instance_name: fmi3String, token: fmi3String, resource_path: fmi3String, visible: fmi3Boolean, logging_on: fmi3Boolean, environment: fmi3InstanceEnvironment, log_message: Option<fmi3LogMessageCallback>) -> fmi3Instance => instantiate_model_exchange::<$model>(instance_name, token, resource_path, visible, logging_on, environment, log_message);
            fmi3InstantiateCoSimulation(instance_name: fmi3String, token: fmi3String, resource_path: fmi3String, visible: fmi3Boolean, logging_on: fmi3Boolean, event_mode_used: fmi3Boolean, early_return_allowed: fmi3Boolean, required: *const fmi3ValueReference, n_required: usize, environment: fmi3InstanceEnvironment, log_message: Option<fmi3LogMessageCallback>, intermediate_update: Option<fmi3IntermediateUpdateCallback>) -> fmi3Instance => instantiate_co_simulation::<$model>(instance_name, token, resource_path, visible, logging_on, event_mode_used, early_return_allowed, required, n_required, environment, log_message, intermediate_update);
            fmi3InstantiateScheduledExecution(instance_name: fmi3String, token: fmi3String, resource_path: fmi3String, visible: fmi3Boolean, logging_on: fmi3Boolean, environment: fmi3InstanceEnvironment, log_message: Option<fmi3LogMessageCallback>, clock_update: Option<fmi3ClockUpdateCallback>, lock: Option<fmi3LockPreemptionCallback>, unlock: Option<fmi3UnlockPreemptionCallback>) -> fmi3Instance => instantiate_scheduled_execution::<$model>(instance_name, token, resource_path, visible, logging_on, environment, log_message, clock_update, lock, unlock);
            fmi3FreeInstance(c: fmi3Instance) => handle::free::<$model>(c, Standard::Fmi3);
            fmi3EnterInitializationMode(c: fmi3Instance, tolerance_defined: fmi3Boolean, tolerance: fmi3Float64, start_time: fmi3Float64, stop_time_defined: fmi3Boolean, stop_time: fmi3Float64) -> fmi3Status => enter_initialization_mode::<$model>(c, tolerance_defined, tolerance, start_time, stop_time_defined, stop_time);
            fmi3ExitInitializationMode(c: fmi3Instance) -> fmi3Status => alike::exit_initialization_mode::<$model, _>(c, Call::ExitInitializationMode);
            fmi3EnterEventMode(c: fmi3Instance) -> fmi3Status => alike::enter_event_mode::<$model, _>(c, Call::EnterEventMode);
            fmi3Terminate(c: fmi3Instance) -> fmi3Status => alike::terminate::<$model, _>(c, Call::Terminate);
            fmi3Reset(c: fmi3Instance) -> fmi3Status => alike::reset::<$model, _>(c, Call::Reset);
            fmi3EnterContinuousTimeMode(c: fmi3Instance) -> fmi3Status => alike::enter_continuous_time_mode::<$model, _>(c, Call::EnterContinuousTimeMode);
            fmi3GetFloat64(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3Float64, n_values: usize) -> fmi3Status => get_float64::<$model>(c, vr, nvr, values, n_values);
            fmi3SetFloat64(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3Float64, n_values: usize) -> fmi3Status => set_float64::<$model>(c, vr, nvr, values, n_values);
            fmi3GetInt32(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3Int32, n_values: usize) -> fmi3Status => get_int32::<$model>(c, vr, nvr, values, n_values);
            fmi3SetInt32(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3Int32, n_values: usize) -> fmi3Status => set_int32::<$model>(c, vr, nvr, values, n_values);
            fmi3GetInt64(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3Int64, n_values: usize) -> fmi3Status => get_int64::<$model>(c, vr, nvr, values, n_values);
            fmi3SetInt64(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3Int64, n_values: usize) -> fmi3Status => set_int64::<$model>(c, vr, nvr, values, n_values);
            fmi3GetBoolean(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3Boolean, n_values: usize) -> fmi3Status => get_boolean::<$model>(c, vr, nvr, values, n_values);
            fmi3SetBoolean(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3Boolean, n_values: usize) -> fmi3Status => set_boolean::<$model>(c, vr, nvr, values, n_values);
            fmi3GetString(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3String, n_values: usize) -> fmi3Status => get_string::<$model>(c, vr, nvr, values, n_values);
            fmi3SetString(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3String, n_values: usize) -> fmi3Status => set_string::<$model>(c, vr, nvr, values, n_values);
            fmi3GetFloat32(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3Float32, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::GetFloat32, nvr, "Float32");
            fmi3SetFloat32(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3Float32, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::SetFloat32, nvr, "Float32");
            fmi3GetInt8(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3Int8, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::GetInt8, nvr, "Int8");
            fmi3SetInt8(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3Int8, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::SetInt8, nvr, "Int8");
            fmi3GetUInt8(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3UInt8, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::GetUInt8, nvr, "UInt8");
            fmi3SetUInt8(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3UInt8, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::SetUInt8, nvr, "UInt8");
            fmi3GetInt16(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3Int16, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::GetInt16, nvr, "Int16");
            fmi3SetInt16(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3Int16, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::SetInt16, nvr, "Int16");
            fmi3GetUInt16(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3UInt16, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::GetUInt16, nvr, "UInt16");
            fmi3SetUInt16(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3UInt16, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::SetUInt16, nvr, "UInt16");
            fmi3GetUInt32(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3UInt32, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::GetUInt32, nvr, "UInt32");
            fmi3SetUInt32(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3UInt32, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::SetUInt32, nvr, "UInt32");
            fmi3GetUInt64(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3UInt64, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::GetUInt64, nvr, "UInt64");
            fmi3SetUInt64(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3UInt64, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::SetUInt64, nvr, "UInt64");
            fmi3GetBinary(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, sizes: *mut usize, values: *mut fmi3Binary, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::GetBinary, nvr, "Binary");
            fmi3SetBinary(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, sizes: *const usize, values: *const fmi3Binary, n_values: usize) -> fmi3Status => no_such_type::<$model>(c, Call::SetBinary, nvr, "Binary");
            fmi3GetClock(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *mut fmi3Clock) -> fmi3Status => refuse::<$model>(c, Call::GetClock, reasons::CLOCKS);
            fmi3SetClock(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, values: *const fmi3Clock) -> fmi3Status => refuse::<$model>(c, Call::SetClock, reasons::CLOCKS);
            fmi3GetNumberOfVariableDependencies(c: fmi3Instance, vr: fmi3ValueReference, n: *mut usize) -> fmi3Status => refuse::<$model>(c, Call::GetNumberOfVariableDependencies, reasons::DEPENDENCIES);
            fmi3GetVariableDependencies(c: fmi3Instance, dependent: fmi3ValueReference, element_indices_of_dependent: *mut usize, independents: *mut fmi3ValueReference, element_indices_of_independents: *mut usize, kinds: *mut fmi3DependencyKind, n: usize) -> fmi3Status => refuse::<$model>(c, Call::GetVariableDependencies, reasons::DEPENDENCIES);
            fmi3GetFMUState(c: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status => fmu_states::get::<$model, _>(c, Call::GetFMUState, state, "FMUState");
            fmi3SetFMUState(c: fmi3Instance, state: fmi3FMUState) -> fmi3Status => fmu_states::set::<$model, _>(c, Call::SetFMUState, state);
            fmi3FreeFMUState(c: fmi3Instance, state: *mut fmi3FMUState) -> fmi3Status => fmu_states::free::<$model, _>(c, Call::FreeFMUState, state, "FMUState");
            fmi3SerializedFMUStateSize(c: fmi3Instance, state: fmi3FMUState, size: *mut usize) -> fmi3Status => fmu_states::serialized_size::<$model, _>(c, Call::SerializedFMUStateSize, state, size);
            fmi3SerializeFMUState(c: fmi3Instance, state: fmi3FMUState, serialized: *mut fmi3Byte, size: usize) -> fmi3Status => fmu_states::serialize::<$model, _>(c, Call::SerializeFMUState, Call::SerializedFMUStateSize, state, serialized, size);
            fmi3DeserializeFMUState(c: fmi3Instance, serialized: *const fmi3Byte, size: usize, state: *mut fmi3FMUState) -> fmi3Status => fmu_states::deserialize::<$model, _>(c, Call::DeserializeFMUState, serialized, size, state, "FMUState");
            fmi3GetDirectionalDerivative(c: fmi3Instance, unknowns: *const fmi3ValueReference, n_unknowns: usize, knowns: *const fmi3ValueReference, n_knowns: usize, seed: *const fmi3Float64, n_seed: usize, sensitivity: *mut fmi3Float64, n_sensitivity: usize) -> fmi3Status => get_directional_derivative::<$model>(c, unknowns, n_unknowns, knowns, n_knowns, seed, n_seed, sensitivity, n_sensitivity);
            fmi3GetAdjointDerivative(c: fmi3Instance, unknowns: *const fmi3ValueReference, n_unknowns: usize, knowns: *const fmi3ValueReference, n_knowns: usize, seed: *const fmi3Float64, n_seed: usize, sensitivity: *mut fmi3Float64, n_sensitivity: usize) -> fmi3Status => refuse::<$model>(c, Call::GetAdjointDerivative, reasons::ADJOINT);
            fmi3EnterConfigurationMode(c: fmi3Instance) -> fmi3Status => refuse::<$model>(c, Call::EnterConfigurationMode, reasons::CONFIGURATION);
            fmi3ExitConfigurationMode(c: fmi3Instance) -> fmi3Status => refuse::<$model>(c, Call::ExitConfigurationMode, reasons::CONFIGURATION);
            fmi3GetIntervalDecimal(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, intervals: *mut fmi3Float64, qualifiers: *mut fmi3IntervalQualifier) -> fmi3Status => refuse::<$model>(c, Call::GetIntervalDecimal, reasons::CLOCKS);
            fmi3GetIntervalFraction(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64, qualifiers: *mut fmi3IntervalQualifier) -> fmi3Status => refuse::<$model>(c, Call::GetIntervalFraction, reasons::CLOCKS);
            fmi3GetShiftDecimal(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, shifts: *mut fmi3Float64) -> fmi3Status => refuse::<$model>(c, Call::GetShiftDecimal, reasons::CLOCKS);
            fmi3GetShiftFraction(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, counters: *mut fmi3UInt64, resolutions: *mut fmi3UInt64) -> fmi3Status => refuse::<$model>(c, Call::GetShiftFraction, reasons::CLOCKS);
            fmi3SetIntervalDecimal(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, intervals: *const fmi3Float64) -> fmi3Status => refuse::<$model>(c, Call::SetIntervalDecimal, reasons::CLOCKS);
            fmi3SetIntervalFraction(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64) -> fmi3Status => refuse::<$model>(c, Call::SetIntervalFraction, reasons::CLOCKS);
            fmi3SetShiftDecimal(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, shifts: *const fmi3Float64) -> fmi3Status => refuse::<$model>(c, Call::SetShiftDecimal, reasons::CLOCKS);
            fmi3SetShiftFraction(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, counters: *const fmi3UInt64, resolutions: *const fmi3UInt64) -> fmi3Status => refuse::<$model>(c, Call::SetShiftFraction, reasons::CLOCKS);
            fmi3EvaluateDiscreteStates(c: fmi3Instance) -> fmi3Status => refuse::<$model>(c, Call::EvaluateDiscreteStates, reasons::CLOCKS);
            fmi3UpdateDiscreteStates(c: fmi3Instance, discrete_states_need_update: *mut fmi3Boolean, terminate_simulation: *mut fmi3Boolean, nominals_changed: *mut fmi3Boolean, values_changed: *mut fmi3Boolean, next_event_time_defined: *mut fmi3Boolean, next_event_time: *mut fmi3Float64) -> fmi3Status => update_discrete_states::<$model>(c, discrete_states_need_update, terminate_simulation, nominals_changed, values_changed, next_event_time_defined, next_event_time);
            fmi3CompletedIntegratorStep(c: fmi3Instance, no_set_prior: fmi3Boolean, enter_event_mode: *mut fmi3Boolean, terminate_simulation: *mut fmi3Boolean) -> fmi3Status => alike::completed_integrator_step::<$model, _, _>(c, Call::CompletedIntegratorStep, enter_event_mode, terminate_simulation);
            fmi3SetTime(c: fmi3Instance, time: fmi3Float64) -> fmi3Status => alike::set_time::<$model, _>(c, Call::SetTime, time);
            fmi3SetContinuousStates(c: fmi3Instance, x: *const fmi3Float64, nx: usize) -> fmi3Status => alike::set_continuous_states::<$model, _>(c, Call::SetContinuousStates, x, nx, "continuousStates");
            fmi3GetContinuousStateDerivatives(c: fmi3Instance, dx: *mut fmi3Float64, nx: usize) -> fmi3Status => alike::get_derivatives::<$model, _>(c, Call::GetContinuousStateDerivatives, dx, nx);
            fmi3GetEventIndicators(c: fmi3Instance, z: *mut fmi3Float64, nz: usize) -> fmi3Status => alike::get_event_indicators::<$model, _>(c, Call::GetEventIndicators, z, nz);
            fmi3GetContinuousStates(c: fmi3Instance, x: *mut fmi3Float64, nx: usize) -> fmi3Status => alike::get_continuous_states::<$model, _>(c, Call::GetContinuousStates, x, nx, "continuousStates");
            fmi3GetNominalsOfContinuousStates(c: fmi3Instance, nominals: *mut fmi3Float64, nx: usize) -> fmi3Status => alike::get_nominals::<$model, _>(c, Call::GetNominalsOfContinuousStates, nominals, nx, "nominals");
            fmi3GetNumberOfEventIndicators(c: fmi3Instance, n: *mut usize) -> fmi3Status => get_number_of_event_indicators::<$model>(c, n);
            fmi3GetNumberOfContinuousStates(c: fmi3Instance, n: *mut usize) -> fmi3Status => get_number_of_continuous_states::<$model>(c, n);
            fmi3EnterStepMode(c: fmi3Instance) -> fmi3Status => refuse::<$model>(c, Call::EnterStepMode, reasons::STEP_MODE);
            fmi3GetOutputDerivatives(c: fmi3Instance, vr: *const fmi3ValueReference, nvr: usize, orders: *const fmi3Int32, values: *mut fmi3Float64, n_values: usize) -> fmi3Status => refuse::<$model>(c, Call::GetOutputDerivatives, reasons::OUTPUT_DERIVATIVES);
            fmi3DoStep(c: fmi3Instance, current_communication_point: fmi3Float64, communication_step_size: fmi3Float64, no_set_fmu_state_prior_to_current_point: fmi3Boolean, event_handling_needed: *mut fmi3Boolean, terminate_simulation: *mut fmi3Boolean, early_return: *mut fmi3Boolean, last_successful_time: *mut fmi3Float64) -> fmi3Status => do_step::<$model>(c, current_communication_point, communication_step_size, no_set_fmu_state_prior_to_current_point, event_handling_needed, terminate_simulation, early_return, last_successful_time);
            fmi3ActivateModelPartition(c: fmi3Instance, clock_reference: fmi3ValueReference, activation_time: fmi3Float64) -> fmi3Status => refuse::<$model>(c, Call::ActivateModelPartition, reasons::SCHEDULED);
        }
    };
}

/// Exports the FMI 3.0 C API of `$model` (a path that resolves from the
/// crate root) under the standard's C names, in the module `fmi3_exports`.
#[macro_export]
macro_rules! export_fmi3 {
    ($model:ty) => { $crate::fmi3_functions!($crate::__export, $model); };
}
