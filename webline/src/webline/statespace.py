"""A line's state-space model from its Line FMU: A, B, C, D at a time, its modes, a frequency response
(Bode plots as CSV and PNG) and a step response.

The scene is exported as one Line FMU (`linefmu.export`), instantiated in Model
Exchange, run there with FMPy's CVode to the time asked (from its start, the
equilibrium unless the scene says given) and linearized with
fmi2GetDirectionalDerivative: dx' = A dx + B du, dy = C dx + D du around the
states, inputs and outputs it has then. The inputs are all the Line's inputs
(motor torques, dancers' loads), the outputs all its outputs.

The Line's directional derivatives are central differences of the line, about
1e-7 relative (docs/line-fmu.md, Limits); each mode carries what such an error
of A's entries can move its eigenvalue by (`LineMode.error`).
"""

from __future__ import annotations

import copy
import dataclasses
import math
import shutil
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from . import fmpy_log, linefmu
from .linear import Mode, participation
from .linearization import directional_jacobian

# The Line's directional derivatives: central differences, about this relative error per entry.
DERIVATIVE_ACCURACY = 1e-7
# CVode's relative tolerance on the way to the time asked: the operating point to about 1e-9
# of the states, below what the derivatives resolve.
RUN_TOLERANCE = 1e-10
# FMPy's loop stops this often on the way (CVode takes at most 500 steps between two stops).
RUN_INTERVALS = 1000
# A state is steady when its rate is below this fraction of its row's terms |A_ij x_j| and of itself per second.
STEADY = 1e-6
# A mode's parts: those with at least this share of its participation, at most SHOWN_PARTS of them.
SHOWN_SHARE = 0.05
SHOWN_PARTS = 4


@dataclass
class StateSpace:
    """dx' = A dx + B du, dy = C dx + D du around the operating point (x, u, y) at `time`, where the
    states move at x' = dx0 (zero where the line is steady)."""

    scene: str
    time: float
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: list[str]
    inputs: list[str]
    outputs: list[str]
    x: np.ndarray
    u: np.ndarray
    y: np.ndarray
    dx0: np.ndarray
    units: dict = field(default_factory=dict)  # variable name -> unit ("" for none)
    messages: list[str] = field(default_factory=list)  # what the FMU logged as a warning or worse

    def input_index(self, name: str) -> int:
        return _index(name, self.inputs, "input")

    def output_index(self, name: str) -> int:
        return _index(name, self.outputs, "output")

    def moving(self) -> list[tuple[str, float]]:
        """The states that are not steady here, with their rates: those whose x' exceeds STEADY of the
        terms of their row of A (a span's flows, which cancel to rounding when steady) and of the
        state itself per second."""
        scale = np.maximum(np.abs(self.A) @ np.abs(self.x), np.abs(self.x) / 1.0)  # x per second
        return [(s, float(r)) for s, r, c in zip(self.states, self.dx0, scale) if abs(r) > STEADY * c]

    def modes(self) -> list[LineMode]:
        """The eigenvalues of A (one of each complex pair), slowest first, with the parts that move in each."""
        if self.A.size == 0:
            return []
        lam, P, vl, vr = participation(self.A)
        parts = [s.split(".")[0] for s in self.states]
        out = []
        for k in np.argsort(np.abs(lam), kind="stable"):
            if lam[k].imag < 0:
                continue
            share = {}
            for p, part in zip(P[:, k], parts):
                share[part] = share.get(part, 0.0) + float(p)
            ranked = sorted(share.items(), key=lambda kv: -kv[1])
            moving = [(part, s, [st.split(".", 1)[1] for st, q in zip(self.states, P[:, k])
                                 if st.startswith(part + ".") and q >= SHOWN_SHARE * s])
                      for part, s in ranked[:SHOWN_PARTS] if s >= SHOWN_SHARE]
            out.append(LineMode(complex(lam[k]), moving, _eigenvalue_error(self.A, vl[:, k], vr[:, k])))
        return out

    def response(self, input: str, output: str, hz) -> np.ndarray:
        """The frequency response d output / d input at the frequencies `hz`: C (j w I - A)^-1 B + D,
        solved at each frequency (SciPy's freqresp goes through poles and zeros, which loses digits
        on a line whose A spans 1e-1 to 1e6)."""
        i, o = self.input_index(input), self.output_index(output)
        n = self.A.shape[0]
        b, c = self.B[:, i], self.C[o]
        return np.array([c @ np.linalg.solve(2j * math.pi * f * np.eye(n) - self.A, b) + self.D[o, i] for f in hz])

    def write_mat(self, path) -> Path:
        """A MATLAB file (scipy.io.savemat, format 5): A, B, C, D; the names `states`, `inputs`,
        `outputs` as cell arrays of strings; the operating point x0, u0, y0 and the states' rates
        there, dx0; the time `t` (s); the units `state_units`, `input_units`, `output_units`; `scene`."""
        from scipy.io import savemat

        cell = lambda names: np.array(list(names), dtype=object).reshape(-1, 1)  # noqa: E731
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        savemat(path, {
            "A": self.A, "B": self.B, "C": self.C, "D": self.D,
            "states": cell(self.states), "inputs": cell(self.inputs), "outputs": cell(self.outputs),
            "x0": self.x.reshape(-1, 1), "dx0": self.dx0.reshape(-1, 1), "u0": self.u.reshape(-1, 1),
            "y0": self.y.reshape(-1, 1), "t": float(self.time),
            "state_units": cell(self.units.get(s, "") for s in self.states),
            "input_units": cell(self.units.get(s, "") for s in self.inputs),
            "output_units": cell(self.units.get(s, "") for s in self.outputs),
            "scene": self.scene,
        }, do_compression=True, oned_as="column")
        return path


