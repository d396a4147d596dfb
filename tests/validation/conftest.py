"""The physics validation suite: each law checked against what first principles say it must give.

Every expected value here is derived in its test's docstring from a conservation law or a closed
form (momentum, energy, mass, a contact at rest), never taken from an engine: the engines'
comparisons among themselves (webline/tests, tests/integration) prove the code, these prove the
law. A check runs wherever its law applies: the Roller FMU, the Line FMU (FMI 2 and 3, co-simulation
and Model Exchange) and webline's reference. Each tolerance is stated with its reason.

Fixtures: the packaged FMUs (fmu/packaged.py).
"""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "fmu"))
from packaged import fmu_path, fmus, require_sticking_contacts  # noqa: E402, F401 (fmu_path and fmus are fixtures)
