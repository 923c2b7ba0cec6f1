"""The optional compiled kernel (``linecheck[fast]``: Numba): compiled forms of the hot loops.

Without Numba, or with ``LINECHECK_KERNEL=numpy``, the numpy code runs everywhere.  With it, the
kernel is made of *pieces* (:data:`PIECES`), each a compiled form of one numpy computation:

- ``newmark``: the Newmark step loop of steps 2-3 (:func:`newmark_block`: one compiled loop over
  the steps of a block, the reactions G u of every step included) and the banded Cholesky solves
  of a long line's step 3 (:func:`background`, :func:`solve_columns`);
- ``rotate``: the change of node bases between mean states (:func:`rotate`);
- ``rowdot``: step 3's static transfer X Bᵀ (:func:`rowdot`);
- ``spectrum``: the wind synthesis' phasors and coherence recursion (:func:`coherent_spectrum`);
- ``mixing``: the many-wire synthesis' mixing across wires (:func:`mix_wires`);
- ``loads``: the fluctuating drag loads (:func:`drag_loads`);
- ``span``: step 1's span-tension Newton integrands (:func:`span_terms`);
- ``reductions``: the statistics' r.m.s. values and peaks over time (:func:`history_reductions`);
- ``field``: the analytic downburst field over the record (:func:`field_velocity`);
- ``quad``: the frequency-domain check's coherence quadrature (:func:`quad_kms`);
- ``second_order``: the second-order tension's elementwise passes per block of rows
  (:func:`second_order_passes`);
- ``second_order_loop``: its whole block loop with the BLAS product P W (scipy's ``dgemm``
  called from compiled code, without the GIL: :func:`second_order_dgemm`).

**Equivalence by tolerance, not by bits.**  A compiled piece and its numpy form compute the same
quantity in a different operation order (fused multiply-adds, other summation orders, another
BLAS), and OpenBLAS itself picks its kernels per CPU (Haswell, SkylakeX, Zen, ...), which round
differently.  So the two forms agree within a stated tolerance, never bit for bit: when the
kernel loads, every piece is run on test data beside its numpy form and is used only if the
largest difference is within :data:`RTOL` (relative 1e-12 of the largest |value| of the compared
array; the float64 forms differ by ~1e-16..1e-14 of it).  A piece whose check fails (or whose
compilation fails) falls back to numpy *alone*; :func:`status` says which pieces are on and why
the others are off (``linecheck info``; run and batch print one warning line).

**Determinism.**  Whether a piece runs depends only on the installation and ``LINECHECK_KERNEL``
(not on how much work a call has, nor on what the process ran before), and every realization is
computed by itself (its own row, fixed-size BLAS calls), so the same case, seed and machine give
the same bits whatever ``--jobs``, chunking, executor or ``--resume``.

The compiled functions are in :mod:`linecheck.core._loops` (module level, so that Numba's disk
cache finds them again in the next process); this module imports it, and with it Numba, only when
a piece is first asked for; the rest of the core imports numpy and scipy only.  Loading costs
≈ 0.5 s per process with a warm cache (the first compilation after installing, ≈ 10-20 s).
"""

from __future__ import annotations

import importlib.util
import os
import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

#: [-] largest allowed difference between a compiled piece and its numpy form at the load check,
#: relative to the largest |value| of the compared array: float64 forms of the same arithmetic in
#: another order differ by a few ulps per operation (~1e-16 relative), ~1e-14 after the
#: condition numbers of the test systems (≤ 1e2); 1e-12 leaves a factor 100 while any real
#: defect (a wrong index, a missed term) shows as 1e-3 or more
RTOL = 1e-12

#: the pieces and what each computes
PIECES: dict[str, str] = {
    "newmark": "Newmark step loop and banded solves (steps 2-3)",
    "rotate": "change of node bases between mean states",
    "rowdot": "step 3's static transfer",
    "spectrum": "wind synthesis: phasors and coherence recursion",
    "mixing": "wind synthesis of many wires: mixing across wires",
    "loads": "fluctuating drag loads",
    "span": "step 1's span-tension integrands",
    "reductions": "statistics: r.m.s. values and peaks over time",
    "field": "analytic downburst field",
    "quad": "frequency-domain coherence quadrature",
    "second_order": "second-order tension: elementwise passes",
    "second_order_loop": "second-order tension: block loop with BLAS, no GIL",
}


