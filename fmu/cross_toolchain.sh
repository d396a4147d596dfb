# Sourced by fmu/toolchain.sh: the tools for the Windows and ARM64 Linux
# binaries, and the emulators that run them here. Installed once; the Rust
# compiler is cached beside zig in $CONVERTING_SPAN_TOOLS.
#
#   rust-web/      Debian bookworm-security's rustc-web, cargo-web and
#                  rust-web-src (the standard library's source, dependencies
#                  vendored), fetched with `apt-get download` and unpacked
#                  with `dpkg-deb -x`: installing rustc-web would replace
#                  Debian's rustc. It builds std for each target
#                  (-Zbuild-std), as rustup can add no target here.
#   apt            x86_64-w64-mingw32-gcc and aarch64-linux-gnu-gcc (linkers,
#                  and the compilers of the test importer), wine64 (Wine 8)
#                  and qemu-user-static (qemu-aarch64-static).
#   wine-prefix/   the Wine prefix of the tests, with a test-only
#                  bcryptprimitives.dll (tests/cross/bcryptprimitives.c):
#                  Wine 8 lacks ProcessPrng, which Rust's std imports.
#                  Windows 10 and later have it; the shim never ships.
#
# Exports CROSS_CARGO and CROSS_RUSTC (cargo-web, rustc-web), WINEPREFIX, and the cargo
# linkers and runners of both targets (CARGO_TARGET_<TRIPLE>_...).
# The rustc-web that bookworm-security ships now (a security update replaces it
# there, and a new one is unpacked beside the old); its std and LLVM packages
# carry the version in their names, so they are read from its dependencies.
candidate() { apt-cache policy "$1" 2>/dev/null | awk '/Candidate:/ && $2 != "(none)" {print $2}'; }
RUST_WEB_VERSION="$(candidate rustc-web)"
if [ -z "$RUST_WEB_VERSION" ]; then
    apt-get update -qq -o DPkg::Lock::Timeout=300 || true
    RUST_WEB_VERSION="$(candidate rustc-web)"
fi
[ -n "$RUST_WEB_VERSION" ] || { echo "cross_toolchain.sh: apt knows no rustc-web (is bookworm-security in the sources?)" >&2; return 1; }
RUST_WEB="$TOOLS/rust-web-$RUST_WEB_VERSION"
STD_PACKAGE="$(apt-cache depends "libstd-rust-web-dev=$RUST_WEB_VERSION" | awk '/Depends: libstd-rust-web-[0-9]/ {print $2}')"
LLVM_PACKAGE="$(apt-cache depends "$STD_PACKAGE=$RUST_WEB_VERSION" | awk '/Depends: libllvm[0-9]/ {print $2}')"

APT_PACKAGES=(gcc-mingw-w64-x86-64 gcc-aarch64-linux-gnu wine64 qemu-user-static libgit2-1.5 libssh2-1 "$LLVM_PACKAGE")
installed() { [ "$(dpkg-query -W -f='${Status}\n' "$@" 2>/dev/null | grep -c '^install ok installed$')" = "$#" ]; }
if ! installed "${APT_PACKAGES[@]}"; then
    echo "cross_toolchain.sh: installing mingw-w64, aarch64 gcc, Wine and QEMU (apt, about 2 GB, once)"
    # libgit2, libssh2 (for cargo-web) and libllvm (for rustc-web): libraries only.
    apt_install "${APT_PACKAGES[@]}"
fi

if ! [ -x "$RUST_WEB/bin/cargo" ]; then
    echo "cross_toolchain.sh: unpacking rustc-web $RUST_WEB_VERSION (apt-get download) into $RUST_WEB"
    debs="$(mktemp -d)"
    (cd "$debs" && apt-get download -qq -o APT::Sandbox::User=root $(for p in rustc-web cargo-web rust-web-src libstd-rust-web-dev "$STD_PACKAGE"; do
        echo "$p=$RUST_WEB_VERSION"; done))
    rm -rf "$RUST_WEB.tmp" && mkdir -p "$RUST_WEB.tmp/bin"
    for deb in "$debs"/*.deb; do dpkg-deb -x "$deb" "$RUST_WEB.tmp"; done
    rm -rf "$debs"
    # rustc finds its sysroot from its own path (usr/); its driver library is beside it.
    cat > "$RUST_WEB.tmp/bin/rustc" <<EOF
#!/bin/sh
LD_LIBRARY_PATH="$RUST_WEB/usr/lib/x86_64-linux-gnu\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}" exec "$RUST_WEB/usr/bin/rustc" "\$@"
EOF
    # -Zbuild-std is unstable: RUSTC_BOOTSTRAP=1 lets this stable cargo take it.
    cat > "$RUST_WEB.tmp/bin/cargo" <<EOF
#!/bin/sh
RUSTC="$RUST_WEB/bin/rustc" RUSTDOC=false RUSTC_BOOTSTRAP=1 exec "$RUST_WEB/usr/bin/cargo" "\$@"
EOF
    chmod +x "$RUST_WEB.tmp/bin/rustc" "$RUST_WEB.tmp/bin/cargo"
    rm -rf "$RUST_WEB" && mv "$RUST_WEB.tmp" "$RUST_WEB"
fi
export CROSS_CARGO="$RUST_WEB/bin/cargo" CROSS_RUSTC="$RUST_WEB/bin/rustc"

export CARGO_TARGET_X86_64_PC_WINDOWS_GNU_LINKER=x86_64-w64-mingw32-gcc
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export WINEPREFIX="$TOOLS/wine-prefix"
export WINEDEBUG=-all
export CARGO_TARGET_X86_64_PC_WINDOWS_GNU_RUNNER=/usr/lib/wine/wine64
export QEMU_LD_PREFIX=/usr/aarch64-linux-gnu
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER=qemu-aarch64-static

SHIM_SOURCE="$ROOT/tests/cross/bcryptprimitives.c"
SHIM="$WINEPREFIX/drive_c/windows/system32/bcryptprimitives.dll"
if ! [ -f "$WINEPREFIX/system.reg" ]; then
    echo "cross_toolchain.sh: creating the Wine prefix $WINEPREFIX"
    /usr/lib/wine/wine64 wineboot --init >/dev/null 2>&1
    /usr/lib/wine/wineserver -w
fi
if ! [ -f "$SHIM" ] || [ "$SHIM_SOURCE" -nt "$SHIM" ]; then
    x86_64-w64-mingw32-gcc -O2 -shared -o "$SHIM" "$SHIM_SOURCE" -ladvapi32
fi
