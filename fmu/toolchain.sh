# Sourced by fmu/env.sh: the tools that build the FMUs' three binaries,
# installed once and cached outside the work tree (so a fresh clone on the
# same machine reuses them):
#
#   zig            from PyPI (package ziglang), in its own virtual environment
#   cargo-zigbuild from crates.io: cargo build with zig as the linker, which
#                  links against glibc 2.17 symbol versions when the target is
#                  x86_64-unknown-linux-gnu.2.17 or aarch64-unknown-linux-gnu.2.17
#   rustc-web      the Windows and ARM64 compiler (fmu/cross_toolchain.sh)
#
# fmu/package.py uses them for the FMU's binaries; plain `cargo build` does not.
ZIGLANG_VERSION=0.15.2
ZIGBUILD_VERSION=0.24.1

# A failed install leaves nothing that the next run takes for installed: it tries again.
zig_setup() {
    if ! [ -x "$TOOLS/zig-venv/bin/python" ] || ! "$TOOLS/zig-venv/bin/python" -m ziglang version 2>/dev/null | grep -qx "$ZIGLANG_VERSION"; then
        echo "toolchain.sh: installing zig $ZIGLANG_VERSION (PyPI ziglang) into $TOOLS"
        { python3 -m venv "$TOOLS/zig-venv" \
            && "$TOOLS/zig-venv/bin/pip" install --quiet --disable-pip-version-check "ziglang==$ZIGLANG_VERSION"; } \
            || setup_failed toolchain.sh "installing zig" "pip could not install ziglang==$ZIGLANG_VERSION (its message is above)" \
                "Check that PyPI is reachable, then run again."
    fi
    if ! [ -x "$TOOLS/bin/zig" ]; then
        mkdir -p "$TOOLS/bin"
        printf '#!/bin/sh\nexec "%s/zig-venv/bin/python" -m ziglang "$@"\n' "$TOOLS" > "$TOOLS/bin/zig"
        chmod +x "$TOOLS/bin/zig"
    fi
}

zigbuild_setup() {
    "$TOOLS/bin/cargo-zigbuild" --version 2>/dev/null | grep -q " $ZIGBUILD_VERSION" && return 0
    echo "toolchain.sh: installing cargo-zigbuild $ZIGBUILD_VERSION (crates.io) into $TOOLS"
    cargo install --quiet --locked --no-default-features --root "$TOOLS" "cargo-zigbuild@$ZIGBUILD_VERSION" \
        || setup_failed toolchain.sh "installing cargo-zigbuild" "cargo install failed (its message is above)" \
            "Check that crates.io is reachable, then run again."
}

[ "${SETUP_FUNCTIONS_ONLY:-}" = 1 ] && return 0

mkdir -p "$TOOLS/bin"
zig_setup
zigbuild_setup
case ":$PATH:" in
    *":$TOOLS/bin:"*) ;;
    *) export PATH="$TOOLS/bin:$PATH" ;;
esac
# The Windows and ARM64 Linux compiler and linker (see the file).
source "$ROOT/fmu/cross_toolchain.sh" || exit 1
