//! Getting and setting values: the checks the description drives (ranges,
//! enumeration items, Booleans, value references, types, causality and
//! variability), each refusal one line naming what was wrong, and sets
//! that apply all of a call or nothing.

use super::scene::*;
use crate::*;
use fmi_core::description::{Causality, Family, Initial, Kind, Range, Start, Variability, Variable};
use crate::Tested;

/// Values outside `r` (the neighbouring doubles of each finite bound, an
/// open bound itself, and far beyond), and the values just inside.
fn outside(r: &Range) -> (Vec<f64>, Vec<f64>) {
    let mut bad = vec![f64::MIN, f64::MAX, -1e300, 1e300];
    let mut fine = Vec::new();
    for (bound, inclusive_end) in [(r.min, r.lo), (r.max, r.hi)] {
        if bound.is_finite() {
            bad.extend([bound, bound.next_down(), bound.next_up()]);
            fine.push(inclusive_end);
        }
    }
    bad.retain(|&x| !r.contains(x));
    bad.sort_by(f64::total_cmp);
    bad.dedup();
    (bad, fine)
}

/// " unit" as the layer writes it after a value (nothing for "" and "1").
fn unit_suffix(v: &Variable) -> String {
    if v.unit.is_empty() || v.unit == "1" {
        String::new()
    } else {
        format!(" {}", v.unit)
    }
}

/// The words of the refusal of `x` for `v` outside its range.
fn range_needles(v: &Variable, x: f64) -> [String; 2] {
    [format!("{} = {x}{}", v.name, unit_suffix(v)), format!("is outside its allowed range {}", v.range)]
}

fn strs(needles: &[String]) -> Vec<&str> {
    needles.iter().map(String::as_str).collect()
}

fn bounded(v: &Variable) -> bool {
    !v.range.is_unbounded()
}

/// What `config` or the start value gives `v` before anything else is set.
fn configured<M: Tested>(v: &Variable) -> f64 {
    config::<M>().iter().find(|(n, _)| *n == v.name).map_or_else(|| start_of(v), |c| c.1)
}

/// Proves that every parameter and input has a start value inside its
/// allowed range (enumerations: one of its items), and that in
/// initialization mode each reads back exactly that value through the get
/// function of its type.
pub fn start_values_are_allowed_and_read_back<M: Tested>() {
    let fmu = drive_fresh_into_init::<M>();
    let knowable = M::description().variables.iter().filter(|v| matches!(v.causality, Causality::Parameter | Causality::Input));
    for v in knowable {
        match (v.kind, v.start) {
            (Kind::String, Start::String(text)) => assert_eq!(fmu.text(&v.name), text, "{}", v.name),
            (Kind::Enumeration { values, .. }, Start::Integer(x)) => {
                assert!(values.contains(&x), "{} start {x} is not an item", v.name);
                assert_eq!(fmu.get(&v.name), Ok(x as f64), "{}", v.name);
            }
            (_, Start::String(_) | Start::None) => panic!("{} has no start value of its type", v.name),
            _ => {
                let x = start_of(v);
                assert!(v.kind == Kind::Boolean || v.range.contains(x), "{} start {x} is outside {}", v.name, v.range);
                assert_eq!(fmu.get(&v.name).map(f64::to_bits), Ok(x.to_bits()), "{}", v.name);
            }
        }
    }
    assert!(fmu.logs().is_empty(), "{:?}", fmu.logs());
}

/// A fresh instance (start values) in initialization mode.
fn drive_fresh_into_init<M: Tested>() -> Fmu<M> {
    let fmu = Fmu::<M>::new();
    assert_eq!(fmu.setup_experiment(0.0), OK);
    assert_eq!(fmu.enter_init(), OK);
    fmu
}

