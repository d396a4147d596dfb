# Sourced by the test scripts after fmu/env.sh: what only the tests need,
# installed once (the main job never installs these):
#
#   tests/requirements.txt  pytest and mpmath (cached like fmu/requirements.txt, fmu/env.sh)
#   apt                     Wine (wine64) and QEMU (qemu-user-static), which run
#                           the Windows and ARM64 binaries; aarch64 gcc, which
#                           compiles the C importer for ARM64 and whose sysroot
#                           QEMU loads; valgrind; libclang-dev (fmi-sim's build)
#   apt (browser)           Chromium and its WebDriver (chromium, chromium-driver), which
#                           tests/integration/python/test_browser.py drives headless
#   wine-prefix/            the tests' Wine prefix, with a test-only
#                           bcryptprimitives.dll (tests/integration/cross/bcryptprimitives.c):
#                           Wine 8 lacks ProcessPrng, which Rust's std imports.
#                           Windows 10 and later have it; the shim never ships.
#   fmi-sim                 rust-fmi's simulator, from crates.io (into the tools cache)
#
# libcosim comes with the venv (PyPI libcosimpy, fmu/requirements.txt).
# Exports WINEPREFIX and the runners and linkers of both cross targets.
# Each step installs what it needs before it first uses it (the apt packages
# before the Wine prefix and fmi-sim's build); SETUP_FUNCTIONS_ONLY=1 defines
# the steps without running them (fmu/tests/test_setup.py).

TEST_PACKAGES=(wine64 qemu-user-static gcc-aarch64-linux-gnu valgrind libclang-dev binutils)
installed() { [ "$(dpkg-query -W -f='${Status}\n' "$@" 2>/dev/null | grep -c '^install ok installed$')" = "$#" ]; }
test_packages_setup() {
    installed "${TEST_PACKAGES[@]}" && return 0
    echo "tools.sh: installing Wine, QEMU, aarch64 gcc, valgrind and libclang for the tests (apt, once)"
    apt_install "${TEST_PACKAGES[@]}" || setup_failed tools.sh "apt-get install ${TEST_PACKAGES[*]}" \
        "apt could not install the tests' packages (its message is above)" "Check that Debian's mirrors are reachable, then run again."
}

# Its own step: the browser test is the one test that needs it, and its message names only these.
BROWSER_PACKAGES=(chromium chromium-driver)
browser_setup() {
    installed "${BROWSER_PACKAGES[@]}" && return 0
    echo "tools.sh: installing Chromium and its WebDriver for the browser test (apt, once)"
    apt_install "${BROWSER_PACKAGES[@]}" || setup_failed tools.sh "apt-get install ${BROWSER_PACKAGES[*]}" \
        "apt could not install Chromium (its message is above)" "Check that Debian's mirrors are reachable, then run again."
}

wine_prefix_setup() {
    local source="$ROOT/tests/integration/cross/bcryptprimitives.c" shim="$WINEPREFIX/drive_c/windows/system32/bcryptprimitives.dll"
    if ! [ -f "$WINEPREFIX/system.reg" ]; then
        echo "tools.sh: creating the Wine prefix $WINEPREFIX"
        /usr/lib/wine/wine64 wineboot --init >/dev/null 2>&1
        /usr/lib/wine/wineserver -w
    fi
    if ! [ -f "$shim" ] || [ "$source" -nt "$shim" ]; then
        x86_64-w64-mingw32-gcc -O2 -shared -o "$shim" "$source" -ladvapi32
    fi
}

FMI_SIM_VERSION=0.7.0
fmi_sim_setup() {
    # `fmi-sim --version` prints "Error: fmi-sim 0.7.0" on stderr and fails.
    local found
    found="$("$CONVERTING_SPAN_TOOLS/bin/fmi-sim" --version 2>&1 || true)"
    [[ "$found" == *"fmi-sim $FMI_SIM_VERSION"* ]] && return 0
    echo "tools.sh: installing fmi-sim $FMI_SIM_VERSION (crates.io) into $CONVERTING_SPAN_TOOLS"
    # Unoptimized: a cold build takes about 2 min of CPU instead of about 8 (arrow at
    # opt-level 3), and the tests' 1000 steps still take 0.1 s.
    CARGO_PROFILE_RELEASE_OPT_LEVEL=0 \
        cargo install --quiet --locked --root "$CONVERTING_SPAN_TOOLS" "fmi-sim@$FMI_SIM_VERSION" \
        || setup_failed tools.sh "installing fmi-sim" "cargo install failed (its message is above)" \
            "Check that crates.io is reachable, then run again."
}

export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_LINKER=aarch64-linux-gnu-gcc
export WINEPREFIX="$CONVERTING_SPAN_TOOLS/wine-prefix"
export WINEDEBUG=-all
export CARGO_TARGET_X86_64_PC_WINDOWS_GNU_RUNNER=/usr/lib/wine/wine64
export QEMU_LD_PREFIX=/usr/aarch64-linux-gnu
export CARGO_TARGET_AARCH64_UNKNOWN_LINUX_GNU_RUNNER=qemu-aarch64-static

[ "${SETUP_FUNCTIONS_ONLY:-}" = 1 ] && return 0

python_packages tests "$ROOT/tests/requirements.txt"
test_packages_setup
browser_setup
wine_prefix_setup
fmi_sim_setup
