"""A drive's loop broken at its torque output: the loop transfer function L(s) and its gain and phase margins.

The Line FMU closes each loop inside; its linearization (`statespace`) gives the closed loop
x' = A x + b d, with d the roller's input tau_m, which adds to the drive's torque, and its output
tau = k x + d + (the table's torque). The loop's own torque is c = tau - d, so with the loop open
(the plant driven by u alone) x' = (A - b k) x + b u, and

    L(s) = -k (sI - A + b k)^-1 b,

the return ratio at the torque: the loop is 1 + L = 0's roots, and the margins are read on L as on
any negative-feedback loop: the gain margin 1/|L| where L's phase crosses -180 deg, the phase margin
180 deg + arg L where |L| crosses 1.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from .linefmu import LineFmuError

# Where crossovers are looked for: this band (Hz), on a grid fine enough that no two crossings of
# one kind fall between two points (then refined to the root by Brent's method).
SEARCH_BAND = (1e-4, 1e4)
SEARCH_PER_DECADE = 400


@dataclass
class Crossing:
    frequency: float  # Hz
    margin: float  # dB (gain margin) or deg (phase margin)


@dataclass
class LoopMargins:
    loop: str
    gain: list  # [Crossing]: where arg L = -180 deg, margin -20 log10 |L| (dB)
    phase: list  # [Crossing]: where |L| = 1, margin 180 + arg L (deg)
    unstable_open: int  # eigenvalues of the open loop's A in the right half-plane

    @property
    def gain_margin(self):
        """The smallest gain margin (dB), or None where the phase never crosses -180 deg."""
        return min(self.gain, key=lambda c: c.margin) if self.gain else None

    @property
    def phase_margin(self):
        """The smallest phase margin (deg), or None where |L| never crosses 1."""
        return min(self.phase, key=lambda c: c.margin) if self.phase else None


class OpenLoop:
    """The loop of roller `name` broken at its torque: L(j 2 pi f) at any frequency."""

    def __init__(self, ss, name: str):
        inputs, outputs = f"{name}.tau_m", f"{name}.tau"
        if inputs not in ss.inputs or outputs not in ss.outputs or f"{name}.loop.I" not in ss.states:
            loops = sorted({s.split(".")[0] for s in ss.states if s.endswith(".loop.I")})
            raise LineFmuError(f"--loop {name}: the line has no drive loop on a roller {name!r} whose torque is an "
                               f"input ({inputs}); its loops: {', '.join(loops) or 'none'}")
        i, o = ss.input_index(inputs), ss.output_index(outputs)
        feedthrough = ss.D[o, i]
        if abs(feedthrough - 1.0) > 1e-6:
            raise LineFmuError(f"--loop {name}: d {outputs}/d {inputs} = {feedthrough:.6g}, not 1: the motor's torque "
                               "is at its limit here, and the loop is not linear around this point")
        self.name = name
        self.b = ss.B[:, i]
        self.k = ss.C[o]
        self.A = ss.A - np.outer(self.b, self.k)

    def response(self, hz) -> np.ndarray:
        """L(j 2 pi f), solved at each frequency (as `StateSpace.response`, for a stiff A)."""
        n = self.A.shape[0]
        return np.array([-self.k @ np.linalg.solve(2j * math.pi * f * np.eye(n) - self.A, self.b) for f in np.atleast_1d(hz)])

    def margins(self) -> LoopMargins:
        lo, hi = SEARCH_BAND
        hz = np.geomspace(lo, hi, int(SEARCH_PER_DECADE * math.log10(hi / lo)) + 1)
        L = self.response(hz)
        at = lambda f: self.response(f)[0]  # noqa: E731
        gain = []
        # Phase crossover: L real and negative (Im L changes sign where Re L < 0).
        im = L.imag
        for j in np.nonzero(np.sign(im[:-1]) * np.sign(im[1:]) < 0)[0]:
            f = brentq(lambda f: at(f).imag, hz[j], hz[j + 1], xtol=1e-12 * hz[j], rtol=1e-12)
            x = at(f)
            if x.real < 0:
                gain.append(Crossing(f, -20.0 * math.log10(abs(x))))
        phase = []
        g = np.log(np.abs(L))
        for j in np.nonzero(np.sign(g[:-1]) * np.sign(g[1:]) < 0)[0]:
            f = brentq(lambda f: math.log(abs(at(f))), hz[j], hz[j + 1], xtol=1e-12 * hz[j], rtol=1e-12)
            phase.append(Crossing(f, math.degrees(np.angle(-at(f)))))
        lam = np.linalg.eigvals(self.A)
        tol = 1e-7 * max(np.max(np.abs(lam)), 1.0)  # the derivatives' accuracy (statespace.DERIVATIVE_ACCURACY)
        return LoopMargins(self.name, gain, phase, int(np.sum(lam.real > tol)))


def report(m: LoopMargins) -> str:
    """The margins as a controls engineer reads them."""
    out = [f"  loop {m.loop} broken at its torque output (L = -k (sI - A + b k)^-1 b, negative feedback):"]
    gm, pm = m.gain_margin, m.phase_margin
    out.append(f"    gain margin  {gm.margin:8.2f} dB  at the phase crossover {gm.frequency:.4g} Hz" if gm
               else "    gain margin  infinite: the phase of L never crosses -180 deg")
    out.append(f"    phase margin {pm.margin:8.2f} deg at the gain crossover {pm.frequency:.4g} Hz" if pm
               else "    phase margin infinite: |L| never crosses 1")
    more = [f"{c.margin:.2f} dB at {c.frequency:.4g} Hz" for c in m.gain if c is not gm]
    more += [f"{c.margin:.2f} deg at {c.frequency:.4g} Hz" for c in m.phase if c is not pm]
    if more:
        out.append("    other crossings: " + ", ".join(more))
    if m.unstable_open:
        out.append(f"    warning: the open loop has {m.unstable_open} eigenvalue(s) in the right half-plane: margins read "
                   "from L do not tell the closed loop's stability (Nyquist: count the encirclements)")
    return "\n".join(out)