@dataclass(frozen=True)
class PieceState:
    """One piece of the kernel: ``on`` when it runs compiled; ``reason`` ("" when on) says why not."""

    name: str
    on: bool
    reason: str
    description: str


_lock = threading.RLock()  # re-entrant: a piece's check may ask for the piece it requires
_fns = None  # the compiled module (linecheck.core._loops) once loaded
_pieces: dict[str, PieceState] = {}  # filled per piece by its load check (_state)
_checks: dict[str, Callable[[object], float]] = {}  # piece -> load check (register_check)
_numpy_forms: dict[str, Callable] = {}  # piece -> numpy form an entry point falls back to
_dgemm_address: int | None = None  # scipy's dgemm for the compiled second-order loop
_NO_BAND = np.zeros((1, 1))  # the remainder argument of a stepper without one

#: a piece that runs only when another one is on
_REQUIRES = {"second_order_loop": "second_order"}


def register_check(piece: str, check: Callable[[object], float], numpy: Callable | None = None) -> None:
    """Register ``piece``'s load check: ``check(fns)`` runs the compiled functions ``fns`` (the
    module :mod:`linecheck.core._loops`) on test data beside the numpy form and returns the
    largest relative difference (:func:`worst_difference`); it runs the first time the piece is
    asked for (:func:`use`, :func:`status`).  ``numpy``: the numpy form the piece's entry point
    falls back to when the piece is off (entry points that return None instead need none).

    The core module that owns a piece's numpy form registers it when imported;
    :mod:`linecheck.core.pieces` imports all of them (for a full :func:`status`)."""
    if piece not in PIECES:
        raise ValueError(f"unknown kernel piece {piece!r}")
    _checks[piece] = check
    if numpy is not None:
        _numpy_forms[piece] = numpy


def mode() -> str:
    """``LINECHECK_KERNEL``: "auto" (default: compiled pieces where Numba is installed), "numpy"
    (never compile) or "numba" (as auto; kept for scripts that force the kernel)."""
    m = os.environ.get("LINECHECK_KERNEL", "auto").strip().lower()
    return m if m in ("auto", "numpy", "numba") else "auto"


def installed() -> bool:
    """Whether Numba can be imported (found without importing it)."""
    return importlib.util.find_spec("numba") is not None


def loaded() -> bool:
    """Whether this process has loaded (or tried to load) the kernel."""
    return bool(_pieces)


def _one_line(e: BaseException) -> str:
    text = " ".join(f"{type(e).__name__}: {e}".split())
    return text if len(text) <= 160 else text[:157] + "..."


def relative_difference(ref, got) -> float:
    """Largest |got - ref| over the largest |ref| of one array (inf on a shape or finiteness mismatch)."""
    ref, got = np.asarray(ref), np.asarray(got)
    if ref.shape != got.shape or not np.array_equal(np.isfinite(ref), np.isfinite(got)):
        return np.inf
    fin = np.isfinite(ref)
    if not fin.any():
        return 0.0
    scale = float(np.max(np.abs(ref[fin])))
    diff = float(np.max(np.abs(got[fin] - ref[fin])))
    return diff / scale if scale > 0 else (0.0 if diff == 0 else np.inf)


def worst_difference(pairs) -> float:
    """The largest :func:`relative_difference` over (ref, got) pairs (what a load check returns)."""
    return max((relative_difference(r, g) for r, g in pairs), default=0.0)


def _load() -> None:
    """Import Numba and the compiled loops; when that fails, every piece is off with the reason."""
    global _fns, _dgemm_address
    if not installed():
        _pieces.update({k: PieceState(k, False, "Numba not installed (linecheck[fast])", d) for k, d in PIECES.items()})
        return
    try:
        from . import _loops  # imports Numba
    except Exception as e:  # a Numba that cannot import or compile here: numpy everywhere
        why = f"Numba failed to load: {_one_line(e)}"
        _pieces.update({k: PieceState(k, False, why, d) for k, d in PIECES.items()})
        return
    _fns = _loops
    try:
        _dgemm_address = _loops.scipy_dgemm()
    except Exception:  # pragma: no cover - a scipy without cython_blas
        _dgemm_address = None


