"""Banded symmetric positive-definite solves by LAPACK (``dpbtrf`` / ``dpbtrs``, upper band),
with every right-hand side solved exactly as if it were alone.

``dpbtrs`` solves the columns of B one after the other (two ``dtbsv`` each), so a column's
result depends only on its own values -- but OpenBLAS's level-2 kernels for some CPUs (the SSE3
"Prescott" kernels, ``OPENBLAS_CORETYPE=Prescott``) round by the alignment of the vector in
memory. With an odd number of DOFs the columns of a Fortran array alternate between 16-byte and
8-byte alignment, so a realization's bits depended on its position among the columns (on
another CPU they did not). :func:`solve` therefore solves in a scratch array whose leading
dimension is even: the factor gets one decoupled DOF of unit stiffness (zero coupling, so the
other DOFs' arithmetic is unchanged) and every column starts 16-byte aligned.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import lapack

from .errors import NumericalError

_dpbtrf = lapack.dpbtrf
_dpbtrs = lapack.dpbtrs


def factor(K_band: np.ndarray, diag_add: np.ndarray, what: str, band_add: np.ndarray | None = None) -> np.ndarray:
    """Banded Cholesky U^T U of K + band_add + diag(diag_add) (LAPACK ``dpbtrf``, upper).

    Args:
        K_band: [N/m] upper band storage, shape (kd + 1, n).
        diag_add: [N/m] added to the diagonal, shape (n,).
        what: names the matrix in the error.
        band_add: [N/m] optional band added to K_band, shape (kd + 1, n).
    Returns: the factor in band storage, shape (kd + 1, n).
    Raises: NumericalError if the matrix is not positive definite.
    """
    ab = K_band.copy() if band_add is None else K_band + band_add
    ab[-1] += diag_add
    c, info = _dpbtrf(ab, lower=0, overwrite_ab=1)
    if info != 0:
        raise NumericalError(f"{what}: matrix is not positive definite (LAPACK dpbtrf info {info})")
    return c


def padded(c: np.ndarray) -> np.ndarray:
    """The factor with one decoupled DOF of unit diagonal appended when n is odd (else ``c``),
    shape (kd + 1, n + n % 2)."""
    n = c.shape[1]
    if n % 2 == 0:
        return c
    cp = np.zeros((c.shape[0], n + 1))
    cp[:, :n] = c
    cp[-1, n] = 1.0
    return cp


class ColumnSolver:
    """K^-1 on columns (or rows) of right-hand sides, each column's bits its own.

    Args:
        c: the upper band factor of K, shape (kd + 1, n) (:func:`factor`).
    """

    def __init__(self, c: np.ndarray) -> None:
        self.n = c.shape[1]
        self.c = padded(c)
        self._scratch: np.ndarray | None = None

    def _work(self, m: int) -> np.ndarray:
        """A Fortran scratch (n_even, m), fresh from the allocator (16-byte aligned base)."""
        s = self._scratch
        if s is None or s.shape[1] != m:
            s = np.zeros((self.c.shape[1], m), order="F")  # the padding row stays 0
            self._scratch = s
        return s

    def _solve_scratch(self, s: np.ndarray) -> np.ndarray:
        x, info = _dpbtrs(self.c, s, lower=0, overwrite_b=1)
        if info != 0:  # pragma: no cover - c comes from a successful dpbtrf
            raise NumericalError(f"banded solve failed (LAPACK dpbtrs info {info})")
        return x

    def columns(self, B: np.ndarray) -> np.ndarray:
        """K^-1 B for B of shape (n, m) -> a new Fortran-ordered array (n, m) (its transpose, a
        row per right-hand side, is C-contiguous as LAPACK's own result would be)."""
        s = self._work(B.shape[1])
        s[: self.n] = B
        return self._solve_scratch(s)[: self.n].copy(order="F")

    def rows_in_place(self, U: np.ndarray) -> None:
        """U <- (K^-1 U^T)^T for U of shape (m, n), in place."""
        s = self._work(U.shape[0])
        s[: self.n] = U.T
        U[...] = self._solve_scratch(s)[: self.n].T


def solve(c: np.ndarray, B: np.ndarray) -> np.ndarray:
    """K^-1 B by the band factor c (shape (kd + 1, n)) for B of shape (n, m), each column solved
    as if alone (see the module docstring)."""
    return ColumnSolver(c).columns(B)


# ---- the banded solves of the compiled kernel's piece ``newmark`` (linecheck.core.kernel):
# their part of its load check (registered by linecheck.core.dynamics)

def band_solve_pairs(fns, kd: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """The compiled banded solves (``fns.band_solve``: four lanes, ``band_solve_1``: one vector,
    ``solve_columns``) beside LAPACK ``dpbtrs`` on diagonally dominant systems (condition ≲ 10)
    of half-bandwidth kd, long and short: (reference, compiled) pairs of solutions."""
    rng = np.random.default_rng(20)
    pairs = []
    for n in (60, 4):
        ab = np.zeros((kd + 1, n))
        for off in range(kd + 1):
            ab[kd - off, off:] = rng.uniform(-1.0, 1.0, max(n - off, 0))
        ab[kd] = 4.0 * (kd + 1) + rng.uniform(0.0, 1.0, n)  # diagonally dominant
        c, info = _dpbtrf(ab, lower=0)
        if info != 0:  # pragma: no cover - diagonally dominant by construction
            raise NumericalError("load check: test matrix not positive definite")
        B = rng.standard_normal((4, n))
        ref = _dpbtrs(c, np.asfortranarray(B.T), lower=0)[0]
        X = np.ascontiguousarray(B.T)[None]  # one group of four lanes
        fns.band_solve(c, X)
        pairs.append((ref, X[0]))
        for q in range(4):
            x = B[q].copy()
            fns.band_solve_1(c, x)
            pairs.append((ref[:, q], x))
        cols = np.array(B.T)
        fns.solve_columns(c, cols)
        pairs.append((ref, cols))
    return pairs
