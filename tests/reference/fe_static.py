"""Independent non-linear finite-element reference for step 1 (static equilibrium).

Written from scratch for the tests; it shares nothing with ``linecheck.core.static``
except the geometry inputs read from :class:`~linecheck.core.system.LineSystem`
(span length, sag, W, EA, insulator length, supports and the unstretched length L_u).

Model
-----
* Axes: x along the line (towers at x_j = (j-1) L), y transverse, z up.
* Conductor: ``n_el`` two-node elastic cable (truss) elements per span, all of
  unstretched length l0 = L_u / n_el, axial force N = EA (l/l0 - 1) with l the
  current (exact) element length.  Total Lagrangian in the unknown displacements
  U of the conductor nodes; no shallow-cable or sag approximation anywhere.
  Consistent tangent of the element (Crisfield 1991, "Non-linear Finite Element
  Analysis of Solids and Structures", Vol. 1, ch. 3, material + geometric
  stiffness of the truss):

      k = (EA/l0) e e^T + (N/l) (I - e e^T),   K_e = [[k, -k], [-k, k]],

  e the current unit vector of the element.  (d(N e)/dD for N = EA(|D|/l0 - 1).)
* Strain tower: the conductor node is pinned at (x_j, 0, 0).
* Suspension tower: a very stiff truss (EA_ins = ``insulator_stiffness`` * EA,
  unstretched length v) from the fixed point (x_j, 0, v) to the conductor node; it
  carries no bending, so it swings freely as a pendulum.  The stiffness is a
  penalty: the insulator stretch is reported (``insulator_length_error``; with the
  default EA_ins = 1e3 EA it is ~1e-5 m, i.e. ~3e-6 v).  A stiffer penalty (1e4 EA)
  gives the same answer but its round-off floor (axial stiffness EA_ins/v ~ 1e10 N/m
  times the spacing of doubles near the node position, ~4e-16 m) is ~1e-6 N, the
  size of the force tolerance.
* Loads (dead, per unit UNSTRETCHED length): weight W toward -z; transverse load
  g_y(s) toward +y, given at linecheck's FE nodes (s = 0, 1/ne, ..., 1 of each span)
  and piecewise linear in the normalised (unstretched arc-length) coordinate s.
  Nodal loads are the exact integrals of the (linearly interpolated) load times the
  nodal hat functions over the tributary unstretched length (W h/2 per element end;
  h (2 g_a + g_b)/6 and h (g_a + 2 g_b)/6 for the transverse load, h = L_u/n_el).
  This is exact for the piecewise-linear g_y when n_el is a multiple of ne.
* Solution: initial geometry = still-air parabola z = -4 S s (1 - s) with the nodes
  at equal arc length; Newton-Raphson with load stepping (the weight first, then
  the wind in adaptive increments, cut back when an increment fails) and step
  limiting (largest nodal increment <= L/10; steps giving non-finite forces are
  halved), to a force residual of ``tol`` [N] at every free degree of freedom.
  Banded direct solves (half band width 5 dofs, nodes numbered along the line).

Outputs follow linecheck's convention: reactions are the forces the conductor
system exerts on each tower at its fixed point, R_x toward +x, R_y toward +y,
R_z DOWNWARD positive.

The discrete chain converges to the continuous elastic catenary (Irvine 1981,
"Cable Structures", ch. 2) as O(1/n_el^2); the tests check it against
``tests/reference/irvine.py``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import solve_banded

from linecheck.core.system import LineSystem

from .truss import load_stepping, truss_internal, truss_state

_BAND = 5  # half band width in dofs: node k couples with node k+1 only


class FEConvergenceError(RuntimeError):
    """The reference Newton iteration did not converge."""


@dataclass(frozen=True)
class FEResult:
    """Converged FE equilibrium.

    Attributes:
        reactions: [N] (R_x, R_y, R_z) at every tower's fixed point, shape (n_towers, 3);
            forces ON the tower, R_z downward positive.
        tension: [N] horizontal tension (x-component of the axial force) per span,
            mean over the span's elements, shape (n_spans,).
        tension_spread: [-] largest relative deviation of an element's x-force from its
            span mean (zero up to round-off: there is no load along x), scalar.
        displacement: [m] attachment-point displacements from (x_j, 0, 0), shape (n_towers, 3).
        nodes: [m] deformed conductor node coordinates, shape (n_spans * n_el + 1, 3).
        axial_force: [N] conductor element axial forces, shape (n_spans * n_el,).
        insulator_force: [N] insulator axial force per tower (0 at strain towers), shape (n_towers,).
        insulator_length_error: [m] largest |l_ins - v| over the insulators (penalty error).
        residual: [N] largest out-of-balance force at a free degree of freedom.
        iterations: total Newton iterations over all load steps.
        load_steps: number of accepted load increments (weight step included).
    """

    reactions: np.ndarray
    tension: np.ndarray
    tension_spread: float
    displacement: np.ndarray
    nodes: np.ndarray
    axial_force: np.ndarray
    insulator_force: np.ndarray
    insulator_length_error: float
    residual: float
    iterations: int
    load_steps: int


class _Model:
    """Nodes, elements, stiffness and loads of the discrete cable + insulator system."""

    def __init__(self, system: LineSystem, gy: np.ndarray, n_el: int, insulator_stiffness: float) -> None:
        line = system.line
        ns, nt = system.n_spans, system.n_towers
        L, S, v = line.span_length, line.sag, line.insulator_length
        EA, Lu, W = line.ea, system.unstretched_length, line.weight
        gy = np.asarray(gy, dtype=float)
        if gy.ndim != 2 or gy.shape[0] != ns or gy.shape[1] < 2:
            raise ValueError(f"gy must have shape ({ns}, ne+1), got {gy.shape}")
        n = int(n_el)
        nc = ns * n + 1  # conductor nodes
        self.n, self.nc, self.ns, self.nt = n, nc, ns, nt
        self.tower_node = np.arange(nt) * n
        sus = np.array([s == "suspension" for s in line.supports], dtype=bool)
        self.sus = sus
        sus_idx = np.flatnonzero(sus)
        self.sus_idx = sus_idx
        self.v = v

        # ---- reference geometry X0: still-air parabola, nodes at equal arc length
        sf = np.linspace(0.0, 1.0, 20001)
        dzds = -4.0 * S * (1.0 - 2.0 * sf)
        ds = np.sqrt(L**2 + dzds**2)
        arc = np.concatenate([[0.0], np.cumsum(0.5 * (ds[1:] + ds[:-1]) * np.diff(sf))])
        s_nodes = np.interp(np.linspace(0.0, arc[-1], n + 1), arc, sf)
        X0 = np.zeros((nc + sus_idx.size, 3))
        for k in range(ns):
            sl = slice(k * n, (k + 1) * n + 1)
            X0[sl, 0] = k * L + s_nodes * L
            X0[sl, 2] = -4.0 * S * s_nodes * (1.0 - s_nodes)
        X0[nc:, 0] = sus_idx * L  # insulator fixed points (x_j, 0, v)
        X0[nc:, 2] = v
        self.X0 = X0
        self.nn = X0.shape[0]

        # ---- elements: conductor chain, then insulators (fixed point -> attachment node)
        a = np.concatenate([np.arange(ns * n), nc + np.arange(sus_idx.size)])
        b = np.concatenate([np.arange(1, ns * n + 1), self.tower_node[sus_idx]])
        self.a, self.b = a, b
        self.n_cond = ns * n
        self.l0 = np.concatenate([np.full(ns * n, Lu / n), np.full(sus_idx.size, v)])
        self.EA = np.concatenate([np.full(ns * n, EA), np.full(sus_idx.size, insulator_stiffness * EA)])
        dX0 = X0[b] - X0[a]
        self.dX0 = dX0
        self.c0 = np.einsum("ij,ij->i", dX0, dX0) - self.l0**2  # |dX0|^2 - l0^2 (exact for insulators)

        # ---- dofs: 3 per node; free = conductor nodes not pinned at strain towers
        free = np.zeros((self.nn, 3), dtype=bool)
        free[:nc] = True
        free[self.tower_node[~sus]] = False
        self.free = free.reshape(-1)
        self.ndof_c = 3 * nc  # the banded system covers the conductor dofs only

        # ---- loads per node (per unit unstretched length, tributary / consistent)
        h = Lu / n
        fw = np.zeros((self.nn, 3))
        fy = np.zeros((self.nn, 3))
        s_lc = np.linspace(0.0, 1.0, gy.shape[1])
        s_fe = np.linspace(0.0, 1.0, n + 1)
        for k in range(ns):
            g = np.interp(s_fe, s_lc, gy[k])
            idx = k * n + np.arange(n)
            np.add.at(fy[:, 1], idx, h * (2.0 * g[:-1] + g[1:]) / 6.0)
            np.add.at(fy[:, 1], idx + 1, h * (g[:-1] + 2.0 * g[1:]) / 6.0)
            np.add.at(fw[:, 2], idx, -0.5 * W * h)
            np.add.at(fw[:, 2], idx + 1, -0.5 * W * h)
        self.fw, self.fy = fw.reshape(-1), fy.reshape(-1)

        # ---- assembly index maps (element blocks -> banded storage), built once
        dof_a = 3 * a[:, None] + np.arange(3)
        dof_b = 3 * b[:, None] + np.arange(3)
        dofs = np.concatenate([dof_a, dof_b], axis=1)  # (n_elem, 6)
        rows = np.repeat(dofs[:, :, None], 6, axis=2)
        cols = np.repeat(dofs[:, None, :], 6, axis=1)
        keep = self.free[rows] & self.free[cols]
        self._keep = keep
        # LAPACK band storage ab[BAND + i - j, j] = K[i, j], flattened
        self._ab_flat = (_BAND + rows - cols)[keep] * self.ndof_c + cols[keep]
        self._fixed_c = np.flatnonzero(~self.free[: self.ndof_c])

    # ------------------------------------------------------------------ element state
    def element_state(self, U: np.ndarray):
        """Axial forces [N] (n_elem,), unit vectors (n_elem, 3), lengths [m] (n_elem,)."""
        return truss_state(U.reshape(-1, 3), self.a, self.b, self.dX0, self.c0, self.l0, self.EA)

    def internal_force(self, U: np.ndarray) -> np.ndarray:
        """Internal nodal forces f_int [N], shape (3 nn,): node a gets -N e, node b +N e."""
        N, e, _ = self.element_state(U)
        return truss_internal(N, e, self.a, self.b, self.nn)

    def tangent_banded(self, U: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """f_int and the consistent tangent in LAPACK band storage (2*5+1, 3 nc)."""
        N, e, ell = self.element_state(U)
        Ne = N[:, None] * e
        f = np.zeros((self.nn, 3))
        np.add.at(f, self.b, Ne)
        np.add.at(f, self.a, -Ne)
        # Crisfield (1991) Vol. 1 ch. 3: k = EA/l0 e e^T + N/l (I - e e^T)
        ee = e[:, :, None] * e[:, None, :]
        k = (self.EA / self.l0 - N / ell)[:, None, None] * ee + (N / ell)[:, None, None] * np.eye(3)
        Ke = np.block([[k, -k], [-k, k]])  # (n_elem, 6, 6)
        ab = np.bincount(self._ab_flat, weights=Ke[self._keep], minlength=(2 * _BAND + 1) * self.ndof_c)
        ab = ab.reshape(2 * _BAND + 1, self.ndof_c)
        ab[_BAND, self._fixed_c] = 1.0
        return f.reshape(-1), ab


def _newton(model: _Model, U: np.ndarray, fext: np.ndarray, tol: float, max_iter: int, dmax: float):
    """Full Newton-Raphson with step limiting (largest nodal increment <= ``dmax`` [m]).

    No residual-norm line search: the stiff insulator penalty makes the residual of a
    good Newton step transiently huge (a swing of the attachment node along the
    tangent stretches the insulator by ~d^2/(2v)), so a norm-decrease test would
    throttle the iteration; plain Newton recovers in a few iterations and the load
    stepping in :func:`solve_fe` cuts the increment back if it does not.  Steps that
    produce non-finite forces are halved.

    Returns (U, iterations, residual [N]); raises FEConvergenceError.
    """
    free = model.free
    nd = model.ndof_c
    res = np.inf
    for it in range(max_iter + 1):
        fint, ab = model.tangent_banded(U)
        r = np.where(free, fext - fint, 0.0)
        res = float(np.max(np.abs(r)))
        if not np.isfinite(res):
            raise FEConvergenceError("non-finite residual")
        if res <= tol:
            return U, it, res
        if it == max_iter:
            break
        du = np.zeros_like(U)
        du[:nd] = solve_banded((_BAND, _BAND), ab, r[:nd], check_finite=False)
        du[~free] = 0.0
        big = float(np.max(np.abs(du)))
        if not np.isfinite(big):
            raise FEConvergenceError("singular tangent")
        alpha = min(1.0, dmax / big) if big > 0 else 1.0
        for _ in range(20):
            Ut = U + alpha * du
            if np.all(np.isfinite(model.internal_force(Ut))) and np.all(model.element_state(Ut)[2] > 0):
                break
            alpha *= 0.5
        U = Ut
    raise FEConvergenceError(f"no convergence in {max_iter} iterations (residual {res:.3g} N, tolerance {tol:.3g} N)")


def solve_fe(
    system: LineSystem,
    gy: np.ndarray,
    *,
    n_el: int = 80,
    insulator_stiffness: float = 1e3,
    tol: float = 1e-6,
    wind_steps: int = 4,
    max_iter: int = 40,
) -> FEResult:
    """Exact (large-displacement) static equilibrium of the line section.

    Args:
        system: the line section (geometry, conductor and supports).
        gy: [N/m] transverse load per unit unstretched length toward +y at linecheck's
            FE nodes of every span, shape (n_spans, ne+1), piecewise linear in s.
        n_el: cable elements per span (use a multiple of ne for exact load lumping).
        insulator_stiffness: [-] EA_ins / EA of the penalty insulator truss.
        tol: [N] force residual at every free degree of freedom.
        wind_steps: initial number of wind increments (halved adaptively on failure).
        max_iter: Newton iterations per load increment.

    Raises:
        FEConvergenceError: the load stepping could not reach the full load.
    """
    model = _Model(system, gy, n_el, insulator_stiffness)
    L = system.line.span_length
    dmax = 0.1 * L  # [m] step limit per Newton iteration
    U = np.zeros(3 * model.nn)
    U, its, res = _newton(model, U, model.fw, tol, max_iter, dmax)
    total_its, steps = its, 1
    if np.any(model.fy != 0.0):
        U, res, its, n = load_stepping(lambda U0, f: _newton(model, U0, f, tol, max_iter, dmax), U, model.fw, model.fy,
                                       wind_steps, 5, FEConvergenceError)
        total_its += its
        steps += n
    fext = model.fw + model.fy
    return _result(model, U, fext, res, total_its, steps)


def _result(model: _Model, U, fext, res, its, steps) -> FEResult:
    """Reactions (force on each tower's fixed point = out-of-balance force there), spans, insulators."""
    N, e, ell = model.element_state(U)
    r_all = (fext - model.internal_force(U)).reshape(-1, 3)  # at fixed nodes: force on the support
    nt = model.nt
    F = np.zeros((nt, 3))
    strain = ~model.sus
    F[strain] = r_all[model.tower_node[strain]]
    F[model.sus_idx] = r_all[model.nc + np.arange(model.sus_idx.size)]
    R = F * np.array([1.0, 1.0, -1.0])  # R_z downward positive
    nc_el = model.n_cond
    Hx = (N[:nc_el] * e[:nc_el, 0]).reshape(model.ns, model.n)
    H = Hx.mean(axis=1)
    spread = float(np.max(np.abs(Hx - H[:, None]) / np.abs(H[:, None])))
    Un = U.reshape(-1, 3)
    nodes = model.X0[: model.nc] + Un[: model.nc]
    ins_force = np.zeros(nt)
    ins_force[model.sus_idx] = N[nc_el:]
    ins_err = float(np.max(np.abs(ell[nc_el:] - model.v))) if model.sus_idx.size else 0.0
    return FEResult(
        reactions=R,
        tension=H,
        tension_spread=spread,
        displacement=Un[model.tower_node].copy(),
        nodes=nodes,
        axial_force=N[:nc_el].copy(),
        insulator_force=ins_force,
        insulator_length_error=ins_err,
        residual=res,
        iterations=its,
        load_steps=steps,
    )
