#!/usr/bin/env bash
# Hardening checks of the FMU binary: fuzzed C API, memory checks, panic
# boundary, portable binary. Threads and global state are in the conformance
# suite (fmi/testkit: its threads and statics modules; cargo test).
#
#   bash tests/integration/hardening.sh            CI size (tests/run.sh runs this), a few minutes
#   bash tests/integration/hardening.sh --full     the long runs: 1,000,000 fuzzed sequences,
#                                      1,000 dlopen/dlclose cycles under valgrind, ...
#   bash tests/integration/hardening.sh --afl S    coverage-guided fuzzing with cargo-afl (AFL++)
#                                      for S seconds, then its queue and crashes are
#                                      replayed through the oracle
#   bash tests/integration/hardening.sh --fuzz     the CI size's fuzzing alone (steps 3 and 9)
#
# What runs (sizes: CI / --full):
#   1. the packaged FMU's .so: glibc <= 2.17, only glibc + libgcc_s, no test hook
#      (pytest tests/integration/hardening)
#   2. panic boundary through the C API (cargo test --features test-hooks)
#   3. each model's fuzz target (the harness of fmi/fuzz; the span's in fuzz/, the
#      Roller's in models/roller/fuzz), property-based, --strict: 50,000 / 1,000,000
#      sequences; its FMI 3 mode (--fmi3): 5,000 / 1,000,000; the Roller's FMI 2.0 run
#      fails with fewer than 100 stick<->slide transitions in Co-Simulation or in Model
#      Exchange (--min-transitions)
#   4. (--full) the same harness built with AddressSanitizer (LeakSanitizer
#      included): 200,000 sequences; FMI 3: 100,000 (in CI, valgrind's run of
#      step 5 and the ASan runs of step 6 watch the memory)
#   5. the same harness under valgrind memcheck: 200 / 5,000 sequences
#   6. tests/integration/hardening/dlopen_cycles.c on each shipped .so, with ASan+UBSan:
#      1,000 / 1,000 cycles; under valgrind: 100 / 1,000 cycles; and the C importer
#      reloading the library under a live instance (ASan+UBSan)
#   7. (--full) the same with a panic caught in every cycle, on a portable build
#      with the test-only hook: ASan 1,000, valgrind 200 cycles (in CI, step 2
#      and the conformance suite cross the panic boundary through the C API)
#   8. (--full) the C importer of tests/integration/c_importer under valgrind, if present
#      (reported, not enforced: it is another program)
#   9. the Line (its test line, models/line/resources): its fuzz target line-fuzz
#      (models/line/fuzz) in the Line's own workspace, strict: LINE_SEQ / LINE_SEQ3
#      sequences (CI 3,000 / 1,000; --full 200,000 / 50,000, and 20,000 / 5,000
#      under ASan, 500 under valgrind, and the Line's panic-boundary tests)
# A summary is printed at the end and written to target/hardening/summary.txt.
set -euo pipefail
source "$(dirname "$0")/../../fmu/env.sh"
source "$ROOT/tests/tools.sh"
cd "$ROOT"
# A panic the FMU catches still goes through Rust's default panic hook, which
# prints it (and, with RUST_BACKTRACE set, symbolizes a backtrace: very slow
# under valgrind). Section 7 panics on purpose: one line each, into a log.
export RUST_BACKTRACE=0

MODE=ci
AFL_SECONDS=0
FUZZ_ONLY=false
case "${1:-}" in
    --full) MODE=full ;;
    --afl) MODE=afl; AFL_SECONDS="${2:?--afl needs a number of seconds}" ;;
    --fuzz) FUZZ_ONLY=true ;;
    "") ;;
    *) echo "usage: $0 [--full | --afl SECONDS | --fuzz]" >&2; exit 2 ;;
