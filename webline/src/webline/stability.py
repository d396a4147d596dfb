"""The line's stable communication step: linearize, build the master's one-step map, find where it diverges.

An explicit master couples FMUs that each integrate their own ODE
(x' = A x + B u, y = C x + D u) over a communication step h with the inputs
the master gave them. Near an operating point every such scheme is a linear
map of what the master carries from one step to the next: the FMUs' states x,
the inputs each FMU last saw at the end of its step (its outputs feed them
through D), and, for extrapolation, the outputs at the previous point. The
scheme is stable when that map's spectral radius is at most 1.

- `linearize(system)`: A, B, C, D of every component from its FMU in Model
  Exchange (`fmi2GetDirectionalDerivative` when provided, else central
  differences), at the system's start.
- `step_map(line, h, algorithm, coupling)`: the exact one-step map of the
  master (docs/stability.md, "The one-step map"); `spectral_radius` of it.
- `stable_step(line, algorithm, coupling)`: the first h, from small h up,
  where the radius passes 1 (a scan, then bisection).
- `predict_step(system)`, `export_step(system)`: the step the SSP export writes.
"""

from __future__ import annotations

import math
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.linalg import expm, null_space

from .linear import Block, Line, Mode, StabilityError, participation

ALGORITHMS = ("jacobi", "gauss-seidel")
COUPLINGS = ("hold", "extrapolate")
# The map is stable when its radius is at most 1 + RADIUS_SLACK: the rounding of
# eigenvalues of a ~20x20 map of entries ~1, not a physical margin.
RADIUS_SLACK = 1e-9
# predict_step: this fraction of the smallest predicted limit (the linearization
# holds at the start; speed and tension change the modes along the run).
SAFETY = 0.5


# ---------------------------------------------------------------- the one-step map


def discretize(block: Block, h: float):
    """Exact discretization over h with the input u0 + s*du (0 <= s <= h) (Van Loan):
    x(h) = Phi x + G0 u0 + G1 du, from expm of [[A, B, 0], [0, 0, I], [0, 0, 0]] h."""
    n, m = block.B.shape
    M = np.zeros((n + 2 * m, n + 2 * m))
    M[:n, :n] = block.A
    M[:n, n : n + m] = block.B
    M[n : n + m, n + m :] = np.eye(m)
    E = expm(M * h)
    return E[:n, :n], E[:n, n : n + m], E[:n, n + m :]


def step_map(line: Line, h: float, algorithm: str, coupling: str) -> np.ndarray:
    """The master's one-step map s_{k+1} = M s_k, s = [x; ue; yp].

    Each quantity is carried as the matrix that gives it from s_k. Per step:
    the outputs at t_k are y = C x + D ue (ue: the inputs the FMU held or
    reached at the end of its last step); each component, in list order for
    Gauss–Seidel or all from the values at t_k for Jacobi, gets its inputs
    from the sources' values (`_inputs`) and steps exactly."""
    if algorithm not in ALGORITHMS or coupling not in COUPLINGS:
        raise ValueError(f"algorithm must be one of {ALGORITHMS}, coupling one of {COUPLINGS}")
    ox, ou, oy, dim = line.offsets()
    I = np.eye(dim)
    X = [I[ox[i] : ox[i + 1]] for i in range(len(line.blocks))]
    UE = [I[ou[i] : ou[i + 1]] for i in range(len(line.blocks))]
    YP = [I[oy[i] : oy[i + 1]] for i in range(len(line.blocks))]
    Y0 = [b.C @ X[i] + b.D @ UE[i] for i, b in enumerate(line.blocks)]
    now = list(Y0)  # each block's outputs as the master sees them now
    prev = list(YP)  # and at the communication point before
    stepped = [False] * len(line.blocks)
    gs = algorithm == "gauss-seidel"
    Xn, UEn = list(X), list(UE)
    for i, b in enumerate(line.blocks):
        u0, du = _inputs(line, i, now, prev, stepped, h, coupling)
        Phi, G0, G1 = discretize(b, h)
        Xn[i] = Phi @ X[i] + G0 @ u0 + G1 @ du
        UEn[i] = u0 + h * du
        if gs:  # later components see this one's outputs at t_k+h, and its value at t_k as the previous one
            prev[i] = Y0[i]
            now[i] = b.C @ Xn[i] + b.D @ UEn[i]
            stepped[i] = True
    return np.vstack(Xn + UEn + Y0)


