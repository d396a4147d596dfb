#!/usr/bin/env bash
# The other platforms' tests: Windows x64 under Wine, ARM64 Linux under QEMU
# (tests/run.sh runs this; docs/platforms.md).
#
#   bash tests/integration/cross.sh [--full]
#
#   1. the Rust tests of each target under its emulator (cargo's
#      CARGO_TARGET_<TRIPLE>_RUNNER, set by fmu/cross_toolchain.sh): what meets
#      the platform: the unit tests of the model, the FMI layer and the solvers,
#      the span's C API, its web records (files and paths), the FMI layer's
#      conformance suite and panic boundary on both models (but its objdump
#      checks, `statics::`, which read only the host's objects), the Roller's
#      profiles; on win64 in CI, on aarch64-linux (whose system is Linux's, as
#      here) with --full. --full adds the tests of pure arithmetic (the span
#      and the Roller against exact solutions, the solvers, the hard cases),
#      whose results step 3 compares bit for bit anyway
#   2. each model's fuzz target (the harness of fmi/fuzz) built for each target: FUZZ_SEQUENCES each,
#      and FUZZ3_SEQUENCES through its FMI 3 mode (20,000 and 5,000; --full:
#      200,000 and 50,000); for the Line (its test line), its fuzz target
#      line-fuzz: LINE_FUZZ_SEQUENCES and LINE_FUZZ3_SEQUENCES (300 and 100;
#      only with --full: 20,000 and 5,000; in CI the Line's library runs step 3)
#   3. tests/integration/cross/test_platforms.py: importer.c on every platform's binary in
#      the packaged FMUs, bit for bit against Linux x86-64; importer3.c's scene
#      through the FMI 3 FMU likewise
#
# Each target's std is in rustc-web's sysroot (fmu/cross_toolchain.sh builds it
# there once). The tests and the fuzz targets build into target/cross-test
# (profile cross-test, with the test hooks: apart from the shipped libraries of
# target/cross); the Line's fuzz target, of another workspace, into target/cross-test-line.
# A summary is printed at the end and written to target/platforms/summary.txt.
set -euo pipefail
source "$(dirname "$0")/../../fmu/env.sh"
source "$ROOT/tests/tools.sh"
cd "$ROOT"
export RUST_BACKTRACE=0 # the panic-boundary tests panic on purpose
case "${1:-}" in
    --full) FULL=1 FUZZ_SEQUENCES="${FUZZ_SEQUENCES:-200000}" FUZZ3_SEQUENCES="${FUZZ3_SEQUENCES:-50000}"
        LINE_FUZZ_SEQUENCES="${LINE_FUZZ_SEQUENCES:-20000}" LINE_FUZZ3_SEQUENCES="${LINE_FUZZ3_SEQUENCES:-5000}" ;;
    "") FULL=0 FUZZ_SEQUENCES="${FUZZ_SEQUENCES:-20000}" FUZZ3_SEQUENCES="${FUZZ3_SEQUENCES:-5000}" ;;
    *) echo "usage: $0 [--full]" >&2; exit 2 ;;
esac
OUT=target/platforms
mkdir -p "$OUT"
SUMMARY="$OUT/summary.txt"
: > "$SUMMARY"
note() { echo "$*" | tee -a "$SUMMARY"; }
START=$SECONDS
cross() { # cargo COMMAND ARGS...: rustc-web's cargo, whose sysroot has each target's std
    "$CROSS_CARGO" "$1" --quiet "${@:2}"
}

declare -A NAME=([x86_64-pc-windows-gnu]="win64 (Wine)" [aarch64-unknown-linux-gnu]="aarch64-linux (QEMU)")
# Each model's fuzz target (fuzz/, models/roller/fuzz): the harness of fmi/fuzz on that model.
declare -A MODEL_NAME=([span]=ConvertingSpan [roller]=Roller)
declare -A FUZZ_TARGET=([span]=converting-span-fuzz [roller]=roller-fuzz)
SPAN_TESTS=(--test span_c_api --test conformance --test panic_boundary --test records)
ROLLER_TESTS=(--test conformance --test panic_boundary --test profiles --test instance_profiles)
if [ "$FULL" = 1 ]; then
    SPAN_TESTS+=(--test span_exact --test span_solvers --test hard_cases)
    ROLLER_TESTS=(--tests)
