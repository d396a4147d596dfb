# Sourced by fmu/toolchain.sh: the compiler and linker of the Windows and
# ARM64 Linux binaries. What runs them (Wine, QEMU) is the tests' business
# (tests/tools.sh); building needs only this.
#
#   rust-web-VERSION/  Debian's rustc-web, cargo-web, rust-web-src (std's
#                      source, dependencies vendored) and libstd-rust-web,
#                      fetched with `apt-get download` and unpacked with
#                      `dpkg-deb -x`: installing rustc-web would replace
#                      Debian's rustc. rustup can add no target here, so
#                      std is built once for each cross target (-Zbuild-std)
#                      into this compiler's own sysroot, as `rustup target
#                      add` would install it: later builds find it there.
#   apt                the libraries those packages declare in their own
#                      Depends (`apt-get satisfy`), and the MinGW-w64 linker.
#
# The version is the newest rustc-web that apt offers once its lists are
# updated (bookworm-security carries it); it is resolved once, on the run
# that fills the cache, and recorded in $TOOLS/rust-web.version. Before first
# use, every shared library of cargo and rustc must resolve (ldd), or the run
# stops with one line naming the library and the package that ships it.
#
# Order: MinGW-w64 first (building std for Windows calls its dlltool), then
# rustc-web. Exports CROSS_CARGO and CROSS_RUSTC and the Windows target's linker.
# APT_OPTIONS (e.g. "-o Dir::State::Lists=DIR") points apt at another state:
# the tests resolve against a partial one (fmu/tests/test_setup.py).

APT_OPTIONS="${APT_OPTIONS:-}"
RUST_WEB_UNPACKED=(rustc-web cargo-web rust-web-src libstd-rust-web-dev)
MINGW_PACKAGE=gcc-mingw-w64-x86-64
say() { echo "cross_toolchain.sh: $*" >&2; }

# Sets RUST_WEB_VERSION to the rustc-web apt offers after updating its
# lists: stale lists name an older one (bookworm main's, which needed a
# library nothing installed).
rust_web_resolve() {
    if [ "$(id -u)" = 0 ]; then
        apt_quiet $APT_OPTIONS update || {
            say "could not update the apt lists (apt-get update); check that Debian's mirrors are reachable, then run again"
            return 1
        }
        [ -n "$APT_OPTIONS" ] || APT_LISTS_UPDATED=1
    else
        say "not root: using apt's lists as they are (run once as root for the current rustc-web)"
    fi
    RUST_WEB_VERSION="$(apt-cache $APT_OPTIONS policy rustc-web 2>/dev/null | awk '/Candidate:/ && $2 != "(none)" {print $2}')"
    [ -n "$RUST_WEB_VERSION" ] || { say "apt offers no rustc-web: add bookworm-security to apt's sources, then run again"; return 1; }
}

# The Debian package that ships a shared library, by Debian's naming policy
# (libpcre.so.3 -> libpcre3, libfoo1.2.so.0 -> libfoo1.2-0), if apt knows it.
library_package() {
    local name="${1%%.so*}" version="${1#*.so.}" package
    version="${version%%.*}"
    if [[ "$name" =~ [0-9]$ ]]; then package="$name-$version"; else package="$name$version"; fi
    package="$(echo "$package" | tr 'A-Z_' 'a-z-')"
    if apt-cache $APT_OPTIONS show "$package" >/dev/null 2>&1; then echo "$package"; fi
}

# Every shared library of the given executables and libraries resolves
# (LD_LIBRARY_PATH as they will run); otherwise one line names the first
# that does not, and the package to install.
check_libraries() { # LIBRARY_PATH OWNER FILE...
    local path="$1" owner="$2" file missing package
    shift 2
    for file in "$@"; do
        missing="$(LD_LIBRARY_PATH="$path" ldd "$file" 2>&1 | awk '/=> not found/ {print $1; exit}')"
        if [ -n "$missing" ]; then
            package="$(library_package "$missing")"
            say "$owner's $(basename "$file") needs $missing, which is not installed${package:+ (Debian package $package: apt-get install $package)}"
            return 1
        fi
    done
}

