//! The panic boundary of the FMI layer (fmi/testkit) on the Line's library:
//! `cargo test --release --manifest-path models/line/Cargo.toml --features test-hooks --target-dir target/line-hooks --test panic_boundary`
//! (a separate target directory, so that the feature never reaches a shipped library).

mod common;
use common::TestedLine;

fmi_testkit::panic_boundary_tests!(TestedLine);
