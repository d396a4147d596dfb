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

    from conftest import ROOT

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
