"""The compatibility files fmu/compat.py writes next to each FMU (FMI
cross-check rules): their form, FMPy's own cross-check validation, that the
FMU reproduces its _ref.csv from _in.csv and _ref.opt alone, and that the
references are the exact solutions of their scenes.

Tolerances: reproducing a reference is the same binary, importer and inputs,
so it must be identical to 1e-14 relative (the CSV holds every digit); against
the exact solution the tolerance of conftest.py (1e-12, why given there).
"""

import re
import subprocess
import sys

import numpy as np
import pytest
from fmpy import read_model_description, simulate_fmu
from fmpy.cross_check.validate_vendor_repo import validate_test_fmu
from fmpy.util import read_csv, read_ref_opt_file

from conftest import ABS_STRAIN, ROOT, compare, exact_solution, start_values
from test_roller_fmu import exact_omega

MODELS = ["ConvertingSpan", "Roller"]


@pytest.fixture(scope="module")
def folder(fmus):
    """out/ with both FMUs and their compatibility files (written if missing)."""
    if not all((fmus / f"{m}_ref.csv").exists() for m in MODELS):
        subprocess.run([sys.executable, "fmu/compat.py", str(fmus)], cwd=ROOT, check=True)
    return fmus


@pytest.mark.parametrize("model", MODELS)
def test_files_have_the_cross_check_form(folder, model):
    names = {v.name: v for v in read_model_description(str(folder / f"{model}.fmu")).modelVariables}
    inputs = sorted(n for n, v in names.items() if v.causality == "input")
    for suffix in ("_in.csv", "_ref.csv"):
        path = folder / f"{model}{suffix}"
        assert path.stat().st_size < 1e6, f"{path.name} is over the rules' 1 MB"
        lines = path.read_text().splitlines()
        header = lines[0].split(",")
        assert all(re.fullmatch(r'"[^"]+"', h) for h in header), f"{path.name}: the header must be quoted names"
        columns = [h.strip('"') for h in header]
        assert columns[0] == "time" and set(columns[1:]) <= set(names), f"{path.name}: {columns}"
        assert all(not re.search(r'["a-df-zA-DF-Z]', line) for line in lines[1:]), f"{path.name}: numbers only"
        if suffix == "_in.csv":
            assert sorted(columns[1:]) == inputs, f"{path.name} must hold every input"
        else:
            assert 1 <= len(columns) - 1 <= 10, f"{path.name}: at most 10 variables"
    opt = read_ref_opt_file(folder / f"{model}_ref.opt")
    assert set(opt) == {"StartTime", "StopTime", "StepSize", "RelTol"}
    readme = (folder / "ReadMe.txt").read_text()
    assert f"{model}.fmu" in readme and f"{model}_ref.csv" in readme


@pytest.mark.parametrize("model", MODELS)
def test_fmpys_cross_check_validation_finds_no_problem(folder, model, tmp_path):
    """validate_test_fmu reads the FMI version, type and platform from the rules' folder layout."""
    place = tmp_path / "fmus" / "2.0" / "cs" / "linux64" / "ConvertingSpan" / "0.1.0" / model
    place.mkdir(parents=True)
    for name in (f"{model}.fmu", f"{model}_in.csv", f"{model}_ref.csv", f"{model}_ref.opt", "ReadMe.txt"):
        (place / name).symlink_to(folder / name)
    assert validate_test_fmu(str(place)) == []


def reproduce(folder, model):
    """The simulation the files describe: _ref.opt's settings, _in.csv's inputs, _ref.csv's variables."""
    opt = read_ref_opt_file(folder / f"{model}_ref.opt")
    ref = read_csv(folder / f"{model}_ref.csv")
    result = simulate_fmu(
        str(folder / f"{model}.fmu"), start_time=opt["StartTime"], stop_time=opt["StopTime"],
        output_interval=opt["StepSize"], relative_tolerance=opt["RelTol"],
        input=read_csv(folder / f"{model}_in.csv"), output=list(ref.dtype.names[1:]),
    )
    return ref, result


@pytest.mark.parametrize("model", MODELS)
def test_fmu_reproduces_its_reference(folder, model):
    ref, result = reproduce(folder, model)
    assert len(result) == len(ref) and result["time"][-1] == pytest.approx(ref["time"][-1], abs=1e-12)
    for name in ref.dtype.names[1:]:
        np.testing.assert_allclose(result[name], ref[name], rtol=1e-14, atol=0, err_msg=f"{model}: {name}")


def test_span_reference_is_the_exact_solution(folder, model_description):
    ref = read_csv(folder / "ConvertingSpan_ref.csv")
    exact = exact_solution(start_values(model_description), read_csv(folder / "ConvertingSpan_in.csv"), ref["time"])
    EA = 1.43e10 * 59e-6 * 1.0  # the default wp2: E * thickness * width
    compare("compat: ConvertingSpan_ref.csv", "T", ref["T"], exact["tension"], ABS_STRAIN * EA, times=ref["time"])
    compare("compat: ConvertingSpan_ref.csv", "summary_Strain", ref["summary_Strain"], exact["strain"], ABS_STRAIN,
            times=ref["time"])


def test_roller_reference_is_the_exact_solution(folder):
    ref = read_csv(folder / "Roller_ref.csv")
    table = read_csv(folder / "Roller_in.csv")
    # Pieces from the table: a repeated time starts the next piece.
    pieces = [(t, fu, fd, tau) for t, fu, fd, tau in zip(table["time"], table["web_a.F"], table["web_b.F"], table["tau_m"])]
    pieces = [p for i, p in enumerate(pieces) if i + 1 == len(pieces) or pieces[i + 1][0] != p[0]]
    for t, omega in zip(ref["time"], ref["omega"]):
        exact = float(exact_omega(0.05, 0.05, 0.0, 100.0, pieces, t))
        assert omega == pytest.approx(exact, rel=1e-12), f"omega at t = {t}"
