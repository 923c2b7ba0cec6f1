"""Damping of the linearised conductor (paper Eqs 9-13; docs/method.md, "Damping").

Two aerodynamic models, selected by ``[analysis] damping``:

- ``"paper"`` (Eq. 13): c_a,i(t) = rho C_d D L_i V_i(t) on the transverse (y) DOF of node i
  only, L_i the tributary conductor length and V_i the local running-mean speed normal to
  the line -- the linearisation of 1/2 rho C_d D (V - u')^2 about u' = 0 (Eqs 10-12).
- ``"quasi-steady"``: the drag 1/2 rho C_d D |V_rel| V_rel acts on the velocity of the wind
  relative to the conductor in the plane normal to the conductor axis (cross-flow
  principle).  Linearised about the mean wind V w (w the unit wind direction in that
  plane): dF = -rho C_d D L V [w w^T + 1/2 (P - w w^T)] u', P = I - e e^T the projector
  normal to the conductor axis e.  Along-wind c = rho C_d D V L (= Eq. 13), cross-wind
  (in the plane, normal to the wind, mostly vertical) c = 1/2 rho C_d D V L (Davenport
  1962; Matheson & Holmes 1981, whose full analysis has the relative velocity in every
  direction).

Structural damping (``structural_damping`` = zeta_s): stiffness-proportional,
C_s = beta K with beta = 2 zeta_s / omega_1 (omega_1 the lowest undamped mode of the mean
state), so the ratio is zeta_s at that mode and grows with frequency (Chopra 2012,
section 11.4).  Conductor self-damping (inter-strand friction) is small, of the order of
0.1-1 % of critical and dependent on tension and amplitude (IEEE Guide on conductor
self-damping measurements, 1978).  With "paper" the default is 0 (the paper's method);
with "quasi-steady" it is 0.2 % (:data:`~linecheck.core.case.DEFAULT_STRUCTURAL_DAMPING`):
the cross-flow principle gives no aerodynamic damping for motion along the conductor
axis, so without it the axial modes of a span (2.3 Hz and up for 300 m) keep damping
ratios of 1e-5..1e-8 (docs/method.md, "Damping").

Every function returns the damping matrix in the upper band storage of
:mod:`linecheck.core.model` (shape (BANDWIDTH + 1, n_dof)).
"""

from __future__ import annotations

import numpy as np

from .case import Case
from .model import BANDWIDTH, LinearModel, project_axial, project_axial_stack


def _add_node_blocks(ab: np.ndarray, first_dof: np.ndarray, blocks: np.ndarray) -> None:
    """Add symmetric 3x3 blocks on the diagonal of an upper band matrix."""
    u = ab.shape[-2] - 1
    for a in range(3):
        for b in range(a, 3):
            ab[..., u - (b - a), first_dof + b] += blocks[..., a, b]


def node_tangents(nodes: np.ndarray) -> np.ndarray:
    """Unit conductor tangent at every global node (mean of the adjacent chords), (..., n_nodes, 3)
    for node coordinates [m] of shape (..., n_nodes, 3) (leading axes: mean states)."""
    seg = np.diff(nodes, axis=-2)
    seg /= np.linalg.norm(seg, axis=-1)[..., None]
    t = np.zeros_like(nodes)
    t[..., :-1, :] += seg
    t[..., 1:, :] += seg
    return t / np.linalg.norm(t, axis=-1)[..., None]


def _cross_blocks(c: np.ndarray, u: np.ndarray, dirs: np.ndarray, P: np.ndarray | None) -> np.ndarray:
    """[N s/m] the aerodynamic damping blocks (..., n_free, 3, 3) of the cross-flow form: c the
    coefficients rho C_d D L |V_perp| (..., n_free), u [m/s] V_perp (..., n_free, 3), dirs the
    load directions d (n_free, 3); "paper" (P None): c d d^T (Eq. 13 along the load); quasi-steady:
    the relative wind w = P V_perp / |P V_perp| (P the projector normal to the deformed axis)."""
    if P is None:
        return c[..., None, None] * dirs[:, :, None] * dirs[:, None, :]
    w = np.einsum("...ab,...b->...a", P, u)
    size = np.linalg.norm(w, axis=-1)
    fall = np.einsum("...ab,...b->...a", P, np.broadcast_to(dirs, w.shape))  # no wind: the load direction
    w = np.where((size > 0)[..., None], w, fall)
    w = w / np.linalg.norm(w, axis=-1)[..., None]
    ww = w[..., :, None] * w[..., None, :]
    return c[..., None, None] * (ww + 0.5 * (P - ww))


