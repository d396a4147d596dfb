# Sourced by fmu/env.sh: the portable-build tools, installed once and cached
# outside the work tree (so a fresh clone on the same machine reuses them).
#
#   zig            from PyPI (package ziglang), in its own virtual environment
#   cargo-zigbuild from crates.io: cargo build with zig as the linker, which
#                  links against glibc 2.17 symbol versions when the target is
#                  x86_64-unknown-linux-gnu.2.17
#
# fmu/package.py uses them for the FMU's binary; plain `cargo build` does not.
TOOLS="${CONVERTING_SPAN_TOOLS:-${XDG_CACHE_HOME:-$HOME/.cache}/converting-span-tools}"
ZIGLANG_VERSION=0.15.2
ZIGBUILD_VERSION=0.24.1
export CONVERTING_SPAN_TOOLS="$TOOLS"

if ! [ -x "$TOOLS/zig-venv/bin/python" ] || ! "$TOOLS/zig-venv/bin/python" -m ziglang version 2>/dev/null | grep -qx "$ZIGLANG_VERSION"; then
    echo "toolchain.sh: installing zig $ZIGLANG_VERSION (PyPI ziglang) into $TOOLS"
    mkdir -p "$TOOLS"
    python3 -m venv "$TOOLS/zig-venv"
    "$TOOLS/zig-venv/bin/pip" install --quiet --disable-pip-version-check "ziglang==$ZIGLANG_VERSION"
fi
mkdir -p "$TOOLS/bin"
if ! [ -x "$TOOLS/bin/zig" ]; then
    printf '#!/bin/sh\nexec "%s/zig-venv/bin/python" -m ziglang "$@"\n' "$TOOLS" > "$TOOLS/bin/zig"
    chmod +x "$TOOLS/bin/zig"
fi
if ! "$TOOLS/bin/cargo-zigbuild" --version 2>/dev/null | grep -q " $ZIGBUILD_VERSION"; then
    echo "toolchain.sh: installing cargo-zigbuild $ZIGBUILD_VERSION (crates.io) into $TOOLS"
    cargo install --quiet --locked --no-default-features --root "$TOOLS" "cargo-zigbuild@$ZIGBUILD_VERSION"
fi
case ":$PATH:" in
    *":$TOOLS/bin:"*) ;;
    *) export PATH="$TOOLS/bin:$PATH" ;;
esac
# The Windows and ARM64 Linux tools and their emulators (see the file).
source "$ROOT/fmu/cross_toolchain.sh"