@dataclass
class LineMode(Mode):
    """A mode of the line: its eigenvalue, the parts whose states carry it, how far A's error may move it."""

    parts: list  # [(part, share of the participation, [its states that carry it])], largest first
    error: float  # bound of |d eigenvalue| from DERIVATIVE_ACCURACY of A's entries (1/s)

    @property
    def natural_frequency(self):  # Hz
        return self.omega_n / (2 * math.pi)

    @property
    def resolved(self) -> bool:
        """Whether the eigenvalue is told from zero by the derivatives' accuracy."""
        return self.omega_n > self.error


def _index(name, names, what):
    if name not in names:
        raise linefmu.LineFmuError(f"the line has no {what} {name!r}; its {what}s: {', '.join(names) or 'none'}")
    return names.index(name)


def _eigenvalue_error(A, left, right) -> float:
    """First-order bound of how far an eigenvalue moves when each entry of A is off by up to
    DERIVATIVE_ACCURACY of itself: eps |l|^T |A| |r| / |l^H r| (the componentwise condition number)."""
    return DERIVATIVE_ACCURACY * float(np.abs(left) @ np.abs(A) @ np.abs(right)) / max(abs(np.conj(left) @ right), 1e-300)


def linearize(scene, at: float = 0.0, fmu_dir=None) -> StateSpace:
    """The scene's Line FMU linearized at time `at` (s) after its start; a sampled loop's hold and
    delay as a first-order Padé approximation of e^(-s (T/2 + delay)) (`with_holds`)."""
    sampled = {c.name: c.drive.loop for c in scene.nodes
               if getattr(getattr(c, "drive", None), "loop", None) is not None and c.drive.loop.sample > 0.0}
    if not sampled:
        return _linearized(scene, at, fmu_dir)
    continuous = copy.deepcopy(scene)
    for c in continuous.nodes:
        if c.name in sampled:
            c.drive.loop.sample = c.drive.loop.delay = 0.0
    ss = _linearized(continuous, at, fmu_dir)
    for name, lp in sampled.items():
        ss = with_hold(ss, name, lp.sample / 2 + lp.delay, lp.lag)
    return ss


def hold_path(ss: StateSpace, part: str, lag: float):
    """Where a loop's command enters and what it is, in ss: the rates' column b of the torque it
    applies (its motor torque input's column; with a lag, 1/lag into the lag's state) and the command's
    rows (k over the states, k_u over the inputs): the torque output without tau_m's share, or with a
    lag the lag's input, lag*motor.torque' + motor.torque."""
    tau_m = ss.input_index(f"{part}.tau_m")
    if lag > 0.0:
        m = ss.states.index(f"{part}.motor.torque")
        b = np.zeros(len(ss.states))
        b[m] = 1.0 / lag
        k, k_u = lag * ss.A[m] + np.eye(len(ss.states))[m], lag * ss.B[m]
    else:
        b = ss.B[:, tau_m]
        o = ss.output_index(f"{part}.tau")
        k, k_u = ss.C[o].copy(), ss.D[o].copy()
        k_u[tau_m] -= 1.0
    return b, k, k_u


