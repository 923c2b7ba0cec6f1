"""Running-mean wind along the line (paper section 2.1).

Contract used by the solver steps:

``mean_wind(case, system, times)`` returns a :class:`MeanWind` with the
running-mean velocity components at the still-air FE node positions of every span
(normal to the line, +y, and along it, +x) at the requested instants.
``event_window(case)`` gives the analysed time window [s].

Synoptic wind: V_ref (or ``span_speeds``) uniform along each span, constant in time; with a
direction d and a power-law profile on sections and when set.

Downburst wind: the field model is :mod:`linecheck.core.wind.downburst` (Holmes & Oliver 2000,
Wood et al. 2001, Chay et al. 2006; ring-jet models; user tables read by
:mod:`linecheck.core.wind.field_table`), placed and scaled to V_ref at point p by
:mod:`linecheck.core.wind.downburst_case`; this module evaluates it at the nodes.  The names
callers import from here (``downburst_field``, ``event_window``, the profiles and defaults, the
field-table reader) are re-exported.  See ``docs/wind.md``.  Nothing here prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..case import Case
from ..system import LineSystem
from .downburst import R_MAX_OVER_DJ as R_MAX_OVER_DJ
from .downburst import RADIAL_DECAY_OVER_DJ as RADIAL_DECAY_OVER_DJ
from .downburst import T1_DEFAULT as T1_DEFAULT
from .downburst import T_F_DEFAULT as T_F_DEFAULT
from .downburst import Z_MAX_OVER_DJ as Z_MAX_OVER_DJ
from .downburst import DownburstField
from .downburst import intensity as intensity
from .downburst import radial_profile as radial_profile
from .downburst import vertical_profile as vertical_profile
from .downburst import wood_delta as wood_delta
from .downburst_case import SYNOPTIC_DURATION_DEFAULT as SYNOPTIC_DURATION_DEFAULT
from .downburst_case import downburst_field, event_window, reference_height
from .downburst_case import ring_scale as ring_scale
from .field_table import FieldTable as FieldTable
from .field_table import load_field_table as load_field_table
from .profiles import ETA_PEAK as ETA_PEAK


# ------------------------------------------------------------------------- MeanWind
@dataclass(frozen=True)
class MeanWind:
    """Running-mean wind at the FE nodes.

    Attributes:
        time: [s] instants, shape (n_t,).
        normal: [m/s] component normal to the line (toward +y) at each span's FE nodes,
            shape (n_t, n_spans, ne+1) (span-local nodes, so a speed may jump at a tower).
        longitudinal: [m/s] component along the line (toward +x), same shape.
        point_p: [m] x-coordinate of point p (line point nearest the downburst centre;
            synoptic: the tower of interest).  Section form: p's coordinate along the tower of
            interest's frame x axis, counted from the first tower like a station.
        point_xy: [m] plan position (x, y) of p in the global frame (section form; equal-span
            form: (point_p, 0)).

    Section form: ``normal`` is the component along each span's horizontal normal
    n_i = (-sin h_i, cos h_i, 0) and ``longitudinal`` along its horizontal direction
    (cos h_i, sin h_i, 0), at the nodes' still-air plan positions and heights above ground.
    """

    time: np.ndarray
    normal: np.ndarray
    longitudinal: np.ndarray
    point_p: float
    point_xy: tuple[float, float] | None = None


def synoptic_span_speeds(case: Case) -> np.ndarray:
    """Mean speed of every span [m/s], shape (n_spans,): ``span_speeds`` or V_ref."""
    if case.wind.span_speeds is None:
        return np.full(case.line.spans, case.wind.v_ref)
    return np.asarray(case.wind.span_speeds, dtype=float)


# ------------------------------------------------------------------------- synoptic direction and profile
def profile_factor(case: Case, z_agl: np.ndarray) -> np.ndarray:
    """V(z)/v_ref [-] = (z_agl / z_ref)^alpha at heights above ground z_agl [m] (any shape).

    Power law (Hellmann 1916; Davenport 1960);
    alpha = ``profile_exponent`` (0: exactly 1 everywhere).  A point at or below the ground
    (possible only for a sagging conductor) gets 0."""
    z_agl = np.asarray(z_agl, dtype=float)
    alpha = float(case.wind.profile_exponent)
    if alpha == 0.0:
        return np.ones_like(z_agl)
    # power law (Hellmann 1916; Davenport 1960): V(z) = V_ref (z / z_ref)^alpha
    return (np.maximum(z_agl, 0.0) / reference_height(case)) ** alpha


def wind_direction_vector(case: Case) -> np.ndarray:
    """Unit mean-wind direction m = (sin d, cos d, 0) [-], shape (3,) (d = ``wind.direction``;
    d = 0 blows toward +y, normal to the first span)."""
    d = math.radians(case.wind.direction)
    return np.array([math.sin(d), math.cos(d), 0.0])


def _span_node_index(system: LineSystem) -> np.ndarray:
    """Global node index of every span-local node, shape (n_spans, ne+1)."""
    return np.arange(system.n_spans)[:, None] * system.ne + np.arange(system.ne + 1)[None, :]


def _span_along(system: LineSystem) -> np.ndarray:
    """Horizontal unit direction (cos h_i, sin h_i, 0) of every span, shape (n_spans, 3)."""
    h = system.span_headings
    return np.stack([np.cos(h), np.sin(h), np.zeros_like(h)], axis=1)


def _node_along(system: LineSystem) -> np.ndarray:
    """Horizontal unit along-line direction of every global node, shape (n_nodes, 3): the node
    normal turned -90 deg in plan (span nodes: the span's direction; tower nodes: the tower frame x)."""
    n = system.node_normals
    return np.stack([n[:, 1], -n[:, 0], np.zeros(n.shape[0])], axis=1)


def _synoptic_plain(case: Case, system: LineSystem) -> bool:
    """True for the paper's synoptic wind: equal-span form, d = 0, no profile (the original,
    bit-identical code path)."""
    return (not system.is_section and case.wind.direction == 0.0 and case.wind.profile_exponent == 0.0
            and case.wind.reference_height is None)


# ------------------------------------------------------------------------- public evaluators
def span_node_x(system: LineSystem) -> np.ndarray:
    """Still-air x [m] of each span's FE nodes, shape (n_spans, ne+1)."""
    return system.span_node_x0


def mean_velocity_at(case: Case, x: np.ndarray, time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Running-mean (longitudinal v_x, normal v_y) [m/s] at line points x [m], times [s].

    x shape (n_x,), time shape (n_t,) -> two arrays (n_t, n_x).  Synoptic: (0, V_ref)
    everywhere (``span_speeds`` apply only through :func:`mean_wind` and the node helpers).
    Equal-span form (points on the straight line y = 0 at the conductor height); sections use
    :func:`mean_vector_at_nodes`.
    """
    x = np.atleast_1d(np.asarray(x, dtype=float))
    time = np.atleast_1d(np.asarray(time, dtype=float))
    if case.wind.type == "synoptic":
        shape = (time.size, x.size)
        return np.zeros(shape), np.full(shape, case.wind.v_ref)
    return _equal_span_downburst(case, downburst_field(case), x, time)


def point_p(case: Case) -> float:
    """x [m] of point p: the line point nearest the downburst centre (synoptic: tower of interest).

    Section form: p's coordinate along the tower of interest's frame x axis, counted like a
    station (the tower's station + R sin(Theta)); its plan position is :func:`point_p_xy`."""
    if case.wind.type == "synoptic":
        return float(LineSystem(case.line).tower_x[case.line.tower_of_interest - 1])
    return downburst_field(case).point_p


def point_p_xy(case: Case) -> tuple[float, float]:
    """Plan position (x, y) [m] of point p in the global frame (synoptic: the tower of interest's
    still-air clamp; downburst on a section: the foot of the perpendicular from the centre on the
    tower of interest's frame x axis; equal-span form: (point_p, 0))."""
    if case.wind.type == "synoptic":
        c = LineSystem(case.line).clamp_points[case.line.tower_of_interest - 1]
        return float(c[0]), float(c[1])
    return downburst_field(case).p_xy()


def nearest_node_to_p(case: Case, system: LineSystem) -> int:
    """Global FE node nearest point p (0-based): in plan (still-air ``node_xyz0``) on a section,
    along x (``node_x0``) on the equal-span form."""
    if not system.is_section:
        return int(np.argmin(np.abs(system.node_x0 - point_p(case))))
    px, py = point_p_xy(case)
    xy = system.node_xyz0[:, :2]
    return int(np.argmin(np.hypot(xy[:, 0] - px, xy[:, 1] - py)))


def _downburst_nodes(case: Case, system: LineSystem, field: DownburstField,
                     time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Downburst (v_x, v_y) [m/s] in the global plan frame at every global node's still-air plan
    position and height above ground (section form), shape (n_t, n_nodes) each."""
    xyz = system.node_xyz0
    return field.velocity_at(xyz[:, 0], xyz[:, 1], time, system.node_height)


def _synoptic_speed_nodes(case: Case, system: LineSystem) -> np.ndarray:
    """Synoptic mean speed |V| [m/s] at the global nodes: the span speed (tower nodes: the mean
    of their two spans) times the power-law profile at the node's height, shape (n_nodes,)."""
    return _synoptic_node_speeds(case, system) * profile_factor(case, system.node_height)


def mean_vector_at_nodes(case: Case, system: LineSystem, time: np.ndarray) -> np.ndarray:
    """Running-mean wind velocity vector [m/s] at the global FE nodes in the global frame
    (x along the first span, y to its left, z up; z component 0), shape (n_t, n_nodes, 3).

    Synoptic: V(z_node) (sin d, cos d, 0), V(z) = v (z/z_ref)^alpha with v the node's
    span speed (``span_speeds``, else V_ref; tower nodes the mean of their two spans).
    Downburst: the horizontal outflow at the node's still-air plan position and height
    (equal-span form: on y = 0 at the conductor height, as :func:`mean_velocity_at`).
    """
    time = np.atleast_1d(np.asarray(time, dtype=float))
    out = np.zeros((time.size, system.n_nodes, 3))
    if case.wind.type == "synoptic":
        v = _synoptic_speed_nodes(case, system)
        m = wind_direction_vector(case)
        out[:, :, 0] = (v * m[0])[None, :]
        out[:, :, 1] = (v * m[1])[None, :]
        return out
    field = downburst_field(case)
    if system.is_section:
        vx, vy = _downburst_nodes(case, system, field, time)
    else:
        vx, vy = _equal_span_downburst(case, field, system.node_x0, time)
    out[:, :, 0], out[:, :, 1] = vx, vy
    return out


def _equal_span_downburst(case: Case, field: DownburstField, x: np.ndarray,
                          time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Equal-span form: the field on y = 0 at the conductor height (the original path; with an
    explicit ``reference_height`` the scaling height differs from the conductor height)."""
    if reference_height(case) == float(case.line.height):
        return field.velocity(x, time)
    return field.velocity_at(x, np.zeros_like(x), time, np.full(x.size, float(case.line.height)))


def equal_span_downburst_both(case: Case, system: LineSystem,
                              time: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """An equal-span downburst's running-mean (v_x, v_y) [m/s] at the span nodes, each
    (n_t, n_spans, ne+1) (as :func:`mean_wind`), and at the global nodes, each (n_t, n_nodes) (as
    :func:`mean_speed_at_nodes`), from one evaluation of the field at the distinct stations of
    both sets (they differ in the last bit at some nodes of a single span).  The field is
    evaluated point by point, so the values are the same bits as evaluating each set."""
    time = np.atleast_1d(np.asarray(time, dtype=float))
    xs = span_node_x(system).ravel()
    xu, inv = np.unique(np.concatenate([xs, system.node_x0]), return_inverse=True)
    vx, vy = _equal_span_downburst(case, downburst_field(case), xu, time)
    span, node = inv[:xs.size], inv[xs.size:]
    shape = (time.size, system.n_spans, system.ne + 1)
    # np.take along the columns copies the same values as vx[:, span], 3-5x faster (≈ 35 ms of a
    # six-span downburst realization's four (12,001 x 64) gathers)
    return (np.take(vx, span, axis=1).reshape(shape), np.take(vy, span, axis=1).reshape(shape),
            np.take(vx, node, axis=1), np.take(vy, node, axis=1))


def mean_wind(case: Case, system: LineSystem, times: np.ndarray | None = None) -> MeanWind:
    """Running-mean wind at the FE nodes at ``times`` [s].

    Synoptic: constant (``times`` default one instant t = 0).  Downburst: ``times``
    default ``analysis.mean_states`` instants over :func:`event_window`.
    Components per span node: ``normal`` along the span's horizontal normal n_i, ``longitudinal``
    along its horizontal direction (equal-span form: +y and +x).
    """
    if case.wind.type == "synoptic":
        t = np.zeros(1) if times is None else np.asarray(times, dtype=float)
        p = float(system.tower_x[case.line.tower_of_interest - 1])
        if _synoptic_plain(case, system):
            v = synoptic_span_speeds(case)
            normal = np.broadcast_to(v[:, None], (t.size, system.n_spans, system.ne + 1)).copy()
            return MeanWind(t, normal, np.zeros_like(normal), p)
        # section form: V(z) = v_span (z_agl/z_ref)^alpha at each span node's still-air height, direction
        # m = (sin d, cos d, 0); normal V m.n_i = V cos(d + h_i), longitudinal V m.e_i = V sin(d + h_i)
        idx = _span_node_index(system)
        speed = synoptic_span_speeds(case)[:, None] * profile_factor(case, system.node_height[idx])
        m = wind_direction_vector(case)
        cn = system.span_normals @ m  # (n_spans,)
        cl = _span_along(system) @ m
        shape = (t.size, system.n_spans, system.ne + 1)
        normal = np.broadcast_to(speed * cn[:, None], shape).copy()
        longitudinal = np.broadcast_to(speed * cl[:, None], shape).copy()
        c = system.clamp_points[case.line.tower_of_interest - 1]
        return MeanWind(t, normal, longitudinal, p, (float(c[0]), float(c[1])) if system.is_section else None)
    if times is None:
        t0, t1 = event_window(case)
        t = np.linspace(t0, t1, case.analysis.mean_states)
    else:
        t = np.atleast_1d(np.asarray(times, dtype=float))
    field = downburst_field(case)
    shape = (t.size, system.n_spans, system.ne + 1)
    if not system.is_section:
        xs = span_node_x(system)
        vx, vy = _equal_span_downburst(case, field, xs.ravel(), t)
        return MeanWind(t, vy.reshape(shape), vx.reshape(shape), field.point_p)
    # section form: the field at each span node's plan position and height, resolved on the span's
    # horizontal normal n_i and direction e_i (a tower node gets each adjacent span's components)
    idx = _span_node_index(system).ravel()
    vx, vy = _downburst_nodes(case, system, field, t)
    vx, vy = vx[:, idx], vy[:, idx]
    span = np.repeat(np.arange(system.n_spans), system.ne + 1)
    n, e = system.span_normals[span], _span_along(system)[span]
    normal = vx * n[None, :, 0] + vy * n[None, :, 1]
    longitudinal = vx * e[None, :, 0] + vy * e[None, :, 1]
    return MeanWind(t, normal.reshape(shape), longitudinal.reshape(shape), field.point_p, field.p_xy())


def _synoptic_node_speeds(case: Case, system: LineSystem) -> np.ndarray:
    """Synoptic speed at the global nodes [m/s], shape (n_nodes,); a shared tower node
    takes the average of its two spans."""
    v = synoptic_span_speeds(case)
    ne = system.ne
    node = np.repeat(v, ne)
    node = np.append(node, v[-1])
    inner = system.tower_nodes[1:-1]
    node[inner] = 0.5 * (v[:-1] + v[1:])
    return node


def mean_components_at_nodes(case: Case, system: LineSystem, time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Running-mean (normal, longitudinal) components [m/s] at the global FE nodes, shape
    (n_steps, n_nodes) each: along ``system.node_normals`` (span nodes: the span's normal n_i;
    tower nodes: the tower frame's y) and along the node's horizontal along-line direction
    (the normal turned -90 deg in plan; tower nodes: the tower frame's x).

    This is the synoptic longitudinal component the fluctuating loads need (cos phi = |V_n|/|V|).
    """
    time = np.atleast_1d(np.asarray(time, dtype=float))
    if not system.is_section and case.wind.type == "downburst":
        vx, vy = _equal_span_downburst(case, downburst_field(case), system.node_x0, time)
        return vy, vx
    if case.wind.type == "synoptic" and _synoptic_plain(case, system):
        return mean_normal_at_nodes(case, system, time), np.zeros((time.size, system.n_nodes))
    u = mean_vector_at_nodes(case, system, time)
    n, e = system.node_normals, _node_along(system)
    return (u[..., 0] * n[None, :, 0] + u[..., 1] * n[None, :, 1],
            u[..., 0] * e[None, :, 0] + u[..., 1] * e[None, :, 1])


def mean_normal_at_nodes(case: Case, system: LineSystem, time: np.ndarray) -> np.ndarray:
    """Running-mean normal speed [m/s] at the global FE nodes, shape (n_steps, n_nodes): toward +y
    on the equal-span form, along ``system.node_normals`` on a section.

    Nodes at their still-air position.  Synoptic with ``span_speeds``: a
    tower node shared by two spans takes their average.
    """
    time = np.atleast_1d(np.asarray(time, dtype=float))
    if case.wind.type == "synoptic" and _synoptic_plain(case, system):
        return np.broadcast_to(_synoptic_node_speeds(case, system), (time.size, system.n_nodes)).copy()
    if case.wind.type == "downburst" and not system.is_section:
        return _equal_span_downburst(case, downburst_field(case), system.node_x0, time)[1]
    return mean_components_at_nodes(case, system, time)[0]


def mean_speed_at_nodes(case: Case, system: LineSystem, time: np.ndarray) -> np.ndarray:
    """Running-mean horizontal speed magnitude [m/s] at the global FE nodes, shape (n_steps, n_nodes)."""
    time = np.atleast_1d(np.asarray(time, dtype=float))
    if case.wind.type == "synoptic":
        if _synoptic_plain(case, system):
            return np.abs(mean_normal_at_nodes(case, system, time))
        return np.broadcast_to(np.abs(_synoptic_speed_nodes(case, system)), (time.size, system.n_nodes)).copy()
    if not system.is_section:
        vx, vy = _equal_span_downburst(case, downburst_field(case), system.node_x0, time)
    else:
        vx, vy = _downburst_nodes(case, system, downburst_field(case), time)
    return np.hypot(vx, vy)
