"""The stable-step prediction (webline/src/webline/stability.py, docs/stability.md).

First on a line of springs and a mass written here by hand (x1' = v - v_a,
x2' = v_b - v, m v' = F2 - F1, F = k x + c x'), where the limits are known in
closed form and the one-step map can be checked against an independent
simulation of the master's rules; then on lines of FMUs.
"""

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from webline.stability import Block, Line, conserved_modes, spectral_radius, stable_step, step_map

from .conftest import ROOT, SCENES


def spring_line(k=1e6, m=0.04, c=0.0):
    """source -> span1 -> idler -> span2 -> sink; source and sink speeds held (not blocks).
    Order: idler first, then the spans (the Gauss–Seidel order of the System)."""
    idler = Block("idler", A=np.zeros((1, 1)), B=np.array([[-1 / m, 1 / m]]), C=np.eye(1), D=np.zeros((1, 2)),
                  states=["v"], inputs=["F_up", "F_down"], outputs=["v"], interpolates=False)
    # span1: x' = v_b (its input: the idler's speed); F = k x + c x'
    span1 = Block("span1", A=np.zeros((1, 1)), B=np.array([[1.0]]), C=np.array([[k]]), D=np.array([[c]]),
                  states=["x"], inputs=["web_b.v"], outputs=["F"], interpolates=True)
    # span2: x' = -v_a
    span2 = Block("span2", A=np.zeros((1, 1)), B=np.array([[-1.0]]), C=np.array([[k]]), D=np.array([[-c]]),
                  states=["x"], inputs=["web_a.v"], outputs=["F"], interpolates=True)
    return Line([idler, span1, span2], [[(1, 0), (2, 0)], [(0, 0)], [(0, 0)]])


def omega(k=1e6, m=0.04):
    return math.sqrt(2 * k / m)


def simulate(line: Line, h, algorithm, coupling, s0, steps):
    """The master's rules step by step, each block integrated by solve_ivp (independent of `discretize`)."""
    blocks = line.blocks
    ox, ou, oy, dim = line.offsets()
    x = [s0[ox[i]:ox[i + 1]].copy() for i in range(len(blocks))]
    ue = [s0[ou[i]:ou[i + 1]].copy() for i in range(len(blocks))]
    yp = [s0[oy[i]:oy[i + 1]].copy() for i in range(len(blocks))]
    for _ in range(steps):
        y0 = [b.C @ x[i] + b.D @ ue[i] for i, b in enumerate(blocks)]
        now, prev, done = list(y0), list(yp), [False] * len(blocks)
        nx, nue = list(x), list(ue)
        for i, b in enumerate(blocks):
            u0, du = np.zeros(len(b.inputs)), np.zeros(len(b.inputs))
            for r, (j, o) in enumerate(line.sources[i]):
                n, p = now[j][o], prev[j][o]
                if coupling == "hold":
                    u0[r] = n
                elif done[j]:
                    u0[r], du[r] = (p, (n - p) / h) if b.interpolates else (0.5 * (p + n), 0.0)
                else:
                    u0[r], du[r] = (n, (n - p) / h) if b.interpolates else (1.5 * n - 0.5 * p, 0.0)
            sol = solve_ivp(lambda t, z: b.A @ z + b.B @ (u0 + t * du), (0, h), x[i], rtol=1e-12, atol=1e-14, method="DOP853")
            nx[i], nue[i] = sol.y[:, -1], u0 + h * du
            if algorithm == "gauss-seidel":
                prev[i], now[i], done[i] = y0[i], b.C @ nx[i] + b.D @ nue[i], True
        x, ue, yp = nx, nue, y0
    return np.concatenate(x + ue + yp)


@pytest.mark.parametrize("algorithm", ["jacobi", "gauss-seidel"])
@pytest.mark.parametrize("coupling", ["hold", "extrapolate"])
def test_map_is_the_master(algorithm, coupling):
    """M^k s0 equals the master's rules simulated step by step: to 1e-8 of the state's size
    (solve_ivp at rtol 1e-12 over 6 steps of a map with entries up to 1e6*h)."""
    line = spring_line(c=2e2)
    h = 0.5 / omega()
    rng = np.random.default_rng(1)
    s0 = rng.normal(size=line.offsets()[3]) * np.array([1.0, 1e-6, 1e-6, 1e-3, 1e-3, 1.0, 1.0, 1.0, 1.0, 1.0])
    s0[5:] *= 1.0
    M = step_map(line, h, algorithm, coupling)
    want = simulate(line, h, algorithm, coupling, s0, 6)
    got = np.linalg.matrix_power(M, 6) @ s0
    scale = np.maximum(np.abs(want), 1e-6 * np.abs(want).max())
    assert np.max(np.abs(got - want) / scale) < 1e-8


