"""The compiled loops of the optional kernel: Numba functions at module level.

Imported only by :mod:`linecheck.core.kernel` when a piece of the kernel is first asked for (the
rest of the core imports numpy and scipy only; tests/test_import_boundary.py).  The functions are
module-level so that Numba's on-disk cache (``cache=True``) can key them: a function that calls
other jitted functions through closure cells gets a new cache key in every process (the cells are
pickled by identity) and was recompiled every time.  What the loops compute, and how they are
checked against the numpy forms (a tolerance, not bits), is documented in
:mod:`linecheck.core.kernel`.  Where two loops here serve the same realization in different
groupings (one vector or four lanes), they run the same operations in the same order, so a
realization's bits do not depend on the grouping (determinism across chunking and ``--jobs``).

This module holds the Newmark step loops, the banded solves, the change of node bases, step 3's
static transfer, the span-tension integrands and the statistics' reductions; the wind's loops
(:mod:`linecheck.core._loops_wind`) and the second-order tension's
(:mod:`linecheck.core._loops_second_order`) are re-exported here: the kernel reads one namespace."""

from __future__ import annotations

import numba
import numpy as np

from ._loops_second_order import (
    scipy_dgemm,
    so_frame,
    so_history,
    so_nodes,
    so_nodes_t,
    so_place,
    so_products,
    so_solve,
)
from ._loops_wind import coherent_spectrum, drag_loads, field_radius, field_velocity, mix_wires, phasors, quad_kms

__all__ = ["background", "band_solve", "band_solve_1", "coherent_spectrum", "drag_loads",
           "field_radius", "field_velocity", "from_lanes", "history_reductions", "mix_wires", "phasors",
           "quad_kms", "reactions_into", "rest_product", "rotate", "rowdot", "scipy_dgemm",
           "so_frame", "so_history", "so_nodes", "so_nodes_t", "so_place", "so_products",
           "so_solve", "solve_columns", "span_terms", "steps", "steps_1", "to_lanes"]


# the banded triangular solves (LAPACK dpbtrs' algorithm: a dot product per row, then an axpy
# per column), with contraction (fused multiply-adds where LLVM finds them).
# x is (n_groups, n_dof, 4): the realizations in groups of four lanes (padded with zeros),
# every lane solved by itself in the same order; four independent chains per group hide the
# latency of the dependent divide and multiply-adds (LLVM keeps the lanes scalar; measured:
# four lanes cost ≈ 1.4 x one)
@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def band_solve(c, x):  # pragma: no cover - compiled
    """Solve U^T U x = b in place for every lane of x (n_groups, n, 4); U upper band,
    c[kd + i - j, j] = U[i, j]."""
    kd = c.shape[0] - 1
    n = c.shape[1]
    for g in range(x.shape[0]):
        y = x[g]
        for j in range(n):  # U^T y = b: dtbsv('U', 'T', 'N'), a dot product per row
            k = min(j, kd)
            s0 = 0.0
            s1 = 0.0
            s2 = 0.0
            s3 = 0.0
            for t in range(k):
                i = j - k + t
                cij = c[kd + i - j, j]
                s0 += cij * y[i, 0]
                s1 += cij * y[i, 1]
                s2 += cij * y[i, 2]
                s3 += cij * y[i, 3]
            cjj = c[kd, j]
            y[j, 0] = (y[j, 0] - s0) / cjj
            y[j, 1] = (y[j, 1] - s1) / cjj
            y[j, 2] = (y[j, 2] - s2) / cjj
            y[j, 3] = (y[j, 3] - s3) / cjj
        for j in range(n - 1, -1, -1):  # U x = y: dtbsv('U', 'N', 'N'), an axpy per column
            cjj = c[kd, j]
            x0 = y[j, 0] / cjj
            x1 = y[j, 1] / cjj
            x2 = y[j, 2] / cjj
            x3 = y[j, 3] / cjj
            y[j, 0] = x0
            y[j, 1] = x1
            y[j, 2] = x2
            y[j, 3] = x3
            k = min(j, kd)
            for t in range(k):
                i = j - k + t
                cij = c[kd + i - j, j]
                y[i, 0] += -x0 * cij
                y[i, 1] += -x1 * cij
                y[i, 2] += -x2 * cij
                y[i, 3] += -x3 * cij


