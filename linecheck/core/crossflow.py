"""Cross-flow drag on inclined spans (docs/method.md "Loads").

The drag on a yawed circular cylinder acts along the component of the wind normal to the
cylinder's axis and scales with its square (the cross-flow, or independence, principle:
Hoerner 1965, "Fluid-Dynamic Drag", ch. 3; used for conductors by e.g. Matheson & Holmes 1981).
A span's axis here is its still-air CHORD c_i (clamp to clamp, so it includes the inclination
theta_i of an inclined span but not the sag): with the horizontal mean wind V = V_n n_i + V_x e_i
(n_i the span's horizontal normal, e_i its horizontal direction),

    V_perp = V - (V . c_i) c_i = V_n n_i - V_x sin(theta_i) m_i,   m_i = -sin(theta_i) e_i + cos(theta_i) z,

so an inclined span in oblique wind gets, besides the horizontal drag, a part in its vertical
plane of size V_x sin(theta_i) (vertical part V_x sin(theta) cos(theta)).  On a level span c_i = e_i
and V_perp = V_n n_i: the horizontal-normal form, which ``[analysis] drag_direction =
"horizontal-normal"`` keeps everywhere.  The sag's slope is left out of the axis: its effect
is antisymmetric within a span and cancels to second order in the tower reactions (measured
against an independent FE with follower cross-flow loads on every deformed element,
docs/validation.md).

Steps 2-3 load every node along ONE direction d_j (the paper's scalar load machinery):
d_j = V_perp / |V_perp| at the node.  A synoptic mean wind is constant, so this is exact; in a
downburst the mean wind turns as the storm passes, and d_j is taken at the node's largest
|V_perp| over the record (its largest mean load); the load's component along d_j is kept
(docs/method.md "Loads" gives the bound on what this leaves out).  Nothing here prints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .case import Case
from .system import LineSystem

INCLINED = 1e-9  # |sin(theta)| below this is a level span (clamp heights equal to ~1 um per km)


def span_axes(system: LineSystem) -> np.ndarray:
    """[-] unit still-air chord c_i of every span, (n_spans, 3) (global frame, z up)."""
    c = system.span_chords
    return c / np.linalg.norm(c, axis=1)[:, None]


def node_axes(system: LineSystem) -> np.ndarray:
    """[-] conductor axis at every global FE node, (n_nodes, 3): its span's chord; a tower node
    the normalised sum of its two spans' chords (one at an end tower)."""
    c = span_axes(system)
    span = system.span_of_node(np.arange(system.n_nodes))
    a = c[span].copy()
    inner = system.tower_nodes[1:-1]
    s = c[:-1] + c[1:]
    a[inner] = s / np.linalg.norm(s, axis=1)[:, None]
    return a


def applies(case: Case, system: LineSystem) -> bool:
    """True when the cross-flow drag differs from the horizontal-normal form: ``drag_direction``
    is "cross-flow", the section has an inclined span, and the wind can have a component along a
    span (a downburst, an angle tower or an oblique synoptic direction)."""
    if case.analysis.drag_direction != "cross-flow" or not system.is_section:
        return False
    if not np.any(np.abs(span_axes(system)[:, 2]) > INCLINED):
        return False
    return not (case.wind.type == "synoptic" and system.straight_in_plan and case.wind.direction == 0.0)


def normal_part(v: np.ndarray, axes: np.ndarray) -> np.ndarray:
    """[m/s] the part of the wind vectors v (..., n, 3) normal to the unit axes (n, 3):
    v - (v . a) a (cross-flow principle, Hoerner 1965)."""
    return v - (v * axes).sum(axis=-1)[..., None] * axes


def span_drag_vectors(case: Case, system: LineSystem, normal: np.ndarray, longitudinal: np.ndarray) -> np.ndarray:
    """[m/s] V_perp at every span node, (..., n_spans, ne+1, 3), from the running-mean
    components along the span's horizontal normal and direction (:class:`MeanWind` ``normal``,
    ``longitudinal``, each (..., n_spans, ne+1))."""
    h = system.span_headings
    e = np.stack([np.cos(h), np.sin(h), np.zeros_like(h)], axis=1)
    v = normal[..., None] * system.span_normals[:, None, :] + longitudinal[..., None] * e[:, None, :]
    c = span_axes(system)[:, None, :]
    return v - (v * c).sum(axis=-1)[..., None] * c


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


def node_wind(system: LineSystem, v: np.ndarray, directions: np.ndarray | None = None) -> NodeWind:
    """:class:`NodeWind` from the running-mean wind vectors v [m/s] at the global nodes,
    (n_t, n_nodes, 3) (:func:`~linecheck.core.wind.mean.mean_vector_at_nodes`); ``directions``
    (n_nodes, 3) fixes d_j (default :func:`load_directions` over these instants)."""
    u = normal_part(v, node_axes(system))
    d = load_directions(system, u) if directions is None else directions
    along = (u * d).sum(axis=-1)
    speed2 = (v * v).sum(axis=-1)
    return NodeWind(along, np.sqrt(np.maximum(speed2 - along * along, 0.0)), np.linalg.norm(u, axis=-1), u, d)
