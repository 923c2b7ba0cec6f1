"""Geometry of the conductor system and its still-air reference (nominal) state.

``LineSystem`` owns ALL the geometry of a line section: tower stations, clamp
points, per-span horizontal and unstretched lengths, element lengths and the
still-air node coordinates.  The numerical path reads these arrays, never the
case's ``span_length`` key (tests/test_import_boundary.py checks this), so that
unequal spans (line sections) only change how the arrays are built here.

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
        if self.is_section:
            return np.diff(self.stations)
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
        """Unstretched conductor length of every span L_u [m], shape (n_spans,).

        Section form: the inclined elastic catenary with horizontal tension H0 between the two
        still-air clamps (Irvine 1981, :func:`~linecheck.core.catenary.clip_in`)."""
        if self.is_section:
            return self._clip_in[0]
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
        """Tower stations [m] along the line from the first tower, shape (n_towers,)
        (equal-span form: also the still-air clamp x)."""
        if self.is_section:
            return self.stations
        return np.arange(self.n_towers, dtype=float) * self.line.span_length

    @cached_property
    def clamp_points(self) -> np.ndarray:
        """Still-air conductor clamp points (x, y, z) [m], shape (n_towers, 3).

        Equal-span form: level (z = 0) on y = 0.  Section form: plan position P_j (the first
        span along +x, span i turned by its heading h_i) and z = ground + height (docs/method.md,
        "Line sections")."""
        p = np.zeros((self.n_towers, 3))
        if self.is_section:
            h = self.span_headings
            L = self.span_lengths
            p[1:, 0] = np.cumsum(L * np.cos(h))
            p[1:, 1] = np.cumsum(L * np.sin(h))
            p[:, 2] = self.ground + np.array([t.height for t in self.line.towers])
            return p
        p[:, 0] = self.tower_x
        return p

    # ------------------------------------------------------------------ section form (line sections)
    @property
    def is_section(self) -> bool:
        """True when the case describes its towers ([[line.towers]] / towers_file)."""
        return self.line.is_section

    @cached_property
    def stations(self) -> np.ndarray:
        """[m] horizontal distance along the line of every tower from the first, (n_towers,)."""
        if not self.is_section:
            return self.tower_x
        s = np.array([t.station for t in self.line.towers], dtype=float)
        return s - s[0]

    @cached_property
    def ground(self) -> np.ndarray:
        """[m] ground elevation at every tower, (n_towers,) (equal-span form: 0 with clamps at -height)."""
        if not self.is_section:
            return np.full(self.n_towers, -float(self.line.height))
        return np.array([t.ground for t in self.line.towers], dtype=float)

    @cached_property
    def tower_angles(self) -> np.ndarray:
        """[rad] horizontal line deviation at every tower, + turning left, (n_towers,)."""
        if not self.is_section:
            return np.zeros(self.n_towers)
        return np.radians([t.angle for t in self.line.towers])

    @cached_property
    def span_headings(self) -> np.ndarray:
        """[rad] heading h_i of every span from +x (sum of the angles of towers 1..i), (n_spans,)."""
        return np.cumsum(self.tower_angles[:-1])

    @cached_property
    def tower_headings(self) -> np.ndarray:
        """[rad] heading of every tower's frame x axis: mean of its two spans' headings (ends: its span's)."""
        h = self.span_headings
        out = np.empty(self.n_towers)
        out[0], out[-1] = h[0], h[-1]
        out[1:-1] = 0.5 * (h[:-1] + h[1:])
        return out

    @property
    def straight_in_plan(self) -> bool:
        """True when the frames of every tower and node are the global axes (no rotation needed):
        the equal-span form, or a section without angle towers (inclined spans allowed)."""
        return not self.is_section or not np.any(self.tower_angles)

    def to_tower_frames(self, R: np.ndarray, towers: slice = slice(None)) -> np.ndarray:
        """Reactions (..., n_towers, 3) from the global frame (x, y, z down) to every tower's own
        frame: x along its mean heading psi_j, y = x turned +90 deg in plan, z down.

        R'_x = R_x cos psi + R_y sin psi, R'_y = -R_x sin psi + R_y cos psi, R'_z = R_z.  Returns
        ``R`` itself (no copy) when every tower frame is the global frame.  ``towers``: R holds
        the reactions of these towers only (a slice of the towers)."""
        if self.straight_in_plan:
            return R
        c, s = np.cos(self.tower_headings[towers]), np.sin(self.tower_headings[towers])
        out = np.array(R, dtype=float, copy=True)
        out[..., 0] = R[..., 0] * c + R[..., 1] * s
        out[..., 1] = -R[..., 0] * s + R[..., 1] * c
        return out

    def from_tower_frames(self, R: np.ndarray) -> np.ndarray:
        """Inverse of :meth:`to_tower_frames`."""
        if self.straight_in_plan:
            return R
        c, s = np.cos(self.tower_headings), np.sin(self.tower_headings)
        out = np.array(R, dtype=float, copy=True)
        out[..., 0] = R[..., 0] * c - R[..., 1] * s
        out[..., 1] = R[..., 0] * s + R[..., 1] * c
        return out

    @cached_property
    def insulator_lengths(self) -> np.ndarray:
        """[m] insulator length v_j of every tower (strain towers: the line default, unused), (n_towers,)."""
        v = float(self.line.insulator_length)
        if not self.is_section:
            return np.full(self.n_towers, v)
        return np.array([t.insulator_length if t.insulator_length is not None else v for t in self.line.towers])

    @cached_property
    def insulator_tops(self) -> np.ndarray:
        """[m] fixed top of every insulator, v_j straight above the still-air clamp, (n_towers, 3)."""
        tops = self.clamp_points.copy()
        tops[:, 2] += self.insulator_lengths
        return tops

    @cached_property
    def span_chords(self) -> np.ndarray:
        """[m] still-air chord of every span (second clamp - first), (n_spans, 3)."""
        return np.diff(self.clamp_points, axis=0)

    @cached_property
    def span_directions(self) -> np.ndarray:
        """[-] unit still-air chord of every span, (n_spans, 3) (global frame, z up)."""
        c = self.span_chords
        return c / np.linalg.norm(c, axis=1)[:, None]

    @cached_property
    def span_normals(self) -> np.ndarray:
        """[-] horizontal unit normal n_i = (-sin h_i, cos h_i, 0) of every span (the drag direction), (n_spans, 3)."""
        h = self.span_headings
        return np.stack([-np.sin(h), np.cos(h), np.zeros_like(h)], axis=1)

    @cached_property
    def tower_along(self) -> np.ndarray:
        """[-] horizontal unit vector of every tower frame's x axis, (n_towers, 3)."""
        h = self.tower_headings
        return np.stack([np.cos(h), np.sin(h), np.zeros_like(h)], axis=1)

    @cached_property
    def _clip_in(self) -> tuple[np.ndarray, np.ndarray]:
        from .catenary import clip_in

        c = self.span_chords
        H0 = np.full(self.n_spans, float(self.line.tension))
        return clip_in(H0, self.span_lengths, c[:, 2], self.line.weight, self.line.ea)

    @cached_property
    def clip_in_nodes(self) -> np.ndarray:
        """[m] node positions of the clipped-in catenaries (insulators vertical), (n_nodes, 3):
        the still-air shape the wind is evaluated on (section form)."""
        from .catenary import solve_spans

        Lu, V0 = self._clip_in
        e = np.stack([np.cos(self.span_headings), np.sin(self.span_headings), np.zeros(self.n_spans)], axis=1)
        N0 = float(self.line.tension) * e
        N0[:, 2] = V0
        p = np.zeros((self.n_spans, self.ne + 1, 3))
        p[..., 2] = -self.line.weight
        sol = solve_spans(self.span_chords, p, Lu, self.line.ea, N0, what="clipping-in")
        r = self.clamp_points[:-1, None, :] + sol.r
        nodes = np.empty((self.n_nodes, 3))
        nodes[:-1] = r[:, :-1].reshape(-1, 3)
        nodes[-1] = r[-1, -1]
        return nodes

    @cached_property
    def still_air(self):
        """The still-air equilibrium under weight (a :class:`~linecheck.core.static.StaticState`),
        solved once per system and shared read-only: the reference of every wind-induced value
        and, on a section, the shape the wind is evaluated on."""
        from .static import solve_static  # the step-1 solver needs no wind geometry

        return solve_static(self, np.zeros((self.n_spans, self.ne + 1)), label="still-air state")

    @cached_property
    def node_xyz0(self) -> np.ndarray:
        """[m] still-air position of every global FE node (x, y, z), (n_nodes, 3).

        Equal-span form: (node_x0, 0, 0) (the paper's wind sees a straight, level line).
        Section form: the still-air equilibrium under weight (the height above ground of a
        conductor point is taken from the still-air shape, docs/wind.md, "Sections"; at angle towers the insulators have swung;
        on a straight section it is the clipped-in shape, :attr:`clip_in_nodes`)."""
        if self.is_section:
            return self.still_air.nodes
        out = np.zeros((self.n_nodes, 3))
        out[:, 0] = self.node_x0
        return out

    @cached_property
    def node_station(self) -> np.ndarray:
        """[m] horizontal distance along the line of every FE node from the first tower, (n_nodes,)."""
        if not self.is_section:
            return self.node_x0
        xyz = self.node_xyz0
        span = self.span_of_node(np.arange(self.n_nodes))
        e = np.stack([np.cos(self.span_headings), np.sin(self.span_headings)], axis=1)[span]
        return self.stations[span] + np.einsum("ij,ij->i", xyz[:, :2] - self.clamp_points[span, :2], e)

    @cached_property
    def node_height(self) -> np.ndarray:
        """[m] still-air height above ground of every FE node (ground interpolated linearly in
        station between towers), (n_nodes,).  Equal-span form: ``height`` everywhere."""
        if not self.is_section:
            return np.full(self.n_nodes, float(self.line.height))
        g = np.interp(self.node_station, self.stations, self.ground)
        return self.node_xyz0[:, 2] - g

    @cached_property
    def node_normals(self) -> np.ndarray:
        """[-] horizontal unit normal of every FE node, the direction of its transverse load and
        of its "y" DOF (span nodes: the span's normal; tower nodes: the tower frame's y), (n_nodes, 3)."""
        span = self.span_of_node(np.arange(self.n_nodes))
        n = self.span_normals[span].copy()
        h = self.tower_headings
        n[self.tower_nodes] = np.stack([-np.sin(h), np.cos(h), np.zeros_like(h)], axis=1)
        return n

    @cached_property
    def node_frames(self) -> np.ndarray:
        """[-] per-node orthonormal bases, columns (along-line horizontal, normal, up), (n_nodes, 3, 3):
        the DOF frames of a section with angles (identity otherwise)."""
        b = self.node_normals
        T = np.zeros((self.n_nodes, 3, 3))
        T[:, 0, 0], T[:, 1, 0] = b[:, 1], -b[:, 0]  # along = normal turned -90 deg
        T[:, :, 1] = b
        T[:, 2, 2] = 1.0
        return T

    @cached_property
    def node_gaps(self) -> np.ndarray:
        """[m] distance along the line between neighbouring still-air FE nodes (their stations),
        (n_nodes - 1,): the spacing of the Markov (exponential) coherence along the line, the same
        as the turbulence synthesis' (equal-span form: the element length)."""
        if not self.is_section:
            return np.repeat(self.element_lengths, self.ne)
        return np.diff(self.node_station)  # as the turbulence synthesis (Markov along the stations)

    @cached_property
    def eq17_lengths(self) -> np.ndarray:
        """[m] Eq. 17's L_x at every tower: the mean of its adjacent spans (ends: its span), (n_towers,)."""
        return np.array([self.span_lengths_at_tower(j) for j in range(self.n_towers)])

    def span_lengths_at_tower(self, j: int) -> float:
        """[m] Eq. 17's L_x at tower j (0-based): the mean of its adjacent spans' horizontal lengths."""
        L = self.span_lengths
        adj = [L[i] for i in (j - 1, j) if 0 <= i < self.n_spans]
        return float(sum(adj) / len(adj))

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
        """Still-air x of every global FE node [m], shape (n_nodes,) (a section: its station,
        the horizontal distance along the line, :attr:`node_station`)."""
        if self.is_section:
            return self.node_station
        return np.arange(self.n_nodes) * (self.line.span_length / self.ne)

    @cached_property
    def span_node_x0(self) -> np.ndarray:
        """Still-air x of each span's FE nodes [m], shape (n_spans, ne+1) (a section: stations)."""
        if self.is_section:
            x = self.node_station
            return np.stack([x[i * self.ne:(i + 1) * self.ne + 1] for i in range(self.n_spans)])
        return self.tower_x[:-1, None] + self.node_s[None, :] * self.span_lengths[:, None]

    @property
    def tension_nominal(self) -> float:
        """T0 = W L_x^2 / (8 S) [N] (paper Table 1, parabolic cable); section form: H0."""
        if self.is_section:
            return float(self.line.tension)
        L, S = self.line.span_length, self.line.sag
        return self.line.weight * L**2 / (8.0 * S)

    @property
    def stretched_length(self) -> float:
        """Still-air stretched length L_x (1 + 8/3 (S/L_x)^2) [m] (parabola, Irvine 1981 Eq. 2.14)."""
        L, S = self.line.span_length, self.line.sag
        return L * (1.0 + 8.0 / 3.0 * (S / L) ** 2)

    @property
    def unstretched_length(self) -> float:
        """Unstretched span length L_u = stretched / (1 + T0/EA) [m] (linecheck's definition)."""
        return self.stretched_length / (1.0 + self.tension_nominal / self.line.ea)

    def span_of_node(self, node: np.ndarray | int) -> np.ndarray:
        """Span index (0-based) of a global node (attachment nodes belong to the span on their right)."""
        return np.minimum(np.asarray(node) // self.ne, self.n_spans - 1)