esac
if [ "$MODE" = full ]; then
    SEQ=1000000 SEQ_ASAN=200000 SEQ_VALGRIND=5000 CYCLES_VALGRIND=1000 PANIC_VALGRIND=200
    SEQ3=1000000 SEQ3_ASAN=100000
    LINE_SEQ=200000 LINE_SEQ3=50000 LINE_SEQ_ASAN=20000 LINE_SEQ3_ASAN=5000 LINE_SEQ_VALGRIND=500
else
    SEQ=50000 SEQ_ASAN=10000 SEQ_VALGRIND=200 CYCLES_VALGRIND=100 PANIC_VALGRIND=20
    SEQ3=5000 SEQ3_ASAN=2000
    LINE_SEQ=3000 LINE_SEQ3=1000 LINE_SEQ_ASAN=0 LINE_SEQ3_ASAN=0 LINE_SEQ_VALGRIND=0
fi
CYCLES_ASAN=1000

OUT=target/hardening
mkdir -p "$OUT"
SUMMARY="$OUT/summary.txt"
: > "$SUMMARY"
note() { echo "$*" | tee -a "$SUMMARY"; }
step() { echo; echo "== $*"; }
START=$SECONDS

# Each model's fuzz target: the harness of fmi/fuzz on that model.
MODELS=(span roller)
declare -A FUZZ_TARGET=([span]=converting-span-fuzz [roller]=roller-fuzz)
declare -A NAME=([span]=ConvertingSpan [roller]=Roller)
# The Roller's fuzz target follows its web's contact (traction): its FMI 2.0 run must see it
# stick and slide by turns, in both interfaces.
declare -A TRANSITIONS=([span]="" [roller]="--min-transitions 100")
# The Roller runs twice the sequences: its contact that sticks slides in Model Exchange some 2.5 times per
# thousand of them (254 in 100,000), and the bound asks 100.
declare -A SEQ_SCALE=([span]=1 [roller]=2)
# The lines of a run's totals the summary keeps.
totals() { grep -E '^fuzzed|by state|random calls|^  Model Exchange:|stick<->slide' "$1" | sed 's/^ *//'; }
fuzz_of() { echo "target/fuzz/fuzz/fuzz_sequences-$1"; }
build_fuzz() { # MODEL: one target folder for both (their crates are shared), each binary copied aside
    cargo build --profile fuzz --quiet -p "${FUZZ_TARGET[$1]}" --target-dir target/fuzz
    cp target/fuzz/fuzz/fuzz_sequences "$(fuzz_of "$1")"
}

if [ "$MODE" = afl ]; then
    # cargo-afl from crates.io builds AFL++ itself and runs on stable Rust.
    if ! command -v cargo-afl >/dev/null; then
        cargo install --quiet --locked --root "$CONVERTING_SPAN_TOOLS" cargo-afl@0.18.2
    fi
    cargo afl config --build 2>/dev/null || true # "already built" is fine
    step "AFL++ (cargo-afl), $AFL_SECONDS s"
    cargo afl build --profile fuzz --quiet --features afl -p converting-span-fuzz --target-dir target/fuzz-afl
    build_fuzz span
    FUZZ=$(fuzz_of span)
    mkdir -p "$OUT/afl-seeds"
    # Seeds: a few sequences of the property driver's generator.
    "$PY" - "$OUT/afl-seeds" <<'EOF'
import os, random, sys
rng = random.Random(1)
for k in range(16):
    with open(os.path.join(sys.argv[1], f"seed{k}"), "wb") as f:
        f.write(bytes(rng.randrange(256) for _ in range(64 + 32 * k)))
