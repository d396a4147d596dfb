//! What the conformance tests drive a model with, derived from its
//! description alone: values off the start values, the inputs of a run, the
//! phases of the co-simulation state machine and how to reach each of them.

use crate::{Fmu, LogLine, DISCARD, ERROR, OK};
use fmi_core::description::{Causality, Initial, Kind, Start, Variable};
use crate::Tested;

pub fn of_causality<M: Tested>(c: Causality) -> Vec<&'static Variable> {
    M::description().variables.iter().filter(|v| v.causality == c).collect()
}

pub fn real_inputs<M: Tested>() -> Vec<&'static Variable> {
    of_causality::<M>(Causality::Input).into_iter().filter(|v| v.kind == Kind::Real).collect()
}

/// Parameters an importer may set before initialization (initial exact or approx).
pub fn settable_parameters<M: Tested>() -> Vec<&'static Variable> {
    of_causality::<M>(Causality::Parameter).into_iter().filter(|v| matches!(v.initial, Initial::Exact | Initial::Approx)).collect()
}

/// The first Real input; every model of this project has one (a step needs something to act on).
pub fn first_real_input<M: Tested>() -> &'static Variable {
    real_inputs::<M>().into_iter().next().expect("a Real input")
}

pub fn first_real_output<M: Tested>() -> &'static Variable {
    of_causality::<M>(Causality::Output).into_iter().find(|v| v.kind == Kind::Real).expect("a Real output")
}

/// A value reference no variable has.
pub fn unused_vr<M: Tested>() -> u32 {
    M::description().variables.iter().map(|v| v.vr).max().unwrap_or(0) + 1
}

/// The start value as `Fmu::set` takes it (Booleans and enumerations as numbers).
pub fn start_of(v: &Variable) -> f64 {
    match v.start {
        Start::Real(x) => x,
        Start::Integer(x) => x as f64,
        Start::Boolean(x) => x as u8 as f64,
        Start::String(_) | Start::None => panic!("{} has no numeric start value", v.name),
    }
}

/// Another allowed value of `v` than `x`, near it: a Real moved by a quarter
/// (or to 0.01 from 0), an Integer by one, the next enumeration item, the other Boolean.
pub fn other_value(v: &Variable, x: f64) -> f64 {
    let candidates: Vec<f64> = match v.kind {
        Kind::Real if x == 0.0 => vec![0.01, -0.01, v.range.lo, v.range.hi],
        Kind::Real => vec![x * 1.25, x * 0.8, v.range.lo, v.range.hi],
        Kind::Integer => vec![x + 1.0, x - 1.0],
        Kind::Enumeration { values, .. } => {
            let at = values.iter().position(|&i| i as f64 == x).unwrap_or(0);
            vec![values[(at + 1) % values.len()] as f64]
        }
        Kind::Boolean => vec![1.0 - x],
        Kind::String => panic!("{} is a String", v.name),
    };
    let allowed = |y: f64| match v.kind {
        Kind::Real | Kind::Integer => v.range.contains(y),
        _ => true,
    };
    let found = candidates.into_iter().find(|&y| y != x && y.is_finite() && allowed(y));
    found.unwrap_or_else(|| panic!("no other value of {} than {x}", v.name))
}

/// Values off the start values, so that a reset has something to undo: the
/// first settable parameter of each type and the first Real input.
pub fn config<M: Tested>() -> Vec<(&'static str, f64)> {
    let parameters = settable_parameters::<M>();
    let kinds: [fn(&Kind) -> bool; 4] = [
        |k| *k == Kind::Real,
        |k| *k == Kind::Integer,
        |k| matches!(k, Kind::Enumeration { .. }),
        |k| *k == Kind::Boolean,
    ];
    let mut out: Vec<(&'static str, f64)> = kinds
        .iter()
        .filter_map(|kind| parameters.iter().find(|v| kind(&v.kind)))
        .map(|v| (v.name.as_ref(), other_value(v, start_of(v))))
        .collect();
    let input = first_real_input::<M>();
    out.push((&input.name, other_value(input, start_of(input))));
    out
}

/// The value of Real input number `j` (of `real_inputs`) in step `k` of the
/// standard run: its start value moved by up to 1 % (0.01 from 0), each input
/// at its own pace; the start value where that leaves the range.
pub fn input_at(v: &Variable, j: usize, k: usize) -> f64 {
    let x0 = start_of(v);
    let amplitude = if x0 == 0.0 { 0.01 } else { 0.01 * x0.abs() };
    let x = x0 + amplitude * (0.9 * k as f64 + 1.7 * j as f64).sin();
    if v.range.contains(x) {
        x
    } else {
        x0
    }
}

/// The step size of step `k` of the standard run.
pub fn step_size(k: usize) -> f64 {
    [1e-3, 2.5e-3, 1e-2, 3.7e-4, 0.05][k % 5]
}

/// Every Real's value reference.
pub fn reals<M: Tested>() -> Vec<u32> {
    M::description().variables.iter().filter(|v| v.kind == Kind::Real).map(|v| v.vr).collect()
}

/// Steps `from..to` of the standard run, from time `t`: sets the inputs,
/// steps, and records the bits of every Real after each step. Returns the
/// record and the end time.
pub fn run<M: Tested>(fmu: &Fmu<M>, mut t: f64, from: usize, to: usize) -> (Vec<Vec<u64>>, f64) {
    let reals = reals::<M>();
    let inputs = real_inputs::<M>();
    let vrs: Vec<u32> = inputs.iter().map(|v| v.vr).collect();
    let mut record = Vec::new();
    for k in from..to {
        let u: Vec<f64> = inputs.iter().enumerate().map(|(j, v)| input_at(v, j, k)).collect();
        assert_eq!(fmu.set_reals_vr(&vrs, &u), OK, "{:?}", fmu.logs());
        let h = step_size(k);
        assert_eq!(fmu.do_step(t, h), OK, "step {k} at t = {t}: {:?}", fmu.logs());
        t += h;
        let values = fmu.get_reals_vr(&reals).expect("fmi2GetReal");
        record.push(values.iter().map(|x| x.to_bits()).collect());
    }
    (record, t)
}

/// Every variable's value as bits (Strings hashed, see `Fmu::get`).
pub fn all_values<M: Tested>(fmu: &Fmu<M>) -> Vec<u64> {
    M::description()
        .variables
        .iter()
        .map(|v| fmu.get(&v.name).unwrap_or_else(|s| panic!("get {}: {s} {:?}", v.name, fmu.logs())).to_bits())
        .collect()
}

/// Initialization from the instantiated phase and three steps: the values
/// after initialization and the record of the steps.
pub fn init_and_run<M: Tested>(fmu: &Fmu<M>) -> Vec<Vec<u64>> {
    fmu.init(0.0);
    let mut out = vec![all_values(fmu)];
    out.extend(run(fmu, 0.0, 0, 3).0);
    out
}

/// An instance at its start values in step complete after `steps` steps of
/// the standard run, and its time.
pub fn running<M: Tested>(steps: usize) -> (Fmu<M>, f64) {
    let fmu = Fmu::new();
    fmu.init(0.0);
    let (_, t) = run(&fmu, 0.0, 0, steps);
    fmu.take_logs();
    (fmu, t)
}

/// The phases of the FMI 2.0 co-simulation state machine, numbered as the
/// first payload byte of a serialized FMU state (fmi_core::snapshot),
/// written here independently of the product's own enum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    Instantiated = 0,
    Init = 1,
    Complete = 2,
    Failed = 3,
    Terminated = 4,
    Error = 5,
}

