"""Geometry of the conductor system and its still-air reference (nominal) state.

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
        tower_x: [m] tower abscissae, shape (n_towers,).
        suspension: bool mask of suspension towers, shape (n_towers,).
        unstretched_length: [m] unstretched conductor length per span L_u.
        tension_nominal: [N] T0 = W L_x^2 / (8 S) (paper Table 1).
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

    @cached_property
    def tower_x(self) -> np.ndarray:
        return np.arange(self.n_towers, dtype=float) * self.line.span_length

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