def _checked(name: str) -> PieceState | None:
    """Run one piece's load check: on when its difference from numpy is within :data:`RTOL`;
    None when no module has registered it yet (not remembered: asked again later)."""
    desc = PIECES[name]
    check = _checks.get(name)
    if check is None:
        return None
    need = _REQUIRES.get(name)
    if need is not None and not _state(need).on:
        return PieceState(name, False, f"needs the piece {need}", desc) if need in _pieces else None
    if name == "second_order_loop" and _dgemm_address is None:  # pragma: no cover - no LP64 dgemm
        return PieceState(name, False, "scipy's cython_blas dgemm not found", desc)
    try:
        d = check(_fns)
    except Exception as e:  # compilation or the compiled call failed: this piece only
        return PieceState(name, False, f"load check failed: {_one_line(e)}", desc)
    if not d <= RTOL:
        return PieceState(name, False, f"load check: differs from numpy by {d:.1e} of the largest value "
                                       f"(allowed {RTOL:.0e})", desc)
    return PieceState(name, True, "", desc)


def _state(piece: str) -> PieceState:
    """``piece``'s state: loads the kernel on the first call, then runs the piece's check once."""
    s = _pieces.get(piece)
    if s is not None:
        return s
    with _lock:
        if not _pieces:
            _load()
        s = _pieces.get(piece)
        if s is None:
            s = _checked(piece)
            if s is None:
                return PieceState(piece, False, "no load check registered (linecheck.core.pieces not imported)",
                                  PIECES[piece])
            _pieces[piece] = s
        return s


def status() -> tuple[PieceState, ...]:
    """Every piece's state (loads the kernel and runs every registered check first unless
    ``LINECHECK_KERNEL=numpy``; import :mod:`linecheck.core.pieces` for all of them)."""
    if mode() == "numpy":
        return tuple(PieceState(k, False, "LINECHECK_KERNEL=numpy", d) for k, d in PIECES.items())
    return tuple(_state(k) for k in PIECES)


def _ensure() -> None:
    """Load the compiled module (for entry points whose caller checked :func:`use`)."""
    if _fns is None:
        with _lock:
            if _fns is None:
                _load()


def use(piece: str) -> bool:
    """Whether ``piece`` runs compiled in this process (loads the kernel and checks the piece on
    the first call).  The answer depends only on the installation, ``LINECHECK_KERNEL`` and the
    piece's load check, so every run of a case on one machine takes the same path."""
    if os.environ.get("LINECHECK_KERNEL") is not None and mode() == "numpy":  # asked per call: cheap
        return False
    s = _pieces.get(piece)
    return s.on if s is not None else _state(piece).on


def available() -> bool:
    """Whether any piece of the kernel runs compiled here (loads it on the first call)."""
    return mode() != "numpy" and any(p.on for p in status())


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


def _loads_check(fns) -> float:
    """The compiled drag loads against :func:`drag_loads_numpy` (linear and quadratic drag)."""
    rng = np.random.default_rng(24)
    v = rng.standard_normal((3, 40, 9))
    pv, pq, s2 = (rng.random((40, 9))[:, 1:8] for _ in range(3))  # strided, as the slices of the service
    pairs = []
    for quad in (False, True):
        ref, got = np.empty((40, 3, 7)), np.empty((40, 3, 7))
        drag_loads_numpy(pv, pq if quad else None, s2, v, slice(1, 8), ref)
        fns.drag_loads(pv, pq, s2, v, 1, quad, got)
        pairs.append((ref, got))
    return worst_difference(pairs)


register_check("loads", _loads_check)  # its numpy form is here (the other pieces': linecheck.core.pieces)


# ---- the pieces' entry points: each runs compiled when its piece is on, else returns None (the
# caller runs the numpy form) or runs the numpy form itself

