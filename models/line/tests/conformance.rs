//! The conformance suite of the FMI layer (fmi/testkit), run on the Line's
//! library over its test line (resources/: an unwinder and a winder under
//! tension control, an idler on a load cell, a dancer between two spans of
//! variable length, a pull roll whose speed steps at 20 ms; README.md there).
//! `TestedLine` (tests/common) stands in for the Line, whose interface the
//! library builds from line.json when it instantiates.

mod common;
use common::TestedLine;

fmi_testkit::conformance_tests!(TestedLine);
