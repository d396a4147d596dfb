//! No global mutable state in a model's library, which could couple
//! instances on different threads: checked in its source and in its
//! compiled library (objdump reads the host's objects only, so tests/integration/cross.sh
//! skips these), with a control in the test kit's own tests showing that the
//! binary check does catch a static Atomic, a `static mut` and a thread-local.

use crate::Tested;
use std::path::{Path, PathBuf};
use std::process::Command;

/// The model's package folder: cargo runs its tests there.
fn package() -> String {
    std::env::var("CARGO_MANIFEST_DIR").expect("CARGO_MANIFEST_DIR (set by cargo test): the model's package")
}

/// Symbols of a crate that live in writable storage: `.data`, `.bss` and
/// their per-symbol sections, and thread-local `.tdata`/`.tbss`
/// (`.data.rel.ro` is read-only after relocation and fine).
fn mutable_statics(object: &Path, crate_prefix: &str) -> (Vec<String>, usize) {
    let out = Command::new("objdump").args(["-t", "-C"]).arg(object).output().expect("objdump (binutils) is needed for this test");
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

/// The rlibs this test binary was linked with: .../target/<profile>/deps/.
fn deps_dir() -> PathBuf {
    std::env::current_exe().unwrap().parent().unwrap().to_path_buf()
}

pub fn the_compiled_library_has_no_writable_statics<M: Tested>() {
    let krate = M::library();
    let rlib = deps_dir().join(format!("lib{krate}.rlib"));
    assert!(rlib.exists(), "{} is missing", rlib.display());
    let (found, ours) = mutable_statics(&rlib, &format!("{krate}::"));
    assert!(ours > 10, "objdump found only {ours} symbols of the crate in {}: the check would prove nothing", rlib.display());
    assert!(found.is_empty(), "global mutable state in the library: {found:#?}");
}

pub fn the_source_declares_no_mutable_statics<M: Tested>() {
    let src = Path::new(&package()).join("src");
    let mut found = Vec::new();
    let mut files = vec![src.clone()];
    let mut read = 0;
    while let Some(path) = files.pop() {
        if path.is_dir() {
            files.extend(std::fs::read_dir(&path).unwrap().map(|e| e.unwrap().path()));
            continue;
        }
        if path.extension().is_none_or(|e| e != "rs") {
            continue;
        }
        read += 1;
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
    assert!(read > 0, "no Rust source in {}: the check would prove nothing", src.display());
    assert!(found.is_empty(), "global mutable state declared in {}: {found:#?}", src.display());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_binary_check_catches_an_atomic_a_static_mut_and_a_thread_local() {
        // The control: a tiny crate with exactly the things the check must find.
        let dir = std::env::temp_dir().join(format!("fmi-testkit-static-control-{}", std::process::id()));
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
}