fi
for target in x86_64-pc-windows-gnu aarch64-unknown-linux-gnu; do
    runner_var="CARGO_TARGET_$(echo "$target" | tr 'a-z-' 'A-Z_')_RUNNER"
    if [ "$FULL" = 1 ] || [ "$target" = x86_64-pc-windows-gnu ]; then
        echo "== Rust tests for $target under ${NAME[$target]}"
        t0=$SECONDS
        cross test --profile cross-test --target-dir target/cross-test --features test-hooks --target "$target" \
            -p converting-span -p solver -p fmi-core --lib "${SPAN_TESTS[@]}" \
            -- --skip statics:: 2>&1 | tee "$OUT/rust-$target.log" | grep -E "^test result|FAILED|panicked" || true
        cross test --profile cross-test --target-dir target/cross-test --features test-hooks --target "$target" -p roller --lib "${ROLLER_TESTS[@]}" \
            -- --skip statics:: 2>&1 | tee -a "$OUT/rust-$target.log" | grep -E "^test result|FAILED|panicked" || true
        if grep -q "FAILED\|error\[" "$OUT/rust-$target.log" || ! grep -q "^test result: ok" "$OUT/rust-$target.log"; then
            echo "Rust tests failed for $target: $OUT/rust-$target.log"; exit 1
        fi
        passed=$(grep -o "^test result: ok. [0-9]* passed" "$OUT/rust-$target.log" | awk '{s += $4} END {print s}')
        note "Rust tests on ${NAME[$target]}: $passed passed in $((SECONDS - t0)) s"
    fi

    for model in span roller; do
        echo "== fuzz harness for $target, ${MODEL_NAME[$model]}: $FUZZ_SEQUENCES sequences"
        t0=$SECONDS
        # the tests' target directory: std and the FMU are already built there
        cross build --profile cross-test --target-dir target/cross-test --target "$target" -p "${FUZZ_TARGET[$model]}" --bin fuzz_sequences
        exe="target/cross-test/$target/cross-test/fuzz_sequences"
        [ -f "$exe.exe" ] && exe="$exe.exe"
        log="$OUT/fuzz-$model-$target.log"
        "${!runner_var}" "$exe" --sequences "$FUZZ_SEQUENCES" --seed 3 | tr -d '\r' | tee "$log"
        grep -q "^$FUZZ_SEQUENCES passed, 0 failed" "$log" || { echo "fuzz violations on $target"; exit 1; }
        note "fuzz ${MODEL_NAME[$model]} on ${NAME[$target]}: $(grep '^fuzzed' "$log"), 0 violations ($((SECONDS - t0)) s with the build)"
        t0=$SECONDS
        log="$OUT/fuzz3-$model-$target.log"
        "${!runner_var}" "$exe" --fmi3 --sequences "$FUZZ3_SEQUENCES" --seed 3 | tr -d '\r' | tee "$log"
        grep -q "^$FUZZ3_SEQUENCES passed, 0 failed" "$log" || { echo "FMI 3 fuzz violations on $target"; exit 1; }
        note "fuzz (FMI 3) ${MODEL_NAME[$model]} on ${NAME[$target]}: $(grep '^fuzzed' "$log"), 0 violations ($((SECONDS - t0)) s)"
    done

    [ "$FULL" = 1 ] || continue
    echo "== fuzz harness for $target, the Line: $LINE_FUZZ_SEQUENCES sequences, FMI 3: $LINE_FUZZ3_SEQUENCES"
    t0=$SECONDS
    # line-fuzz, a member of the Line's own workspace (in the main one the span's `fmu`
    # feature would be unified into the Line), in a target directory of its own: sharing the
    # tests' one, the two workspaces overwrite each other's fmi_core (rustc then finds two).
    cross build --profile cross-test --manifest-path models/line/Cargo.toml --target-dir target/cross-test-line \
        --target "$target" -p line-fuzz --bin fuzz_sequences
    exe="target/cross-test-line/$target/cross-test/fuzz_sequences"
    [ -f "$exe.exe" ] && exe="$exe.exe"
    for api in 2 3; do
        if [ "$api" = 2 ]; then n=$LINE_FUZZ_SEQUENCES flag="" log="$OUT/fuzz-line-$target.log"
        else n=$LINE_FUZZ3_SEQUENCES flag="--fmi3" log="$OUT/fuzz3-line-$target.log"; fi
        # shellcheck disable=SC2086
        "${!runner_var}" "$exe" $flag --sequences "$n" --seed 3 --strict | tr -d '\r' | tee "$log"
        grep -q "^$n passed, 0 failed" "$log" || { echo "Line fuzz violations on $target (FMI $api)"; exit 1; }
    done
    note "fuzz Line on ${NAME[$target]}: $(grep '^fuzzed' "$OUT/fuzz-line-$target.log"); $(grep '^fuzzed' "$OUT/fuzz3-line-$target.log"); 0 violations ($((SECONDS - t0)) s with the build)"
done

echo "== importer.c on every platform's binary"
t0=$SECONDS
[ -n "${CONVERTING_SPAN_PACKAGED:-}" ] || python3 fmu/package.py # tests/run.sh has packaged
"$PY" -m pytest tests/integration/cross -q -p no:cacheprovider
note "importer.c and importer3.c scenes on win64, aarch64-linux, linux64: passed in $((SECONDS - t0)) s"
note "cross-platform tests took $((SECONDS - START)) s"
echo
cat "$SUMMARY"
