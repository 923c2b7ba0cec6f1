"""The compiled loops of steps 2 and 3 (issue 20), optional.

The numpy step loop of :func:`linecheck.core.dynamics.integrate` makes about a dozen numpy
calls and one LAPACK ``dpbtrs`` per time step; for the six-span system that is ≈ 12 µs (one
realization) to ≈ 60 µs (ten) per step of mostly call overhead.  With the optional extra
``linecheck[fast]`` (Numba) the same recurrence runs here as one compiled loop over the steps
of a block (:func:`newmark_block`), together with the reactions G u of every step, the change
of node bases between mean states (:func:`rotate`), step 3's static transfer (:func:`rowdot`)
and a long line's step 3 (:func:`background`, :func:`solve_columns`; also each downburst mean
state's K^-1 G^T), and before the steps the wind synthesis' phasors and coherence recursion
(:func:`coherent_spectrum`), the analytic downburst field over the record (:func:`field_velocity`)
and the fluctuating drag (:func:`drag_loads`), in step 1 the span tension's Newton integrands (:func:`span_terms`: a
downburst's 250 mean states at once, their sums over the Gauss points left to numpy's
``matmul``, so the same BLAS sums them), and after the steps the statistics' r.m.s. values and
peaks over time (:func:`history_reductions`: numpy sums along the time axis one sample after the
other, and so does the loop), and the second-order tension's elementwise passes per block of rows
(:func:`second_order_passes`: the rotation out of the node bases, the insulators' frames, the
terms P of :func:`linecheck.core.second_order.reaction_form` and step 3's banded solve of the
loads by rows of lanes (``_loops.so_solve``, the order of ``second_order._band_solve_rows``), their
3 × 3 products as the fused multiply-add chain of OpenBLAS's dgemm kernel; where numpy's own
``cblas_sgemm`` is found, :func:`second_order_sgemm`, the whole block loop with its BLAS products
P W (float32), called with the arguments numpy's ``matmul`` passes: the same bits, without the
GIL that ``matmul`` keeps during a 2-D product); without it (or with ``LINECHECK_KERNEL=numpy``) the numpy
code runs.
Each compiled function is compared with its numpy form when the kernel loads; one that differs
here is not used.

**Same bits.**  The kernel repeats the numpy loop's arithmetic operation by operation, so the
two paths give bit-identical results (tested on synoptic, downburst, structural-damping and
section cases):

- the right-hand side ((cu u + cv v) + dm a) + F (+ C~_off (a1 u + v)), each product and sum
  rounded separately as numpy's ufuncs round them (no fused multiply-add: compiled without
  ``contract``); F = load × ycoef as numpy forms it; the structural-damping remainder summed
  row by row from 0 over the columns ascending, as scipy's ``csr_matvecs`` sums the CSR row
  (the compiled loop runs the rows side by side, by diagonals, :func:`_loops.rest_product`:
  its extra terms are products with exact zeros, which leave the sums' bits unchanged);
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

The compiled functions themselves are in :mod:`linecheck.core._loops` (module level, so that
Numba's disk cache finds them again in the next process); this module imports it, and with it
Numba, only when the kernel is first asked for; the rest of the core imports numpy and scipy only.
"""

from __future__ import annotations

import os
import threading

import numpy as np

_lock = threading.Lock()
_state: dict[str, object] = {}
_NO_BAND = np.zeros((1, 1))  # the remainder argument of a stepper without one


def _compile():
    """The compiled functions (Numba, :mod:`linecheck.core._loops`) by name, or None when Numba
    is not installed."""
    try:
        from . import _loops  # imports Numba
    except ImportError:
        return None
    return _loops