/// Proves that a parameter set outside its range is accepted by fmi2SetReal
/// (parameters may pass through odd values while being set one by one) but
/// refused by fmi2ExitInitializationMode with fmi2Error and one line naming
/// the variable, the value and the range; that nothing set before is lost
/// (readable in the error state, and a state saved before the bad value
/// brings the instance back to an initialization that then runs exactly
/// like an instance that never saw the bad value); and that the values just
/// inside the range are accepted (so the bound is where the XML puts it).
pub fn parameter_out_of_range_is_refused_at_exit_initialization<M: Tested>() {
    let good = config::<M>();
    let reference = {
        let fmu = Fmu::<M>::new();
        fmu.set_all(&good);
        init_and_run(&fmu)
    };
    let parameters: Vec<&Variable> =
        settable_parameters::<M>().into_iter().filter(|v| v.kind == Kind::Real && v.initial == Initial::Exact && bounded(v)).collect();
    assert!(!parameters.is_empty(), "no Real parameter with an allowed range: nothing to check");
    let mut cases = 0;
    for v in &parameters {
        let (bad, fine) = outside(&v.range);
        for &x in &bad {
            let fmu = Fmu::<M>::new();
            fmu.set_all(&good);
            assert_eq!(fmu.setup_experiment(0.0), OK);
            assert_eq!(fmu.enter_init(), OK);
            let saved = fmu.get_state().unwrap();
            assert_eq!(fmu.set(&v.name, x), OK, "{} = {x} is only checked when initialization ends", v.name);
            assert_eq!(fmu.exit_init(), ERROR, "{} = {x}", v.name);
            assert_one_error(&fmu.take_logs(), &strs(&range_needles(v, x)));
            assert_eq!(phase_of(&fmu), Phase::Error);
            for (g, value) in good.iter().filter(|(g, _)| *g != v.name) {
                assert_eq!(fmu.get(g), Ok(*value), "{g} after the failed exit with {} = {x}", v.name);
            }
            assert_eq!(fmu.set_state(saved), OK);
            assert_eq!(fmu.exit_init(), OK, "{:?}", fmu.logs());
            let mut after = vec![all_values(&fmu)];
            after.extend(run(&fmu, 0.0, 0, 3).0);
            assert_eq!(after, reference, "{} = {x}: restoring the saved state must lose nothing", v.name);
            cases += 1;
        }
        for &x in &fine {
            let case = format!("values::parameter_out_of_range_is_refused_at_exit_initialization: {} = {x}", v.name);
            if let Some(reason) = M::skipped(&case) {
                eprintln!("skipped {case}: {reason}");
                continue;
            }
            let fmu = Fmu::<M>::new();
            assert_eq!(fmu.set(&v.name, x), OK);
            assert_eq!(fmu.setup_experiment(0.0), OK);
            assert_eq!(fmu.enter_init(), OK);
            assert_eq!(fmu.exit_init(), OK, "{} = {x} is inside {}: {:?}", v.name, v.range, fmu.logs());
        }
    }
    assert!(cases >= 3 * parameters.len(), "only {cases} cases");
}

/// Proves that an Integer parameter outside its min/max is refused when
/// initialization ends, with one line naming the variable, the value and
/// the range, and that both bounds are accepted.
pub fn integer_parameter_out_of_range_is_refused_at_exit_initialization<M: Tested>() {
    for v in settable_parameters::<M>().into_iter().filter(|v| v.kind == Kind::Integer && bounded(v)) {
        let (lo, hi) = (v.range.lo, v.range.hi);
        let mut bad: Vec<i32> = [lo - 1.0, lo - 5.0, hi + 1.0, i32::MIN as f64, i32::MAX as f64]
            .into_iter()
            .filter(|&x| x >= i32::MIN as f64 && x <= i32::MAX as f64 && !v.range.contains(x))
            .map(|x| x as i32)
            .collect();
        bad.dedup();
        assert!(!bad.is_empty(), "{}: no Integer outside {}", v.name, v.range);
        for x in bad {
            let fmu = Fmu::<M>::new();
            assert_eq!(fmu.set_integers_vr(&[v.vr], &[x]), OK);
            assert_eq!(fmu.setup_experiment(0.0), OK);
            assert_eq!(fmu.enter_init(), OK);
            assert_eq!(fmu.exit_init(), ERROR, "{} = {x}", v.name);
            assert_one_error(&fmu.take_logs(), &[&format!("{} = {x}", v.name), &v.range.to_string()]);
        }
        for x in [lo, hi].into_iter().filter(|x| x.abs() <= i32::MAX as f64) {
            let fmu = Fmu::<M>::new();
            assert_eq!(fmu.set_integers_vr(&[v.vr], &[x as i32]), OK);
            fmu.init(0.0);
        }
    }
}

