#!/usr/bin/env bash
# Every test: Rust tests of the model core and of the C API, then the packaged
# FMU through a C importer and through FMPy (pytest).
set -euo pipefail
source "$(dirname "$0")/../fmu/env.sh"
cd "$ROOT"
cargo test --release --quiet
# The Roller's C API: the same library built with the feature that exports it.
cargo test --release --quiet --features roller --target-dir target/roller --test roller
python3 fmu/package.py
"$PY" -m pytest tests/python -q
# Hardening, CI size (tests/hardening.sh --full for the long runs): the
# portable .so, the panic boundary, the fuzzed C API, AddressSanitizer and
# valgrind, dlopen/dlclose cycles.
bash tests/hardening.sh