def test_gauss_seidel_hold_is_symplectic_euler():
    """Undamped, Gauss–Seidel with held inputs is symplectic Euler on the idler's mode:
    stable exactly up to h*omega_n = 2 (omega_n = sqrt(2k/m), physics.md)."""
    line = spring_line()
    limit, rho = stable_step(line, "gauss-seidel", "hold")
    assert limit == pytest.approx(2 / omega(), rel=1e-3)
    assert rho(1.01 * 2 / omega()) > 1.001


def test_jacobi_hold_undamped_has_no_stable_step():
    """Undamped, Jacobi with held inputs is explicit Euler on the mode: |lambda|^2 = 1 + (h omega)^2 > 1 at every h."""
    line = spring_line()
    limit, rho = stable_step(line, "jacobi", "hold")
    assert limit == 0.0
    h = 0.1 / omega()
    assert rho(h) == pytest.approx(math.sqrt(1 + (h * omega()) ** 2), rel=1e-9)


def test_damping_gives_jacobi_a_step():
    """With damping (c = k*d_r) Jacobi-hold has a stable step, shorter than 2/omega_n."""
    line = spring_line(c=1e6 * 2e-5)
    limit, _ = stable_step(line, "jacobi", "hold")
    assert 0.0 < limit < 2 / omega()


def test_conserved_length_is_excluded_by_rule():
    """x1 + x2 (the web between the fixed-speed ends) is conserved: A_c has a zero eigenvalue, the map an
    eigenvalue 1 at every h. The rule takes out exactly that direction; a growing mode is not taken out."""
    line = spring_line(c=200.0)
    S = conserved_modes(line)
    assert S.shape[1] == 1
    h = 0.3 / omega()
    M = step_map(line, h, "gauss-seidel", "hold")
    lam = np.linalg.eigvals(M)
    assert np.min(np.abs(lam - 1.0)) < 1e-9  # the map does have the eigenvalue 1
    assert spectral_radius(line, h, "gauss-seidel", "hold") < 1.0 - 1e-6  # the rest decays
    # Without the rule the radius would be 1 (not a decay); a damped line far beyond its limit still grows.
    assert spectral_radius(line, 3 / omega(), "gauss-seidel", "hold") > 1.0


# ---------------------------------------------------------------- FMUs


def span_component(name="s", E=4e9, thickness=5e-4, L=0.2, d_r=1e-4, damping=True, eps=1e-3, v=2.0, fmu=None):
    from types import SimpleNamespace

    start = {"L": L, "startAtEquilibrium": False, "eps_start": eps, "web_a.v": v, "web_a.eps": eps, "web_b.v": v * 1.001,
             "includeDamping": damping}
    for w in ("wp1", "wp2"):
        start.update({f"{w}.record": "", f"{w}.E": E, f"{w}.thickness": thickness, f"{w}.width": 1.0,
                      f"{w}.density": 800.0, f"{w}.d_r": d_r})
    return SimpleNamespace(name=name, kind="span", fmu=fmu or ROOT / "out" / "ConvertingSpan.fmu", start=start, profile=None)


def test_span_jacobians_by_differences(fmu_path, tmp_path):
    """The span's Jacobians through FMPy by central differences against the material balance written
    out here: x' = v_a/(1+eps_a) - v_b*x/L, eps = L/x - 1, F = EA*(eps + d_r*eps'). Relative 1e-6:
    the differences' truncation and rounding are below 1e-9 (RELATIVE_STEP 1e-6)."""
    from webline.linearization import ModelInstance

    c = span_component(fmu=fmu_path)
    st = c.start
    m = ModelInstance(c, 0.0, tmp_path)
    try:
        (x,) = m.states()
        J = m.jacobians_by_differences(["web_a.v", "web_a.eps", "web_b.v"], ["web_a.F", "web_b.eps"])
    finally:
        m.free()
    L, va, ea, vb = st["L"], st["web_a.v"], st["web_a.eps"], st["web_b.v"]
    EA, d_r = st["wp2.E"] * st["wp2.thickness"] * st["wp2.width"], st["wp2.d_r"]
    dxdot = np.array([-vb / L, 1 / (1 + ea), -va / (1 + ea) ** 2, -x / L])  # d x' / d(x, v_a, eps_a, v_b)
    deps_dx = -L / x**2
    xdot = va / (1 + ea) - vb * x / L
    dF = EA * (np.array([deps_dx, 0, 0, 0]) + d_r * (deps_dx * dxdot + np.array([2 * L / x**3 * xdot, 0, 0, 0])))
    want = np.vstack([dxdot, dF, [deps_dx, 0, 0, 0]])
    scale = np.abs(want).max(axis=1, keepdims=True)
    assert np.max(np.abs(J - want) / scale) < 1e-6