/// Proves that NaN, +inf and -inf are refused at once by fmi2SetReal for
/// every Real parameter and input, in every phase in which the variable can
/// be set, with one line naming variable, value and range, and that the
/// variable keeps its previous value (read back in the error state).
pub fn non_finite_reals_are_refused_immediately<M: Tested>() {
    let knowable = settable_parameters::<M>().into_iter().chain(real_inputs::<M>()).filter(|v| v.kind == Kind::Real);
    for v in knowable {
        let phases: &[Phase] = match (v.causality, v.initial) {
            (Causality::Input, _) => &[Phase::Instantiated, Phase::Init, Phase::Complete],
            (_, Initial::Exact) => &[Phase::Instantiated, Phase::Init],
            _ => &[Phase::Instantiated],
        };
        let expected = configured::<M>(v);
        for &phase in phases {
            for x in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                let fmu = drive::<M>(phase);
                assert_eq!(fmu.set(&v.name, x), ERROR, "{} = {x} in {phase:?}", v.name);
                assert_one_error(&fmu.take_logs(), &strs(&range_needles(v, x)));
                assert_eq!(phase_of(&fmu), Phase::Error);
                assert_eq!(fmu.real(&v.name).to_bits(), expected.to_bits(), "{} changed by a refused set", v.name);
            }
        }
    }
}

/// Proves that an input outside its range is refused at once (inputs take
/// effect immediately), for every Real input with a bound and every value
/// just beyond or far beyond it, in every phase where inputs can be set,
/// with the name, value and range in the message and the value kept; the
/// values just inside are accepted. After restoring a state saved before
/// the bad call the instance continues exactly like one that never saw it.
pub fn input_out_of_range_is_refused_immediately<M: Tested>() {
    let inputs: Vec<&Variable> = real_inputs::<M>().into_iter().filter(|v| bounded(v)).collect();
    assert!(!inputs.is_empty(), "no Real input with an allowed range: nothing to check");
    for v in &inputs {
        let (bad, fine) = outside(&v.range);
        let kept = configured::<M>(v);
        for phase in [Phase::Instantiated, Phase::Init, Phase::Complete] {
            for &x in &bad {
                let fmu = drive::<M>(phase);
                assert_eq!(fmu.set(&v.name, x), ERROR, "{} = {x} in {phase:?}", v.name);
                assert_one_error(&fmu.take_logs(), &strs(&range_needles(v, x)));
                assert_eq!(fmu.real(&v.name).to_bits(), kept.to_bits(), "{}: value kept", v.name);
            }
            for &x in &fine {
                let fmu = drive::<M>(phase);
                assert_eq!(fmu.set(&v.name, x), OK, "{} = {x} is inside {} in {phase:?}: {:?}", v.name, v.range, fmu.logs());
            }
        }
    }
    // Nothing lost: a state saved before the refused call continues bit-identically.
    let v = inputs[0];
    let bad = outside(&v.range).0[0];
    let (fmu, t) = running::<M>(7);
    let (reference, _) = {
        let (r, t2) = running::<M>(7);
        run(&r, t2, 7, 20)
    };
    let saved = fmu.get_state().unwrap();
    assert_eq!(fmu.set(&v.name, bad), ERROR);
    assert_eq!(fmu.do_step(t, 0.01), ERROR, "the instance is in the error state");
    assert_eq!(fmu.set_state(saved), OK);
    assert_eq!(run(&fmu, t, 7, 20).0, reference);
}