@numba.njit(cache=True, nogil=True)
def to_lanes(X):  # pragma: no cover - compiled
    """Rows of X (m, n) as lanes (n_groups, n, 4): row r is lane r % 4 of group r // 4
    (padding lanes zero)."""
    m, n = X.shape
    x = np.zeros(((m + 3) // 4, n, 4))
    for r in range(m):
        for d in range(n):
            x[r // 4, d, r % 4] = X[r, d]
    return x


@numba.njit(cache=True, nogil=True)
def from_lanes(x, X):  # pragma: no cover - compiled
    """The inverse of :func:`to_lanes`, into X (m, n)."""
    m, n = X.shape
    for r in range(m):
        for d in range(n):
            X[r, d] = x[r // 4, d, r % 4]


@numba.njit(cache=True, nogil=True)
def reactions_into(u, nz, GT, cols, Rr):  # pragma: no cover - compiled
    """Rr (n_r,) = G u, summed coordinate by coordinate from zero over the columns
    [cols[q, 0], cols[q, 1]) of GT's row q (the order of dynamics._sparse_reactions)."""
    Rr[:] = 0.0
    for q in range(nz.size):
        x = u[nz[q]]
        for k in range(cols[q, 0], cols[q, 1]):
            Rr[k] += x * GT[q, k]


@numba.njit(cache=True, nogil=True)
def solve_columns(c, B):  # pragma: no cover - compiled
    """dpbtrs on every column of B (n, m) in place, four columns at a time."""
    x = to_lanes(B.T)
    band_solve(c, x)
    from_lanes(x, B.T)


@numba.njit(cache=True, nogil=True)
def background(c, L, dirs, straight, nz, GT, cols, R):  # pragma: no cover - compiled
    """Step 3 of a long line for rows of loads L (m, n_free): K u = loads (global y, or along
    ``dirs`` (n_free, 3) when not ``straight``), solved four rows at a time, and R (m, n_r)
    = G u summed coordinate by coordinate from zero (dynamics._sparse_reactions' order)."""
    m, n_free = L.shape
    n = c.shape[1]
    G = (m + 3) // 4
    x = np.zeros((G, n, 4))
    for r in range(m):
        g, l = r // 4, r % 4
        for i in range(n_free):
            f = L[r, i]
            if straight:
                x[g, 3 * i + 1, l] = f
            else:
                for q in range(3):
                    x[g, 3 * i + q, l] = f * dirs[i, q]
    band_solve(c, x)
    for r in range(m):
        reactions_into(x[r // 4, :, r % 4], nz, GT, cols, R[r])


@numba.njit(cache=True, nogil=True, fastmath={"contract"}, inline="always")
def _band_solve_1_rows(c, x):  # pragma: no cover - compiled
    """:func:`band_solve_1` of any half-bandwidth kd = c.shape[0] - 1, x (n,) in place: a dot
    product per row forward, an axpy per column back (:func:`band_solve`'s loops, one lane)."""
    kd = c.shape[0] - 1
    n = c.shape[1]
    for j in range(n):
        k = min(j, kd)
        s0 = 0.0
        for t in range(k):
            i = j - k + t
            s0 += c[kd + i - j, j] * x[i]
        x[j] = (x[j] - s0) / c[kd, j]
    for j in range(n - 1, -1, -1):
        x0 = x[j] / c[kd, j]
        x[j] = x0
        k = min(j, kd)
        for t in range(k):
            i = j - k + t
            x[i] += -x0 * c[kd + i - j, j]


@numba.njit(cache=True, nogil=True, fastmath={"contract"}, inline="always")
def _forward_5(c, x):  # pragma: no cover - compiled
    """U^T y = b in place, x (n,) with n >= 6, half-bandwidth 5: the first five rows read fewer
    unknowns; then r_m = y[j - m] rolled along the rows in registers."""
    n = c.shape[1]
    for j in range(5):
        s0 = 0.0
        for t in range(j):
            s0 += c[5 + t - j, j] * x[t]
        x[j] = (x[j] - s0) / c[5, j]
    r1 = x[4]
    r2 = x[3]
    r3 = x[2]
    r4 = x[1]
    r5 = x[0]
    for j in range(5, n):
        s0 = 0.0
        s0 += c[0, j] * r5
        s0 += c[1, j] * r4
        s0 += c[2, j] * r3
        s0 += c[3, j] * r2
        s0 += c[4, j] * r1
        yj = (x[j] - s0) / c[5, j]
        x[j] = yj
        r5 = r4
        r4 = r3
        r3 = r2
        r2 = r1
        r1 = yj


@numba.njit(cache=True, nogil=True, fastmath={"contract"}, inline="always")
def _back_5(c, x):  # pragma: no cover - compiled
    """U x = y in place, x (n,) with n >= 6, half-bandwidth 5: q_m holds y[j - m] with the
    updates of the columns after j (in the same order), rolled in registers; the first five
    rows as in :func:`_band_solve_1_rows`."""
    n = c.shape[1]
    q0 = x[n - 1]
    q1 = x[n - 2]
    q2 = x[n - 3]
    q3 = x[n - 4]
    q4 = x[n - 5]
    for j in range(n - 1, 4, -1):
        x0 = q0 / c[5, j]
        x[j] = x0
        q5 = x[j - 5]
        q5 += -x0 * c[0, j]
        q4 += -x0 * c[1, j]
        q3 += -x0 * c[2, j]
        q2 += -x0 * c[3, j]
        q1 += -x0 * c[4, j]
        q0 = q1
        q1 = q2
        q2 = q3
        q3 = q4
        q4 = q5
    x[4] = q0
    x[3] = q1
    x[2] = q2
    x[1] = q3
    x[0] = q4
    for j in range(4, -1, -1):
        x0 = x[j] / c[5, j]
        x[j] = x0
        for t in range(j):
            x[t] += -x0 * c[5 + t - j, j]


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def band_solve_1(c, x):  # pragma: no cover - compiled
    """:func:`band_solve` for one vector x (n,) (one realization: no lanes).

    With the core's half-bandwidth (5) the five unknowns a row reads stay in registers (rolled
    along the rows: :func:`_forward_5`, :func:`_back_5`) instead of being stored and loaded again
    at every row: the same operations in the same order (the same bits), without the
    store-to-load latency on the dependent chain (measured ≈ 6 → 3.5 µs for 177 DOFs)."""
    if c.shape[0] != 6 or c.shape[1] < 6:
        _band_solve_1_rows(c, x)
        return
    _forward_5(c, x)
    _back_5(c, x)


@numba.njit(cache=True, nogil=True)
def rest_product(band, wp, t):  # pragma: no cover - compiled
    """t (L, n) = C~_off w for L vectors w: the structural-damping remainder by its diagonals,
    band (2 h + 1, n) with band[o, d] = C~_off[d, d + o - h] (zero outside the matrix and where
    the CSR arrays have no entry), wp (L, n + 2 h) the vectors with h zeros on either side.
    Each row is summed from 0 over its columns ascending, as scipy's ``csr_matvecs`` sums the
    CSR row; the extra terms are products with an exact zero, which leave a sum unchanged
    (x + ±0 = x, and +0 + ±0 = +0): the same bits, but the rows' sums run side by side
    (vectorised over the rows) instead of one dependent chain after the other (177 DOFs: one
    vector measured ≈ 4 → 0.6 µs)."""
    n = t.shape[1]
    t[:, :] = 0.0
    for l in range(t.shape[0]):
        tl = t[l]
        wl = wp[l]
        for o in range(band.shape[0]):
            bo = band[o]
            for d in range(n):
                tl[d] += bo[d] * wl[d + o]


@numba.njit(cache=True, nogil=True)
def steps_1(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, has_rest, band, a1,
            out, nz, GT, cols, R):  # pragma: no cover - compiled
    """:func:`steps` for one realization (U, V, A of shape (1, n_dof)): plain vectors."""
    n_b, _, n_free = loads.shape
    keep = out.shape[1] > 0  # the states after every step, for the second-order tension (dof-major)
    n = U.shape[1]
    u = U[0]
    v = V[0]
    a = A[0]
    b = np.empty(n)
    h = (band.shape[0] - 1) // 2
    w = np.zeros((1, n + 2 * h))  # a1 u + v, zero-padded (rest_product)
    t = np.empty((1, n))
    for k in range(n_b):
        for i in range(n_free):
            f = loads[k, 0, i]
            for q in range(3):
                d = 3 * i + q
                b[d] = ((cu[d] * u[d] + cv[d] * v[d]) + dm[d] * a[d]) + f * ycoef[i, q]
        if has_rest:
            for d in range(n):
                w[0, h + d] = a1 * u[d] + v[d]
            rest_product(band, w, t)
            for d in range(n):
                b[d] += t[0, d]
        band_solve_1(chat, b)
        for d in range(n):
            vn = (b[d] - u[d]) * r2 - v[d]
            a[d] = (vn - v[d]) * r2 - a[d]
            v[d] = vn
            u[d] = b[d]
            if keep:
                out[d, k] = b[d]
        reactions_into(u, nz, GT, cols, R[k, 0])


@numba.njit(cache=True, nogil=True)
def _newmark_rhs(loads_k, g, ycoef, cu, cv, dm, ug, vg, ag, bg, f, has_rest, band, a1, w, t):  # pragma: no cover - compiled
    """The right-hand side bg (n_dof, 4) [N] of group g's four lanes for one step: (cu u + cv v)
    + dm a + F, F = load x ycoef (the numpy loop's Fb; loads_k (n_real, n_free) [N], lanes past
    n_real load-free), plus C~_off (a1 u + v) with ``has_rest`` (csr_matvecs' bits:
    :func:`rest_product`).  ug, vg, ag (n_dof, 4) the lanes' state; f (4,), w (4, n_dof + 2 h),
    t (4, n_dof): scratch."""
    m, n_free = loads_k.shape
    n = ug.shape[0]
    h = (band.shape[0] - 1) // 2
    for i in range(n_free):
        for l in range(4):
            r = 4 * g + l
            f[l] = loads_k[r, i] if r < m else 0.0
        for q in range(3):
            d = 3 * i + q
            yc = ycoef[i, q]
            for l in range(4):
                bg[d, l] = ((cu[d] * ug[d, l] + cv[d] * vg[d, l]) + dm[d] * ag[d, l]) + f[l] * yc
    if has_rest:
        for d in range(n):
            for l in range(4):
                w[l, h + d] = a1 * ug[d, l] + vg[d, l]
        rest_product(band, w, t)
        for d in range(n):
            for l in range(4):
                bg[d, l] += t[l, d]


@numba.njit(cache=True, nogil=True)
def _newmark_update(ug, vg, ag, bg, r2):  # pragma: no cover - compiled
    """The new state of four lanes (n_dof, 4) in place from the solved u' = bg [m]:
    v' = (u' - u) 2/dt - v, a' = (v' - v) 2/dt - a (r2 = 2/dt [1/s])."""
    for d in range(ug.shape[0]):
        for l in range(4):
            vn = (bg[d, l] - ug[d, l]) * r2 - vg[d, l]
            ag[d, l] = (vn - vg[d, l]) * r2 - ag[d, l]
            vg[d, l] = vn
            ug[d, l] = bg[d, l]


@numba.njit(cache=True, nogil=True)
def _keep_states(u, c0, m, out):  # pragma: no cover - compiled
    """u of the m realizations (lanes (n_groups, n_dof, 4)) into out[:, c0:c0 + m] (dof-major: a
    row's m values at once)."""
    for d in range(u.shape[1]):
        for r in range(m):
            out[d, c0 + r] = u[r // 4, d, r % 4]


@numba.njit(cache=True, nogil=True)
def steps(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, has_rest, band, a1,
          out, nz, GT, cols, R):  # pragma: no cover - compiled
    """Newmark steps of one block; U, V, A updated in place.

    U, V, A (n_real, n_dof) rotated state; loads (n_b, n_real, n_free) [N]; ycoef
    (n_free, 3); out (n_dof, >= n_b n_real) receives u after every step, dof-major (column
    k n_real + r: realization r after step k; not written when out has no columns: only the
    second-order tension reads it, second_order_reactions(transposed=True)); R (n_b, n_real, n_r)
    the reactions G u, summed coordinate by coordinate from zero over the columns
    [cols[i, 0], cols[i, 1]) of GT's row i (the order of dynamics._sparse_reactions)."""
    n_b, m = loads.shape[:2]
    keep = out.shape[1] > 0  # the states after every step, for the second-order tension
    n = U.shape[1]
    u = to_lanes(U)  # lane l of group g is realization 4 g + l (padding lanes stay 0)
    v = to_lanes(V)
    a = to_lanes(A)
    G = u.shape[0]
    b = np.zeros((G, n, 4))
    h = (band.shape[0] - 1) // 2
    w = np.zeros((4, n + 2 * h))  # a1 u + v of the four lanes, zero-padded (rest_product)
    t = np.zeros((4, n))
    f = np.zeros(4)
    for k in range(n_b):
        for g in range(G):
            _newmark_rhs(loads[k], g, ycoef, cu, cv, dm, u[g], v[g], a[g], b[g], f, has_rest, band, a1, w, t)
        band_solve(chat, b)
        for g in range(G):
            _newmark_update(u[g], v[g], a[g], b[g], r2)
        if keep:  # dof-major: column k m + r is realization r after step k
            _keep_states(u, k * m, m, out)
        for r in range(m):
            reactions_into(u[r // 4, :, r % 4], nz, GT, cols, R[k, r])
    from_lanes(u, U)
    from_lanes(v, V)
    from_lanes(a, A)


@numba.njit(cache=True, nogil=True)
def rotate(X, To, Tn, has_old):  # pragma: no cover - compiled
    """X (n_real, n_dof) from the node bases To (global if not has_old) to Tn, in place."""
    m, n = X.shape
    for r in range(m):
        for i in range(n // 3):
            x0 = X[r, 3 * i]
            x1 = X[r, 3 * i + 1]
            x2 = X[r, 3 * i + 2]
            if has_old:  # u = T u~: numpy's einsum sums this 3-term reduction as (p0 + p2) + p1
                g0 = (x0 * To[i, 0, 0] + x2 * To[i, 0, 2]) + x1 * To[i, 0, 1]
                g1 = (x0 * To[i, 1, 0] + x2 * To[i, 1, 2]) + x1 * To[i, 1, 1]
                g2 = (x0 * To[i, 2, 0] + x2 * To[i, 2, 2]) + x1 * To[i, 2, 1]
            else:
                g0 = x0
                g1 = x1
                g2 = x2
            for j in range(3):  # u~ = T^T u: summed in order (p0 + p1) + p2
                X[r, 3 * i + j] = (g0 * Tn[i, 0, j] + g1 * Tn[i, 1, j]) + g2 * Tn[i, 2, j]


@numba.njit(cache=True, nogil=True)
def rowdot(X, BT, out):  # pragma: no cover - compiled
    """out = X @ BT, every row summed over d in order from zero (numpy's einsum "rd,dk->rk")."""
    m, n = X.shape
    q = BT.shape[1]
    r0 = 0
    if q <= 8:  # few columns (a scan's one tower): four rows' sums at once, each in the same order
        while r0 + 4 <= m:
            for k in range(q):
                s0 = 0.0
                s1 = 0.0
                s2 = 0.0
                s3 = 0.0
                for d in range(n):
                    b = BT[d, k]
                    s0 += X[r0, d] * b
                    s1 += X[r0 + 1, d] * b
                    s2 += X[r0 + 2, d] * b
                    s3 += X[r0 + 3, d] * b
                out[r0, k] = s0
                out[r0 + 1, k] = s1
                out[r0 + 2, k] = s2
                out[r0 + 3, k] = s3
            r0 += 4
    for r in range(r0, m):
        o = out[r]
        for k in range(q):
            o[k] = 0.0
        for d in range(n):
            x = X[r, d]
            for k in range(q):
                o[k] += x * BT[d, k]


@numba.njit(cache=True, nogil=True, error_model="numpy")
def span_terms(ay, az, by, bz, H, EA, l, with_e, f, g, e):  # pragma: no cover - compiled
    """The integrands of one Newton step of the span tension (static.span_terms):
    p = a + b/H, u = sqrt(1 + p_y^2 + p_z^2), den = 1 + H u/EA, f = u/den,
    g = -u^2/(EA den^2) - (p_y b_y + p_z b_z)/(H^2 den^2 u) and, with with_e,
    e = -(p_y a_y + p_z a_z)/(l den^2 u); with the reciprocals of H, EA and l per span and two
    divisions per point (1/den, 1/u) instead of the numpy form's seven (within rounding of it:
    the kernel's load check).  ay, az, H, l (n, n_spans); by, bz (1 or n, n_spans, n_gp) (one for
    all states or one per state); f, g, e (n, n_spans, n_gp)."""
    n, n_spans = H.shape
    n_gp = by.shape[2]
    inv_ea = 1.0 / EA
    for i in range(n):
        iy = i if by.shape[0] > 1 else 0
        iz = i if bz.shape[0] > 1 else 0
        for j in range(n_spans):
            h = H[i, j]
            inv_h = 1.0 / h
            inv_h2 = inv_h * inv_h
            h_ea = h * inv_ea
            a_y, a_z = ay[i, j], az[i, j]
            inv_l = 1.0 / l[i, j]
            by_r, bz_r, f_r, g_r, e_r = by[iy, j], bz[iz, j], f[i, j], g[i, j], e[i, j]
            for q in range(n_gp):  # vectorised by LLVM (error_model="numpy": no zero-division branch)
                b_y, b_z = by_r[q], bz_r[q]
                py = a_y + b_y * inv_h
                pz = a_z + b_z * inv_h
                u = np.sqrt(1.0 + py * py + pz * pz)
                r = 1.0 / (1.0 + h_ea * u)  # 1/den
                fu = r * r
                inv_u = 1.0 / u
                f_r[q] = u * r
                g_r[q] = -(u * u) * inv_ea * fu - fu * (py * b_y + pz * b_z) * inv_h2 * inv_u
                if with_e:
                    e_r[q] = -fu * (py * a_y + pz * a_z) * inv_l * inv_u


@numba.njit(cache=True, nogil=True)
def history_reductions(M, B, R, sa, out):  # pragma: no cover - compiled
    """results.history_reductions in one pass: per (sample, tower, component)
    the sums of B^2, R^2, (B + R)^2 over time, one sample after the other from the first (numpy's
    order along a non-contiguous axis), divided by n_t, square-rooted; and the largest |M + B|,
    |(M + B) + R|, |(M + B) + sa|, |((M + B) + R) + sa|.  The histories are finite (the time
    integration checks them).  M (1 or n, n_t, n_towers, 3); B, R (n, n_t, n_towers, 3); sa
    (n_towers, 3); out (7, n, n_towers, 3)."""
    n, T, nt, nc = B.shape
    out[:] = 0.0
    for i in range(n):
        im = i if M.shape[0] > 1 else 0
        for t in range(T):
            for k in range(nt):
                for c in range(nc):
                    b = B[i, t, k, c]
                    r = R[i, t, k, c]
                    qs = M[im, t, k, c] + b
                    dy = qs + r
                    f = b + r
                    out[0, i, k, c] += b * b
                    out[1, i, k, c] += r * r
                    out[2, i, k, c] += f * f
                    out[3, i, k, c] = max(out[3, i, k, c], abs(qs))
                    out[4, i, k, c] = max(out[4, i, k, c], abs(dy))
                    out[5, i, k, c] = max(out[5, i, k, c], abs(qs + sa[k, c]))
                    out[6, i, k, c] = max(out[6, i, k, c], abs(dy + sa[k, c]))
    for q in range(3):
        for i in range(n):
            for k in range(nt):
                for c in range(nc):
                    out[q, i, k, c] = np.sqrt(out[q, i, k, c] / T)