# ---------------------------------------------------------------- lines of FMUs: prediction against runs
#
# A run starts from the line's steady state with the light roller's speed disturbed (DISTURBANCE), and
# takes N steps, N chosen so that the predicted growth at 1.25x, rho^N, is at least 1e4. Deviation:
# the largest |T - T_start| over the spans at a communication point. "Bounded": the deviation over the
# last quarter of the run stays below 2x the largest of the first 10 steps (a decaying or marginal
# mode passes; any mode growing by rho^N >= 1e4 does not). "Grows": the last deviation is at least 100x
# the largest of the first 10 steps.

DISTURBANCE = 1e-5  # m/s on the light roller's speed: the deviations stay linear (T changes by < 1 N)
GROWTH = 1e4


def light_idler_scene(tmp_path):
    """Thick PET (E*A = 9e5 N, Kelvin-Voigt d_r = 0.2 ms) over two 0.9 m spans, k = E*A/L = 1e6 N/m,
    around an idler of J = 4e-4 kg.m2, R = 0.05 m (m = 0.16 kg): omega_n = sqrt(2k/m) = 3536 rad/s."""
    import json

    scene = {
        "name": "light_idler", "stop_time": "0.1 s", "step": "0.1 ms",
        "webs": {"PET": {"E": "4.5 GPa", "thickness": "0.2 mm", "width": "1 m", "density": "1390 kg/m3", "d_r": "0.2 ms"}},
        "line": [
            {"type": "source", "name": "infeed", "speed": "2 m/s", "strain": 0.001},
            {"type": "span", "name": "first", "L": "0.9 m", "web": "PET", "effects": ["includeDamping"]},
            {"type": "roller", "name": "idler", "J": "0.0004 kg.m2", "R": "0.05 m"},
            {"type": "span", "name": "second", "L": "0.9 m", "web": "PET", "effects": ["includeDamping"]},
            {"type": "sink", "name": "outfeed", "speed": "2 m/s"},
        ],
    }
    path = tmp_path / "light_idler.json"
    path.write_text(json.dumps(scene))
    return path


def compiled(path, fmus):
    from webline.scene import load_scene
    from webline.compiler import compile_scene

    system = compile_scene(load_scene(path), fmus)
    system.record = [(c.name, "summary_Tension") for c in system.components if c.kind == "span"]
    system.sums = None  # every span's own tension, a laminate's layers each (its columns are these variables)
    return system


def disturbed(system, roller, h, n, dv=DISTURBANCE):
    import copy

    s = copy.deepcopy(system)
    s.component(roller).start["v_start"] += dv
    s.stop_time = s.start_time + n * h
    s.step = h
    return s


def run_webline(system, h):
    from webline.master import Master, Options

    r = Master(system, Options.engine(step=h)).run()
    return r.data[1:]  # the rows after each step


def run_libcosim(system, h, tmp_path):
    """The System built directly in libcosim: a local slave per component, its start values, its connections."""
    from fmpy import read_model_description
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver
    from libcosimpy.CosimSlave import CosimLocalSlave
    from webline.system import component_fmus

    log_output_level(CosimLogLevel.ERROR)
    ns = int(round(h * 1e9))
    assert abs(ns - h * 1e9) < 1e-6, "steps in whole nanoseconds (libcosim's time unit)"
    n = int(round((system.stop_time - system.start_time) / h))
    fmus = component_fmus(system, tmp_path / "fmus")
    ex = CosimExecution.from_step_size(step_size=ns)
    index, vr = {}, {}
    for c in system.components:
        i = ex.add_local_slave(CosimLocalSlave(fmu_path=str(fmus[c.name]), instance_name=c.name))
        index[c.name] = i
        md = {v.name: v for v in read_model_description(str(fmus[c.name])).modelVariables}
        vr[c.name] = {name: v.valueReference for name, v in md.items()}
        for name, value in c.start.items():
            t = md[name].type
            ok = (ex.real_initial_value(i, md[name].valueReference, float(value)) if t == "Real"
                  else ex.boolean_initial_value(i, md[name].valueReference, bool(value)) if t == "Boolean"
                  else ex.integer_initial_value(i, md[name].valueReference, int(value)) if t == "Integer"
                  else ex.string_initial_value(i, md[name].valueReference, str(value)))
            assert ok, f"libcosim refused {c.name}.{name} = {value}"
    for conn in system.connections:
        (a, y), (b, u) = conn.source, conn.target
        assert ex.connect_real_variables(index[a], vr[a][y], index[b], vr[b][u]) == 0  # cosim_success
    observer = CosimObserver.create_last_value()
    ex.add_observer(observer)
    rows = []
    for _ in range(n):
        assert ex.step()
        rows.append([observer.last_real_values(index[c], [vr[c][v]])[0] for c, v in system.record])
    return np.array(rows)


