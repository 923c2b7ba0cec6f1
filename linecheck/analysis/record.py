"""The record of steps 2-3: its time grid (with a synoptic burn-in), the running-mean wind and the
turbulence's modulation at the nodes over it, the step-1 mean reactions interpolated to it, and
the mean state each step uses (the nearest, or the reference scheme's linear interpolation).
Nothing here prints.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from ..core.case import Case
from ..core.crossflow import NodeWind, node_wind
from ..core.damping import aerodynamic_damping, node_tangents, stiffness_proportional
from ..core.line_damping import reference_state_index, structural_omega1
from ..core.loads import to_global_nodes
from ..core.model import LinearModel, build_model
from ..core.static import MeanStates
from ..core.system import LineSystem
from ..core.wind.mean import mean_wind
from .step1 import StaticResult


def record_time(case: Case) -> np.ndarray:
    """Time grid of steps 2-3 [s], shape (n_steps,): synoptic 0..duration, downburst the event window."""
    from ..core.wind.point import record_times

    return record_times(case)


def burn_in_steps(case: Case, burn_in: float) -> int:
    """Time steps of a burn-in of ``burn_in`` [s]: the whole number that covers it."""
    dt = case.analysis.time_step
    return max(0, math.ceil(burn_in / dt - 1e-9))


def with_burn_in(case: Case, t: np.ndarray, burn_in: float) -> np.ndarray:
    """The record ``t`` [s] lengthened at its start by at least ``burn_in`` [s] (a whole number of
    time steps, :func:`burn_in_steps`), shape (n_steps + burn_in_steps,); the analysed record is
    its last n_steps instants, exactly ``t``'s."""
    dt = case.analysis.time_step
    n = burn_in_steps(case, burn_in)
    return t[0] - dt * n + dt * np.arange(t.size + n)


def peak_window_steps(case: Case) -> int | None:
    """Samples per peak window (``analysis.peak_window`` / time step), None for the whole record."""
    w = case.analysis.peak_window
    return None if w is None else max(1, int(round(w / case.analysis.time_step)))


def record_mean_wind(case: Case, st: StaticResult, t: np.ndarray) -> tuple[np.ndarray, np.ndarray | None]:
    """Running-mean normal and longitudinal speeds [m/s] at the global nodes over the record
    ``t``, shape (n_steps, n_nodes) each (synoptic: the step-1 wind held, longitudinal None)."""
    system = st.system
    if case.wind.type == "synoptic":
        vn = np.broadcast_to(to_global_nodes(system, st.wind.normal)[0], (t.size, system.n_nodes))
        if not system.is_section and case.wind.direction == 0.0:
            return vn, None  # the paper's wind: normal to the line, cos(phi) = 1
        from ..core.wind.mean import mean_components_at_nodes

        # oblique wind or a section: the longitudinal component gives cos(phi) = |V_n|/|V| of the fluctuation
        vl = np.broadcast_to(mean_components_at_nodes(case, system, t[:1])[1][0], (t.size, system.n_nodes))
        return vn, vl
    mw = mean_wind(case, system, t)
    return to_global_nodes(system, mw.normal), to_global_nodes(system, mw.longitudinal)


def record_cross_wind(case: Case, st: StaticResult, t: np.ndarray, vn: np.ndarray,
                      vl: np.ndarray | None) -> NodeWind | None:
    """The mean states' cross-flow wind (:attr:`StaticResult.cross_wind`) over the record ``t`` [s], (n_steps, n_nodes) each, from the
    record's running-mean normal and along-line speeds ``vn``, ``vl`` [m/s] (:func:`record_wind`,
    (n_steps, n_nodes); the horizontal wind vn n + vl e at each node, n its normal and e its
    along-line direction): the mean wind at every step on the axes of its nearest mean state,
    with the states' load directions (one per node for the whole record; a synoptic record holds
    its mean, rows of stride 0)."""
    states = st.cross_wind
    if states is None:
        return None
    system, d = st.system, states.directions
    axes = node_tangents(st.mean.nodes)  # (n_k, n_nodes, 3)
    n, e = system.node_normals, system.node_frames[:, :, 0]
    held = case.wind.type == "synoptic"
    rows = slice(0, 1) if held else slice(None)
    vl = np.zeros_like(vn) if vl is None else vl
    v = vn[rows, :, None] * n + vl[rows, :, None] * e
    if held:
        one = node_wind(system, v, axes[0], d)

        def over(a: np.ndarray) -> np.ndarray:
            return np.broadcast_to(a, (t.size,) + a.shape[1:])

        return NodeWind(over(one.along), over(one.rest), over(one.perp), over(one.perp_vectors), d)
    return node_wind(system, v, axes[state_of_step(st.mean.time, t)[0]], d)


