"""The compiled loops of the second-order tension (:mod:`linecheck.core.second_order`): the
elementwise passes, the banded solves of loads and the whole block loop with scipy's ``dgemm``
called without the GIL (Numba functions at module level, re-exported by
:mod:`linecheck.core._loops`; what they compute and how they are checked:
:mod:`linecheck.core.kernel`)."""

from __future__ import annotations

import numba
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import get_cython_function_address, intrinsic

__all__ = ["scipy_dgemm", "so_frame", "so_history", "so_nodes", "so_nodes_t", "so_place", "so_products", "so_solve"]

# the second-order tension's passes (second_order._reactions): the 3 x 3 products as a
# multiply-add chain over k = 0, 1, 2, compiled with ``contract``
@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def so_nodes(U, r, T, node_of_free, rotate_, u):  # pragma: no cover - compiled
    """u[node, k, j] (n_nodes, 3, nb) of the free nodes from the rows j < r of U (m, 3 n_f):
    (T[f] @ U[j, 3f:3f + 3])[k] with ``rotate_``, else U[j, 3f + k]; zero for j >= r."""
    nb = u.shape[2]
    for f in range(node_of_free.size):
        node = node_of_free[f]
        for k in range(3):
            row = u[node, k]
            if rotate_:
                t0 = T[f, k, 0]
                t1 = T[f, k, 1]
                t2 = T[f, k, 2]
                for j in range(r):
                    acc = 0.0 + t0 * U[j, 3 * f]
                    acc = acc + t1 * U[j, 3 * f + 1]
                    acc = acc + t2 * U[j, 3 * f + 2]
                    row[j] = acc + 0.0
            else:
                for j in range(r):
                    row[j] = U[j, 3 * f + k]
            for j in range(r, nb):
                row[j] = 0.0


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def so_nodes_t(U, i0, r, T, node_of_free, rotate_, u):  # pragma: no cover - compiled
    """so_nodes of the rows i0 <= j < i0 + r stored as columns, U (3 n_f, m) (the compiled Newmark
    loop's dof-major history): the same values, the same fused chain, read along the rows (of a
    column slice: indexing U[., i0 + j] ran 2.3x slower, measured)."""
    nb = u.shape[2]
    Ub = U[:, i0:i0 + r]
    for f in range(node_of_free.size):
        node = node_of_free[f]
        for k in range(3):
            if rotate_:
                t0 = T[f, k, 0]
                t1 = T[f, k, 1]
                t2 = T[f, k, 2]
                for j in range(r):
                    acc = 0.0 + t0 * Ub[3 * f, j]
                    acc = acc + t1 * Ub[3 * f + 1, j]
                    acc = acc + t2 * Ub[3 * f + 2, j]
                    u[node, k, j] = acc + 0.0
            else:
                for j in range(r):
                    u[node, k, j] = Ub[3 * f + k, j]
            for j in range(r, nb):
                u[node, k, j] = 0.0


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def so_frame(u, ins_nodes, frame, li):  # pragma: no cover - compiled
    """li[s] (3, nb) = frame[s] (3 x 3) @ u[ins_nodes[s]] (3, nb), dgemm's chain (above)."""
    nb = u.shape[2]
    for s in range(ins_nodes.size):
        x = u[ins_nodes[s]]
        for k in range(3):
            f0 = frame[s, k, 0]
            f1 = frame[s, k, 1]
            f2 = frame[s, k, 2]
            for j in range(nb):
                acc = 0.0 + f0 * x[0, j]
                acc = acc + f1 * x[1, j]
                acc = acc + f2 * x[2, j]
                li[s, k, j] = acc + 0.0