/// Proves that a tunable Real parameter set outside its range after initialization is refused at
/// once, as an input is (no later check would see it, and an FMU state saved with it would not
/// restore), with one line naming the variable, the value and the range, the value kept; its own
/// value is accepted again. A model without tunable parameters has nothing to check.
pub fn tunable_parameter_out_of_range_after_initialization_is_refused<M: Tested>() {
    let tunables: Vec<&Variable> = of_causality::<M>(Causality::Parameter)
        .into_iter()
        .filter(|v| v.kind == Kind::Real && matches!(v.variability, Variability::Tunable) && bounded(v))
        .collect();
    if tunables.is_empty() {
        println!("skipped: no tunable Real parameter with an allowed range");
        return;
    }
    for v in &tunables {
        let kept = configured::<M>(v);
        for &x in &outside(&v.range).0 {
            let fmu = drive::<M>(Phase::Complete);
            assert_eq!(fmu.set(&v.name, x), ERROR, "{} = {x} after initialization", v.name);
            assert_one_error(&fmu.take_logs(), &strs(&range_needles(v, x)));
            assert_eq!(fmu.real(&v.name).to_bits(), kept.to_bits(), "{}: value kept", v.name);
        }
        let fmu = drive::<M>(Phase::Complete);
        assert_eq!(fmu.set(&v.name, kept), OK, "{} = {kept} (its own value) after initialization: {:?}", v.name, fmu.logs());
    }
}

/// Proves that enumeration values outside the declared items (just below
/// and above them, -1, i32::MAX) are refused for every enumeration with one
/// line naming the variable, the value and the allowed items, that the old
/// value is kept, and that the first and last items are accepted.
pub fn enumeration_outside_its_items_is_refused<M: Tested>() {
    let enumerations = M::description().variables.iter().filter(|v| v.settable_in != 0);
    for v in enumerations {
        let Kind::Enumeration { values, .. } = v.kind else { continue };
        let (min, max) = (*values.iter().min().unwrap(), *values.iter().max().unwrap());
        let other = other_value(v, start_of(v));
        for x in [min - 1, max + 1, -1, i32::MAX].into_iter().filter(|x| !values.contains(x)) {
            let fmu = Fmu::<M>::new();
            assert_eq!(fmu.set(&v.name, other), OK);
            assert_eq!(fmu.set_integers_vr(&[v.vr], &[x]), ERROR, "{} = {x}", v.name);
            assert_one_error(&fmu.take_logs(), &[&format!("{} = {x}", v.name), &format!("{min}..{max}")]);
            assert_eq!(fmu.get(&v.name), Ok(other));
        }
        for x in [min, max] {
            let fmu = Fmu::<M>::new();
            assert_eq!(fmu.set_integers_vr(&[v.vr], &[x]), OK);
            fmu.init(0.0);
            assert_eq!(fmu.get(&v.name), Ok(x as f64));
        }
    }
}

/// Proves that fmi2SetBoolean refuses values other than 0 and 1 (2, -1)
/// for every Boolean with one line naming variable, value and the allowed
/// values, and keeps the old value.
pub fn boolean_other_than_0_or_1_is_refused<M: Tested>() {
    for v in M::description().variables.iter().filter(|v| v.kind == Kind::Boolean && v.settable_in != 0) {
        for x in [2, -1] {
            let fmu = Fmu::<M>::new();
            assert_eq!(fmu.set_booleans_vr(&[v.vr], &[x]), ERROR, "{} = {x}", v.name);
            assert_one_error(&fmu.take_logs(), &[&format!("{} = {x}", v.name), "0 = false, 1 = true"]);
            assert_eq!(fmu.get(&v.name), Ok(start_of(v)));
        }
    }
}

type Probe<M> = fn(&Fmu<M>, u32) -> i32;

/// Proves that value references that name no variable (0, the largest
/// used + 1, 9999, u32::MAX, those of them no variable has) are refused by
/// every get and set function with one line naming the value reference.
pub fn unknown_value_references_are_refused<M: Tested>() {
    let d = M::description();
    let unused = [0u32, unused_vr::<M>(), 9999, u32::MAX].into_iter().filter(|&vr| d.variable(vr).is_none());
    for bad in unused {
        let needle = format!("unknown value reference {bad}");
        let setters: [(&str, Probe<M>); 4] = [
            ("fmi2SetReal", |f, r| f.set_reals_vr(&[r], &[1.0])),
            ("fmi2SetInteger", |f, r| f.set_integers_vr(&[r], &[1])),
            ("fmi2SetBoolean", |f, r| f.set_booleans_vr(&[r], &[1])),
            ("fmi2SetString", |f, r| f.set_strings_vr(&[r], &["x"])),
        ];
        let getters: [(&str, Probe<M>); 4] = [
            ("fmi2GetReal", |f, r| f.get_reals_vr(&[r]).err().unwrap_or(OK)),
            ("fmi2GetInteger", |f, r| f.get_integers_vr(&[r]).err().unwrap_or(OK)),
            ("fmi2GetBoolean", |f, r| f.get_booleans_vr(&[r]).err().unwrap_or(OK)),
            ("fmi2GetString", |f, r| f.get_strings_vr(&[r]).err().unwrap_or(OK)),
        ];
        for (function, set) in setters {
            let fmu = Fmu::<M>::new();
            assert_eq!(set(&fmu, bad), ERROR, "{function} vr {bad}");
            assert_one_error(&fmu.take_logs(), &[function, &needle]);
        }
        for (function, get) in getters {
            let fmu = drive::<M>(Phase::Complete);
            assert_eq!(get(&fmu, bad), ERROR, "{function} vr {bad}");
            assert_one_error(&fmu.take_logs(), &[function, &needle]);
        }
    }
}

