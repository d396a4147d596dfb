//! The state machines: which call the standard allows in which phase (FMI
//! 2.0, 4.2.4 for co-simulation, 3.2.3 for model exchange), what a refused
//! call does (fmi2Error, one line, the error state) and how fmi2Reset undoes
//! it; the functions an instance of one interface or this layer does not
//! offer; NULL for the instance.

use super::scene::*;
use crate::*;
use crate::Tested;

/// The phases in which FMI 2.0 (section 4.2.4, the co-simulation state
/// table) allows a call, written here independently of the product's table.
fn allowed(api: Api, phase: Phase) -> bool {
    use Phase::*;
    let phases: &[Phase] = match api {
        Api::SetDebugLogging | Api::Reset => &PHASES,
        Api::SetupExperiment | Api::EnterInitializationMode => &[Instantiated],
        Api::ExitInitializationMode => &[Init],
        Api::Terminate => &[Complete, Failed],
        Api::GetReal | Api::GetInteger | Api::GetBoolean | Api::GetString => &[Init, Complete, Failed, Terminated, Error],
        Api::SetReal | Api::SetInteger | Api::SetBoolean | Api::SetString => &[Instantiated, Init, Complete],
        Api::GetFMUstate
        | Api::SetFMUstate
        | Api::FreeFMUstate
        | Api::SerializedFMUstateSize
        | Api::SerializeFMUstate
        | Api::DeSerializeFMUstate => &PHASES,
        Api::GetDirectionalDerivative => &[Init, Complete, Failed, Terminated, Error],
        Api::SetRealInputDerivatives => &[Instantiated, Init, Complete],
        Api::GetRealOutputDerivatives => &[Complete, Failed, Terminated, Error],
        Api::DoStep => &[Complete],
        Api::GetStatus | Api::GetRealStatus | Api::GetIntegerStatus | Api::GetBooleanStatus | Api::GetStringStatus => {
            &[Complete, Failed, Terminated]
        }
        // Model Exchange functions in a co-simulation FMU, and fmi2CancelStep
        // (only in "step in progress", which synchronous steps never reach).
        _ => &[],
    };
    phases.contains(&phase)
}

