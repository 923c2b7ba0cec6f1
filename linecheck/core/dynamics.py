"""Steps 2 and 3: linear dynamics and quasi-static response under the fluctuating wind.

Step 2 (paper Eq. 6): M u'' + C(t) u' + K(t) u = F_w(t), Newmark's average-acceleration
method (gamma = 1/2, beta = 1/4; Bathe 1996 section 9.2.4) in total form, with K(t)
and C(t) taken from the step-1 mean state in force at each time step.  Step 3
(paper Eq. 14): K(t) u = F_w(t) gives the background B; the resonant part is
R = F - B.

Structure exploited: K, C and M are banded (half-bandwidth 5, 3x3 node
blocks); the recurrence is stepped in per-node bases in which M and the aerodynamic C
are diagonal (:func:`node_bases`), so that the per-step products are elementwise;
K_hat = K + 2/dt C + 4/dt^2 M is factorised once per mean state (banded Cholesky,
LAPACK dpbtrf), never per step; all realizations are columns of one right-hand side;
step 3 applies the static transfer matrix G K^-1 P.  For downbursts K(t), C(t) are
piecewise constant between
the mean-state instants (default), or linearly interpolated at every step
(``interpolate=True``, one factorisation per step) to show that the difference
is negligible (docs/validation.md).
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from . import kernel
from .banded import ColumnSolver, band_solve_pairs
from .banded import factor as _factor
from .banded import solve as _solve
from .errors import Cancelled, NumericalError
from .model import BANDWIDTH, CSRArrays, LinearModel, band_to_csr, band_to_csr_stack, rotate_band
from .node_bases import node_bases, node_bases_stack
from .second_order import second_order_of_loads, second_order_reactions

try:  # the kernel behind scipy's CSR @ dense product, called without the per-call dispatch
    from scipy.sparse._sparsetools import csr_matvecs as _csr_matvecs
except ImportError:  # pragma: no cover - a scipy without it: the public product (same bits)
    _csr_matvecs = None


@dataclass(frozen=True)
class Newmark:
    """Average-acceleration Newmark constants (Bathe 1996 Table 9.3, gamma = 1/2, beta = 1/4)."""

    dt: float

    @property
    def a0(self) -> float:
        return 4.0 / self.dt**2  # 1/(beta dt^2)

    @property
    def a1(self) -> float:
        return 2.0 / self.dt  # gamma/(beta dt)

    @property
    def a2(self) -> float:
        return 4.0 / self.dt  # 1/(beta dt)


#: values of the Newmark displacement history kept per block when the second-order tension
#: reads it (512 KB: it stays in the core's L2 cache between the steps and the second-order pass)
SECOND_ORDER_HISTORY = 65536
#: above this many DOFs step 3 solves the banded stiffness every step instead of applying the
#: dense static transfer matrix (O(n) instead of O(n^2) per step); the two agree to
#: rounding (tests), and smaller systems keep the transfer matrix (bit-identical to before)
BACKGROUND_SOLVE_DOF = 600


@dataclass(frozen=True)
class DynamicResponse:
    """Reaction histories of steps 2 and 3 (wind-induced fluctuating parts).

    Attributes:
        fluctuating: [N] F(t) = B + R at every tower, shape (n_real, n_steps, n_towers, 3).
        background: [N] B(t), same shape.
    """

    fluctuating: np.ndarray
    background: np.ndarray

    @property
    def resonant(self) -> np.ndarray:
        """[N] R = F - B (paper Fig. 4)."""
        return self.fluctuating - self.background


def integrate(
    models: list[LinearModel],
    damping: np.ndarray,
    state_of_step: np.ndarray,
    loads: np.ndarray,
    dt: float,
    *,
    direct: np.ndarray | None = None,
    model_at: Callable[[int], tuple[LinearModel, np.ndarray]] | None = None,
    second_order: list | None = None,
    second_order_start: int = 0,
    progress: Callable[[int, int], None] | None = None,
    cancel: threading.Event | None = None,
    load_dirs: np.ndarray | None = None,
) -> DynamicResponse:
    """Steps 2 and 3 for all realizations at once.

    Args:
        models: linear models of the mean states, length n_k (all with the same DOF map).
        damping: [N s/m] damping matrix of every mean state in upper band storage, shape
            (n_k, BANDWIDTH + 1, n_dof) (see :mod:`linecheck.core.damping`).
        state_of_step: index into ``models`` in force at every step, shape (n_steps,).
        loads: [N] fluctuating transverse (y) loads on the free nodes, shape
            (n_steps, n_real, n_free_nodes) (paper Eq. 5).
        dt: [s] time step.
        direct: [N] reactions caused directly by loads applied at pinned nodes,
            shape (n_steps, n_real, n_towers * 3) (added to both F and B).
        model_at: optional ``model_at(n) -> (model, damping band)``, the linear model of step n
            itself (reference scheme: the step-1 state interpolated in time, the model rebuilt
            and factorised every step); default: ``models[state_of_step[n]]``, piecewise constant.
        second_order: optional :class:`~linecheck.core.second_order.SecondOrder` operator of
            every mean state (same length as ``models``): the reactions of F and of B then
            include the second-order tension increment of their own displacement histories
            (with ``model_at`` the nearest state's operator), from step ``second_order_start``
            on (the steps before it, a burn-in the caller discards, keep the linear reactions).
        progress: ``progress(done, total)`` about every 1 % of the steps (per block).
        cancel: stop early (raises :class:`Cancelled`).
        load_dirs: [-] unit direction of every free node's transverse load, shape (n_free, 3)
            (a section: its span normals); None = the global y axis (a straight line).

    Returns:
        :class:`DynamicResponse` with tower reactions.  The record starts from the quasi-static
        solution at t = 0 (u0 = K^-1 F0, u'0 = 0): no background transient.
    """
    if not np.all(np.isfinite(loads)):
        raise NumericalError("non-finite fluctuating wind load")
    run = _Run(models, damping, state_of_step, loads, Newmark(dt), load_dirs, model_at, second_order,
               second_order_start, kernel.use("newmark"))
    R_B = _background(run)  # step 3
    R_F = _newmark(run, progress, cancel)  # step 2
    return _response(run, R_F, R_B, direct, progress)


def _response(run: _Run, R_F: np.ndarray, R_B: np.ndarray, direct: np.ndarray | None,
              progress: Callable[[int, int], None] | None) -> DynamicResponse:
    """R_F, R_B [N] (n_steps, n_real, n_r) checked finite, ``direct`` added to both, as the
    :class:`DynamicResponse` ((n_real, n_steps, n_towers, 3)); the last ``progress`` report."""
    if not (np.all(np.isfinite(R_F)) and np.all(np.isfinite(R_B))):
        raise NumericalError("non-finite response in the time integration")
    if direct is not None:
        R_F += direct
        R_B += direct
    if progress is not None:
        progress(run.n_steps, run.n_steps)
    shape = (run.n_steps, run.n_real, run.n_r // 3, 3)
    return DynamicResponse(
        fluctuating=np.ascontiguousarray(R_F.reshape(shape).transpose(1, 0, 2, 3)),
        background=np.ascontiguousarray(R_B.reshape(shape).transpose(1, 0, 2, 3)),
    )


@dataclass
class _Run:
    """What steps 2 and 3 of one :func:`integrate` call share: its arguments, the sizes, and
    the maps between the free nodes' transverse loads and the DOFs.  Vectors are kept
    "transposed", shape (n_real, n_dof) C-ordered, i.e. (n_dof, n_real) Fortran-ordered as
    LAPACK wants them: no copies in the step loop."""

    models: list[LinearModel]
    damping: np.ndarray  # [N s/m] (n_k, BANDWIDTH + 1, n_dof)
    state_of_step: np.ndarray  # (n_steps,)
    loads: np.ndarray  # [N] (n_steps, n_real, n_free)
    nm: Newmark
    load_dirs: np.ndarray | None  # [-] (n_free, 3) or None (global y)
    model_at: Callable[[int], tuple[LinearModel, np.ndarray]] | None
    second_order: list | None
    second_order_start: int
    compiled: bool  # the kernel's piece ``newmark`` (compiled step loop and banded solves)

    def __post_init__(self) -> None:
        self.n_steps, self.n_real, self.n_free = self.loads.shape
        self.n_dof = self.models[0].mass.size
        self.n_r = self.models[0].G.shape[0]
        self.ydof = 3 * np.arange(self.n_free) + 1  # node-major DOFs: y is the second of each node

    def model_of(self, n: int) -> tuple[LinearModel, np.ndarray]:
        """Linear model and damping band in force at step n."""
        if self.model_at is not None:
            return self.model_at(n)
        k = int(self.state_of_step[n])
        return self.models[k], self.damping[k]

    def loads_full(self, f: np.ndarray) -> np.ndarray:
        """y-loads [N] (m, n_free) -> full transposed right-hand sides (m, n_dof)."""
        out = np.zeros((f.shape[0], self.n_dof))
        if self.load_dirs is None:
            out[:, self.ydof] = f
        else:  # along every node's load direction
            out.reshape(f.shape[0], self.n_free, 3)[:] = f[..., None] * self.load_dirs
        return out

    def from_ydof(self, A: np.ndarray) -> np.ndarray:
        """Rows of a (n_dof, m) array combined along the load directions -> (n_free, m)."""
        if self.load_dirs is None:
            return A[self.ydof]
        return np.einsum("nca,nc->na", A.reshape(self.n_free, 3, -1), self.load_dirs)

    def so(self, n: int, U: np.ndarray) -> np.ndarray:
        """[N] second-order reactions (..., n_r) of global displacements U [m] (..., n_dof) under
        the state of step n."""
        op = self.second_order[int(self.state_of_step[n])]
        return second_order_reactions(op, U.reshape(-1, self.n_dof)).reshape(U.shape[:-1] + (self.n_r,))


# -------- step 3: the quasi-static background K u_B = F (paper Eq. 14), R_B = G u_B

def _background(run: _Run) -> np.ndarray:
    """[N] step 3's reactions R_B (n_steps, n_real, n_r): one factorisation per mean state (the
    static transfer, or on a long line banded solves), or per step with ``model_at``."""
    R_B = np.empty((run.n_steps, run.n_real, run.n_r))
    if run.model_at is not None:
        _background_per_step(run, R_B)
    elif run.n_dof > BACKGROUND_SOLVE_DOF:
        _background_solves(run, R_B)
    else:
        _background_transfer(run, R_B)
    return R_B


def _background_solves(run: _Run, R_B: np.ndarray) -> None:
    """A long line: the dense static transfer (n_free x n_r) would cost O(n^2) per step; solve
    K u_B = P l by the banded Cholesky instead (dpbtrs: column by column, so a realization's bits
    do not depend on what else is solved) and take G u_B sparsely."""
    n_dof, n_real, n_r, n_free = run.n_dof, run.n_real, run.n_r, run.n_free
    per = max(1, max(1, 2_000_000 // n_dof) // max(n_real, 1))  # right-hand sides per solve: ~16 MB
    for k in np.unique(run.state_of_step):
        c = _factor(run.models[k].K_band, np.zeros(n_dof), f"stiffness of mean state {k + 1}")
        sparse_g, solver = _sparse_rows(run.models[k].G), ColumnSolver(c)  # padded once per state
        all_steps = np.flatnonzero(run.state_of_step == k)
        for i0 in range(0, all_steps.size, per):
            steps = all_steps[i0:i0 + per]
            if run.compiled and run.second_order is None:  # the same arithmetic, compiled and fused
                R_B[steps] = kernel.background(c, run.loads[steps].reshape(-1, n_free), run.load_dirs,
                                               sparse_g).reshape(steps.size, n_real, n_r)
                continue
            rhs = run.loads_full(run.loads[steps].reshape(-1, n_free)).T  # (n_dof, m)
            UB = (kernel.solve_columns(c, rhs) if run.compiled else solver.columns(rhs)).T  # (m, n_dof), global
            R_B[steps] = _sparse_reactions(UB, *sparse_g).reshape(steps.size, n_real, n_r)
            sk = steps >= run.second_order_start
            if run.second_order is not None and sk.any():  # the quasi-static displacements themselves
                R_B[steps[sk]] += run.so(int(steps[sk][0]), UB.reshape(steps.size, n_real, n_dof)[sk])


def _background_transfer(run: _Run, R_B: np.ndarray) -> None:
    """Step 3 by the static transfer from the y-loads to the reactions, (G K^-1 P)^T =
    (K^-1 G^T)[y], one per mean state, applied row by row (:func:`kernel.rowdot`)."""
    n_dof, n_real, n_r, n_free = run.n_dof, run.n_real, run.n_r, run.n_free
    chunk = max(1, 8192 // max(n_real, 1))
    for k in np.unique(run.state_of_step):
        c = _factor(run.models[k].K_band, np.zeros(n_dof), f"stiffness of mean state {k + 1}")
        # K^-1 G^T by the band factor, compiled with the piece newmark (in place, on a copy of
        # G^T; dpbtrs copies its right-hand sides itself)
        GT = run.models[k].G.T
        TB = np.ascontiguousarray(run.from_ydof(kernel.solve_columns(c, np.array(GT, order="F")) if run.compiled
                                                else _solve(c, np.asfortranarray(GT))))  # (n_free, n_r)
        all_steps = np.flatnonzero(run.state_of_step == k)
        for i0 in range(0, all_steps.size, chunk):
            steps = all_steps[i0:i0 + chunk]
            R_B[steps] = kernel.rowdot(run.loads[steps].reshape(-1, n_free), TB).reshape(steps.size, n_real, n_r)
            sk = steps[steps >= run.second_order_start]
            if run.second_order is not None and sk.size:  # the quasi-static displacements themselves
                # K^-1 (loads along y or load_dirs) by the band factor; a run of consecutive
                # steps (one mean state) as a view of the loads, not a copy
                rows = slice(int(sk[0]), int(sk[-1]) + 1) if sk[-1] - sk[0] + 1 == sk.size else sk
                R_B[rows] += second_order_of_loads(run.second_order[k], run.loads[rows].reshape(-1, n_free), c,
                                                   run.load_dirs).reshape(sk.size, n_real, n_r)


def _background_per_step(run: _Run, R_B: np.ndarray) -> None:
    """Step 3 of the reference scheme (``model_at``): the model of every step factorised."""
    for n in range(run.n_steps):
        m, _ = run.model_of(n)
        c = _factor(m.K_band, np.zeros(run.n_dof), f"stiffness at step {n}")
        UB = _solve(c, run.loads_full(run.loads[n]).T).T
        R_B[n] = rowdot_numpy(UB, m.G.T)
        if run.second_order is not None and n >= run.second_order_start:
            R_B[n] += run.so(n, UB)


# -------- step 2: Newmark (Bathe 1996 Table 9.3), one factorisation per mean state, in node
# bases that make M and C diagonal (so that the per-step products are elementwise; see _Stepper)

def _newmark(run: _Run, progress: Callable[[int, int], None] | None,
             cancel: threading.Event | None) -> np.ndarray:
    """[N] step 2's reactions R_F (n_steps, n_real, n_r): the segments of steps under one
    linear model, cut into blocks run by the compiled or the numpy stepper (one interface,
    :class:`_BlockStepper`), the second-order tension added per block."""
    n_steps, n_real, n_r = run.n_steps, run.n_real, run.n_r
    m0, _ = run.model_of(0)
    chol = _factor(m0.K_band, np.zeros(run.n_dof), "stiffness at t = 0")
    U = _solve(chol, run.loads_full(run.loads[0]).T).T  # quasi-static start, (n_real, n_dof), global
    R_F = np.empty((n_steps, n_real, n_r))
    R_F[0] = rowdot_numpy(U, m0.G.T)
    if run.second_order is not None and run.second_order_start == 0:
        R_F[0] += run.so(0, U)
    stepper = (_CompiledSteps if run.compiled else _NumpySteps)(run, U)
    starts, ends = _segments(run)
    report = max(1, n_steps // 100)
    # the Newmark operators of all mean states in vectorised chunks; the reference scheme
    # (model_at) builds one operator per step instead
    stacked = (_StackedBases(run.models, run.damping, np.asarray(run.state_of_step)[starts], run.nm, run.load_dirs)
               if run.model_at is None else None)
    for s0, s1 in zip(starts, ends):
        stepper.enter(_Stepper.build(*run.model_of(int(s0)), run.nm, run.load_dirs) if stacked is None
                      else stacked.get(int(run.state_of_step[s0])))
        for b0 in range(int(s0), int(s1), stepper.block):
            b1 = min(b0 + stepper.block, int(s1))
            stepper.steps(b0, b1, R_F)
            c0 = max(b0, run.second_order_start)
            if run.second_order is not None and c0 < b1:  # from the node bases, u = T u~ node by node
                H, transposed = stepper.history(c0 - b0, b1 - b0)
                R2 = second_order_reactions(run.second_order[int(run.state_of_step[c0])], H, T=stepper.st.T,
                                            transposed=transposed)
                R_F[c0:b1] += R2.reshape(b1 - c0, n_real, n_r)
            if progress is not None and b1 // report != b0 // report:
                progress(b1, n_steps)
            if cancel is not None and cancel.is_set():
                raise Cancelled("step 2 cancelled")
    return R_F


def _segments(run: _Run) -> tuple[np.ndarray, np.ndarray]:
    """First and end steps of the runs of steps under one linear model (one mean state; every
    step with ``model_at``), from step 1 on (step 0 is the quasi-static start)."""
    n_steps = run.n_steps
    keys = np.arange(n_steps) if run.model_at is not None else np.asarray(run.state_of_step)
    starts = np.concatenate([[1], 2 + np.flatnonzero(keys[2:] != keys[1:-1])]) if n_steps > 1 else np.zeros(0, int)
    return starts, np.append(starts[1:], n_steps)


class _BlockStepper:
    """Newmark's average-acceleration steps of one :func:`integrate` call, block by block: the
    state U, V, A [m, m/s, m/s²] (n_real, n_dof) of every realization in the node bases of the
    current segment's :class:`_Stepper` ``st``.  :meth:`enter` changes the segment,
    :meth:`steps` runs a block and writes its reactions, :meth:`history` gives the block's
    displacements to the second-order tension."""

    def __init__(self, run: _Run, U: np.ndarray, block: int) -> None:
        self.run, self.block = run, block
        self.U, self.V, self.A = U, None, None  # U global until the first segment
        self.st: _Stepper | None = None

    def enter(self, new: _Stepper) -> None:
        """Move the state into the node bases of ``new`` (the segment's operator)."""
        st, rot = self.st, kernel.rotate  # the change of node bases (compiled when its piece is on)
        if st is None:
            self.U = rot(self.U, None, new)
            self.V = np.zeros_like(self.U)
            self.A = np.zeros_like(self.U)  # M a0 = F0 - K u0 - C v0 = 0
        else:
            # A rigid insulator: the attachment node has no velocity or acceleration along
            # the insulator axis (its axial displacement is the static one).  M and C have no
            # axial part, so the (-1)^n Newmark residue of that algebraic coordinate is
            # harmless while the axis stays put; it is removed when the mean state (and the
            # axis) changes, before it could leak into the tangential motion.
            self.V[:, st.axial] = 0.0
            self.A[:, st.axial] = 0.0
            self.U, self.V, self.A = (rot(X, st, new) for X in (self.U, self.V, self.A))
        self.st = new
        self.U, self.V, self.A = (np.ascontiguousarray(X) for X in (self.U, self.V, self.A))


class _CompiledSteps(_BlockStepper):
    """The compiled step loop (:func:`kernel.newmark_block`, piece ``newmark``): the same
    arithmetic as :class:`_NumpySteps`; it keeps only what the second-order tension reads,
    dof-major (n_dof, steps x realizations), which the second-order pass reads along its rows."""

    def __init__(self, run: _Run, U: np.ndarray) -> None:
        n = max(run.n_real * run.n_dof, 1)
        block = max(1, min(512, 2_000_000 // n))  # steps per block
        if run.second_order is not None:  # the history the second-order tension reads stays in
            # cache (L2: 512 instead of 3600 KB for case09-six; median run 30-90 ms faster, measured)
            block = max(1, min(block, SECOND_ORDER_HISTORY // n))
        super().__init__(run, U, block)
        self.hist = np.empty((run.n_dof, block * run.n_real if run.second_order is not None else 0))

    def steps(self, b0: int, b1: int, R_F: np.ndarray) -> None:
        st = self.st
        kernel.newmark_block(self.U, self.V, self.A, self.run.loads[b0:b1], st.ycoef, st.cu, st.cv, st.dm, st.r2,
                             st.chat, st.rest, st.a1, self.hist, st.nz, st.GT, st.cols, R_F[b0:b1])

    def history(self, i0: int, i1: int) -> tuple[np.ndarray, bool]:
        """Displacements of the block's steps i0..i1 in the node bases, dof-major (transposed)."""
        n_real = self.run.n_real
        return self.hist[:, i0 * n_real:i1 * n_real], True


class _NumpySteps(_BlockStepper):
    """The numpy step loop: work arrays reused every step (the loop allocates nothing), the new
    state written into U_new, V_new, A_new and the names swapped with the old ones; the block's
    history kept row-major for its reactions and the second-order tension."""

    def __init__(self, run: _Run, U: np.ndarray) -> None:
        super().__init__(run, U, max(1, min(512, 2_000_000 // max(run.n_real * run.n_dof, 1))))
        self.buf = np.empty((self.block, run.n_real, run.n_dof))

    def enter(self, new: _Stepper) -> None:
        super().enter(new)
        U, rest = self.U, new.rest
        self.work = tuple(np.empty_like(U) for _ in range(4))  # U_new, V_new, A_new, tmp
        self.rest_product = None if rest is None else _RestProduct(rest, new.a1, U.shape)
        self.solver = ColumnSolver(new.chat)  # each realization solved as if alone (banded.py)

    def steps(self, b0: int, b1: int, R_F: np.ndarray) -> None:
        st, buf, rest_product, solver = self.st, self.buf, self.rest_product, self.solver
        cu, cv, dm = (x.reshape(1, -1) for x in (st.cu, st.cv, st.dm))  # (1, n): no broadcast set-up per op
        r2 = st.r2
        U, V, A = self.U, self.V, self.A
        U_new, V_new, A_new, tmp = self.work
        Fb = (self.run.loads[b0:b1][..., None] * st.ycoef).reshape(b1 - b0, self.run.n_real, self.run.n_dof)
        for k in range(b1 - b0):
            # K_hat u_{n+1} = F_{n+1} + M (a0 u + a2 v + a) + C (a1 u + v)   (Bathe Table 9.3)
            np.multiply(cu, U, out=U_new)
            np.multiply(cv, V, out=tmp)
            U_new += tmp
            np.multiply(dm, A, out=tmp)
            U_new += tmp
            U_new += Fb[k]
            if rest_product is not None:
                U_new += rest_product(U, V)  # C~_off (a1 u + v)
            solver.rows_in_place(U_new)
            # trapezoidal relations of average acceleration: v' = 2/dt (u' - u) - v,
            # a' = 2/dt (v' - v) - a  (= a0 (u' - u) - a2 v - a, Bathe Table 9.3)
            np.subtract(U_new, U, out=V_new)
            V_new *= r2
            V_new -= V
            np.subtract(V_new, V, out=A_new)
            A_new *= r2
            A_new -= A
            U, U_new = U_new, U
            V, V_new = V_new, V
            A, A_new = A_new, A
            buf[k] = U
        self.U, self.V, self.A = U, V, A
        self.work = (U_new, V_new, A_new, tmp)
        R_F[b0:b1] = st.reactions(buf[: b1 - b0])

    def history(self, i0: int, i1: int) -> tuple[np.ndarray, bool]:
        """Displacements of the block's steps i0..i1 in the node bases, (m, n_dof)."""
        return self.buf[i0:i1].reshape(-1, self.run.n_dof), False


def rowdot_numpy(X: np.ndarray, BT: np.ndarray) -> np.ndarray:
    """X @ BT computed row by row in a fixed order (no BLAS): every realization's reactions
    are then bit-identical whichever other realizations share the call (batch chunking,
    workers); a BLAS gemm rounds differently for different numbers of rows.  X is made
    C-contiguous first: einsum sums a contiguous row in another order than a strided one."""
    return np.einsum("rd,dk->rk", np.ascontiguousarray(X), BT, optimize=False)


def _rotated_stack(models: list[LinearModel], c_bands: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Node bases T and rotated bands T^T K T, T^T C T of many states at once, each of shape
    (n_k, ...) (what :meth:`_Stepper.build` computes state by state; bit-identical)."""
    T = node_bases_stack(models, c_bands)
    return T, rotate_band(np.stack([m.K_band for m in models]), T), rotate_band(c_bands, T)


class _StackedBases:
    """The Newmark operators of the mean states, computed in chunks of states in one vectorised
    pass each (:func:`_rotated_stack`, :meth:`_Stepper.stack`), in the order the steps need
    them; only one chunk is held (memory bounded for long sections)."""

    def __init__(self, models: list[LinearModel], damping: np.ndarray, order: np.ndarray, nm: Newmark,
                 load_dirs: np.ndarray | None = None) -> None:
        self.models, self.damping, self.nm, self.load_dirs = models, damping, nm, load_dirs
        self.order = list(dict.fromkeys(int(k) for k in order))  # distinct states, first use first
        self.pos = {k: i for i, k in enumerate(self.order)}
        n_dof = models[0].mass.size
        self.chunk = max(1, min(len(self.order), 4_000_000 // max(30 * n_dof, 1)))  # ~32 MB of blocks
        self.held: dict[int, _Stepper] = {}

    def get(self, k: int) -> _Stepper:
        """The operator of mean state k."""
        if k not in self.held:
            ks = self.order[self.pos[k]:self.pos[k] + self.chunk]
            ms = [self.models[i] for i in ks]
            T, Kr, Cr = _rotated_stack(ms, self.damping[ks])
            self.held = dict(zip(ks, _Stepper.stack(ms, T, Kr, Cr, self.nm, self.load_dirs)))
        return self.held[k]


@dataclass(frozen=True)
class _Stepper:
    """One mean state's Newmark operator in the node bases of :func:`node_bases`.

    u = T u~ node by node (T orthonormal), so K~ = T^T K T keeps the band, M~ is diagonal
    (dm) and C~ is diagonal (dc) plus, with structural damping, an inter-node remainder
    (``rest``, sparse).  The per-step products M~ x and C~ y are then elementwise.
    Attributes are SI; vectors are (n_real, n_dof) in the rotated coordinates.
    """

    T: np.ndarray  # (n_nodes, 3, 3)
    chat: np.ndarray  # Cholesky factor of K~ + a1 C~ + a0 M~ (band)
    dm: np.ndarray  # [kg] diagonal of M~, (n_dof,)
    cu: np.ndarray  # a0 dm + a1 dc
    cv: np.ndarray  # a2 dm + dc
    rest: CSRArrays | None  # off-diagonal part of C~ (its CSR arrays) or None
    a1: float
    r2: float  # 2/dt
    ycoef: np.ndarray  # local components of a unit load along each node's load direction (global y), (n_nodes, 3)
    axial: np.ndarray  # rotated coordinates along the insulator axes, (n_susp,)
    nz: np.ndarray  # coordinates that enter the reactions, (n_nz,)
    GT: np.ndarray  # [N/m] (G T)^T rows nz, (n_nz, n_r)
    cols: np.ndarray  # per row of GT the column range [c0, c1) of its non-zeros (its tower), (n_nz, 2)

    @staticmethod
    def build(model: LinearModel, c_band: np.ndarray, nm: Newmark, load_dirs: np.ndarray | None = None) -> _Stepper:
        T = node_bases(model, c_band)
        return _Stepper.from_bases(model, T, rotate_band(model.K_band, T), rotate_band(c_band, T), nm, load_dirs)

    @staticmethod
    def from_bases(model: LinearModel, T: np.ndarray, Kr: np.ndarray, Cr: np.ndarray, nm: Newmark,
                   load_dirs: np.ndarray | None = None) -> _Stepper:
        """The operator from the node bases T (n_nodes, 3, 3) and the rotated stiffness and
        damping bands K~ = T^T K T, C~ = T^T C T (:meth:`stack` of one state)."""
        return _Stepper.stack([model], T[None], Kr[None], Cr[None], nm, load_dirs)[0]

    @staticmethod
    def stack(models: list[LinearModel], T: np.ndarray, Kr: np.ndarray, Cr: np.ndarray, nm: Newmark,
              load_dirs: np.ndarray | None = None) -> list[_Stepper]:
        """The operators of many mean states of one system from their node bases T and rotated
        bands K~, C~ (:func:`_rotated_stack`, each with a leading axis of n_k), in vectorised passes
        over the states (≈ 0.7 ms per state built one by one, 250 states in a downburst
        run) and one ``dpbtrf`` per state; elementwise along the states, so a state's operator
        does not depend on the others (tested)."""
        n_k = len(models)
        axial = models[0].axial_dof + 2  # (t1, t2, a): the axis is the third local coordinate
        dm = np.stack([m.mass for m in models])
        dm[:, axial] = 0.0  # rigid insulator: no inertia along its axis (model.M_band)
        dc = Cr[:, -1].copy()
        dc[:, axial] = 0.0  # nor damping (project_axial)
        off = Cr.copy()
        off[:, -1] = 0.0
        scale = np.abs(dc).max(axis=1) if dc.shape[1] else np.zeros(n_k)
        small = np.abs(off).reshape(n_k, -1).max(axis=1) <= 1e-12 * scale  # only rounding of the rotation
        off[small] = 0.0
        rests = band_to_csr_stack(off)
        used = off.copy()
        used[:, -1] = dc
        # G T node by node, only over the nodes G touches (a few per tower): the same einsum on
        # those nodes, so bit-identical to the full product (whose other columns are zero)
        G3 = np.stack([m.G for m in models]).reshape(n_k, models[0].G.shape[0], -1, 3)
        Gr = np.zeros(G3.shape)
        for k in range(n_k):
            touched = np.flatnonzero(np.any(G3[k] != 0.0, axis=(0, 2)))
            Gr[k][:, touched] = np.einsum("rna,naj->rnj", G3[k][:, touched], T[k][touched])
        Gr = Gr.reshape(n_k, G3.shape[1], -1)
        rows = _sparse_rows_stack(Gr)
        rows_of = ((lambda k: (rows[0], rows[1][k], rows[2][k])) if rows is not None
                   else (lambda k: _sparse_rows(Gr[k])))  # the states' reaction coordinates differ
        ycoef = (np.ascontiguousarray(T[:, :, 1, :]) if load_dirs is None else
                 np.stack([np.einsum("naj,na->nj", T[k], load_dirs) for k in range(n_k)]))
        cu = nm.a0 * dm + nm.a1 * dc
        cv = nm.a2 * dm + dc
        return [_Stepper(T[k], _factor(Kr[k], nm.a0 * dm[k], "effective stiffness", band_add=nm.a1 * used[k]),
                         dm[k], cu[k], cv[k], None if small[k] else rests[k], nm.a1, 2.0 / nm.dt, ycoef[k],
                         axial, *rows_of(k))
                for k in range(n_k)]

    def reactions(self, U: np.ndarray) -> np.ndarray:
        """[N] G u for rotated vectors U (..., n_dof) -> (..., n_r) (:func:`_sparse_reactions`)."""
        return _sparse_reactions(U, self.nz, self.GT, self.cols)


class _RestProduct:
    """(C~_off (a1 U + V)^T)^T for the step loop: the structural damping's inter-node remainder
    times a1 u + v, for all realizations (rows of U, V (n_real, n_dof)).

    The same arithmetic as ``(rest @ (a1 * U + V).T).T`` -- scipy's CSR kernel ``csr_matvecs``
    on the same C-ordered copy of the transposed vectors into a zeroed result -- so the same
    bits (tested), without the ≈ 25 µs of Python dispatch per call that made it the costliest
    line of the loop with quasi-steady damping.  Falls back to the public product."""

    def __init__(self, rest, a1: float, shape: tuple[int, int]):
        self.rest, self.a1 = rest, a1
        self.fast = _csr_matvecs is not None and getattr(rest, "format", "") == "csr"
        if not self.fast and isinstance(rest, CSRArrays):  # the public product needs the scipy matrix
            self.rest = rest.tocsr()
        if self.fast:
            self.w = np.empty(shape)
            self.xT = np.empty(shape[::-1])
            self.yT = np.empty(shape[::-1])
            self.args = (rest.shape[0], rest.shape[1], shape[0], rest.indptr, rest.indices, rest.data)

    def __call__(self, U: np.ndarray, V: np.ndarray) -> np.ndarray:
        if not self.fast:
            return (self.rest @ (self.a1 * U + V).T).T
        np.multiply(self.a1, U, out=self.w)
        self.w += V
        self.xT[...] = self.w.T
        self.yT.fill(0.0)
        _csr_matvecs(*self.args, self.xT.ravel(), self.yT.ravel())
        return self.yT.T


def _sparse_rows(G: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The coordinates a reaction map G (n_r, n_dof) touches, (n_nz,); its rows there, G^T
    (n_nz, n_r); and per such row the column range [c0, c1) of its non-zeros (the reactions of
    the tower(s) next to that coordinate), (n_nz, 2)."""
    nz, GT, cols = _sparse_rows_stack(G[None])
    return nz, GT[0], cols[0]


def _sparse_rows_stack(G: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """:func:`_sparse_rows` of the reaction maps G (n_k, n_r, n_dof) of states that touch the same
    coordinates: (nz, GT (n_k, n_nz, n_r), cols (n_k, n_nz, 2)); None where their coordinates differ."""
    on_nz = np.any(G != 0.0, axis=1)  # (n_k, n_dof)
    if not (on_nz == on_nz[:1]).all():
        return None
    nz = np.flatnonzero(on_nz[0])
    GT = np.ascontiguousarray(G.transpose(0, 2, 1)[:, nz])
    on = GT != 0.0
    c0 = np.argmax(on, axis=2)
    c1 = GT.shape[2] - np.argmax(on[:, :, ::-1], axis=2)
    return nz, GT, np.stack([c0, c1], axis=2)


def _sparse_reactions(U: np.ndarray, nz: np.ndarray, GT: np.ndarray, cols: np.ndarray) -> np.ndarray:
    """[N] G u for vectors U (..., n_dof) -> (..., n_r), accumulated coordinate by coordinate in
    a fixed order: elementwise only, so every realization's reactions are bit-identical whatever
    else shares the array (no BLAS blocking).  Each coordinate updates only the columns where
    its row is non-zero (O(n) instead of O(n^2) on a long line); the skipped terms are
    exact zeros, so the sums are the same bits as over every column."""
    out = np.zeros(U.shape[:-1] + (GT.shape[1],))
    for d, g, (a, b) in zip(nz, GT, cols):
        out[..., a:b] += U[..., d, None] * g[a:b]
    return out


def st_rotate(X: np.ndarray, old: _Stepper | None, new: _Stepper) -> np.ndarray:
    """Vectors (n_real, n_dof) from ``old``'s node bases (global if None) to ``new``'s."""
    shape = X.shape
    Xn = X.reshape(shape[0], -1, 3)
    if old is not None:
        Xn = np.einsum("rnj,naj->rna", Xn, old.T)  # u = T u~
    return np.ascontiguousarray(np.einsum("rna,naj->rnj", Xn, new.T).reshape(shape))  # u~ = T^T u


# ---- the compiled kernel's pieces ``newmark``, ``rotate`` and ``rowdot`` (linecheck.core.kernel):
# their load checks and numpy forms

def _newmark_check(fns) -> float:
    """The compiled banded solves against LAPACK (:func:`~linecheck.core.banded.band_solve_pairs`) and the
    structural-damping remainder by diagonals (``fns.rest_product``) against scipy's CSR product
    (:class:`_RestProduct`'s numpy form); the largest relative difference."""
    rng = np.random.default_rng(20)
    pairs = []
    for n in (60, 4):
        ab = rng.uniform(-1.0, 1.0, (BANDWIDTH + 1, n))
        ab[BANDWIDTH] = 0.0  # an off-diagonal remainder, with some exact zeros
        ab[rng.random(ab.shape) < 0.2] = 0.0
        rest = band_to_csr(ab)
        W = rng.standard_normal((4, n))
        t = np.empty((4, n))
        fns.rest_product(rest.band, np.pad(W, ((0, 0), (BANDWIDTH, BANDWIDTH))), t)
        pairs.append(((rest.tocsr() @ W.T).T, t))
    return kernel.worst_difference(band_solve_pairs(fns, BANDWIDTH) + pairs)


def _rotate_check(fns) -> float:
    """The compiled change of node bases (``fns.rotate``) against :func:`st_rotate`."""
    from types import SimpleNamespace

    rng = np.random.default_rng(21)
    To, Tn = (np.linalg.qr(rng.standard_normal((20, 3, 3)))[0] for _ in range(2))
    X = rng.standard_normal((5, 60))
    pairs = []
    for old in (None, SimpleNamespace(T=To)):
        Y = X.copy()
        fns.rotate(Y, To, Tn, old is not None)
        pairs.append((st_rotate(X, old, SimpleNamespace(T=Tn)), Y))
    return kernel.worst_difference(pairs)


def _rowdot_check(fns) -> float:
    """The compiled X @ BT (``fns.rowdot``) against :func:`rowdot_numpy` on the shapes the core
    uses (many rows, tens of columns)."""
    rng = np.random.default_rng(22)
    pairs = []
    for m, n, q in ((480, 59, 21), (7, 177, 9), (33, 3, 40), (482, 55, 3), (6, 10, 2)):
        X, BT = rng.standard_normal((m, n)), rng.standard_normal((n, q))
        out = np.empty((m, q))
        fns.rowdot(X, BT, out)
        pairs.append((rowdot_numpy(X, BT), out))
    return kernel.worst_difference(pairs)


kernel.register_check("newmark", _newmark_check)
kernel.register_check("rotate", _rotate_check, numpy=st_rotate)
kernel.register_check("rowdot", _rowdot_check, numpy=rowdot_numpy)
