"""Exact large-displacement elastic truss elements shared by the independent FE references
(``fe_static.py`` for the paper's straight line, ``section_fe.py`` for sections); they share no
code with linecheck's solvers.  Total Lagrangian in the displacements U from the reference
positions X0 (Crisfield 1991, "Non-linear Finite Element Analysis of Solids and Structures",
Vol. 1, ch. 3)."""

from __future__ import annotations

import numpy as np


def truss_state(U: np.ndarray, a: np.ndarray, b: np.ndarray, dX0: np.ndarray, c0: np.ndarray, l0: np.ndarray,
                EA: np.ndarray | float):
    """Axial forces N [N], unit vectors e, lengths l [m] of elements a -> b at displacements U (nn, 3).

    l - l0 without cancellation: (l^2 - l0^2)/(l + l0), l^2 - l0^2 = c0 + 2 dX0.dU + dU.dU with
    c0 = |dX0|^2 - l0^2, so round-off does not grow with the absolute coordinates; N = EA (l - l0)/l0."""
    dU = U[b] - U[a]
    D = dX0 + dU
    ell = np.sqrt(np.einsum("ij,ij->i", D, D))
    dl = (c0 + 2.0 * np.einsum("ij,ij->i", dX0, dU) + np.einsum("ij,ij->i", dU, dU)) / (ell + l0)
    N = EA * dl / l0
    return N, D / ell[:, None], ell


def truss_internal(N: np.ndarray, e: np.ndarray, a: np.ndarray, b: np.ndarray, nn: int) -> np.ndarray:
    """Internal nodal forces [N], shape (3 nn,): node a gets -N e, node b +N e."""
    Ne = N[:, None] * e
    f = np.zeros((nn, 3))
    np.add.at(f, b, Ne)
    np.add.at(f, a, -Ne)
    return f.reshape(-1)


def load_stepping(newton, U: np.ndarray, f0: np.ndarray, df: np.ndarray, steps: int, easy: int,
                  failure: type[Exception]) -> tuple[np.ndarray, float, int, int]:
    """Apply the external load f0 + lam df from lam = 0 to 1 in adaptive increments (load
    control; Crisfield 1991, ch. 9): an increment whose Newton solve raises ``failure`` is
    halved (down to 1e-4), one that converged within ``easy`` iterations lets the next double.

    newton(U, fext) -> (U, iterations, residual [N]) solves one increment from U.
    Returns (U, the last residual [N], the iterations of all increments, the increments).
    """
    lam, dlam, total, n, res = 0.0, 1.0 / steps, 0, 0, float("nan")
    while lam < 1.0:
        target = min(1.0, lam + dlam)
        try:
            Un, its, res = newton(U, f0 + target * df)
        except failure:
            dlam *= 0.5
            if dlam < 1e-4:
                raise
            continue
        U, lam = Un, target
        total += its
        n += 1
        if its <= easy:
            dlam = min(2.0 * dlam, 1.0)
    return U, res, total, n
