//! ModelStructure: the dependencies the description lists for outputs and
//! initial unknowns are exact (each listed known changes the unknown at some
//! operating point, no unlisted one ever does), and fmi2GetDirectionalDerivative
//! agrees with them and with the values.

use super::scene::*;
use super::{Hints, Point};
use crate::*;
use fmi_core::description::{Causality, Dependency, Kind, Variable};
use crate::Tested;

/// The operating points: the start values; each settable Boolean parameter
/// flipped and each enumeration parameter at each other item (alone); and
/// the model's hints.
fn points<M: Tested>(hints: &Hints) -> Vec<Point> {
    let mut out = vec![Point::default()];
    for v in settable_parameters::<M>() {
        let others: Vec<f64> = match v.kind {
            Kind::Boolean => vec![1.0 - start_of(v)],
            Kind::Enumeration { values, .. } => values.iter().map(|&i| i as f64).filter(|&i| i != start_of(v)).collect(),
            _ => continue,
        };
        out.extend(others.into_iter().map(|x| Point { values: vec![(&v.name, x)], texts: vec![] }));
    }
    out.extend(hints.points.iter().cloned());
    out
}

/// A fresh instance with `point` set; `None` (with the log) when a set is refused.
fn at<M: Tested>(point: &Point) -> Result<Fmu<M>, String> {
    let fmu = Fmu::<M>::new();
    for &(name, x) in &point.values {
        if fmu.set(name, x) != OK {
            return Err(format!("{name} = {x}: {:?}", fmu.logs()));
        }
    }
    for (name, text) in &point.texts {
        if fmu.set_text(name, text) != OK {
            return Err(format!("{name} = {text:?}: {:?}", fmu.logs()));
        }
    }
    Ok(fmu)
}

/// A small change of a parameter or input inside its range: relative 1e-6
/// for Reals (1e-6 absolute at 0), the other value for Booleans, the next
/// item for enumerations, one more or less for Integers.
fn perturbed(v: &Variable, x: f64) -> f64 {
    let candidates = match v.kind {
        Kind::Real if x == 0.0 => [1e-6, -1e-6],
        Kind::Real => [x * (1.0 + 1e-6), x * (1.0 - 1e-6)],
        Kind::Integer => [x + 1.0, x - 1.0],
        Kind::Boolean => return 1.0 - x,
        Kind::Enumeration { values, .. } => {
            let max = *values.iter().max().unwrap() as f64;
            return if x < max { x + 1.0 } else { x - 1.0 };
        }
        Kind::String => unreachable!("{} is a String", v.name),
    };
    candidates.into_iter().find(|&y| v.range.contains(y)).unwrap_or_else(|| panic!("no small change of {} = {x}", v.name))
}

/// Whether `known` is listed for `unknown`; `None` when the description
/// gives no list (FMI 2.0: then it depends on all knowns, a conservative
/// statement that claims nothing exact).
fn listed(u: &Dependency, known: &Variable) -> Option<bool> {
    u.on.as_ref().map(|on| on.contains(&known.vr))
}

/// Mismatches of the measured largest relative changes per (unknown, known)
/// with the listed dependencies: a listed known must change the unknown by
/// more than `significant` at some point; an unlisted one must never change
/// it by more than `rounding`.
fn dependency_problems<M: Tested>(
    unknowns: &[Dependency],
    knowns: &[&Variable],
    largest: &[Vec<f64>],
    significant: f64,
    rounding: f64,
) -> Vec<String> {
    let mut problems = Vec::new();
    for (i, u) in unknowns.iter().enumerate() {
        let unknown = &M::description().variable(u.vr).unwrap().name;
        for (j, known) in knowns.iter().enumerate() {
            let c = largest[i][j];
            match listed(u, known) {
                Some(true) if c <= significant => {
                    problems.push(format!("{unknown} lists {} but never changes with it (largest change {c:e})", known.name))
                }
                Some(false) if c > rounding => {
                    problems.push(format!("{unknown} does not list {} but changes with it by {c:e}", known.name))
                }
                _ => {}
            }
        }
    }
    problems
}