EOF
    rm -rf "$OUT/afl-out"
    AFL_SKIP_CPUFREQ=1 AFL_I_DONT_CARE_ABOUT_MISSING_CRASHES=1 AFL_NO_UI=1 AFL_QUIET=1 \
        timeout --preserve-status $((AFL_SECONDS + 60)) \
        cargo afl fuzz -V "$AFL_SECONDS" -i "$OUT/afl-seeds" -o "$OUT/afl-out" \
        target/fuzz-afl/fuzz/afl_target > "$OUT/afl.log" 2>&1 || true
    STATS="$OUT/afl-out/default/fuzzer_stats"
    [ -f "$STATS" ] || { echo "AFL++ did not run; see $OUT/afl.log"; tail -20 "$OUT/afl.log"; exit 1; }
    execs=$(awk -F': *' '/^execs_done/ {print $2}' "$STATS")
    corpus=$(awk -F': *' '/^corpus_count/ {print $2}' "$STATS")
    crashes=$(awk -F': *' '/^saved_crashes/ {print $2}' "$STATS")
    edges=$(awk -F': *' '/^bitmap_cvg/ {print $2}' "$STATS")
    note "AFL++: $execs sequences executed in $AFL_SECONDS s, corpus $corpus, map coverage $edges, crashes $crashes"
    # Replay the queue and any crash through the oracle (with messages).
    "$FUZZ" --replay "$OUT"/afl-out/default/queue/id* > "$OUT/afl-replay.log" || true
    if [ "$crashes" != 0 ]; then
        "$FUZZ" --replay "$OUT"/afl-out/default/crashes/id* || true
        note "AFL++ found $crashes crashing sequences: $OUT/afl-out/default/crashes"
        exit 1
    fi
    note "$((corpus)) passed, 0 failed"
    exit 0
fi

if ! $FUZZ_ONLY; then
step "1. portable binary (packaged FMU)"
[ -n "${CONVERTING_SPAN_PACKAGED:-}" ] || python3 fmu/package.py # tests/run.sh has packaged
"$PY" -m pytest tests/integration/hardening -q -s -p no:cacheprovider | tee "$OUT/portable.log"
grep "newest symbol version" "$OUT/portable.log" | sed 's/^\.*//' | while read -r line; do
    note "shipped $line (allowed: up to GLIBC_2.17)"
done

step "2. panic boundary (test-only hook, separate target directory): the span, the Roller"
# (the tests' profile: release speed without the LTO a test binary would redo; step 7 checks the LTO build)
cargo test --profile cross-test --quiet --features test-hooks --target-dir target/test-hooks --test panic_boundary
cargo test --profile cross-test --quiet -p roller --features test-hooks --target-dir target/test-hooks --test panic_boundary
fi

for model in "${MODELS[@]}"; do
    step "3. fuzz harness, strict (a non-finite output after accepted values fails too), ${NAME[$model]}: $(( SEQ * ${SEQ_SCALE[$model]} )) sequences"
    build_fuzz "$model"
    fuzz=$(fuzz_of "$model")
    # shellcheck disable=SC2086
    "$fuzz" --sequences "$(( SEQ * ${SEQ_SCALE[$model]} ))" --strict ${TRANSITIONS[$model]} | tee "$OUT/fuzz-$model.log"
    note "fuzz ${NAME[$model]}: $(totals "$OUT/fuzz-$model.log")"
    "$fuzz" --fmi3 --sequences "$SEQ3" --strict | tee "$OUT/fuzz3-$model.log"
    note "fuzz ${NAME[$model]}: $(totals "$OUT/fuzz3-$model.log")"

    [ "$MODE" = full ] || continue
    step "4. fuzz harness with AddressSanitizer, ${NAME[$model]}: $SEQ_ASAN sequences"
    # -Zsanitizer needs a nightly flag: RUSTC_BOOTSTRAP=1 lets this stable toolchain take it.
    RUSTC_BOOTSTRAP=1 RUSTFLAGS="-Zsanitizer=address" \
        cargo build --quiet --target x86_64-unknown-linux-gnu \
        --profile fuzz -p "${FUZZ_TARGET[$model]}" --target-dir "target/fuzz-asan-$model"
    asan="target/fuzz-asan-$model/x86_64-unknown-linux-gnu/fuzz/fuzz_sequences"
    ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 "$asan" --sequences "$SEQ_ASAN" --seed 7 | tee "$OUT/fuzz-asan-$model.log"
    note "fuzz ${NAME[$model]} under ASan: $(grep '^fuzzed' "$OUT/fuzz-asan-$model.log"), no ASan/LSan report"
    ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 "$asan" --fmi3 --sequences "$SEQ3_ASAN" --seed 7 | tee "$OUT/fuzz3-asan-$model.log"
    note "fuzz ${NAME[$model]} under ASan: $(grep '^fuzzed' "$OUT/fuzz3-asan-$model.log"), no ASan/LSan report"
