#!/usr/bin/env bash
# The first run on a clean machine, which this machine's history cannot fake: a
# fresh Debian 12 root (mmdebstrap, minbase), only the README's prerequisites
# installed in it, a clone of this checkout, and both README commands run there
# in a chroot, each timed and its download counted. Not in CI (about 30 minutes);
# run it before any change to the set-up path is called done (docs/testing.md).
#
#   bash tests/clean_machine.sh [--keep] [--only-main]
#
# What the root shares with this machine, and why:
#   - the Rust toolchain: rustup cannot download toolchains here and Debian 12's
#     rustc is too old, so ~/.rustup is bind-mounted (read-only) and rustup's
#     proxies (cargo, rustc) copied to the root's ~/.cargo/bin: what a user who
#     followed the README's "rustup" has;
#   - this machine's network settings for the package registries: its CA
#     certificates, pip's configuration and PIP_* variables, cargo's
#     configuration if any; apt's sources are mmdebstrap's for bookworm (main,
#     updates, security). Nothing of them is written into the repository.
# Nothing else: no tools cache, no apt lists, no packages beyond the prerequisites.
set -euo pipefail
KEEP=0
ONLY_MAIN=0
for arg in "$@"; do
    case "$arg" in
        --keep) KEEP=1 ;;
        --only-main) ONLY_MAIN=1 ;;
        *) echo "usage: bash tests/clean_machine.sh [--keep] [--only-main]" >&2; exit 2 ;;
    esac
done
[ "$(id -u)" = 0 ] || { echo "clean_machine.sh: needs root (mmdebstrap, mount, chroot)" >&2; exit 1; }
HERE="$(cd "$(dirname "$0")/.." && pwd)"
# The README's prerequisites, as Debian packages (tests/python/test_readme.py holds the
# README to this list): Python 3.11 and git. The Rust toolchain comes from rustup (above).
PREREQUISITES=(python3 git)

if ! command -v mmdebstrap >/dev/null; then
    echo "clean_machine.sh: installing mmdebstrap (apt, once)"
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq mmdebstrap >/dev/null
fi
ROOTFS="$(mktemp -d /var/tmp/clean-machine.XXXXXX)"
MOUNTS=()
cleanup() {
    local m
    for ((i = ${#MOUNTS[@]} - 1; i >= 0; i--)); do umount -l "${MOUNTS[i]}" 2>/dev/null || true; done
    if [ "$KEEP" = 1 ]; then echo "clean_machine.sh: the root is kept in $ROOTFS"; else rm -rf "$ROOTFS"; fi
}
trap cleanup EXIT

received() { # bytes received by every network interface but loopback
    local total=0 f
    for f in /sys/class/net/*/statistics/rx_bytes; do
        [[ "$f" == */lo/* ]] || total=$((total + $(cat "$f")))
    done
    echo "$total"
}

RESULTS=()
measure() { # NAME COMMAND...: runs it, notes time, download and result
    local name="$1" t0 rx0 status=0
    shift
    t0=$SECONDS
    rx0=$(received)
    echo "clean_machine.sh: $name"
    "$@" || status=$?
    local mb=$(( ($(received) - rx0) / 1000000 ))
    local verdict=passed
    [ "$status" = 0 ] || verdict="FAILED (exit $status)"
    RESULTS+=("$(printf '%-40s %6d s %7d MB downloaded  %s' "$name" $((SECONDS - t0)) "$mb" "$verdict")")
    return "$status"
}

report() {
    echo
    echo "clean_machine.sh: Debian 12 root $ROOTFS"
    printf '%s\n' "${RESULTS[@]}"
}

measure "clean Debian 12 root (mmdebstrap)" \
    mmdebstrap --quiet --variant=minbase --include="$(IFS=,; echo "${PREREQUISITES[*]}")" bookworm "$ROOTFS"

# This machine's network settings for the registries (see the header).
# The machine's own certificate authorities (update-ca-certificates adds them to the
# bundle when the set-up installs ca-certificates).
mkdir -p "$ROOTFS/usr/local/share/ca-certificates"
cp -r /usr/local/share/ca-certificates/. "$ROOTFS/usr/local/share/ca-certificates/" 2>/dev/null || true
[ -f /etc/pip.conf ] && cp /etc/pip.conf "$ROOTFS/etc/pip.conf"
cp /etc/resolv.conf "$ROOTFS/etc/resolv.conf"
mkdir -p "$ROOTFS/root/.cargo/bin" "$ROOTFS/root/.rustup"
for f in "$HOME"/.cargo/config "$HOME"/.cargo/config.toml; do
    [ -f "$f" ] && cp "$f" "$ROOTFS/root/.cargo/"
done
# rustup's proxies (cargo, rustc, ...), not what `cargo install` put beside them.
for tool in cargo rustc rustup rustdoc rust-gdb rust-lldb rustfmt cargo-fmt cargo-clippy clippy-driver; do
    [ -e "$HOME/.cargo/bin/$tool" ] && cp -L "$HOME/.cargo/bin/$tool" "$ROOTFS/root/.cargo/bin/"
done
ENVIRONMENT=(HOME=/root PATH=/root/.cargo/bin:/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin
    LANG=C.UTF-8 TERM=dumb RUSTUP_HOME=/root/.rustup CARGO_HOME=/root/.cargo)
while IFS='=' read -r name value; do
    ENVIRONMENT+=("$name=$value")
done < <(env | grep -E '^(PIP_|CARGO_HTTP_|CARGO_NET_|CARGO_REGISTRIES_|HTTPS?_PROXY|https?_proxy|NO_PROXY|no_proxy)=' || true)

bind() { # SOURCE TARGET [OPTIONS]
    mkdir -p "$2"
    mount --bind "$1" "$2"
    MOUNTS+=("$2")
    [ -z "${3:-}" ] || mount -o "remount,bind,$3" "$2"
}
bind /proc "$ROOTFS/proc"
bind /sys "$ROOTFS/sys"
bind /dev "$ROOTFS/dev"
bind /dev/pts "$ROOTFS/dev/pts"
bind "${RUSTUP_HOME:-$HOME/.rustup}" "$ROOTFS/root/.rustup" ro

# The checkout as committed: what a clone gets.
git clone --quiet "$HERE" "$ROOTFS/root/ConvertingSpan"
in_root() { # COMMAND: runs it in the root, in the clone, as root
    chroot "$ROOTFS" /usr/bin/env -i "${ENVIRONMENT[@]}" bash -c "cd /root/ConvertingSpan && $1"
}

status=0
measure "bash fmu/main.sh (first run)" in_root "bash fmu/main.sh" || status=$?
if [ "$status" = 0 ] && [ "$ONLY_MAIN" = 0 ]; then
    measure "bash tests/run.sh (after it)" in_root "bash tests/run.sh" || status=$?
fi
report
exit "$status"
