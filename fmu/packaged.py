"""The packaged FMUs in out/ as pytest fixtures, for every test folder that runs them
(tests/integration/python and webline/tests import them into their conftest.py)."""

import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
FMU = ROOT / "out" / "ConvertingSpan.fmu"


def packaged(path):
    """`path` (an FMU in out/), written by fmu/package.py if it is not there yet."""
    if not path.exists():
        subprocess.run(["python3", "fmu/package.py"], cwd=ROOT, check=True)
    assert path.exists(), f"{path} was not written by fmu/package.py"
    return path


@pytest.fixture(scope="session")
def fmu_path():
    """The packaged span FMU."""
    return packaged(FMU)


@pytest.fixture(scope="session")
def fmus():
    """The folder with both FMUs of a web line (ConvertingSpan.fmu, Roller.fmu)."""
    packaged(FMU)
    return packaged(FMU.parent / "Roller.fmu").parent


def has_sticking_contacts(fmus) -> bool:
    """Whether the packaged Roller has the contact law that sticks (issue 41): its parameter
    traction.creep, which webline passes with traction.static and brake.creep."""
    import zipfile

    with zipfile.ZipFile(Path(fmus) / "Roller.fmu") as z:
        return 'name="traction.creep"' in z.read("modelDescription.xml").decode()


def require_sticking_contacts(fmus):
    """Skip, saying why, a test that runs a contact or a brake in FMUs whose Roller predates the sticking law."""
    if not has_sticking_contacts(fmus):
        pytest.skip("the packaged Roller has no traction.creep: it predates the contact law that sticks (issue 41), "
                    "which webline passes to every contact and brake; package FMUs that have it")