def phasors(phases: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """The unit phasors (cos phi, sin phi) of phases [rad] (n_nodes, n_freq), compiled (the
    values :func:`coherent_spectrum` uses), or None when the piece ``spectrum`` is off.  They
    depend on the seed, the realization, the nodes and the grid only, so a scan's positions can
    share them (turbulence.unit_phases)."""
    if not use("spectrum"):
        return None
    phases = np.ascontiguousarray(phases, dtype=float)
    xr, xi = np.empty_like(phases), np.empty_like(phases)
    _fns.phasors(phases, xr, xi)
    return xr, xi


def coherent_spectrum(phases, rho_rows: np.ndarray, row_of_gap: np.ndarray, amp: np.ndarray,
                      m: int, *, s_rows: np.ndarray | None = None, out: np.ndarray | None = None) -> np.ndarray | None:
    """The synthesis spectrum of ordered nodes (turbulence.synthesize), compiled, or None when
    the piece ``spectrum`` is off.

    phases [rad] (n_nodes, n_freq), or their :func:`phasors` (cos, sin) already computed;
    rho_rows [-] neighbour coherence rows (n_rows, n_freq) and the row of every gap (n_nodes - 1,)
    (equal gaps: one row); amp [-] cosine amplitudes (n_freq,); m the FFT length.  Returns
    (n_nodes, m // 2 + 1) complex: column k + 1 = (m/2) amp_k y_k with y the KMS / Markov
    recursion of the unit phasors (Deodatis 1996).

    ``s_rows``: sqrt(max(1 - rho_rows², 0)) when the caller has it (a many-wire synthesis computes
    it once for every wire; the same values as computed here); ``out``: a C-ordered complex array
    of that shape, zero outside columns 1 .. n_freq, filled and returned instead of a new one."""
    if not use("spectrum"):
        return None
    xr, xi = phases if isinstance(phases, tuple) else phasors(phases)
    rho_rows = np.ascontiguousarray(rho_rows, dtype=float)
    if s_rows is None:
        s_rows = np.sqrt(np.maximum(1.0 - rho_rows * rho_rows, 0.0))
    spec = np.zeros((xr.shape[0], m // 2 + 1), dtype=complex) if out is None else out
    _fns.coherent_spectrum(xr, xi, rho_rows, np.ascontiguousarray(s_rows, dtype=float),
                           np.ascontiguousarray(row_of_gap, dtype=np.int64),
                           np.ascontiguousarray(amp, dtype=float), 0.5 * m, spec)
    return spec


def mix_wires(spec: np.ndarray, low: np.ndarray, k0: int) -> None:
    """The many-wire synthesis' mixing across wires (:func:`~linecheck.core.wind.wires.mix_wires_numpy`),
    in place: spec (n_p, n_nodes, n_bins) complex (C-ordered), the points' single-wire spectra;
    low [-] (n_p, n_p, n_freq) the lower factor L_w(f); bins k0 .. k0 + n_freq - 1 of every point
    p >= 1 become sum_(q <= p) L_w[p, q] times point q's.  Compiled in one pass when the piece
    ``mixing`` is on, else the numpy form (registered with the piece's check)."""
    if not use("mixing"):
        _numpy_forms["mixing"](spec, low, k0)
        return
    _fns.mix_wires(spec, np.ascontiguousarray(low, dtype=float), int(k0))


def drag_loads(pv: np.ndarray, pq: np.ndarray | None, s2: np.ndarray | None, v: np.ndarray, sel,
               loads: np.ndarray) -> bool:
    """Fill loads (n_steps, n_real, n_free) [N] = pv v (+ (v² − s2) pq with the quadratic drag,
    pq and s2 given) on the free nodes ``sel`` of v (n_real, n_steps, n_nodes) [m/s]: compiled
    in one pass when the piece ``loads`` is on and ``sel`` is a slice (returns True), else by
    :func:`drag_loads_numpy` (False)."""
    if isinstance(sel, slice) and use("loads"):
        quad = pq is not None
        _fns.drag_loads(pv, pq if quad else pv, s2 if quad else pv, v, int(sel.start), quad, loads)
        return True
    drag_loads_numpy(pv, pq, s2, v, sel, loads)
    return False


def field_compiled(fns, field, x: np.ndarray, t: np.ndarray, fz: float, pi: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`field_velocity` by the compiled functions ``fns`` (also for the piece's load check):
    fz [-] the height factor f_z at the field's height, pi [-] Pi(t) at every t (n_t,)."""
    x = np.ascontiguousarray(x, dtype=float)
    t = np.ascontiguousarray(t, dtype=float)
    cx, cy = (np.ascontiguousarray(np.broadcast_to(c, t.shape), dtype=float) for c in field.centre_at(t))
    r = np.empty((t.size, x.size))
    z = np.empty_like(r)
    fns.field_radius(x, cx, cy, float(field.r_max), float(field.radial_decay), r, z)
    e = np.exp(z, out=z)
    pi = np.ascontiguousarray(pi, dtype=float)
    vx, vy = np.empty_like(r), np.empty_like(r)
    fns.field_velocity(x, cx, cy, r, e, float(field.r_max), float(fz), pi, float(field.v_max),
                       float(field.translation[0]), float(field.translation[1]), vx, vy)
    return vx, vy


def field_velocity(field, x: np.ndarray, t: np.ndarray, fz: float,
                   pi: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
    """:meth:`~linecheck.core.wind.mean.DownburstField.velocity` of the analytic field (Holmes &
    Oliver 2000 radial profile, Wood et al. 2001 height factor fz [-], Chay et al. 2006 Pi(t)
    given as pi [-] (n_t,)) in two compiled passes: r and the Gaussian's exponent, numpy's exp on
    the whole array, then the profile, the speed and the vector sum with the translation.  None
    when the piece ``field`` is off.  x [m] (n_x,), t [s] (n_t,) -> (v_x, v_y) [m/s], each (n_t, n_x)."""
    if not use("field"):
        return None
    return field_compiled(_fns, field, x, t, fz, pi)


def quad_kms(w: np.ndarray, rho: np.ndarray) -> np.ndarray | None:
    """:func:`~linecheck.core.spectral._quad_kms_nodes` of w (K, N, F) complex in one compiled
    pass, or None when the piece ``quad`` is off."""
    if not use("quad"):
        return None
    w = np.ascontiguousarray(w, dtype=complex)
    out = np.empty((w.shape[0], w.shape[2]))
    _fns.quad_kms(w, np.ascontiguousarray(np.atleast_2d(rho), dtype=float), rho.ndim == 2, out)
    return out


def span_compiled(fn, ay, az, by, bz, H, EA, l):
    """:func:`span_terms` by the compiled ``fn`` (``_loops.span_terms``; also for the load check)."""
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


def span_terms(ay: np.ndarray, az: np.ndarray, by: np.ndarray, bz: np.ndarray, H: np.ndarray, EA: float,
               l: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """:func:`~linecheck.core.static.span_terms` (the span tension's Newton integrands) in one
    compiled pass when the piece ``span`` is on, else the numpy form.
    Shapes: ay, az (..., n_spans, 1); by, bz (..., n_spans, n_gp); H, l (..., n_spans)."""
    if not use("span"):
        return _numpy_forms["span"](ay, az, by, bz, H, EA, l)
    return span_compiled(_fns.span_terms, ay, az, by, bz, H, EA, l)


def reductions_compiled(fn, M, background, resonant, still_air):
    """:func:`history_reductions` by the compiled ``fn`` (also for the load check)."""
    B = np.ascontiguousarray(background, dtype=float)
    out = np.empty((7, B.shape[0]) + B.shape[2:])
    fn(np.ascontiguousarray(M, dtype=float), B, np.ascontiguousarray(resonant, dtype=float),
       np.ascontiguousarray(still_air, dtype=float), out)
    return tuple(np.array(o) for o in out)  # seven arrays of their own, as numpy's


def history_reductions(M: np.ndarray, background: np.ndarray, resonant: np.ndarray,
                       still_air: np.ndarray) -> tuple[np.ndarray, ...] | None:
    """:func:`~linecheck.core.results.history_reductions` (the statistics' r.m.s. values and peaks
    over time) in one compiled pass, or None when the piece ``reductions`` is off."""
    if not use("reductions"):
        return None
    return reductions_compiled(_fns.history_reductions, M, background, resonant, still_air)


def second_order_dgemm() -> int | None:
    """The address of scipy's ``dgemm`` (scipy.linalg.cython_blas) for the compiled second-order
    block loop (:func:`linecheck.core._loops.so_history`) when the piece ``second_order_loop`` is
    on, else None."""
    return _dgemm_address if use("second_order_loop") else None


def second_order_passes():
    """The compiled elementwise passes of the second-order tension (``so_nodes``, ``so_frame``,
    ``so_products`` of :mod:`linecheck.core._loops`) when the piece ``second_order`` is on, else
    None (the numpy passes run)."""
    return _fns if use("second_order") else None


def rowdot(X: np.ndarray, BT: np.ndarray) -> np.ndarray:
    """X (m, n) @ BT (n, q), row by row (a row's result does not depend on the other rows):
    compiled when the piece ``rowdot`` is on, else :func:`~linecheck.core.dynamics.rowdot_numpy`."""
    if not use("rowdot"):
        return _numpy_forms["rowdot"](X, BT)
    out = np.empty((X.shape[0], BT.shape[1]))
    _fns.rowdot(np.ascontiguousarray(X), np.ascontiguousarray(BT), out)
    return out


def rotate(X: np.ndarray, old, new) -> np.ndarray:
    """Vectors (n_real, n_dof) from ``old``'s node bases (global if None) to ``new``'s: compiled
    when the piece ``rotate`` is on, else :func:`~linecheck.core.dynamics.st_rotate`."""
    if not use("rotate"):
        return _numpy_forms["rotate"](X, old, new)
    Y = np.array(X, dtype=float, order="C")
    _fns.rotate(Y, new.T if old is None else old.T, new.T, old is not None)
    return Y


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
        R: [N] receives the reactions G T u~ after every step, (n_b, n_real, n_r) (as
            :func:`~linecheck.core.dynamics._sparse_reactions`).
    """
    _ensure()
    fns = _fns  # piece ``newmark`` (the caller checked use("newmark"))
    steps = fns.steps_1 if U.shape[0] == 1 else fns.steps
    if rest is None:
        steps(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, False, _NO_BAND, a1, out, nz, GT, cols, R)
    else:
        steps(U, V, A, loads, ycoef, cu, cv, dm, r2, chat, True, rest.band, a1, out, nz, GT, cols, R)


def background(c: np.ndarray, L: np.ndarray, load_dirs: np.ndarray | None, sparse_g) -> np.ndarray:
    """Step 3 of a long line (:func:`~linecheck.core.dynamics.integrate`, above
    BACKGROUND_SOLVE_DOF; piece ``newmark``): the reactions G K^-1 P l of load rows L [N]
    (m, n_free), as building the right-hand sides, ``dpbtrs`` and ``_sparse_reactions`` do.

    c: Cholesky factor of K (upper band); load_dirs: (n_free, 3) or None (global y);
    sparse_g: ``_sparse_rows(G)`` (nz, GT, cols).  Returns R [N] (m, n_r)."""
    _ensure()  # piece ``newmark`` (the caller checked use("newmark"))
    nz, GT, cols = sparse_g
    R = np.empty((L.shape[0], GT.shape[1]))
    dirs = np.zeros((1, 3)) if load_dirs is None else np.ascontiguousarray(load_dirs, dtype=float)
    _fns.background(c, np.ascontiguousarray(L), dirs, load_dirs is None, nz, GT, cols, R)
    return R


def solve_columns(c: np.ndarray, B: np.ndarray) -> np.ndarray:
    """LAPACK ``dpbtrs`` (upper) on every column of B (n_dof, m), in place (piece ``newmark``).

    c: Cholesky factor of a banded SPD matrix (upper band storage, (BANDWIDTH + 1, n_dof));
    B: right-hand sides as columns.  Returns B (solved; LAPACK's own when the piece is off)."""
    if not use("newmark"):
        from scipy.linalg import lapack

        B[...] = lapack.dpbtrs(c, B, lower=0)[0]
        return B
    _fns.solve_columns(c, B)
    return B
