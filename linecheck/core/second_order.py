"""Second-order tension: the reaction increment quadratic in the linear motion (issue 16).

The linear model (paper Eq. 7) keeps the element forces to first order in the nodal
displacements.  A cable element (or insulator) of chord c = L_e e, tension N and axial
stiffness k = EA/L_e (linecheck's element law, :mod:`linecheck.core.model`) under a relative
end displacement du = u_b - u_a has the chord length (docs/method.md "Second-order tension")

    L' = |c + du| = L_e + e.du + |du_perp|^2 / (2 L_e) + O(du^3),   du_perp = du - (e.du) e,

and the force it exerts on its end a, f = N' (c + du)/L' with N' = N + k (L' - L_e), is

    f = N e + [k (e.du) e + (N/L_e) du_perp]                               (Eq. 7, first order)
          + (EA - N)/L_e^2 [ |du_perp|^2/2 e + (e.du) du_perp ] + O(du^3)  (second order, f2).

The first bracket of f2 is the second-order stretch (the tension increment
dT_2 = EA |du_perp|^2 / (2 L_e^2)), the second the rotation of the first-order tension change
(for an insulator: dR_res x the swing angle, the term the linear R_x misses).

The full second-order response adds the displacement u_2 that restores equilibrium of the
second-order nodal forces p_2: K u_2 = -p_2 (quasi-static: its inertia is neglected, see
docs/method.md), so that the reaction increment is

    R_2 = S f2_support - G K^-1 p_2,

S the sign flip of R_z (positive downward).  u_2 spreads the element-wise stretch into the
uniform tension increment of the span ((EA/2L_0) int |w'|^2 ds for a taut string).  It is a
post-processing of the linear displacement history: the same operator for the dynamic F and
for the quasi-static B, so that R = F - B stays consistent.  Nothing here prints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import lapack

from .errors import NumericalError
from .model import LinearModel
from .static import StaticState

_FLIP = np.array([1.0, 1.0, -1.0])  # R_z is positive downward


@dataclass(frozen=True)
class SecondOrder:
    """Second-order reaction operator of one mean state.

    Attributes:
        e: [-] unit chords of the cable elements then of the insulators (fixed point to
            attachment), flattened (x, y, z per member), shape (3 n_m,), n_m = n_el + n_s.
        c: [N/m^2] (EA - N)/L_e^2 of every cable element, then (k_ax v - R_res)/v^2 of every
            insulator, shape (n_m,).
        n_nodes: global nodes; pinned: the pinned (strain tower) nodes.
        runs: contiguous runs of free nodes (first node, end node, first free index).
        ins_free: index among the free nodes of every suspension attachment, (n_s,).
        A: [-] member second-order forces -> reactions: the support terms S f2 minus the
            p_2 -> G K^-1 p_2 transfer (Z = K^-1 G^T, module docstring), shape (3 n_m, n_r).
    """

    e: np.ndarray
    c: np.ndarray
    n_nodes: int
    pinned: np.ndarray
    runs: tuple[tuple[int, int, int], ...]
    ins_free: np.ndarray
    A: np.ndarray


def second_order_operator(model: LinearModel, state: StaticState) -> SecondOrder:
    """The :class:`SecondOrder` operator of the mean state ``state`` with its linear ``model``."""
    from .model import INSULATOR_AXIAL_FACTOR

    system = model.system
    line = system.line
    n_nodes = system.n_nodes
    seg = np.diff(state.nodes, axis=0)
    Le = np.linalg.norm(seg, axis=1)
    e_el = seg / Le[:, None]
    c_el = (line.ea - state.element_tension) / Le**2  # (EA - N)/L_e^2, k L_e = EA (Eq. 7)
    sus = np.flatnonzero(system.suspension)
    v = line.insulator_length
    k_ax = INSULATOR_AXIAL_FACTOR * line.ea / float(system.element_unstretched_lengths.min())  # as model.py
    c_in = (k_ax * v - state.insulator_force[sus]) / v**2
    n_el, n_s = e_el.shape[0], sus.size
    n_m = n_el + n_s
    # Z = K^-1 G^T (banded Cholesky, LAPACK dpbtrf/dpbtrs)
    ch, info = lapack.dpbtrf(model.K_band, lower=0)
    if info != 0:
        raise NumericalError(f"second-order tension: stiffness not positive definite (dpbtrf info {info})")
    Z, info = lapack.dpbtrs(ch, np.asfortranarray(model.G.T), lower=0)
    if info != 0:  # pragma: no cover
        raise NumericalError(f"second-order tension: banded solve failed (dpbtrs info {info})")
    n_r = Z.shape[1]
    Zn = np.zeros((n_nodes + 1, 3, n_r))  # per node (pinned and the fixed point: zero)
    Zn[model.dofs.free_nodes] = Z.reshape(-1, 3, n_r)
    fixed = n_nodes  # the insulators' fixed points share one zero padding node
    a_node = np.concatenate([np.arange(n_el), np.full(n_s, fixed)])
    b_node = np.concatenate([np.arange(1, n_el + 1), system.tower_nodes[sus]])
    # p_2: -f2 on end a, +f2 on end b; R_2 = S f2_support - Z^T p_2 = (S + Z_a - Z_b)^T f2
    A = Zn[a_node] - Zn[b_node]  # (n_m, 3, n_r)
    flip = np.diag(_FLIP)
    for j in range(system.n_towers):
        node = system.tower_nodes[j]
        rows = slice(3 * j, 3 * j + 3)
        if system.suspension[j]:
            A[n_el + int(np.flatnonzero(sus == j)[0]), :, rows] += flip  # the insulator's end a
        else:
            if node < n_el:
                A[node, :, rows] += flip  # element node -> node+1 pulls its end a (the support)
            if node > 0:
                A[node - 1, :, rows] -= flip  # element node-1 -> node: end b is the support
    free = model.dofs.free_nodes
    cuts = np.flatnonzero(np.diff(free) != 1) + 1
    runs = tuple((int(r[0]), int(r[-1]) + 1, int(np.searchsorted(free, r[0]))) for r in np.split(free, cuts) if r.size)
    A = A.transpose(1, 0, 2).reshape(3 * n_m, n_r)  # component-major rows, as _member_forces
    pinned = np.setdiff1d(np.arange(n_nodes), free)
    return SecondOrder(np.concatenate([e_el, model.axes]).ravel(), np.concatenate([c_el, c_in]), n_nodes, pinned, runs,
                       model.dofs.node_dof[system.tower_nodes[sus]] // 3, np.ascontiguousarray(A))


SINGLE_THREAD_WORK = 200_000  # rows x A.size below OpenBLAS' multithreading threshold (4 x 65536)


def second_order_reactions(op: SecondOrder, U: np.ndarray) -> np.ndarray:
    """[N] R_2 at every tower for free displacements U [m], shape (m, n_dof) -> (m, n_r)."""
    m = U.shape[0]
    U3 = U.reshape(m, -1, 3)
    return second_order_from_components(op, U3[:, :, 0], U3[:, :, 1], U3[:, :, 2])


def second_order_from_components(op: SecondOrder, ux: np.ndarray, uy: np.ndarray, uz: np.ndarray,
                                  T: np.ndarray | None = None) -> np.ndarray:
    """[N] R_2 at every tower from the x, y, z displacements [m] of the free nodes, each
    shape (m, n_free_nodes) -> (m, n_r).  With ``T`` (per-node bases, (n_free_nodes, 3, 3)) the
    components are those of u~ in the node bases, u = T u~ (rotated block by block).

    Rows are processed in blocks of a fixed size that depends on the operator only (the last
    block padded with zeros), so the BLAS product always has the same shape: a row's result
    does not depend on how many other rows (realizations) share the call, and results stay
    bit-identical whatever the batch chunking.  The blocks are small enough for OpenBLAS to
    run the product on one thread (no thread start-up on a shared machine).
    """
    m = ux.shape[0]
    chunk = max(8, SINGLE_THREAD_WORK // op.A.size)
    n_blk = max(1, 512 // chunk) * chunk  # rows of one elementwise pass: arrays stay in cache
    out = np.empty((m, op.A.shape[1]))
    for i0 in range(0, m, n_blk):
        i1 = min(i0 + n_blk, m)
        comps = (ux[i0:i1], uy[i0:i1], uz[i0:i1])
        if T is not None:  # u = T u~ node by node
            comps = tuple(comps[0] * T[:, c, 0] + comps[1] * T[:, c, 1] + comps[2] * T[:, c, 2] for c in range(3))
        f = _member_forces(op, *comps)
        for j0 in range(0, i1 - i0, chunk):
            j1 = min(j0 + chunk, i1 - i0)
            if j1 - j0 == chunk:
                np.matmul(f[j0:j1], op.A, out=out[i0 + j0:i0 + j1])
            else:
                pad = np.zeros((chunk, f.shape[1]))
                pad[: j1 - j0] = f[j0:j1]
                out[i0 + j0:i0 + j1] = (pad @ op.A)[: j1 - j0]
    return out


def _member_forces(op: SecondOrder, *comps: np.ndarray) -> np.ndarray:
    """f2 of every member (force on its end a) [N], component-major, shape (m, 3 n_m), from the
    free-node displacement components (m, n_free_nodes) each (module docstring for f2)."""
    m = comps[0].shape[0]
    n_m, n_el = op.c.size, op.n_nodes - 1
    d = np.empty((3, m, n_m))
    u = np.empty((m, op.n_nodes))
    u[:, op.pinned] = 0.0
    for k, uk in enumerate(comps):
        for lo, hi, f0 in op.runs:  # free nodes in contiguous runs (slices, no fancy indexing)
            u[:, lo:hi] = uk[:, f0:f0 + hi - lo]
        np.subtract(u[:, 1:], u[:, :-1], out=d[k, :, :n_el])  # cable elements: u_b - u_a
        d[k, :, n_el:] = uk[:, op.ins_free]  # insulators: the fixed point does not move
    e = op.e.reshape(-1, 3)
    a = d[0] * e[:, 0]
    a += d[1] * e[:, 1]
    a += d[2] * e[:, 2]  # e.du
    q = np.einsum("kmi,kmi->mi", d, d)
    q *= 0.5
    q -= 1.5 * a * a
    # f2 = c [a du + (|du|^2/2 - 3 a^2/2) e]: force of the member on its end a
    a *= op.c
    q *= op.c
    d *= a
    f = np.empty((m, 3, n_m))
    for k in range(3):
        np.multiply(q, e[:, k], out=f[:, k])
        f[:, k] += d[k]
    return f.reshape(m, 3 * n_m)
