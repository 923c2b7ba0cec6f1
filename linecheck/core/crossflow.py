"""Cross-flow drag on a line section (docs/method.md "Loads").

The drag on a yawed circular cylinder acts along the component of the wind normal to the
cylinder's axis and scales with its square (the cross-flow, or independence, principle:
Hoerner 1965, "Fluid-Dynamic Drag", ch. 3).  For a conductor the axis is its own tangent t on
the deformed cable: V_perp = V - (V . t) t and the drag per unit length is
1/2 rho C_d D |V_perp| V_perp.  On an inclined span in oblique wind V_perp has a part in the
span's vertical plane of size about V_x sin(theta) (V_x the along-span wind, theta the
inclination), i.e. a vertical drag; on a blown-out span the tangent near the clamps leans with
the wind and the drag there is smaller than on the horizontal normal.  Step 1 solves this
follower load on the deformed cable (:func:`linecheck.core.static.solve_mean_states`); the
horizontal-normal form, ``[analysis] drag_direction = "horizontal-normal"``, keeps V_n n_i
(n_i the span's horizontal normal) as before, and the equal-span (paper) form always uses it.

Steps 2-3 load every node along ONE direction d_j (the paper's scalar load machinery):
d_j = V_perp / |V_perp| on the mean state's deformed axes.  A synoptic mean wind is constant,
so this is exact; in a downburst d_j is taken at the node's largest |V_perp| among the step-1
mean states and the load's component along d_j is kept (docs/method.md "Loads" says what this
leaves out).  Nothing here prints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .case import Case
from .system import LineSystem


def applies(case: Case, system: LineSystem) -> bool:
    """True when the cross-flow drag is used: ``drag_direction`` "cross-flow" on a section (the
    equal-span form is the paper's horizontal-normal idealisation)."""
    return case.analysis.drag_direction == "cross-flow" and system.is_section


def normal_part(v: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """[m/s] the part of the wind vectors v (..., 3) normal to the unit axes (broadcastable,
    (..., 3)): v - (v . a) a (cross-flow principle, Hoerner 1965)."""
    return v - (v * axes).sum(axis=-1)[..., None] * axes


def span_wind_vectors(system: LineSystem, normal: np.ndarray, longitudinal: np.ndarray) -> np.ndarray:
    """[m/s] the horizontal mean wind at every span node as vectors, (..., n_spans, ne+1, 3), from
    its components along the span's horizontal normal and direction (:class:`MeanWind` ``normal``,
    ``longitudinal``, each (..., n_spans, ne+1))."""
    h = system.span_headings
    e = np.stack([np.cos(h), np.sin(h), np.zeros_like(h)], axis=1)
    return normal[..., None] * system.span_normals[:, None, :] + longitudinal[..., None] * e[:, None, :]


@dataclass(frozen=True)
class NodeWind:
    """The running-mean wind at the global nodes as steps 2-3 load them, cross-flow form.

    Attributes:
        along: [m/s] V_perp . d_j, the signed component along each node's load direction,
            (n_t, n_nodes); the fluctuating loads' "normal speed".
        rest: [m/s] sqrt(|V|^2 - along^2), so that hypot(along, rest) = |V| (the full mean speed
            the turbulence intensity refers to), (n_t, n_nodes).
        perp: [m/s] |V_perp|, (n_t, n_nodes).
        perp_vectors: [m/s] V_perp, (n_t, n_nodes, 3) (the damping's relative wind).
        directions: [-] d_j, (n_nodes, 3).
    """

    along: np.ndarray
    rest: np.ndarray
    perp: np.ndarray
    perp_vectors: np.ndarray
    directions: np.ndarray


def load_directions(system: LineSystem, u: np.ndarray) -> np.ndarray:
    """[-] d_j = V_perp/|V_perp| at each node's largest |V_perp| over the instants of u
    (n_t, n_nodes, 3); the node normal where the wind is zero throughout, (n_nodes, 3)."""
    size = np.linalg.norm(u, axis=-1)
    k = np.argmax(size, axis=0)
    j = np.arange(system.n_nodes)
    top, s = u[k, j], size[k, j]
    d = system.node_normals.copy()
    ok = s > 0
    d[ok] = top[ok] / s[ok, None]
    return d


def node_wind(system: LineSystem, v: np.ndarray, axes: np.ndarray, directions: np.ndarray | None = None) -> NodeWind:
    """:class:`NodeWind` from the running-mean wind vectors v [m/s] at the global nodes,
    (n_t, n_nodes, 3) (:func:`~linecheck.core.wind.mean.mean_vector_at_nodes`), on the conductor's
    unit axes there (the mean states' deformed tangents, broadcastable to v); ``directions``
    (n_nodes, 3) fixes d_j (default :func:`load_directions` over these instants)."""
    u = normal_part(v, axes)
    d = load_directions(system, u) if directions is None else directions
    along = (u * d).sum(axis=-1)
    speed2 = (v * v).sum(axis=-1)
    return NodeWind(along, np.sqrt(np.maximum(speed2 - along * along, 0.0)), np.linalg.norm(u, axis=-1), u, d)