/// Proves that ModelStructure/Outputs is exact: at every operating point
/// (see `points`), right after initialization and after five steps of the
/// standard run, perturbing one input (see `perturbed`) changes an output at
/// some point if the input is listed as its dependency (by far more than
/// rounding), and leaves it bit-identical at every point if not. Every
/// perturbation uses a fresh instance; every output must be listed.
pub fn output_dependencies_are_exact<M: Tested>(hints: &Hints) {
    let outputs = &M::description().output_dependencies;
    let output_vrs: Vec<u32> = of_causality::<M>(Causality::Output).iter().map(|v| v.vr).collect();
    assert_eq!(outputs.iter().map(|d| d.vr).collect::<Vec<_>>(), output_vrs, "every output is listed");
    let inputs = of_causality::<M>(Causality::Input);
    let mut largest = vec![vec![0.0f64; inputs.len()]; outputs.len()];
    let mut measured = 0;
    for base in points::<M>(hints) {
        for steps in [0, 5] {
            let outputs_at = |perturbed_input: Option<u32>| -> Result<Vec<f64>, String> {
                let fmu = at::<M>(&base)?;
                assert_eq!(fmu.setup_experiment(0.0), OK);
                assert_eq!(fmu.enter_init(), OK);
                if fmu.exit_init() != OK {
                    return Err(format!("{:?}", fmu.logs()));
                }
                run(&fmu, 0.0, 0, steps);
                for input in &inputs {
                    let x = fmu.get(&input.name).unwrap();
                    let y = if perturbed_input == Some(input.vr) { perturbed(input, x) } else { x };
                    assert_eq!(fmu.set(&input.name, y), OK, "{} = {y}: {:?}", input.name, fmu.logs());
                }
                Ok(outputs.iter().map(|d| fmu.get_reals_vr(&[d.vr]).unwrap()[0]).collect())
            };
            let baseline = match outputs_at(None) {
                Ok(values) => values,
                // A variant the model refuses adds nothing; a hint must initialize.
                Err(why) if !hints.points.contains(&base) => {
                    let _ = why;
                    continue;
                }
                Err(why) => panic!("the hint {base:?} does not initialize: {why}"),
            };
            assert_eq!(Ok(baseline.clone()), outputs_at(None), "deterministic");
            for (j, input) in inputs.iter().enumerate() {
                let after = outputs_at(Some(input.vr)).expect("a perturbed input initializes as the base did");
                for i in 0..outputs.len() {
                    largest[i][j] = largest[i][j].max(relative_change(baseline[i], after[i]));
                }
            }
            measured += 1;
        }
    }
    assert!(measured >= 2, "only {measured} operating points initialize");
    let problems = dependency_problems::<M>(&outputs, &inputs, &largest, 1e-10, 0.0);
    assert!(problems.is_empty(), "{problems:#?}");
}

