# Sourced by fmu/main.sh and tests/run.sh: makes sure the tools are there.
# Creates .venv (FMPy, pytest, mpmath, numpy, matplotlib, the webline runner) on first use and
# installs the Debian packages the tests compile with, if they are missing.
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$ROOT/.venv"
PY="$VENV/bin/python"

apt_install() {
    if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null; then
        apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "$@" >/dev/null
    else
        echo "env.sh: please install the Debian packages: $*" >&2
        return 1
    fi
}

command -v cargo >/dev/null || { echo "env.sh: cargo (the Rust toolchain) is needed" >&2; exit 1; }
command -v gcc >/dev/null || apt_install gcc libc6-dev

# The venv is (re)filled whenever fmu/requirements.txt changes: a stamp in
# the venv holds the checksum of the requirements it was installed from.
STAMP="$VENV/.requirements.sha256"
WANT="$(sha256sum "$ROOT/fmu/requirements.txt" | cut -d' ' -f1)"
if [ ! -x "$PY" ]; then
    echo "env.sh: creating $VENV"
    python3 -m venv "$VENV" 2>/dev/null || { apt_install python3-venv && python3 -m venv "$VENV"; }
fi
if [ "$(cat "$STAMP" 2>/dev/null)" != "$WANT" ]; then
    echo "env.sh: installing the Python tools into $VENV (fmu/requirements.txt)"
    (cd "$ROOT/fmu" && "$PY" -m pip install --quiet --disable-pip-version-check -r requirements.txt)
    echo "$WANT" > "$STAMP"
fi
# The webline runner (webline/) and its `webline` command, installed editable;
# again when the installed one is not this folder's (e.g. after a move).
if [ "$("$PY" -c 'import webline, os; print(os.path.dirname(os.path.dirname(webline.__file__)))' 2>/dev/null)" != "$ROOT/webline/src" ] \
    || [ ! -x "$VENV/bin/webline" ]; then
    echo "env.sh: installing the webline runner into $VENV (pip install -e webline)"
    "$PY" -m pip install --quiet --disable-pip-version-check -e "$ROOT/webline"
fi
export MPLBACKEND=Agg
# zig and cargo-zigbuild for the portable FMU binary (cached; see the file).
source "$ROOT/fmu/toolchain.sh"
