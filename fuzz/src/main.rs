//! The span's fuzz target: the harness's driver on ConvertingSpan, with the
//! resources its FMU ships (see fmi/fuzz).

/// The span's resources/ folder, at the root.
const RESOURCES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../resources/");

fn main() {
    fmi_fuzz::driver::main(&fmi_fuzz::Fuzzed::of::<converting_span::ConvertingSpan>(RESOURCES));
}