def _inputs(line: Line, i: int, now, prev, stepped, h, coupling):
    """(value at t_k, slope over the step) of block i's inputs, as matrices of s_k.

    hold: the source's value now, held. extrapolate: a component that takes
    input derivatives gets the line through the last two points (value now,
    slope), or, from a source already stepped (Gauss–Seidel), the line from its
    value at t_k to its value at t_k+h; a component that holds its inputs gets
    that line's value at the middle of the step."""
    b = line.blocks[i]
    dim = now[0].shape[1] if now else 0
    u0 = np.zeros((len(b.inputs), dim))
    du = np.zeros((len(b.inputs), dim))
    for r, (j, o) in enumerate(line.sources[i]):
        n, p = now[j][o], prev[j][o]
        if coupling == "hold":
            u0[r] = n
        elif stepped[j]:  # the line from p (t_k) to n (t_k+h)
            if b.interpolates:
                u0[r], du[r] = p, (n - p) / h
            else:
                u0[r] = 0.5 * (p + n)
        else:  # the line through p (t_k-h) and n (t_k), extrapolated
            if b.interpolates:
                u0[r], du[r] = n, (n - p) / h
            else:
                u0[r] = 1.5 * n - 0.5 * p
    return u0, du


# ---------------------------------------------------------------- radius, marginal modes, the limit


def conserved_modes(line: Line, A_c=None, K=None):
    """The coupled system's rigid-body modes: A_c v = 0 (a free line speed, say).

    Rule: such a v, lifted into the map's state (x = v, ue = K v, yp = the outputs
    it gives), is a fixed point of every consistent master at every h: it is a
    neighbouring steady state, not a growing mode. Exactly these directions are
    taken out of the radius (`spectral_radius`), and only after checking M s = s."""
    if A_c is None:
        A_c, K = line.continuous()
    if A_c.size == 0:
        return np.zeros((0, 0))
    V = null_space(A_c, rcond=1e-10)  # singular values below 1e-10 of the largest: exact zeros in rounding
    if V.size == 0:
        return np.zeros((line.offsets()[3], 0))
    A, B, C, D, P = line.coupling_matrices()
    U = K @ V
    Y = C @ V + D @ U
    return np.vstack([V, U, Y])


def spectral_radius(line: Line, h: float, algorithm: str, coupling: str, conserved=None) -> float:
    """Largest |eigenvalue| of the one-step map, the conserved directions (`conserved_modes`) taken out."""
    M = step_map(line, h, algorithm, coupling)
    S = conserved_modes(line) if conserved is None else conserved
    if S.shape[1]:
        Q, _ = np.linalg.qr(S)
        if np.linalg.norm(M @ Q - Q) > 1e-6 * max(1.0, np.linalg.norm(M)):
            raise StabilityError(f"a rigid-body mode is not a fixed point of the {algorithm}/{coupling} map at h = {h}")
        W = null_space(Q.T)
        M = W.T @ M @ W
    if M.size == 0:
        return 0.0
    return float(np.max(np.abs(np.linalg.eigvals(M))))


def fastest_frequency(line: Line) -> float:
    A_c, _ = line.continuous()
    lam = np.linalg.eigvals(A_c) if A_c.size else np.zeros(0)
    return float(np.max(np.abs(lam))) if lam.size else 0.0


