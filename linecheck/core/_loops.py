"""The compiled loops of the optional kernel: Numba functions at module level.

Imported only by :mod:`linecheck.core.kernel` when a piece of the kernel is first asked for (the
rest of the core imports numpy and scipy only; tests/test_import_boundary.py).  The functions are
module-level so that Numba's on-disk cache (``cache=True``) can key them: a function that calls
other jitted functions through closure cells gets a new cache key in every process (the cells are
pickled by identity) and was recompiled every time.  What the loops compute, and how they are
checked against the numpy forms (a tolerance, not bits), is documented in
:mod:`linecheck.core.kernel`.  Where two loops here serve the same realization in different
groupings (one vector or four lanes), they run the same operations in the same order, so a
realization's bits do not depend on the grouping (determinism across chunking and ``--jobs``)."""

from __future__ import annotations

import numba
import numpy as np
from llvmlite import ir
from numba import types
from numba.core import cgutils
from numba.extending import get_cython_function_address, intrinsic

__all__ = ["background", "band_solve", "band_solve_1", "coherent_spectrum", "drag_loads", "field_radius", "field_velocity", "from_lanes", "history_reductions", "phasors", "quad_kms", "reactions_into",
           "rest_product", "rotate", "rowdot", "so_frame", "so_history", "so_nodes", "so_nodes_t", "so_place", "so_products", "so_solve", "solve_columns", "span_terms",
           "steps", "steps_1", "to_lanes"]


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


