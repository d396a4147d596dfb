//! Threads: FMI 2.0 lets an importer run different instances on different
//! threads at the same time. Eight instances stepping concurrently on eight
//! threads must give results bit-identical to the same eight runs made one
//! after another, and no instance changes what another starts with (that
//! nothing global could couple them: `statics`).

use super::scene::*;
use crate::*;
use fmi_core::description::Kind;
use crate::Tested;
use std::sync::Barrier;

const THREADS: usize = 8;
const STEPS: usize = 3000;

/// Run `k`: its own value of the first Real parameter, its own item of
/// every enumeration parameter (a solver, a unit), inputs moving about
/// their start values at its own pace and, in the second half, apart;
/// returns the bits of every Real after every step.
fn scenario<M: Tested>(k: usize, barrier: Option<&Barrier>) -> Vec<u64> {
    let fmu = Fmu::<M>::named(&format!("thread{k}"));
    let parameters = settable_parameters::<M>();
    let first = parameters.iter().find(|v| v.kind == Kind::Real).expect("a Real parameter");
    let mut x = start_of(first);
    for _ in 0..k {
        x = other_value(first, x);
    }
    assert_eq!(fmu.set(&first.name, x), OK, "{:?}", fmu.messages());
    for v in &parameters {
        if let Kind::Enumeration { values, .. } = v.kind {
            assert_eq!(fmu.set(&v.name, values[k % values.len()] as f64), OK, "{:?}", fmu.messages());
        }
    }
    assert_eq!(fmu.initialize(), OK, "{:?}", fmu.messages());
    let reals = reals::<M>();
    let inputs = real_inputs::<M>();
    if let Some(b) = barrier {
        b.wait(); // all eight step at the same time
    }
    let mut bits = Vec::with_capacity(STEPS * reals.len());
    let h = 1e-3;
    for n in 0..STEPS {
        let t = n as f64 * h;
        for (j, v) in inputs.iter().enumerate() {
            let apart = if n > STEPS / 2 { j as f64 * 0.002 } else { 0.0 };
            let wave = 0.01 * (t * (1.0 + k as f64) + j as f64).sin() + apart;
            let x0 = start_of(v);
            let y = if x0 == 0.0 { wave } else { x0 * (1.0 + wave) };
            let y = if v.range.contains(y) { y } else { x0 };
            assert_eq!(fmu.set(&v.name, y), OK, "{:?}", fmu.messages());
        }
        let status = fmu.do_step(t, h);
        assert_eq!(status, OK, "run {k}, step {n}: {:?}", fmu.messages());
        let (status, values) = fmu.get_reals(&reals);
        assert_eq!(status, OK);
        bits.extend(values.iter().map(|x| x.to_bits()));
    }
    bits
}

pub fn eight_instances_on_eight_threads_match_the_same_runs_one_after_another<M: Tested>() {
    let sequential: Vec<Vec<u64>> = (0..THREADS).map(|k| scenario::<M>(k, None)).collect();
    // The runs differ from each other, so a mix-up between instances shows.
    for k in 1..THREADS {
        assert_ne!(sequential[k], sequential[0], "runs {k} and 0 are identical: the comparison would prove nothing");
    }
    for round in 0..3 {
        let barrier = Barrier::new(THREADS);
        let concurrent: Vec<Vec<u64>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..THREADS)
                .map(|k| {
                    let barrier = &barrier;
                    s.spawn(move || scenario::<M>(k, Some(barrier)))
                })
                .collect();
            handles.into_iter().map(|h| h.join().expect("thread")).collect()
        });
        for k in 0..THREADS {
            assert!(concurrent[k] == sequential[k], "round {round}: run {k} on its own thread differs from the same run made alone");
        }
    }
}

pub fn start_values_do_not_depend_on_other_instances<M: Tested>() {
    // An instance changed and stepped must not change what a new one starts with.
    let first = settable_parameters::<M>().into_iter().find(|v| v.kind == Kind::Real).expect("a Real parameter");
    let a = Fmu::<M>::named("a");
    assert_eq!(a.set(&first.name, other_value(first, start_of(first))), OK);
    assert_eq!(a.initialize(), OK);
    assert_eq!(a.do_step(0.0, 0.1), OK);
    let b = Fmu::<M>::named("b");
    assert_eq!(b.initialize(), OK);
    assert_eq!(b.get(&first.name), Ok(start_of(first)));
}
