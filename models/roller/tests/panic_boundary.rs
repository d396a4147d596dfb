//! The panic boundary of the FMI layer (fmi/testkit) on the Roller's library:
//! `cargo test --profile cross-test -p roller --features test-hooks --target-dir target/test-hooks --test panic_boundary`
//! (a separate target directory, so that the feature never reaches a shipped library).

fmi_testkit::panic_boundary_tests!(roller::Roller);
