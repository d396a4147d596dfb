"""A line linearized: one Block (x' = A x + B u, y = C x + D u) per component and the Line that connects them.

`linearization` builds a Line from a System's FMUs; `stability` builds the
master's one-step map from it. Both raise StabilityError. A `Mode` is an
eigenvalue; `participation` tells which states carry each (`stability`, and
`statespace` for the whole line as one FMU).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np


class StabilityError(RuntimeError):
    pass


@dataclass
class Mode:
    eigenvalue: complex

    @property
    def omega_n(self):
        return abs(self.eigenvalue)

    @property
    def frequency(self):  # Hz, damped
        return abs(self.eigenvalue.imag) / (2 * math.pi)

    @property
    def damping(self):
        return -self.eigenvalue.real / abs(self.eigenvalue) if self.eigenvalue else 0.0


def participation(M: np.ndarray):
    """M's eigenvalues, their participation factors P (column k: |l_ik r_ik| over the states i, from the
    left and right eigenvectors of eigenvalue k, summing to 1: the same whatever units the states are
    in), and the left and right eigenvectors (columns)."""
    from scipy.linalg import eig

    lam, vl, vr = eig(M, left=True, right=True)
    P = np.abs(np.conj(vl) * vr)
    return lam, P / np.maximum(P.sum(axis=0), np.finfo(float).tiny), vl, vr


@dataclass
class Block:
    """One component linearized: x' = A x + B u, y = C x + D u (deviations from the operating point)."""

    name: str
    A: np.ndarray
    B: np.ndarray
    C: np.ndarray
    D: np.ndarray
    states: list[str]
    inputs: list[str]  # connected inputs only: the others are held at their start values
    outputs: list[str]  # connected outputs only
    interpolates: bool = False  # takes input derivatives: extrapolation gives it a ramp, not a held value
    method: str = ""  # how A, B, C, D were obtained


@dataclass
class Line:
    """Linearized components and the connections between them (list order = Gauss–Seidel order)."""

    blocks: list[Block]
    # For each block, for each of its inputs: (source block index, source output index).
    sources: list[list[tuple[int, int]]]
    notes: list[str] = field(default_factory=list)

    def sizes(self):
        n = [b.A.shape[0] for b in self.blocks]
        m = [len(b.inputs) for b in self.blocks]
        p = [len(b.outputs) for b in self.blocks]
        return n, m, p

    def offsets(self):
        """Index ranges of x, ue (inputs at the end of the last step) and yp (previous outputs) in the map's state."""
        n, m, p = self.sizes()
        N, Mt, Pt = sum(n), sum(m), sum(p)
        ox = np.concatenate([[0], np.cumsum(n)]).astype(int)
        ou = N + np.concatenate([[0], np.cumsum(m)]).astype(int)
        oy = N + Mt + np.concatenate([[0], np.cumsum(p)]).astype(int)
        return ox, ou, oy, N + Mt + Pt

    def coupling_matrices(self):
        """Block-diagonal A, B, C, D and the connection matrix P (u = P y)."""
        from scipy.linalg import block_diag

        n, m, p = self.sizes()
        A = block_diag(*[b.A for b in self.blocks]) if sum(n) else np.zeros((0, 0))
        B = _block_diag_rect([b.B for b in self.blocks], n, m)
        C = _block_diag_rect([b.C for b in self.blocks], p, n)
        D = _block_diag_rect([b.D for b in self.blocks], p, m)
        oy = np.concatenate([[0], np.cumsum(p)]).astype(int)
        P = np.zeros((sum(m), sum(p)))
        row = 0
        for i, srcs in enumerate(self.sources):
            for (j, o) in srcs:
                P[row, oy[j] + o] = 1.0
                row += 1
        return A, B, C, D, P

    def continuous(self):
        """The coupled continuous system's matrix: x' = (A + B (I - P D)^-1 P C) x."""
        A, B, C, D, P = self.coupling_matrices()
        K = np.linalg.solve(np.eye(P.shape[0]) - P @ D, P @ C)  # u = K x
        return A + B @ K, K


def _block_diag_rect(mats, rows, cols):
    out = np.zeros((sum(rows), sum(cols)))
    r = c = 0
    for M, nr, nc in zip(mats, rows, cols):
        out[r : r + nr, c : c + nc] = M
        r += nr
        c += nc
    return out