def with_hold(ss: StateSpace, part: str, tau: float, lag: float = 0.0) -> StateSpace:
    """ss with `part`'s loop command delayed by tau (s) on its way to the torque it applies [R14]: a
    first-order Padé approximation (1 - s tau/2)/(1 + s tau/2) of e^(-s tau), one more state. A zero-
    order hold of period T lags by T/2 on average (its phase, -w T/2, at frequencies below 1/T), so a
    sampled loop's tau is T/2 + its delay. Applied torque a = P c: x' = A x + b (a - c), w' = -2/tau w + c,
    a = -c + 4/tau w."""
    b, k, k_u = hold_path(ss, part, lag)
    n = len(ss.states)
    A = np.zeros((n + 1, n + 1))
    A[:n, :n] = ss.A - 2.0 * np.outer(b, k)
    A[:n, n] = b * 4.0 / tau
    A[n, :n], A[n, n] = k, -2.0 / tau
    B = np.vstack([ss.B - 2.0 * np.outer(b, k_u), k_u])
    C, D = np.hstack([ss.C, np.zeros((len(ss.outputs), 1))]), ss.D.copy()
    if lag == 0.0:  # the torque output is the torque applied
        o = ss.output_index(f"{part}.tau")
        C[o, :n] -= 2.0 * k
        C[o, n] = 4.0 / tau
        D[o] -= 2.0 * k_u
    state = f"{part}.hold"
    return dataclasses.replace(ss, A=A, B=B, C=C, D=D, states=ss.states + [state], x=np.append(ss.x, 0.0), dx0=np.append(ss.dx0, 0.0),
                               units={**ss.units, state: "N.m.s"},
                               messages=ss.messages + [f"{part}: its sampled loop's hold and delay as a first-order Padé "
                                                       f"approximation of a delay of {tau:g} s (T/2 + delay)"])


def _linearized(scene, at: float = 0.0, fmu_dir=None) -> StateSpace:
    """The scene's Line FMU linearized at time `at` (s) after its start."""
    from fmpy import extract, read_model_description, simulate_fmu
    from fmpy.simulation import instantiate_fmu

    if not (at >= 0.0 and math.isfinite(at)):
        raise linefmu.LineFmuError(f"{scene.name}: --at {at} s: the time must be 0 or later")
    workdir = Path(tempfile.mkdtemp(prefix="webline-linearize-"))
    fmu = None
    try:
        path = extract(str(linefmu.export(scene, workdir / f"{scene.name}.fmu", fmu_dir, start=linefmu.run_start(scene))),
                       unzipdir=str(workdir / "fmu"))
        md = read_model_description(path)
        variables = [v for v in md.modelVariables if v.type == "Real"]
        states = [d.variable.derivative for d in md.derivatives]
        inputs = [v for v in variables if v.causality == "input"]
        outputs = [v for v in variables if v.causality == "output"]
        vrs = lambda vs: [v.valueReference for v in vs]  # noqa: E731
        rates = [d.variable.valueReference for d in md.derivatives]
        with fmpy_log.collecting_proxied() as messages:
            try:
                fmu = instantiate_fmu(path, md, "ModelExchange")
                # FMPy's loop: initialization, CVode between events, each event at its time; it ends in
                # fmi2Terminate, where the standard still allows the reads below.
                simulate_fmu(path, model_description=md, fmu_instance=fmu, fmi_type="ModelExchange",
                             stop_time=at, output_interval=at / RUN_INTERVALS or 1.0, relative_tolerance=RUN_TOLERANCE,
                             output=[])
                n = len(states)
                J = directional_jacobian(fmu, rates + vrs(outputs), vrs(states) + vrs(inputs))
                x = np.array(fmu.getReal(vrs(states)) if states else [], dtype=float)
                u = np.array(fmu.getReal(vrs(inputs)) if inputs else [], dtype=float)
                y = np.array(fmu.getReal(vrs(outputs)) if outputs else [], dtype=float)
                dx0 = np.array(fmu.getReal(rates) if states else [], dtype=float)
            except Exception as e:  # FMPy names the call; the FMU's log says why
                raise linefmu.LineFmuError(f"{scene.name}: linearizing at t = {at:g} s: {e}"
                                           + "".join(f"\n  {m}" for _, m in messages[-3:])) from e
        return StateSpace(
            scene=scene.name, time=at, A=J[:n, :n], B=J[:n, n:], C=J[n:, :n], D=J[n:, n:],
            states=[v.name for v in states], inputs=[v.name for v in inputs], outputs=[v.name for v in outputs],
            x=x, u=u, y=y, dx0=dx0, units={v.name: _unit(v) for v in variables},
            messages=[m for status, m in messages if status >= fmpy_log.WARNING],
        )
    finally:
        if fmu is not None:
            fmu.freeInstance()
        shutil.rmtree(workdir, ignore_errors=True)


