"""Model Exchange: the same FMU integrated by FMPy's CVode.

The continuous state is the unstretched length x; FMPy gives CVode
rtol = relative_tolerance and atol = relative_tolerance * nominal (= L), so
CVode controls the error of x relative to x. The tension follows from the
strain L/x - 1, which magnifies a relative error of x by (1+eps)/eps; the
tests therefore check x against the exact solution to CVode's tolerance, and
the tension to that tolerance magnified by (1+eps)/eps.
"""

import mpmath
import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from conftest import simulate_fmu, exact_solution, step_table

# CVode's global error stays within a small multiple of its local tolerance
# on this well-damped linear problem (measured: 1x to 8x from rtol 1e-6 to
# 1e-10); 20x leaves room without hiding a wrong derivative, which would be
# off by orders of magnitude.
GLOBAL_FACTOR = 20.0


def after_events(result):
    """Keep the last row of each time (FMPy records an event twice)."""
    t = result["time"]
    keep = np.append(t[1:] != t[:-1], True)
    return result[keep]


def run_me(fmu_path, rtol, table, start_values=None, stop=2.0, interval=1e-2, logger=None):
    return simulate_fmu(
        fmu_path,
        fmi_type="ModelExchange",
        solver="CVode",
        relative_tolerance=rtol,
        stop_time=stop,
        output_interval=interval,
        start_values=start_values or {},
        input=table,
        output=["unstretchedLength", "summary_Tension", "summary_Strain", "T"],
        logger=logger,
    )


@pytest.mark.parametrize("rtol", [1e-6, 1e-8, 1e-10])
def test_cvode_on_model_exchange_matches_the_exact_solution_to_its_tolerance(fmu_path, defaults, rtol):
    table = step_table(2.0, {"web_a.v": 5.0, "web_a.eps": 1e-3, "web_b.v": 5.0}, [(0.5, {"web_b.v": 5.005})])
    result = after_events(run_me(fmu_path, rtol, table))
    exact = exact_solution(defaults, table, result["time"])
    x_err = max(abs(float((mpmath.mpf(float(a)) - b) / b)) for a, b in zip(result["unstretchedLength"], exact["x"]))
    assert x_err <= GLOBAL_FACTOR * rtol, f"state error {x_err:.2e} at rtol {rtol}"
    magnification = max(float((1 + e) / abs(e)) for e in exact["strain"])
    t_err = max(abs(float((mpmath.mpf(float(a)) - b) / b)) for a, b in zip(result["summary_Tension"], exact["tension"]))
    assert t_err <= GLOBAL_FACTOR * rtol * magnification, f"tension error {t_err:.2e} at rtol {rtol}"
    print(f"rtol {rtol:.0e}: state error {x_err:.1e}, tension error {t_err:.1e}")


def test_the_slack_event_indicator_makes_cvode_stop_at_the_crossing(fmu_path, defaults):
    # The downstream roller slows by 1 %: the strain falls through zero. With
    # preventNegativeTension the event indicator (the bracket of [E5]) crosses
    # zero there; FMPy then records the event time twice. The exact crossing:
    # x(t) = L, from the closed form of the balance.
    table = step_table(1.0, {"web_a.v": 5.0, "web_a.eps": 1e-3, "web_b.v": 5.0}, [(0.1, {"web_b.v": 4.95})])
    values = {"preventNegativeTension": True}
    result = run_me(fmu_path, 1e-10, table, values, stop=1.0, interval=0.05)
    t = result["time"]
    events = sorted(set(t[1:][t[1:] == t[:-1]]) - {0.1})
    L, q, lam = 1.0, 5.0 / 1.001, 4.95
    x0, x_inf = 1.0 / 1.001, q / lam
    crossing = 0.1 + float(mpmath.log((x0 - x_inf) / (L - x_inf)) / lam)
    assert events and abs(events[0] - crossing) < 1e-6, f"events {events}, exact crossing {crossing}"
    slack = result["time"] > crossing + 1e-6
    assert np.all(result["summary_Tension"][slack] == 0.0)
    assert np.all(result["summary_Strain"][slack] < 0.0), "the strain itself goes negative"


def test_no_event_indicator_crossings_without_the_slack_option(fmu_path):
    table = step_table(1.0, {"web_a.v": 5.0, "web_a.eps": 1e-3, "web_b.v": 5.0}, [(0.1, {"web_b.v": 4.95})])
    result = run_me(fmu_path, 1e-8, table, stop=1.0, interval=0.05)
    t = result["time"]
    assert set(t[1:][t[1:] == t[:-1]]) <= {0.1}, "only the input step is an event"
    assert result["summary_Tension"][-1] < 0.0, "without the option the web takes compression"


@pytest.mark.parametrize(
    "values, needles",
    [
        ({"includeMass": True}, ["includeMass", "Model Exchange", "dv_b/dt"]),
        ({"includeDamping": True, "variableLength": True}, ["includeDamping", "variableLength", "dL/dt"]),
    ],
)
def test_effects_model_exchange_cannot_serve_are_refused_with_a_reason(fmu_path, values, needles):
    messages = []

    def logger(component, instance, status, category, message):
        messages.append(message.decode())

    table = step_table(0.1, {"web_a.v": 5.0, "web_a.eps": 1e-3, "web_b.v": 5.0})
    with pytest.raises(FMICallException):
        run_me(fmu_path, 1e-6, table, values, stop=0.1, logger=logger)
    assert any(all(n in m for n in needles) for m in messages), messages


def test_model_exchange_and_co_simulation_agree(fmu_path):
    # Damping and a slack web are served by both interfaces; at a tight CVode
    # tolerance the two agree to the tension error the state scaling allows.
    table = step_table(1.0, {"web_a.v": 5.0, "web_a.eps": 1e-3, "web_b.v": 5.0}, [(0.2, {"web_b.v": 5.01})])
    values = {"includeDamping": True, "wp2.d_r": 0.01}
    me = after_events(run_me(fmu_path, 1e-11, table, values, stop=1.0, interval=0.01))
    cs = simulate_fmu(fmu_path, fmi_type="CoSimulation", stop_time=1.0, output_interval=0.01,
                      start_values=values, input=table, output=["summary_Tension"])
    common = np.intersect1d(np.round(me["time"], 9), np.round(cs["time"], 9))
    common = common[np.abs(common - 0.2) > 1e-9]  # the step itself: before/after differ by design
    pick = lambda r: r["summary_Tension"][np.searchsorted(np.round(r["time"], 9), common)]
    rel = np.max(np.abs(pick(me) - pick(cs)) / np.abs(pick(cs)))
    assert rel < 1e-6, rel
