"""The wind of a run exported (``linecheck wind``): the running mean and turbulence of one
realization at every conductor node over the record a run analyses (the public NPZ layout of
docs/wind.md), the loads recomputed from such a file, and the wind at point p (paper Fig. 3).
Nothing here prints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..core.case import Case
from ..core.crossflow import node_wind
from ..core.damping import node_tangents
from ..core.loads import fluctuating_loads
from ..core.model import build_model
from ..core.system import LineSystem
from .burnin import synoptic_burn_in
from .guard import Warn, check_budget
from .record import record_mean_wind, record_time, with_burn_in
from .step1 import StaticResult, static_analysis
from .uplift import require_tension


@dataclass(frozen=True)
class WindField:
    """The wind of one realization of a run at every conductor node (``linecheck wind --field``;
    public NPZ layout in docs/wind.md).

    Attributes:
        t: [s] the analysed record's equally spaced instants, burn-in included, shape (n_t,).
        burn_in: [s] the discarded start of ``t`` (0 for downbursts and ``damping = "paper"``).
        x_node: [m] still-air node positions (x along the line, z up), shape (n_nodes, 3);
            nodes in line order, tower nodes once (n_spans * elements_per_span + 1).  Section form:
            ``LineSystem.node_xyz0`` (x along the first span, y to its left, z up, global frame).
        u_mean: [m/s] running-mean wind velocity (x, y, z) at each node, (n_t, n_nodes, 3)
            (section form: the full vector in the global frame, synoptic V(z)(sin d, cos d, 0)).
        u_turb: [m/s] turbulent wind velocity (x, y, z): the along-wind fluctuation v along the
            running mean's direction, (n_t, n_nodes, 3).
        v_along: [m/s] the along-wind fluctuation v itself (signed), (n_t, n_nodes).
        realization: 1-based; seed: the case's seed.
    """

    case: Case
    t: np.ndarray
    burn_in: float
    x_node: np.ndarray
    u_mean: np.ndarray
    u_turb: np.ndarray
    v_along: np.ndarray
    realization: int
    seed: int

    def to_npz_dict(self) -> dict[str, np.ndarray]:
        """Arrays of the public NPZ layout (docs/wind.md)."""
        return {
            "t": self.t, "burn_in": np.float64(self.burn_in), "x_node": self.x_node,
            "u_mean": self.u_mean, "u_turb": self.u_turb, "v_along": self.v_along,
            "realization": np.int64(self.realization), "seed": np.int64(self.seed),
            "case": np.str_(self.case.name), "units": np.str_(
                "SI: s, m, m/s; global frame: x along the first span, y to its left, z up" if self.case.line.is_section
                else "SI: s, m, m/s; x along the line, y transverse, z up"),
        }


def record_grid(case: Case, st: StaticResult | None = None) -> tuple[np.ndarray, float]:
    """Instants of steps 2-3 [s] with the burn-in exactly as
    :func:`~linecheck.analysis.run.run_case` builds them, and the burn-in [s]."""
    st = static_analysis(case) if st is None else st
    t = record_time(case)
    burn = 0.0
    if case.wind.type == "synoptic":
        burn = synoptic_burn_in(case, st).seconds
    if burn > 0:
        t = with_burn_in(case, t, burn)
    return t, float(burn)


def wind_field(case: Case, *, realization: int = 0) -> WindField:
    """The running mean and turbulence of ``realization`` (0-based) at every conductor node and
    step of the record :func:`~linecheck.analysis.run.run_case` analyses (burn-in included): the
    same calls, so the same field bit for bit.  u_turb = v (V_x, V_y, 0)/|V| (Eq. 5's normal
    component is its y component); no vertical wind (z components zero)."""
    from ..core.errors import CaseError
    from ..core.wind.turbulence import fluctuating_velocity

    if not 0 <= realization < case.analysis.realizations:
        raise CaseError(f"realization {realization + 1} is out of range: expected 1 to {case.analysis.realizations} "
                        "(analysis.realizations)")
    st = static_analysis(case)
    t, burn = record_grid(case, st)
    lead = t.size - record_time(case).size  # the burn-in's steps, as run_case keeps them
    if _wind_vectors(case, st.system):
        v = fluctuating_velocity(case, st.system, t, [realization], lead=lead)[0]
        u_mean, u_turb, x_node = _vector_field(case, st.system, t, v)
    else:
        vn, vl = record_mean_wind(case, st, t)
        v = fluctuating_velocity(case, st.system, t, [realization], lead=lead)[0]
        u_mean, u_turb = _normal_field(vn, vl, v)
        x_node = st.mean.still_air.nodes.copy()
    return WindField(case, t, burn, x_node, u_mean, u_turb, v, realization + 1, case.analysis.seed)


def _vector_field(case: Case, system: LineSystem, t: np.ndarray, v: np.ndarray):
    """u_mean, u_turb [m/s] (n_t, n_nodes, 3) as full vectors in the global frame at the still-air
    node positions (section form), and those positions [m] (n_nodes, 3); ``v`` [m/s] the
    along-wind fluctuation (n_t, n_nodes)."""
    from ..core.wind.mean import mean_vector_at_nodes

    u_mean = np.broadcast_to(mean_vector_at_nodes(case, system, t[:1] if case.wind.type == "synoptic" else t),
                             (t.size, system.n_nodes, 3)).copy()
    speed = np.hypot(u_mean[..., 0], u_mean[..., 1])
    normal = system.node_normals[None, :, :]  # direction of the fluctuation where |V| = 0
    with np.errstate(invalid="ignore", divide="ignore"):
        unit = np.where(speed[..., None] > 0, u_mean / np.where(speed > 0, speed, 1.0)[..., None], normal)
    return u_mean, v[..., None] * unit, system.node_xyz0.copy()


def _normal_field(vn: np.ndarray, vl: np.ndarray | None, v: np.ndarray):
    """u_mean, u_turb [m/s] (n_t, n_nodes, 3) of the equal-span form: (longitudinal, normal, 0)
    from the mean speeds ``vn``, ``vl`` and the along-wind fluctuation ``v`` [m/s] (n_t, n_nodes)."""
    vl = np.zeros_like(vn) if vl is None else vl
    zero = np.zeros_like(vn)
    u_mean = np.stack([vl, vn, zero], axis=-1)
    speed = np.hypot(vn, vl)
    with np.errstate(invalid="ignore", divide="ignore"):
        unit_n = np.where(speed > 0, vn / np.where(speed > 0, speed, 1.0), 1.0)
        unit_l = np.where(speed > 0, vl / np.where(speed > 0, speed, 1.0), 0.0)
    return u_mean, np.stack([v * unit_l, v * unit_n, zero], axis=-1)


def _wind_vectors(case: Case, system: LineSystem) -> bool:
    """True when the wind field is built from full mean-wind vectors (a section, or a synoptic
    wind with a direction or profile); False keeps the equal-span form's original arrays."""
    w = case.wind
    return system.is_section or (w.type == "synoptic" and (w.direction != 0.0 or w.profile_exponent != 0.0
                                                           or w.reference_height is not None))


