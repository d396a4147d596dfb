# Sourced by fmu/main.sh and tests/run.sh: makes sure the tools are there.
# Creates .venv (FMPy, pytest, mpmath, numpy, matplotlib) on first use and
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

if ! "$PY" -c "import fmpy, pytest, mpmath, numpy, matplotlib" 2>/dev/null; then
    echo "env.sh: creating $VENV"
    python3 -m venv "$VENV" 2>/dev/null || { apt_install python3-venv && python3 -m venv "$VENV"; }
    "$PY" -m pip install --quiet --disable-pip-version-check -r "$ROOT/fmu/requirements.txt"
fi
export MPLBACKEND=Agg