# Installs (as root) what the unpacked packages declare in their Depends,
# apart from each other: apt-get satisfy reads the fields as written
# (versions, alternatives, virtual packages).
satisfy_depends() { # DEPENDS-FILE
    local wanted
    wanted="$(paste -sd, "$1")"
    [ -n "$wanted" ] || return 0
    if apt-get satisfy -s -qq "$wanted" 2>/dev/null | grep -q '^Inst '; then
        say "installing the libraries rustc-web and cargo-web depend on (apt)"
        apt_install_satisfy "$wanted" || {
            say "apt-get satisfy \"$wanted\" failed; install those packages, then run again"
            return 1
        }
    fi
}

rust_web_unpack() { # VERSION DIR
    local version="$1" dir="$2" debs std
    std="$(apt-cache $APT_OPTIONS depends "libstd-rust-web-dev=$version" | awk '/Depends: libstd-rust-web-[0-9]/ {print $2; exit}')"
    [ -n "$std" ] || { say "apt knows no standard library package for rustc-web $version"; return 1; }
    say "unpacking rustc-web $version (apt-get download) into $dir"
    debs="$(mktemp -d)"
    (cd "$debs" && apt-get $APT_OPTIONS download -qq -o APT::Sandbox::User=root \
        $(for p in "${RUST_WEB_UNPACKED[@]}" "$std"; do echo "$p=$version"; done)) || {
        say "apt-get download of rustc-web $version failed; check that Debian's mirrors are reachable, then run again"
        rm -rf "$debs"; return 1
    }
    rm -rf "$dir.tmp" && mkdir -p "$dir.tmp/bin"
    local deb own
    own="$(printf '%s\n' "${RUST_WEB_UNPACKED[@]}" "$std" | paste -sd'|')"
    for deb in "$debs"/*.deb; do
        dpkg-deb -x "$deb" "$dir.tmp"
        # Each Depends clause, minus those the unpacked packages meet themselves.
        dpkg-deb -f "$deb" Depends | tr ',' '\n' | sed 's/^ *//; s/ *$//' | grep -v '^$' \
            | grep -Ev "^($own)( |$)" >> "$dir.tmp/DEPENDS" || true
    done
    sort -u -o "$dir.tmp/DEPENDS" "$dir.tmp/DEPENDS"
    rm -rf "$debs"
    rm -rf "$dir" && mv "$dir.tmp" "$dir"
}

# bin/rustc and bin/cargo: rustc-web's, with its driver library beside rustc (which
# finds its sysroot, usr/, from its own path). They find the folder from their own
# path too, so a cache that is moved or copied keeps working.
rust_web_wrappers() { # DIR
    local dir="$1" here='here="$(dirname "$(dirname "$(readlink -f "$0")")")"'
    mkdir -p "$dir/bin"
    write_if_changed "$dir/bin/rustc" <<EOF
#!/bin/sh
$here
LD_LIBRARY_PATH="\$here/usr/lib/x86_64-linux-gnu\${LD_LIBRARY_PATH:+:\$LD_LIBRARY_PATH}" exec "\$here/usr/bin/rustc" "\$@"
EOF
    write_if_changed "$dir/bin/cargo" <<EOF
#!/bin/sh
$here
RUSTC="\$here/bin/rustc" RUSTDOC=false exec "\$here/usr/bin/cargo" "\$@"
EOF
    chmod +x "$dir/bin/rustc" "$dir/bin/cargo"
}

write_if_changed() { # FILE < CONTENT: rewrites FILE only when its bytes change
    local new
    new="$(cat)"
    [ -f "$1" ] && [ "$(cat "$1")" = "$new" ] && return 0
    printf '%s\n' "$new" > "$1.tmp" && mv "$1.tmp" "$1"
}