@numba.njit(cache=True, nogil=True)
def so_products(u, ec, li, P, d):  # pragma: no cover - compiled
    """P (3 n_el + 3 n_s, nb) of second_order._reactions: every cable element's second-order
    force per unit c, a d + q e (d = u[e + 1] - u[e], a = e.d, q = |d|^2/2 - 3 a^2/2; ec (n_el, 3)
    the unit chords), every insulator's a s, a w, s^2 + w^2 from li = (a, s, w); each product
    and sum rounded by itself, in float64.  d: scratch (5, nb)
    for d, a and q: one output row per loop vectorises (a loop writing three rows did not: too
    many possible overlaps for LLVM's run-time checks; measured 2.5x)."""
    n_el = u.shape[0] - 1
    nb = u.shape[2]
    d0 = d[0]
    d1 = d[1]
    d2 = d[2]
    a = d[3]
    q = d[4]
    for e in range(n_el):
        e0 = ec[e, 0]
        e1 = ec[e, 1]
        e2 = ec[e, 2]
        for c in range(3):
            ua = u[e, c]
            ub = u[e + 1, c]
            dc = d[c]
            for j in range(nb):
                dc[j] = ub[j] - ua[j]
        for j in range(nb):
            a[j] = d0[j] * e0 + d1[j] * e1 + d2[j] * e2
        for j in range(nb):
            q[j] = 0.5 * (d0[j] * d0[j] + d1[j] * d1[j] + d2[j] * d2[j]) - 1.5 * (a[j] * a[j])
        p = P[3 * e]
        for j in range(nb):
            p[j] = a[j] * d0[j] + q[j] * e0
        p = P[3 * e + 1]
        for j in range(nb):
            p[j] = a[j] * d1[j] + q[j] * e1
        p = P[3 * e + 2]
        for j in range(nb):
            p[j] = a[j] * d2[j] + q[j] * e2
    b0 = 3 * n_el
    for s in range(li.shape[0]):
        b = b0 + 3 * s
        for j in range(nb):
            P[b, j] = li[s, 0, j] * li[s, 1, j]
        for j in range(nb):
            P[b + 1, j] = li[s, 0, j] * li[s, 2, j]
        for j in range(nb):
            P[b + 2, j] = li[s, 1, j] * li[s, 1, j] + li[s, 2, j] * li[s, 2, j]


@numba.njit(cache=True, nogil=True)
def _rhs(Lt, dirs, straight, j, y):  # pragma: no cover - compiled
    """Row j of the right-hand sides into y[j]: load i = j // 3 of Lt (n_free, nb) along global
    y (``straight``) or along dirs[i], as second_order.second_order_of_loads places them."""
    i = j // 3
    q = j - 3 * i
    nb = y.shape[1]
    if straight:
        if q == 1:
            for l in range(nb):
                y[j, l] = Lt[i, l]
        else:
            for l in range(nb):
                y[j, l] = 0.0
    else:
        dq = dirs[i, q]
        for l in range(nb):
            y[j, l] = Lt[i, l] * dq


@numba.njit(cache=True, nogil=True)
def _loads_to_lanes(L, i0, r, Lt):  # pragma: no cover - compiled
    """Lt[i, j] (n_free, nb) = L[i0 + j, i] [N] for the lanes j < r, zero for j >= r (row by
    row: 1.6x faster than in tiles, measured)."""
    nb = Lt.shape[1]
    nf = L.shape[1]
    Lb = L[i0:i0 + r]
    for j in range(r):
        for i in range(nf):
            Lt[i, j] = Lb[j, i]
    for i in range(nf):
        for j in range(r, nb):
            Lt[i, j] = 0.0


@numba.njit(cache=True, nogil=True)
def _forward_rows(c, inv, Lt, dirs, straight, j5, y, s):  # pragma: no cover - compiled
    """U^T y = b for the rows j < j5 (n_dof, nb): each row's right-hand side placed by
    :func:`_rhs`, the band's sum over its k = min(j, kd) earlier rows accumulated in s (nb,)."""
    kd = c.shape[0] - 1
    nb = y.shape[1]
    for j in range(j5):
        _rhs(Lt, dirs, straight, j, y)
        k = min(j, kd)
        w = inv[j]
        if k > 0:
            cij = c[kd - k, j]
            for l in range(nb):
                s[l] = cij * y[j - k, l]
            for t in range(1, k):
                cij = c[kd - k + t, j]
                for l in range(nb):
                    s[l] = s[l] + cij * y[j - k + t, l]
            for l in range(nb):
                y[j, l] = (y[j, l] - s[l]) * w
        else:
            for l in range(nb):
                y[j, l] = y[j, l] * w


@numba.njit(cache=True, nogil=True)
def _forward_rows_5(c, inv, Lt, dirs, straight, j5, y):  # pragma: no cover - compiled
    """U^T y = b for the rows j >= j5 of a half-bandwidth 5 (y (n_dof, nb)): the band's sum in a
    register, the load of row j (:func:`_rhs`'s) placed in the same pass (no zeroed right-hand
    side)."""
    n = c.shape[1]
    nb = y.shape[1]
    for j in range(j5, n):
        c0 = c[0, j]
        c1 = c[1, j]
        c2 = c[2, j]
        c3 = c[3, j]
        c4 = c[4, j]
        w = inv[j]
        i = j // 3
        q = j - 3 * i
        if not straight:
            dq = dirs[i, q]
            for l in range(nb):
                y[j, l] = (Lt[i, l] * dq - (c0 * y[j - 5, l] + c1 * y[j - 4, l] + c2 * y[j - 3, l] + c3 * y[j - 2, l]
                                            + c4 * y[j - 1, l])) * w
        elif q == 1:
            for l in range(nb):
                y[j, l] = (Lt[i, l] - (c0 * y[j - 5, l] + c1 * y[j - 4, l] + c2 * y[j - 3, l] + c3 * y[j - 2, l]
                                       + c4 * y[j - 1, l])) * w
        else:
            for l in range(nb):
                y[j, l] = (0.0 - (c0 * y[j - 5, l] + c1 * y[j - 4, l] + c2 * y[j - 3, l] + c3 * y[j - 2, l]
                                  + c4 * y[j - 1, l])) * w


