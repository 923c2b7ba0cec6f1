"""Aerodynamic damping of the linearised conductor (paper Eqs 9-13).

``paper`` model (Eq. 13): c_a,i(t) = rho C_d D L_i V_i(t) on the transverse (y) DOF
of node i only, L_i the tributary conductor length and V_i the local running-mean
speed normal to the line (the linearisation of 1/2 rho C_d D (V - u')^2 about u' = 0,
Eqs 10-12).
"""

from __future__ import annotations

import numpy as np

from .case import Case
from .model import LinearModel


def aerodynamic_damping(case: Case, model: LinearModel, vn_nodes: np.ndarray) -> np.ndarray:
    """Viscous damping per DOF [N s/m], shape (n_dof,).

    Args:
        case: the case (air density, C_d, D).
        model: linear model of the mean state (DOF map, tributary lengths).
        vn_nodes: [m/s] running-mean normal speed at every global node, shape (n_nodes,).
    """
    line = case.line
    coef = case.wind.air_density * line.drag_coefficient * line.diameter  # rho C_d D (Eq. 13)
    free = model.dofs.free_nodes
    c = np.zeros(model.dofs.n_dof)
    c[1::3] = coef * model.tributary[free] * np.abs(vn_nodes[free])
    return c
