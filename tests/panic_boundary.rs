//! The panic boundary of the FMI layer (fmi/testkit: conformance::panic_boundary)
//! on the span's library. Needs the test-only panic hook:
//! `cargo test --profile cross-test --features test-hooks --target-dir target/test-hooks --test panic_boundary`
//! (tests/run.sh uses a separate target directory, so that the feature never
//! reaches the library that fmu/package.py ships).

fmi_testkit::panic_boundary_tests!(converting_span::ConvertingSpan);