@numba.njit(cache=True, nogil=True, fastmath={"contract"})
def band_solve_1(c, x):  # pragma: no cover - compiled
    """:func:`band_solve` for one vector x (n,) (one realization: no lanes).

    With the core's half-bandwidth (5) the five unknowns a row reads stay in registers (rolled
    along the rows) instead of being stored and loaded again at every row: the same operations
    in the same order (the same bits), without the store-to-load latency on the dependent chain
    (measured ≈ 6 → 3.5 µs for 177 DOFs)."""
    kd = c.shape[0] - 1
    n = c.shape[1]
    if kd != 5 or n < 6:
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
        return
    for j in range(5):  # U^T y = b: the first rows read fewer than five unknowns
        s0 = 0.0
        for t in range(j):
            s0 += c[kd + t - j, j] * x[t]
        x[j] = (x[j] - s0) / c[kd, j]
    r1 = x[4]
    r2 = x[3]
    r3 = x[2]
    r4 = x[1]
    r5 = x[0]
    for j in range(5, n):  # r_m = y[j - m]
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
    # U x = y: q_m holds y[j - m] with the updates of the columns after j (in the same order)
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
        x0 = x[j] / c[kd, j]
        x[j] = x0
        for t in range(j):
            x[t] += -x0 * c[kd + t - j, j]


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
def steps(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, has_rest, band, a1,
          out, nz, GT, cols, R):  # pragma: no cover - compiled
    """Newmark steps of one block; U, V, A updated in place.

    U, V, A (n_real, n_dof) rotated state; loads (n_b, n_real, n_free) [N]; ycoef
    (n_free, 3); out (n_dof, >= n_b n_real) receives u after every step, dof-major (column
    k n_real + r: realization r after step k; not written when out has no columns: only the
    second-order tension reads it, second_order_reactions(transposed=True)); R (n_b, n_real, n_r)
    the reactions G u, summed coordinate by coordinate from zero over the columns
    [cols[i, 0], cols[i, 1]) of GT's row i (the order of dynamics._sparse_reactions)."""
    n_b, m, n_free = loads.shape
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
            ug, vg, ag, bg = u[g], v[g], a[g], b[g]
            for i in range(n_free):  # F = load x ycoef (the numpy loop's Fb)
                for l in range(4):
                    r = 4 * g + l
                    f[l] = loads[k, r, i] if r < m else 0.0
                for q in range(3):
                    d = 3 * i + q
                    yc = ycoef[i, q]
                    for l in range(4):
                        bg[d, l] = ((cu[d] * ug[d, l] + cv[d] * vg[d, l]) + dm[d] * ag[d, l]) + f[l] * yc
            if has_rest:  # C~_off (a1 u + v): csr_matvecs' bits (rest_product)
                for d in range(n):
                    for l in range(4):
                        w[l, h + d] = a1 * ug[d, l] + vg[d, l]
                rest_product(band, w, t)
                for d in range(n):
                    for l in range(4):
                        bg[d, l] += t[l, d]
        band_solve(chat, b)
        for g in range(G):
            ug, vg, ag, bg = u[g], v[g], a[g], b[g]
            for d in range(n):  # v' = (u' - u) 2/dt - v, a' = (v' - v) 2/dt - a
                for l in range(4):
                    vn = (bg[d, l] - ug[d, l]) * r2 - vg[d, l]
                    ag[d, l] = (vn - vg[d, l]) * r2 - ag[d, l]
                    vg[d, l] = vn
                    ug[d, l] = bg[d, l]
        if keep:  # dof-major: column k m + r is realization r after step k (a row's m values at once)
            c0 = k * m
            for d in range(n):
                for r in range(m):
                    out[d, c0 + r] = u[r // 4, d, r % 4]
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


@numba.njit(cache=True, nogil=True)
def phasors(phases, xr, xi):  # pragma: no cover - compiled
    """The unit phasors exp(i phi) = cos phi + i sin phi of the wind synthesis (glibc's cexp at a
    zero real part, as numpy's complex exp): xr = cos, xi = sin, each (n_nodes, n_freq)."""
    n_nodes, n_freq = phases.shape
    for j in range(n_nodes):
        for k in range(n_freq):
            p = phases[j, k]
            xr[j, k] = np.cos(p)
            xi[j, k] = np.sin(p)


@numba.njit(cache=True, nogil=True)
def coherent_spectrum(xr_, xi_, rho_rows, s_rows, row_of_gap, amp, scale, spec):  # pragma: no cover - compiled
    """The wind synthesis' spectrum of ordered nodes in one pass (issue 20): from the unit phasors
    xi = exp(i phi) (:func:`phasors`: xr_ + i xi_), the Markov (equal gaps: KMS) recursion
    y_0 = xi_0, y_j = rho y_(j-1) + s xi_j along the nodes with the coefficient row of gap j - 1,
    and spec[j, k + 1] = scale (amp_k y_jk), as numpy's form (turbulence.synthesize): a real
    times a complex as numpy forms it (the real cast to complex: (a x_r - 0 x_i, a x_i + 0 x_r)).
    xr_, xi_ (n_nodes, n_freq); rho_rows, s_rows (n_rows, n_freq); row_of_gap (n_nodes - 1,);
    amp (n_freq,); spec (n_nodes, >= n_freq + 1) complex, zero outside columns 1 .. n_freq."""
    n_nodes, n_freq = xr_.shape
    pr = np.empty(n_freq)
    pi = np.empty(n_freq)
    for j in range(n_nodes):
        g = row_of_gap[j - 1] if j > 0 else 0
        for k in range(n_freq):
            xr = xr_[j, k]
            xi = xi_[j, k]
            if j == 0:
                yr = xr
                yi = xi
            else:
                r = rho_rows[g, k]
                w = s_rows[g, k]
                yr = (r * pr[k] - 0.0 * pi[k]) + (w * xr - 0.0 * xi)
                yi = (r * pi[k] + 0.0 * pr[k]) + (w * xi + 0.0 * xr)
            pr[k] = yr
            pi[k] = yi
            a = amp[k]
            zr = a * yr - 0.0 * yi
            zi = a * yi + 0.0 * yr
            spec[j, k + 1] = complex(scale * zr - 0.0 * zi, scale * zi + 0.0 * zr)


@numba.njit(cache=True, nogil=True)
def drag_loads(pv, pq, s2, v, s0, quad, loads):  # pragma: no cover - compiled
    """The fluctuating drag on the free nodes (service.fluctuating_loads), as the numpy form:
    loads[t, i, f] = pv[t, f] v[i, t, s0 + f] (paper Eq. 5), plus ((v^2 - s2) pq) with the
    quadratic drag (issue 16), each product and sum rounded by itself.  pv, pq, s2 (n_steps,
    n_free); v (n_real, n_steps, n_nodes), the free nodes s0 .. s0 + n_free - 1; loads
    (n_steps, n_real, n_free)."""
    n_real, n_steps = v.shape[0], v.shape[1]
    n_free = loads.shape[2]
    for t in range(n_steps):
        for i in range(n_real):
            for f in range(n_free):
                x = v[i, t, s0 + f]
                val = pv[t, f] * x
                if quad:
                    val = val + ((x * x - s2[t, f]) * pq[t, f])
                loads[t, i, f] = val


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


@numba.njit(cache=True, nogil=True)
def field_radius(x, cx, cy, r_max, decay, r, z):  # pragma: no cover - compiled
    """First pass of DownburstField.velocity (Holmes & Oliver 2000): per instant
    t and line point x, r = hypot(x - cx, 0 - cy) and the Gaussian's exponent
    z = -(((r - r_max)/decay)^2) (numpy then takes exp(z) on the whole array, as it does now).
    x (n_x,); cx, cy (n_t,); r, z (n_t, n_x)."""
    for t in range(cx.size):
        dy = 0.0 - cy[t]
        for i in range(x.size):
            dx = x[i] - cx[t]
            rr = np.hypot(dx, dy)
            r[t, i] = rr
            q = (rr - r_max) / decay
            z[t, i] = -(q * q)


@numba.njit(cache=True, nogil=True)
def field_velocity(x, cx, cy, r, e, r_max, fz, pi, v_max, tx, ty, vx, vy):  # pragma: no cover - compiled
    """Second pass: f_r = r/r_max inside r_max else e (= exp(z)), speed = v_max ((f_r f_z) Pi(t)),
    v = speed d/r + translation (0 + translation at r = 0)."""
    for t in range(cx.size):
        dy = 0.0 - cy[t]
        p = pi[t]
        for i in range(x.size):
            rr = r[t, i]
            fr = rr / r_max if rr <= r_max else e[t, i]
            speed = v_max * ((fr * fz) * p)
            if rr > 0.0:
                dx = x[i] - cx[t]
                vx[t, i] = (speed * dx) / rr + tx
                vy[t, i] = (speed * dy) / rr + ty
            else:
                vx[t, i] = 0.0 + tx
                vy[t, i] = 0.0 + ty


@numba.njit(cache=True, nogil=True)
def quad_kms(w, rho, gap, out):  # pragma: no cover - compiled
    """spectral._quad_kms_nodes in one pass: w (K, N, F) complex, rho (F,) (``gap`` False)
    or per gap (N - 1, F); out (K, F) = sum_i |w_i|^2 (summed over the nodes one after the other,
    as numpy reduces a non-contiguous axis) + 2 sum_j Re(conj(w_j) h_j), h_j = (h_{j-1} + w_{j-1})
    rho_j, the complex-times-real product written as numpy forms it, (a c - b 0, a 0 + b c)."""
    K, N, F = w.shape
    hr = np.empty(F)
    hi = np.empty(F)
    cr = np.empty(F)
    for k in range(K):
        for f in range(F):
            x = w[k, 0, f]
            out[k, f] = x.real * x.real + x.imag * x.imag
        for j in range(1, N):
            for f in range(F):
                x = w[k, j, f]
                out[k, f] += x.real * x.real + x.imag * x.imag
        hr[:] = 0.0
        hi[:] = 0.0
        cr[:] = 0.0
        for j in range(1, N):
            g = j - 1 if gap else 0
            for f in range(F):
                y = w[k, j - 1, f]
                a = hr[f] + y.real
                b = hi[f] + y.imag
                c = rho[g, f]
                hr[f] = a * c - b * 0.0
                hi[f] = a * 0.0 + b * c
                x = w[k, j, f]
                cr[f] += x.real * hr[f] + x.imag * hi[f]
        for f in range(F):
            out[k, f] = out[k, f] + 2.0 * cr[f]


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
def so_solve(c, inv, L, dirs, straight, i0, r, y, xr, s, Lt):  # pragma: no cover - compiled
    """The quasi-static displacements of the load rows i0 <= i < i0 + r of L (m, n_free), lane
    j = row i0 + j (lanes >= r solve zeros): the right-hand sides (global y, or along ``dirs``
    (n_free, 3) when not ``straight``), then U^T U x = b by rows of lanes (c the upper band of
    dpbtrf, inv = 1 / its diagonal); x returned in xr (n_dof, nb) in reversed row order,
    xr[n - 1 - j] = x_j (the algorithm of LAPACK dpbtrs, which the numpy form calls; no
    contraction).  y (n_dof, nb), s (nb,), Lt (n_free, nb): scratch.

    Speed (measured when written): the rows with the core's full half-bandwidth (5) in
    one pass, the band's sum in a register and the load placed in the same pass (no zeroed
    right-hand side), 2-D indexing (row views kept LLVM's overlap checks: 3x slower), loop bounds
    rather than a flag around the loop (it did not vectorise: 2.8x), and the back substitution
    written upward into xr (reading the rows just written below the one written; reading the rows
    above it in place ran 2x slower)."""
    kd = c.shape[0] - 1
    n = c.shape[1]
    nb = y.shape[1]
    nf = L.shape[1]
    Lb = L[i0:i0 + r]
    for j in range(r):  # L's rows into lanes (row by row: 1.6x faster than in tiles, measured)
        for i in range(nf):
            Lt[i, j] = Lb[j, i]
    for i in range(nf):
        for j in range(r, nb):
            Lt[i, j] = 0.0
    # the rows in the register form: j >= j5 forward, n - 1 - j >= jb5 back
    j5 = 5 if kd == 5 and n > 5 else n
    for j in range(j5):  # U^T y = b
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
    jb5 = 5 if j5 < n else n
    for jr in range(jb5):  # U x = y, x_j = xr[jr], j = n - 1 - jr
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
