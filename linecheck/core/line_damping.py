"""The damping of a line's linear models at its step-1 mean states: the aerodynamic damping of
``analysis.damping`` (paper Eq. 13 or the quasi-steady model, :mod:`linecheck.core.damping`) plus
stiffness-proportional structural damping calibrated at the lowest mode of a reference mean state
(docs/method.md, "Damping").  Nothing here prints.
"""

from __future__ import annotations

import numpy as np

from .case import Case
from .damping import aerodynamic_damping_stack, stiffness_proportional_stack
from .model import LinearModel, build_model
from .static import MeanStates
from .system import LineSystem


def reference_state_index(case: Case, mean: MeanStates) -> int:
    """Mean state used for single-state quantities (modes, structural damping calibration):
    synoptic 0; downburst the instant of the largest wind-induced mean reaction at the tower."""
    j = case.line.tower_of_interest - 1
    return int(np.argmax(np.abs(mean.reactions_wind[:, j, :]).max(axis=1)))


def structural_omega1(ref: LinearModel) -> float:
    """[rad/s] the lowest natural circular frequency of the reference state's model ``ref``, at
    which the structural damping is calibrated (:func:`~linecheck.core.modes.natural_modes`:
    dense up to 600 DOFs, sparse Lanczos above)."""
    from .modes import natural_modes

    return 2 * np.pi * float(natural_modes(ref, 1).frequencies_hz[0])


def damping_stack(case: Case, system: LineSystem, mean: MeanStates, vn: np.ndarray, models: list[LinearModel],
                  states: list[int], omega1: float | None = None,
                  cross: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Damping of mean states [N s/m], upper band storage, shape (len(models), 6, n_dof).

    ``models[i]`` is the model of mean state ``states[i]``; ``vn`` [m/s] the running-mean normal
    speed at the global nodes of every mean state, (n_k, n_nodes).  Aerodynamic (``analysis.damping``)
    plus stiffness-proportional structural damping, C_s = 2 zeta_s / omega_1 K (Chopra 2012,
    section 11.4), calibrated at the lowest mode of the reference mean state
    (:func:`reference_state_index`), or at ``omega1`` [rad/s] when given.  ``cross``: the
    cross-flow form's V_perp [m/s] of every mean state (n_k, n_nodes, 3) and load directions
    (n_nodes, 3) (:func:`~linecheck.core.damping.aerodynamic_damping_stack`).
    """
    u = None if cross is None else (cross[0][states], cross[1])
    C = aerodynamic_damping_stack(case, models, vn[states], mean.nodes[states], u)  # all states in one pass
    zs = case.analysis.structural_ratio
    if zs > 0:
        if omega1 is None:
            k_ref = reference_state_index(case, mean)
            ref = models[states.index(k_ref)] if k_ref in states else build_model(system, mean.state(k_ref))
            omega1 = structural_omega1(ref)
        C = C + stiffness_proportional_stack(models, zs, omega1)
    return C
