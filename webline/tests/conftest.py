"""Fixtures of webline's tests: the packaged FMUs a line is made of (fmu/packaged.py), and where
the scenes are.

A test here hands FMPy a logger (simulate_fmu with `logger=`, the call that re-points
FMPy's process-wide logger proxy) only through webline.fmpy_log.collecting(), which points
the proxy back at FMPy's printer afterwards.
"""

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "fmu"))
from packaged import fmu_path, fmus, require_sticking_contacts  # noqa: E402, F401 (fmu_path and fmus are fixtures)

# The web-line scenes of the webline runner.
SCENES = ROOT / "webline" / "scenes"