done

if ! $FUZZ_ONLY; then
VALGRIND=(valgrind --tool=memcheck --leak-check=full --show-leak-kinds=definite,indirect,possible
    --errors-for-leak-kinds=definite,indirect,possible --error-exitcode=99)
valgrind_summary() { # log file -> one line
    local errors lost
    errors=$(grep -o "ERROR SUMMARY: [0-9,]* errors" "$1" | tail -1)
    lost=$(grep -E "definitely lost|indirectly lost|possibly lost|All heap blocks were freed" "$1" |
        sed 's/^==[0-9]*== *//' | tr '\n' ';' | sed 's/;$//')
    echo "$errors; ${lost:-no leak summary}"
}

for model in "${MODELS[@]}"; do
    step "5. fuzz harness under valgrind, ${NAME[$model]}: $SEQ_VALGRIND sequences"
    "${VALGRIND[@]}" --log-file="$OUT/valgrind-fuzz-$model.log" "$(fuzz_of "$model")" --sequences "$SEQ_VALGRIND" --threads 1 --seed 11
    note "fuzz ${NAME[$model]} under valgrind ($SEQ_VALGRIND sequences): $(valgrind_summary "$OUT/valgrind-fuzz-$model.log")"
done

HEADERS=$("$PY" -c "import fmpy, pathlib; print(pathlib.Path(fmpy.__file__).parent / 'c-code')")
C_FLAGS=(-O1 -g -Wall -Wextra -Werror -I "$HEADERS" -I tests/integration/c_importer)
gcc "${C_FLAGS[@]}" -o "$OUT/dlopen_cycles" tests/integration/hardening/dlopen_cycles.c -ldl -lm
gcc "${C_FLAGS[@]}" -fsanitize=address,undefined -fno-omit-frame-pointer \
    -o "$OUT/dlopen_cycles_asan" tests/integration/hardening/dlopen_cycles.c -ldl -lm
gcc "${C_FLAGS[@]}" -fsanitize=address,undefined -fno-omit-frame-pointer \
    -o "$OUT/importer_asan" tests/integration/c_importer/importer.c -ldl -lm
