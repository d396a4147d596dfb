"""Fixtures of webline's tests: the packaged FMUs a line is made of, and where the scenes are.

A test here hands FMPy a logger (simulate_fmu with `logger=`, the call that re-points
FMPy's process-wide logger proxy) only through webline.fmpy_log.collecting(), which points
the proxy back at FMPy's printer afterwards.
"""

import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
FMU = ROOT / "out" / "ConvertingSpan.fmu"
# The web-line scenes of the webline runner.
SCENES = ROOT / "webline" / "scenes"


def _packaged(path):
    """`path` (an FMU in out/), written by fmu/package.py if it is not there yet."""
    if not path.exists():
        subprocess.run(["python3", "fmu/package.py"], cwd=ROOT, check=True)
    assert path.exists(), f"{path} was not written by fmu/package.py"
    return path


@pytest.fixture(scope="session")
def fmu_path():
    """The packaged span FMU."""
    return _packaged(FMU)


@pytest.fixture(scope="session")
def fmus():
    """The folder with both FMUs of a web line (ConvertingSpan.fmu, Roller.fmu), for webline."""
    _packaged(FMU)
    return _packaged(FMU.parent / "Roller.fmu").parent
