#!/bin/sh
# rustc-web's cargo and rustc in the set-up's tests (fake_apt.py packs it as both):
# `build` with -Zbuild-std writes each target's std as the real one would, and
# needs MinGW's dlltool for the Windows target, as the real one does.
echo "cargo $*" >> "$FAKE_APT/calls"
case " $* " in *" build "*) ;; *) echo "cargo 9.9.9"; exit 0 ;; esac
if [ -f "$FAKE_APT/fail-std-once" ]; then
    rm -f "$FAKE_APT/fail-std-once"
    echo "error: could not write the build's output (No space left on device)" >&2
    exit 101
fi
targets=""
previous=""
for arg in "$@"; do
    [ "$previous" = "--target" ] && targets="$targets $arg"
    previous="$arg"
done
for target in $targets; do
    if [ "$target" = x86_64-pc-windows-gnu ] && ! command -v x86_64-w64-mingw32-dlltool >/dev/null; then
        echo "error: error calling dlltool 'x86_64-w64-mingw32-dlltool': No such file or directory (os error 2)" >&2
        exit 101
    fi
    mkdir -p "target/$target/release/deps"
    for crate in std core panic_unwind panic_abort test; do
        : > "target/$target/release/deps/lib$crate-fake.rlib"
    done
done
