"""The compiled loops of steps 2 and 3 (issue 20), optional.

The numpy step loop of :func:`linecheck.core.dynamics.integrate` makes about a dozen numpy
calls and one LAPACK ``dpbtrs`` per time step; for the six-span system that is ≈ 12 µs (one
realization) to ≈ 60 µs (ten) per step of mostly call overhead.  With the optional extra
``linecheck[fast]`` (Numba) the same recurrence runs here as one compiled loop over the steps
of a block (:func:`newmark_block`), together with the reactions G u of every step, the change
of node bases between mean states (:func:`rotate`), step 3's static transfer (:func:`rowdot`)
and a long line's step 3 (:func:`background`, :func:`solve_columns`); without it (or with
``LINECHECK_KERNEL=numpy``) the numpy code runs.

**Same bits.**  The kernel repeats the numpy loop's arithmetic operation by operation, so the
two paths give bit-identical results (tested on synoptic, downburst, structural-damping and
section cases):

- the right-hand side ((cu u + cv v) + dm a) + F (+ C~_off (a1 u + v)), each product and sum
  rounded separately as numpy's ufuncs round them (no fused multiply-add: compiled without
  ``contract``); F = load × ycoef as numpy forms it; the structural-damping remainder summed
  row by row from 0 in CSR order, as scipy's ``csr_matvecs`` sums it;
- the banded Cholesky solve U^T U x = b (upper band storage, LAPACK ``dpbtrs``: two
  ``dtbsv`` calls per right-hand side) with the operation order of OpenBLAS's ``dtbsv`` —
  the transposed solve as a dot product of the (at most BANDWIDTH) earlier unknowns
  subtracted from b_j, then a division by the diagonal; the back-substitution column by
  column (divide, then an axpy of −x_j times the column into the earlier entries) — compiled
  *with* ``contract``, because OpenBLAS's Haswell kernels form those dot products and axpys
  with fused multiply-adds (the test compares against ``dpbtrs`` itself, so a BLAS that rounds
  differently is detected: :func:`available` then returns False and the numpy loop runs);
- the trapezoidal updates v' = (u' − u) 2/Δt − v, a' = (v' − v) 2/Δt − a (Bathe Table 9.3).

Each realization is integrated by itself (its own row), so its bits do not depend on which
other realizations share the run, as in the numpy loop.

This module imports Numba only when the kernel is first asked for; the rest of the core
imports numpy and scipy only.
"""

from __future__ import annotations

import os
import threading

import numpy as np

_lock = threading.Lock()
_state: dict[str, object] = {}
_NO_INDEX = np.zeros(1, dtype=np.int32)  # the CSR arguments of a stepper without a remainder
_NO_DATA = np.zeros(1)