# std for each cross target, built once with rustc-web's own std sources into its sysroot
# (usr/lib/rustlib/TARGET/lib), as `rustup target add` installs it: every build after it
# (packaging, the tests, the fuzz harness) needs no -Zbuild-std, so none compiles std again.
# Bitcode stays in the objects, as in rustup's std, so LTO takes std in; test and
# panic_abort are there for `cargo test` and panic=abort builds.
CROSS_TARGETS=(x86_64-pc-windows-gnu aarch64-unknown-linux-gnu)
CROSS_STD_RECIPE=1 # raise it when the recipe changes: every cache builds std again
rust_web_target_std() { # DIR
    local dir="$1" target missing=() work lib
    for target in "${CROSS_TARGETS[@]}"; do
        [ -f "$dir/usr/lib/rustlib/$target/lib/.std-recipe-$CROSS_STD_RECIPE" ] || missing+=("$target")
    done
    [ "${#missing[@]}" = 0 ] && return 0
    say "building std for ${missing[*]} into rustc-web's sysroot (once, about two minutes)"
    work="$dir/std-build"
    rm -rf "$work" && mkdir -p "$work/src"
    printf '[package]\nname = "std-for-target"\nversion = "0.0.0"\nedition = "2021"\n[workspace]\n' > "$work/Cargo.toml"
    echo '#![no_std]' > "$work/src/lib.rs"
    # -Zbuild-std is unstable: RUSTC_BOOTSTRAP=1 lets this stable cargo take it.
    (cd "$work" && RUSTC_BOOTSTRAP=1 RUSTFLAGS="-Cembed-bitcode=yes" "$dir/bin/cargo" build --quiet --release --lib \
        -Zbuild-std=std,panic_unwind,panic_abort,test $(printf -- '--target %s ' "${missing[@]}")) || {
        # Nothing is recorded for a failed build: the next run builds std again.
        say "building std for ${missing[*]} with rustc-web failed (its message is above); fix what it names, then run again"
        return 1
    }
    for target in "${missing[@]}"; do
        lib="$dir/usr/lib/rustlib/$target/lib"
        rm -rf "$lib.tmp" "$lib" && mkdir -p "$lib.tmp"
        find "$work/target/$target/release/deps" -maxdepth 1 -type f ! -name '*.d' ! -name '*std_for_target*' \
            -exec cp {} "$lib.tmp/" \;
        touch "$lib.tmp/.std-recipe-$CROSS_STD_RECIPE"
        mv "$lib.tmp" "$lib"
    done
    rm -rf "$work"
}

# cargo, rustc and rustc's driver library, as the build will run them.
rust_web_check() { # DIR
    local dir="$1"
    [ -x "$dir/usr/bin/cargo" ] && [ -x "$dir/usr/bin/rustc" ] || { say "$dir lacks cargo or rustc: remove it, then run again"; return 1; }
    check_libraries "$dir/usr/lib/x86_64-linux-gnu" "rustc-web $(basename "$dir" | sed 's/^rust-web-//')" \
        "$dir/usr/bin/cargo" "$dir/usr/bin/rustc" "$dir"/usr/lib/x86_64-linux-gnu/librustc_driver-*.so
}

# The one entry: a cached toolchain if there is one, else resolve and unpack.
rust_web_setup() {
    local dir
    RUST_WEB_VERSION="$(cat "$TOOLS/rust-web.version" 2>/dev/null || true)"
    if [ -z "$RUST_WEB_VERSION" ] || ! [ -f "$TOOLS/rust-web-$RUST_WEB_VERSION/DEPENDS" ]; then
        rust_web_resolve || return 1
        rust_web_unpack "$RUST_WEB_VERSION" "$TOOLS/rust-web-$RUST_WEB_VERSION" || return 1
        echo "$RUST_WEB_VERSION" > "$TOOLS/rust-web.version"
    fi
    dir="$TOOLS/rust-web-$RUST_WEB_VERSION"
    satisfy_depends "$dir/DEPENDS" || return 1
    rust_web_wrappers "$dir"
    rust_web_check "$dir" || return 1
    rust_web_target_std "$dir" || return 1
    export CROSS_CARGO="$dir/bin/cargo" CROSS_RUSTC="$dir/bin/rustc"
}

# MinGW-w64 first: building std for the Windows target (rust_web_target_std) calls its dlltool.
mingw_setup() {
    command -v x86_64-w64-mingw32-gcc >/dev/null && command -v x86_64-w64-mingw32-dlltool >/dev/null && return 0
    say "installing the MinGW-w64 linker and dlltool of the Windows binary (apt, once)"
    apt_install "$MINGW_PACKAGE" || { say "apt-get install $MINGW_PACKAGE failed (its message is above); check that Debian's mirrors are reachable, then run again"; return 1; }
}

if [ "${SETUP_FUNCTIONS_ONLY:-}" != 1 ]; then
    mingw_setup || return 1
    rust_web_setup || return 1
    export CARGO_TARGET_X86_64_PC_WINDOWS_GNU_LINKER=x86_64-w64-mingw32-gcc
fi
