"""Second-order tension: the reaction increment quadratic in the linear motion.

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

from dataclasses import dataclass, field

import numpy as np
from scipy.linalg import lapack

from . import banded
from .errors import NumericalError
from .model import LinearModel
from .static import StaticState

_FLIP = np.array([1.0, 1.0, -1.0])  # R_z is positive downward
SINGLE_THREAD_WORK = 4 * 65536  # rows x W.size up to OpenBLAS' multithreading threshold (m n k <= 4 x 65536)
BLOCK_ROWS = 128  # rows of one block of elementwise passes (their arrays stay in cache)


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
        W: [N/m^2] the same map from the members' second-order terms P: R_2 = P W, shape
            (3 n_el + 3 n_s, n_r) (:func:`reaction_form`).
        ins_nodes: global node of every suspension attachment, (n_s,).
        ins_frame: [-] rows (e, t1, t2) of every insulator's orthonormal frame, (n_s, 3, 3).

    Derived once per operator (also by ``dataclasses.replace``), for the block passes that run
    once per Newmark block: ``Wp`` W C-ordered, ``ec``
    the cable elements' unit chords (n_el, 3), ``node_of_free`` the global node of every free
    node and ``run_lo``, ``run_hi``, ``run_f0`` the runs' first node, end node and first free
    index (int64), ``chunk`` the rows of one BLAS product and ``nb`` of one block (a multiple).
    """

    e: np.ndarray
    c: np.ndarray
    n_nodes: int
    pinned: np.ndarray
    runs: tuple[tuple[int, int, int], ...]
    ins_free: np.ndarray
    A: np.ndarray
    W: np.ndarray
    ins_nodes: np.ndarray
    ins_frame: np.ndarray
    Wp: np.ndarray = field(init=False, repr=False)
    ec: np.ndarray = field(init=False, repr=False)
    node_of_free: np.ndarray = field(init=False, repr=False)
    run_lo: np.ndarray = field(init=False, repr=False)
    run_hi: np.ndarray = field(init=False, repr=False)
    run_f0: np.ndarray = field(init=False, repr=False)
    chunk: int = field(init=False, repr=False)
    nb: int = field(init=False, repr=False)

    def __post_init__(self) -> None:
        put = object.__setattr__  # frozen: set the derived fields once, here
        put(self, "ins_nodes", np.ascontiguousarray(self.ins_nodes, dtype=np.int64))
        put(self, "ins_frame", np.ascontiguousarray(self.ins_frame, dtype=float))
        put(self, "Wp", np.ascontiguousarray(self.W, dtype=float))
        put(self, "ec", np.ascontiguousarray(np.asarray(self.e, dtype=float)[:3 * (self.n_nodes - 1)].reshape(-1, 3)))
        runs = sorted(self.runs, key=lambda x: x[2])
        put(self, "node_of_free", np.concatenate([np.arange(lo, hi, dtype=np.int64) for lo, hi, _ in runs]))
        for i, name in enumerate(("run_lo", "run_hi", "run_f0")):
            put(self, name, np.array([x[i] for x in runs], dtype=np.int64))
        # whole micro-kernel tiles: with 23-row blocks the edge rows' kernel rounded a column differently
        chunk = max(16, SINGLE_THREAD_WORK // self.W.size // 16 * 16)
        put(self, "chunk", chunk)
        put(self, "nb", max(1, BLOCK_ROWS // chunk) * chunk)  # rows of one elementwise pass: in cache


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
    v = system.insulator_lengths[sus]  # per tower
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
    A = A.transpose(1, 0, 2).reshape(3 * n_m, n_r)  # component-major rows
    pinned = np.setdiff1d(np.arange(n_nodes), free)
    e = np.concatenate([e_el, model.axes])
    c = np.concatenate([c_el, c_in])
    W, frame = reaction_form(e, c, A, n_el)
    return SecondOrder(e.ravel(), c, n_nodes, pinned, runs, model.dofs.node_dof[system.tower_nodes[sus]] // 3,
                       np.ascontiguousarray(A), W, system.tower_nodes[sus].copy(), frame)


def reaction_form(e: np.ndarray, c: np.ndarray, A: np.ndarray, n_el: int) -> tuple[np.ndarray, np.ndarray]:
    """[N/m^2] W (3 n_el + 3 n_s, n_r) such that R_2 = P W, and the insulators' frames.

    P holds per row, member-major: for every cable element its second-order force per unit c,
    f2/c = a du + q e (x, y, z; a = e.du, q = |du|^2/2 - 3 a^2/2, the module docstring's f2);
    for every insulator (a s, a w, s^2 + w^2), with (a, s, w) = F du its components in its
    frame F = (e, t1, t2) (rows; returned, (n_s, 3, 3)).

    With g_r a member's 3 rows of A (component-major, (3 n_m, n_r)) and h_r = e.g_r:
    * a cable element: f2.g_r = c (a du + q e).g_r, so its three rows of W are c g_r (paper
      Eq. 7's element law; the member-force form: 3 rows per element, where the six products
      of du's components would need 6);
    * an insulator: with du = a e + s t1 + w t2, g_r.du = h_r a + (g_r.t1) s + (g_r.t2) w and
      q = (s^2 + w^2)/2 - a^2, so the a^2 terms cancel exactly:
      f2.g_r = c [(g_r.t1) a s + (g_r.t2) a w + h_r (s^2 + w^2)/2].  Its c is ~10^4 times a
      cable element's (rigid insulator) and a stays ~10^-5 |du| (it swings about its fixed
      point): a du + q e in x, y, z would carry the rounding of q e (~|du|^2) times that c, the
      frame keeps the products of a instead.
    e: unit chords (n_m, 3); c: (n_m,); the first n_el members are the cable elements.
    """
    n_m = c.size
    g = A.reshape(3, n_m, -1)  # (component, member, reaction)
    h = np.einsum("mk,kmr->mr", e, g)
    el = slice(0, n_el)
    Wq = g[:, el].transpose(1, 0, 2) * c[el, None, None]  # (n_el, 3, n_r): c g_r
    ei = e[n_el:]
    helper = np.where(np.abs(ei[:, :1]) < 0.9, [[1.0, 0.0, 0.0]], [[0.0, 1.0, 0.0]])
    t1 = np.cross(ei, helper)
    t1 /= np.linalg.norm(t1, axis=1)[:, None]
    t2 = np.cross(ei, t1)
    frame = np.stack([ei, t1, t2], axis=1)  # (n_s, 3, 3), rows e, t1, t2
    gi = g[:, n_el:]  # (3, n_s, n_r)
    ci = c[n_el:, None]
    Wi = np.stack([ci * np.einsum("sk,ksr->sr", t1, gi), ci * np.einsum("sk,ksr->sr", t2, gi), 0.5 * ci * h[n_el:]],
                  axis=1)  # (n_s, 3, n_r)
    W = np.concatenate([Wq.reshape(3 * n_el, -1), Wi.reshape(3 * (n_m - n_el), A.shape[1])])
    return W, frame




_AUTO = object()  # passes: the compiled kernel's when loaded and verified (kernel.second_order_passes)


def _passes(passes):
    if passes is _AUTO:
        from . import kernel

        return kernel.second_order_passes()
    return passes


def _dgemm(dgemm, fns):
    """scipy's dgemm (its address) for the compiled block loop, or None (no compiled passes, or
    the piece ``second_order_loop`` off)."""
    if fns is None:
        return None
    if dgemm is _AUTO:
        from . import kernel

        return kernel.second_order_dgemm()
    return dgemm


def _history(op: SecondOrder, fns, dgemm: int, m: int, U=None, T=None, loads=None, transposed=False) -> np.ndarray:
    """R_2 (m, n_r) by the compiled block loop (:func:`linecheck.core._loops.so_history`): the
    same blocks and chunks as :func:`_reactions`, P W by scipy's dgemm called from compiled code,
    without the GIL and the per-block Python calls; ``loads`` = (L, c, inv, dirs) of
    :func:`second_order_of_loads`."""
    W, nb = op.Wp, op.nb
    n_s = op.c.size - (op.n_nodes - 1)
    if loads is None:
        L, c, inv, dirs, y = np.zeros((1, 1)), np.zeros((1, 1)), np.zeros(1), np.zeros((1, 3)), np.zeros((1, nb))
    else:
        L, c, inv, dirs = loads
        y = np.empty((c.shape[1], nb))
    out = np.empty((m, W.shape[1]))
    fns.so_history(dgemm, loads is not None, transposed, np.zeros((1, 3)) if U is None else U,
                   np.zeros((1, 3, 3)) if T is None else np.ascontiguousarray(T, dtype=float), T is not None,
                   op.node_of_free, L, c, inv, np.zeros((1, 3)) if dirs is None else dirs, dirs is None, y,
                   np.empty_like(y), np.empty(nb), np.empty((L.shape[1], nb)), op.run_lo, op.run_hi, op.run_f0,
                   op.ins_nodes, op.ins_frame, op.ec, W, op.chunk, np.zeros((op.n_nodes, 3, nb)),
                   np.empty((n_s, 3, nb)), np.zeros((W.shape[0], nb), dtype=W.dtype), np.empty((5, nb)),
                   np.empty((op.chunk, W.shape[1]), dtype=W.dtype), out)
    return out


def second_order_reactions(op: SecondOrder, U: np.ndarray, T: np.ndarray | None = None, *, transposed: bool = False,
                           passes=_AUTO, dgemm=_AUTO) -> np.ndarray:
    """[N] R_2 at every tower for free displacements U [m], shape (m, n_dof) -> (m, n_r).

    With ``T`` (per-node bases as columns, (n_free_nodes, 3, 3)) U holds the components u~ in
    the node bases, u = T u~ node by node (the Newmark history of :mod:`.dynamics`).  With
    ``transposed`` U is given as its transpose (n_dof, m) (the compiled Newmark loop's dof-major
    history): the same result, read along its rows.

    R_2 = P W (:func:`reaction_form`), block by block of rows (:func:`_reactions`): the
    displacements go node-major into a preallocated (n_nodes, 3, rows) array (rotated by one
    batched 3x3 product per node), the members' second-order terms into P (transposed,
    (3 n_el + 3 n_s, rows)), and P W by BLAS.  With the optional compiled kernel (``passes``: the
    kernel's by default when its piece ``second_order`` is on, None for numpy) a block's
    elementwise work is three compiled calls (:func:`linecheck.core._loops.so_nodes`,
    ``so_frame``, ``so_products``), and with the piece ``second_order_loop`` (``dgemm``: scipy's
    dgemm address, the kernel's by default) the whole block loop is one compiled call
    (:func:`_history`, no GIL).  The forms agree within the kernel's tolerance
    (:data:`linecheck.core.kernel.RTOL`), not bit for bit.

    Rows are processed in blocks of a fixed size that depends on the operator only (the last
    block padded with zeros), so every BLAS product always has the same shape: a row's result
    does not depend on how many other rows (realizations) share the call, and results stay
    bit-identical (on one machine and code path) whatever the batch chunking.  The products are
    small enough for OpenBLAS to run on one thread (no thread start-up on a shared machine).
    """
    fns = _passes(passes)
    fp = _dgemm(dgemm, fns)
    m = U.shape[1] if transposed else U.shape[0]
    if fp is not None:
        return _history(op, fns, fp, m, U=np.ascontiguousarray(U, dtype=float), T=T, transposed=transposed)
    if fns is not None:
        return _reactions(op, m, _compiled_fill(op, fns, U, T, transposed), fns=fns)
    if transposed:
        U = U.T
    return _reactions(op, U.shape[0], _numpy_fill(op, U, T))


def _compiled_fill(op: SecondOrder, fns, U: np.ndarray, T: np.ndarray | None, transposed: bool):
    """The ``fill(u, i0, r)`` of :func:`_reactions` for U [m] (m, n_dof) (or (n_dof, m) when
    ``transposed``) in the node bases T (n_free_nodes, 3, 3) or global (None): the compiled
    ``so_nodes`` (``so_nodes_t``)."""
    Uc = np.ascontiguousarray(U, dtype=float)
    Tc = np.zeros((1, 3, 3)) if T is None else np.ascontiguousarray(T, dtype=float)

    def fill(u: np.ndarray, i0: int, r: int) -> None:
        if transposed:
            fns.so_nodes_t(Uc, i0, r, Tc, op.node_of_free, T is not None, u)
        else:
            fns.so_nodes(Uc[i0:i0 + r], r, Tc, op.node_of_free, T is not None, u)

    return fill


def _numpy_fill(op: SecondOrder, U: np.ndarray, T: np.ndarray | None):
    """The ``fill(u, i0, r)`` of :func:`_reactions` for U [m] (m, n_dof) in the node bases T
    (n_free_nodes, 3, 3) (u = T u~ node by node, one batched product per run of free nodes on a
    block padded with zero rows: the product keeps its shape) or global (None), numpy form."""
    n_f = U.shape[1] // 3
    pad = None

    def fill(u: np.ndarray, i0: int, r: int) -> None:
        nonlocal pad
        nb = u.shape[2]
        Ub = U[i0:i0 + r]
        if T is not None and r < nb:  # the batched product keeps its shape
            if pad is None:
                pad = np.zeros((nb, U.shape[1]))
            pad[:r] = Ub
            pad[r:] = 0.0
            Ub = pad
        Un = Ub.reshape(-1, n_f, 3).transpose(1, 2, 0)  # (n_free_nodes, 3, rows)
        for lo, hi, f0 in op.runs:  # free nodes in contiguous runs (slices, no fancy indexing)
            if T is None:
                u[lo:hi, :, :r] = Un[f0:f0 + hi - lo]
            else:  # u = T u~ node by node
                np.matmul(T[f0:f0 + hi - lo], Un[f0:f0 + hi - lo], out=u[lo:hi])
        if T is None and r < nb:
            u[:, :, r:] = 0.0

    return fill


def second_order_of_loads(op: SecondOrder, L: np.ndarray, c: np.ndarray, dirs: np.ndarray | None = None, *,
                          passes=_AUTO, dgemm=_AUTO) -> np.ndarray:
    """[N] R_2 of the quasi-static displacements u = K^-1 b of loads L [N], shape (m, n_free)
    -> (m, n_r): b the load of free node i along global y (``dirs`` None) or along dirs[i]
    ((n_free, 3), unit), K = U^T U with c [N/m] its upper band factor as ``dpbtrf`` returns it
    (kd + 1, n_dof).  As :func:`second_order_reactions` of the solved displacements: each block
    of rows is solved by the band (forward and back substitution over rows of lanes, ≈ 4 kd
    multiply-adds per dof and row instead of the n_free of a dense K^-1: LAPACK ``dpbtrs`` on all
    rows at once, or compiled as ``_loops.so_solve`` straight into the node-major work array); the
    rest of a block as there (``passes``, ``dgemm``)."""
    fns = _passes(passes)
    fp = _dgemm(dgemm, fns)
    c = np.ascontiguousarray(c, dtype=float)
    inv = 1.0 / c[-1]
    Dc = None if dirs is None else np.ascontiguousarray(dirs, dtype=float)
    if fp is not None:
        return _history(op, fns, fp, L.shape[0], loads=(np.ascontiguousarray(L, dtype=float), c, inv, Dc))
    n_dof = c.shape[1]
    if fns is not None:
        Lc = np.ascontiguousarray(L, dtype=float)
        D3 = np.zeros((1, 3)) if Dc is None else Dc
        y, xr, sc, Lt = np.empty((n_dof, op.nb)), np.empty((n_dof, op.nb)), np.empty(op.nb), np.empty((L.shape[1], op.nb))

        def fill(u: np.ndarray, i0: int, r: int) -> None:
            fns.so_solve(c, inv, Lc, D3, Dc is None, i0, r, y, xr, sc, Lt)
            fns.so_place(xr, op.run_lo, op.run_hi, op.run_f0, u)

        return _reactions(op, L.shape[0], fill, fns=fns)
    Y = np.zeros((n_dof, L.shape[0]))  # the right-hand sides of all rows, solved at once
    if Dc is None:
        Y[1::3] = L.T
    else:
        Y.reshape(-1, 3, L.shape[0])[...] = L.T[:, None, :] * Dc[:, :, None]
    Y = banded.solve(c, Y)  # column by column, each as if alone: a row's result is its own

    def fill(u: np.ndarray, i0: int, r: int) -> None:
        for lo, hi, f0 in op.runs:
            u[lo:hi, :, :r] = Y[3 * f0:3 * (f0 + hi - lo), i0:i0 + r].reshape(hi - lo, 3, r)
        if r < u.shape[2]:
            u[:, :, r:] = 0.0

    return _reactions(op, L.shape[0], fill)


def _reactions(op: SecondOrder, m: int, fill, fns=None) -> np.ndarray:
    """R_2 [N] (m, n_r) of m rows of displacements [m] that ``fill(u, i0, r)`` writes node-major
    into u[:, :, :r] (global x, y, z; (n_nodes, 3, nb)), zeroing u[:, :, r:] (docstrings above);
    ``fns`` the compiled passes or None (numpy: :func:`_products`).  Per block of nb rows the
    members' second-order terms go into P (3 n_el + 3 n_s, nb), then P W (W (3 n_el + 3 n_s,
    n_r)) in products of always ``chunk`` rows."""
    W, chunk, nb = op.Wp, op.chunk, op.nb
    n_s = op.c.size - (op.n_nodes - 1)
    u = np.zeros((op.n_nodes, 3, nb))  # pinned nodes stay zero
    P = np.zeros((W.shape[0], nb), dtype=W.dtype)  # padding columns stay zero
    li = np.empty((n_s, 3, nb))
    tmp = np.empty((chunk, W.shape[1]), dtype=W.dtype)
    work = _Work(op, P) if fns is None else np.empty((5, nb))
    out = np.empty((m, W.shape[1]))
    for i0 in range(0, m, nb):
        i1 = min(i0 + nb, m)
        r = i1 - i0
        fill(u, i0, r)
        if fns is not None:  # the same operations, compiled (_loops.so_frame, so_products)
            fns.so_frame(u, op.ins_nodes, op.ins_frame, li)
            fns.so_products(u, op.ec, li, P, work)
        else:
            _products(op, u, li, work)
        for j0 in range(0, r, chunk):  # P W in products of always chunk rows (a row's bits its own)
            np.matmul(P[:, j0:j0 + chunk].T, W, out=tmp)
            out[i0 + j0:min(i0 + j0 + chunk, i1)] = tmp[:min(chunk, r - j0)]
    return out


class _Work:
    """The numpy form's scratch for one block of nb rows (:func:`_products`): du (n_el, 3, nb),
    a, q, t, v (n_el, nb), the unit chords E[k] (n_el, 1), P's views Pq (n_el, 3, nb) (cable
    elements) and Pi (n_s, 3, nb) (insulators), and di, pi (n_s, 3, nb), sq (n_s, 2, nb)."""

    def __init__(self, op: SecondOrder, P: np.ndarray) -> None:
        nb = P.shape[1]
        n_el = op.n_nodes - 1
        n_s = op.c.size - n_el
        self.d = np.empty((n_el, 3, nb))
        self.a = np.empty((n_el, nb))
        self.q = np.empty((n_el, nb))
        self.t = np.empty((n_el, nb))
        self.v = np.empty((n_el, nb))
        self.E = [op.ec[:, k, None] for k in range(3)]  # (n_el, 1) each
        self.Pq = P[:3 * n_el].reshape(n_el, 3, nb)  # cable elements: a du + q e
        self.Pi = P[3 * n_el:].reshape(n_s, 3, nb)  # insulators: a s, a w, s^2 + w^2
        self.di = np.empty((n_s, 3, nb))
        self.sq = np.empty((n_s, 2, nb))
        self.pi = np.empty((n_s, 3, nb))


def _products(op: SecondOrder, u: np.ndarray, li: np.ndarray, w: _Work) -> None:
    """The members' second-order terms (:func:`reaction_form`) of one block of displacements u
    [m] (n_nodes, 3, nb) into P's views w.Pq, w.Pi, numpy form (as _loops.so_products): every
    cable element's a du + q e (du = u_b - u_a, a = e.du, q = |du|^2/2 - 3 a^2/2), every
    insulator's a s, a w, s^2 + w^2 of li = (a, s, w) (n_s, 3, nb), its end's displacement in
    its frame (the fixed point does not move)."""
    d, a, q, t, v, E = w.d, w.a, w.q, w.t, w.v, w.E
    np.subtract(u[1:], u[:-1], out=d)  # du = u_b - u_a
    np.multiply(d[:, 0], E[0], out=a)  # a = e.du
    np.multiply(d[:, 1], E[1], out=t)
    a += t
    np.multiply(d[:, 2], E[2], out=t)
    a += t
    np.multiply(d[:, 0], d[:, 0], out=q)  # q = |du|^2/2 - 3 a^2/2
    np.multiply(d[:, 1], d[:, 1], out=t)
    q += t
    np.multiply(d[:, 2], d[:, 2], out=t)
    q += t
    q *= 0.5
    np.multiply(a, a, out=t)
    t *= 1.5
    q -= t
    for k in range(3):  # a du + q e
        np.multiply(a, d[:, k], out=v)
        np.multiply(q, E[k], out=t)
        v += t
        w.Pq[:, k] = v
    np.take(u, op.ins_nodes, axis=0, out=w.di)  # insulators: the fixed point does not move
    np.matmul(op.ins_frame, w.di, out=li)  # (a, s, w) in the insulator's frame
    np.multiply(li[:, :1], li[:, 1:], out=w.pi[:, :2])  # a s, a w
    np.multiply(li[:, 1:], li[:, 1:], out=w.sq)
    np.add(w.sq[:, 0], w.sq[:, 1], out=w.pi[:, 2])  # s^2 + w^2
    w.Pi[...] = w.pi


# ---- the compiled kernel's pieces ``second_order`` and ``second_order_loop``
# (linecheck.core.kernel): their load checks

def _check_operator(rng) -> tuple[SecondOrder, np.ndarray]:
    """A second-order operator of random numbers for the load checks: 21 nodes, two runs of free
    nodes (nodes 0, 10 and 20 pinned), three insulators.  Returns it and the free node bases
    T (n_free, 3, 3)."""
    n_nodes, n_s, n_r = 21, 3, 7
    n_el = n_nodes - 1
    e = rng.standard_normal((n_el + n_s, 3))
    op = SecondOrder(
        e=(e / np.linalg.norm(e, axis=1)[:, None]).ravel(), c=np.ones(n_el + n_s), n_nodes=n_nodes,
        pinned=np.array([0, 10, 20]), runs=((1, 10, 0), (11, 20, 9)), ins_free=np.array([4, 10, 15]),
        A=np.zeros((3 * (n_el + n_s), n_r)), W=rng.standard_normal((3 * n_el + 3 * n_s, n_r)) * 1e3,
        ins_nodes=np.array([5, 12, 17]), ins_frame=np.linalg.qr(rng.standard_normal((n_s, 3, 3)))[0])
    return op, np.linalg.qr(rng.standard_normal((n_nodes - 3, 3, 3)))[0]


def _second_order_check(fns, dgemm: int | None = None) -> float:
    """The compiled second-order passes (``dgemm`` None) or the whole compiled block loop with
    scipy's ``dgemm`` (its address) against the numpy form, through
    :func:`second_order_reactions` (in node bases and global, the history row- and dof-major)
    and :func:`second_order_of_loads`, on an operator of random numbers with rows of zeros and a
    padded last block; the largest relative difference."""
    from . import kernel

    rng = np.random.default_rng(28)
    op, T = _check_operator(rng)
    n_free = T.shape[0]
    U = rng.standard_normal((300, 3 * n_free)) * 0.2
    U[[0, 7, 150]] = 0.0
    L = rng.standard_normal((150, n_free))
    L[[3, 90]] = 0.0
    kd, n = 5, 3 * n_free  # a banded stiffness's factor (dpbtrf, upper)
    ab = rng.uniform(-1.0, 1.0, (kd + 1, n)) * 1e3
    ab[kd] = 1e4 * (kd + 1) * (1.0 + rng.uniform(0.0, 1.0, n))
    c = lapack.dpbtrf(ab, lower=0)[0]
    dirs = rng.standard_normal((n_free, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    Ut = np.ascontiguousarray(U.T)  # the compiled Newmark loop's dof-major history
    pairs = []
    for t in (T, None):
        ref = second_order_reactions(op, U, t, passes=None, dgemm=None)
        pairs.append((ref, second_order_reactions(op, U, t, passes=fns, dgemm=dgemm)))
        pairs.append((ref, second_order_reactions(op, Ut, t, transposed=True, passes=fns, dgemm=dgemm)))
    for d in (None, dirs):
        ref = second_order_of_loads(op, L, c, d, passes=None, dgemm=None)
        pairs.append((ref, second_order_of_loads(op, L, c, d, passes=fns, dgemm=dgemm)))
    return kernel.worst_difference(pairs)


def _register_kernel_checks() -> None:
    from . import kernel

    kernel.register_check("second_order", _second_order_check)
    kernel.register_check("second_order_loop", lambda fns: _second_order_check(fns, fns.scipy_dgemm()))


_register_kernel_checks()