def stable_step(line: Line, algorithm: str, coupling: str, h_range=None, per_decade=24, rtol=1e-4):
    """The largest h below which every step is stable: the first crossing of radius 1 from small h.

    The radius need not grow monotonically with h (a mode can alias back into
    the unit disc), so a scan on a logarithmic grid finds the first unstable
    point and bisection narrows the crossing down to `rtol`. Returns
    (limit, radius function); limit is 0.0 when even the smallest h is
    unstable, inf when none in the range is."""
    S = conserved_modes(line)
    rho = lambda h: spectral_radius(line, h, algorithm, coupling, S)  # noqa: E731
    if h_range is None:
        w = max(fastest_frequency(line), 1e-9)
        h_range = (1e-3 / w, 1e3 / w)
    lo, hi = h_range
    grid = np.geomspace(lo, hi, int(per_decade * math.log10(hi / lo)) + 1)
    good = None
    for h in grid:
        if rho(h) > 1.0 + RADIUS_SLACK:
            if good is None:
                return 0.0, rho
            a, b = good, h
            while b - a > rtol * a:
                mid = math.sqrt(a * b)
                if rho(mid) > 1.0 + RADIUS_SLACK:
                    b = mid
                else:
                    a = mid
            return a, rho
        good = h
    return math.inf, rho


# ---------------------------------------------------------------- modes and the hand estimate


def modes(line: Line) -> list[Mode]:
    """Eigenvalues of the coupled continuous system, fastest first (one of each complex pair)."""
    A_c, _ = line.continuous()
    lam = np.linalg.eigvals(A_c) if A_c.size else np.zeros(0, complex)
    out = [Mode(complex(x)) for x in lam if x.imag >= 0]
    return sorted(out, key=lambda m: -m.omega_n)


def hand_estimate(system) -> list[tuple[str, float, float]]:
    """physics.md's estimate per roller between spans: omega_n = sqrt((k_up + k_down)/m),
    k = E*A/L of each span, m = J/R^2; h ~ 2/omega_n. [(roller, omega_n, h)]."""
    comps = {c.name: c for c in system.components}
    out = []
    for c in system.components:
        if c.kind != "roller" or "J" not in c.start or "R" not in c.start or "speed" in (c.profile or {}):
            continue  # a prescribed speed (source, sink, speed drive) is no mass on the springs
        spans = {conn.source[0] for conn in system.connections if conn.target[0] == c.name and comps[conn.source[0]].kind == "span"}
        k = 0.0
        for s in spans:
            st = comps[s].start
            try:
                k += float(st["wp2.E"]) * float(st["wp2.thickness"]) * float(st["wp2.width"]) / float(st["L"])
            except KeyError:  # a web by record: no E*A here
                k = math.nan
        m = float(c.start["J"]) / float(c.start["R"]) ** 2
        if spans and k > 0:
            w = math.sqrt(k / m)
            out.append((c.name, w, 2.0 / w))
    return out


# ---------------------------------------------------------------- the prediction and its report

VARIANTS = (("jacobi", "hold"), ("jacobi", "extrapolate"), ("gauss-seidel", "hold"), ("gauss-seidel", "extrapolate"))


@dataclass
class Prediction:
    line: Line
    limits: dict  # (algorithm, coupling) -> largest stable step, s (inf: none found, 0: none stable)
    modes: list
    estimate: list  # hand_estimate(system)

    def step(self) -> float:
        """The step to recommend: SAFETY times the smallest limit, rounded down to 1, 2 or 5 times a power of ten."""
        finite = [h for h in self.limits.values() if h > 0.0 and math.isfinite(h)]
        if not finite:
            return math.nan
        return nice_floor(SAFETY * min(finite))


def nice_floor(h: float) -> float:
    """The largest of 1, 2, 5 times a power of ten that is at most h."""
    e = math.floor(math.log10(h))
    for m in (5.0, 2.0, 1.0):
        if m * 10.0**e <= h * (1 + 1e-12):
            return float(f"{m * 10.0**e:.3g}")
    return 10.0 ** (e - 1) * 5