declare -A MODEL_DIR=([span]=. [roller]=models/roller)
declare -A PACKAGE=([span]=converting-span [roller]=roller)
declare -A LIBRARY=([span]=libconverting_span.so [roller]=libroller.so)
# The Real input each scene sets to NaN (refused) and the one it steps.
declare -A REFUSED=([span]=web_a.v [roller]=web_a.F) STEPPED=([span]=web_b.v [roller]=tau_m)
for model in "${MODELS[@]}"; do
    step "6. dlopen/dlclose cycles of the shipped ${NAME[$model]}.so, and a reload under a live instance"
    rm -rf "$OUT/fmu" && mkdir -p "$OUT/fmu"
    "$PY" -c "import zipfile,sys; zipfile.ZipFile(sys.argv[1]).extractall(sys.argv[2])" "out/${NAME[$model]}.fmu" "$OUT/fmu"
    SHIPPED="$OUT/${NAME[$model]}.so"
    cp "$OUT/fmu/binaries/linux64/${NAME[$model]}.so" "$SHIPPED"
    # GUID, the two inputs' and the Real outputs' value references, from the model description.
    read -r GUID VR_A VR_B OUTPUTS < <("$PY" - "${MODEL_DIR[$model]}/modelDescription.xml" "${REFUSED[$model]}" "${STEPPED[$model]}" <<'EOF'
import sys
import xml.etree.ElementTree as ET
root = ET.parse(sys.argv[1]).getroot()
vr = {v.get("name"): v.get("valueReference") for v in root.iter("ScalarVariable")}
outs = [v.get("valueReference") for v in root.iter("ScalarVariable")
        if v.get("causality") == "output" and v.find("Real") is not None]
print(root.get("guid"), vr[sys.argv[2]], vr[sys.argv[3]], ",".join(outs))
EOF
    )
    CYCLE_ARGS=("$GUID" "$VR_A" "$VR_B" "$OUTPUTS")
    ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
        "$OUT/dlopen_cycles_asan" "$SHIPPED" "${CYCLE_ARGS[0]}" "$CYCLES_ASAN" "${CYCLE_ARGS[@]:1}" | tee "$OUT/cycles-asan-$model.log"
    note "dlopen cycles of ${NAME[$model]} under ASan+UBSan: $(head -1 "$OUT/cycles-asan-$model.log"); no report"
    "${VALGRIND[@]}" --log-file="$OUT/valgrind-cycles-$model.log" \
        "$OUT/dlopen_cycles" "$SHIPPED" "${CYCLE_ARGS[0]}" "$CYCLES_VALGRIND" "${CYCLE_ARGS[@]:1}"
    note "dlopen cycles of ${NAME[$model]} under valgrind ($CYCLES_VALGRIND cycles): $(valgrind_summary "$OUT/valgrind-cycles-$model.log")"
    ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
        "$OUT/importer_asan" "$SHIPPED" "$GUID" --reload "$VR_B" "${OUTPUTS%%,*}" > "$OUT/reload-$model.log" 2>&1 \
        || { tail -20 "$OUT/reload-$model.log"; exit 1; }
    grep -q "^reload,unloaded,1" "$OUT/reload-$model.log" || { echo "${NAME[$model]} stayed loaded after the reload scene"; exit 1; }
    note "${NAME[$model]} reloaded under a live instance (ASan+UBSan): both instances finished, unloaded after the last free"

    [ "$MODE" = full ] || continue
    step "7. a caught panic in every cycle, ${NAME[$model]} (portable build with the test-only hook)"
    cargo zigbuild --release --quiet --lib -p "${PACKAGE[$model]}" --features test-hooks --target x86_64-unknown-linux-gnu.2.17 \
        --target-dir target/portable-hooks
    HOOKED="target/portable-hooks/x86_64-unknown-linux-gnu/release/${LIBRARY[$model]}"
    ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
        "$OUT/dlopen_cycles_asan" "$HOOKED" "${CYCLE_ARGS[0]}" "$CYCLES_ASAN" "${CYCLE_ARGS[@]:1}" --panic \
        2> "$OUT/panic-asan-$model.stderr" | tee "$OUT/panic-asan-$model.log" || { tail -30 "$OUT/panic-asan-$model.stderr"; exit 1; }
    note "panic cycles of ${NAME[$model]} under ASan+UBSan: $(head -1 "$OUT/panic-asan-$model.log"); no report"
    "${VALGRIND[@]}" --log-file="$OUT/valgrind-panic-$model.log" \
        "$OUT/dlopen_cycles" "$HOOKED" "${CYCLE_ARGS[0]}" "$PANIC_VALGRIND" "${CYCLE_ARGS[@]:1}" --panic 2> "$OUT/panic-valgrind-$model.stderr"
    note "panic cycles of ${NAME[$model]} under valgrind ($PANIC_VALGRIND cycles): $(valgrind_summary "$OUT/valgrind-panic-$model.log")"
done

