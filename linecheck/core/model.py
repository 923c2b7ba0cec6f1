"""Linearised finite-element model about a step-1 mean state (paper section 4, Step 2).

Degrees of freedom: 3 translations (x, y, z) per global FE node, node-major, with
the nodes at strain towers removed (pinned).  Element matrices:

- cable element (paper Eq. 7): in local axes diag(EA, T, T)/L_e, i.e. in global axes
  k = (EA/L_e) e e^T + (T/L_e) (I - e e^T), e the unit chord of the deformed element;
- insulator: from the fixed point to the attachment node, axially stiff
  (penalty EA_ins/v, see :data:`INSULATOR_AXIAL_FACTOR`) and with the geometric
  stiffness R_res/v transversely;
- lumped mass (paper Eq. 8): m = W L_u / (ne g) per element, half to each node.
  A rigid insulator keeps its attachment node from moving along the insulator axis, so
  that node has neither inertia nor damping along the axis (M and C are projected onto
  the plane normal to it): the axial direction is a static equation, solved exactly at
  every step, and the stiff penalty creates no spurious high-frequency mode.  Eigen
  analyses condense that direction out exactly (:func:`condensed`);
- aerodynamic damping (paper Eqs 9-13): c_i = rho C_d D L_i |V_i| on the y DOF of
  node i (L_i its tributary conductor length, V_i the local running-mean normal speed).

Reactions on tower j (force of the conductor system on its fixed point, R_z
downward) are linear in the free displacements u and in the loads applied
directly at pinned nodes: R = G u + D f_pinned.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from functools import cached_property

import numpy as np

from .case import GRAVITY
from .static import StaticState
from .system import LineSystem

# Axial stiffness of an insulator relative to the axial stiffness EA/L_e of one cable
# element.  Large enough that its stretch is negligible (< 0.1 % of the transverse
# response), small enough to keep K well conditioned; the mode it creates is far
# above the wind band (hundreds of Hz) and average-acceleration Newmark is
# unconditionally stable, so it costs nothing.
INSULATOR_AXIAL_FACTOR = 1.0e3


@dataclass(frozen=True)
class DofMap:
    """Map between global FE nodes and free DOFs.

    Attributes:
        free_nodes: indices of the nodes that carry DOFs, shape (n_free_nodes,).
        node_dof: first DOF of every node (-1 for pinned nodes), shape (n_nodes,).
        n_dof: number of free DOFs (3 * n_free_nodes).
    """

    free_nodes: np.ndarray
    node_dof: np.ndarray
    n_dof: int


def dof_map(system: LineSystem) -> DofMap:
    pinned = np.zeros(system.n_nodes, dtype=bool)
    pinned[system.tower_nodes[~system.suspension]] = True
    free = np.flatnonzero(~pinned)
    node_dof = np.full(system.n_nodes, -1)
    node_dof[free] = 3 * np.arange(free.size)
    return DofMap(free, node_dof, 3 * free.size)


@dataclass(frozen=True)
class LinearModel:
    """Stiffness (banded), mass and damping of the linearised system at one mean state.

    Attributes:
        system: the line section.
        dofs: the DOF map.
        K_band: [N/m] symmetric stiffness in LAPACK upper banded storage, shape (6, n_dof)
            (half-bandwidth 5, node-major ordering).
        mass: [kg] lumped nodal mass per DOF, shape (n_dof,) (before the axial projection).
        tributary: [m] tributary unstretched conductor length of every global node, (n_nodes,).
        G: [N/m] reactions from free displacements, shape (n_towers * 3, n_dof); row 3j+c is
            component c (x, y, z-down) of tower j.
        axes: unit insulator axes at the suspension attachment nodes, shape (n_susp, 3).
        axial_dof: first DOF of each suspension attachment node, shape (n_susp,).
        K_axial_band: [N/m] the insulator axial penalty part of ``K_band`` (same storage).
        load_directions: [-] the transverse load's direction at every node, (n_nodes, 3), where
            it is not ``system.node_normals`` (the cross-flow form, :mod:`linecheck.core.crossflow`).
    """

    system: LineSystem
    dofs: DofMap
    K_band: np.ndarray
    mass: np.ndarray
    tributary: np.ndarray
    G: np.ndarray
    axes: np.ndarray
    axial_dof: np.ndarray
    K_axial_band: np.ndarray
    load_directions: np.ndarray | None = None

    @cached_property
    def M_band(self) -> np.ndarray:
        """[kg] mass in upper band storage, projected normal to the insulator axes."""
        ab = np.zeros_like(self.K_band)
        ab[-1] = self.mass
        return project_axial(self, ab)

    @cached_property
    def K_dense(self) -> np.ndarray:
        """Dense stiffness [N/m], shape (n_dof, n_dof) (modes, tests, baselines)."""
        return band_to_dense(self.K_band)


BANDWIDTH = 5  # half-bandwidth with node-major DOFs and two-node elements


def band_to_dense(ab: np.ndarray) -> np.ndarray:
    """Upper banded storage (LAPACK 'U', ab[u + i - j, j] = A[i, j]) to a dense symmetric matrix."""
    u, n = ab.shape[0] - 1, ab.shape[1]
    A = np.zeros((n, n))
    for k in range(u + 1):
        d = ab[u - k, k:]
        idx = np.arange(n - k)
        A[idx, idx + k] = d
        A[idx + k, idx] = d
    return A


@dataclass(frozen=True)
class CSRArrays:
    """A square CSR matrix as its three arrays (what the step loops read), without building a
    scipy matrix (≈ 40 µs each, 250 times in a downburst run); :meth:`tocsr` builds one."""

    indptr: np.ndarray  # int32, (n + 1,)
    indices: np.ndarray  # int32, (nnz,): each row's columns ascending
    data: np.ndarray  # (nnz,)
    shape: tuple[int, int]
    #: the same matrix by diagonals, (2 u + 1, n): band[o, i] = A[i, i + o - u], zero outside the
    #: matrix (what the compiled step loop reads, kernel.newmark_block)
    band: np.ndarray = field(compare=False, repr=False)
    format = "csr"

    def tocsr(self):
        """The scipy CSR matrix of these arrays."""
        from scipy.sparse import csr_matrix

        out = csr_matrix((self.data, self.indices, self.indptr), shape=self.shape)
        out.has_canonical_format = True
        return out


def band_to_csr(ab: np.ndarray) -> CSRArrays:
    """Upper banded storage (LAPACK 'U', ab[u + i - j, j] = A[i, j]) of a symmetric matrix to
    its CSR arrays: those of scipy's ``dia_matrix(...).tocsr()`` (explicit zeros dropped, each
    row's columns ascending, int32 indices), gathered in one vectorised pass (the same
    arrays, tested; :func:`band_to_csr_stack` of one matrix)."""
    return band_to_csr_stack(ab[None])[0]


def band_to_csr_stack(ab: np.ndarray) -> list[CSRArrays]:
    """:func:`band_to_csr` of many band matrices of one size, shape (n_k, u + 1, n), in one
    vectorised pass (a downburst's 250 mean states)."""
    n_k, u, n = ab.shape[0], ab.shape[1] - 1, ab.shape[2]
    offs = np.arange(-u, u + 1)
    rows = np.arange(n)[:, None]
    cols = rows + offs  # (n, 2u + 1): row i's possible columns, ascending
    inside = (cols >= 0) & (cols < n)
    # A[i, i + k] = ab[u - k, i + k] (k >= 0) and A[i, i + k] = A[i + k, i] = ab[u + k, i] (k < 0)
    vals = np.where(inside, ab[:, u - np.abs(offs), np.clip(np.where(offs >= 0, cols, rows), 0, n - 1)], 0.0)
    keep = vals != 0.0  # (n_k, n, 2u + 1)
    indptr = np.zeros((n_k, n + 1), dtype=np.int32)
    np.cumsum(keep.sum(axis=2), axis=1, out=indptr[:, 1:])
    band = np.ascontiguousarray(vals.transpose(0, 2, 1))  # (n_k, 2u + 1, n): by diagonals
    return [CSRArrays(indptr[k], cols[keep[k]].astype(np.int32), vals[k][keep[k]], (n, n), band[k]) for k in range(n_k)]


def band_to_sparse(ab: np.ndarray):
    """Upper banded storage to a symmetric scipy CSR matrix (no dense intermediate;
    :func:`band_to_csr`)."""
    return band_to_csr(ab).tocsr()


def _cable_blocks(nodes: np.ndarray, tension: np.ndarray, ea: float) -> np.ndarray:
    """3x3 element stiffness blocks k = EA/L e e^T + T/L (I - e e^T) (paper Eq. 7).

    Args:
        nodes: [m] node coordinates, shape (..., n_nodes, 3) (leading axes: mean states).
        tension: [N] element tensions, shape (..., n_el).

    Returns: [N/m] shape (..., n_el, 3, 3).
    """
    seg = np.diff(nodes, axis=-2)
    Le = np.linalg.norm(seg, axis=-1)
    e = seg / Le[..., None]
    eet = e[..., :, None] * e[..., None, :]
    eye = np.eye(3)
    return (ea / Le)[..., None, None] * eet + (tension / Le)[..., None, None] * (eye - eet)


def _insulator_axial_stiffness(system: LineSystem) -> float:
    """k_ax [N/m]: the insulators' axial penalty, :data:`INSULATOR_AXIAL_FACTOR` times the
    stiffest cable element of the section (equal spans: every element, EA ne / L_u)."""
    ea_cable_el = system.line.ea / float(system.element_unstretched_lengths.min())
    return INSULATOR_AXIAL_FACTOR * ea_cable_el


def _lumped_mass(system: LineSystem, dm: DofMap) -> tuple[np.ndarray, np.ndarray]:
    """Lumped mass by tributary unstretched length (paper Eq. 8), state-independent.

    Returns: tributary length [m] of every global node (n_nodes,) and the mass [kg] per free
    DOF (n_dof,)."""
    Le_u = system.element_unstretched_lengths  # (n_elements,)
    trib = np.zeros(system.n_nodes)
    trib[:-1] += 0.5 * Le_u
    trib[1:] += 0.5 * Le_u
    m_node = system.line.weight * trib / GRAVITY
    return trib, np.repeat(m_node[dm.free_nodes], 3)


def _cable_band(kb: np.ndarray, nd: np.ndarray, n_dof: int) -> np.ndarray:
    """Cable elements' stiffness (paper Eq. 7) scattered into upper band storage.

    kb: [N/m] element blocks (n_el, 3, 3); nd: first DOF of every node (-1 pinned), (n_nodes,).
    Returns: [N/m] (BANDWIDTH + 1, n_dof).
    """
    ab = np.zeros((BANDWIDTH + 1, n_dof))
    u = BANDWIDTH
    ia, ib = np.triu_indices(3)  # upper triangle of a diagonal 3x3 block

    def add_diag_blocks(first: np.ndarray, blocks: np.ndarray) -> None:
        """Add symmetric 3x3 blocks at DOFs first..first+2 (vectorised, repeated DOFs summed)."""
        rows = np.broadcast_to(u + ia - ib, (first.size, ia.size))
        cols = first[:, None] + ib[None, :]
        np.add.at(ab, (rows, cols), blocks[:, ia, ib])

    left, right = nd[:-1], nd[1:]
    add_diag_blocks(left[left >= 0], kb[left >= 0])
    add_diag_blocks(right[right >= 0], kb[right >= 0])
    both = (left >= 0) & (right >= 0)  # element between two free nodes: -k off the diagonal
    a, b = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    rows = np.broadcast_to((u + a - 3 - b).ravel(), (int(both.sum()), 9))  # right node = left + 3
    cols = right[both][:, None] + b.ravel()[None, :]
    np.add.at(ab, (rows, cols), -kb[both].reshape(-1, 9))
    return ab


def _add_insulators(ab: np.ndarray, system: LineSystem, state: StaticState, nd: np.ndarray):
    """Add the suspension insulators' stiffness to the band ``ab`` (in place).

    Each insulator is axially stiff (penalty k_ax along its axis) with the geometric stiffness
    R_res/v transversely (pendulum of length v under the insulator force R_res).

    Returns: {tower: 3x3 block [N/m]}, the unit axes (n_susp, 3), the attachment nodes' first
    DOFs (n_susp,) and the axial penalty part of the band [N/m] (BANDWIDTH + 1, n_dof).
    """
    u = BANDWIDTH

    def add_block(r0: int, c0: int, blk: np.ndarray) -> None:
        # one 3x3 block at (r0, c0), upper triangle only (insulators)
        for a_ in range(3):
            for b_ in range(3):
                i, j = r0 + a_, c0 + b_
                if i <= j:
                    ab[u + i - j, j] += blk[a_, b_]

    v_all = system.insulator_lengths  # per tower (equal-span form: line.insulator_length)
    k_ax = _insulator_axial_stiffness(system)
    ins_blocks = {}
    axes, axial_dof = [], []
    K_axial = np.zeros_like(ab)
    for j in np.flatnonzero(system.suspension):
        v = v_all[j]
        d = state.displacement[j]
        axis = np.array([d[0], d[1], d[2] - v]) / v  # from fixed point to attachment (points down)
        axis /= np.sqrt((axis[0] * axis[0] + axis[1] * axis[1]) + axis[2] * axis[2])  # as build_models
        P = np.outer(axis, axis)
        blk = k_ax * P + (state.insulator_force[j] / v) * (np.eye(3) - P)
        ins_blocks[j] = blk
        r = nd[system.tower_nodes[j]]
        add_block(r, r, blk)
        for a_ in range(3):
            for b_ in range(a_, 3):
                K_axial[u + a_ - b_, r + b_] += k_ax * P[a_, b_]
        axes.append(axis)
        axial_dof.append(r)
    return ins_blocks, np.array(axes).reshape(-1, 3), np.array(axial_dof, dtype=int), K_axial


def _reaction_map(system: LineSystem, nd: np.ndarray, kb: np.ndarray, ins_blocks: dict,
                  n_dof: int) -> np.ndarray:
    """Reaction map G [N/m] (3 n_towers, n_dof): force of the system on every tower's fixed
    point from the free displacements (R_z positive downward)."""
    n_el = kb.shape[0]
    G = np.zeros((3 * system.n_towers, n_dof))
    flip = np.array([1.0, 1.0, -1.0])  # R_z is positive downward
    for j in range(system.n_towers):
        node = system.tower_nodes[j]
        if system.suspension[j]:
            # insulator: force on the fixed point = k_ins u_node
            r = nd[node]
            G[3 * j:3 * j + 3, r:r + 3] = flip[:, None] * ins_blocks[j]
        else:
            # pinned node: force on the support = -(K_rf u) from the adjacent cable elements
            for e, other in ((node - 1, node - 1), (node, node + 1)):
                if 0 <= e < n_el and nd[other] >= 0:
                    c = nd[other]
                    G[3 * j:3 * j + 3, c:c + 3] += flip[:, None] * kb[e]
    return G


def build_model(system: LineSystem, state: StaticState) -> LinearModel:
    """Assemble K, M and the reaction map about the mean state ``state`` (paper Eqs 7-8)."""
    dm = dof_map(system)
    kb = _cable_blocks(state.nodes, state.element_tension, system.line.ea)  # (n_el, 3, 3)
    ab = _cable_band(kb, dm.node_dof, dm.n_dof)
    ins_blocks, axes, axial_dof, K_axial = _add_insulators(ab, system, state, dm.node_dof)
    trib, mass = _lumped_mass(system, dm)
    G = _reaction_map(system, dm.node_dof, kb, ins_blocks, dm.n_dof)
    return LinearModel(system, dm, ab, mass, trib, G, axes, axial_dof, K_axial)


def _stacked_cable_band(kb: np.ndarray, nd: np.ndarray, n_dof: int) -> np.ndarray:
    """:func:`_cable_band` of n_k states at once: kb (n_k, n_el, 3, 3) -> (n_k, BANDWIDTH + 1, n_dof)."""
    n_k = kb.shape[0]
    u = BANDWIDTH
    ia, ib = np.triu_indices(3)
    ab = np.zeros((n_k, BANDWIDTH + 1, n_dof))
    diag_rows = (u + ia - ib)[None, :]  # upper triangle of a diagonal 3x3 block
    # no DOF repeats within one scatter, so a fancy-indexed += adds exactly as np.add.at
    left, right = nd[:-1], nd[1:]
    for ends, mask in ((left, left >= 0), (right, right >= 0)):  # same order as build_model
        ab[:, diag_rows, ends[mask][:, None] + ib[None, :]] += kb[:, mask][:, :, ia, ib]
    both = (left >= 0) & (right >= 0)  # element between two free nodes: -k off the diagonal
    a, b = np.meshgrid(np.arange(3), np.arange(3), indexing="ij")
    rows = (u + a - 3 - b).ravel()[None, :]  # right node = left + 3
    cols = right[both][:, None] + b.ravel()[None, :]
    ab[:, rows, cols] += -kb[:, both].reshape(n_k, -1, 9)
    return ab


def _stacked_insulators(ab: np.ndarray, system: LineSystem, states: list[StaticState], nd: np.ndarray):
    """:func:`_add_insulators` of n_k states at once (adds to ``ab`` (n_k, BANDWIDTH + 1, n_dof)).

    Returns: insulator blocks [N/m] (n_k, n_susp, 3, 3), unit axes (n_k, n_susp, 3), the
    attachment nodes' first DOFs (n_susp,) and the axial penalty bands [N/m] (n_k, BANDWIDTH + 1, n_dof).
    """
    u = BANDWIDTH
    ia, ib = np.triu_indices(3)
    diag_rows = (u + ia - ib)[None, :]  # upper triangle of a diagonal 3x3 block
    susp = np.flatnonzero(system.suspension)
    v = system.insulator_lengths[susp]  # (n_s,)
    k_ax = _insulator_axial_stiffness(system)
    d = np.stack([s.displacement for s in states])[:, susp]  # (n_k, n_s, 3)
    axes = np.stack([d[..., 0], d[..., 1], d[..., 2] - v], axis=-1) / v[:, None]  # fixed point -> attachment
    # |axis| element-wise, as build_model (a BLAS dot of a 3-vector rounds by its alignment on
    # OpenBLAS's SSE3 kernels, so a stacked state would not match one built alone)
    axes /= np.sqrt((axes[..., 0] * axes[..., 0] + axes[..., 1] * axes[..., 1]) + axes[..., 2] * axes[..., 2])[..., None]
    P = axes[..., :, None] * axes[..., None, :]  # (n_k, n_s, 3, 3)
    fins = np.stack([s.insulator_force for s in states])[:, susp]  # (n_k, n_s)
    ins_blocks = k_ax * P + (fins / v)[..., None, None] * (np.eye(3) - P)
    r = nd[system.tower_nodes[susp]]  # first DOF of every attachment node
    ins_cols = r[:, None] + ib[None, :]
    ab[:, diag_rows, ins_cols] += ins_blocks[:, :, ia, ib]
    K_axial = np.zeros_like(ab)
    K_axial[:, diag_rows, ins_cols] += (k_ax * P)[:, :, ia, ib]
    return ins_blocks, axes, np.array(r, dtype=int), K_axial


def _stacked_reaction_maps(system: LineSystem, nd: np.ndarray, kb: np.ndarray, ins_blocks: np.ndarray,
                           r: np.ndarray, n_dof: int) -> list[np.ndarray]:
    """:func:`_reaction_map` of n_k states: suspension towers k_ins u_node, strain towers
    -(K_rf u); one dense (3 n_towers, n_dof) map per state, allocated state by state (no
    (n_k, 3 n_towers, n_dof) stack)."""
    n_el = kb.shape[1]
    susp = np.flatnonzero(system.suspension)
    flip = np.array([1.0, 1.0, -1.0])[:, None]  # R_z is positive downward
    i3 = np.arange(3)
    susp_rows, susp_cols = (3 * susp)[:, None, None] + i3[:, None], r[:, None, None] + i3
    susp_vals = flip * ins_blocks  # (n_k, n_s, 3, 3)
    strain_rows, strain_cols, strain_el = [], [], []
    for j in np.flatnonzero(~system.suspension):
        node = system.tower_nodes[j]
        for e, other in ((node - 1, node - 1), (node, node + 1)):
            if 0 <= e < n_el and nd[other] >= 0:
                strain_rows.append(3 * j)
                strain_cols.append(nd[other])
                strain_el.append(e)
    rr = np.array(strain_rows, dtype=int)[:, None, None] + i3[:, None]
    cc = np.array(strain_cols, dtype=int)[:, None, None] + i3
    strain_vals = flip * kb[:, strain_el]  # (n_k, n_blocks, 3, 3)
    G = []
    for k in range(kb.shape[0]):
        Gk = np.zeros((3 * system.n_towers, n_dof))
        Gk[susp_rows, susp_cols] = susp_vals[k]
        Gk[rr, cc] += strain_vals[k]
        G.append(Gk)
    return G


def build_models(system: LineSystem, states: Sequence[StaticState]) -> list[LinearModel]:
    """:func:`build_model` for many mean states of one system in one vectorised pass.

    The element blocks (paper Eq. 7) of all states are computed as one stacked array
    (n_k, n_el, 3, 3) and scattered into a stacked band (n_k, BANDWIDTH + 1, n_dof) with a
    leading state axis; the insulator blocks of all states and towers are batched the same
    way.  Every floating-point operation is the one :func:`build_model` does, in the same
    order, so each model is bit-identical to building it alone (tests/core/test_build_models.py).
    What does not depend on the state (DOF map, lumped mass, tributary lengths, axial DOFs)
    is computed once and shared, read-only, by all models.  Each model keeps its own dense
    reaction map G, as :func:`build_model` does (allocated state by state; 3 n_towers x n_dof
    each, the dominant memory of a long section's downburst models).

    Args:
        system: the line section.
        states: the mean states, length n_k.

    Returns: the linear models, ``[build_model(system, s) for s in states]``.
    """
    states = list(states)
    if not states:
        return []
    dm = dof_map(system)
    nodes = np.stack([s.nodes for s in states])  # (n_k, n_nodes, 3)
    tension = np.stack([s.element_tension for s in states])  # (n_k, n_el)
    kb = _cable_blocks(nodes, tension, system.line.ea)  # (n_k, n_el, 3, 3)
    ab = _stacked_cable_band(kb, dm.node_dof, dm.n_dof)
    ins_blocks, axes, axial_dof, K_axial = _stacked_insulators(ab, system, states, dm.node_dof)
    trib, mass = _lumped_mass(system, dm)
    G = _stacked_reaction_maps(system, dm.node_dof, kb, ins_blocks, axial_dof, dm.n_dof)
    for x in (dm.free_nodes, dm.node_dof, mass, trib, axial_dof):
        x.flags.writeable = False  # shared by all the models
    return [LinearModel(system, dm, ab[k], mass, trib, G[k], axes[k], axial_dof, K_axial[k])
            for k in range(len(states))]


def mul3(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """Stacked 3x3 matrix products A B, element by element (broadcast over leading axes).

    Written as three multiply-adds in a fixed order instead of ``A @ B``: numpy's matmul
    hands each 3x3 product to BLAS, and OpenBLAS's SSE3 (Prescott) kernels round such a
    small product differently by the alignment of the matrix in memory, so a state's bits
    depended on its position in a stack. Element-wise IEEE operations round the same
    wherever the data lie, on every CPU.

    Args:
        A, B: shapes (..., 3, 3), broadcast against each other.
    Returns:
        shape (..., 3, 3).
    """
    return (A[..., :, 0, None] * B[..., None, 0, :] + A[..., :, 1, None] * B[..., None, 1, :]) \
        + A[..., :, 2, None] * B[..., None, 2, :]


def project_axial(model: LinearModel, ab: np.ndarray) -> np.ndarray:
    """P^T A P for a symmetric upper-band matrix A, P = I - a a^T at every suspension
    attachment node (identity elsewhere): removes the components along the insulator axes.

    The band is block tridiagonal (:func:`band_blocks`): the node's diagonal block becomes
    P D P and its coupling blocks E P (from the left neighbour) and P E (to the right one).
    """
    if model.axial_dof.size == 0:
        return ab.copy()
    D, E = band_blocks(ab)
    k = model.axial_dof // 3
    P = np.eye(3)[None] - model.axes[:, :, None] * model.axes[:, None, :]  # (n_s, 3, 3)
    D[k] = mul3(mul3(P, D[k]), P)
    left = k > 0
    E[k[left] - 1] = mul3(E[k[left] - 1], P[left])
    right = k < D.shape[0] - 1
    E[k[right]] = mul3(P[right], E[k[right]])
    return blocks_to_band(D, E, ab.shape[0] - 1)


def project_axial_stack(axial_dof: np.ndarray, axes: np.ndarray, ab: np.ndarray) -> np.ndarray:
    """:func:`project_axial` for a stack of band matrices of one system, vectorised over the
    stack (the mean states of :func:`build_models`); bit-identical to one at a time.

    Args:
        axial_dof: first DOF of every suspension attachment node, shape (n_s,) (shared).
        axes: [-] unit insulator axes of every matrix, shape (n_k, n_s, 3).
        ab: upper band storage, shape (n_k, BANDWIDTH + 1, n_dof).
    """
    if axial_dof.size == 0:
        return ab.copy()
    D, E = band_blocks(ab)
    k = axial_dof // 3
    P = np.eye(3) - axes[..., :, None] * axes[..., None, :]  # (n_k, n_s, 3, 3)
    D[:, k] = mul3(mul3(P, D[:, k]), P)
    left = k > 0
    E[:, k[left] - 1] = mul3(E[:, k[left] - 1], P[:, left])
    right = k < D.shape[1] - 1
    E[:, k[right]] = mul3(P[:, right], E[:, k[right]])
    return blocks_to_band(D, E, ab.shape[-2] - 1)


@dataclass(frozen=True)
class Condensed:
    """The model with the insulator-axial directions condensed out (exact for massless,
    undamped DOFs): u = S t, K* = S^T K S, M* = S^T M S, C* = S^T C S.

    Attributes:
        S: [-] map from condensed to full DOFs, shape (n_dof, n_t).
        K, M, C: dense condensed matrices, shape (n_t, n_t).
    """

    S: np.ndarray
    K: np.ndarray
    M: np.ndarray
    C: np.ndarray


#: above this many DOFs :func:`condensed` works with sparse matrices (O(n) instead of the dense
#: O(n^3) products; equal to the dense path to rounding, tests/core/test_sections_core.py); below it
#: the dense path keeps every existing result bit for bit
SPARSE_CONDENSATION_DOF = 600


def condensed(model: LinearModel, damping_band: np.ndarray | None = None) -> Condensed:
    """Static condensation of the axial directions at suspension nodes (Guyan 1965; exact
    here because those directions carry no mass and no damping)."""
    n = model.mass.size
    if n > SPARSE_CONDENSATION_DOF:
        return _condensed_sparse(model, damping_band)
    K = model.K_dense
    keep = np.ones(n, dtype=bool)
    Tt = np.eye(n)
    ax_cols = []
    for first, a in zip(model.axial_dof, model.axes):
        # orthonormal basis (t1, t2, a) of the node's space
        basis = np.linalg.svd(np.eye(3) - np.outer(a, a))[0][:, :2]
        Tt[first:first + 3, first:first + 3] = 0.0
        Tt[first:first + 3, first:first + 2] = basis
        keep[first + 2] = False
        col = np.zeros(n)
        col[first:first + 3] = a
        ax_cols.append(col)
    T = Tt[:, keep]  # (n, n_t): condensed coordinates
    if ax_cols:
        Ax = np.array(ax_cols).T  # (n, n_a)
        Kaa = Ax.T @ K @ Ax
        Kat = Ax.T @ K @ T
        S = T - Ax @ np.linalg.solve(Kaa, Kat)  # u = T t + a u_a, u_a = -Kaa^-1 Kat t
    else:
        S = T
    M = band_to_dense(model.M_band)
    C = np.zeros_like(K) if damping_band is None else band_to_dense(damping_band)
    return Condensed(S, S.T @ K @ S, S.T @ M @ S, S.T @ C @ S)


def _condensed_sparse(model: LinearModel, damping_band: np.ndarray | None) -> Condensed:
    """:func:`condensed` with sparse K, M, C, T and S (the same algebra): each axial direction
    couples only to its node's neighbours, and the axial DOFs of different towers are never
    coupled (K_aa is diagonal), so S = T - A K_aa^-1 K_at stays sparse; the products are then
    O(n) and only the condensed matrices are made dense (long sections)."""
    from scipy.sparse import coo_matrix, diags

    n = model.mass.size
    Ks = band_to_sparse(model.K_band)
    keep = np.ones(n, dtype=bool)
    rows, cols, vals = [], [], []
    a_rows, a_cols, a_vals = [], [], []
    plain = np.ones(n, dtype=bool)
    for j, (first, a) in enumerate(zip(model.axial_dof, model.axes)):
        basis = np.linalg.svd(np.eye(3) - np.outer(a, a))[0][:, :2]  # as the dense path
        plain[first:first + 3] = False
        keep[first + 2] = False
        for c in range(2):
            rows += [first, first + 1, first + 2]
            cols += [first + c] * 3
            vals += list(basis[:, c])
        a_rows += [first, first + 1, first + 2]
        a_cols += [j] * 3
        a_vals += list(a)
    idx = np.flatnonzero(plain)
    rows += list(idx)
    cols += list(idx)
    vals += [1.0] * idx.size
    col_of = np.cumsum(keep) - 1  # full column (first + c) -> condensed column
    T = coo_matrix((vals, (rows, col_of[np.asarray(cols, dtype=int)])), shape=(n, int(keep.sum()))).tocsr()
    if a_rows:
        Ax = coo_matrix((a_vals, (a_rows, a_cols)), shape=(n, len(model.axial_dof))).tocsr()
        Kaa = (Ax.T @ Ks @ Ax).toarray()
        Kat = Ax.T @ Ks @ T
        if np.count_nonzero(Kaa - np.diag(np.diag(Kaa))):  # pragma: no cover - adjacent axial DOFs
            S = T - Ax @ coo_matrix(np.linalg.solve(Kaa, Kat.toarray())).tocsr()
        else:
            S = T - Ax @ (diags(1.0 / np.diag(Kaa)) @ Kat)
    else:
        S = T
    S = S.tocsr()
    St = S.T.tocsr()
    M = band_to_sparse(model.M_band)
    out = [(St @ A @ S).toarray() for A in (Ks, M)]
    C = np.zeros_like(out[0]) if damping_band is None else (St @ band_to_sparse(damping_band) @ S).toarray()
    return Condensed(S.toarray(), out[0], out[1], C)


def reaction_matrix_direct(system: LineSystem, directions: np.ndarray | None = None) -> np.ndarray:
    """D: reactions from nodal transverse loads applied at pinned nodes, shape (n_towers*3, n_nodes).

    A load applied directly at a pinned node goes straight into its support (along the
    node's load direction, :attr:`LineSystem.node_normals`; global y on a straight line; or
    ``directions`` (n_nodes, 3), the cross-flow form's, z up, the reaction's z down).
    """
    D = np.zeros((3 * system.n_towers, system.n_nodes))
    for j in np.flatnonzero(~system.suspension):
        if directions is not None:
            b = directions[system.tower_nodes[j]]
            D[3 * j:3 * j + 3, system.tower_nodes[j]] = (b[0], b[1], -b[2])
        elif system.straight_in_plan:
            D[3 * j + 1, system.tower_nodes[j]] = 1.0
        else:
            b = system.node_normals[system.tower_nodes[j]]
            D[3 * j, system.tower_nodes[j]] = b[0]
            D[3 * j + 1, system.tower_nodes[j]] = b[1]
    return D


def band_blocks(ab: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Node blocks of a symmetric node-major matrix in upper band storage (half-bandwidth 5).

    With three DOFs per node and two-node elements the band is exactly block tridiagonal.

    ``ab`` may carry leading axes (a stack of matrices, e.g. one per mean state), shape
    (..., BANDWIDTH + 1, n_dof); the blocks then carry the same leading axes.

    Returns:
        D: diagonal blocks A[node i, node i], shape (..., n_nodes, 3, 3);
        E: coupling blocks A[node i, node i+1], shape (..., n_nodes - 1, 3, 3).
    """
    u = ab.shape[-2] - 1
    n_nodes = ab.shape[-1] // 3
    a = np.arange(3)[:, None]
    b = np.arange(3)[None, :]
    first = 3 * np.arange(n_nodes)[:, None, None]
    lo, hi = np.minimum(a, b), np.maximum(a, b)
    D = ab[..., u + lo - hi, first + hi]  # A[3i+lo, 3i+hi] (upper triangle, symmetric)
    E = ab[..., u - 3 + a - b, first[:-1] + 3 + b]  # A[3i+a, 3i+3+b]
    return D, E


def blocks_to_band(D: np.ndarray, E: np.ndarray, u: int = BANDWIDTH) -> np.ndarray:
    """Inverse of :func:`band_blocks` (upper band storage, shape (..., u + 1, 3 n_nodes))."""
    n_nodes = D.shape[-3]
    ab = np.zeros(D.shape[:-3] + (u + 1, 3 * n_nodes))
    first = 3 * np.arange(n_nodes)
    for a in range(3):
        for b in range(3):
            if b >= a:
                ab[..., u + a - b, first + b] = D[..., a, b]
            ab[..., u - 3 + a - b, first[:-1] + 3 + b] = E[..., a, b]
    return ab


def rotate_band(ab: np.ndarray, T: np.ndarray) -> np.ndarray:
    """T^T A T for a node-major symmetric band matrix and a block-diagonal rotation.

    Args:
        ab: upper band storage, shape (..., BANDWIDTH + 1, 3 n_nodes) (leading axes: a stack
            of matrices, e.g. the mean states, each rotated by its own bases).
        T: [-] per-node orthonormal bases (columns: local axes in global coordinates),
            shape (..., n_nodes, 3, 3).

    Every 3x3 product is element-wise (:func:`mul3`), so a stack gives bit for bit the
    matrices rotated one at a time on any CPU (tests/core/test_build_models.py).
    """
    D, E = band_blocks(ab)
    Tt = np.swapaxes(T, -1, -2)
    Dr = mul3(mul3(Tt, D), T)
    Er = mul3(mul3(Tt[..., :-1, :, :], E), T[..., 1:, :, :])
    return blocks_to_band(0.5 * (Dr + np.swapaxes(Dr, -1, -2)), Er, ab.shape[-2] - 1)