#[derive(Debug, PartialEq)]
enum Outcome {
    Ok,
    /// fmi2Discard: the status kind is not provided.
    Discard,
    /// fmi2Error: the FMU does not offer the function; the message says why in these words.
    Unsupported(&'static str),
}

/// What an allowed call (with the harmless arguments of `Fmu::call`) gives,
/// from what the description offers.
fn outcome<M: Tested>(api: Api) -> Outcome {
    let d = M::description();
    match api {
        Api::GetStatus | Api::GetIntegerStatus | Api::GetStringStatus => Outcome::Discard,
        Api::GetRealOutputDerivatives | Api::CancelStep => Outcome::Unsupported("not supported"),
        Api::SetRealInputDerivatives if !d.can_interpolate_inputs => Outcome::Unsupported("canInterpolateInputs is false"),
        Api::GetDirectionalDerivative if !d.provides_directional_derivative[0] => Outcome::Unsupported("not supported"),
        _ => Outcome::Ok,
    }
}

/// The phase after an allowed call that succeeded.
fn next_phase(api: Api, phase: Phase) -> Phase {
    match api {
        Api::SetupExperiment | Api::Reset => Phase::Instantiated,
        Api::EnterInitializationMode => Phase::Init,
        Api::ExitInitializationMode | Api::DoStep => Phase::Complete,
        Api::Terminate => Phase::Terminated,
        _ => phase,
    }
}

/// Proves, for every phase and every function that takes an instance:
/// a call the standard forbids returns fmi2Error, logs exactly one
/// logStatusError line naming the function and "illegal call sequence",
/// and leaves the instance in the error state, from which fmi2Reset brings
/// it back to the start values (initialization and steps then give exactly
/// what a fresh instance gives, although the instance had non-start values);
/// an allowed call succeeds (or discards, for the status kinds the FMU does
/// not provide; or says why the model does not offer it) and moves to the
/// phase the standard prescribes.
pub fn state_machine_rejects_illegal_calls_and_recovers_by_reset<M: Tested>() {
    let fresh = init_and_run(&Fmu::<M>::new());
    let mut illegal = 0;
    for phase in PHASES {
        // The Model Exchange functions on a co-simulation instance: see
        // `co_simulation_instance_refuses_model_exchange_functions`.
        for api in callable().filter(|a| a.model_exchange_only() != Some(true)) {
            let fmu = drive::<M>(phase);
            let status = fmu.call(api);
            let lines = fmu.take_logs();
            let what = format!("{} in {phase:?}", api.c_name());
            if allowed(api, phase) {
                match outcome::<M>(api) {
                    Outcome::Ok => {
                        assert_eq!(status, OK, "{what}: {lines:?}");
                        assert!(lines.is_empty(), "{what}: {lines:?}");
                        assert_eq!(phase_of(&fmu), next_phase(api, phase), "{what}");
                    }
                    Outcome::Discard => {
                        assert_eq!(status, DISCARD, "{what}: {lines:?}");
                        assert_eq!(lines.len(), 1, "{what}: {lines:?}");
                        assert_eq!((lines[0].status, lines[0].category.as_str()), (DISCARD, "logStatusDiscard"));
                        assert_eq!(phase_of(&fmu), phase, "{what}");
                    }
                    Outcome::Unsupported(why) => {
                        assert_eq!(status, ERROR, "{what}");
                        assert_one_error(&lines, &[api.c_name(), why]);
                        assert_eq!(phase_of(&fmu), Phase::Error, "{what}");
                    }
                }
                continue;
            }
            illegal += 1;
            assert_eq!(status, ERROR, "{what}: {lines:?}");
            if let (Outcome::Unsupported(why), false) = (outcome::<M>(api), PHASES.iter().any(|&p| allowed(api, p))) {
                // Never allowed (fmi2CancelStep): either reason is a correct
                // explanation (`cancel_step_says_not_supported` asks for the latter).
                assert_one_error(&lines, &[api.c_name()]);
                let m = &lines[0].message;
                assert!(m.contains("illegal call sequence") || m.contains(why), "{what}: {m}");
            } else {
                assert_one_error(&lines, &[api.c_name(), "illegal call sequence"]);
            }
            assert_eq!(phase_of(&fmu), Phase::Error, "{what} must lead to the error state");
            assert_eq!(fmu.reset(), OK, "{what}: fmi2Reset from the error state");
            assert_eq!(phase_of(&fmu), Phase::Instantiated);
            assert_eq!(init_and_run(&fmu), fresh, "{what}: after fmi2Reset the instance must behave like a fresh one");
            assert!(fmu.logs().is_empty(), "{what}: {:?}", fmu.logs());
        }
    }
    // 30 functions in 6 phases; the standard allows 113 of these 180 calls.
    assert_eq!(illegal, 180 - 113);
}

/// Proves that fmi2Reset works from every phase (not only after an error)
/// and restores start values: afterwards the instance equals a fresh one.
pub fn reset_from_every_phase_restores_start_values<M: Tested>() {
    let fresh = init_and_run(&Fmu::<M>::new());
    for phase in PHASES {
        let fmu = drive::<M>(phase);
        assert_eq!(fmu.reset(), OK, "{phase:?}");
        assert_eq!(init_and_run(&fmu), fresh, "{phase:?}");
    }
    // And the configured values really differ from the start values.
    let configured = Fmu::<M>::new();
    configured.set_all(&config::<M>());
    assert_ne!(init_and_run(&configured), fresh, "{:?} changes nothing", config::<M>());
}

/// Proves that an instance created as fmi2CoSimulation refuses the Model
/// Exchange functions in every phase of the co-simulation state machine
/// (FMI 2.0, 4.2.4: they are not part of it) with fmi2Error and one line.
pub fn co_simulation_instance_refuses_model_exchange_functions<M: Tested>() {
    let mut accepted = Vec::new();
    for phase in PHASES {
        for api in callable().filter(|a| a.model_exchange_only() == Some(true)) {
            let fmu = drive::<M>(phase);
            let status = fmu.call(api);
            let lines = fmu.take_logs();
            if status != ERROR {
                accepted.push(format!("{} in {phase:?} -> {status}", api.c_name()));
            } else {
                assert_one_error(&lines, &[api.c_name(), "illegal call sequence"]);
            }
        }
    }
    assert!(accepted.is_empty(), "{accepted:#?}");
}

/// Proves the mirror image: an instance created as fmi2ModelExchange
/// refuses the Co-Simulation-only functions (fmi2DoStep, fmi2CancelStep,
/// fmi2SetRealInputDerivatives, fmi2GetRealOutputDerivatives and the five
/// status functions) in every phase of the model-exchange state machine
/// (FMI 2.0, 3.2.3). A model without Model Exchange refuses the instance.
pub fn model_exchange_instance_refuses_co_simulation_functions<M: Tested>() {
    let me = || instantiate::<M>(&Setup { fmu_type: ME, ..Setup::default() });
    if !M::description().model_exchange {
        assert!(me().is_err(), "no <ModelExchange> in the description, yet fmi2ModelExchange is instantiated");
        return;
    }
    let phases: [(&str, fn(&Fmu<M>)); 6] = [
        ("instantiated", |_| {}),
        ("initialization mode", |f| {
            assert_eq!(f.setup_experiment(0.0), OK);
            assert_eq!(f.enter_init(), OK);
        }),
        ("event mode", |f| f.init(0.0)),
        ("continuous-time mode", |f| {
            f.init(0.0);
            assert_eq!(f.call(Api::EnterContinuousTimeMode), OK);
        }),
        ("terminated", |f| {
            f.init(0.0);
            assert_eq!(f.terminate(), OK);
        }),
        ("error", |f| assert_eq!(f.exit_init(), ERROR)),
    ];
    let co_simulation_only = [
        Api::DoStep,
        Api::CancelStep,
        Api::SetRealInputDerivatives,
        Api::GetRealOutputDerivatives,
        Api::GetStatus,
        Api::GetRealStatus,
        Api::GetIntegerStatus,
        Api::GetBooleanStatus,
        Api::GetStringStatus,
    ];
    let mut accepted = Vec::new();
    for (phase, reach) in phases {
        for api in co_simulation_only {
            let fmu = me().expect("a Model Exchange instance");
            reach(&fmu);
            fmu.take_logs();
            let status = fmu.call(api);
            let lines = fmu.take_logs();
            if status != ERROR {
                accepted.push(format!("{} in {phase} -> {status}", api.c_name()));
            } else {
                assert_one_error(&lines, &[api.c_name()]);
            }
        }
    }
    assert!(accepted.is_empty(), "{accepted:#?}");
}

/// Proves that the co-simulation function this layer does not provide
/// (output derivatives) returns fmi2Error with one line naming the function
/// and saying "not supported" in step complete.
pub fn unsupported_co_simulation_functions_say_not_supported<M: Tested>() {
    for api in [Api::GetRealOutputDerivatives] {
        let fmu = drive::<M>(Phase::Complete);
        assert_eq!(fmu.call(api), ERROR, "{}", api.c_name());
        assert_one_error(&fmu.take_logs(), &[api.c_name(), "not supported"]);
    }
}

/// Proves that fmi2CancelStep, which this layer does not offer (steps are
/// synchronous, so no step is ever in progress), returns fmi2Error with one
/// line saying "not supported" where a step could be (step complete, step
/// failed); elsewhere it is an illegal call sequence (see the state-machine
/// test).
pub fn cancel_step_says_not_supported<M: Tested>() {
    for phase in [Phase::Complete, Phase::Failed] {
        let fmu = drive::<M>(phase);
        assert_eq!(fmu.call(Api::CancelStep), ERROR);
        assert_one_error(&fmu.take_logs(), &["fmi2CancelStep", "not supported"]);
        assert_eq!(phase_of(&fmu), Phase::Error);
    }
}

/// Proves that every function taking an fmi2Component returns fmi2Error
/// for NULL without crashing, and that fmi2FreeInstance(NULL) is a no-op.
pub fn null_component_is_refused_everywhere<M: Tested>() {
    for api in callable() {
        assert_eq!(call_with_null_component::<M>(api), ERROR, "{}", api.c_name());
    }
    free_null_instance();
    // A real instance still works afterwards.
    drive::<M>(Phase::Complete);
}
