//! Threads: FMI 2.0 lets an importer run different instances on different
//! threads at the same time. Eight instances stepping concurrently on eight
//! threads must give results bit-identical to the same eight runs made one
//! after another; and the library has no global mutable state that could
//! couple them (checked in the source and in the compiled library, with a
//! control that shows the binary check does catch a static Atomic, a
//! `static mut` and a thread-local).

type Fmu = fmi_testkit::Fmu<converting_span::ConvertingSpan>;

use fmi_core::description::{Kind, Start};
use fmi_core::Model;
use fmi_testkit::*;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::Barrier;

const THREADS: usize = 8;
const STEPS: usize = 3000;

fn description() -> &'static fmi_core::description::ModelDescription {
    <converting_span::ConvertingSpan as Model>::description()
}

/// Run `k`: its own span length, speeds and (if the model has one) solver,
/// with a speed ramp and a draw step, returning the bits of every Real after
/// every step.
fn scenario(k: usize, barrier: Option<&Barrier>) -> Vec<u64> {
    let fmu = Fmu::named(&format!("thread{k}"));
    assert_eq!(fmu.set_real("L", 0.5 + 0.25 * k as f64), OK);
    if let Some(v) = description().variable_by_name("solver") {
        if let Kind::Enumeration { values, .. } = v.kind {
            let solver = values[k % values.len()];
            assert_eq!(unsafe { fmi2SetInteger(fmu.c, &v.vr, 1, &solver) }, OK, "{:?}", fmu.messages());
        }
    }
    assert_eq!(fmu.initialize(), OK, "{:?}", fmu.messages());
    let reals: Vec<u32> =
        description().variables.iter().filter(|v| v.kind == Kind::Real).map(|v| v.vr).collect();
    if let Some(b) = barrier {
        b.wait(); // all eight step at the same time
    }
    let mut bits = Vec::with_capacity(STEPS * reals.len());
    let h = 1e-3;
    for n in 0..STEPS {
        let t = n as f64 * h;
        let speed = 5.0 + k as f64 * 0.5 + 2.0 * (t * (1.0 + k as f64)).sin();
        let draw = if n > STEPS / 2 { 1.002 } else { 1.0 };
        assert_eq!(fmu.set_real("web_a.v", speed), OK);
        assert_eq!(fmu.set_real("web_b.v", speed * draw), OK);
        let status = fmu.do_step(t, h);
        assert_eq!(status, OK, "run {k}, step {n}: {:?}", fmu.messages());
        let (status, values) = fmu.get_reals(&reals);
        assert_eq!(status, OK);
        bits.extend(values.iter().map(|x| x.to_bits()));
    }
    bits
}

#[test]
fn eight_instances_on_eight_threads_match_the_same_runs_one_after_another() {
    let sequential: Vec<Vec<u64>> = (0..THREADS).map(|k| scenario(k, None)).collect();
    // The runs differ from each other, so a mix-up between instances shows.
    for k in 1..THREADS {
        assert_ne!(sequential[k], sequential[0], "runs {k} and 0 are identical: the comparison would prove nothing");
    }
    for round in 0..3 {
        let barrier = Barrier::new(THREADS);
        let concurrent: Vec<Vec<u64>> = std::thread::scope(|s| {
            let handles: Vec<_> = (0..THREADS).map(|k| {
                let barrier = &barrier;
                s.spawn(move || scenario(k, Some(barrier)))
            }).collect();
            handles.into_iter().map(|h| h.join().expect("thread")).collect()
        });
        for k in 0..THREADS {
            assert!(
                concurrent[k] == sequential[k],
                "round {round}: run {k} on its own thread differs from the same run made alone"
            );
        }
    }
}

#[test]
fn start_values_do_not_depend_on_other_instances() {
    // An instance changed and stepped must not change what a new one starts with.
    let a = Fmu::named("a");
    assert_eq!(a.set_real("L", 3.0), OK);
    assert_eq!(a.initialize(), OK);
    assert_eq!(a.do_step(0.0, 0.1), OK);
    let b = Fmu::named("b");
    assert_eq!(b.initialize(), OK);
    let Start::Real(start) = description().variable_by_name("L").unwrap().start else { panic!("L has a Real start") };
    assert_eq!(b.get_real("L"), (OK, start));
}

// ------------------------------------------------------ no global mutable state

