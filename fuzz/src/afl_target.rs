//! The span's coverage-guided target for cargo-afl: each input is one call
//! sequence (see fmi/fuzz); a broken rule panics, which AFL++ records as a
//! crash. `fuzz_nohook!` leaves the panic hook alone, so the panics that the
//! FMU itself catches (the test hook's) are not taken for crashes.
//!
//! Build and run: bash tests/integration/hardening.sh --afl SECONDS
fn main() {
    let span = fmi_fuzz::Fuzzed::of::<converting_span::ConvertingSpan>(concat!(env!("CARGO_MANIFEST_DIR"), "/../resources/"));
    afl::fuzz_nohook!(|data: &[u8]| {
        if let Err(v) = fmi_fuzz::run(&span, fmi_fuzz::Api::Fmi2, data) {
            panic!("violation: {}", v.0);
        }
    });
}