def _compile():
    """The compiled functions (Numba) by name, or None when Numba is not installed."""
    try:
        import numba
    except ImportError:
        return None
    njit = numba.njit

    # the banded triangular solves, with contraction as OpenBLAS's Haswell dtbsv forms them.
    # x is (n_groups, n_dof, 4): the realizations in groups of four lanes (padded with zeros),
    # every lane solved by itself in dtbsv's order; four independent chains per group hide the
    # latency of the dependent divide and multiply-adds (LLVM keeps the lanes scalar; measured:
    # four lanes cost ≈ 1.4 x one, docs/performance.md)
    @njit(cache=True, nogil=True, fastmath={"contract"})
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

    @njit(cache=True, nogil=True)
    def to_lanes(X):  # pragma: no cover - compiled
        """Rows of X (m, n) as lanes (n_groups, n, 4): row r is lane r % 4 of group r // 4
        (padding lanes zero)."""
        m, n = X.shape
        x = np.zeros(((m + 3) // 4, n, 4))
        for r in range(m):
            for d in range(n):
                x[r // 4, d, r % 4] = X[r, d]
        return x

    @njit(cache=True, nogil=True)
    def from_lanes(x, X):  # pragma: no cover - compiled
        """The inverse of :func:`to_lanes`, into X (m, n)."""
        m, n = X.shape
        for r in range(m):
            for d in range(n):
                X[r, d] = x[r // 4, d, r % 4]

    @njit(cache=True, nogil=True)
    def reactions_into(u, nz, GT, cols, Rr):  # pragma: no cover - compiled
        """Rr (n_r,) = G u, summed coordinate by coordinate from zero over the columns
        [cols[q, 0], cols[q, 1]) of GT's row q (the order of dynamics._sparse_reactions)."""
        Rr[:] = 0.0
        for q in range(nz.size):
            x = u[nz[q]]
            for k in range(cols[q, 0], cols[q, 1]):
                Rr[k] += x * GT[q, k]

    @njit(cache=True, nogil=True)
    def solve_columns(c, B):  # pragma: no cover - compiled
        """dpbtrs on every column of B (n, m) in place, four columns at a time."""
        x = to_lanes(B.T)
        band_solve(c, x)
        from_lanes(x, B.T)

    @njit(cache=True, nogil=True)
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

    @njit(cache=True, nogil=True, fastmath={"contract"})
    def band_solve_1(c, x):  # pragma: no cover - compiled
        """:func:`band_solve` for one vector x (n,) (one realization: no lanes)."""
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

    @njit(cache=True, nogil=True)
    def steps_1(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, has_rest, indptr, indices, data, a1,
                out, nz, GT, cols, R):  # pragma: no cover - compiled
        """:func:`steps` for one realization (U, V, A of shape (1, n_dof)): plain vectors."""
        n_b, _, n_free = loads.shape
        n = U.shape[1]
        u = U[0]
        v = V[0]
        a = A[0]
        b = np.empty(n)
        w = np.empty(n)
        for k in range(n_b):
            for i in range(n_free):
                f = loads[k, 0, i]
                for q in range(3):
                    d = 3 * i + q
                    b[d] = ((cu[d] * u[d] + cv[d] * v[d]) + dm[d] * a[d]) + f * ycoef[i, q]
            if has_rest:
                for d in range(n):
                    w[d] = a1 * u[d] + v[d]
                for d in range(n):
                    t0 = 0.0
                    for jj in range(indptr[d], indptr[d + 1]):
                        t0 += data[jj] * w[indices[jj]]
                    b[d] += t0
            band_solve_1(chat, b)
            for d in range(n):
                vn = (b[d] - u[d]) * r2 - v[d]
                a[d] = (vn - v[d]) * r2 - a[d]
                v[d] = vn
                u[d] = b[d]
                out[k, 0, d] = b[d]
            reactions_into(u, nz, GT, cols, R[k, 0])

    @njit(cache=True, nogil=True)
    def steps(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, has_rest, indptr, indices, data, a1,
              out, nz, GT, cols, R):  # pragma: no cover - compiled
        """Newmark steps of one block; U, V, A updated in place.

        U, V, A (n_real, n_dof) rotated state; loads (n_b, n_real, n_free) [N]; ycoef
        (n_free, 3); out (n_b, n_real, n_dof) receives u after every step; R (n_b, n_real, n_r)
        the reactions G u, summed coordinate by coordinate from zero over the columns
        [cols[i, 0], cols[i, 1]) of GT's row i (the order of dynamics._sparse_reactions)."""
        n_b, m, n_free = loads.shape
        n = U.shape[1]
        u = to_lanes(U)  # lane l of group g is realization 4 g + l (padding lanes stay 0)
        v = to_lanes(V)
        a = to_lanes(A)
        G = u.shape[0]
        b = np.zeros((G, n, 4))
        w = np.zeros((n, 4))
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
                if has_rest:  # C~_off (a1 u + v): csr_matvecs order, each row summed from 0
                    for d in range(n):
                        for l in range(4):
                            w[d, l] = a1 * ug[d, l] + vg[d, l]
                    for d in range(n):
                        t0 = 0.0
                        t1 = 0.0
                        t2 = 0.0
                        t3 = 0.0
                        for jj in range(indptr[d], indptr[d + 1]):
                            gj = data[jj]
                            e = indices[jj]
                            t0 += gj * w[e, 0]
                            t1 += gj * w[e, 1]
                            t2 += gj * w[e, 2]
                            t3 += gj * w[e, 3]
                        bg[d, 0] += t0
                        bg[d, 1] += t1
                        bg[d, 2] += t2
                        bg[d, 3] += t3
            band_solve(chat, b)
            for g in range(G):
                ug, vg, ag, bg = u[g], v[g], a[g], b[g]
                for d in range(n):  # v' = (u' - u) 2/dt - v, a' = (v' - v) 2/dt - a
                    for l in range(4):
                        vn = (bg[d, l] - ug[d, l]) * r2 - vg[d, l]
                        ag[d, l] = (vn - vg[d, l]) * r2 - ag[d, l]
                        vg[d, l] = vn
                        ug[d, l] = bg[d, l]
            from_lanes(u, out[k])
            for r in range(m):
                reactions_into(u[r // 4, :, r % 4], nz, GT, cols, R[k, r])
        from_lanes(u, U)
        from_lanes(v, V)
        from_lanes(a, A)

    @njit(cache=True, nogil=True)
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

    @njit(cache=True, nogil=True)
    def rowdot(X, BT, out):  # pragma: no cover - compiled
        """out = X @ BT, every row summed over d in order from zero (numpy's einsum "rd,dk->rk")."""
        m, n = X.shape
        q = BT.shape[1]
        for r in range(m):
            o = out[r]
            for k in range(q):
                o[k] = 0.0
            for d in range(n):
                x = X[r, d]
                for k in range(q):
                    o[k] += x * BT[d, k]

    from types import SimpleNamespace

    return SimpleNamespace(band_solve=band_solve, steps=steps, steps_1=steps_1, solve_columns=solve_columns,
                           rotate=rotate, rowdot=rowdot, background=background)


def _self_test(band_solve) -> bool:
    """The compiled banded solve gives dpbtrs's bits on a system of the size the core uses."""
    from scipy.linalg import lapack

    from .model import BANDWIDTH

    rng = np.random.default_rng(20)
    n, kd = 60, BANDWIDTH
    ab = np.zeros((kd + 1, n))
    for off in range(kd + 1):
        ab[kd - off, off:] = rng.uniform(-1.0, 1.0, n - off)
    ab[kd] = 4.0 * (kd + 1) + rng.uniform(0.0, 1.0, n)
    c, info = lapack.dpbtrf(ab, lower=0)
    if info != 0:  # pragma: no cover - diagonally dominant by construction
        return False
    B = rng.standard_normal((4, n))
    ref, info = lapack.dpbtrs(c, np.asfortranarray(B.T), lower=0)
    X = np.ascontiguousarray(B.T)[None]  # one group of four lanes
    band_solve(c, X)
    return info == 0 and bool(np.array_equal(X[0], ref))


#: loading Numba and the cached kernel costs ≈ 0.6 s once per process; below this much work
#: (steps × realizations × DOFs, ≈ 0.3 s of the numpy loop) a process that has not loaded it yet
#: keeps the numpy loop, which gives the same bits (a one-realization six-span run is 2.2e6)
LOAD_WORK = 2.0e7


def _mode() -> str:
    """``LINECHECK_KERNEL``: "auto" (default), "numpy" (never compile) or "numba" (always)."""
    return os.environ.get("LINECHECK_KERNEL", "auto").strip().lower()


def use(work: float) -> bool:
    """Whether to run ``work`` (steps × realizations × DOFs) through the compiled kernel: when
    it is available and either already loaded in this process or the work pays for loading it
    (:data:`LOAD_WORK`; ``LINECHECK_KERNEL=numba`` always loads it).  Same bits either way."""
    mode = _mode()
    if mode == "numpy":
        return False
    if "ok" in _state or mode == "numba" or work >= LOAD_WORK:
        return available()
    return False


def _rotate_test(rotate) -> bool:
    """The compiled change of node bases gives :func:`~linecheck.core.dynamics.st_rotate`'s bits
    (numpy's einsum order; if a numpy rounds it differently, the numpy rotation is used)."""
    from types import SimpleNamespace

    from .dynamics import st_rotate

    rng = np.random.default_rng(21)
    To, Tn = (np.linalg.qr(rng.standard_normal((20, 3, 3)))[0] for _ in range(2))
    X = rng.standard_normal((5, 60))
    ok = True
    for old in (None, SimpleNamespace(T=To)):
        Y = X.copy()
        rotate(Y, To, Tn, old is not None)
        ok &= bool(np.array_equal(Y, st_rotate(X, old, SimpleNamespace(T=Tn))))
    return ok


def _rowdot_test(rowdot) -> bool:
    """The compiled X @ BT gives :func:`~linecheck.core.dynamics._rowdot`'s bits (numpy's einsum
    order) on the shapes the core uses (many rows, tens of columns); else numpy's is used."""
    from .dynamics import _rowdot

    rng = np.random.default_rng(22)
    ok = True
    for m, n, q in ((480, 59, 21), (7, 177, 9), (33, 3, 40)):
        X, BT = rng.standard_normal((m, n)), rng.standard_normal((n, q))
        out = np.empty((m, q))
        rowdot(X, BT, out)
        ok &= bool(np.array_equal(out, _rowdot(X, BT)))
    return ok


def rowdot(X: np.ndarray, BT: np.ndarray) -> np.ndarray:
    """X (m, n) @ BT (n, q) with the bits of :func:`~linecheck.core.dynamics._rowdot` (compiled
    when that was verified at load)."""
    if not _state.get("rowdot"):
        from .dynamics import _rowdot

        return _rowdot(X, BT)
    out = np.empty((X.shape[0], BT.shape[1]))
    _state["fns"].rowdot(np.ascontiguousarray(X), np.ascontiguousarray(BT), out)
    return out


def rotate(X: np.ndarray, old, new) -> np.ndarray:
    """Vectors (n_real, n_dof) from ``old``'s node bases (global if None) to ``new``'s, with the
    bits of :func:`~linecheck.core.dynamics.st_rotate` (compiled when that was verified)."""
    if not _state.get("rotate"):
        from .dynamics import st_rotate

        return st_rotate(X, old, new)
    Y = np.array(X, dtype=float, order="C")
    _state["fns"].rotate(Y, new.T if old is None else old.T, new.T, old is not None)
    return Y


def available() -> bool:
    """True when the compiled kernel is installed, wanted and bit-identical to LAPACK here.

    ``LINECHECK_KERNEL=numpy`` switches it off (the numpy loop runs); the first call compiles
    (or loads Numba's on-disk cache) and checks the banded solve against ``dpbtrs``."""
    if _mode() == "numpy":
        return False
    with _lock:
        if "ok" not in _state:
            try:
                fns = _compile()
                ok = fns is not None and _self_test(fns.band_solve)
                rot = ok and _rotate_test(fns.rotate)
                dot = ok and _rowdot_test(fns.rowdot)
            except Exception:  # a Numba that cannot compile or cache here: the numpy loop (same bits)
                fns, ok, rot, dot = None, False, False, False
            _state["ok"] = ok
            _state["fns"] = fns if ok else None
            _state["rotate"] = rot
            _state["rowdot"] = dot
        return bool(_state["ok"])


def newmark_block(U: np.ndarray, V: np.ndarray, A: np.ndarray, loads: np.ndarray, ycoef: np.ndarray,
                  cu: np.ndarray, cv: np.ndarray, dm: np.ndarray, r2: float, chat: np.ndarray, rest,
                  a1: float, out: np.ndarray, nz: np.ndarray, GT: np.ndarray, cols: np.ndarray,
                  R: np.ndarray) -> None:
    """Newmark average-acceleration steps of one block (Bathe 1996 Table 9.3) in the node bases.

    Args:
        U, V, A: [m, m/s, m/s²] rotated state of every realization, (n_real, n_dof), C-ordered,
            updated in place.
        loads: [N] transverse loads of the block's steps, (n_b, n_real, n_free).
        ycoef: [-] local components of each node's unit load, (n_free, 3).
        cu, cv, dm: the diagonal operators of :class:`~linecheck.core.dynamics._Stepper`, (n_dof,).
        r2: [1/s] 2/Δt.  chat: Cholesky factor of K̂ (upper band, (BANDWIDTH + 1, n_dof)).
        rest: off-diagonal structural damping C~_off (scipy CSR) or None; a1: [1/s] 2/Δt.
        out: receives u after every step, (n_b, n_real, n_dof).
        nz, GT, cols: the stepper's sparse reaction rows (:func:`~linecheck.core.dynamics._sparse_rows`).
        R: [N] receives the reactions G T u~ after every step, (n_b, n_real, n_r) (the bits of
            :func:`~linecheck.core.dynamics._sparse_reactions`).
    """
    fns = _state["fns"]
    steps = fns.steps_1 if U.shape[0] == 1 else fns.steps
    if rest is None:
        steps(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, False, _NO_INDEX, _NO_INDEX, _NO_DATA, a1, out, nz, GT,
              cols, R)
    else:
        steps(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, True, rest.indptr, rest.indices, rest.data, a1, out, nz, GT, cols, R)


def background(c: np.ndarray, L: np.ndarray, load_dirs: np.ndarray | None, sparse_g) -> np.ndarray:
    """Step 3 of a long line (:func:`~linecheck.core.dynamics.integrate`, above
    BACKGROUND_SOLVE_DOF): the reactions G K^-1 P l of load rows L [N] (m, n_free), with the bits
    of building the right-hand sides, ``dpbtrs`` and ``_sparse_reactions``.

    c: Cholesky factor of K (upper band); load_dirs: (n_free, 3) or None (global y);
    sparse_g: ``_sparse_rows(G)`` (nz, GT, cols).  Returns R [N] (m, n_r)."""
    nz, GT, cols = sparse_g
    R = np.empty((L.shape[0], GT.shape[1]))
    dirs = np.zeros((1, 3)) if load_dirs is None else np.ascontiguousarray(load_dirs, dtype=float)
    _state["fns"].background(c, np.ascontiguousarray(L), dirs, load_dirs is None, nz, GT, cols, R)
    return R


def solve_columns(c: np.ndarray, B: np.ndarray) -> np.ndarray:
    """LAPACK ``dpbtrs`` (upper) on every column of B (n_dof, m), in place, with its bits.

    c: Cholesky factor of a banded SPD matrix (upper band storage, (BANDWIDTH + 1, n_dof));
    B: right-hand sides as columns.  Returns B (solved)."""
    _state["fns"].solve_columns(c, B)
    return B
