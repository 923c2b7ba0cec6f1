"""Natural frequencies and mode shapes of a linearised state (`linecheck modes`).

Generalised eigenproblem K phi = omega^2 M phi with the lumped (diagonal) mass, on the
model with the insulator-axial directions condensed out (:func:`~linecheck.core.model.condensed`),
solved as the symmetric standard problem M^-1/2 K M^-1/2 psi = omega^2 psi.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import eigh

from .model import LinearModel, condensed


@dataclass(frozen=True)
class Modes:
    """Lowest natural modes of one state.

    Attributes:
        frequencies_hz: [Hz] natural frequencies, ascending, shape (n_modes,).
        shapes: mass-normalised mode shapes at every global node (zero at pinned nodes),
            shape (n_modes, n_nodes, 3), last axis (x, y, z).
    """

    frequencies_hz: np.ndarray
    shapes: np.ndarray
    frames: np.ndarray | None = None  # per-node (along, normal, up) bases of a section with angles

    def dominant_direction(self) -> np.ndarray:
        """Index (0 x, 1 y, 2 z) of the direction holding most of each mode's kinetic energy, (n_modes,).

        On a section with angle towers x, y, z are every node's own along-line, transverse
        (horizontal normal) and vertical directions."""
        sh = self.shapes if self.frames is None else np.einsum("mna,nab->mnb", self.shapes, self.frames)
        return np.argmax((sh**2).sum(axis=1), axis=1)


def natural_modes(model: LinearModel, n_modes: int = 20) -> Modes:
    """The ``n_modes`` lowest undamped modes of ``model``.

    Up to :data:`~linecheck.core.model.SPARSE_CONDENSATION_DOF` DOFs the dense symmetric
    eigensolver of the condensed problem (module docstring).  Larger systems (long
    lines; the dense solver is O(n^3)): shift-invert Lanczos (ARPACK via
    ``scipy.sparse.linalg.eigsh``; Ericsson & Ruhe 1980) on the sparse banded K and lumped M
    about sigma = 0, O(n) per mode.  The insulator-axial DOFs carry no mass, so M is only
    semi-definite, which shift-invert allows; their infinite eigenvalues map to 0, and the
    modes are those of the condensed problem (whose condensation is exact for massless DOFs).
    Its shapes are M-normalised with their largest component positive (the dense solver's
    signs are LAPACK's)."""
    from .model import SPARSE_CONDENSATION_DOF

    if model.mass.size > SPARSE_CONDENSATION_DOF and n_modes < model.mass.size - len(model.axial_dof) - 1:
        return _natural_modes_sparse(model, n_modes)
    c = condensed(model)
    m = np.diag(c.M)  # diagonal in the condensed coordinates (lumped mass)
    n = min(n_modes, m.size)
    s = 1.0 / np.sqrt(m)
    A = c.K * s[:, None] * s[None, :]
    w2, psi = eigh(A, subset_by_index=[0, n - 1])
    phi = c.S @ (psi * s[:, None])  # back to the full DOFs, mass-normalised
    return _modes(model, w2, phi)


def _modes(model: LinearModel, w2: np.ndarray, phi: np.ndarray) -> Modes:
    """:class:`Modes` from eigenvalues w2 [rad^2/s^2] (n,) and M-normalised free-DOF shapes (n_dof, n)."""
    n = w2.size
    freq = np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi)
    shapes = np.zeros((n, model.system.n_nodes, 3))
    free = model.dofs.free_nodes
    shapes[:, free, :] = phi.T.reshape(n, free.size, 3)
    system = model.system
    return Modes(freq, shapes, None if system.straight_in_plan else system.node_frames)


def _natural_modes_sparse(model: LinearModel, n_modes: int) -> Modes:
    """:func:`natural_modes` of a large system by shift-invert Lanczos (see there)."""
    from scipy.sparse.linalg import eigsh

    from .model import band_to_sparse

    K = band_to_sparse(model.K_band).tocsc()
    M = band_to_sparse(model.M_band).tocsc()
    w2, phi = eigsh(K, k=n_modes, M=M, sigma=0.0, which="LM", v0=np.ones(K.shape[0]), tol=0.0)
    order = np.argsort(w2)
    w2, phi = w2[order], phi[:, order]
    phi = phi / np.sqrt(np.einsum("ik,ik->k", phi, M @ phi))  # M-normalised (M: the axially projected lumped mass)
    big = np.argmax(np.abs(phi), axis=0)
    phi = phi * np.sign(phi[big, np.arange(phi.shape[1])])
    return _modes(model, w2, phi)



def pair_by_shape(modes: Modes, model: LinearModel, right: np.ndarray, S) -> tuple[np.ndarray, np.ndarray]:
    """The damped counterpart of each undamped mode of ``model``: the pairing of the undamped
    ``modes`` with the complex modes (displacement halves ``right`` (n_t, n_c) in the condensed
    coordinates, u = ``S`` t; :class:`~linecheck.core.spectral.ComplexModes`) that maximises the
    sum of the mass-weighted modal assurance criteria
    MAC = |phi^T M psi|^2 / ((phi^T M phi)(psi^H M psi)) (Allemang & Brown 1982), one complex
    mode per undamped mode (the assignment problem, ``scipy.optimize.linear_sum_assignment``).
    Sorting both sets by frequency is not a pairing: damping splits and shifts near-degenerate
    modes (in-plane/out-of-plane) differently.

    Returns the index of the paired complex mode (n_modes,), -1 where there are fewer complex
    modes than undamped ones, and its MAC [-] in [0, 1] (NaN where unpaired).
    """
    from scipy.optimize import linear_sum_assignment

    n = modes.frequencies_hz.size
    free = model.dofs.free_nodes
    phi = modes.shapes[:, free, :].reshape(n, -1).T  # (n_dof, n), the full DOFs of the model
    psi = np.asarray(S @ right)  # (n_dof, n_c) complex
    m = model.mass
    cross = np.abs(phi.T @ (m[:, None] * psi)) ** 2  # (n, n_c)
    norm_phi = np.einsum("ik,ik->k", phi, m[:, None] * phi)
    norm_psi = np.einsum("ik,ik->k", psi.conj(), m[:, None] * psi).real
    mac = cross / np.maximum(norm_phi[:, None] * norm_psi[None, :], np.finfo(float).tiny)
    rows, cols = linear_sum_assignment(-mac)
    index = np.full(n, -1, dtype=int)
    best = np.full(n, np.nan)
    index[rows] = cols
    best[rows] = mac[rows, cols]
    return index, best
