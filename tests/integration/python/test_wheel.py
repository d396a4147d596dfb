"""The webline wheel outside the repository (docs/wheel.md).

A fresh venv in a temporary folder outside the repository gets only the wheel from out/dist/
(fmu/wheel.py; its dependencies from the package index or pip's cache). Its `webline`, run
from that folder, must not see the repository (sys.path checked) and must use the wheel's FMUs.
It checks a scene, exports it as SSP, runs it, exports its Line FMU, which FMPy runs and which
is the repository's own export byte for byte (same libraries, line.json and description), and
linearizes it; it refuses a sweep and the libcosim engine, naming their extras, as the base
install pulls neither libcosimpy nor distributed. The last test adds the studies extra from the
same wheel to the same venv and runs a 4-point sweep: the tests run in this file's order."""

import csv
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from webline import linefmu, load_scene  # the repository's own webline, for its own export

ROOT = Path(__file__).resolve().parents[3]

SCENE = "lamination"


def built_wheel() -> Path:
    """The wheel fmu/main.sh and tests/run.sh build; built here from out/ when it is not there."""
    dist = ROOT / "out" / "dist"
    if not list(dist.glob("webline-*-py3-none-any.whl")):
        subprocess.run([sys.executable, "fmu/wheel.py"], cwd=ROOT, check=True)
    (wheel,) = dist.glob("webline-*-py3-none-any.whl")
    return wheel


class Venv:
    """A venv of its own in `folder`; its commands run from `folder`, with no PYTHONPATH."""

    def __init__(self, folder: Path):
        self.folder = folder
        self.bin = folder / "venv" / "bin"
        self.env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PYTHONHOME")}
        subprocess.run(["python3", "-m", "venv", str(folder / "venv")], check=True)

    def run(self, *args, check=True):
        done = subprocess.run(list(args), cwd=self.folder, env=self.env, capture_output=True, text=True)
        if check and done.returncode != 0:
            pytest.fail(f"{' '.join(map(str, args))} exited with {done.returncode}:\n{done.stdout}\n{done.stderr}")
        return done

    def pip(self, *args):
        return self.run(str(self.bin / "python"), "-m", "pip", "install", "--quiet", *args)

    def python(self, code, *args):
        return self.run(str(self.bin / "python"), "-c", code, *map(str, args)).stdout

    def webline(self, *args, check=True):
        return self.run(str(self.bin / "webline"), *map(str, args), check=check)


@pytest.fixture(scope="module")
def venv():
    wheel = built_wheel()
    # Removed afterwards: the venv with the studies extra takes 750 MB.
    with tempfile.TemporaryDirectory(prefix="webline-wheel-user-") as folder:
        folder = Path(folder).resolve()
        assert ROOT not in folder.parents, f"{folder} must lie outside the repository"
        venv = Venv(folder)
        venv.pip(str(wheel))
        venv.wheel = wheel
        yield venv


def test_the_base_install_sees_no_repository_and_pulls_no_extras(venv):
    found = json.loads(venv.python(
        "import importlib.util, json, sys, webline; print(json.dumps({'path': sys.path, 'webline': webline.__file__, "
        "'missing': [m for m in ('libcosimpy', 'distributed', 'dask', 'pyarrow') if importlib.util.find_spec(m) is None]}))"))
    inside = [p for p in found["path"] if p and (Path(p).resolve() == ROOT or ROOT in Path(p).resolve().parents)]
    assert not inside, f"the repository is on the venv's sys.path: {inside}"
    assert Path(found["webline"]).is_relative_to(venv.folder / "venv"), found["webline"]
    assert found["missing"] == ["libcosimpy", "distributed", "dask", "pyarrow"]
    version = venv.webline("--version").stdout
    assert version.startswith(f"webline {venv.wheel.name.split('-')[1]}\n"), version
    assert "the wheel's package data" in version and "linux64" in version, version
    venv.webline("scenes")
    refused = venv.webline("sweep", f"scenes/{SCENE}.json", "--grid", "line.film.L=1 m,2 m", check=False)
    assert refused.returncode == 2, refused
    assert "pip install 'webline[studies]'" in refused.stderr, refused.stderr
    refused = venv.webline("run", f"scenes/{SCENE}.json", "--engine", "libcosim", "--no-plot", check=False)
    assert refused.returncode == 2 and "pip install 'webline[cosim]'" in refused.stderr, refused.stderr


def test_a_scene_runs_exports_and_linearizes_outside_the_repository(venv, tmp_path):
    venv.webline("scenes")
    venv.webline("check", f"scenes/{SCENE}.json")
    venv.webline("export", f"scenes/{SCENE}.json", "-o", "lamination.ssp")
    venv.webline("run", f"scenes/{SCENE}.json", "--report")  # the report's template is the wheel's package data
    assert (venv.folder / "out" / f"{SCENE}.png").stat().st_size > 0
    assert "<h2>Versions</h2>" in (venv.folder / "out" / f"{SCENE}.html").read_text(encoding="utf-8")
    with open(venv.folder / "out" / f"{SCENE}.csv", newline="") as f:
        rows = list(csv.reader(f))
    film_T = float(rows[-1][rows[0].index("film.T [N]")])

    fmu = venv.folder / "line.fmu"
    venv.webline("export", f"scenes/{SCENE}.json", "--fmu", "-o", fmu)
    ours = linefmu.export(load_scene(ROOT / "webline" / "scenes" / f"{SCENE}.json"), tmp_path / "line.fmu")
    assert fmu.read_bytes() == ours.read_bytes(), "the wheel's Line FMU differs from the repository's export"
    # FMPy (the wheel's dependency) runs it as webline run did: 1 ms steps to 3.5 s, the same last tension, exactly.
    last = venv.python("import sys; from fmpy import simulate_fmu; r = simulate_fmu(sys.argv[1], stop_time=3.5, "
                       "step_size=1e-3, output_interval=1e-3, output=['film.T']); print(repr(float(r['time'][-1])), repr(float(r['film.T'][-1])))",
                       fmu).split()
    assert abs(float(last[0]) - 3.5) < 1e-9 and float(last[1]) == film_T, (last, film_T)

    venv.webline("linearize", f"scenes/{SCENE}.json")
    assert (venv.folder / "out" / f"{SCENE}_linear.mat").stat().st_size > 0


def test_the_studies_extra_from_the_same_wheel_sweeps(venv):
    venv.pip(f"{venv.wheel}[studies]")
    venv.webline("scenes")
    venv.webline("sweep", f"scenes/{SCENE}.json", "--grid", "line.rewind.drive.tension=250 N,300 N",
                 "--grid", "line.to_rewind.L=1 m,2 m", "--workers", "1")
    with open(venv.folder / "out" / "sweep.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 4 and not [r for r in rows if r["status"].startswith("failed")], rows


def test_no_wheel_is_built_without_the_fmus(tmp_path):
    refused = subprocess.run([sys.executable, "fmu/wheel.py", "--fmus", str(tmp_path), "--dist", str(tmp_path / "dist")],
                             cwd=ROOT, capture_output=True, text=True)
    assert refused.returncode == 1 and "lacks ConvertingSpan.fmu" in refused.stderr, refused.stderr
    assert not list((tmp_path / "dist").glob("*.whl"))
