#!/usr/bin/env bash
# Every test: Rust tests of the models, the FMI layer and its conformance suite,
# then the packaged FMUs through a C importer, FMPy, fmi-sim and libcosim, and
# webline's own tests (pytest), hardening, and the Windows and ARM64 binaries
# under Wine and QEMU (tests/cross.sh).
#
#   bash tests/run.sh           what CI runs (docs/testing.md: under 15 minutes with the tools cached)
#   bash tests/run.sh --full    the same with the long runs: hardening's million fuzzed
#                               sequences and its long sanitizer runs, 200,000 fuzzed
#                               sequences per other platform
set -euo pipefail
FULL=()
case "${1:-}" in
    --full) FULL=(--full) ;;
    "") ;;
    *) echo "usage: bash tests/run.sh [--full]" >&2; exit 2 ;;
esac
source "$(dirname "$0")/../fmu/env.sh"
source "$ROOT/tests/tools.sh"
cd "$ROOT"
START=$SECONDS
TIMES=()
stage() { # NAME COMMAND...: runs it and notes how long it took
    local name="$1" t0=$SECONDS
    shift
    "$@"
    TIMES+=("$(printf '%5d s  %s' $((SECONDS - t0)) "$name")")
}
# Every package of the workspace but the fuzz harness (tests/hardening.sh builds it with
# its own profile): the models, the FMI layer and its conformance suite, the generator, the solvers.
stage "Rust tests" cargo test --profile cross-test --quiet --workspace --exclude fmi-fuzz
# The Line FMU's crate: a workspace of its own, built in a folder of its own (models/line/Cargo.toml).
stage "Rust tests of the Line" cargo test --profile cross-test --quiet \
    --manifest-path models/line/Cargo.toml --target-dir target/line
stage "packaging" python3 fmu/package.py
stage "compatibility files" "$PY" fmu/compat.py out
# --rootdir: webline/pyproject.toml would otherwise become the rootdir (it is among the
# arguments' folders), and the test ids of tests/python would lose their folder.
stage "pytest: FMPy, C importer, fmi-sim, libcosim, README, set-up, webline" \
    "$PY" -m pytest --rootdir "$ROOT" tests/python fmu/tests webline/tests -q
# Hardening (--full for the long runs): the portable .so, the panic boundary,
# the fuzzed C API of both models, AddressSanitizer and valgrind, dlopen/dlclose cycles.
stage "hardening" bash tests/hardening.sh "${FULL[@]}"
# Windows x64 under Wine, ARM64 Linux under QEMU: Rust tests, fuzzing, the C
# importer on each binary against Linux x86-64's bits (docs/platforms.md).
stage "other platforms" bash tests/cross.sh "${FULL[@]}"
echo
echo "tests/run.sh ${FULL[*]}: every test passed in $((SECONDS - START)) s"
printf '%s\n' "${TIMES[@]}"