def _unit(v) -> str:
    return v.unit or (v.declaredType.unit if v.declaredType is not None and v.declaredType.unit else "")


def report(ss: StateSpace, modes: list[LineMode]) -> str:
    """The operating point's size and the modes, slowest first: natural frequency, damping ratio,
    eigenvalue, each with what the derivatives' accuracy allows, and the parts that move most."""
    out = [f"{ss.scene}: linearized at t = {ss.time:g} s (Line FMU in Model Exchange, fmi2GetDirectionalDerivative): "
           f"{len(ss.states)} states, {len(ss.inputs)} inputs ({', '.join(ss.inputs) or 'none'}), {len(ss.outputs)} outputs"]
    out += [f"  FMU: {m}" for m in ss.messages]
    moving = ss.moving()
    if moving:
        out.append("  the line is not steady here (A, B, C, D describe deviations from a moving point): "
                   + ", ".join(f"{s}' = {r:.4g} {_rate_unit(ss.units.get(s, ''))}" for s, r in moving))
    out.append("  modes, slowest first: f_n = |lambda|/2 pi, damping ratio = -Re(lambda)/|lambda| (< 0: the mode grows), one eigenvalue of")
    out.append("  each conjugate pair; ± how far a relative inaccuracy of "
               f"{DERIVATIVE_ACCURACY:g} in A's entries may move them; parts by their states' participation")
    out.append(f"  {'f_n [Hz]':>10} {'±':>7} {'damping':>8} {'±':>7}  {'eigenvalue [1/s]':<20} parts that move most")
    for m in modes:
        lam = m.eigenvalue
        parts = ", ".join(f"{part} {100 * s:.0f} %" + (f" ({', '.join(states)})" if len(states) < _n_states(ss, part) else "")
                          for part, s, states in m.parts)
        if not m.resolved:
            out.append(f"  {'0':>10} {'':>7} {'':>8} {'':>7}  {'0':<20} {parts}: {_still(ss, m)}")
            continue
        eig = f"{lam.real:.5g}" + (f"{lam.imag:+.5g}j" if lam.imag > m.error else "")
        kind = "" if lam.imag > m.error else f" (no oscillation: time constant {1 / m.omega_n:.3g} s)"
        if lam.real > m.error:
            kind += (" (a roll's radius: it drifts as the web winds)" if radius_mode(m)
                     else f"  <- GROWS: doubles every {math.log(2.0) / lam.real:.3g} s")
        out.append(f"  {m.natural_frequency:>10.4g} {m.error / (2 * math.pi):>7.1g} {m.damping:>8.4f} "
                   f"{m.error / m.omega_n:>7.1g}  {eig:<20} {parts}{kind}")
    return "\n".join(out)


def _still(ss: StateSpace, m: LineMode) -> str:
    """Why a mode's eigenvalue is zero: the states that carry it are prescribed (their rows of A and B
    vanish: a drive sets the speed), or nothing pulls them back."""
    rows = [i for i, s in enumerate(ss.states) for part, _, states in m.parts if s in {f"{part}.{x}" for x in states}]
    if rows and not np.any(ss.A[rows]) and not np.any(ss.B[rows]):
        return "a speed its drive prescribes (0 within the derivatives' accuracy)"
    return "nothing pulls it back (0 within the derivatives' accuracy)"


def _rate_unit(unit: str) -> str:
    return f"{unit}/s" if unit else "1/s"


def _n_states(ss, part):
    return sum(s.startswith(part + ".") for s in ss.states)


