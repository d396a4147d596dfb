# Sourced by tests/run.sh after fmu/env.sh: the importers the tests run besides
# FMPy and the C importer, installed once into the tools cache of fmu/toolchain.sh:
#
#   fmi-sim   rust-fmi's simulator, from crates.io; its build runs bindgen,
#             which needs libclang (Debian libclang-dev)
#
# libcosim comes with the venv (PyPI libcosimpy, fmu/requirements.txt).
FMI_SIM_VERSION=0.7.0
# `fmi-sim --version` prints "Error: fmi-sim 0.7.0" on stderr and fails.
FMI_SIM_FOUND="$("$CONVERTING_SPAN_TOOLS/bin/fmi-sim" --version 2>&1 || true)"
if [[ "$FMI_SIM_FOUND" != *"fmi-sim $FMI_SIM_VERSION"* ]]; then
    dpkg -s libclang-dev >/dev/null 2>&1 || apt_install libclang-dev
    echo "importers.sh: installing fmi-sim $FMI_SIM_VERSION (crates.io) into $CONVERTING_SPAN_TOOLS"
    # Unoptimized: a cold build takes about 2 min of CPU instead of about 8 (arrow at
    # opt-level 3), and the tests' 1000 steps still take 0.1 s.
    CARGO_PROFILE_RELEASE_OPT_LEVEL=0 \
        cargo install --quiet --locked --root "$CONVERTING_SPAN_TOOLS" "fmi-sim@$FMI_SIM_VERSION"
fi
