"""Web records through FMPy (webline/tests/test_records.py: in the webline runner).

* The FMU ships resources/webs.json, byte for byte the repository's library,
  and the Python reader (webline.records) reads every record of it.
* A record by name gives the same numbers as its values set one by one.
* Nonlinear tension: a stress-strain record (a user's file) in a span whose
  strain relaxes after a speed step, against a reference built from the
  exact solution of the balance and SciPy's PCHIP, in co-simulation and in
  Model Exchange, with Kelvin-Voigt damping (the tangent modulus).
"""

import zipfile

import numpy as np
import pytest
from conftest import ROOT
from fmpy import simulate_fmu
from webline import records

USER = ROOT / "tests" / "records" / "user_webs.json"
L, VA, EPS_A, VB0, VB1 = 0.5, 5.0, 1e-3, 5.0, 5.03


def test_the_fmu_ships_the_library_and_python_reads_every_record(fmu_path):
    with zipfile.ZipFile(fmu_path) as z:
        assert z.read("resources/webs.json") == (ROOT / "resources" / "webs.json").read_bytes()
    shipped = records.shipped_library(fmu_path)
    names = set(shipped)
    assert {"PET-12", "BOPP-20", "LDPE-50", "paper-80gsm", "board-350", "Al-foil-9", "PET12-Al9", "PET12-PE50",
            "nonwoven-PP-spunbond", "steel-0.3"} <= names
    assert shipped["nonwoven-PP-spunbond"].table is not None
    for name, r in shipped.items():
        assert r.E > 0 and r.thickness > 0 and r.width > 0 and r.density > 0, name


def test_a_record_by_name_equals_its_values_set_one_by_one(fmu_path):
    r = records.shipped_library(fmu_path)["PET12-Al9"]
    common = dict(includeDamping=True, includeMass=True, **{"web_b.v": 5.01})
    by_name = simulate_fmu(fmu_path, stop_time=0.5, output_interval=1e-3, output=["T", "web_b.F"],
                           start_values={"wp2.record": "PET12-Al9", **common})
    by_value = simulate_fmu(fmu_path, stop_time=0.5, output_interval=1e-3, output=["T", "web_b.F"],
                            start_values={"wp2.E": r.E, "wp2.thickness": r.thickness, "wp2.width": r.width,
                                          "wp2.density": r.density, "wp2.d_r": 0.0, **common})
    assert np.array_equal(by_name["T"], by_value["T"]) and np.array_equal(by_name["web_b.F"], by_value["web_b.F"])


def exact_tension(t, curve, record, damped):
    """The span after web_b.v steps from VB0 to VB1 at t = 0 with the strain
    at its equilibrium: x' = VA/(1+EPS_A) - VB1*x/L, so x relaxes
    exponentially; eps = L/x - 1, deps/dt = -L/x^2 x';
    T = A*(sigma(eps) + d_r*sigma'(eps)*deps/dt)."""
    x_eq = L * VA / (VB1 * (1 + EPS_A))
    x0 = L / (1 + EPS_A)  # equilibrium of the first speed, eps_b = eps_a
    x = x_eq + (x0 - x_eq) * np.exp(-VB1 / L * t)
    dx = VA / (1 + EPS_A) - VB1 * x / L
    eps = L / x - 1
    deps = -L / x**2 * dx
    area = record.width * record.thickness
    return area * (curve.sigma(eps) + (record.d_r * curve.tangent(eps) * deps if damped else 0.0)), eps


def run_table_span(fmu_path, fmi_type, damped, **options):
    inputs = np.array([(0.0, VA, EPS_A, VB1)], dtype=[("time", float), ("web_a.v", float), ("web_a.eps", float), ("web_b.v", float)])
    return simulate_fmu(
        fmu_path, fmi_type=fmi_type, stop_time=0.4, output_interval=2e-3, input=inputs,
        output=["web_a.F", "web_b.eps", "summary_Stress"],
        start_values={"webLibrary": str(USER), "wp2.record": "paper-measured", "L": L, "includeDamping": damped,
                      # eps_start: the equilibrium of the speeds before the step
                      "startAtEquilibrium": False, "eps_start": EPS_A},
        **options,
    )


@pytest.mark.parametrize("damped", [False, True])
def test_nonlinear_tension_in_co_simulation_matches_the_exact_reference(fmu_path, damped):
    record = records.read_library(USER)["paper-measured"]
    curve = record.curve()
    result = run_table_span(fmu_path, "CoSimulation", damped)
    t = result["time"]
    want, eps = exact_tension(t, curve, record, damped)
    assert eps.max() > 0.004 and eps.min() < 0.002, "the run crosses table nodes"
    err = np.max(np.abs(result["web_a.F"] - want) / np.abs(want).max())
    # The exact step is exact to rounding; eps = L/x - 1 at eps ~ 5e-3 keeps
    # about 14 digits, and the cubic adds a few roundings: 1e-11 is ~100x that.
    assert err < 1e-11, f"largest error {err:.1e} of the tension relative to its peak"
    assert np.allclose(result["summary_Stress"], want / (record.width * record.thickness), rtol=1e-11, atol=0)
    print(f"co-simulation, damping {damped}: tension error {err:.1e} relative to its peak")


@pytest.mark.parametrize("damped", [False, True])
def test_nonlinear_tension_in_model_exchange_matches_the_exact_reference(fmu_path, damped):
    record = records.read_library(USER)["paper-measured"]
    curve = record.curve()
    rtol = 1e-10
    result = run_table_span(fmu_path, "ModelExchange", damped, solver="CVode", relative_tolerance=rtol)
    t = result["time"]
    want, eps = exact_tension(t, curve, record, damped)
    err = np.max(np.abs(result["web_a.F"] - want) / np.abs(want).max())
    # CVode's error in x (<= 20*rtol, see test_model_exchange.py) is magnified
    # by (1+eps)/eps ~ 200 in the strain and by E_t*eps/sigma ~ 1 in the stress.
    assert err < 20 * rtol * 200, f"largest error {err:.1e} of the tension relative to its peak"
    print(f"model exchange, damping {damped}: tension error {err:.1e} relative to its peak")
