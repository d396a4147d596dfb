# Sourced by fmu/main.sh, tests/run.sh and the other scripts: makes sure the
# tools of the main job are there (tests/tools.sh adds the tests' own).
# Creates .venv (the packages of fmu/requirements.txt, cached, and the
# webline runner) on first use, then the build toolchain (fmu/toolchain.sh).
# Every step installs what it needs before it first uses it; one that fails
# says which step, why, and what to do, in one line, and stops the run.
# With SETUP_FUNCTIONS_ONLY=1 it defines its functions and does nothing else
# (fmu/tests/test_setup.py runs the steps one by one).
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="${VENV:-$ROOT/.venv}"
PY="$VENV/bin/python"

# One line naming the failed step and the way out; stops the calling script.
setup_failed() { # SCRIPT STEP WHY WHAT-TO-DO
    echo "$1: $2 failed: $3. $4" >&2
    exit 1
}

# apt runs quietly; its own messages are shown only when it fails.
apt_quiet() { # apt-get ARGUMENTS...
    local log status=0
    log="$(mktemp)"
    DEBIAN_FRONTEND=noninteractive apt-get -qq -o DPkg::Lock::Timeout=300 "$@" >"$log" 2>&1 || status=$?
    [ "$status" = 0 ] || cat "$log" >&2
    rm -f "$log"
    return "$status"
}
# apt's lists are updated once per run, before the first install: a
# machine's lists may be months old.
apt_lists_update() {
    [ -n "${APT_LISTS_UPDATED:-}" ] && return 0
    apt_quiet update && APT_LISTS_UPDATED=1
}
apt_can_install() {
    [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null
}
# The same names go to apt (as root) and into the message (otherwise), so the
# package the message names is the one the set-up installs.
apt_install() { # PACKAGE...
    if ! apt_can_install; then
        echo "env.sh: please install the Debian packages $*, then run again" >&2
        return 1
    fi
    apt_lists_update && apt_quiet install -y "$@"
}
apt_install_satisfy() { # "DEPENDS, FIELD"
    if ! apt_can_install; then
        echo "env.sh: please install what this Depends field names: $1" >&2
        return 1
    fi
    apt_lists_update && apt_quiet satisfy -y "$1"
}

# The C compiler and linker cargo links with, and the certificates pip and cargo
# reach their registries with: installed first, as everything after uses them.
BASE_PACKAGES=(gcc libc6-dev ca-certificates)
base_setup() {
    command -v gcc >/dev/null && [ -f /usr/include/stdio.h ] && [ -s /etc/ssl/certs/ca-certificates.crt ] && return 0
    echo "env.sh: installing ${BASE_PACKAGES[*]} (apt, once)"
    apt_install "${BASE_PACKAGES[@]}" \
        || setup_failed env.sh "installing ${BASE_PACKAGES[*]}" "apt-get could not install them (its message is above)" \
            "Install them, then run again."
}

# The clone's .venv, made with Debian's python3-venv where python3 lacks venv.
VENV_PACKAGE=python3-venv
venv_setup() {
    [ -x "$PY" ] && return 0
    echo "env.sh: creating $VENV"
    python3 -m venv "$VENV" >/dev/null 2>&1 && return 0
    rm -rf "$VENV"
    { apt_install "$VENV_PACKAGE" && python3 -m venv "$VENV"; } \
        || { rm -rf "$VENV"; setup_failed env.sh "creating $VENV" "python3 -m venv does not work here" \
            "Install Debian's $VENV_PACKAGE, then run again."; }
}

# Python packages are installed once per requirements file into the tools
# cache (again when the file changes); the clone's own .venv sees them
# through a .pth file and holds only this clone's webline runner.
python_packages() { # NAME FILE
    local want base site
    want="$(sha256sum "$2" | cut -c1-16)"
    base="$TOOLS/python/$1-$want"
    if ! [ -f "$base/.complete" ]; then
        echo "env.sh: installing the Python packages of ${2#"$ROOT"/} into $base (once)"
        # Only this file's own folder: another clone of another commit may use another's.
        rm -rf "$base"
        { python3 -m venv "$base" && "$base/bin/python" -m pip install --quiet --disable-pip-version-check -r "$2"; } \
            || setup_failed env.sh "pip install -r ${2#"$ROOT"/}" "pip could not install a package (its message is above)" \
                "Check that PyPI is reachable, then run again."
        touch "$base/.complete"
    fi
    site="$("$base/bin/python" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')"
    local pth
    pth="$("$PY" -c 'import sysconfig; print(sysconfig.get_paths()["purelib"])')/converting_span_$1.pth"
    [ "$(cat "$pth" 2>/dev/null)" = "$site" ] || echo "$site" > "$pth"
}

# The webline runner (webline/) and its `webline` command, installed editable
# (its dependencies are the packages above); again when the installed one is
# not this folder's (e.g. after a move).
webline_setup() {
    if [ "$("$PY" -c 'import webline, os; print(os.path.dirname(os.path.dirname(webline.__file__)))' 2>/dev/null)" != "$ROOT/webline/src" ] \
        || [ ! -x "$VENV/bin/webline" ]; then
        echo "env.sh: installing the webline runner into $VENV (pip install -e webline)"
        "$PY" -m pip install --quiet --disable-pip-version-check --no-deps -e "$ROOT/webline" \
            || setup_failed env.sh "pip install -e webline" "pip could not install the webline runner (its message is above)" \
                "Check that PyPI is reachable, then run again."
    fi
}

# The tools cache, outside the work tree: a fresh clone on the same machine reuses it.
TOOLS="${CONVERTING_SPAN_TOOLS:-${XDG_CACHE_HOME:-$HOME/.cache}/converting-span-tools}"
export CONVERTING_SPAN_TOOLS="$TOOLS"

[ "${SETUP_FUNCTIONS_ONLY:-}" = 1 ] && return 0

command -v cargo >/dev/null || setup_failed env.sh "finding cargo" "the Rust toolchain is not on PATH" \
    "Install it with rustup (https://rustup.rs), then run again."
base_setup
mkdir -p "$TOOLS"
venv_setup
python_packages main "$ROOT/fmu/requirements.txt"
webline_setup
export MPLBACKEND=Agg
# zig, cargo-zigbuild and the cross compiler for the FMU's binaries (cached; see the file).
source "$ROOT/fmu/toolchain.sh"