def deviation(rows, start):
    return np.max(np.abs(rows - start), axis=1)


def judged(rows, start):
    d = deviation(np.asarray(rows), start)
    first = d[:10].max()
    return d, first, d[-len(d) // 4 :].max() <= 2 * first, d[-1] >= 100 * first


LINES = {
    "light_idler": (light_idler_scene, "idler"),
    "lamination": (lambda tmp: SCENES / "lamination.json", "idler"),
    # A nip where two webs merge: the foil's side path (its idler, the line's fastest mode) is in the analysis.
    "laminator": (lambda tmp: SCENES / "laminator.json", "guide_foil"),
}
OBSERVED = {}


@pytest.fixture(scope="module")
def predictions(fmus, tmp_path_factory):
    from webline.stability import analyse

    out = {}
    for name, (scene, roller) in LINES.items():
        system = compiled(scene(tmp_path_factory.mktemp(name)), fmus)
        p = analyse(system, variants=[("jacobi", "hold")])
        h = p.limits[("jacobi", "hold")]
        assert 0 < h < math.inf, f"{name}: no finite Jacobi-hold limit"
        rho = spectral_radius(p.line, 1.25 * h, "jacobi", "hold")
        n = int(math.ceil(math.log(GROWTH) / math.log(rho)))
        # The run ends before the first profile breakpoint (lamination: the nip starts at 0.2 s): the
        # linearization at the start holds while the profiles stand still.
        quiet = (system.breakpoints() or [system.stop_time])[0] - system.start_time
        n = min(n, int(quiet / (1.25 * h)))
        assert rho**n >= 300, f"{name}: the predicted growth rho^n = {rho**n:.3g} is too small to see"
        out[name] = (system, roller, h, n, rho, p.line)
    return out


@pytest.mark.parametrize("engine", ["webline", "libcosim"])
@pytest.mark.parametrize("line", list(LINES))
def test_predicted_step_separates_bounded_from_growing(predictions, line, engine, tmp_path):
    system, roller, h_pred, n, rho, _ = predictions[line]
    assert n <= 20000, f"{line}: rho(1.25 h) = {rho}: the growth would take {n} steps"
    run = (lambda s, h: run_webline(s, h)) if engine == "webline" else (lambda s, h: run_libcosim(s, h, tmp_path))
    for factor, want_bounded in ((0.8, True), (1.25, False)):
        h = round(factor * h_pred * 1e9) / 1e9  # whole nanoseconds, for libcosim
        rows = run(disturbed(system, roller, h, n), h)
        base = run(disturbed(system, roller, h, 1, dv=0.0), h)[0]  # the steady line's tensions
        d, first, bounded, grows = judged(rows, base)
        half = len(d) // 2
        rate = (d[-1] / d[half]) ** (1.0 / (len(d) - 1 - half))  # growth per step over the second half
        OBSERVED[(line, engine, factor)] = (h, d[-1] / first, rate, spectral_radius(predictions[line][5], h, "jacobi", "hold"))
        if want_bounded:
            assert bounded, f"{line} in {engine} at {factor} x {h_pred:.4g} s: deviation grew {d[-1] / first:.3g} x in {n} steps"
        else:
            assert grows, f"{line} in {engine} at {factor} x {h_pred:.4g} s: deviation only {d[-1] / first:.3g} x in {n} steps"


def teardown_module():
    """Printed with pytest -s: the table of docs/stability.md."""
    for (line, engine, factor), (h, growth, rate, rho) in sorted(OBSERVED.items()):
        print(f"\n{line:12} {engine:9} {factor:5} x: h = {h * 1e3:.4g} ms, deviation x {growth:.3g}, "
              f"growth per step {rate:.5f} (predicted radius {rho:.5f})")


def test_directional_derivatives_agree_with_differences(fmus, tmp_path):
    """Both ways to the Jacobians give the same line: relative 1e-6 per row (the differences' accuracy)."""
    from webline.linearization import linearize
    from fmpy import read_model_description

    if not any(read_model_description(str(fmus / f)).modelExchange.providesDirectionalDerivative for f in ("ConvertingSpan.fmu", "Roller.fmu")):
        pytest.skip("no FMU provides directional derivatives yet")
    system = compiled(light_idler_scene(tmp_path), fmus)
    a, b = linearize(system, method="auto"), linearize(system, method="differences")
    for x, y in zip(a.blocks, b.blocks):
        for M, N in ((x.A, y.A), (x.B, y.B), (x.C, y.C), (x.D, y.D)):
            if M.size:
                scale = np.maximum(np.abs(N).max(axis=1, keepdims=True), 1e-300)
                assert np.max(np.abs(M - N) / scale) < 1e-6, x.name