/// Symbols of a crate that live in writable storage: `.data`, `.bss` and
/// their per-symbol sections, and thread-local `.tdata`/`.tbss`
/// (`.data.rel.ro` is read-only after relocation and fine).
fn mutable_statics(object: &Path, crate_prefix: &str) -> (Vec<String>, usize) {
    let out = Command::new("objdump")
        .args(["-t", "-C"])
        .arg(object)
        .output()
        .expect("objdump (binutils) is needed for this test");
    let text = String::from_utf8_lossy(&out.stdout);
    let mut found = Vec::new();
    let mut ours = 0;
    for line in text.lines() {
        // address, flags (7 columns), section, size, name
        if line.len() < 26 {
            continue;
        }
        let rest = &line[25..];
        let mut parts = rest.split_whitespace();
        let (Some(section), Some(_size)) = (parts.next(), parts.next()) else { continue };
        let name = parts.collect::<Vec<_>>().join(" ");
        if !name.starts_with(crate_prefix) {
            continue;
        }
        ours += 1;
        let writable = (section.starts_with(".data") && !section.starts_with(".data.rel.ro"))
            || section.starts_with(".bss")
            || section.starts_with(".tdata")
            || section.starts_with(".tbss");
        if writable {
            found.push(format!("{name} in {section}"));
        }
    }
    (found, ours)
}

/// The rlib this test binary was linked with: .../target/<profile>/deps/.
fn deps_dir() -> PathBuf {
    std::env::current_exe().unwrap().parent().unwrap().to_path_buf()
}

#[test]
fn the_compiled_library_has_no_writable_statics() {
    let rlib = deps_dir().join("libconverting_span.rlib");
    assert!(rlib.exists(), "{} is missing", rlib.display());
    let (found, ours) = mutable_statics(&rlib, "converting_span::");
    assert!(ours > 10, "objdump found only {ours} symbols of the crate in {}: the check would prove nothing", rlib.display());
    assert!(found.is_empty(), "global mutable state in the library: {found:#?}");
}

#[test]
fn the_binary_check_catches_an_atomic_a_static_mut_and_a_thread_local() {
    // The control: a tiny crate with exactly the things the check must find.
    let dir = std::env::temp_dir().join(format!("converting-span-static-control-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let source = dir.join("control.rs");
    std::fs::write(
        &source,
        r#"
        use std::sync::atomic::{AtomicUsize, Ordering};
        pub static COUNTER: AtomicUsize = AtomicUsize::new(0);
        pub static mut RAW: [u64; 4] = [1, 2, 3, 4];
        thread_local! { pub static LOCAL: std::cell::Cell<u64> = const { std::cell::Cell::new(7) }; }
        pub static TABLE: [&str; 2] = ["read", "only"];
        pub fn touch() -> usize {
            LOCAL.with(|l| l.set(l.get() + 1));
            COUNTER.fetch_add(TABLE.len(), Ordering::Relaxed)
        }
        "#,
    )
    .unwrap();
    let object = dir.join("control.o");
    let status = Command::new(std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into()))
        .args(["--crate-type", "lib", "--crate-name", "control", "--edition", "2021", "-O", "--emit", "obj", "-o"])
        .arg(&object)
        .arg(&source)
        .status()
        .expect("rustc");
    assert!(status.success());
    let (found, _) = mutable_statics(&object, "control::");
    let _ = std::fs::remove_dir_all(&dir);
    for name in ["control::COUNTER", "control::RAW", "LOCAL"] {
        assert!(found.iter().any(|f| f.contains(name)), "the check missed {name}: {found:?}");
    }
    assert!(!found.iter().any(|f| f.contains("TABLE")), "the check flagged read-only data: {found:?}");
}

#[test]
fn the_source_declares_no_mutable_statics() {
    let mut found = Vec::new();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = vec![src];
    while let Some(path) = files.pop() {
        if path.is_dir() {
            files.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
            continue;
        }
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        for (n, line) in std::fs::read_to_string(&path).unwrap().lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            let interior = ["Atomic", "Mutex", "RwLock", "Cell<", "OnceLock", "OnceCell", "LazyLock", "Lazy<", "Once"];
            let bad = code.contains("static mut ")
                || code.contains("thread_local!")
                || (code.contains("static ") && interior.iter().any(|t| code.contains(t)));
            if bad {
                found.push(format!("{}:{}: {}", path.display(), n + 1, line.trim()));
            }
        }
    }
    assert!(found.is_empty(), "global mutable state declared in src/: {found:#?}");
}
