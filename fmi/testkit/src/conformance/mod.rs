//! The conformance suite of the FMI layer: every test of what the standard
//! and this layer promise an importer, written once, generic over the model
//! and driven by its description (names, value references, causality,
//! ranges and start values come from `M::description()` of `crate::Tested`,
//! never from a model's own names). Each model runs it through the C API of
//! its own library with one line in its tests:
//!
//! ```text
//! fmi_testkit::conformance_tests!(roller::Roller);
//! fmi_testkit::conformance_tests!(converting_span::ConvertingSpan, hints = span_hints);
//! fmi_testkit::panic_boundary_tests!(roller::Roller); // a test target with the model's feature `test-hooks`
//! fmi_testkit::conformance_tests!(TestedLine); // a stand-in: the Line's interface comes with its resources
//! ```
//!
//! * `scene` — what the tests drive a model with, derived from its description;
//! * `state_machine`, `instantiate`, `values`, `stepping`, `logging`,
//!   `fmu_states`, `dependencies`, `threads`, `statics`, `panic_boundary` — the tests.
//!
//! Only the ModelStructure tests need more than the description can say:
//! operating points where every listed dependency shows (`Hints`).

pub mod dependencies;
pub mod fmu_states;
pub mod instantiate;
pub mod logging;
pub mod panic_boundary;
pub mod scene;
pub mod state_machine;
pub mod statics;
pub mod stepping;
pub mod threads;
pub mod values;