def analyse(system, method: str = "auto", variants=VARIANTS, line=None) -> Prediction:
    """The four couplings' limits at the system's start (`line`: the system already linearized)."""
    from .linearization import linearize

    line = line or linearize(system, method=method)
    limits = {v: stable_step(line, *v)[0] for v in variants}
    return Prediction(line, limits, modes(line), hand_estimate(system))


def predict_step(system) -> float:
    """The communication step the SSP export writes: SAFETY (0.5) times the smallest of the four predicted
    limits (Jacobi and Gauss–Seidel, held and extrapolated inputs), rounded down to 1, 2 or 5 times a power
    of ten. The half is for what the linearization at the start does not see: speeds and tensions that change
    the modes along the run. NaN when no variant has a stable step."""
    return analyse(system).step()


def export_step(system) -> float:
    """The step an export carries (and the engines' agreement runs at): `predict_step` when it is smaller
    than the scene's step, else the scene's."""
    predicted = predict_step(system)  # NaN: no stable step found
    return min(system.step, predicted) if math.isfinite(predicted) else system.step


def _ms(h):
    if h == 0.0:
        return "none stable"
    if not math.isfinite(h):
        return "no limit found"
    return f"{h * 1e3:.4g} ms"


# What `webline check` reports, labelled: webline's own coupling and a plain importer's (stability.PLAIN).
LABELS = ("webline's coupling ({}, {}; `webline run --engine parts`)", "a plain importer's coupling ({}, {}: libcosim, FMPy)")


def report(system, prediction: Prediction, limits=None, n_modes: int = 4) -> str:
    """The modes, the four couplings' limits at the start, and `limits` ([webline's, a plain importer's]
    CouplingLimit, over the run's operating points) labelled."""
    p = prediction
    out = [f"  linearized at t = {system.start_time:g} s: "
           + ", ".join(f"{b.name} ({len(b.states)} states, {b.method})" for b in p.line.blocks)]
    out += [f"  note: {n}" for n in p.line.notes]
    fast = [m for m in p.modes if m.omega_n > 0][:n_modes]
    if fast:
        out.append("  fastest modes:  omega_n [rad/s]  frequency [Hz]  damping ratio")
        out += [f"  {'':14}{m.omega_n:>14.4g}{m.frequency:>16.4g}{m.damping:>15.3g}" for m in fast]
    out.append("  largest stable step: " + ", ".join(f"{a} {c} {_ms(h)}" for (a, c), h in p.limits.items()))
    for name, w, h in p.estimate:
        ratio = ""
        jh = p.limits.get(("gauss-seidel", "hold"))
        if jh and math.isfinite(jh):
            ratio = f" (Gauss–Seidel hold predicts {jh / h:.2f} times that)"
        out.append(f"  estimate (physics.md) at {name}: omega_n = sqrt(sum(EA/L)/(J/R^2)) = {w:.4g} rad/s, "
                   f"h ~ 2/omega_n = {_ms(h)}{ratio}")
    for label, lim in zip(LABELS, limits or []):
        out.append(f"  {label.format(lim.algorithm, lim.coupling)}: {lim.describe()}")
    out.append(f"  the SSP export writes {_ms(p.step())} ({SAFETY:g} of the smallest limit at the start, rounded down)")
    return "\n".join(out)


# ---------------------------------------------------------------- a run's own limit, over its speeds

# The importers other than webline couple this way (libcosim, FMPy's simulate_ssp, an SSP export's step).
PLAIN = ("jacobi", "hold")


