//! [`export_fmi2!`](crate::export_fmi2): the 44 functions of the FMI 2.0 C
//! API for one model, each a one-line shell around its generic body in
//! `calls` (or `instantiate`/`free_instance`). One invocation per FMU crate:
//! `fmi2::export_fmi2!(crate::MyModel);`. The signature list below is the
//! only place the C declarations are written.

/// Exports the FMI 2.0 C API of `$model` (a path that resolves from the
/// crate root) under the standard's C names.
#[macro_export]
macro_rules! export_fmi2 {
    ($model:ty) => {
        $crate::__export_fmi2! {
            $model;
            fmi2SetDebugLogging(c: fmi2Component, logging_on: fmi2Boolean, n_categories: usize, categories: *const fmi2String) -> fmi2Status = set_debug_logging;
            fmi2Instantiate(instance_name: fmi2String, fmu_type: fmi2Type, guid: fmi2String, resource_location: fmi2String, functions: *const fmi2CallbackFunctions, visible: fmi2Boolean, logging_on: fmi2Boolean) -> fmi2Component = instantiate;
            fmi2FreeInstance(c: fmi2Component) = free_instance;
            fmi2SetupExperiment(c: fmi2Component, tolerance_defined: fmi2Boolean, tolerance: fmi2Real, start_time: fmi2Real, stop_time_defined: fmi2Boolean, stop_time: fmi2Real) -> fmi2Status = setup_experiment;
            fmi2EnterInitializationMode(c: fmi2Component) -> fmi2Status = enter_initialization_mode;
            fmi2ExitInitializationMode(c: fmi2Component) -> fmi2Status = exit_initialization_mode;
            fmi2Terminate(c: fmi2Component) -> fmi2Status = terminate;
            fmi2Reset(c: fmi2Component) -> fmi2Status = reset;
            fmi2GetReal(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *mut fmi2Real) -> fmi2Status = get_real;
            fmi2GetInteger(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *mut fmi2Integer) -> fmi2Status = get_integer;
            fmi2GetBoolean(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *mut fmi2Boolean) -> fmi2Status = get_boolean;
            fmi2GetString(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *mut fmi2String) -> fmi2Status = get_string;
            fmi2SetReal(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *const fmi2Real) -> fmi2Status = set_real;
            fmi2SetInteger(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *const fmi2Integer) -> fmi2Status = set_integer;
            fmi2SetBoolean(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *const fmi2Boolean) -> fmi2Status = set_boolean;
            fmi2SetString(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, value: *const fmi2String) -> fmi2Status = set_string;
            fmi2GetFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status = get_fmu_state;
            fmi2SetFMUstate(c: fmi2Component, state: fmi2FMUstate) -> fmi2Status = set_fmu_state;
            fmi2FreeFMUstate(c: fmi2Component, state: *mut fmi2FMUstate) -> fmi2Status = free_fmu_state;
            fmi2SerializedFMUstateSize(c: fmi2Component, state: fmi2FMUstate, size: *mut usize) -> fmi2Status = serialized_fmu_state_size;
            fmi2SerializeFMUstate(c: fmi2Component, state: fmi2FMUstate, serialized: *mut fmi2Byte, size: usize) -> fmi2Status = serialize_fmu_state;
            fmi2DeSerializeFMUstate(c: fmi2Component, serialized: *const fmi2Byte, size: usize, state: *mut fmi2FMUstate) -> fmi2Status = de_serialize_fmu_state;
            fmi2GetDirectionalDerivative(c: fmi2Component, unknown_refs: *const fmi2ValueReference, n_unknown: usize, known_refs: *const fmi2ValueReference, n_known: usize, dv_known: *const fmi2Real, dv_unknown: *mut fmi2Real) -> fmi2Status = get_directional_derivative;
            fmi2EnterEventMode(c: fmi2Component) -> fmi2Status = enter_event_mode;
            fmi2NewDiscreteStates(c: fmi2Component, info: *mut fmi2EventInfo) -> fmi2Status = new_discrete_states;
            fmi2EnterContinuousTimeMode(c: fmi2Component) -> fmi2Status = enter_continuous_time_mode;
            fmi2CompletedIntegratorStep(c: fmi2Component, no_set_prior: fmi2Boolean, enter_event_mode: *mut fmi2Boolean, terminate_simulation: *mut fmi2Boolean) -> fmi2Status = completed_integrator_step;
            fmi2SetTime(c: fmi2Component, time: fmi2Real) -> fmi2Status = set_time;
            fmi2SetContinuousStates(c: fmi2Component, x: *const fmi2Real, nx: usize) -> fmi2Status = set_continuous_states;
            fmi2GetDerivatives(c: fmi2Component, dx: *mut fmi2Real, nx: usize) -> fmi2Status = get_derivatives;
            fmi2GetEventIndicators(c: fmi2Component, z: *mut fmi2Real, ni: usize) -> fmi2Status = get_event_indicators;
            fmi2GetContinuousStates(c: fmi2Component, x: *mut fmi2Real, nx: usize) -> fmi2Status = get_continuous_states;
            fmi2GetNominalsOfContinuousStates(c: fmi2Component, x_nominal: *mut fmi2Real, nx: usize) -> fmi2Status = get_nominals_of_continuous_states;
            fmi2SetRealInputDerivatives(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, order: *const fmi2Integer, value: *const fmi2Real) -> fmi2Status = set_real_input_derivatives;
            fmi2GetRealOutputDerivatives(c: fmi2Component, vr: *const fmi2ValueReference, nvr: usize, order: *const fmi2Integer, value: *mut fmi2Real) -> fmi2Status = get_real_output_derivatives;
            fmi2DoStep(c: fmi2Component, current_communication_point: fmi2Real, communication_step_size: fmi2Real, no_set_fmu_state_prior_to_current_point: fmi2Boolean) -> fmi2Status = do_step;
            fmi2CancelStep(c: fmi2Component) -> fmi2Status = cancel_step;
            fmi2GetStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Status) -> fmi2Status = get_status;
            fmi2GetRealStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Real) -> fmi2Status = get_real_status;
            fmi2GetIntegerStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Integer) -> fmi2Status = get_integer_status;
            fmi2GetBooleanStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2Boolean) -> fmi2Status = get_boolean_status;
            fmi2GetStringStatus(c: fmi2Component, kind: fmi2StatusKind, value: *mut fmi2String) -> fmi2Status = get_string_status;
        }
    };
}

#[doc(hidden)]
#[macro_export]
macro_rules! __export_fmi2 {
    ($model:ty; $($name:ident($($arg:ident: $ty:ty),*) $(-> $ret:ty)? = $call:ident;)*) => {
        /// The FMI 2.0 C API of this library's model, written by `fmi2::export_fmi2!`.
        #[allow(non_snake_case, clippy::missing_safety_doc)]
        pub mod fmi2_exports {
            use $crate::ffi::*;

            #[no_mangle]
            pub extern "C" fn fmi2GetTypesPlatform() -> *const ::std::ffi::c_char {
                get_types_platform()
            }

            #[no_mangle]
            pub extern "C" fn fmi2GetVersion() -> *const ::std::ffi::c_char {
                get_version()
            }

            $(
                #[no_mangle]
                pub unsafe extern "C" fn $name($($arg: $ty),*) $(-> $ret)? {
                    $call::<$model>($($arg),*)
                }
            )*
        }
    };
}