def _self_test(fns) -> bool:
    """The compiled banded solves give dpbtrs's bits on systems of the sizes the core uses (four
    lanes; one vector, with the registers of the half-bandwidth 5 and the general loop of a short
    system), and the remainder by diagonals scipy's CSR product's bits."""
    from scipy.linalg import lapack

    from .model import BANDWIDTH, band_to_csr

    rng = np.random.default_rng(20)
    ok = True
    for n in (60, 4):
        kd = BANDWIDTH
        ab = np.zeros((kd + 1, n))
        for off in range(kd + 1):
            ab[kd - off, off:] = rng.uniform(-1.0, 1.0, max(n - off, 0))
        ab[kd] = 4.0 * (kd + 1) + rng.uniform(0.0, 1.0, n)
        c, info = lapack.dpbtrf(ab, lower=0)
        if info != 0:  # pragma: no cover - diagonally dominant by construction
            return False
        B = rng.standard_normal((4, n))
        ref, info = lapack.dpbtrs(c, np.asfortranarray(B.T), lower=0)
        ok &= info == 0
        X = np.ascontiguousarray(B.T)[None]  # one group of four lanes
        fns.band_solve(c, X)
        ok &= bool(np.array_equal(X[0], ref))
        for q in range(4):
            x = B[q].copy()
            fns.band_solve_1(c, x)
            ok &= bool(np.array_equal(x, ref[:, q]))
        ab[kd] = 0.0  # an off-diagonal remainder, with some exact zeros
        ab[rng.random(ab.shape) < 0.2] = 0.0
        rest = band_to_csr(ab)
        W = rng.standard_normal((4, n))
        t = np.empty((4, n))
        fns.rest_product(rest.band, np.pad(W, ((0, 0), (kd, kd))), t)
        ok &= bool(np.array_equal(t.T, rest.tocsr() @ W.T))
    return ok


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
    for m, n, q in ((480, 59, 21), (7, 177, 9), (33, 3, 40), (482, 55, 3), (6, 10, 2)):
        X, BT = rng.standard_normal((m, n)), rng.standard_normal((n, q))
        out = np.empty((m, q))
        rowdot(X, BT, out)
        ok &= bool(np.array_equal(out, _rowdot(X, BT)))
    return ok


def _spectrum_test(fns) -> bool:
    """The compiled spectrum gives the numpy forms' bits, signs of zeros included (glibc's sin and
    cos for numpy's complex exp; numpy's real-times-complex products): equal gaps (the KMS
    recursion) and unequal ones (the Markov recursion, a coefficient row per gap); else numpy's."""
    from .wind.turbulence import fft_input, gap_rows, kms_apply, markov_apply

    rng = np.random.default_rng(23)
    n_nodes, n_freq = 9, 301
    phases = rng.random((n_nodes, n_freq)) * (2.0 * np.pi)
    freq = np.arange(1, n_freq + 1) * 0.01
    amp = rng.random(n_freq)
    m = 2 * n_freq + 2
    x = np.cumsum(np.r_[0.0, rng.choice([30.0, 12.5], n_nodes - 1)])
    rows, gap = gap_rows(x, freq, 10.0, 40.0)
    cases = [(markov_apply(x, freq, np.exp(1j * phases), 10.0, 40.0), rows, gap),
             (kms_apply(rows[0], np.exp(1j * phases)), rows[:1], np.zeros(n_nodes - 1, dtype=np.int64))]
    ok = True
    for y, r, g in cases:
        ref = fft_input(y, amp, m)
        got = np.zeros_like(ref)
        xr, xi = np.empty_like(phases), np.empty_like(phases)
        fns.phasors(phases, xr, xi)
        fns.coherent_spectrum(xr, xi, r, np.sqrt(np.maximum(1.0 - r * r, 0.0)), g, amp, 0.5 * m, got)
        ok &= bool(np.array_equal(got.view(float), ref.view(float))
                   and np.array_equal(np.signbit(got.view(float)), np.signbit(ref.view(float))))
    return ok


