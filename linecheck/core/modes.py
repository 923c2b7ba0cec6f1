"""Natural frequencies and mode shapes of a linearised state (issue 4, `linecheck modes`).

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
        (horizontal normal) and vertical directions (issue 17)."""
        sh = self.shapes if self.frames is None else np.einsum("mna,nab->mnb", self.shapes, self.frames)
        return np.argmax((sh**2).sum(axis=1), axis=1)


def natural_modes(model: LinearModel, n_modes: int = 20) -> Modes:
    """The ``n_modes`` lowest undamped modes of ``model`` (dense symmetric eigensolver)."""
    c = condensed(model)
    m = np.diag(c.M)  # diagonal in the condensed coordinates (lumped mass)
    n = min(n_modes, m.size)
    s = 1.0 / np.sqrt(m)
    A = c.K * s[:, None] * s[None, :]
    w2, psi = eigh(A, subset_by_index=[0, n - 1])
    phi = c.S @ (psi * s[:, None])  # back to the full DOFs, mass-normalised
    freq = np.sqrt(np.clip(w2, 0.0, None)) / (2 * np.pi)
    shapes = np.zeros((n, model.system.n_nodes, 3))
    free = model.dofs.free_nodes
    shapes[:, free, :] = phi.T.reshape(n, free.size, 3)
    system = model.system
    return Modes(freq, shapes, None if system.straight_in_plan else system.node_frames)
