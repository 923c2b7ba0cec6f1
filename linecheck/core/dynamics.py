"""Steps 2 and 3: linear dynamics and quasi-static response under the fluctuating wind.

Step 2 (paper Eq. 6): M u'' + C(t) u' + K(t) u = F_w(t), Newmark's average-acceleration
method (gamma = 1/2, beta = 1/4; Bathe 1996 section 9.2.4) in total form, with K(t)
and C(t) taken from the step-1 mean state in force at each time step.  Step 3
(paper Eq. 14): K(t) u = F_w(t) gives the background B; the resonant part is
R = F - B.

Structure exploited (issue 4): K, C and M are banded (half-bandwidth 5; M is diagonal
but for the 3x3 blocks of the insulator attachment nodes, projected normal to the
insulator axis); K_hat = K + 2/dt C + 4/dt^2 M is factorised once per mean state
(banded Cholesky, LAPACK dpbtrf), never per step; all realizations are columns of
one right-hand side.  For downbursts K(t), C(t) are piecewise constant between
the mean-state instants (default), or linearly interpolated at every step
(``interpolate=True``, one factorisation per step) to show that the difference
is negligible (docs/validation.md).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from scipy.linalg import lapack

from .errors import Cancelled, NumericalError
from .model import LinearModel

_dpbtrf = lapack.dpbtrf
_dpbtrs = lapack.dpbtrs


@dataclass(frozen=True)
class Newmark:
    """Average-acceleration Newmark constants (Bathe 1996 Table 9.3, gamma = 1/2, beta = 1/4)."""

    dt: float

    @property
    def a0(self) -> float:
        return 4.0 / self.dt**2  # 1/(beta dt^2)

    @property
    def a1(self) -> float:
        return 2.0 / self.dt  # gamma/(beta dt)

    @property
    def a2(self) -> float:
        return 4.0 / self.dt  # 1/(beta dt)


def _factor(K_band: np.ndarray, diag_add: np.ndarray, what: str, band_add: np.ndarray | None = None) -> np.ndarray:
    """Banded Cholesky of K + band_add + diag(diag_add); NumericalError if not positive definite."""
    ab = K_band.copy() if band_add is None else K_band + band_add
    ab[-1] += diag_add
    c, info = _dpbtrf(ab, lower=0, overwrite_ab=1)
    if info != 0:
        raise NumericalError(f"{what}: matrix is not positive definite (LAPACK dpbtrf info {info})")
    return c


def _solve(c: np.ndarray, b: np.ndarray) -> np.ndarray:
    x, info = _dpbtrs(c, b, lower=0)
    if info != 0:  # pragma: no cover - only for malformed input
        raise NumericalError(f"banded solve failed (LAPACK dpbtrs info {info})")
    return x


@dataclass(frozen=True)
class DynamicResponse:
    """Reaction histories of steps 2 and 3 (wind-induced fluctuating parts).

    Attributes:
        fluctuating: [N] F(t) = B + R at every tower, shape (n_real, n_steps, n_towers, 3).
        background: [N] B(t), same shape.
    """

    fluctuating: np.ndarray
    background: np.ndarray

    @property
    def resonant(self) -> np.ndarray:
        """[N] R = F - B (paper Fig. 4)."""
        return self.fluctuating - self.background


def integrate(
    models: list[LinearModel],
    damping: np.ndarray,
    state_of_step: np.ndarray,
    loads: np.ndarray,
    dt: float,
    *,
    direct: np.ndarray | None = None,
    model_at: Callable[[int], tuple[LinearModel, np.ndarray]] | None = None,
    progress: Callable[[int, int], None] | None = None,
    cancel: threading.Event | None = None,
) -> DynamicResponse:
    """Steps 2 and 3 for all realizations at once.

    Args:
        models: linear models of the mean states, length n_k (all with the same DOF map).
        damping: [N s/m] damping matrix of every mean state in upper band storage, shape
            (n_k, BANDWIDTH + 1, n_dof) (see :mod:`linecheck.core.damping`); when it is
            diagonal (paper Eq. 9) the product C u' is a vector multiply.
        state_of_step: index into ``models`` in force at every step, shape (n_steps,).
        loads: [N] fluctuating transverse (y) loads on the free nodes, shape
            (n_steps, n_real, n_free_nodes) (paper Eq. 5).
        dt: [s] time step.
        direct: [N] reactions caused directly by loads applied at pinned nodes,
            shape (n_steps, n_real, n_towers * 3) (added to both F and B).
        model_at: optional ``model_at(n) -> (model, damping band)`` giving the linear model of
            step n itself (reference scheme: the step-1 state interpolated in time and the
            model rebuilt and factorised at every step); default: ``models[state_of_step[n]]``
            held piecewise constant.
        progress: ``progress(done, total)`` every few hundred steps.
        cancel: stop early (raises :class:`Cancelled`).

    Returns:
        :class:`DynamicResponse` with tower reactions.  The record starts from the
        quasi-static solution at t = 0 (u0 = K^-1 F0, u'0 = 0), so no background
        transient is created.
    """
    nm = Newmark(dt)
    n_steps, n_real, n_free = loads.shape
    n_dof = models[0].mass.size
    ydof = 3 * np.arange(n_free) + 1  # node-major DOFs: y is the second of each node
    n_r = models[0].G.shape[0]
    if not np.all(np.isfinite(loads)):
        raise NumericalError("non-finite fluctuating wind load")
    # Vectors are kept "transposed", shape (n_real, n_dof) C-ordered, i.e. (n_dof, n_real)
    # Fortran-ordered as LAPACK wants them: no copies in the step loop.

    def model_of(n: int) -> tuple[LinearModel, np.ndarray]:
        """Linear model and damping band in force at step n."""
        if model_at is not None:
            return model_at(n)
        k = int(state_of_step[n])
        return models[k], damping[k]

    def mats(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """K band, damping band, mass band and reaction map in force at step n."""
        m, c = model_of(n)
        return m.K_band, c, m.M_band, m.G

    def loads_full(f: np.ndarray) -> np.ndarray:
        """y-loads (m, n_free) -> full transposed right-hand sides (m, n_dof)."""
        out = np.zeros((f.shape[0], n_dof))
        out[:, ydof] = f
        return out

    # -------- step 3: quasi-static background, one factorisation per mean state
    R_B = np.empty((n_steps, n_real, n_r))
    chunk = max(1, 8192 // max(n_real, 1))
    if model_at is None:
        for k in np.unique(state_of_step):
            c = _factor(models[k].K_band, np.zeros(n_dof), f"stiffness of mean state {k + 1}")
            all_steps = np.flatnonzero(state_of_step == k)
            GT = models[k].G.T
            for i0 in range(0, all_steps.size, chunk):
                steps = all_steps[i0:i0 + chunk]
                UT = _solve(c, loads_full(loads[steps].reshape(-1, n_free)).T).T
                R_B[steps] = _rowdot(UT, GT).reshape(steps.size, n_real, n_r)
    else:
        for n in range(n_steps):
            Kb, _, _, G = mats(n)
            c = _factor(Kb, np.zeros(n_dof), f"stiffness at step {n}")
            R_B[n] = _rowdot(_solve(c, loads_full(loads[n]).T).T, G.T)

    # -------- step 2: Newmark, one factorisation per mean state
    Kb0, _, _, G0 = mats(0)
    chol = _factor(Kb0, np.zeros(n_dof), "stiffness at t = 0")
    U = _solve(chol, loads_full(loads[0]).T).T  # quasi-static start, (n_real, n_dof)
    V = np.zeros_like(U)
    A = np.zeros_like(U)  # M a0 = F0 - K u0 - C v0 = 0
    R_F = np.empty((n_steps, n_real, n_r))
    R_F[0] = _rowdot(U, G0.T)
    current = None
    report = max(1, n_steps // 100)
    a0, a1, a2 = nm.a0, nm.a1, nm.a2
    half_dt = 0.5 * dt
    for n in range(1, n_steps):
        key = int(state_of_step[n]) if model_at is None else n
        if key != current:
            # A rigid insulator: the attachment node has no velocity or acceleration along
            # the insulator axis (its axial displacement is the static one).  M and C have no
            # axial part, so the (-1)^n Newmark residue of that algebraic direction is
            # harmless while the axis stays put; it is removed when the mean state (and the
            # axis) changes, before it could leak into the tangential motion.
            if current is not None:
                drop_axial(V)
                drop_axial(A)
            Kb, cd, Mb, G = mats(n)
            chat = _factor(Kb, np.zeros(n_dof), f"effective stiffness at step {n}", band_add=a1 * cd + a0 * Mb)
            mcmul = _pair_multiplier(Mb, cd)
            drop_axial = _axial_remover(model_of(n)[0])
            GT = G.T
            current = key
        # K_hat u_{n+1} = F_{n+1} + M (a0 u + a2 v + a) + C (a1 u + v)   (Bathe Table 9.3)
        rhs = mcmul(a0 * U + a2 * V + A, a1 * U + V)
        rhs[:, ydof] += loads[n]
        U_new = _solve(chat, rhs.T).T
        A_new = a0 * (U_new - U) - a2 * V - A
        V += half_dt * (A + A_new)
        U, A = U_new, A_new
        R_F[n] = _rowdot(U, GT)
        if progress is not None and n % report == 0:
            progress(n, n_steps)
            if cancel is not None and cancel.is_set():
                raise Cancelled("step 2 cancelled")
    if not (np.all(np.isfinite(R_F)) and np.all(np.isfinite(R_B))):
        raise NumericalError("non-finite response in the time integration")
    if direct is not None:
        R_F += direct
        R_B += direct
    if progress is not None:
        progress(n_steps, n_steps)
    shape = (n_steps, n_real, n_r // 3, 3)
    return DynamicResponse(
        fluctuating=np.ascontiguousarray(R_F.reshape(shape).transpose(1, 0, 2, 3)),
        background=np.ascontiguousarray(R_B.reshape(shape).transpose(1, 0, 2, 3)),
    )


def _axial_remover(model: LinearModel) -> Callable[[np.ndarray], None]:
    """In-place removal of the insulator-axial components of transposed vectors (n_real, n_dof)."""
    if model.axial_dof.size == 0:
        return lambda x: None
    idx = model.axial_dof[:, None] + np.arange(3)[None, :]  # (n_s, 3)
    a = model.axes  # (n_s, 3)

    def drop(x: np.ndarray) -> None:
        xs = x[:, idx]  # (n_real, n_s, 3)
        x[:, idx] = xs - np.einsum("rsd,sd->rs", xs, a)[..., None] * a[None]

    return drop


def _rowdot(X: np.ndarray, BT: np.ndarray) -> np.ndarray:
    """X @ BT computed row by row in a fixed order (no BLAS): every realization's reactions
    are then bit-identical whichever other realizations share the call (batch chunking,
    workers); a BLAS gemm rounds differently for different numbers of rows."""
    return np.einsum("rd,dk->rk", X, BT, optimize=False)


def _pair_multiplier(m_band: np.ndarray, c_band: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """(x, y) -> x M + y C for transposed vectors: elementwise when both are diagonal, else
    one sparse product with [M C] (one call per step instead of two)."""
    if not np.any(m_band[:-1]) and not np.any(c_band[:-1]):
        dm, dc = m_band[-1][None, :], c_band[-1][None, :]
        return lambda x, y: dm * x + dc * y
    from scipy.sparse import hstack

    from .model import band_to_sparse

    MC = hstack([band_to_sparse(m_band), band_to_sparse(c_band)]).tocsr()  # (n, 2n)
    return lambda x, y: (MC @ np.hstack([x, y]).T).T