def aerodynamic_damping(case: Case, model: LinearModel, vn_nodes: np.ndarray, nodes: np.ndarray | None = None,
                        cross: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """Aerodynamic damping matrix [N s/m] in upper band storage, shape (BANDWIDTH + 1, n_dof).

    Args:
        case: the case (air density, C_d, D, ``analysis.damping``).
        model: linear model of the mean state (DOF map, tributary lengths).
        vn_nodes: [m/s] running-mean normal speed at every global node, shape (n_nodes,).
        nodes: [m] deformed node coordinates of the mean state, (n_nodes, 3); needed for
            ``"quasi-steady"``.
        cross: the cross-flow form on inclined spans (:mod:`linecheck.core.crossflow`): V_perp
            [m/s] (n_nodes, 3) and the load directions d (n_nodes, 3); ``vn_nodes`` is then unused.
    """
    line = case.line
    coef = case.wind.air_density * line.drag_coefficient * line.diameter  # rho C_d D (Eq. 13)
    free = model.dofs.free_nodes
    n_dof = model.dofs.n_dof
    ab = np.zeros((BANDWIDTH + 1, n_dof))
    first = model.dofs.node_dof[free]
    system = model.system
    if cross is not None:  # |V_perp| (cross-flow principle, Hoerner 1965) in place of |V_n|
        u, dirs = cross[0][free], cross[1][free]
        c = coef * model.tributary[free] * np.linalg.norm(u, axis=-1)
        P = None
        if case.analysis.damping != "paper":
            if nodes is None:
                raise ValueError("quasi-steady damping needs the mean-state node coordinates")
            e = node_tangents(nodes)[free]
            P = np.eye(3)[None] - e[:, :, None] * e[:, None, :]
        _add_node_blocks(ab, first, _cross_blocks(c, u, dirs, P))
        return project_axial(model, ab)  # a rigid insulator carries the axial part
    c = coef * model.tributary[free] * np.abs(vn_nodes[free])  # (n_free,)
    if case.analysis.damping == "paper":
        if system.straight_in_plan:
            ab[BANDWIDTH, first + 1] = c  # Eq. 9: transverse DOF only
        else:  # along each node's transverse direction b (line sections): c b b^T
            b = system.node_normals[free]
            _add_node_blocks(ab, first, c[:, None, None] * b[:, :, None] * b[:, None, :])
        return project_axial(model, ab)  # a rigid insulator carries the axial part
    if nodes is None:
        raise ValueError("quasi-steady damping needs the mean-state node coordinates")
    e = node_tangents(nodes)[free]  # (n_free, 3)
    P = np.eye(3)[None] - e[:, :, None] * e[:, None, :]
    if system.straight_in_plan:
        w = P[:, :, 1]  # the wind (+y) projected normal to the axis
    else:  # the node's transverse load direction b projected normal to the axis (line sections)
        w = np.einsum("nab,nb->na", P, system.node_normals[free])
    w = w / np.linalg.norm(w, axis=1)[:, None]
    ww = w[:, :, None] * w[:, None, :]
    blocks = c[:, None, None] * (ww + 0.5 * (P - ww))
    _add_node_blocks(ab, first, blocks)
    return project_axial(model, ab)  # a rigid insulator carries the axial part


def stiffness_proportional(model: LinearModel, ratio: float, omega1: float) -> np.ndarray:
    """Structural damping C_s = (2 zeta_s / omega_1) K_c [N s/m], upper band storage.

    K_c is the stiffness without the insulator axial penalty, projected normal to the
    insulator axes (a rigid insulator does not deform, so it dissipates nothing).
    """
    if ratio <= 0.0:
        return np.zeros_like(model.K_band)
    return (2.0 * ratio / omega1) * project_axial(model, model.K_band - model.K_axial_band)


def aerodynamic_damping_stack(case: Case, models: list[LinearModel], vn_nodes: np.ndarray,
                              nodes: np.ndarray | None = None,
                              cross: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
    """:func:`aerodynamic_damping` of many mean states of one system in one vectorised pass
    (long lines), bit-identical to calling it state by state.

    Args:
        models: the linear models of the states (one system, e.g. from
            :func:`~linecheck.core.model.build_models`), length n_k.
        vn_nodes: [m/s] running-mean normal speed at every global node, shape (n_k, n_nodes).
        nodes: [m] deformed node coordinates, shape (n_k, n_nodes, 3) (``"quasi-steady"``).
        cross: the cross-flow form (as :func:`aerodynamic_damping`): V_perp [m/s] of every state
            (n_k, n_nodes, 3) and the load directions d (n_nodes, 3).

    Returns: [N s/m] upper band storage, shape (n_k, BANDWIDTH + 1, n_dof).
    """
    model = models[0]
    line = case.line
    coef = case.wind.air_density * line.drag_coefficient * line.diameter  # rho C_d D (Eq. 13)
    free = model.dofs.free_nodes
    n_k = len(models)
    ab = np.zeros((n_k, BANDWIDTH + 1, model.dofs.n_dof))
    first = model.dofs.node_dof[free]
    system = model.system
    axes = np.stack([m.axes for m in models])  # (n_k, n_s, 3)
    if cross is not None:  # |V_perp| (cross-flow principle, Hoerner 1965) in place of |V_n|
        u, dirs = np.asarray(cross[0])[:, free], cross[1][free]
        c = coef * model.tributary[free] * np.linalg.norm(u, axis=-1)  # (n_k, n_free)
        P = None
        if case.analysis.damping != "paper":
            if nodes is None:
                raise ValueError("quasi-steady damping needs the mean-state node coordinates")
            e = node_tangents(np.asarray(nodes))[:, free]
            P = np.eye(3) - e[..., :, None] * e[..., None, :]
        _add_node_blocks(ab, first, _cross_blocks(c, u, dirs, P))
        return project_axial_stack(model.axial_dof, axes, ab)  # a rigid insulator carries the axial part
    c = coef * model.tributary[free] * np.abs(np.asarray(vn_nodes)[:, free])  # (n_k, n_free)
    if case.analysis.damping == "paper":
        if system.straight_in_plan:
            ab[:, BANDWIDTH, first + 1] = c  # Eq. 9: transverse DOF only
        else:  # along each node's transverse direction b (line sections): c b b^T
            b = system.node_normals[free]
            _add_node_blocks(ab, first, c[..., None, None] * b[:, :, None] * b[:, None, :])
        return project_axial_stack(model.axial_dof, axes, ab)  # a rigid insulator carries the axial part
    if nodes is None:
        raise ValueError("quasi-steady damping needs the mean-state node coordinates")
    e = node_tangents(np.asarray(nodes))[:, free]  # (n_k, n_free, 3)
    P = np.eye(3) - e[..., :, None] * e[..., None, :]
    if system.straight_in_plan:
        w = P[..., :, 1]  # the wind (+y) projected normal to the axis
    else:  # the node's transverse load direction b projected normal to the axis (line sections)
        w = np.einsum("nab,nb->na", P.reshape(-1, 3, 3),
                      np.tile(system.node_normals[free], (n_k, 1))).reshape(P.shape[:-1])
    w = w / np.linalg.norm(w, axis=-1)[..., None]
    ww = w[..., :, None] * w[..., None, :]
    blocks = c[..., None, None] * (ww + 0.5 * (P - ww))
    _add_node_blocks(ab, first, blocks)
    return project_axial_stack(model.axial_dof, axes, ab)  # a rigid insulator carries the axial part


def stiffness_proportional_stack(models: list[LinearModel], ratio: float, omega1: float) -> np.ndarray:
    """:func:`stiffness_proportional` of many mean states in one pass, shape (n_k, BANDWIDTH + 1, n_dof)."""
    K = np.stack([m.K_band for m in models])
    if ratio <= 0.0:
        return np.zeros_like(K)
    Kc = K - np.stack([m.K_axial_band for m in models])
    return (2.0 * ratio / omega1) * project_axial_stack(models[0].axial_dof, np.stack([m.axes for m in models]), Kc)