/// The get and set functions of each type family, with a harmless value.
fn functions<M: Tested>(family: Family) -> [(String, Probe<M>); 2] {
    match family {
        Family::Real => [
            ("fmi2GetReal".into(), |f, r| f.get_reals_vr(&[r]).err().unwrap_or(OK)),
            ("fmi2SetReal".into(), |f, r| f.set_reals_vr(&[r], &[1.0])),
        ],
        Family::Integer => [
            ("fmi2GetInteger".into(), |f, r| f.get_integers_vr(&[r]).err().unwrap_or(OK)),
            ("fmi2SetInteger".into(), |f, r| f.set_integers_vr(&[r], &[1])),
        ],
        Family::Boolean => [
            ("fmi2GetBoolean".into(), |f, r| f.get_booleans_vr(&[r]).err().unwrap_or(OK)),
            ("fmi2SetBoolean".into(), |f, r| f.set_booleans_vr(&[r], &[1])),
        ],
        Family::String => [
            ("fmi2GetString".into(), |f, r| f.get_strings_vr(&[r]).err().unwrap_or(OK)),
            ("fmi2SetString".into(), |f, r| f.set_strings_vr(&[r], &["x"])),
        ],
    }
}

const FAMILIES: [Family; 4] = [Family::Real, Family::Integer, Family::Boolean, Family::String];

/// Proves that a value reference used with the function of another type is
/// refused with one line naming the function, the variable with its value
/// reference and both types, and that a refused set changes nothing: for
/// the first settable variable and the first computed one of every type,
/// with every other type's get function, and its set function where the
/// variable could be set.
pub fn wrong_type_is_refused<M: Tested>() {
    let d = M::description();
    for family in FAMILIES {
        let of_family = d.variables.iter().filter(|v| v.family == family);
        let in_init = |v: &&Variable| v.causality == Causality::Input || (v.initial == Initial::Exact && v.settable_in != 0);
        let settable = of_family.clone().find(in_init);
        let computed = of_family.clone().find(|v| v.settable_in == 0);
        for v in settable.into_iter().chain(computed) {
            for other in FAMILIES.into_iter().filter(|&f| f != family) {
                let [(get_name, get), (set_name, set)] = functions::<M>(other);
                let mut calls = vec![(get_name, get)];
                if v.settable_in != 0 {
                    calls.push((set_name, set));
                }
                for (function, call) in calls {
                    let fmu = drive::<M>(Phase::Init);
                    let before = fmu.get(&v.name).unwrap();
                    fmu.take_logs();
                    assert_eq!(call(&fmu, v.vr), ERROR, "{function} on {}", v.name);
                    let named = format!("{} (value reference {})", v.name, v.vr);
                    let types = format!("of type {}, not {}", family.name(), other.name());
                    assert_one_error(&fmu.take_logs(), &[&function, &named, &types]);
                    assert_eq!(fmu.get(&v.name).map(f64::to_bits), Ok(before.to_bits()), "{function} on {}", v.name);
                }
            }
        }
    }
}

