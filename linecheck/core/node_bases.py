"""Per-node orthonormal bases in which the mass and the damping's 3x3 node blocks are diagonal:
the bases of the Newmark step loop of :mod:`linecheck.core.dynamics` (its per-step products are
then elementwise), for one mean state or many at once."""

from __future__ import annotations

import numpy as np

from .model import LinearModel, band_blocks

__all__ = ["node_bases", "node_bases_stack"]


def node_bases(model: LinearModel, c_band: np.ndarray) -> np.ndarray:
    """Per-node orthonormal bases in which M and the node blocks of C are diagonal.

    A free node's mass is isotropic (m I), so the eigenvectors of its 3x3 damping block
    diagonalise both.  At a suspension attachment node the mass and damping are projected
    normal to the insulator axis a (rigid insulator): the basis is (t1, t2, a) with t1, t2
    the eigenvectors of the in-plane 2x2 damping block.

    Returns: [-] bases as columns (local axes in global coordinates), shape (n_nodes, 3, 3).
    """
    D, _ = band_blocks(c_band)
    _, T = np.linalg.eigh(D)
    if model.axial_dof.size:
        k = model.axial_dof // 3
        a = model.axes / np.linalg.norm(model.axes, axis=1)[:, None]
        h = np.where(np.abs(a[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        t1 = np.cross(a, h)
        t1 /= np.linalg.norm(t1, axis=1)[:, None]
        t2 = np.cross(a, t1)
        Q = np.stack([t1, t2], axis=2)  # (n_s, 3, 2) orthonormal basis of the plane
        _, W = np.linalg.eigh(np.einsum("sai,sab,sbj->sij", Q, D[k], Q))
        T[k] = np.concatenate([np.einsum("sai,sij->saj", Q, W), a[:, :, None]], axis=2)
    return T


def node_bases_stack(models: list[LinearModel], c_bands: np.ndarray) -> np.ndarray:
    """:func:`node_bases` of many mean states of one system in one vectorised pass:
    the eigen-decompositions of all states' 3x3 node blocks in one batched LAPACK call;
    bit-identical to calling it state by state.

    Args:
        models: linear models of the states (one system: same DOF map), length n_k.
        c_bands: [N s/m] their damping bands, shape (n_k, BANDWIDTH + 1, n_dof).

    Returns: [-] bases, shape (n_k, n_nodes, 3, 3).
    """
    D, _ = band_blocks(c_bands)  # (n_k, n_nodes, 3, 3)
    _, T = np.linalg.eigh(D)
    axial_dof = models[0].axial_dof
    if axial_dof.size:
        n_k, n_s = len(models), axial_dof.size
        k = axial_dof // 3
        axes = np.stack([m.axes for m in models]).reshape(-1, 3)  # (n_k n_s, 3): as node_bases, flattened
        a = axes / np.linalg.norm(axes, axis=1)[:, None]
        h = np.where(np.abs(a[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
        t1 = np.cross(a, h)
        t1 /= np.linalg.norm(t1, axis=1)[:, None]
        t2 = np.cross(a, t1)
        Q = np.stack([t1, t2], axis=2)  # (n_k n_s, 3, 2) orthonormal basis of the plane
        _, W = np.linalg.eigh(np.einsum("sai,sab,sbj->sij", Q, D[:, k].reshape(-1, 3, 3), Q))
        T[:, k] = np.concatenate([np.einsum("sai,sij->saj", Q, W), a[:, :, None]], axis=2).reshape(n_k, n_s, 3, 3)
    return T