@dataclass
class CouplingLimit:
    """The largest stable step of one coupling over a run's operating points, and where it is set."""

    algorithm: str
    coupling: str
    limit: float  # s (inf: none found, 0: none stable)
    part: str  # the component whose states carry the mode that grows first
    time: float  # the operating point (time of the run) that sets it

    def step(self) -> float:
        """The step to use: SAFETY times the limit, rounded down to 1, 2 or 5 times a power of ten."""
        return nice_floor(SAFETY * self.limit) if 0.0 < self.limit < math.inf else math.nan

    def describe(self) -> str:
        if self.limit == 0.0:
            return f"no step is stable (the mode of {self.part} grows at every step)"
        if not math.isfinite(self.limit):
            return "no limit found"
        where = "at the start" if self.time == 0.0 else f"at t = {self.time:g} s"
        return f"stable up to {_ms(self.limit)}, set by {self.part} {where}; use {_ms(self.step())}"


def growing_part(line: Line, h: float, algorithm: str, coupling: str) -> str:
    """The block whose states and signals carry most of the one-step map's largest mode at h
    (participation factors |l_k r_k|: the same whatever units the states are in)."""
    lam, P, _, _ = participation(step_map(line, h, algorithm, coupling))
    p = P[:, int(np.argmax(np.abs(lam)))]
    ox, ou, oy, _ = line.offsets()
    share = [p[ox[k]:ox[k + 1]].sum() + p[ou[k]:ou[k + 1]].sum() + p[oy[k]:oy[k + 1]].sum() for k in range(len(line.blocks))]
    return line.blocks[int(np.argmax(share))].name


def operating_lines(scene, fmu_dir=None, method="auto") -> list:
    """[(t, Line)]: the line linearized at each operating point of its run (`Scene.speed_times`: the
    start, and where the prescribed speeds are slowest and fastest, the line in its steady state then)."""
    from .compiler import compile_scene
    from .linearization import linearize

    return [(t, linearize(compile_scene(scene, fmu_dir, settle=False, at=t), method=method)) for t in scene.speed_times()]


def coupling_limits(points, couplings=(("gauss-seidel", "extrapolate"),), kind_of=None) -> list[CouplingLimit]:
    """Each coupling's largest stable step over the operating points [(t, Line)] (`operating_lines`), the
    smallest kept with the part that sets it; `kind_of(name)` gives a part's kind for the message."""
    out = []
    for algorithm, coupling in couplings:
        h, t, line = min(((stable_step(line, algorithm, coupling)[0], t, line) for t, line in points), key=lambda x: x[0])
        probe = h * 1.01 if 0.0 < h < math.inf else 1e-3 / max(fastest_frequency(line), 1e-9)
        name = growing_part(line, probe, algorithm, coupling) if math.isfinite(h) else ""
        part = f"{kind_of(name) if kind_of else 'part'} {name!r}" if name else "none"
        out.append(CouplingLimit(algorithm, coupling, h, part, t))
    return out


class UnstableStep(StabilityError):
    """A co-simulation asked for at a step above its coupling's predicted limit."""


def refuse_unstable(lines, name: str, step: float, algorithm: str, coupling: str, kind_of=None) -> CouplingLimit:
    """The coupling's limit over the operating points (`coupling_limits`); UnstableStep, in one line, when
    `step` is above it."""
    (lim,) = coupling_limits(lines, ((algorithm, coupling),), kind_of)
    if lim.limit == 0.0:
        raise UnstableStep(f"{name}: no step is stable with webline's {algorithm}/{coupling} coupling for this line "
                           f"(the mode of {lim.part} grows at every step): use another --algorithm or --coupling, or "
                           "--engine line (exact at any step); --force runs it anyway")
    if step > lim.limit:
        where = "" if lim.time == 0.0 else f" at t = {lim.time:g} s"
        raise UnstableStep(f"{name}: a step of {_ms(step)} is above the largest stable step of webline's {algorithm}/"
                           f"{coupling} coupling for this line, {_ms(lim.limit)} (set by {lim.part}{where}): use --step "
                           f"{_ms(lim.step()).replace(' ', '')} or less, or --engine line (exact at any step); --force runs it anyway")
    return lim