def read_wind_field(path) -> dict[str, np.ndarray]:
    """The arrays of a ``linecheck wind --field`` NPZ file (docs/wind.md)."""
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def loads_from_field(case: Case, field: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """Fluctuating loads of steps 2-3 (:func:`~linecheck.core.loads.fluctuating_loads`, paper
    Eq. 5) from a wind field's arrays (``WindField.to_npz_dict`` or :func:`read_wind_field`):
    loads [N] (n_t, 1, n_free) and the direct reactions [N] (n_t, 1, 3 n_towers)."""
    st = static_analysis(case)
    require_tension(st)
    model = build_model(st.system, st.mean.state(0))
    u = field["u_mean"]
    if _wind_vectors(case, st.system):
        # full vectors: normal component along each node's horizontal normal (span normal; tower
        # nodes: the tower frame's y) and the along-line rest, for cos(phi) = |V_n|/|V|
        n, e = st.system.node_normals, st.system.node_frames[:, :, 0]
        vn = u[..., 0] * n[None, :, 0] + u[..., 1] * n[None, :, 1]
        vl = u[..., 0] * e[None, :, 0] + u[..., 1] * e[None, :, 1]
        states = st.cross_wind  # inclined spans, cross-flow: along the run's directions
        cross = None if states is None else node_wind(st.system, u, node_tangents(st.mean.nodes[0]), states.directions)
        return fluctuating_loads(case, st.system, model, field["t"], field["v_along"][None], vn, vl, cross)
    vl = None if case.wind.type == "synoptic" else u[:, :, 0]
    return fluctuating_loads(case, st.system, model, field["t"], field["v_along"][None], u[:, :, 1], vl)


@dataclass(frozen=True)
class WindAtP:
    """Wind at the FE node nearest point p (paper Fig. 3).

    Attributes:
        time: [s] shape (n_steps,); mean: [m/s] running-mean speed (magnitude);
        total: [m/s] mean + turbulence of ``realization``; x: [m] abscissa of the node used.
    """

    case: Case
    time: np.ndarray
    mean: np.ndarray
    total: np.ndarray
    x: float
    realization: int


def wind_at_p(case: Case, *, realization: int = 0, warn: Warn | None = None) -> WindAtP:
    """Running-mean and total wind speed at point p over the record (paper Fig. 3)."""
    from ..core.wind.point import point_series

    check_budget(case, "wind", warn=warn)
    p = point_series(case, realization)
    return WindAtP(case, p.time, p.mean_speed, p.total, p.node_x, realization)
