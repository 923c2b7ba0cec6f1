"""Wind loads on the conductor: the mean load of step 1 (paper Eq. 1) and the fluctuating loads
of steps 2-3 (paper Eq. 5), with the quadratic drag's corrections (docs/method.md "Quadratic
drag") and the normal component of an oblique wind.

Span-local values (one row of ``ne + 1`` nodes per span) are mapped to the global nodes by
:func:`to_global_nodes`.  Nothing here prints.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from . import kernel
from .case import Case
from .crossflow import applies, normal_part, span_wind_vectors
from .static import drag_intensity
from .system import LineSystem

if TYPE_CHECKING:  # names of annotations only
    from .crossflow import NodeWind
    from .model import LinearModel
    from .wind.mean import MeanWind


def to_global_nodes(system: LineSystem, span_local: np.ndarray) -> np.ndarray:
    """Span-local node values (..., n_spans, ne+1) to global nodes (..., n_nodes).

    A tower node shared by two spans takes the mean of both sides.
    """
    head = span_local[..., :, :-1].reshape(span_local.shape[:-2] + (-1,))
    out = np.concatenate([head, span_local[..., -1:, -1]], axis=-1)
    if system.n_spans > 1:
        out[..., system.tower_nodes[1:-1]] = 0.5 * (span_local[..., :-1, -1] + span_local[..., 1:, 0])
    return out


def turbulence_variance_ratio(case: Case, normal: np.ndarray, longitudinal: np.ndarray) -> np.ndarray:
    """sigma^2 / |V|^2 [-]: variance of the along-wind turbulence over the squared running-mean
    speed, same shape as ``normal`` [m/s] (0 where |V| = 0).

    Downburst: sigma = I |V_m| (Chay et al. 2006), so the ratio is I^2; synoptic: sigma = I V_ref
    on a span of mean speed |V| (I^2 unless ``span_speeds`` differ from v_ref).
    """
    i = case.wind.turbulence_intensity
    if case.wind.type == "downburst":
        return np.full(np.shape(normal), i * i)
    speed2 = normal**2 + longitudinal**2
    sig2 = (i * case.wind.v_ref) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(speed2 > 0, sig2 / np.where(speed2 > 0, speed2, 1.0), 0.0)


def mean_loads(case: Case, wind: MeanWind) -> np.ndarray:
    """Transverse mean load per unit length [N/m], shape (n_t, n_spans, ne+1) (paper Eq. 1).

    ``drag = "quadratic"``: the mean of the drag on the total wind, 1/2 rho C_d D V_n|V_n|
    (1 + sigma^2/|V|^2), i.e. the paper's Eq. 1 times (1 + I^2) (docs/method.md "Quadratic drag").
    """
    line = case.line
    g = drag_intensity(wind.normal, case.wind.air_density, line.drag_coefficient, line.diameter)
    if case.analysis.drag == "quadratic":
        g = g * (1.0 + turbulence_variance_ratio(case, wind.normal, wind.longitudinal))
    return g


def mean_drag(case: Case, system: LineSystem, wind: MeanWind) -> Callable[[np.ndarray], np.ndarray] | None:
    """Cross-flow form of :func:`mean_loads` on a section: ``drag(tangents)`` -> the mean drag per
    unit length [N/m] as vectors, 1/2 rho C_d D |V_perp| V_perp (times 1 + sigma^2/|V|^2 with the
    quadratic drag), V_perp the wind's part normal to the conductor's unit tangents [-] at the
    span nodes (cross-flow principle, Hoerner 1965; :mod:`linecheck.core.crossflow`), both of
    shape (n_t, n_spans, ne+1, 3): a follower load, which step 1 solves on the deformed conductor.
    None for the horizontal-normal form (:func:`~linecheck.core.crossflow.applies`)."""
    if not applies(case, system):
        return None
    line = case.line
    half = 0.5 * case.wind.air_density * line.drag_coefficient * line.diameter
    factor = 1.0
    if case.analysis.drag == "quadratic":  # the mean of the drag on the total wind (Quadratic drag)
        factor = 1.0 + turbulence_variance_ratio(case, wind.normal, wind.longitudinal)[..., None]
    v = span_wind_vectors(system, wind.normal, wind.longitudinal)

    def drag(tangents: np.ndarray) -> np.ndarray:
        u = normal_part(v, tangents)
        return (half * np.linalg.norm(u, axis=-1))[..., None] * u * factor

    return drag


def synoptic_load_per_v(case: Case, model: LinearModel, vn: np.ndarray, vl: np.ndarray | None,
                        perp: np.ndarray | None = None) -> np.ndarray:
    """[N s/m] the synoptic load per unit along-wind turbulence at the global nodes, shape
    (n_nodes,): rho C_d D L_i V_n (paper Eq. 5 per unit v), times cos(phi) = |V_n|/|V| for the
    normal component of the fluctuation when ``vl`` [m/s] (the longitudinal mean speed, oblique
    wind or section) is given; ``vn`` [m/s] the normal mean speed, (n_nodes,).  ``perp``: the
    cross-flow form, as :func:`fluctuating_loads` (|V_perp| / |V| in place of |V_n| / |V|)."""
    line, wind = case.line, case.wind
    a = wind.air_density * line.drag_coefficient * line.diameter * model.tributary * vn  # Eq. 5 per unit v
    if vl is not None:
        speed = np.hypot(vn, vl)  # cos(phi) = |V_n| / |V|, as the time domain (fluctuating_loads)
        size = np.abs(vn) if perp is None else perp
        a = a * np.where(speed > 0, size / np.where(speed > 0, speed, 1.0), 1.0)
    return a


def _load_factors(case: Case, model: LinearModel, vn: np.ndarray, vl: np.ndarray | None,
                  perp: np.ndarray | None = None):
    """Per-node factors of the fluctuating drag over the rows of ``vn`` [m/s] (n_rows, n_nodes):
    per_v [N s/m] (paper Eq. 5 per unit v, normal component v cos(phi)) and, with the quadratic
    drag, per_q [N s^2/m^2] (1/2 rho C_d D L V_n|V_n|/|V|^2) and sig2 [m^2/s^2] (sigma^2), else
    None twice.  ``perp`` [m/s] (cross-flow form, :class:`~linecheck.core.crossflow.NodeWind`):
    |V_perp| in place of |V_n|, ``vn`` then the component of V_perp along the load direction and
    hypot(vn, vl) = |V|."""
    line, wind = case.line, case.wind
    size = np.abs(vn) if perp is None else perp  # |V_n|, or |V_perp| (cross-flow principle, Hoerner 1965)
    if vl is None:
        cos_n = np.ones_like(vn)
    else:
        speed = np.hypot(vn, vl)
        with np.errstate(invalid="ignore", divide="ignore"):
            cos_n = np.where(speed > 0, size / np.where(speed > 0, speed, 1.0), 1.0)
    coef = wind.air_density * line.drag_coefficient * line.diameter
    # Eq. 5 per unit v, normal component of the fluctuation: v cos(phi), phi the angle of
    # the mean wind to the normal of the line
    per_v = coef * model.tributary[None, :] * (vn * cos_n)  # (n_rows, n_nodes)
    if case.analysis.drag != "quadratic":
        return per_v, None, None
    vl0 = np.zeros_like(vn) if vl is None else vl
    ratio = turbulence_variance_ratio(case, vn, vl0)  # sigma^2/|V|^2
    speed2 = vn**2 + vl0**2
    with np.errstate(divide="ignore", invalid="ignore"):
        inv = np.where(speed2 > 0, 1.0 / np.where(speed2 > 0, speed2, 1.0), 0.0)
    # 1/2 rho C_d D L V_n|V_n| / |V|^2 per unit (v^2 - sigma^2); sigma^2 = ratio |V|^2
    per_q = 0.5 * coef * model.tributary[None, :] * vn * size * inv
    return per_v, per_q, ratio * speed2


def _pinned_reactions(system: LineSystem, pinned: np.ndarray, pv_p, pq_p, s2_p, v: np.ndarray,
                      direct: np.ndarray, dirs: np.ndarray | None = None) -> None:
    """Write the loads [N] at the pinned nodes ``pinned`` straight into their supports' reactions
    ``direct`` (n_steps, n_real, 3 n_towers): R_y, or along the node normal of a section, or
    along the nodes' load directions ``dirs`` (n_nodes, 3) (cross-flow form; R_z downward)."""
    cols = 3 * np.flatnonzero(~system.suspension)
    for i in range(v.shape[0] if pinned.size else 0):
        vp = v[i][:, pinned]
        f_i = pv_p * vp  # (n_steps, n_pinned)
        if pq_p is not None:
            f_i += pq_p * (vp * vp - s2_p)
        if dirs is not None:
            b = dirs[pinned]
            direct[:, i, cols] = f_i * b[:, 0]
            direct[:, i, cols + 1] = f_i * b[:, 1]
            direct[:, i, cols + 2] = -f_i * b[:, 2]  # the reaction's z is downward
        elif system.straight_in_plan:
            direct[:, i, cols + 1] = f_i
        else:
            b = system.node_normals[pinned]
            direct[:, i, cols] = f_i * b[:, 0]
            direct[:, i, cols + 1] = f_i * b[:, 1]


