"""Geometry of the conductor system and its still-air reference (nominal) state.

``LineSystem`` owns ALL the geometry of a line section: tower stations, clamp
points, per-span horizontal and unstretched lengths, element lengths and the
still-air node coordinates.  The numerical path reads these arrays, never the
case's ``span_length`` key (tests/test_import_boundary.py checks this), so that
unequal spans (issue 17) only change how the arrays are built here.

Axes: x along the line (towers at x_j = (j-1) L_x), y transverse (the wind blows
toward +y), z up.  Conductor attachment points are level (z = 0) in still air;
a suspension insulator hangs from its fixed point at z = +v.  Finite-element
nodes of a span are equally spaced along its horizontal projection; global node
numbering runs along the line and shares the attachment nodes.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from .case import Line


@dataclass(frozen=True)
class LineSystem:
    """Derived, immutable description of one line section.

    Attributes (all SI):
        line: the case's :class:`Line`.
        tower_x: [m] tower stations (still-air clamp x), shape (n_towers,).
        clamp_points: [m] still-air clamp points (x, y, z), shape (n_towers, 3).
        span_lengths: [m] horizontal length of every span, shape (n_spans,).
        unstretched_lengths: [m] unstretched conductor length of every span, shape (n_spans,).
        element_lengths: [m] horizontal FE element length of every span, shape (n_spans,).
        node_x0: [m] still-air x of every global FE node, shape (n_nodes,).
        suspension: bool mask of suspension towers, shape (n_towers,).
        unstretched_length: [m] unstretched conductor length per span L_u (equal spans).
        tension_nominal: [N] T0 = W L_x^2 / (8 S) (paper Table 1).

    Today every array is built from the equal-span keys (``spans``, ``span_length``,
    ``sag``); the operations are those of the scalar formulas, so results are
    bit-identical to the scalar code.
    """

    line: Line

    @property
    def n_spans(self) -> int:
        return self.line.spans

    @property
    def n_towers(self) -> int:
        return self.line.spans + 1

    @property
    def ne(self) -> int:
        """Cable elements per span."""
        return self.line.elements_per_span

    @property
    def n_nodes(self) -> int:
        """Global FE nodes along the line (attachment nodes shared)."""
        return self.n_spans * self.ne + 1

    # ------------------------------------------------------------------ per-span geometry
    @cached_property
    def span_lengths(self) -> np.ndarray:
        """Horizontal length of every span [m], shape (n_spans,) (equal spans: L_x each)."""
        return np.full(self.n_spans, float(self.line.span_length))

    @property
    def equal_spans(self) -> bool:
        """True when all spans have the same horizontal length (closed forms and KMS coherence apply)."""
        return bool(np.all(self.span_lengths == self.span_lengths[0]))

    @property
    def common_span_length(self) -> float:
        """The span length L_x [m] of an equal-span section (closed forms: Davenport, codes).

        Raises ValueError on a section of unequal spans (the caller must use the arrays).
        """
        if not self.equal_spans:
            raise ValueError("the spans of this section are unequal: no common span length")
        return float(self.span_lengths[0])

    @cached_property
    def unstretched_lengths(self) -> np.ndarray:
        """Unstretched conductor length of every span L_u [m], shape (n_spans,)."""
        return np.full(self.n_spans, self.unstretched_length)

    @cached_property
    def element_lengths(self) -> np.ndarray:
        """Horizontal FE element length of every span l/ne [m], shape (n_spans,)."""
        return self.span_lengths / self.ne

    @cached_property
    def element_unstretched_lengths(self) -> np.ndarray:
        """Unstretched length of every cable element L_u/ne [m], shape (n_spans * ne,)."""
        return np.repeat(self.unstretched_lengths / self.ne, self.ne)

    @property
    def uniform_element_length(self) -> float:
        """The common horizontal element length dx [m] (Kac-Murdock-Szego coherence forms).

        Raises ValueError when the FE nodes are not equally spaced along the line.
        """
        dx = self.element_lengths
        if not np.all(dx == dx[0]):
            raise ValueError("FE nodes are not equally spaced along this section")
        return float(dx[0])

    # ------------------------------------------------------------------ per-tower geometry
    @cached_property
    def tower_x(self) -> np.ndarray:
        """Tower stations [m] (still-air clamp x), shape (n_towers,)."""
        return np.arange(self.n_towers, dtype=float) * self.line.span_length

    @cached_property
    def clamp_points(self) -> np.ndarray:
        """Still-air conductor clamp points (x, y, z) [m], shape (n_towers, 3); level (z = 0), y = 0."""
        p = np.zeros((self.n_towers, 3))
        p[:, 0] = self.tower_x
        return p

    @cached_property
    def weight_spans(self) -> np.ndarray:
        """Half the sum of the two adjacent spans [m] at interior towers, the single span at
        the end towers, shape (n_towers,): the start value W * weight_span of the insulator
        force in the static iteration (equal spans: L_x everywhere)."""
        L = self.span_lengths
        out = np.empty(self.n_towers)
        out[1:-1] = 0.5 * (L[:-1] + L[1:])
        out[0], out[-1] = L[0], L[-1]
        return out

    @cached_property
    def suspension(self) -> np.ndarray:
        return np.array([s == "suspension" for s in self.line.supports], dtype=bool)

    @cached_property
    def tower_nodes(self) -> np.ndarray:
        """Global FE node index of each tower's attachment point, shape (n_towers,)."""
        return np.arange(self.n_towers) * self.ne

    @cached_property
    def node_s(self) -> np.ndarray:
        """Normalised position s = x/l of the FE nodes within a span, shape (ne+1,)."""
        return np.linspace(0.0, 1.0, self.ne + 1)

    @cached_property
    def node_x0(self) -> np.ndarray:
        """Still-air x of every global FE node [m], shape (n_nodes,)."""
        return np.arange(self.n_nodes) * (self.line.span_length / self.ne)

    @cached_property
    def span_node_x0(self) -> np.ndarray:
        """Still-air x of each span's FE nodes [m], shape (n_spans, ne+1)."""
        return self.tower_x[:-1, None] + self.node_s[None, :] * self.span_lengths[:, None]

    @property
    def tension_nominal(self) -> float:
        """T0 = W L_x^2 / (8 S) [N] (paper Table 1, parabolic cable)."""
        L, S = self.line.span_length, self.line.sag
        return self.line.weight * L**2 / (8.0 * S)

    @property
    def stretched_length(self) -> float:
        """Still-air stretched length L_x (1 + 8/3 (S/L_x)^2) [m] (parabola, Irvine 1981 Eq. 2.14)."""
        L, S = self.line.span_length, self.line.sag
        return L * (1.0 + 8.0 / 3.0 * (S / L) ** 2)

    @property
    def unstretched_length(self) -> float:
        """Unstretched span length L_u = stretched / (1 + T0/EA) [m] (issue 2 definition)."""
        return self.stretched_length / (1.0 + self.tension_nominal / self.line.ea)

    def span_of_node(self, node: np.ndarray | int) -> np.ndarray:
        """Span index (0-based) of a global node (attachment nodes belong to the span on their right)."""
        return np.minimum(np.asarray(node) // self.ne, self.n_spans - 1)
