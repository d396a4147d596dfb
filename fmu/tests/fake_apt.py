#!/usr/bin/env python3
"""apt-get, apt-cache and dpkg-query as the set-up's tests need them (installed
under those names in a test's PATH): each call is appended to $FAKE_APT/calls, and it does what
the set-up asks of apt without touching the machine.

    apt-get update | install -y PKG... | satisfy [-s] [-y] FIELD | download PKG=VERSION...
    apt-cache policy rustc-web | depends PKG=VERSION | show PKG

$FAKE_APT/fail holds what fails, a line each ("update", "install PKG",
"satisfy", "download", "candidate": no rustc-web offered); $FAKE_APT/inst
means the Depends are not installed yet. Installing the
MinGW-w64 package puts fake x86_64-w64-mingw32-gcc and -dlltool into
$FAKE_APT/bin. A download writes small .deb files of the rustc-web
packages whose rustc and cargo are fake_cargo.sh (test_setup.py).
"""

import os
import subprocess
import sys
import tempfile
from pathlib import Path

HOME = Path(os.environ["FAKE_APT"])
VERSION = "9.9.9+fake1"
STD = "libstd-rust-web-9.9"
# What the fake rustc-web packages depend on: a field the set-up passes to `apt-get satisfy`.
DEPENDS = {"rustc-web": "libc6 (>= 2.34), libgcc-s1", "cargo-web": "libc6, libcurl4 (>= 7.16.2)"}


def failing(what: str) -> bool:
    file = HOME / "fail"
    return file.exists() and what in file.read_text().split("\n")


def deb(folder: Path, package: str, version: str) -> None:
    """A .deb of `package` with its rustc or cargo (the fake compiler) in usr/bin."""
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        (root / "DEBIAN").mkdir()
        control = f"Package: {package}\nVersion: {version}\nArchitecture: amd64\nMaintainer: tests\nDescription: fake\n"
        if package in DEPENDS:
            control += f"Depends: {DEPENDS[package]}, {STD} (= {version})\n"
        (root / "DEBIAN" / "control").write_text(control)
        tool = {"rustc-web": "rustc", "cargo-web": "cargo"}.get(package)
        if tool:
            (root / "usr" / "bin").mkdir(parents=True)
            target = root / "usr" / "bin" / tool
            target.write_bytes(Path(__file__).resolve().with_name("fake_cargo.sh").read_bytes())
            target.chmod(0o755)
        subprocess.run(["dpkg-deb", "-Znone", "--build", "--root-owner-group", str(root), str(folder / f"{package}_{version}_amd64.deb")],
                       check=True, capture_output=True)


def apt_get(args):
    options_end = [a for a in args if not a.startswith("-") and not a.startswith("DPkg") and not a.startswith("APT::")]
    command = options_end[0]
    rest = options_end[1:]
    if command == "update":
        return 1 if failing("update") else 0
    if command == "install":
        for package in rest:
            if failing(f"install {package}"):
                print(f"E: Unable to locate package {package}", file=sys.stderr)
                return 100
        with open(HOME / "installed", "a") as installed:
            installed.write("".join(f"{package}\n" for package in rest))
        if "gcc-mingw-w64-x86-64" in rest:
            for tool in ("x86_64-w64-mingw32-gcc", "x86_64-w64-mingw32-dlltool"):
                path = HOME / "bin" / tool
                path.write_text("#!/bin/sh\nexit 0\n")
                path.chmod(0o755)
        return 0
    if command == "satisfy":
        missing = HOME / "inst"  # Depends not yet installed
        if "-s" in args:
            if missing.exists():
                print("Inst libcurl4 (7.88.1-10+deb12u5 Debian:12)")
            return 0
        if failing("satisfy"):
            return 100
        missing.unlink(missing_ok=True)
        return 0
    if command == "download":
        if failing("download"):
            print("E: Failed to fetch", file=sys.stderr)
            return 100
        for item in rest:
            package, _, version = item.partition("=")
            deb(Path.cwd(), package, version)
        return 0
    print(f"fake apt-get: {command} is not faked", file=sys.stderr)
    return 2


def apt_cache(args):
    rest = [a for a in args if not a.startswith("-") and not a.startswith("Dir::")]
    command = rest[0]
    if command == "policy":
        print("rustc-web:\n  Installed: (none)")
        print(f"  Candidate: {'(none)' if failing('candidate') else VERSION}")
        return 0
    if command == "depends":
        print(f"{rest[1].split('=')[0]}\n  Depends: {STD}")
        return 0
    if command == "show":
        return 100  # no package by the library's name (library_package finds none)
    print(f"fake apt-cache: {command} is not faked", file=sys.stderr)
    return 2


def dpkg_query(args):
    """-W -f='${Status}\\n' PKG...: what this fake apt installed."""
    file = HOME / "installed"
    have = set(file.read_text().split()) if file.exists() else set()
    packages = [a for a in args if not a.startswith("-")]
    for package in packages:
        print("install ok installed" if package in have else "unknown ok not-installed")
    return 0 if all(p in have for p in packages) else 1


def main():
    name = Path(sys.argv[0]).name
    with open(HOME / "calls", "a") as log:
        log.write(f"{name} {' '.join(sys.argv[1:])}\n")
    sys.exit({"apt-get": apt_get, "apt-cache": apt_cache, "dpkg-query": dpkg_query}[name](sys.argv[1:]))


if __name__ == "__main__":
    main()