/// Proves that ModelStructure/InitialUnknowns is exact: for every initial
/// unknown, each listed dependency changes its value (read in
/// initialization mode) at some operating point (see `points`), and no
/// unlisted parameter or input changes it at any of them by more than
/// rounding. Changes are measured against the unknown's largest magnitude
/// over all points; rounding is 1e-13 of that (e.g. a strain L/x - 1
/// computed for a perturbed L may differ in its last bit, and a derivative
/// at equilibrium is 0 up to rounding noise). A String parameter is
/// perturbed to the other text the hints give. Each perturbation is a fresh
/// instance; a perturbation the model refuses must be one the hints name.
/// SHOW_DEPENDENCY_MARGINS=1 prints the margins.
pub fn initial_dependencies_are_exact<M: Tested>(hints: &Hints) {
    let unknowns = &M::description().initial_dependencies;
    let all_knowns = M::description().variables.iter().filter(|v| matches!(v.causality, Causality::Parameter | Causality::Input));
    let text_of = |v: &Variable| hints.texts.iter().find(|(n, _)| *n == v.name).map(|(_, t)| t.clone());
    let (knowns, untextable): (Vec<&Variable>, Vec<&Variable>) =
        all_knowns.partition(|v| v.kind != Kind::String || text_of(v).is_some());
    for v in &untextable {
        let listing: Vec<&str> =
            unknowns.iter().filter(|u| listed(u, v) == Some(true)).map(|u| M::description().variable(u.vr).unwrap().name.as_ref()).collect();
        assert!(listing.is_empty(), "{listing:?} list {}: the hints must give it another text", v.name);
    }
    // Largest absolute change per (unknown, known), and largest magnitude per unknown.
    let mut largest = vec![vec![0.0f64; knowns.len()]; unknowns.len()];
    let mut scale = vec![f64::MIN_POSITIVE; unknowns.len()];
    let mut measured = 0;
    let refused = |fmu: &Fmu<M>, what: &str| {
        let refusal = format!("{:?}", fmu.logs());
        assert!(hints.refusals.iter().any(|r| refusal.contains(r)), "{what} refused: {refusal}");
    };
    for base in points::<M>(hints) {
        // One call for every unknown, as an importer reads them (a refusal of any is a refusal).
        let vrs: Vec<u32> = unknowns.iter().map(|u| u.vr).collect();
        let in_init = |change: Option<(&Variable, f64)>| -> Result<Fmu<M>, String> {
            let fmu = at::<M>(&base)?;
            assert_eq!(fmu.setup_experiment(0.0), OK);
            assert_eq!(fmu.enter_init(), OK);
            if let Some((v, x)) = change {
                // Read first, then perturb in initialization mode: the next read must see the change.
                let _ = fmu.get_reals_vr(&vrs);
                let status = match v.kind {
                    Kind::String => fmu.set_text(&v.name, &text_of(v).unwrap()),
                    _ => fmu.set(&v.name, x),
                };
                assert_eq!(status, OK, "perturbing {} in initialization mode", v.name);
            }
            Ok(fmu)
        };
        // None where initialization refuses the values.
        let read = |fmu: &Fmu<M>| -> Option<Vec<f64>> { fmu.get_reals_vr(&vrs).ok() };
        let probe = in_init(None).unwrap_or_else(|why| panic!("{base:?}: {why}"));
        let Some(baseline) = read(&probe) else {
            // A variant the model refuses adds nothing; a hint must initialize.
            assert!(!hints.points.contains(&base), "the hint {base:?} does not initialize: {:?}", probe.logs());
            continue;
        };
        for (i, y) in baseline.iter().enumerate() {
            scale[i] = scale[i].max(y.abs());
        }
        for (j, known) in knowns.iter().enumerate() {
            let x = if known.kind == Kind::String { 0.0 } else { perturbed(known, probe.get(&known.name).unwrap()) };
            let fmu = in_init(Some((known, x))).unwrap_or_else(|why| panic!("{base:?}: {why}"));
            let Some(after) = read(&fmu) else {
                refused(&fmu, &known.name);
                continue;
            };
            for i in 0..unknowns.len() {
                largest[i][j] = largest[i][j].max((after[i] - baseline[i]).abs());
            }
        }
        measured += 1;
    }
    assert!(measured >= 1, "no operating point initializes");
    for (row, s) in largest.iter_mut().zip(&scale) {
        row.iter_mut().for_each(|c| *c /= s);
    }
    if std::env::var_os("SHOW_DEPENDENCY_MARGINS").is_some() {
        for (i, u) in unknowns.iter().enumerate() {
            let name = M::description().variable(u.vr).unwrap().name.as_ref();
            let (mut smallest_listed, mut largest_unlisted) = (f64::INFINITY, 0.0f64);
            for (j, k) in knowns.iter().enumerate() {
                match listed(u, k) {
                    Some(false) => largest_unlisted = largest_unlisted.max(largest[i][j]),
                    _ => smallest_listed = smallest_listed.min(largest[i][j]),
                }
            }
            eprintln!("{name}: smallest listed {smallest_listed:e}, largest unlisted {largest_unlisted:e}");
        }
    }
    let problems = dependency_problems::<M>(&unknowns, &knowns, &largest, 1e-11, 1e-13);
    assert!(problems.is_empty(), "{problems:#?}");
}