/// Proves FMI 2.0's rule for sets in Model Exchange (3.2.3): in event mode inputs and tunable
/// parameters may be set; in continuous-time mode only continuous inputs, every other input and
/// every tunable parameter is refused with one line naming it and "continuous-time mode". Each
/// set gives the variable its own value, so only the phase decides.
pub fn model_exchange_sets_follow_event_and_continuous_time_mode<M: Tested>() {
    if !M::description().model_exchange {
        return;
    }
    let d = M::description();
    let tunable = d.variables.iter().filter(|v| v.causality == Causality::Parameter && v.variability == Variability::Tunable);
    let inputs = d.variables.iter().filter(|v| v.causality == Causality::Input);
    for v in tunable.chain(inputs) {
        let fmu = Fmu::<M>::with(&Setup { fmu_type: ME, ..Setup::default() });
        fmu.init(0.0);
        let value = fmu.get(&v.name).unwrap();
        assert_eq!(set_any(&fmu, v, value), OK, "{} in event mode: {:?}", v.name, fmu.take_logs());
        assert_eq!(fmu.call(Api::EnterContinuousTimeMode), OK);
        fmu.take_logs();
        if v.causality == Causality::Input && v.variability == Variability::Continuous {
            assert_eq!(set_any(&fmu, v, value), OK, "{} in continuous-time mode: {:?}", v.name, fmu.take_logs());
        } else {
            assert_eq!(set_any(&fmu, v, value), ERROR, "{} in continuous-time mode", v.name);
            assert_one_error(&fmu.take_logs(), &[&format!("cannot set {}", v.name), "continuous-time mode"]);
        }
    }
}

/// Sets `v` to a harmless value of its type.
fn set_any<M: Tested>(fmu: &Fmu<M>, v: &Variable, x: f64) -> i32 {
    match v.kind {
        Kind::String => fmu.set_text(&v.name, "x"),
        _ => fmu.set(&v.name, x),
    }
}

/// Proves that every fixed parameter refuses a set once initialization has
/// ended (step complete: fmi2Error naming the variable and "fixed"; value
/// kept), and that every output, local and calculated parameter refuses a
/// set in every phase in which inputs can be set (naming "causality").
pub fn fixed_parameters_after_init_and_outputs_cannot_be_set<M: Tested>() {
    let d = M::description();
    let fixed = settable_parameters::<M>().into_iter().filter(|v| v.variability == Variability::Fixed);
    for v in fixed {
        let fmu = drive::<M>(Phase::Complete);
        let before = fmu.get(&v.name).unwrap();
        let x = if v.kind == Kind::String { 0.0 } else { other_value(v, before) };
        assert_eq!(set_any(&fmu, v, x), ERROR, "{}", v.name);
        assert_one_error(&fmu.take_logs(), &[&format!("cannot set {}", v.name), "fixed"]);
        assert_eq!(fmu.get(&v.name).map(f64::to_bits), Ok(before.to_bits()));
    }
    let computed = d.variables.iter().filter(|v| !matches!(v.causality, Causality::Parameter | Causality::Input));
    for v in computed {
        for phase in [Phase::Instantiated, Phase::Init, Phase::Complete] {
            let fmu = drive::<M>(phase);
            assert_eq!(set_any(&fmu, v, 1.0), ERROR, "{} in {phase:?}", v.name);
            assert_one_error(&fmu.take_logs(), &[&format!("cannot set {}", v.name), "causality"]);
        }
    }
}

/// Reads `names` from an instance in initialization mode with `config` set:
/// what a refused set must leave behind.
fn values_in_init<M: Tested>(vars: &[&Variable]) -> Vec<u64> {
    let fmu = drive::<M>(Phase::Init);
    vars.iter().map(|v| fmu.get(&v.name).unwrap().to_bits()).collect()
}

fn values_of<M: Tested>(fmu: &Fmu<M>, vars: &[&Variable]) -> Vec<u64> {
    vars.iter().map(|v| fmu.get(&v.name).unwrap_or_else(|s| panic!("get {}: {s}", v.name)).to_bits()).collect()
}