@numba.njit(cache=True, nogil=True)
def _back_rows(c, inv, y, jb5, xr, s):  # pragma: no cover - compiled
    """U x = y for the last rows j = n - 1 - jr, jr < jb5, into xr[jr] (n_dof, nb): the band's
    sum over the k = min(jr, kd) rows below accumulated in s (nb,)."""
    kd = c.shape[0] - 1
    n = c.shape[1]
    nb = y.shape[1]
    for jr in range(jb5):
        j = n - 1 - jr
        k = min(jr, kd)
        w = inv[j]
        if k > 0:
            cji = c[kd - 1, j + 1]
            for l in range(nb):
                s[l] = cji * xr[jr - 1, l]
            for t in range(2, k + 1):
                cji = c[kd - t, j + t]
                for l in range(nb):
                    s[l] = s[l] + cji * xr[jr - t, l]
            for l in range(nb):
                xr[jr, l] = (y[j, l] - s[l]) * w
        else:
            for l in range(nb):
                xr[jr, l] = y[j, l] * w


@numba.njit(cache=True, nogil=True)
def _back_rows_5(c, inv, y, jb5, xr):  # pragma: no cover - compiled
    """U x = y for the rows j = n - 1 - jr, jr >= jb5, of a half-bandwidth 5, into xr[jr]
    (n_dof, nb), the band's sum in a register: written upward, reading the rows of xr just
    written below (reading the rows above in place ran 2x slower, measured)."""
    n = c.shape[1]
    nb = y.shape[1]
    for jr in range(jb5, n):
        j = n - 1 - jr
        c0 = c[4, j + 1]
        c1 = c[3, j + 2]
        c2 = c[2, j + 3]
        c3 = c[1, j + 4]
        c4 = c[0, j + 5]
        w = inv[j]
        for l in range(nb):
            xr[jr, l] = (y[j, l] - (c0 * xr[jr - 1, l] + c1 * xr[jr - 2, l] + c2 * xr[jr - 3, l] + c3 * xr[jr - 4, l]
                                    + c4 * xr[jr - 5, l])) * w


@numba.njit(cache=True, nogil=True)
def so_solve(c, inv, L, dirs, straight, i0, r, y, xr, s, Lt):  # pragma: no cover - compiled
    """The quasi-static displacements [m] of the load rows i0 <= i < i0 + r of L [N]
    (m, n_free), lane j = row i0 + j (lanes >= r solve zeros): the right-hand sides (global y,
    or along ``dirs`` (n_free, 3) when not ``straight``), then U^T U x = b by rows of lanes (c the
    upper band of dpbtrf, inv = 1 / its diagonal); x returned in xr (n_dof, nb) in reversed row
    order, xr[n - 1 - j] = x_j (the algorithm of LAPACK dpbtrs, which the numpy form calls; no
    contraction).  y (n_dof, nb), s (nb,), Lt (n_free, nb): scratch.

    Speed (measured when written): with the core's half-bandwidth (5) the rows past the first
    five take the register form (:func:`_forward_rows_5`, :func:`_back_rows_5`), split off by loop
    bounds rather than a flag around the loop (it did not vectorise: 2.8x); 2-D indexing (row
    views kept LLVM's overlap checks: 3x slower)."""
    kd = c.shape[0] - 1
    n = c.shape[1]
    _loads_to_lanes(L, i0, r, Lt)
    j5 = 5 if kd == 5 and n > 5 else n  # the rows j >= j5 forward, n - 1 - j >= jb5 back: register form
    jb5 = 5 if j5 < n else n
    _forward_rows(c, inv, Lt, dirs, straight, j5, y, s)
    _forward_rows_5(c, inv, Lt, dirs, straight, j5, y)
    _back_rows(c, inv, y, jb5, xr, s)
    _back_rows_5(c, inv, y, jb5, xr)


def scipy_dgemm() -> int | None:
    """The address of scipy's Fortran ``dgemm`` (``scipy.linalg.cython_blas``, 32-bit integer
    sizes: the interface scipy documents for it), or None when that module or an LP64 ``dgemm``
    is not found.  :func:`so_history` calls it from compiled code, without the GIL."""
    try:
        from scipy.linalg import cython_blas
    except ImportError:  # pragma: no cover - scipy always ships it
        return None
    capsule = cython_blas.__pyx_capi__.get("dgemm")
    if capsule is None or "int *" not in str(capsule) or "int64" in str(capsule):  # pragma: no cover
        return None
    return int(get_cython_function_address("scipy.linalg.cython_blas", "dgemm"))