def phasors(phases: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The unit phasors (cos phi, sin phi) of phases [rad] (n_nodes, n_freq), compiled (the
    values :func:`coherent_spectrum` uses), or None when the kernel is not loaded or its spectrum
    did not give numpy's bits at load.  They depend on the seed, the realization, the nodes and
    the grid only, so a scan's positions can share them (turbulence.unit_phases)."""
    if not (use(0.0) and _state.get("spectrum")):
        return None
    phases = np.ascontiguousarray(phases, dtype=float)
    xr, xi = np.empty_like(phases), np.empty_like(phases)
    _state["fns"].phasors(phases, xr, xi)
    return xr, xi


def coherent_spectrum(phases, rho_rows: np.ndarray, row_of_gap: np.ndarray, amp: np.ndarray,
                      m: int) -> np.ndarray | None:
    """The synthesis spectrum of ordered nodes (turbulence.synthesize, issue 20), compiled, or None
    when the kernel is not loaded (or did not give numpy's bits at load).

    phases [rad] (n_nodes, n_freq), or their :func:`phasors` (cos, sin) already computed;
    rho_rows [-] neighbour coherence rows (n_rows, n_freq) and the row of every gap (n_nodes - 1,)
    (equal gaps: one row); amp [-] cosine amplitudes (n_freq,); m the FFT length.  Returns
    (n_nodes, m // 2 + 1) complex: column k + 1 = (m/2) amp_k y_k with y the KMS / Markov
    recursion of the unit phasors (Deodatis 1996)."""
    if not (use(0.0) and _state.get("spectrum")):
        return None
    xr, xi = phases if isinstance(phases, tuple) else phasors(phases)
    rho_rows = np.ascontiguousarray(rho_rows, dtype=float)
    spec = np.zeros((xr.shape[0], m // 2 + 1), dtype=complex)
    _state["fns"].coherent_spectrum(xr, xi, rho_rows,
                                    np.sqrt(np.maximum(1.0 - rho_rows * rho_rows, 0.0)),
                                    np.ascontiguousarray(row_of_gap, dtype=np.int64),
                                    np.ascontiguousarray(amp, dtype=float), 0.5 * m, spec)
    return spec


def drag_loads_numpy(pv, pq, s2, v, sel, loads) -> None:
    """The numpy form of :func:`drag_loads`; ``sel`` the free nodes, a slice or an index array."""
    for i in range(v.shape[0]):
        vi = v[i][:, sel]
        np.multiply(pv, vi, out=loads[:, i, :])
        if pq is not None:  # the quadratic drag's (v^2 - s2) pq
            q = vi * vi
            q -= s2
            q *= pq
            loads[:, i, :] += q


def _loads_test(fn) -> bool:
    """The compiled drag loads give the numpy form's bits (linear and quadratic drag)."""
    rng = np.random.default_rng(24)
    v = rng.standard_normal((3, 40, 9))
    pv, pq, s2 = (rng.random((40, 9))[:, 1:8] for _ in range(3))  # strided, as the slices of the service
    ok = True
    for quad in (False, True):
        ref, got = np.empty((40, 3, 7)), np.empty((40, 3, 7))
        drag_loads_numpy(pv, pq if quad else None, s2, v, slice(1, 8), ref)
        fn(pv, pq, s2, v, 1, quad, got)
        ok &= bool(np.array_equal(ref, got))
    return ok


def drag_loads(pv: np.ndarray, pq: np.ndarray | None, s2: np.ndarray | None, v: np.ndarray, sel,
               loads: np.ndarray) -> bool:
    """Fill loads (n_steps, n_real, n_free) [N] = pv v (+ (v² − s2) pq with the quadratic drag,
    pq and s2 given) on the free nodes ``sel`` of v (n_real, n_steps, n_nodes) [m/s]: compiled
    in one pass when the kernel is loaded and ``sel`` is a slice (returns True), else by
    :func:`drag_loads_numpy` (False).  The same bits either way."""
    if isinstance(sel, slice) and use(0.0) and _state.get("loads"):
        quad = pq is not None
        _state["fns"].drag_loads(pv, pq if quad else pv, s2 if quad else pv, v, int(sel.start), quad, loads)
        return True
    drag_loads_numpy(pv, pq, s2, v, sel, loads)
    return False


def _field_test(fns) -> bool:
    """The compiled analytic downburst field gives :meth:`DownburstField.velocity`'s numpy bits
    (points inside and outside r_max, at the centre, before and after the peak of Pi(t))."""
    from .wind.mean import DownburstField

    field = DownburstField(jet_diameter=600.0, height=15.0, centre=(450.0, -700.0), t_ref=300.0,
                           translation=(3.0, 8.0), v_max=41.3, point_p=450.0, window=(0.0, 600.0),
                           r_max=780.0, radial_decay=430.0, z_max=50.0, delta=272.0, t1=300.0, t_f=1200.0)
    x = np.concatenate([np.linspace(0.0, 1800.0, 37), [712.5]])
    t = np.concatenate([np.linspace(0.0, 900.0, 41), [387.5]])  # the centre crosses the line at x = 712.5
    ref = field.velocity_numpy(x, t)
    got = field_velocity(field, x, t, fns)
    return got is not None and all(np.array_equal(a, b) for a, b in zip(ref, got))


def field_velocity(field, x: np.ndarray, t: np.ndarray, fns=None) -> tuple[np.ndarray, np.ndarray] | None:
    """:meth:`~linecheck.core.wind.mean.DownburstField.velocity` of the analytic field (Holmes &
    Oliver 2000 radial profile, Wood et al. 2001 height factor, Chay et al. 2006 Pi(t)) in two
    compiled passes with the same bits: r and the Gaussian's exponent, numpy's exp on the whole
    array (as the numpy form takes it), then the profile, the speed and the vector sum with the
    translation.  None when the kernel is not loaded or did not give the numpy bits at load.
    x [m] (n_x,), t [s] (n_t,) -> (v_x, v_y) [m/s], each (n_t, n_x)."""
    if fns is None:
        if not (use(0.0) and _state.get("field")):
            return None
        fns = _state["fns"]
    from .wind.mean import intensity, vertical_profile

    x = np.ascontiguousarray(x, dtype=float)
    t = np.ascontiguousarray(t, dtype=float)
    cx, cy = (np.ascontiguousarray(np.broadcast_to(c, t.shape), dtype=float) for c in field.centre_at(t))
    r = np.empty((t.size, x.size))
    z = np.empty_like(r)
    fns.field_radius(x, cx, cy, float(field.r_max), float(field.radial_decay), r, z)
    e = np.exp(z, out=z)
    fz = float(vertical_profile(field.height, field.delta))
    pi = np.ascontiguousarray(intensity(t, field.t1, field.t_f), dtype=float)
    vx, vy = np.empty_like(r), np.empty_like(r)
    fns.field_velocity(x, cx, cy, r, e, float(field.r_max), fz, pi, float(field.v_max),
                       float(field.translation[0]), float(field.translation[1]), vx, vy)
    return vx, vy


def _quad_test(fn) -> bool:
    """The compiled coherence quadrature gives :func:`~linecheck.core.spectral._quad_kms_nodes`'
    bits (one coherence for all gaps and one per gap, signs of zeros included)."""
    from .spectral import _quad_kms_nodes

    rng = np.random.default_rng(27)
    w = rng.standard_normal((9, 13, 37)) + 1j * rng.standard_normal((9, 13, 37))
    w[:, 3] = 0.0  # a node without load
    ok = True
    for rho in (rng.random(37), rng.random((12, 37))):
        ref = _quad_kms_nodes(w, rho, compiled=False)
        got = np.empty(ref.shape)
        fn(w, np.ascontiguousarray(np.atleast_2d(rho)), rho.ndim == 2, got)
        ok &= bool(np.array_equal(got, ref) and np.array_equal(np.signbit(got), np.signbit(ref)))
    return ok


def quad_kms(w: np.ndarray, rho: np.ndarray) -> np.ndarray | None:
    """:func:`~linecheck.core.spectral._quad_kms_nodes` of w (K, N, F) complex in one compiled
    pass (the same bits; None when the kernel is not loaded or differed at load)."""
    if not (use(0.0) and _state.get("quad")):
        return None
    w = np.ascontiguousarray(w, dtype=complex)
    out = np.empty((w.shape[0], w.shape[2]))
    _state["fns"].quad_kms(w, np.ascontiguousarray(np.atleast_2d(rho), dtype=float), rho.ndim == 2, out)
    return out


def _span_test(fn) -> bool:
    """The compiled span-tension integrands give :func:`~linecheck.core.static.span_terms`'
    bits (one and several states, with and without e)."""
    from .static import span_terms as ref_terms

    rng = np.random.default_rng(25)
    ok = True
    for lead in ((), (3,)):
        by = rng.standard_normal(lead + (4, 9)) * 1e4  # per state (step 1's loads), as static passes it
        bz = rng.standard_normal((4, 9)) * 1e4
        ay, az = (rng.standard_normal(lead + (4, 1)) * 0.05 for _ in range(2))
        H = rng.uniform(1e4, 5e4, lead + (4,))
        l = rng.uniform(300.0, 500.0, lead + (4,))
        for ll in (None, l):
            ref = ref_terms(ay, az, by, bz, H, 3.2e7, ll)
            got = span_terms(ay, az, by, bz, H, 3.2e7, ll, fn)
            ok &= len(ref) == len(got) and all(np.array_equal(x, y) for x, y in zip(ref, got))
    return ok


def span_terms(ay: np.ndarray, az: np.ndarray, by: np.ndarray, bz: np.ndarray, H: np.ndarray, EA: float,
               l: np.ndarray | None = None, fn=None) -> tuple[np.ndarray, ...]:
    """:func:`~linecheck.core.static.span_terms` (the span tension's Newton integrands) in one
    compiled pass with the same bits, when the kernel verified it at load (else the numpy form).
    Shapes: ay, az (..., n_spans, 1); by, bz (..., n_spans, n_gp); H, l (..., n_spans)."""
    if fn is None:
        if not _state.get("span"):
            from .static import span_terms as ref_terms

            return ref_terms(ay, az, by, bz, H, EA, l)
        fn = _state["fns"].span_terms
    n_spans, n_gp = by.shape[-2:]
    H2 = np.ascontiguousarray(H, dtype=float).reshape(-1, n_spans)

    def per_state(b):  # (1 or n, n_spans, n_gp): one for all states or one per state
        b = np.asarray(b, dtype=float).reshape(-1, n_spans, n_gp)
        if b.shape[0] not in (1, H2.shape[0]):
            raise ValueError(f"span_terms: load shape {b.shape} does not match {H.shape}")
        return np.ascontiguousarray(b)

    shape = np.broadcast_shapes(H.shape + (1,), by.shape, bz.shape)
    out = [np.empty(shape) for _ in range(2 if l is None else 3)]
    flat = [x.reshape(-1, n_spans, n_gp) for x in out]
    fn(np.ascontiguousarray(ay, dtype=float).reshape(-1, n_spans), np.ascontiguousarray(az, dtype=float).reshape(-1, n_spans),
       per_state(by), per_state(bz), H2, float(EA), H2 if l is None else np.ascontiguousarray(l, dtype=float).reshape(-1, n_spans),
       l is not None, flat[0], flat[1], flat[-1])
    return tuple(out)


def _reductions_test(fn) -> bool:
    """The compiled reductions over time give :func:`~linecheck.core.results.history_reductions`'
    bits (the mean held, and one per sample as with peak windows)."""
    from .results import history_reductions as ref_fn

    rng = np.random.default_rng(26)
    B, R = rng.standard_normal((2, 3, 257, 2, 3)) * 1e3
    sa = rng.standard_normal((2, 3)) * 1e4
    ok = True
    for m in (1, 3):
        M = rng.standard_normal((m, 257, 2, 3)) * 1e4
        ref = ref_fn(M, B, R, sa)
        got = history_reductions(M, B, R, sa, fn)
        ok &= all(np.array_equal(x, y) for x, y in zip(ref, got))
    return ok


def history_reductions(M: np.ndarray, background: np.ndarray, resonant: np.ndarray, still_air: np.ndarray,
                       fn=None) -> tuple[np.ndarray, ...]:
    """:func:`~linecheck.core.results.history_reductions` (the statistics' r.m.s. values and peaks
    over time) in one compiled pass with the same bits when the kernel verified it at load, else
    the numpy form (issue 20: ≈ 0.1 s of a ten-realization six-span run, ten numpy passes)."""
    if fn is None:
        if not (use(0.0) and _state.get("reductions")):
            from .results import history_reductions as ref_fn

            return ref_fn(M, background, resonant, still_air)
        fn = _state["fns"].history_reductions
    B = np.ascontiguousarray(background, dtype=float)
    out = np.empty((7, B.shape[0]) + B.shape[2:])
    fn(np.ascontiguousarray(M, dtype=float), B, np.ascontiguousarray(resonant, dtype=float),
       np.ascontiguousarray(still_air, dtype=float), out)
    return tuple(np.array(o) for o in out)  # seven arrays of their own, as numpy's


def _second_order_test(fns, gemm: int | None = None) -> bool:
    """The compiled second-order passes give the numpy form's bits through
    :func:`~linecheck.core.second_order.second_order_reactions` (in node bases and global) and
    ``second_order_of_loads``, on an operator of random numbers with two runs of free nodes,
    insulators, rows of zeros and a padded last block; else the numpy passes are used (their 3 x 3
    products are OpenBLAS's, whose kernels may round differently on another machine).  With
    ``gemm`` (numpy's cblas_sgemm) the whole block loop of ``_loops.so_history`` is compared."""
    from scipy.linalg import lapack

    from .second_order import SecondOrder, second_order_of_loads, second_order_reactions

    rng = np.random.default_rng(28)
    n_nodes, n_s, n_r = 21, 3, 7
    free = np.r_[1:10, 11:20]  # nodes 0, 10 and 20 pinned
    n_el = n_nodes - 1
    e = rng.standard_normal((n_el + n_s, 3))
    op = SecondOrder(
        e=(e / np.linalg.norm(e, axis=1)[:, None]).ravel(), c=np.ones(n_el + n_s), n_nodes=n_nodes,
        pinned=np.array([0, 10, 20]), runs=((1, 10, 0), (11, 20, 9)), ins_free=np.array([4, 10, 15]),
        A=np.zeros((3 * (n_el + n_s), n_r)), W=rng.standard_normal((3 * n_el + 3 * n_s, n_r)) * 1e3,
        ins_nodes=np.array([5, 12, 17]), ins_frame=np.linalg.qr(rng.standard_normal((n_s, 3, 3)))[0])
    T = np.linalg.qr(rng.standard_normal((free.size, 3, 3)))[0]
    U = rng.standard_normal((300, 3 * free.size)) * 0.2
    U[[0, 7, 150]] = 0.0
    U[:, 4] = -0.0
    L = rng.standard_normal((150, free.size))
    L[[3, 90]] = 0.0
    kd, n = 5, 3 * free.size  # a banded stiffness's factor (dpbtrf, upper)
    ab = rng.uniform(-1.0, 1.0, (kd + 1, n)) * 1e3
    ab[kd] = 1e4 * (kd + 1) * (1.0 + rng.uniform(0.0, 1.0, n))
    c = lapack.dpbtrf(ab, lower=0)[0]
    dirs = rng.standard_normal((free.size, 3))
    dirs /= np.linalg.norm(dirs, axis=1)[:, None]
    ok = True
    Ut = np.ascontiguousarray(U.T)  # the compiled Newmark loop's dof-major history
    for t in (T, None):
        ref = second_order_reactions(op, U, t, passes=None, gemm=None)
        for got in (second_order_reactions(op, U, t, passes=fns, gemm=gemm),
                    second_order_reactions(op, Ut, t, transposed=True, passes=fns, gemm=gemm)):
            ok &= bool(np.array_equal(ref, got) and np.array_equal(np.signbit(ref), np.signbit(got)))
    for d in (None, dirs):
        ref = second_order_of_loads(op, L, c, d, passes=None, gemm=None)
        got = second_order_of_loads(op, L, c, d, passes=fns, gemm=gemm)
        ok &= bool(np.array_equal(ref, got) and np.array_equal(np.signbit(ref), np.signbit(got)))
    return ok


def _numpy_cblas_sgemm() -> int | None:
    """The address of the ``cblas_sgemm`` that numpy's ``matmul`` calls for float32 arrays, when
    numpy is built on scipy-openblas with 64-bit integers (numpy's own wheels: the symbol ``scipy_cblas_sgemm64_``
    of the OpenBLAS library numpy loaded), else None.  The library is the one already in the
    process (Linux: /proc/self/maps; else the folder numpy's wheels bundle it in), so the kernel
    selected for this CPU is numpy's too; the load test then checks the bits."""
    import ctypes
    import glob

    try:
        blas = np.show_config(mode="dicts")["Build Dependencies"]["blas"]
        if blas.get("name") != "scipy-openblas" or "USE64BITINT" not in str(blas.get("openblas configuration", "")):
            return None
    except Exception:  # pragma: no cover - a numpy without the dict form of its build configuration
        return None
    paths = []
    try:
        with open("/proc/self/maps") as f:
            paths = [line.split()[-1] for line in f if "openblas" in line and "/" in line]
    except OSError:  # pragma: no cover - not Linux
        pass
    here = os.path.dirname(np.__file__)
    for pattern in ("../numpy.libs/*openblas*", ".dylibs/*openblas*"):
        paths += glob.glob(os.path.join(here, pattern))
    for path in dict.fromkeys(paths):
        try:
            fn = ctypes.CDLL(path).scipy_cblas_sgemm64_
        except (OSError, AttributeError):
            continue
        return int(ctypes.cast(fn, ctypes.c_void_p).value)
    return None


def second_order_sgemm() -> int | None:
    """The address of numpy's ``cblas_sgemm`` for :func:`linecheck.core._loops.so_history` (the
    second-order tension's whole block loop compiled, BLAS calls included, without the GIL) when the
    kernel is loaded and that loop gave the numpy form's bits at load, else None."""
    if not (use(0.0) and _state.get("so_history")):
        return None
    return _state["sgemm"]


def second_order_passes():
    """The compiled elementwise passes of the second-order tension (issue 16; ``so_nodes``,
    ``so_frame``, ``so_products`` of :mod:`linecheck.core._loops`) when the kernel is loaded and
    they gave the numpy form's bits at load, else None (the numpy passes run)."""
    if not (use(0.0) and _state.get("second_order")):
        return None
    return _state["fns"]


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
                ok = fns is not None and _self_test(fns)
                rot = ok and _rotate_test(fns.rotate)
                dot = ok and _rowdot_test(fns.rowdot)
            except Exception:  # a Numba that cannot compile or cache here: the numpy loop (same bits)
                fns, ok, rot, dot = None, False, False, False
            _state["ok"] = ok
            _state["fns"] = fns if ok else None
            _state["rotate"] = rot
            _state["rowdot"] = dot
            _state["spectrum"] = ok and _spectrum_test(fns)
            _state["loads"] = ok and _loads_test(fns.drag_loads)
            _state["span"] = ok and _span_test(fns.span_terms)
            _state["reductions"] = ok and _reductions_test(fns.history_reductions)
            _state["field"] = ok and _field_test(fns)
            _state["quad"] = ok and _quad_test(fns.quad_kms)
            _state["second_order"] = ok and _second_order_test(fns)
            _state["sgemm"] = _numpy_cblas_sgemm() if _state["second_order"] else None
            _state["so_history"] = _state["sgemm"] is not None and _second_order_test(fns, _state["sgemm"])
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
        rest: off-diagonal structural damping C~_off (:class:`~linecheck.core.model.CSRArrays`, read by its diagonals) or None; a1: [1/s] 2/Δt.
        out: receives u after every step, dof-major (n_dof, >= n_b n_real): column k n_real + r
            is realization r after step k; with no columns (n_dof, 0) nothing is written (only the
            second-order tension reads the states: ``second_order_reactions(transposed=True)``).
        nz, GT, cols: the stepper's sparse reaction rows (:func:`~linecheck.core.dynamics._sparse_rows`).
        R: [N] receives the reactions G T u~ after every step, (n_b, n_real, n_r) (the bits of
            :func:`~linecheck.core.dynamics._sparse_reactions`).
    """
    fns = _state["fns"]
    steps = fns.steps_1 if U.shape[0] == 1 else fns.steps
    if rest is None:
        steps(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, False, _NO_BAND, a1, out, nz, GT, cols, R)
    else:
        steps(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, True, rest.band, a1, out, nz, GT, cols, R)


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