/// Up to `n` variables of `pick`, repeated to `n` when fewer (a value
/// reference may appear twice in a call).
fn several(mut pick: Vec<&'static Variable>, n: usize) -> Vec<&'static Variable> {
    pick.truncate(n);
    if let Some(&first) = pick.first() {
        while pick.len() < n {
            pick.insert(0, first);
        }
    }
    pick
}

/// Proves that the set functions are atomic: when any value of a call is
/// refused (the last one, after valid ones), none of the call's values is
/// applied: Real inputs with the last out of range, Real parameters with the
/// last non-finite, an unknown value reference, an output or a variable of
/// another type as the last element, an enumeration outside its items and a
/// Boolean other than 0 or 1 after valid values.
pub fn set_is_atomic<M: Tested>() {
    let d = M::description();
    let mut inputs = real_inputs::<M>();
    let last = inputs.iter().rposition(|v| bounded(v)).expect("a Real input with an allowed range");
    let refused = inputs.remove(last);
    inputs.push(refused);
    let vrs: Vec<u32> = inputs.iter().map(|v| v.vr).collect();
    let fmu = drive::<M>(Phase::Complete);
    let before = fmu.get_reals_vr(&vrs).unwrap();
    let bad = outside(&refused.range).0[0];
    let mut values: Vec<f64> = inputs.iter().zip(&before).map(|(v, &x)| other_value(v, x)).collect();
    *values.last_mut().unwrap() = bad;
    assert_eq!(fmu.set_reals_vr(&vrs, &values), ERROR);
    assert_one_error(&fmu.take_logs(), &[&format!("{} = {bad}", refused.name)]);
    assert_eq!(fmu.get_reals_vr(&vrs).unwrap(), before);

    let params = several(settable_parameters::<M>().into_iter().filter(|v| v.kind == Kind::Real).collect(), 3);
    let reference = values_in_init::<M>(&params);
    let valid: Vec<f64> = params.iter().map(|v| other_value(v, start_of(v))).collect();
    let pvrs: Vec<u32> = params.iter().map(|v| v.vr).collect();
    for last in [f64::NAN, f64::INFINITY] {
        let fmu = drive::<M>(Phase::Instantiated);
        let values = [&valid[..2], &[last]].concat();
        assert_eq!(fmu.set_reals_vr(&pvrs, &values), ERROR);
        assert_eq!(values_of(&fmu, &params), reference, "in the error state, values unchanged");
    }
    // A bad value reference, an output and a wrong type as the last element.
    let wrong_type = d.variables.iter().find(|v| v.family != Family::Real).map(|v| v.vr);
    for bad in [unused_vr::<M>(), first_real_output::<M>().vr].into_iter().chain(wrong_type) {
        let fmu = drive::<M>(Phase::Instantiated);
        assert_eq!(fmu.set_reals_vr(&[pvrs[0], pvrs[1], bad], &[valid[0], valid[1], 1.0]), ERROR);
        assert_eq!(values_of(&fmu, &params), reference);
    }
    let settable = |f: fn(&Kind) -> bool| -> Vec<&'static Variable> {
        settable_parameters::<M>().into_iter().chain(of_causality::<M>(Causality::Input)).filter(|v| f(&v.kind)).collect()
    };
    let enumerations = settable(|k| matches!(k, Kind::Enumeration { .. }));
    if let Some(&enumeration) = enumerations.last() {
        let Kind::Enumeration { values, .. } = enumeration.kind else { unreachable!() };
        let first = settable(|k| matches!(k, Kind::Integer | Kind::Enumeration { .. }))[0];
        let fmu = drive::<M>(Phase::Instantiated);
        let reference = values_in_init::<M>(&[first]);
        let x = other_value(first, f64::from_bits(reference[0])) as i32;
        let not_an_item = values.iter().max().unwrap() + 1;
        assert_eq!(fmu.set_integers_vr(&[first.vr, enumeration.vr], &[x, not_an_item]), ERROR);
        assert_eq!(values_of(&fmu, &[first]), reference);
    }
    let booleans = several(settable(|k| *k == Kind::Boolean), 2);
    if !booleans.is_empty() {
        let fmu = drive::<M>(Phase::Instantiated);
        let reference = values_in_init::<M>(&booleans[..1]);
        let x = 1 - f64::from_bits(reference[0]) as i32;
        assert_eq!(fmu.set_booleans_vr(&[booleans[0].vr, booleans[1].vr], &[x, 2]), ERROR);
        assert_eq!(values_of(&fmu, &booleans[..1]), reference);
    }
}
