"""The default demo (fmu/demo.py, run by fmu/main.sh): it feeds every input of
the FMU, so FMPy prints no "missing input" warning, and the frame inputs it
holds at their start values change nothing."""

import subprocess
import sys

from conftest import ROOT


def test_demo_runs_without_fmpy_warnings(fmu_path, tmp_path):
    p = subprocess.run([sys.executable, "fmu/demo.py", str(fmu_path), "--out", str(tmp_path)],
                       cwd=ROOT, capture_output=True, text=True, check=True)
    assert "Warning" not in p.stdout + p.stderr, p.stdout + p.stderr
    assert "released" in p.stdout
    header = (tmp_path / "default_scene.csv").read_text().splitlines()[0]
    assert header.startswith('"time","web_a.v","v","T"'), header
