//! Property-based driver of the fuzz harness: random byte strings from a
//! seeded generator, one call sequence each (see lib.rs), on all cores. The
//! `main` of every model's fuzz target (`fuzz_sequences`):
//!
//!   fuzz_sequences [--fmi3] [--sequences N] [--seed S] [--threads T] [--strict] [--min-transitions N]
//!   fuzz_sequences [--fmi3] --replay FILE...  (one sequence per file, e.g. AFL crashes)
//!
//! `--fmi3` makes the calls through the FMI 3.0 C API instead of FMI 2.0's.
//!
//! Sequence k of a run is a function of (seed, k) alone, so a failure is
//! reproduced by its file or by `--seed S --only k`. Exits 1 on a violation
//! (and with --strict also on a finding), printing the call and the rule;
//! with `--min-transitions N` also where the contact of the fuzz target
//! (`Fuzzed::contact`) made fewer than N stick<->slide transitions in
//! Co-Simulation or in Model Exchange.

use crate::{run, Api, Finding, Fuzzed, Outcome};
use std::collections::BTreeMap;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

fn splitmix(state: &mut u64) -> u64 {
    *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// The bytes of sequence `k`: 16 to 1039 random bytes.
fn sequence(seed: u64, k: u64) -> Vec<u8> {
    let mut s = seed ^ k.wrapping_mul(0xd1b5_4a32_d192_ed03);
    let n = 16 + (splitmix(&mut s) % 1024) as usize;
    let mut out = Vec::with_capacity(n + 8);
    while out.len() < n {
        out.extend_from_slice(&splitmix(&mut s).to_le_bytes());
    }
    out.truncate(n);
    out
}

#[derive(Default)]
struct Totals {
    sequences: u64,
    calls: u64,
    statuses: [u64; 4],
    steps_ok: u64,
    panics_caught: u64,
    deserialized_ok: u64,
    by_state: [u64; 8],
    random: [u64; 2],
    transitions: [u64; 2],
    /// Sequences whose Model Exchange instance went through event mode and integrator steps.
    me_through: u64,
    events: [u64; 3],
    findings: BTreeMap<Finding, (u64, String)>,
}

impl Totals {
    fn add(&mut self, o: Outcome, k: u64) {
        self.sequences += 1;
        self.calls += o.calls;
        for k in 0..4 {
            self.statuses[k] += o.statuses[k];
        }
        self.steps_ok += o.steps_ok;
        self.panics_caught += o.panics_caught;
        self.deserialized_ok += o.deserialized_ok;
        add(&mut self.by_state, &o.by_state);
        add(&mut self.random, &o.random);
        add(&mut self.transitions, &o.transitions);
        add(&mut self.events, &o.events);
        self.me_through += (o.me_event && o.me_step) as u64;
        let mut seen = std::collections::BTreeSet::new();
        for (f, example) in o.findings {
            if seen.insert(f.clone()) {
                let e = self
                    .findings
                    .entry(f)
                    .or_insert((0, format!("sequence {k}: {example}")));
                e.0 += 1;
            }
        }
    }
    fn merge(&mut self, other: Totals) {
        self.sequences += other.sequences;
        self.calls += other.calls;
        for k in 0..4 {
            self.statuses[k] += other.statuses[k];
        }
        self.steps_ok += other.steps_ok;
        self.panics_caught += other.panics_caught;
        self.deserialized_ok += other.deserialized_ok;
        add(&mut self.by_state, &other.by_state);
        add(&mut self.random, &other.random);
        add(&mut self.transitions, &other.transitions);
        add(&mut self.events, &other.events);
        self.me_through += other.me_through;
        for (f, (n, example)) in other.findings {
            let e = self.findings.entry(f).or_insert((0, example));
            e.0 += n;
        }
    }
}

fn add<const N: usize>(to: &mut [u64; N], from: &[u64; N]) {
    for (a, b) in to.iter_mut().zip(from) {
        *a += b;
    }
}

/// Percent of `part` in `whole`.
fn share(part: u64, whole: u64) -> f64 {
    100.0 * part as f64 / whole.max(1) as f64
}

/// Runs the driver on `model` with the program's arguments; exits with its status.
pub fn main(model: &Fuzzed) {
    // The FMU catches the panics of its test hook; the default hook would
    // print each one. The harness reports violations itself.
    std::panic::set_hook(Box::new(|_| {}));
    let args: Vec<String> = std::env::args().skip(1).collect();
    let value = |name: &str| {
        args.iter()
            .position(|a| a == name)
            .map(|i| args[i + 1].clone())
    };
    let strict = args.iter().any(|a| a == "--strict");
    let api = if args.iter().any(|a| a == "--fmi3") { Api::Fmi3 } else { Api::Fmi2 };
    if let Some(i) = args.iter().position(|a| a == "--replay") {
        let mut failed = false;
        for file in &args[i + 1..] {
            let bytes = std::fs::read(file).expect("read the sequence file");
            match run(model, api, &bytes) {
                Ok(o) => println!("{file}: ok, {} calls, findings {:?}", o.calls, o.findings),
                Err(v) => {
                    println!("{file}: VIOLATION {}", v.0);
                    failed = true;
                }
            }
        }
        std::process::exit(failed as i32);
    }
    let n: u64 = value("--sequences").map_or(10_000, |v| {
        v.replace('_', "").parse().expect("--sequences N")
    });
    let seed: u64 = value("--seed").map_or(0x5eed, |v| v.parse().expect("--seed S"));
    let only: Option<u64> = value("--only").map(|v| v.parse().expect("--only K"));
    let threads: u64 = value("--threads")
        .map(|v| v.parse().expect("--threads T"))
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get() as u64));
    let failed_dir = value("--failures").unwrap_or_else(|| "target/fuzz/failures".into());
    let min_transitions: Option<u64> = value("--min-transitions").map(|v| v.parse().expect("--min-transitions N"));

    let start = Instant::now();
    let stop = AtomicBool::new(false);
    let indices: Vec<u64> = match only {
        Some(k) => vec![k],
        None => (0..n).collect(),
    };
    let mut totals = Totals::default();
    let mut violations = Vec::new();
    let work = |t: u64, threads: u64| {
        let mut totals = Totals::default();
        let mut violations = Vec::new();
        for &k in indices.iter().skip(t as usize).step_by(threads as usize) {
            if stop.load(Ordering::Relaxed) {
                break;
            }
            let bytes = sequence(seed, k);
            match run(model, api, &bytes) {
                Ok(o) => totals.add(o, k),
                Err(v) => {
                    std::fs::create_dir_all(&failed_dir).ok();
                    let file = format!("{failed_dir}/seed{seed}-seq{k}.bin");
                    std::fs::write(&file, &bytes).ok();
                    violations.push(format!(
                        "sequence {k} (seed {seed}, saved as {file}): {}",
                        v.0
                    ));
                    stop.store(true, Ordering::Relaxed);
                }
            }
        }
        (totals, violations)
    };
    if threads == 1 {
        // On the main thread (no thread handles for valgrind to report).
        let (t, v) = work(0, 1);
        totals.merge(t);
        violations.extend(v);
    } else {
        std::thread::scope(|scope| {
            let workers: Vec<_> = (0..threads)
                .map(|t| {
                    let work = &work;
                    scope.spawn(move || work(t, threads))
                })
                .collect();
            for w in workers {
                let (t, v) = w.join().expect("worker");
                totals.merge(t);
                violations.extend(v);
            }
        });
    }
    let secs = start.elapsed().as_secs_f64();
    let t = &totals;
    println!(
        "fuzzed {} sequences ({} calls, {api:?}) in {secs:.1} s on {threads} threads: {:.0} sequences/s",
        t.sequences,
        t.calls,
        t.sequences as f64 / secs
    );
    println!(
        "  statuses: {} OK, {} Warning, {} Discard, {} Error; {} successful steps; {} panics caught; {} states deserialized",
        t.statuses[0], t.statuses[1], t.statuses[2], t.statuses[3], t.steps_ok, t.panics_caught, t.deserialized_ok
    );
    let b = t.by_state;
    let on_instances: u64 = b.iter().sum();
    println!(
        "  calls on instances by state: {} instantiated, {} initialization mode, {} step complete, {} step failed, {} terminated, {} error ({:.1} %), {} event mode, {} continuous-time mode",
        b[0], b[1], b[2], b[3], b[4], b[5], share(b[5], on_instances), b[6], b[7]
    );
    println!(
        "  random calls on instances: {}, {:.1} % of them in the error state",
        t.random[0],
        share(t.random[1], t.random[0])
    );
    println!(
        "  Model Exchange: {} sequences ({:.1} %) took an instance through event mode and integrator steps; events after initialization: {} time, {} state, {} step",
        t.me_through,
        share(t.me_through, t.sequences),
        t.events[0],
        t.events[1],
        t.events[2]
    );
    if let Some(contact) = model.contact {
        println!(
            "  stick<->slide transitions of {}: {} in Co-Simulation, {} in Model Exchange",
            contact.output, t.transitions[0], t.transitions[1]
        );
    }
    for (f, (count, example)) in &t.findings {
        println!("  finding {f:?}: in {count} sequences, e.g. {example}");
    }
    for v in &violations {
        println!("VIOLATION in {v}");
    }
    let mut failed = !violations.is_empty() || (strict && !t.findings.is_empty());
    if let Some(least) = min_transitions {
        for (k, interface) in ["Co-Simulation", "Model Exchange"].iter().enumerate() {
            if t.transitions[k] < least {
                println!("TOO FEW stick<->slide transitions in {interface}: {}, required {least} (--min-transitions)", t.transitions[k]);
                failed = true;
            }
        }
    }
    println!("{} passed, {} failed", t.sequences, violations.len());
    std::process::exit(failed as i32);
}