/// Settings of an operating point, by variable name.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Point {
    /// Reals, Integers, enumerations and Booleans (as numbers).
    pub values: Vec<(&'static str, f64)>,
    pub texts: Vec<(&'static str, String)>,
}

/// What a model's tests add to what the suite derives from the description,
/// for the ModelStructure tests, which require every listed dependency to
/// show at some operating point.
#[derive(Clone, Debug, Default)]
pub struct Hints {
    /// Operating points that bring into play what the start values leave
    /// idle (a damping coefficient, a drive from a profile); each must
    /// initialize.
    pub points: Vec<Point>,
    /// Another valid text per String parameter, to perturb it by.
    pub texts: Vec<(&'static str, String)>,
    /// Words of the only refusals a perturbed operating point may meet
    /// (a value that contradicts another); any other refusal fails.
    pub refusals: Vec<&'static str>,
}

/// Expands into the conformance suite for one model: `#[test]` functions in
/// modules named as the suite's (`values::set_is_atomic`, ...).
/// `conformance_tests!(crate_name::Model)` or, with operating points for
/// the ModelStructure tests, `conformance_tests!(crate_name::Model, hints = f)`
/// where `f: fn() -> Hints`.
#[macro_export]
macro_rules! conformance_tests {
    ($model:ty) => {
        $crate::conformance_tests!($model, hints = $crate::conformance::Hints::default);
    };
    ($model:ty, hints = $hints:expr) => {
        $crate::__conformance_module!($model; state_machine:
            state_machine_rejects_illegal_calls_and_recovers_by_reset,
            reset_from_every_phase_restores_start_values,
            co_simulation_instance_refuses_model_exchange_functions,
            model_exchange_instance_refuses_co_simulation_functions,
            unsupported_co_simulation_functions_say_not_supported,
            cancel_step_says_not_supported,
            null_component_is_refused_everywhere,
        );
        $crate::__conformance_module!($model; instantiate:
            instantiate_refuses_wrong_guid_and_fmu_type,
            instantiate_tolerates_odd_names_and_null_resources,
            types_platform_and_version,
        );
        $crate::__conformance_module!($model; values:
            start_values_are_allowed_and_read_back,
            parameter_out_of_range_is_refused_at_exit_initialization,
            integer_parameter_out_of_range_is_refused_at_exit_initialization,
            non_finite_reals_are_refused_immediately,
            input_out_of_range_is_refused_immediately,
            tunable_parameter_out_of_range_after_initialization_is_refused,
            enumeration_outside_its_items_is_refused,
            boolean_other_than_0_or_1_is_refused,
            unknown_value_references_are_refused,
            wrong_type_is_refused,
            fixed_parameters_after_init_and_outputs_cannot_be_set,
            model_exchange_sets_follow_event_and_continuous_time_mode,
            set_is_atomic,
        );
        $crate::__conformance_module!($model; stepping:
            do_step_refuses_bad_step_size_and_time,
            a_discarded_step_changes_nothing,
            communication_point_tolerance,
            status_functions,
            set_real_input_derivatives_validates_its_arguments,
        );
        $crate::__conformance_module!($model; logging:
            set_debug_logging_refuses_unknown_categories,
            log_status_error_can_be_switched_off,
            event_logging_follows_logging_on_and_set_debug_logging,
            no_categories_switches_all,
            percent_in_messages_is_escaped_for_printf_loggers,
        );
        $crate::__conformance_module!($model; fmu_states:
            fmu_state_round_trip_continues_bit_identically,
            serialized_state_continues_bit_identically_in_any_instance,
            fmu_state_saved_in_initialization_mode_keeps_the_experiment,
            state_saved_after_a_parameter_changed_in_initialization_mode_restores,
            state_of_the_other_interface_is_refused,
            serialize_checks_the_buffer_size,
            deserialize_refuses_truncated_padded_and_corrupted_bytes,
            deserialize_refuses_wrong_magic_version_model_and_payload,
            deserialize_refuses_values_outside_the_declared_ranges,
            stale_and_foreign_state_pointers_are_refused,
            set_fmu_state_recovers_from_the_error_state,
        );
        $crate::__conformance_module!($model; dependencies:
            output_dependencies_are_exact(&($hints)()),
            initial_dependencies_are_exact(&($hints)()),
            directional_derivatives_through_the_c_api,
        );
        $crate::__conformance_module!($model; threads:
            eight_instances_on_eight_threads_match_the_same_runs_one_after_another,
            start_values_do_not_depend_on_other_instances,
        );
        $crate::__conformance_module!($model; statics:
            the_compiled_library_has_no_writable_statics,
            the_source_declares_no_mutable_statics,
        );
    };
}

/// Expands into the panic-boundary tests for one model; the test target
/// needs the model crate's feature `test-hooks` (`required-features`).
#[macro_export]
macro_rules! panic_boundary_tests {
    ($model:ty) => {
        $crate::__conformance_module!($model; panic_boundary:
            a_panic_inside_the_step_becomes_fmi2error_with_a_log_line($crate::fmi_core::instance::TEST_PANIC_CATEGORY),
            a_poisoned_instance_refuses_everything_but_reset_and_free($crate::fmi_core::instance::TEST_PANIC_CATEGORY),
            a_poisoned_instance_can_be_freed_and_others_are_untouched($crate::fmi_core::instance::TEST_PANIC_CATEGORY),
            without_arming_the_hook_does_nothing($crate::fmi_core::instance::TEST_PANIC_CATEGORY),
        );
    };
}

/// `#[test]` functions calling the suite's functions of `module` for the
/// model, each with the arguments given after its name.
#[doc(hidden)]
#[macro_export]
macro_rules! __conformance_module {
    ($model:ty; $module:ident: $($test:ident $(($($arg:expr),*))?),* $(,)?) => {
        mod $module {
            #[allow(unused_imports)]
            use super::*;
            $(
                #[test]
                fn $test() {
                    let name = concat!(stringify!($module), "::", stringify!($test));
                    if let Some(reason) = <$model as $crate::Tested>::skipped(name) {
                        eprintln!("skipped {name}: {reason}");
                        return;
                    }
                    $crate::conformance::$module::$test::<$model>($($($arg),*)?)
                }
            )*
        }
    };
}

#[cfg(test)]
mod tests {
    /// Every test function of the suite's modules is expanded by a macro
    /// (a function missing from the lists would silently never run).
    #[test]
    fn the_macros_list_every_test_of_the_suite() {
        let macros = include_str!("mod.rs");
        let modules = [
            ("state_machine", include_str!("state_machine.rs")),
            ("instantiate", include_str!("instantiate.rs")),
            ("values", include_str!("values.rs")),
            ("stepping", include_str!("stepping.rs")),
            ("logging", include_str!("logging.rs")),
            ("fmu_states", include_str!("fmu_states.rs")),
            ("dependencies", include_str!("dependencies.rs")),
            ("threads", include_str!("threads.rs")),
            ("statics", include_str!("statics.rs")),
            ("panic_boundary", include_str!("panic_boundary.rs")),
        ];
        let mut tests = 0;
        for (module, source) in modules {
            let listed = macros.split(&format!("; {module}:")).nth(1).unwrap_or_else(|| panic!("no list for {module}"));
            let listed = &listed[..listed.find(");").unwrap()];
            for line in source.lines().filter_map(|l| l.strip_prefix("pub fn ")) {
                let name = &line[..line.find('<').unwrap()];
                let mut words = listed.split(|c: char| !c.is_alphanumeric() && c != '_');
                assert!(words.any(|w| w == name), "{module}::{name} is not in the macro's list");
                tests += 1;
            }
        }
        assert!(tests > 40, "only {tests} test functions found");
    }
}