# A mode slower than this share of the line's fastest is an integrator's or a drift's, not a dynamic a
# plot spans (an open loop's integrator is 0 to the derivatives' rounding, 1e-9 Hz).
SLOWEST_SHOWN = 1e-6


def line_modes(modes: list[LineMode]) -> list[LineMode]:
    """The modes a plot spans: those resolved, without a roll's radius (it drifts over the roll's life,
    at 1e-7 Hz and below: not a dynamic a loop or a plot of the line is about) or an integrator."""
    dynamic = [m for m in modes if m.resolved and not radius_mode(m)]
    fastest = max((m.natural_frequency for m in dynamic), default=0.0)
    return [m for m in dynamic if m.natural_frequency >= SLOWEST_SHOWN * fastest]


def radius_mode(m: LineMode) -> bool:
    """A mode carried by rolls' radii alone: it drifts as the web winds, not a dynamic of the line."""
    return bool(m.parts) and all(states == ["r"] for _, _, states in m.parts)


def frequencies(modes: list[LineMode], per_decade: int = 100) -> np.ndarray:
    """A Bode plot's frequencies (Hz): a decade below the line's slowest mode to a decade above its
    fastest (`line_modes`), with each mode's damped and natural frequency in it, so that no resonance
    peak falls between points."""
    shown = line_modes(modes)
    f = [m.natural_frequency for m in shown]
    lo, hi = (min(f) / 10, max(f) * 10) if f else (0.1, 1000.0)
    grid = np.geomspace(lo, hi, int(per_decade * math.log10(hi / lo)) + 1)
    peaks = [g for m in shown for g in (m.frequency, m.natural_frequency) if lo < g < hi]
    return np.unique(np.concatenate([grid, peaks]))


# Two mode labels closer than this share of the frequency axis (log) are written as one.
LABEL_SPACING = 0.03


def _labels(modes: list[LineMode], lo: float, hi: float) -> list[tuple[float, str]]:
    """One label per group of modes whose frequencies lie within LABEL_SPACING of the axis of each
    other, at the group's first: '3.12 Hz unwind, 3.3 Hz entry'."""
    span = math.log10(hi / lo)
    groups = []
    for m in sorted((m for m in line_modes(modes) if lo <= m.natural_frequency <= hi), key=lambda m: m.natural_frequency):
        text = f"{m.natural_frequency:.3g} Hz {m.parts[0][0] if m.parts else ''}".strip()
        if groups and math.log10(m.natural_frequency / groups[-1][0]) < LABEL_SPACING * span:
            groups[-1][1].append(text)
        else:
            groups.append((m.natural_frequency, [text]))
    return [(f, ", ".join(texts)) for f, texts in groups]


def write_curve(path, header: list[str], columns) -> Path:
    """A CSV of equal-length columns under a header of names with units."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    np.savetxt(path, np.column_stack(columns), delimiter=",", header=",".join(header), comments="", fmt="%.10g")
    return path


def bode(ss: StateSpace, input: str, output: str, path, modes: list[LineMode]) -> tuple[Path, Path]:
    """The frequency response from `input` to `output`: a CSV (frequency [Hz], magnitude [dB], phase
    [deg]) and beside it a PNG of magnitude and phase over the line's modes (`frequencies`)."""
    hz = frequencies(modes)
    h = ss.response(input, output, hz)
    unit_in, unit_out = ss.units.get(input, ""), ss.units.get(output, "")
    title = f"{ss.scene}: from {input} to {output}, linearized at t = {ss.time:g} s"
    what = f"|{output} / {input}| [dB re 1 {unit_out or '1'} per {unit_in or '1'}]"
    return bode_plot(hz, h, path, title, what, modes)


