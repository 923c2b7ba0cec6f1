"""Wind velocity time history at point p (paper Fig. 3): running mean plus turbulence.

Point p is the line point nearest the downburst centre (synoptic: the tower of
interest).  The turbulence at p is the unit field of the FE node nearest p (the
unit field is homogeneous along the line, so its statistics there are those at p),
modulated by a(p, t) = I |V_m(p, t)| (downburst) or I V_ref (synoptic) (Chay et al. 2006).

Section form: p may lie off the line (the foot of the perpendicular from the
downburst centre on the tower of interest's frame x axis), so everything is taken at the FE
node nearest p in plan: its running mean (at its still-air plan position and height above
ground; normal/longitudinal along its node normal and along-line direction) and its unit field.
Nothing here prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..case import Case
from ..errors import CaseError
from ..system import LineSystem
from .mean import downburst_field, event_window, mean_components_at_nodes, mean_velocity_at, nearest_node_to_p, point_p
from .turbulence import length_scale, unit_field


@dataclass(frozen=True, eq=False)
class PointSeries:
    """Velocity history at point p for one turbulence realization.

    Attributes:
        time: [s] instants, shape (n_steps,).
        mean_speed: [m/s] running-mean horizontal speed |V_m(p, t)|, shape (n_steps,).
        mean_normal: [m/s] its component normal to the line (+y), shape (n_steps,).
        mean_longitudinal: [m/s] its component along the line (+x), shape (n_steps,).
        fluctuation: [m/s] a(p, t) u(t), shape (n_steps,).
        total: [m/s] mean_speed + fluctuation, shape (n_steps,).
        unit: [-] the unit turbulence u(t) used, shape (n_steps,).
        point_p: [m] x of p; node: global FE node whose unit field is used; node_x: [m] its x
            (section form: p's coordinate along the tower of interest's frame x axis and the
            node's station).
        realization: 0-based index.
        v_ref: [m/s]; length_scale: [m] L_u; intensity: [-] I; v_max: [m/s] downburst scale (NaN synoptic).
    """

    time: np.ndarray
    mean_speed: np.ndarray
    mean_normal: np.ndarray
    mean_longitudinal: np.ndarray
    fluctuation: np.ndarray
    total: np.ndarray
    unit: np.ndarray
    point_p: float
    node: int
    node_x: float
    realization: int
    v_ref: float
    length_scale: float
    intensity: float
    v_max: float


def record_times(case: Case) -> np.ndarray:
    """Instants [s] of the analysed record: the event window at ``analysis.time_step``, shape (n_steps,)."""
    t0, t1 = event_window(case)
    dt = case.analysis.time_step
    n = int(math.floor((t1 - t0) / dt + 1e-9)) + 1
    if n < 4:
        raise CaseError(f"value {dt!r} is too large for the window {t0:g} to {t1:g} s: expected at least 4 steps",
                        key="analysis.time_step")
    return t0 + dt * np.arange(n)


def point_series(case: Case, realization: int = 0) -> PointSeries:
    """Mean and total velocity at point p over the analysed record (paper Fig. 3).

    realization: 0-based index (must be below ``analysis.realizations``).
    """
    if not 0 <= realization < case.analysis.realizations:
        raise CaseError(f"realization {realization + 1} is out of range: expected 1 to {case.analysis.realizations} "
                        "(analysis.realizations)")
    system = LineSystem(case.line)
    time = record_times(case)
    xp = point_p(case)
    node = nearest_node_to_p(case, system)
    if system.is_section:
        # section: the running mean at the node nearest p (its plan position and height)
        vy, vx = (c[:, node] for c in mean_components_at_nodes(case, system, time))
        node_x = float(system.node_station[node])
    else:
        vx, vy = mean_velocity_at(case, np.array([xp]), time)
        vx, vy = vx[:, 0], vy[:, 0]
        node_x = float(system.node_x0[node])
    speed = np.hypot(vx, vy)
    dt = case.analysis.time_step
    u = unit_field(case, system, time.size, dt, realization)[:, node].copy()
    i = case.wind.turbulence_intensity
    a = i * (speed if case.wind.type == "downburst" else np.full_like(speed, case.wind.v_ref))
    fluct = a * u
    v_max = downburst_field(case).v_max if case.wind.type == "downburst" else math.nan
    return PointSeries(time, speed, vy, vx, fluct, speed + fluct, u, float(xp), node, node_x,
                       realization, case.wind.v_ref, length_scale(case), i, float(v_max))