if [ "$MODE" = full ] && [ -f tests/integration/c_importer/importer.c ]; then
    step "8. the C importer of tests/integration/c_importer under valgrind"
    SHIPPED="$OUT/ConvertingSpan.so"
    GUID=$("$PY" -c "import xml.etree.ElementTree as ET; print(ET.parse('modelDescription.xml').getroot().get('guid'))")
    gcc -O1 -g -Wall -I "$HEADERS" -I tests/integration/c_importer tests/integration/c_importer/importer.c -o "$OUT/importer" -ldl
    ARGS=$("$PY" - <<'EOF'
import xml.etree.ElementTree as ET
root = ET.parse("modelDescription.xml").getroot()
vr = {v.get("name"): v.get("valueReference") for v in root.iter("ScalarVariable")}
names = ["L", "wp2.width", "wp2.d_r", "includeDamping", "toUnitV", "web_a.v", "web_a.eps", "web_b.v",
         "T", "summary_Strain", "unstretchedLength", "v"]
print(" ".join(f"{n}={vr[n]}" for n in names))
EOF
)
    # Another engineer's program: its result is reported, not enforced here
    # (a leak of an instance it never frees would be its own). Where valgrind
    # points into the FMU, read $OUT/valgrind-importer.log.
    # shellcheck disable=SC2086
    "${VALGRIND[@]}" --log-file="$OUT/valgrind-importer.log" "$OUT/importer" "$SHIPPED" "$GUID" $ARGS \
        > "$OUT/importer.out" || true
    note "tests/integration/c_importer under valgrind: $(valgrind_summary "$OUT/valgrind-importer.log");" \
        "its own failed checks: $(grep -c '^check,.*,0$' "$OUT/importer.out" || true)"
fi

fi

# The Line: its fuzz target line-fuzz in the Line's own workspace (models/line/fuzz;
# in this one the span's `fmu` feature, its C API, would be unified into the Line),
# over the Line's test line.
step "9. fuzz harness, strict, the Line (models/line/resources): $LINE_SEQ sequences, FMI 3: $LINE_SEQ3"
LINE_START=$SECONDS
line_fuzz() { # PROFILE TARGET-DIR [cargo options...]
    cargo build --profile "$1" --quiet --manifest-path models/line/Cargo.toml -p line-fuzz --bin fuzz_sequences \
        --target-dir "$2" "${@:3}"
}
# The tests' profile and folder, where tests/run.sh has built the Line's crates already.
line_fuzz cross-test target/line
LINE_FUZZ=target/line/cross-test/fuzz_sequences
"$LINE_FUZZ" --sequences "$LINE_SEQ" --strict | tee "$OUT/fuzz-line.log"
note "fuzz Line: $(totals "$OUT/fuzz-line.log")"
"$LINE_FUZZ" --fmi3 --sequences "$LINE_SEQ3" --strict | tee "$OUT/fuzz3-line.log"
note "fuzz Line: $(totals "$OUT/fuzz3-line.log")"
if [ "$MODE" = full ]; then
    RUSTC_BOOTSTRAP=1 RUSTFLAGS="-Zsanitizer=address" line_fuzz fuzz target/fuzz-asan-line --target x86_64-unknown-linux-gnu
    asan=target/fuzz-asan-line/x86_64-unknown-linux-gnu/fuzz/fuzz_sequences
    ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 "$asan" --sequences "$LINE_SEQ_ASAN" --seed 7 | tee "$OUT/fuzz-asan-line.log"
    note "fuzz Line under ASan: $(grep '^fuzzed' "$OUT/fuzz-asan-line.log"), no ASan/LSan report"
    ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 "$asan" --fmi3 --sequences "$LINE_SEQ3_ASAN" --seed 7 | tee "$OUT/fuzz3-asan-line.log"
    note "fuzz Line under ASan: $(grep '^fuzzed' "$OUT/fuzz3-asan-line.log"), no ASan/LSan report"
    "${VALGRIND[@]}" --log-file="$OUT/valgrind-fuzz-line.log" "$LINE_FUZZ" --sequences "$LINE_SEQ_VALGRIND" --threads 1 --seed 11
    note "fuzz Line under valgrind ($LINE_SEQ_VALGRIND sequences): $(valgrind_summary "$OUT/valgrind-fuzz-line.log")"
    cargo test --release --quiet --manifest-path models/line/Cargo.toml --features test-hooks --target-dir target/line-hooks --test panic_boundary
    note "panic boundary of the Line: passed"
fi
note "the Line took $((SECONDS - LINE_START)) s"

note "hardening ($MODE) took $((SECONDS - START)) s"
echo
cat "$SUMMARY"