def bode_plot(hz, h, path, title: str, what: str, modes: list[LineMode], marks=()) -> tuple[Path, Path]:
    """`path` (.png) and its .csv: 20 log10 |h| and the unwrapped phase of h over `hz`, each mode's
    frequency marked (labels that would overlap joined), and `marks`: [(Hz, text)] drawn in red."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    db = 20.0 * np.log10(np.abs(h))
    deg = np.degrees(np.unwrap(np.angle(h)))
    path = Path(path)
    csv = write_curve(path.with_suffix(".csv"), ["frequency [Hz]", "magnitude [dB]", "phase [deg]"], [hz, db, deg])
    fig, (mag, phase) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True)
    mag.semilogx(hz, db, lw=1.3)
    phase.semilogx(hz, deg, lw=1.3)
    for f, text in _labels(modes, hz[0], hz[-1]):
        for ax in (mag, phase):
            ax.axvline(f, color="0.6", lw=0.7, ls=":")
        mag.annotate(text, (f, 1.0), xycoords=("data", "axes fraction"), rotation=90, va="top", ha="right",
                     fontsize=7, color="0.35")
    for f, text in marks:
        for ax in (mag, phase):
            ax.axvline(f, color="tab:red", lw=0.8, ls="--")
        phase.annotate(text, (f, 0.02), xycoords=("data", "axes fraction"), rotation=90, va="bottom", ha="right",
                       fontsize=7, color="tab:red")
    mag.set_ylabel(what)
    phase.set_ylabel("phase [deg]")
    phase.set_xlabel("frequency [Hz]")
    for ax in (mag, phase):
        ax.grid(True, which="both", alpha=0.3)
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return csv, path


# A step response runs this many of the slowest line mode's time constants (1/|Re lambda|), at least
# this many periods of its slowest oscillation, with STEP_POINTS_PER_PERIOD points in a period of its
# fastest (at least STEP_POINTS, at most STEP_POINTS_MAX: above, the fastest modes are sampled coarser).
STEP_TIME_CONSTANTS = 5.0
STEP_PERIODS = 3.0
STEP_POINTS = 2000
STEP_POINTS_PER_PERIOD = 16
STEP_POINTS_MAX = 100_000


def step_time(modes: list[LineMode]) -> tuple[float, int]:
    """How long a step response runs (s), until the slowest of the line's modes has settled, and in
    how many points."""
    shown = line_modes(modes)
    if not shown:
        return 1.0, STEP_POINTS
    decay = [STEP_TIME_CONSTANTS / -m.eigenvalue.real for m in shown if m.eigenvalue.real < -m.error]
    oscillating = [m.frequency for m in shown if m.eigenvalue.imag > m.error]
    t_end = max(decay + [STEP_PERIODS / f for f in oscillating] or [1.0])
    points = STEP_POINTS_PER_PERIOD * t_end * max(oscillating, default=0.0)
    return t_end, int(min(max(points, STEP_POINTS), STEP_POINTS_MAX))


def step_response(ss: StateSpace, input: str, output: str, t_end: float, points: int = STEP_POINTS) -> tuple[np.ndarray, np.ndarray]:
    """d output (t) after a unit step of `input` at t = 0 (the operating point before it): exact at the
    points, the step held between them (the matrix exponential of [[A, b], [0, 0]] over a point's
    interval: x_{k+1} = Phi x_k + Gamma)."""
    from scipy.linalg import expm

    i, o = ss.input_index(input), ss.output_index(output)
    n = ss.A.shape[0]
    t = np.linspace(0.0, t_end, points + 1)
    M = np.zeros((n + 1, n + 1))
    M[:n, :n], M[:n, n] = ss.A, ss.B[:, i]
    E = expm(M * (t[1] - t[0]))
    phi, gamma = E[:n, :n], E[:n, n]
    x = np.zeros(n)
    y = np.empty_like(t)
    for k in range(len(t)):
        y[k] = ss.C[o] @ x + ss.D[o, i]
        x = phi @ x + gamma
    return t, y


def step_plot(ss: StateSpace, input: str, output: str, path, modes: list[LineMode]) -> tuple[Path, Path]:
    """The step response from `input` to `output` (`step_response`) as a CSV (time [s], the output's
    change per unit of the input) and beside it a PNG."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t, y = step_response(ss, input, output, *step_time(modes))
    unit_in, unit_out = ss.units.get(input, "") or "1", ss.units.get(output, "") or "1"
    path = Path(path)
    what = f"d {output} [{unit_out}] per {unit_in} of {input}"
    csv = write_curve(path.with_suffix(".csv"), ["time [s]", what], [t, y])
    fig, ax = plt.subplots(figsize=(9, 4.5))
    ax.plot(t, y, lw=1.3)
    ax.set_xlabel("time after the step [s]")
    ax.set_ylabel(what)
    ax.grid(True, alpha=0.3)
    ax.set_title(f"{ss.scene}: a unit step of {input} [{unit_in}] at t = {ss.time:g} s, {output}'s change", fontsize=10)
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return csv, path