def fluctuating_loads(case: Case, system: LineSystem, model: LinearModel, t: np.ndarray, v: np.ndarray,
                      vn: np.ndarray, vl: np.ndarray | None = None,
                      cross: NodeWind | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Fluctuating transverse nodal loads of steps 2-3 from the along-wind turbulence.

    Args:
        t: [s] record instants, shape (n_steps,).
        v: [m/s] along-wind turbulence, shape (n_real, n_steps, n_nodes).
        vn: [m/s] running-mean normal speed at the nodes, (n_steps, n_nodes);
        vl: [m/s] running-mean longitudinal speed (downburst; None: zero, cos(phi) = 1).
        cross: the cross-flow form on inclined spans (:class:`~linecheck.core.crossflow.NodeWind`
            over the record; ``vn``, ``vl`` are then ignored): the load acts along each node's
            direction d_j with |V_perp| in place of |V_n|.
    Returns:
        loads [N] on the free nodes, (n_steps, n_real, n_free); direct [N] reactions of the loads
        at pinned nodes, (n_steps, n_real, 3 n_towers).

    ``drag = "linear"``: rho C_d D L_i V_n v_n (paper Eq. 5), v_n = v cos(phi) the normal component
    of the fluctuation.  ``"quadratic"`` adds the zero-mean rest of the drag on the total wind,
    1/2 rho C_d D L_i V_n|V_n|/|V|^2 (v^2 - sigma^2) (docs/method.md "Quadratic drag"; its mean
    sigma^2 is in step 1, :func:`mean_loads`).
    """
    perp = None
    if cross is not None:  # cross-flow principle (Hoerner 1965): V_perp along d_j, |V_perp| for |V_n|
        vn, vl, perp = cross.along, cross.rest, cross.perp
    shape = vn.shape  # (n_steps, n_nodes)
    # a synoptic record holds its mean (rows broadcast, stride 0): the per-node factors are
    # elementwise, so they are computed on one row and viewed over the record (the same values;
    # ≈ 20 ms less per chunk with the quadratic drag)
    held = (vn.ndim == 2 and vn.strides[0] == 0 and (vl is None or vl.strides[0] == 0)
            and (perp is None or perp.strides[0] == 0))
    if held:
        vn = vn[:1]
        vl = None if vl is None else vl[:1]
        perp = None if perp is None else perp[:1]
    per_v, per_q, sig2 = _load_factors(case, model, vn, vl, perp)
    quad = per_q is not None
    if held:  # writeable views, as the materialised factors (np.broadcast_to's are read-only: another
        # array type, i.e. another specialisation of the compiled drag)
        def over_record(a: np.ndarray) -> np.ndarray:
            return np.lib.stride_tricks.as_strided(a, shape=shape, strides=(0, a.strides[1]))

        per_v = over_record(per_v)
        if quad:
            per_q, sig2 = over_record(per_q), over_record(sig2)
    free = model.dofs.free_nodes
    pinned = system.tower_nodes[~system.suspension]
    n_real = v.shape[0]
    loads = np.empty((t.size, n_real, free.size))
    direct = np.zeros((t.size, n_real, 3 * system.n_towers))
    # the free nodes are usually one run (all but the strain towers' nodes): a slice, no gathers
    run = free.size and np.array_equal(free, np.arange(free[0], free[0] + free.size))
    sel = slice(int(free[0]), int(free[0]) + free.size) if run else free
    # the same elementwise products as on every node, written straight into the loads (one
    # compiled pass with the kernel's piece ``loads``)
    kernel.drag_loads(per_v[:, sel], per_q[:, sel] if quad else None, sig2[:, sel] if quad else None, v, sel, loads)
    _pinned_reactions(system, pinned, per_v[:, pinned], per_q[:, pinned] if quad else None,
                      sig2[:, pinned] if quad else None, v, direct, None if cross is None else cross.directions)
    return loads, direct