def record_wind(case: Case, st: StaticResult, t: np.ndarray) -> tuple[np.ndarray, np.ndarray | None, np.ndarray]:
    """:func:`record_mean_wind` (vn, vl) and the turbulence's modulation a = I V_m(x, t) [m/s]
    (:func:`~linecheck.core.wind.turbulence.modulation`, (n_steps, n_nodes) or (1, 1)) over the
    record ``t``.  The equal-span downburst evaluates its field once, at the distinct stations of
    the span nodes and the global nodes together (the two sets differ in the last bit at some
    nodes), instead of once for each (≈ 0.07 s of a six-span run); the field is evaluated point
    by point, so the values are the same bits (tested)."""
    from ..core.wind.mean import equal_span_downburst_both
    from ..core.wind.turbulence import modulation

    system = st.system
    if case.wind.type != "downburst" or system.is_section:
        vn, vl = record_mean_wind(case, st, t)
        return vn, vl, modulation(case, system, t)
    vx_s, vy_s, vx_n, vy_n = equal_span_downburst_both(case, system, t)
    # as record_mean_wind (via mean_wind) and modulation (via mean_speed_at_nodes)
    return (to_global_nodes(system, vy_s), to_global_nodes(system, vx_s),
            case.wind.turbulence_intensity * np.hypot(vx_n, vy_n))


def mean_reactions(system: LineSystem, mean: MeanStates, t: np.ndarray) -> np.ndarray:
    """[N] the wind-induced mean reaction M(t): the step-1 reactions in each tower's own frame,
    interpolated linearly in time to the record ``t``, shape (n_steps, n_towers, 3)."""
    rw = system.to_tower_frames(mean.reactions_wind)  # (n_k, n_towers, 3)
    if mean.time.size == 1:
        return np.broadcast_to(rw[0], (t.size,) + rw.shape[1:]).copy()
    flat = rw.reshape(rw.shape[0], -1)
    return np.stack([np.interp(t, mean.time, flat[:, i]) for i in range(flat.shape[1])], axis=1).reshape(
        (t.size,) + rw.shape[1:])


def state_of_step(mean_times: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest mean state at each step of ``t`` [s], and the bracketing state k and the weight [-]
    toward k+1, each shape (n_steps,); ``mean_times`` [s] the instants of the mean states."""
    if mean_times.size == 1:
        zero = np.zeros(t.size, dtype=int)
        return zero, zero, np.zeros(t.size)
    k = np.clip(np.searchsorted(mean_times, t, side="right") - 1, 0, mean_times.size - 2)
    w = np.clip((t - mean_times[k]) / (mean_times[k + 1] - mean_times[k]), 0.0, 1.0)
    nearest = np.where(w > 0.5, k + 1, k)
    return nearest, k, w


def interpolated_models(case: Case, st: StaticResult, bracket: np.ndarray,
                        weights: np.ndarray) -> Callable[[int], tuple[LinearModel, np.ndarray]]:
    """model_at(n) -> (model, damping [N s/m]) for the reference scheme: the step-1 state
    interpolated linearly in time at step n (``bracket`` and ``weights`` of :func:`state_of_step`)
    and its model and damping rebuilt (structural damping calibrated once, at the reference state)."""
    from ..core.static import StaticState

    mean, system = st.mean, st.system
    vn_all = to_global_nodes(system, st.wind.normal)
    cross = st.cross_wind
    n_k = mean.time.size
    zs = case.analysis.structural_ratio
    w1 = 1.0
    if zs > 0:  # calibrated once, at the reference state (as in damping_matrices)
        w1 = structural_omega1(build_model(system, mean.state(reference_state_index(case, mean))))

    def model_at(n: int):
        k0 = int(bracket[n])
        k1 = min(k0 + 1, n_k - 1)
        w = float(weights[n])

        def lerp(a):
            return (1 - w) * a[k0] + w * a[k1]

        state = StaticState(lerp(mean.displacement), lerp(mean.reactions), lerp(mean.tension),
                            lerp(mean.insulator_force), lerp(mean.nodes), lerp(mean.element_tension), 0, 0.0)
        model = build_model(system, state)
        vn = (1 - w) * vn_all[k0] + w * vn_all[k1]
        u = None if cross is None else (lerp(cross.perp_vectors), cross.directions)
        c = aerodynamic_damping(case, model, vn, state.nodes, u)
        if zs > 0:
            c = c + stiffness_proportional(model, zs, w1)
        return model, c

    return model_at