pub const PHASES: [Phase; 6] = [Phase::Instantiated, Phase::Init, Phase::Complete, Phase::Failed, Phase::Terminated, Phase::Error];

/// The phase of an instance, read without disturbing it: fmi2GetFMUstate
/// and fmi2SerializeFMUstate are allowed in every phase, and the payload
/// (after the 24-byte header) starts with the phase byte.
pub fn phase_of<M: Tested>(fmu: &Fmu<M>) -> Phase {
    let mut s = fmu.get_state().expect("fmi2GetFMUstate");
    let bytes = fmu.serialize(s).expect("fmi2SerializeFMUstate");
    assert_eq!(fmu.free_state(&mut s), OK);
    *PHASES.get(bytes[24] as usize).unwrap_or_else(|| panic!("phase byte {}", bytes[24]))
}

/// A step the model discards from `config` after initialization: a Real
/// input at an end of its range (the first such that works) and a step
/// long enough to leave every bound. FMI 2.0 lets only the model discard,
/// so the step-failed phase is reached through the model's own limits.
pub fn failing_step<M: Tested>() -> (u32, f64, f64) {
    let config = config::<M>();
    for v in real_inputs::<M>() {
        for x in [v.range.hi, v.range.lo].into_iter().filter(|x| x.is_finite()) {
            for h in [1e3, 1e300] {
                let fmu = Fmu::<M>::new();
                fmu.set_all(&config);
                fmu.init(0.0);
                if fmu.set_reals_vr(&[v.vr], &[x]) == OK && fmu.do_step(0.0, h) == DISCARD {
                    return (v.vr, x, h);
                }
            }
        }
    }
    panic!("no step with a Real input at an end of its range is discarded: the step-failed phase cannot be reached")
}

/// A fresh instance with `config` set, brought into `phase` (checked).
pub fn drive<M: Tested>(phase: Phase) -> Fmu<M> {
    let fmu = Fmu::new();
    fmu.set_all(&config::<M>());
    match phase {
        Phase::Instantiated => {}
        Phase::Init => {
            assert_eq!(fmu.setup_experiment(0.0), OK);
            assert_eq!(fmu.enter_init(), OK);
        }
        Phase::Complete => fmu.init(0.0),
        Phase::Failed => {
            let (vr, x, h) = failing_step::<M>();
            fmu.init(0.0);
            assert_eq!(fmu.set_reals_vr(&[vr], &[x]), OK);
            assert_eq!(fmu.do_step(0.0, h), DISCARD, "{:?}", fmu.logs());
        }
        Phase::Terminated => {
            fmu.init(0.0);
            assert_eq!(fmu.do_step(0.0, 0.01), OK);
            assert_eq!(fmu.terminate(), OK);
        }
        Phase::Error => assert_eq!(fmu.do_step(0.0, 0.01), ERROR),
    }
    assert_eq!(phase_of(&fmu), phase, "drive({phase:?})");
    fmu.take_logs();
    fmu
}

/// Exactly one line, fmi2Error in category logStatusError, containing every needle.
#[track_caller]
pub fn assert_one_error(lines: &[LogLine], needles: &[&str]) {
    assert_eq!(lines.len(), 1, "expected exactly one log line, got {lines:#?}");
    let line = &lines[0];
    assert_eq!(line.status, ERROR, "{line:?}");
    assert_eq!(line.category, "logStatusError", "{line:?}");
    for needle in needles {
        assert!(line.message.contains(needle), "message {:?} lacks {needle:?}", line.message);
    }
}

/// |a - b| relative to the larger magnitude (0 when bit-identical).
pub fn relative_change(a: f64, b: f64) -> f64 {
    if a.to_bits() == b.to_bits() {
        0.0
    } else {
        (a - b).abs() / a.abs().max(b.abs()).max(f64::MIN_POSITIVE)
    }
}
