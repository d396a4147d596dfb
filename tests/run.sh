#!/usr/bin/env bash
# Every test: Rust tests of the model core and of the C API, then the packaged
# FMU through a C importer, FMPy, fmi-sim and libcosim, and webline's own tests
# (pytest), hardening, and the Windows and ARM64 binaries under Wine and QEMU
# (tests/cross.sh).
set -euo pipefail
source "$(dirname "$0")/../fmu/env.sh"
source "$ROOT/tests/tools.sh"
cd "$ROOT"
# Every package of the workspace but the fuzz harness (tests/hardening.sh builds it with
# its own profile): the span and the Roller (model and C API),
# the FMI layer, the generator, the solvers.
cargo test --release --quiet --workspace --exclude fmi-fuzz
python3 fmu/package.py
"$PY" fmu/compat.py out
# --rootdir: webline/pyproject.toml would otherwise become the rootdir (it is among the
# arguments' folders), and the test ids of tests/python would lose their folder.
"$PY" -m pytest --rootdir "$ROOT" tests/python fmu/tests webline/tests -q
# Hardening, CI size (tests/hardening.sh --full for the long runs): the
# portable .so, the panic boundary, the fuzzed C API, AddressSanitizer and
# valgrind, dlopen/dlclose cycles.
bash tests/hardening.sh
# Windows x64 under Wine, ARM64 Linux under QEMU: Rust tests, fuzzing, the C
# importer on each binary against Linux x86-64's bits (docs/platforms.md).
bash tests/cross.sh
