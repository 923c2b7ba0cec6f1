"""Damped (complex) modes of the linearised line: the state-space eigenproblem of M u'' + C u' + K u = 0.

Small systems solve the dense state matrix A = [[0, I], [-M^-1 K, -M^-1 C]] (right eigenvectors
by LAPACK, left ones from the right by the symmetry of K, M, C; Tisseur & Meerbergen 2001); large
ones use the undamped modes with modal damping (classical-damping approximation, Clough & Penzien
2003).  The frequency-domain estimate (:mod:`linecheck.core.spectral`) places its refined grid
points on these poles and sums its modal transfer functions over their eigenvectors; the modes
command and the burn-in estimate read them too.  Nothing here prints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import eig

from .model import LinearModel, condensed


@dataclass(frozen=True)
class ComplexModes:
    """Damped modes of M u'' + C u' + K u = 0 (state-space eigenproblem), Im(lambda) > 0.

    Attributes:
        frequencies_hz: [Hz] undamped-equivalent natural frequency |lambda|/(2 pi), (n,).
        damping_ratio: [-] zeta = -Re(lambda)/|lambda|, (n,).
        poles: complex eigenvalues lambda, (n,).
        right: displacement half of the state eigenvectors psi_k (psi = [phi; lambda phi]),
            (n_t, n), or None, in the condensed coordinates t of
            :func:`~linecheck.core.model.condensed` (u = S t).
        left: velocity half of the left state eigenvectors chi_k (chi^H A = lambda chi^H,
            chi = conj([(lambda M + C) phi; M phi])), (n_t, n), or None.
        norm: chi_k^H psi_k, (n,), or None (the modal projections divide by it).
        S: [-] condensed-to-full DOF map (n_dof, n_t), or None.
        mass: [kg] condensed (diagonal) mass, (n_t,), or None.
        expansion: every eigenpair of the state matrix, unfiltered (for the modal
            superposition of :func:`modal_transfer`), or None.
    """

    frequencies_hz: np.ndarray
    damping_ratio: np.ndarray
    poles: np.ndarray
    right: np.ndarray | None = None
    left: np.ndarray | None = None
    S: np.ndarray | None = None
    mass: np.ndarray | None = None
    expansion: StateEigen | None = None
    norm: np.ndarray | None = None


@dataclass(frozen=True)
class StateEigen:
    """All 2 n_t eigenpairs of the state matrix A (complex modes with Im(lambda) >= 0 and,
    implicitly, their conjugates).

    Attributes:
        poles: eigenvalues lambda with Im(lambda) >= 0, (n_e,).
        right, left: psi_k, chi_k as columns (A psi = lambda psi, chi^H A = lambda chi^H),
            (2 n_t, n_e).
        norm: chi_k^H psi_k, (n_e,).
        condition: [-] eigenvalue condition numbers ||psi|| ||chi|| / |chi^H psi|, (n_e,).
    """

    poles: np.ndarray
    right: np.ndarray
    left: np.ndarray
    norm: np.ndarray
    condition: np.ndarray


def complex_modes(model: LinearModel, damping: np.ndarray, max_hz: float | None = None,
                  vectors: bool = False) -> ComplexModes:
    """Eigenvalues (and eigenvectors) of [[0, I], [-M^-1 K, -M^-1 C]], sorted by frequency.

    Args:
        damping: [N s/m] damping matrix in upper band storage (BANDWIDTH + 1, n_dof).
        max_hz: keep only modes below this frequency [Hz].
        vectors: also return right and left eigenvectors.
    """
    cd = condensed(model, damping)  # insulator-axial directions condensed out (exact)
    n = cd.K.shape[0]
    if n > LARGE_SYSTEM_DOF:
        return _approximate_complex_modes(cd, max_hz, vectors)
    minv = 1.0 / np.diag(cd.M)  # diagonal lumped mass in condensed coordinates
    A = np.zeros((2 * n, 2 * n))
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -minv[:, None] * cd.K
    A[n:, n:] = -minv[:, None] * cd.C
    if vectors:
        lam, vr = eig(A, right=True, overwrite_a=True, check_finite=False)  # A is ours and finite (K, C checked)
        # left eigenvectors from the right ones (symmetric K, M, C): A^T w = lambda w with
        # w = [(lambda M + C) phi; M phi], phi the displacement part of psi (Tisseur &
        # Meerbergen 2001, section 3.4); chi = conj(w) so that chi^H A = lambda chi^H
        phi = vr[:n]
        w_top = lam[None, :] * (cd.M @ phi) + cd.C @ phi
        vl = np.conj(np.vstack([w_top, cd.M @ phi]))
    else:
        lam, vl, vr = eig(A, right=False, overwrite_a=True, check_finite=False), None, None
    expansion = nrm = None
    if vectors:
        nrm = np.einsum("ik,ik->k", vl.conj(), vr)  # chi^H psi
        upper = lam.imag >= 0.0  # LAPACK returns exact conjugate pairs for a real matrix
        cond = np.linalg.norm(vr[:, upper], axis=0) * np.linalg.norm(vl[:, upper], axis=0) / np.abs(nrm[upper])
        expansion = StateEigen(lam[upper], vr[:, upper], vl[:, upper], nrm[upper], cond)
    keep = lam.imag > 1e-12
    if max_hz is not None:
        keep &= np.abs(lam) / (2 * np.pi) <= max_hz
    idx = np.flatnonzero(keep)
    idx = idx[np.argsort(np.abs(lam[idx]))]
    lam = lam[idx]
    w = np.abs(lam)
    if not vectors:
        return ComplexModes(w / (2 * np.pi), -lam.real / w, lam)
    return ComplexModes(w / (2 * np.pi), -lam.real / w, lam, vr[:n, idx], vl[n:, idx],
                        cd.S, np.diag(cd.M).copy(), expansion, nrm[idx])


LARGE_SYSTEM_DOF = 600  # above this the dense state-space eigenproblem (O((2n)^3)) is too slow


def _approximate_complex_modes(cd, max_hz: float | None, vectors: bool) -> ComplexModes:
    """Complex modes of large systems from the undamped modes and their modal damping
    zeta_k = phi^T C phi / (2 omega_k) (classical-damping approximation, Clough & Penzien
    2003 section 12-5): lambda = -zeta omega + i omega sqrt(1 - zeta^2).  It cannot see the
    near-degenerate pairs that non-proportional damping splits (docs/method.md)."""
    from scipy.linalg import eigh as _eigh

    m = np.diag(cd.M)
    s = 1.0 / np.sqrt(m)
    A = cd.K * s[:, None] * s[None, :]
    if max_hz is None:
        w2, psi = _eigh(A)
    else:
        w2, psi = _eigh(A, subset_by_value=[-np.inf, (2 * np.pi * max_hz) ** 2])
    phi = psi * s[:, None]  # mass-normalised
    w = np.sqrt(np.clip(w2, 1e-30, None))
    Cphi = cd.C @ phi
    zeta = np.sum(phi * Cphi, axis=0) / (2 * w)  # phi_k^T C phi_k / (2 omega_k)
    zc = np.clip(zeta, 0.0, 0.999999)
    lam = -zc * w + 1j * w * np.sqrt(1 - zc**2)
    if not vectors:
        return ComplexModes(w / (2 * np.pi), zc, lam)
    # psi = [phi; lambda phi], chi = conj([(lambda M + C) phi; M phi]) with real phi:
    # chi^H psi = 2 lambda phi^T M phi + phi^T C phi = 2 lambda + 2 zeta omega (mass-normalised)
    return ComplexModes(w / (2 * np.pi), zc, lam, phi, m[:, None] * phi, cd.S, m.copy(), None,
                        2 * lam + 2 * zc * w)
