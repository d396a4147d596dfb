//! The Roller's fuzz target: the harness's driver on the Roller, with the
//! resources its FMU ships (see fmi/fuzz).

fn main() {
    let resources = concat!(env!("CARGO_MANIFEST_DIR"), "/../resources/");
    fmi_fuzz::driver::main(&fmi_fuzz::Fuzzed::of::<roller::Roller>(resources));
}