@intrinsic
def _dgemm_nt(typingctx, fp, m, n, k, a, lda, b, ldb, c, ldc):  # pragma: no cover - compiled
    """Fortran dgemm('N', 'T', m, n, k, 1.0, a, lda, b, ldb, 0.0, c, ldc) through its address
    ``fp`` (:func:`scipy_dgemm`; every argument by reference, sizes as 32-bit integers): column-
    major C (m, n) = A (m, k) B (n, k)^T."""
    sig = types.void(types.intp, types.int64, types.int64, types.int64, types.voidptr, types.int64,
                     types.voidptr, types.int64, types.voidptr, types.int64)

    def codegen(context, builder, signature, args):
        i8, i32, f64 = ir.IntType(8), ir.IntType(32), ir.DoubleType()
        p8, p32, pf = i8.as_pointer(), i32.as_pointer(), f64.as_pointer()
        fnty = ir.FunctionType(ir.VoidType(), [p8, p8, p32, p32, p32, pf, pf, p32, pf, p32, pf, pf, p32])
        fn = builder.inttoptr(args[0], fnty.as_pointer())

        def ref(ty, value):  # a stack slot holding value (allocated once, in the entry block)
            slot = cgutils.alloca_once(builder, ty)
            builder.store(value, slot)
            return slot

        def size(v):
            return ref(i32, builder.trunc(v, i32))

        builder.call(fn, [ref(i8, ir.Constant(i8, ord("N"))), ref(i8, ir.Constant(i8, ord("T"))),
                          size(args[1]), size(args[2]), size(args[3]), ref(f64, ir.Constant(f64, 1.0)),
                          builder.bitcast(args[4], pf), size(args[5]), builder.bitcast(args[6], pf), size(args[7]),
                          ref(f64, ir.Constant(f64, 0.0)), builder.bitcast(args[8], pf), size(args[9])])
        return context.get_dummy_value()

    return sig, codegen


@numba.njit(cache=True, nogil=True)
def so_place(xr, run_lo, run_hi, run_f0, u):  # pragma: no cover - compiled
    """u[node, k] (n_nodes, 3, nb) of the free nodes from so_solve's xr (reversed rows: dof
    3 f + k of free node f is row n_dof - 1 - 3 f - k), run by run of free nodes."""
    n = xr.shape[0]
    nb = xr.shape[1]
    for g in range(run_lo.size):
        for a in range(run_hi[g] - run_lo[g]):
            for k in range(3):
                src = xr[n - 1 - 3 * (run_f0[g] + a) - k]
                dst = u[run_lo[g] + a, k]
                for j in range(nb):
                    dst[j] = src[j]


@numba.njit(cache=True, nogil=True)
def so_history(fp, of_loads, transposed, U, T, rotate_, node_of_free, L, c, inv, dirs, straight, y, xr, sc, Lt,
               run_lo, run_hi, run_f0, ins_nodes, frame, ec, W, chunk, u, li, P, d, tmp, out):  # pragma: no cover - compiled
    """second_order._reactions in one call: per block of nb = u.shape[2] rows the displacements
    (``of_loads``: so_solve of the block's loads, placed run by run of free nodes by so_place; else
    so_nodes of U, or so_nodes_t of U's columns when ``transposed``), so_frame, so_products and
    P W by the dgemm at ``fp`` (scipy's, :func:`scipy_dgemm`) in ``chunk``-row products into tmp
    ((chunk, n_r)), copied into out: every product has the same shape, so a row's result does not
    depend on the other rows of its block."""
    m = out.shape[0]
    nb = u.shape[2]
    nr = W.shape[1]
    npw = W.shape[0]
    for i0 in range(0, m, nb):
        i1 = min(i0 + nb, m)
        r = i1 - i0
        if transposed:
            so_nodes_t(U, i0, r, T, node_of_free, rotate_, u)
        elif not of_loads:
            so_nodes(U[i0:i1], r, T, node_of_free, rotate_, u)
        else:
            so_solve(c, inv, L, dirs, straight, i0, r, y, xr, sc, Lt)
            so_place(xr, run_lo, run_hi, run_f0, u)
        so_frame(u, ins_nodes, frame, li)
        so_products(u, ec, li, P, d)
        for j0 in range(0, r, chunk):  # P W by dgemm in chunk-row products (always that shape) into tmp
            _dgemm_nt(fp, nr, chunk, npw, W.ctypes.data, nr, P[:, j0:].ctypes.data, nb, tmp.ctypes.data, nr)
            for q in range(min(chunk, r - j0)):
                for cc in range(nr):
                    out[i0 + j0 + q, cc] = tmp[q, cc]
