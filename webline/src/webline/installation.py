"""Where webline finds what it runs: a checkout of the repository, or the installed wheel.

Run from a checkout (this file at webline/src/webline/ of the repository, as `pip install -e
webline` in fmu/env.sh leaves it), webline uses the FMUs that fmu/package.py builds into the
repository's out/, and builds the Line FMU's description tool with cargo. Installed from the
wheel, it uses what the wheel carries as package data, `webline/data`, read through
importlib.resources: ConvertingSpan.fmu and Roller.fmu (FMI 2.0 and, in fmi3/, 3.0; the
span's library of webs is in its resources/), the Line library and its description tool for
each platform (line/), and the shipped scenes (scenes/). `webline --version` says which.
"""

from __future__ import annotations

import platform
import sys
from importlib import metadata, resources
from pathlib import Path

_REPOSITORY = Path(__file__).resolve().parents[3]
# A checkout: the repository's Cargo.toml and webline/pyproject.toml around this file.
CHECKOUT = _REPOSITORY if (_REPOSITORY / "Cargo.toml").is_file() and \
    (_REPOSITORY / "webline" / "pyproject.toml").is_file() else None
# The wheel's package data (fmu/wheel.py puts it there); a folder, as pip installs a wheel unpacked.
DATA = Path(str(resources.files("webline") / "data"))
FMU_DIR = CHECKOUT / "out" if CHECKOUT else DATA
SCENES = CHECKOUT / "webline" / "scenes" if CHECKOUT else DATA / "scenes"
# The Line FMU's libraries, description tools and documentation page (fmu/package.py writes them).
LINE = "line"
# What to install for a command whose packages are missing: a top-level module -> the extra.
EXTRAS = {"dask": "studies", "distributed": "studies", "pyarrow": "studies", "bokeh": "studies",
          "libcosimpy": "cosim"}


class PlatformError(RuntimeError):
    """This machine's platform has no library among webline's FMUs."""


def version() -> str:
    """webline's version, from the installed package's metadata (pyproject.toml holds it)."""
    try:
        return metadata.version("webline")
    except metadata.PackageNotFoundError:
        return "unknown (not installed: fmu/env.sh installs it)"


def host_platform() -> str:
    """This machine's folder name among the FMUs' binaries (fmu/package.py's names)."""
    machine = platform.machine().lower()
    arch = {"amd64": "x86_64", "arm64": "aarch64"}.get(machine, machine)
    if sys.platform == "win32":
        return "win64" if arch == "x86_64" else f"{arch}-windows"
    if sys.platform == "darwin":
        return "darwin64" if arch == "x86_64" else f"{arch}-darwin"
    if sys.platform.startswith("linux"):
        # The libraries are linked against glibc; musl (Alpine) cannot load them.
        libc = "" if platform.libc_ver()[0] == "glibc" else " (musl)"
        return ("linux64" if arch == "x86_64" else f"{arch}-linux") + libc
    return f"{arch}-{sys.platform}"


def carried_platforms(fmu_dir=None) -> list[str]:
    """The platforms whose Line library the FMU folder holds (fmu/package.py builds the span's,
    the Roller's and the Line's for the same platforms)."""
    binaries = Path(fmu_dir or FMU_DIR) / LINE / "fmi2" / "binaries"
    return sorted(p.parent.name for p in binaries.glob("*/Line.*")) if binaries.is_dir() else []


def require_platform(fmu_dir=None):
    """Stops, in one line, on a machine whose platform the FMUs carry no library for, or none FMPy loads."""
    carried = carried_platforms(fmu_dir)
    host = host_platform()
    if host == "aarch64-linux" and host in carried:
        # FMPy 0.3 names ARM64 Linux linux64 (its fmpy.platform), so an FMI 2.0 FMU's ARM64 library,
        # in binaries/aarch64-linux as FMI 2.0.4 names it, is never the one it loads.
        raise PlatformError(
            "this machine is aarch64-linux: the FMUs carry its library (binaries/aarch64-linux), but FMPy 0.3, "
            "which webline runs them with, loads an FMI 2.0 library from binaries/linux64 here; use them from "
            "another importer on this machine (docs/wheel.md)")
    if carried and host not in carried:
        raise PlatformError(
            f"this machine is {host}, and webline's FMUs in {Path(fmu_dir or FMU_DIR)} carry libraries for "
            f"{', '.join(carried)} only: build them on a {host} machine from the repository and add them with "
            f"`python3 fmu/package.py --add-binary PLATFORM=FOLDER` (docs/platforms.md)")


def describe() -> str:
    """What `webline --version` prints: the version, and which FMUs webline uses and why."""
    carried = ", ".join(carried_platforms()) or "none built yet"
    if CHECKOUT:
        why = (f"the repository's out/, as webline runs from the checkout at {CHECKOUT} "
               "(fmu/package.py builds them there; cargo builds the Line's description tool)")
    else:
        why = "the wheel's package data, as webline is installed and runs from no checkout of the repository"
    return (f"webline {version()}\n"
            f"FMUs: {FMU_DIR}: {why}\n"
            f"platforms: {carried}; this machine: {host_platform()}")


def missing_extra(error: ModuleNotFoundError) -> str | None:
    """The extra that brings a missing module, or None when no extra does."""
    return EXTRAS.get((error.name or "").split(".")[0])
