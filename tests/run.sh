#!/usr/bin/env bash
# Every test: Rust tests of the models, the FMI layer and its conformance suite,
# then the packaged FMUs through a C importer, FMPy, fmi-sim and libcosim, and
# webline's own tests (pytest), hardening, and the Windows and ARM64 binaries
# under Wine and QEMU (tests/integration/cross.sh).
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
# Every package of the workspace but the fuzz harness and targets (tests/integration/hardening.sh
# builds them with their own profile): the models, the FMI layer and its conformance suite, the
# generator, the solvers.
stage "Rust tests" cargo test --profile cross-test --quiet --workspace \
    --exclude fmi-fuzz --exclude converting-span-fuzz --exclude roller-fuzz
# The Line FMU's crate: a workspace of its own, built in a folder of its own (models/line/Cargo.toml).
stage "Rust tests of the Line" cargo test --profile cross-test --quiet \
    --manifest-path models/line/Cargo.toml --target-dir target/line
stage "packaging" python3 fmu/package.py
stage "compatibility files" "$PY" fmu/compat.py out
# The webline wheel, which tests/integration/python/test_wheel.py installs into a venv of its own.
stage "wheel" "$PY" fmu/wheel.py
export CONVERTING_SPAN_PACKAGED=1 # hardening.sh and cross.sh need not package again
# Hardening and the other platforms run beside pytest: they spend their time in cargo and
# the emulators, pytest in one Python process, so side by side they keep both cores busy.
# (Packaging again, as both scripts do, rewrites no FMU whose bytes are the same.)
BESIDE_LOG=target/hardening-and-platforms.log
mkdir -p target
t_beside=$SECONDS
setsid bash -c 'bash tests/integration/hardening.sh "$@" && bash tests/integration/cross.sh "$@"' beside "${FULL[@]}" > "$BESIDE_LOG" 2>&1 &
BESIDE=$!
trap 'kill -- -"$BESIDE" 2>/dev/null || true' EXIT
# --rootdir: webline/pyproject.toml would otherwise become the rootdir (it is among the
# arguments' folders), and the test ids of tests/integration/python would lose their folder.
stage "pytest: FMPy, C importer, fmi-sim, libcosim, README, set-up, webline" \
    "$PY" -m pytest --rootdir "$ROOT" tests/integration/python tests/validation fmu/tests webline/tests -q --durations=25
if ! wait "$BESIDE"; then
    tail -60 "$BESIDE_LOG"
    echo "tests/run.sh: tests/integration/hardening.sh or cross.sh failed (beside pytest); their whole log: $BESIDE_LOG"
    exit 1
fi
trap - EXIT
TIMES+=("$(printf '%5d s  %s' $((SECONDS - t_beside)) "hardening and other platforms, beside pytest (log: $BESIDE_LOG)")")
echo
cat target/hardening/summary.txt target/platforms/summary.txt
echo
echo "tests/run.sh ${FULL[*]}: every test passed in $((SECONDS - START)) s"
printf '%s\n' "${TIMES[@]}"