/// Proves that fmi2GetDirectionalDerivative (where the description offers
/// it for Co-Simulation) gives, for every output and every input it lists,
/// the central difference of the output's values to 1e-6; exactly 0 for the
/// inputs it does not list; a sum over knowns weighted by the seed; and
/// that it refuses with one line naming the argument: a parameter as known,
/// a state as known in Co-Simulation, an input as unknown, a value reference
/// of no variable, a NaN seed, NULL arrays and one array for dvKnown and
/// dvUnknown. Without the capability every call is refused as not supported.
pub fn directional_derivatives_through_the_c_api<M: Tested>() {
    let d = M::description();
    let inputs = real_inputs::<M>();
    // An output that lists an input (k1), and another input (k2), for the weighted sum.
    let (output, k1) = d
        .output_dependencies
        .iter()
        .find_map(|u| Some((d.variable(u.vr)?, *inputs.iter().find(|k| listed(u, k) != Some(false))?)))
        .expect("an output that depends on an input");
    let k2 = *inputs.iter().find(|k| k.vr != k1.vr).unwrap_or(&k1);
    if !d.provides_directional_derivative[0] {
        let fmu = drive::<M>(Phase::Complete);
        assert_eq!(fmu.directional_derivative(&[output.vr], &[k1.vr], &[1.0]).0, ERROR);
        assert_one_error(&fmu.take_logs(), &["fmi2GetDirectionalDerivative", "not supported"]);
        return;
    }
    let fmu = drive::<M>(Phase::Complete);
    let mut compared = 0;
    for u in d.output_dependencies.iter().filter(|u| d.variable(u.vr).unwrap().kind == Kind::Real) {
        let name = &d.variable(u.vr).unwrap().name;
        for k in &inputs {
            let (status, column) = fmu.directional_derivative(&[u.vr], &[k.vr], &[1.0]);
            assert_eq!(status, OK, "d{name}/d{}: {:?}", k.name, fmu.logs());
            if listed(u, k) == Some(false) {
                assert_eq!(column[0], 0.0, "d{name}/d{} is structurally 0", k.name);
                continue;
            }
            let x = fmu.real(&k.name);
            let dx = 1e-6 * x.abs().max(1e-3);
            let value_at = |y: f64| {
                assert_eq!(fmu.set(&k.name, y), OK, "{} = {y}: {:?}", k.name, fmu.logs());
                fmu.real(&name)
            };
            let difference = (value_at(x + dx) - value_at(x - dx)) / (2.0 * dx);
            let value = value_at(x);
            // Relative to the larger of both, and to the value's own scale where both are about 0.
            let tolerance = 1e-6 * column[0].abs().max(difference.abs()).max(value.abs() / x.abs().max(1.0));
            let what = format!("d{name}/d{}: {} vs the central difference {difference}", k.name, column[0]);
            assert!((column[0] - difference).abs() <= tolerance, "{what}");
            compared += 1;
        }
    }
    assert!(compared > 0, "no output lists an input: nothing to compare");
    let (s1, one) = fmu.directional_derivative(&[output.vr], &[k1.vr], &[1.0]);
    let (s2, two) = fmu.directional_derivative(&[output.vr], &[k2.vr], &[1.0]);
    let (s3, both) = fmu.directional_derivative(&[output.vr], &[k1.vr, k2.vr], &[2.0, -3.0]);
    assert_eq!((s1, s2, s3), (OK, OK, OK), "{:?}", fmu.logs());
    let sum = 2.0 * one[0] - 3.0 * two[0];
    assert!((both[0] - sum).abs() <= 1e-15 * sum.abs().max(one[0].abs()).max(two[0].abs()), "{} vs {sum}", both[0]);

    let parameter = settable_parameters::<M>().into_iter().find(|v| v.kind == Kind::Real).expect("a Real parameter");
    let state = d.states.first().map(|&vr| d.variable(vr).expect("a state variable"));
    let unused = unused_vr::<M>();
    let named = |v: &Variable| format!("{} (value reference {})", v.name, v.vr);
    let cases: [(&str, Vec<u32>, Vec<u32>, Vec<f64>, String); 4] = [
        (
            "parameter known",
            vec![output.vr],
            vec![parameter.vr],
            vec![1.0],
            format!("vKnown_ref: {} is not a known in Co-Simulation", named(parameter)),
        ),
        ("input unknown", vec![k2.vr], vec![k1.vr], vec![1.0], format!("vUnknown_ref: {} is not an unknown", named(k2))),
        ("no variable", vec![unused], vec![k1.vr], vec![1.0], format!("value reference {unused} (no variable)")),
        ("NaN seed", vec![output.vr], vec![k1.vr, k2.vr], vec![1.0, f64::NAN], "dvKnown[1] = NaN".into()),
    ];
    let state_known =
        state.map(|x| ("state known in CS", vec![output.vr], vec![x.vr], vec![1.0], format!("vKnown_ref: {} is not a known", named(x))));
    for (what, unknowns, knowns, seed, needle) in cases.into_iter().chain(state_known) {
        let fmu = drive::<M>(Phase::Complete);
        assert_eq!(fmu.directional_derivative(&unknowns, &knowns, &seed).0, ERROR, "{what}");
        assert_one_error(&fmu.take_logs(), &["fmi2GetDirectionalDerivative", &needle]);
    }
    for (what, buffer, needle) in [("shared", Some(&mut [1.0][..]), "overlap"), ("NULL", None, "dvKnown is NULL")] {
        let fmu = drive::<M>(Phase::Complete);
        assert_eq!(fmu.directional_derivative_in_place(&[output.vr], &[k1.vr], buffer), ERROR, "{what}");
        assert_one_error(&fmu.take_logs(), &["fmi2GetDirectionalDerivative", needle]);
    }
}
