"""Step 1: non-linear static analysis under the (running-)mean wind.

Semi-analytical technique of the paper (Appendix A, Eqs 2-4, Fig. 6, after
Aboshosha & El Damatty 2014): every span is ONE element described by the
shallow-cable (parabolic) theory; the unknowns are the displacements
d = (d_x, d_y, d_z) of the conductor-insulator attachment points.  The paper's
length-tension relation (its C_n) is for an inextensible conductor; here the
conductor is elastic and the relation and its derivative are derived in
``docs/method.md`` ("Elastic span relation"):

    G(H) = l + D^2/(2 l) + J/(2 H^2) - L_u - (H/EA) (l + D^2/l + J/H^2) = 0

with l the horizontal chord, D^2 = dy^2 + dz^2 the end offsets, L_u the
unstretched length and J = int_0^l (Q_y^2 + Q_z^2) dx the shear integral of the
span loads (loads are per unit conductor length, J = L_u^2 l j_hat).

Iteration (paper Fig. 6): given d_y, d_z, Newton on d_x with the tangent K_x of
Eq. 3 (insulator forces R_res fixed); reactions by Eq. 2; new d_y, d_z from
the insulator equilibrium Eq. 4; repeat until the attachment displacements
stop changing.  Nothing here prints; failures raise :class:`ConvergenceError`.

Sign conventions: reactions are the forces the conductor system exerts on the
tower at its fixed point: R_x toward +x, R_y toward +y, R_z downward.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np
from scipy.linalg import lapack

from . import kernel
from .errors import Cancelled, ConvergenceError
from .span_operators import span_operators

if TYPE_CHECKING:  # annotations only: the system solves its still-air state with this module
    from .system import LineSystem

MAX_STRAIN = 0.05  # conductor strain above this is not an admissible elastic state
FOLLOWER_RTOL = 1e-10  # cross-flow drag: loads settled when they change by less than this (relative)
FOLLOWER_MAX = 30  # passes of the follower substitution (it contracts by ~0.05 a pass on real sections)
_dgtsv = lapack.dgtsv


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class StaticState:
    """Converged step-1 equilibrium of the line section under one set of mean loads.

    Attributes:
        displacement: [m] attachment-point displacements (d_x, d_y, d_z), shape (n_towers, 3).
        reactions: [N] (R_x, R_y, R_z) at every tower's fixed point, shape (n_towers, 3).
        tension: [N] horizontal tension H of every span, shape (n_spans,).
        insulator_force: [N] R_res at every tower (strain towers: resultant reaction), (n_towers,).
        nodes: [m] deformed FE node coordinates (x, y, z), shape (n_nodes, 3).
        element_tension: [N] axial tension of every cable element, shape (n_spans * ne,).
        iterations: outer (Fig. 6) iterations used.
        residual: [N] largest out-of-balance force at an attachment point.
        held: bool per tower, shape (n_towers,): the suspension clamps held at their still-air
            point because their insulator would be in compression (uplift; section form,
            :func:`linecheck.core.catenary.equilibrium`); None when no clamp is held.
    """

    displacement: np.ndarray
    reactions: np.ndarray
    tension: np.ndarray
    insulator_force: np.ndarray
    nodes: np.ndarray
    element_tension: np.ndarray
    iterations: int
    residual: float
    held: np.ndarray | None = None


def span_loads_uniform(system: LineSystem, intensity: np.ndarray | float) -> np.ndarray:
    """Nodal transverse load intensities [N/m] for a uniform load per span, shape (n_spans, ne+1)."""
    g = np.broadcast_to(np.asarray(intensity, dtype=float), (system.n_spans,))
    return np.repeat(g[:, None], system.ne + 1, axis=1)


def drag_intensity(speed: np.ndarray | float, air_density: float, drag_coefficient: float, diameter: float) -> np.ndarray:
    """Mean-wind load per unit length g_y = 1/2 rho C_d V|V| D [N/m] (paper Eq. 1; sign follows V)."""
    v = np.asarray(speed, dtype=float)
    return 0.5 * air_density * drag_coefficient * diameter * v * np.abs(v)


class _Spans:
    """Per-span load integrals for one load case (vectorised over spans)."""

    def __init__(self, system: LineSystem, gy: np.ndarray) -> None:
        op = span_operators(system.ne)
        line = system.line
        self.Lu = system.unstretched_lengths  # (n_spans,)
        self.EA = line.ea
        self.L = system.span_lengths  # (n_spans,)
        W = line.weight
        # beam end reactions per unit L_u (loads per unit unstretched conductor length)
        self.vAy = gy @ op.a_left
        self.vBy = gy @ op.a_right
        self.vAz = self.vBz = 0.5 * W
        self.qy_gp = gy @ op.shear_gp.T  # (n_spans, n_gp) shear of the unit span
        self.qz_gp = op.shear_gp @ np.full(system.ne + 1, W)  # (n_gp,)
        self.w_gp = op.w_gp
        self.my_hat = gy @ op.moment_nodes.T  # (n_spans, ne+1) moment of unit span
        self.mz_hat = 0.5 * W * system.node_s * (1.0 - system.node_s)

    def tension(
        self, l: np.ndarray, dy: np.ndarray, dz: np.ndarray, H0: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Solve the elastic span relation F(H) = 0 for the horizontal tension H.

        F(H) = int_0^l u / (1 + H u / EA) dx - L_u,  u = sqrt(1 + y'^2 + z'^2),
        y' = dy/l + L_u Q_y(s)/H, z' = dz/l - L_u Q_z(s)/H  (docs/method.md, "Elastic
        span relation"; shallow-cable shape, Irvine 1981 ch. 2, exact length integral).

        Args: l, dy, dz [m] chord projections per span, shape (n_spans,) or (n_states, n_spans)
            (the load case then has the same leading axis); H0 [N] start.
        Returns: H [N] and C = dH/dl [N/m] (the elastic form of the paper's C_n).
        """
        Lu, EA = self.Lu, self.EA
        w = self.w_gp
        ay, az = (dy / l)[..., None], (dz / l)[..., None]
        by, bz = Lu[:, None] * self.qy_gp, -Lu[:, None] * self.qz_gp  # both (n_spans, n_gp)
        H = np.array(H0, dtype=float)
        terms = kernel.span_terms  # compiled when its piece is on, else span_terms
        for _ in range(60):
            f, g = terms(ay, az, by, bz, H, EA)
            F = l * (f @ w) - Lu
            dF = l * (g @ w)
            Hn = H - F / dF
            Hn = np.where(Hn <= 0.1 * H, 0.1 * H, Hn)  # F decreasing: guard the first steps only
            done = np.abs(Hn - H) <= 1e-13 * np.abs(H)
            H = Hn
            if np.all(done):
                break
        else:
            raise ConvergenceError("span tension iteration did not converge (non-finite loads?)")
        f, g, e = terms(ay, az, by, bz, H, EA, l)
        dF_dH = l * (g @ w)
        dF_dl = f @ w + l * (e @ w)
        return H, -dF_dl / dF_dH


def span_terms(ay: np.ndarray, az: np.ndarray, by: np.ndarray, bz: np.ndarray, H: np.ndarray,
               EA: float, l: np.ndarray | None = None) -> tuple[np.ndarray, ...]:
    """The integrands of one Newton step of :meth:`_Spans.tension`: f = u/(1 + H u/EA) (the
    length integrand, F = l ∫f - L_u) and g = ∂f/∂H (∂F/∂H = l ∫g); with the chords l also
    e = ∂f/∂l (∂F/∂l = ∫f + l ∫e); docs/method.md, "Elastic span relation".
    (:func:`linecheck.core.kernel.span_terms` computes them in one compiled pass with the
    kernel's piece ``span``, within its tolerance.)

    Args: ay, az [-] chord slopes (..., n_spans, 1); by, bz [N] L_u Q_y, −L_u Q_z at the Gauss
        points (..., n_spans, n_gp); H [N] (..., n_spans); EA [N]; l [m] (..., n_spans).
    Returns: f [-], g [1/N] (and e [1/m]), each (..., n_spans, n_gp).
    """
    Hc = H[..., None]
    py, pz = ay + by / Hc, az + bz / Hc
    u = np.sqrt(1.0 + py**2 + pz**2)
    den = 1.0 + Hc * u / EA
    fu = 1.0 / den**2
    f, g = u / den, -(u**2) / EA / den**2 + fu * (-(py * by + pz * bz) / Hc**2) / u
    if l is None:
        return f, g
    return f, g, fu * (-(py * ay + pz * az) / l[..., None]) / u


def _reactions(sp: _Spans, H, l, dy, dz, n_towers) -> np.ndarray:
    """Conductor forces on every attachment point (paper Eq. 2 incl. the P-delta term K_yz d)."""
    R = np.zeros(H.shape[:-1] + (n_towers, 3))
    Ddy, Ddz = np.diff(dy, axis=-1), np.diff(dz, axis=-1)
    # left end A of each span
    R[..., :-1, 0] += H
    R[..., :-1, 1] += H * Ddy / l + sp.Lu * sp.vAy
    R[..., :-1, 2] += sp.Lu * sp.vAz - H * Ddz / l
    # right end B
    R[..., 1:, 0] -= H
    R[..., 1:, 1] += -H * Ddy / l + sp.Lu * sp.vBy
    R[..., 1:, 2] += sp.Lu * sp.vBz + H * Ddz / l
    return R


def solve_static(
    system: LineSystem,
    gy: np.ndarray,
    *,
    initial: StaticState | None = None,
    tol: float = 1e-8,
    max_iter: int = 500,
    label: str = "mean state",
    drag: Callable[[np.ndarray], np.ndarray] | None = None,
) -> StaticState:
    """Non-linear static equilibrium under weight and the transverse mean-wind load.

    One state of :func:`_fig6_iteration` (a leading state axis of 1).

    Args:
        system: the line section.
        gy: [N/m] transverse load per unit conductor length at each span's FE nodes,
            shape (n_spans, ne+1) (paper Eq. 1; use :func:`drag_intensity`).
        initial: a previous state to start from (downburst time stepping).
        tol: [m] convergence tolerance on the attachment displacements, relative to v.
        max_iter: limit on outer (Fig. 6) iterations.
        label: names the state in error messages (e.g. "mean state 37 (t = 120.0 s)").
        drag: the cross-flow form on a section (:func:`~linecheck.core.loads.mean_drag`): the drag
            vectors [N/m] (1, n_spans, ne+1, 3) as a function of the cable's unit tangents at the
            span nodes (a follower load, :func:`_section_states`), in place of gy along the span
            normals (gy still sets the solver's start).

    Raises:
        ConvergenceError: no convergence, non-finite values or an inadmissible strain.
    """
    line = system.line
    nt = system.n_towers
    gy = np.asarray(gy, dtype=float)
    if gy.shape != (system.n_spans, system.ne + 1):
        raise ValueError(f"gy must have shape {(system.n_spans, system.ne + 1)}, got {gy.shape}")
    if not np.all(np.isfinite(gy)):
        raise ConvergenceError(f"{label}: non-finite mean-wind load")
    if system.is_section:
        return _section_states(system, gy[None], [label], tol=tol, max_iter=max_iter, initial=initial,
                               drag=drag)[0]
    if initial is not None:
        d = initial.displacement.copy()
        H = initial.tension.copy()
        Rres = initial.insulator_force.copy()
    else:
        d = np.zeros((nt, 3))
        H = np.full(system.n_spans, system.tension_nominal)
        # a better start for H: the resultant-load parabola
        wres = np.hypot(line.weight, np.abs(gy).mean(axis=1))
        H = np.maximum(H, system.tension_nominal * wres / line.weight)
        Rres = line.weight * system.weight_spans  # tributary weight (start only)
    return _fig6_iteration(system, gy[None], d[None], H[None], Rres[None], labels=[label], tol=tol,
                           max_iter=max_iter)[0]


def _inner_newton(sp: _Spans, d: np.ndarray, H: np.ndarray, Rres: np.ndarray, inner: np.ndarray, L: np.ndarray,
                  v: float, idx: np.ndarray, adj: np.ndarray, tol_d: float, labels: list[str]) -> np.ndarray:
    """Inner Newton on the longitudinal displacements d_x of the suspension clamps (paper Eq. 3)
    with R_res fixed, on a leading axis of n_s states; moves ``d`` in place.

    Args: d [m] (n_s, n_towers, 3); H [N] start tensions (n_s, n_spans); Rres [N] (n_s, n_towers);
        inner: bool (n_s,), the states still iterating (others frozen; updated in place);
        L [m] (n_spans,); v [m] insulator length; idx: suspension towers (k,); adj: positions in
        idx of towers adjacent to the next one; tol_d [m] the outer tolerance.
    Returns: H [N] (n_s, n_spans) at the last evaluated d_x.
    """
    n_s, nt, k = d.shape[0], d.shape[1], idx.size
    for _inner in range(50):
        l = L + np.diff(d[..., 0], axis=-1)
        H, C = sp.tension(l, np.diff(d[..., 1], axis=-1), np.diff(d[..., 2], axis=-1), H)
        if k == 0 or not inner.any():
            break
        fx = np.zeros((n_s, nt))
        fx[:, :-1] += H
        fx[:, 1:] -= H
        fx = fx - d[..., 0] * Rres / v
        # tangent (paper K_x with the elastic C_n = dH/dl): tridiagonal over all towers,
        # restricted to the suspension towers (strain towers are fixed); free neighbours
        # are adjacent towers j, j+1 -> a symmetric tridiagonal system
        diag = -Rres / v
        diag[:, :-1] -= C
        diag[:, 1:] -= C
        off = np.zeros((n_s, max(k - 1, 0)))
        off[:, adj] = C[:, idx[adj]]
        if n_s == 1:
            _, _, _, step, info = _dgtsv(off[0], diag[0, idx].copy(), off[0].copy(), -fx[0, idx])
            if info != 0:
                raise ConvergenceError(f"{labels[0]}: singular longitudinal tangent (K_x, Eq. 3)")
            step = step[None]
        else:
            step = _tridiag_solve(off, diag[:, idx], off, -fx[:, idx])
        step[~inner] = 0.0
        d[:, idx, 0] += step
        inner &= ~(np.max(np.abs(step), axis=1) <= 1e-3 * tol_d)
        if n_s == 1 and not inner[0]:
            # one state stops right after its last Newton step (its H is recomputed below);
            # several states take one more pass (H of all states at the final d_x) and stop
            # at the check above.  Unifying the two moves the paper cases' results by the
            # round-off of the span-tension Newton (up to 8e-6 relative on near-zero
            # wind-induced Rx histories), so both keep their bit-identical results.
            break
    return H


def _insulator_update(d: np.ndarray, d_old: np.ndarray, R: np.ndarray, Rn: np.ndarray, Rres: np.ndarray,
                      active: np.ndarray, v: float, idx: np.ndarray, change: np.ndarray,
                      residual: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Insulator equilibrium (paper Eq. 4): each active suspension clamp moves to v R / R_res
    below its fixed point (``d`` updated in place).

    Args: d, d_old [m] (n_s, n_towers, 3) after / before this outer iteration; R [N] reactions
        (n_s, n_towers, 3), Rn [N] their norms and Rres [N] the insulator forces (n_s, n_towers);
        active: bool (n_s,); v [m]; idx: suspension towers; change [m], residual [N] (n_s,): the
        previous values, kept for the frozen states.
    Returns: the largest displacement change [m] and out-of-balance force [N] per state, (n_s,) each.
    """
    n_s = d.shape[0]
    if not idx.size:
        return np.where(active, 0.0, change), np.where(active, 0.0, residual)
    a = active
    dn = np.stack([v * R[:, idx, 0] / Rres[:, idx], v * R[:, idx, 1] / Rres[:, idx],
                   v - v * R[:, idx, 2] / Rres[:, idx]], axis=-1)
    d[:, idx] = np.where(a[:, None, None], dn, d[:, idx])
    change = np.where(a, np.max(np.abs(d - d_old).reshape(n_s, -1), axis=1), change)
    # out-of-balance: conductor force minus insulator force along its axis
    axis = np.stack([d_old[:, idx, 0], d_old[:, idx, 1], v - d_old[:, idx, 2]], axis=-1) / v
    res = np.max(np.linalg.norm(R[:, idx] - Rn[:, idx, None] * axis, axis=-1), axis=1)
    return change, np.where(a, res, residual)


def _check_finite(R: np.ndarray, d: np.ndarray, active: np.ndarray, labels: list[str], it: int) -> None:
    """Raise :class:`ConvergenceError` naming the first active state whose reactions R (n_s, n_towers, 3)
    or displacements d (n_s, n_towers, 3) are not all finite after ``it`` iterations."""
    n_s = d.shape[0]
    finite = np.all(np.isfinite(R.reshape(n_s, -1)), axis=1) & np.all(np.isfinite(d.reshape(n_s, -1)), axis=1)
    if not np.all(finite | ~active):
        j = int(np.flatnonzero(~finite & active)[0])
        raise ConvergenceError(f"{labels[j]}: non-finite values after {it} iterations")


def _fig6_iteration(system: LineSystem, gy: np.ndarray, d: np.ndarray, H: np.ndarray, Rres: np.ndarray, *,
                    labels: list[str], tol: float, max_iter: int, progress: Callable[[int, int], None] | None = None,
                    cancel: threading.Event | None = None) -> list[StaticState]:
    """The paper's Fig. 6 iteration, written once, on a leading axis of n_states load cases.

    Inner Newton on d_x (Eq. 3) with R_res fixed, then the reactions (Eq. 2) and the
    insulator update (Eq. 4), repeated until the attachment displacements stop changing;
    each state is frozen at its own convergence, so a state's result does not depend on
    the others.  The longitudinal tangent is solved by LAPACK dgtsv for one state and by
    the vectorised Thomas algorithm for several (same system, both direct).

    Args:
        gy: [N/m] transverse loads, shape (n_states, n_spans, ne+1) (checked finite).
        d: [m] start displacements (n_states, n_towers, 3); H: [N] start tensions
            (n_states, n_spans); Rres: [N] start insulator forces (n_states, n_towers).
        labels: names of the states for error messages, length n_states.
        progress: ``progress(converged, n_states)`` once per outer iteration.
        cancel: set it to stop; raises :class:`Cancelled`.
    """
    nt, v, L, n_s = system.n_towers, system.line.insulator_length, system.span_lengths, gy.shape[0]
    sp = _Spans(system, gy)
    d, H, Rres = d.copy(), H.copy(), Rres.copy()
    idx = np.flatnonzero(system.suspension)
    adj = np.flatnonzero(np.diff(idx) == 1)
    tol_d = tol * max(v, 1.0)
    active = np.ones(n_s, dtype=bool)
    out_d, out_H, out_R = np.empty_like(d), np.empty_like(H), np.empty((n_s, nt, 3))
    out_Rres, out_res = np.empty_like(Rres), np.zeros(n_s)
    out_it = np.zeros(n_s, dtype=int)
    change = np.full(n_s, np.inf)
    residual = np.full(n_s, np.inf)
    for it in range(1, max_iter + 1):
        if cancel is not None and cancel.is_set():
            raise Cancelled("step 1 cancelled")
        d_old = d.copy()
        # ---- inner Newton on d_x (paper Eq. 3), R_res fixed; converged states frozen
        H = _inner_newton(sp, d, H, Rres, active.copy(), L, v, idx, adj, tol_d, labels)
        l = L + np.diff(d[..., 0], axis=-1)
        H, _ = sp.tension(l, np.diff(d[..., 1], axis=-1), np.diff(d[..., 2], axis=-1), H)
        R = _reactions(sp, H, l, d[..., 1], d[..., 2], nt)
        Rn = np.linalg.norm(R, axis=-1)
        Rres = np.where(active[:, None], Rn, Rres)
        _check_finite(R, d, active, labels, it)
        # ---- insulator equilibrium (paper Eq. 4)
        change, residual = _insulator_update(d, d_old, R, Rn, Rres, active, v, idx, change, residual)
        done = active & (change <= tol_d)
        out_d[done], out_H[done], out_R[done] = d[done], H[done], R[done]
        out_Rres[done], out_res[done], out_it[done] = Rres[done], residual[done], it
        active &= ~done
        if progress is not None:
            progress(int(n_s - active.sum()), n_s)
        if not active.any():
            break
    else:
        j = int(np.flatnonzero(active)[0])
        raise ConvergenceError(f"{labels[j]}: step-1 static solver did not converge in {max_iter} iterations (last "
                               f"displacement change {change[j]:.3g} m, out-of-balance force {residual[j]:.3g} N)")
    return _final_states(system, sp.Lu, sp.my_hat, sp.mz_hat, out_d, out_H, out_R, out_Rres, out_it, out_res, labels)


def _final_states(system: LineSystem, Lu: np.ndarray, my_hat: np.ndarray, mz_hat: np.ndarray, d: np.ndarray,
                  H: np.ndarray, R: np.ndarray, Rres: np.ndarray, it: np.ndarray, residual: np.ndarray,
                  labels: list[str]) -> list[StaticState]:
    """Strain check and deformed shape of converged equilibria, on a leading axis of n_s states
    (shallow cable: y = chord + M_y/H, z = chord - M_z/H; element tension T = H ds/dx).  Every
    operation is elementwise along the states (one pass for a downburst's 250 states
    instead of one call each), so a state's arrays do not depend on the others (tested).

    Args: Lu [m] (n_spans,); my_hat [N m/m] (n_s, n_spans, ne+1); mz_hat (ne+1,); d [m]
        (n_s, n_towers, 3); H [N] (n_s, n_spans); R [N] (n_s, n_towers, 3); Rres [N] (n_s, n_towers);
        it, residual [N] (n_s,); labels (n_s).
    """
    line = system.line
    L = system.span_lengths
    n_s = d.shape[0]
    strain = H.max(axis=1) / line.ea
    bad = (strain > MAX_STRAIN) | ~np.isfinite(strain)
    if bad.any():
        j = int(np.flatnonzero(bad)[0])
        raise ConvergenceError(
            f"{labels[j]}: no admissible equilibrium: conductor strain {strain[j]:.3g} exceeds {MAX_STRAIN:g} "
            f"(horizontal tension {H[j].max():.4g} N, out-of-balance force {residual[j]:.3g} N); check the loads"
        )
    l = L + np.diff(d[..., 0], axis=-1)  # (n_s, n_spans)
    s = system.node_s
    xA = system.tower_x[:-1] + d[:, :-1, 0]
    X = xA[..., None] + s * l[..., None]
    scale = (Lu * l / H)[..., None]
    Y = d[:, :-1, 1][..., None] + s * np.diff(d[..., 1], axis=-1)[..., None] + scale * my_hat
    Z = d[:, :-1, 2][..., None] + s * np.diff(d[..., 2], axis=-1)[..., None] - scale * mz_hat
    ne = system.ne
    nodes = np.empty((n_s, system.n_nodes, 3))
    for c, A in enumerate((X, Y, Z)):
        nodes[:, :-1, c] = A[..., :-1].reshape(n_s, -1)
        nodes[:, -1, c] = A[:, -1, -1]
    seg = np.diff(nodes, axis=1)  # (n_s, n_elements, 3)
    seg_len = np.linalg.norm(seg, axis=-1)
    H_el = np.repeat(H, ne, axis=1)
    element_tension = H_el * seg_len / np.abs(seg[..., 0])  # T = H ds/dx (shallow cable)
    return [StaticState(displacement=d[j], reactions=R[j], tension=H[j], insulator_force=Rres[j], nodes=nodes[j],
                        element_tension=element_tension[j], iterations=int(it[j]), residual=float(residual[j]))
            for j in range(n_s)]


def section_loads(system: LineSystem, gy: np.ndarray, drag: np.ndarray | None = None) -> np.ndarray:
    """Load vectors per unit unstretched length [N/m] of a section: weight W downward plus the
    transverse intensity gy along each span's horizontal normal, shape gy.shape + (3,), or plus
    the drag vectors ``drag`` (same shape; the cross-flow form)."""
    p = gy[..., None] * system.span_normals[:, None, :] if drag is None else np.array(drag, dtype=float)
    p[..., 2] -= system.line.weight
    return p


def _section_states(system: LineSystem, gy: np.ndarray, labels: list[str], *, tol: float, max_iter: int,
                    initial: StaticState | None = None, progress=None, cancel=None,
                    drag: Callable[[np.ndarray], np.ndarray] | None = None) -> list[StaticState]:
    """Step 1 of the section form: exact elastic spans, Newton over the suspension
    clamps (:mod:`linecheck.core.catenary`); the same StaticState as the paper's solver.

    ``drag`` (the cross-flow form): the drag vectors [N/m] (n_s, n_spans, ne+1, 3) as a function of
    the conductor's unit tangents at the span nodes (same shape): a follower load, solved by
    successive substitution from the still-air tangents until the loads change by less than
    :data:`FOLLOWER_RTOL` of their largest (docs/method.md "Loads")."""
    from .catenary import equilibrium, span_node_tangents, start_tension

    n_s = gy.shape[0]
    line = system.line
    Lu = system.unstretched_lengths
    clamps = system.clamp_points
    # first pass on the span chords (the still-air axes of a straight cable)
    chord = system.span_directions[None, :, None, :]
    dv = None if drag is None else drag(np.broadcast_to(chord, gy.shape + (3,)))
    p = section_loads(system, gy, dv)
    if initial is not None:
        pos = np.broadcast_to(clamps + initial.displacement, (n_s,) + clamps.shape).copy()
        H = np.broadcast_to(initial.tension, (n_s, system.n_spans))
    else:
        pos = np.broadcast_to(clamps, (n_s,) + clamps.shape).copy()
        wres = np.hypot(line.weight, np.abs(gy).mean(axis=-1))  # resultant-load start (as the paper solver)
        H = system.tension_nominal * wres / line.weight
    N0 = start_tension(np.diff(pos, axis=1), p, Lu, H)
    for _ in range(FOLLOWER_MAX):
        eq = equilibrium(clamps, system.insulator_tops, system.insulator_lengths, system.suspension,
                         system.tower_along, p, Lu, line.ea, pos, N0, labels=labels, tol=tol, max_iter=max_iter,
                         progress=progress, cancel=cancel)
        if drag is None:
            break
        new = drag(span_node_tangents(eq.spans, Lu, p))  # the drag on the deformed axes (follower)
        change = np.abs(new - dv).max() / max(float(np.abs(new).max()), 1e-300)
        if change <= FOLLOWER_RTOL:  # this equilibrium's own drag: settled
            break
        dv, p = new, section_loads(system, gy, new)
        pos, N0 = eq.p.copy(), eq.spans.N0.copy()  # warm start from the last equilibrium
    else:
        raise ConvergenceError(f"{labels[0]}: the cross-flow drag on the deformed conductor did not settle in "
                               f"{FOLLOWER_MAX} passes (last change {change:.2g})")
    e_span = np.stack([np.cos(system.span_headings), np.sin(system.span_headings), np.zeros(system.n_spans)], axis=1)
    out = []
    for j in range(n_s):
        sol_r = eq.spans.r[j]  # (n_spans, ne+1, 3)
        nodes = np.empty((system.n_nodes, 3))
        r = eq.p[j, :-1, None, :] + sol_r
        nodes[:-1] = r[:, :-1].reshape(-1, 3)
        nodes[-1] = r[-1, -1]
        f = eq.force[j]
        R = f * np.array([1.0, 1.0, -1.0])  # force on the tower's fixed point, R_z downward
        T_el = eq.spans.element_tension[j].reshape(-1)
        strain = T_el.max() / line.ea
        if strain > MAX_STRAIN or not np.isfinite(strain):
            raise ConvergenceError(
                f"{labels[j]}: no admissible equilibrium: conductor strain {strain:.3g} exceeds {MAX_STRAIN:g} "
                f"(tension {T_el.max():.4g} N); check the loads")
        out.append(StaticState(
            displacement=eq.p[j] - clamps,
            reactions=R,
            tension=np.einsum("ij,ij->i", eq.spans.N0[j], e_span),
            insulator_force=np.linalg.norm(f, axis=1),
            nodes=nodes,
            element_tension=T_el,
            iterations=int(eq.iterations[j]),
            residual=float(eq.residual[j]),
            held=eq.held[j] if eq.held[j].any() else None,
        ))
    return out


def _tridiag_solve(sub: np.ndarray, diag: np.ndarray, sup: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Thomas algorithm vectorised over a leading axis: (n_b, k-1), (n_b, k), (n_b, k-1), (n_b, k).

    Used for the longitudinal tangent K_x (paper Eq. 3), which is symmetric and diagonally
    dominant (-K_x: diagonal R_res/v + C_left + C_right, off-diagonal C), so elimination
    without pivoting is stable (Golub & Van Loan 2013, section 4.3.5)."""
    k = diag.shape[1]
    c = np.empty_like(diag)
    y = np.empty_like(b)
    c_prev = np.zeros(diag.shape[0])
    y_prev = np.zeros(diag.shape[0])
    piv = diag[:, 0].copy()
    for i in range(k):
        if i:
            piv = diag[:, i] - sub[:, i - 1] * c_prev
        c[:, i] = sup[:, i] / piv if i < k - 1 else 0.0
        y[:, i] = (b[:, i] - (sub[:, i - 1] * y_prev if i else 0.0)) / piv
        c_prev, y_prev = c[:, i], y[:, i]
    x = np.empty_like(b)
    x[:, -1] = y[:, -1]
    for i in range(k - 2, -1, -1):
        x[:, i] = y[:, i] - c[:, i] * x[:, i + 1]
    return x


def solve_static_batch(
    system: LineSystem,
    gy: np.ndarray,
    *,
    labels: list[str],
    tol: float = 1e-8,
    max_iter: int = 500,
    progress: Callable[[int, int], None] | None = None,
    cancel: threading.Event | None = None,
    drag: Callable[[np.ndarray], np.ndarray] | None = None,
) -> list[StaticState]:
    """:func:`solve_static` for many load cases at once (the downburst's mean states).

    The same Fig. 6 iteration (:func:`_fig6_iteration`) on all states together, each state
    frozen at its own convergence.  Every state starts from the still-air equilibrium (no
    warm start from its neighbour in time), so a state's result does not depend on the
    others; it agrees with the sequential solver to the tolerance ``tol``.

    Args:
        gy: [N/m] transverse loads, shape (n_states, n_spans, ne+1).
        labels: names of the states for error messages, length n_states.
        progress: ``progress(converged, n_states)`` once per outer iteration.
        drag: the cross-flow form's drag as a function of the tangents (:func:`solve_static`).
    """
    nt = system.n_towers
    gy = np.asarray(gy, dtype=float)
    n_s = gy.shape[0]
    if gy.shape[1:] != (system.n_spans, system.ne + 1):
        raise ValueError(f"gy must have shape (n, {system.n_spans}, {system.ne + 1}), got {gy.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(gy.reshape(n_s, -1)), axis=1))
    if bad.size:
        raise ConvergenceError(f"{labels[bad[0]]}: non-finite mean-wind load")
    if system.is_section:
        return _section_states(system, gy, labels, tol=tol, max_iter=max_iter, progress=progress, cancel=cancel,
                               drag=drag)
    still = still_air_state(system)
    d = np.broadcast_to(still.displacement, (n_s, nt, 3))
    H = np.broadcast_to(still.tension, (n_s, system.n_spans))
    Rres = np.broadcast_to(still.insulator_force, (n_s, nt))
    return _fig6_iteration(system, gy, d, H, Rres, labels=labels, tol=tol, max_iter=max_iter,
                           progress=progress, cancel=cancel)


@dataclass(frozen=True)
class MeanStates:
    """Step-1 results over time (downburst) or a single instant (synoptic).

    Attributes:
        time: [s] instants of the mean states, shape (n_t,).
        displacement: [m] (n_t, n_towers, 3); reactions: [N] (n_t, n_towers, 3);
        tension: [N] (n_t, n_spans); insulator_force: [N] (n_t, n_towers);
        nodes: [m] (n_t, n_nodes, 3); element_tension: [N] (n_t, n_elements);
        gy: [N/m] the mean transverse loads used, (n_t, n_spans, ne+1).
        still_air: the zero-wind reference state.
        held: bool (n_t, n_towers): the suspension clamps held at their still-air point in each
            state because their insulator would be in compression (uplift, :class:`StaticState`).
    """

    time: np.ndarray
    displacement: np.ndarray
    reactions: np.ndarray
    tension: np.ndarray
    insulator_force: np.ndarray
    nodes: np.ndarray
    element_tension: np.ndarray
    gy: np.ndarray
    still_air: StaticState
    held: np.ndarray

    def state(self, k: int) -> StaticState:
        """The k-th instant as a :class:`StaticState`."""
        return StaticState(
            self.displacement[k], self.reactions[k], self.tension[k], self.insulator_force[k],
            self.nodes[k], self.element_tension[k], 0, 0.0, self.held[k] if self.held[k].any() else None,
        )

    @property
    def reactions_wind(self) -> np.ndarray:
        """Wind-induced reactions (total - still air) [N], shape (n_t, n_towers, 3)."""
        return self.reactions - self.still_air.reactions[None]


def still_air_state(system: LineSystem) -> StaticState:
    """Equilibrium under self-weight only (reference for wind-induced values).

    Solved once per :class:`LineSystem` (:attr:`LineSystem.still_air`): a section's wind is
    evaluated on it too (node heights), so step 1 does not solve it again."""
    return system.still_air


def solve_mean_states(
    system: LineSystem,
    time: np.ndarray,
    gy: np.ndarray,
    *,
    progress: Callable[[int, int], None] | None = None,
    cancel: threading.Event | None = None,
    drag: Callable[[np.ndarray], np.ndarray] | None = None,
) -> MeanStates:
    """Step 1 at every instant of ``time`` (several instants: :func:`solve_static_batch`).

    Args:
        time: [s] shape (n_t,).
        gy: [N/m] mean transverse loads, shape (n_t, n_spans, ne+1).
        progress: called as ``progress(done, total)``.
        cancel: set it to stop; raises :class:`Cancelled`.
        drag: the cross-flow form's drag as a function of the tangents (:func:`solve_static`).
    """
    still = still_air_state(system)
    n_t = len(time)
    labels = [f"mean state {k + 1} of {n_t} (t = {time[k]:.1f} s)" for k in range(n_t)]
    if n_t > 1:  # all states at once (same iteration, vectorised over the states)
        states = solve_static_batch(system, gy, labels=labels, progress=progress, cancel=cancel, drag=drag)
    else:
        if cancel is not None and cancel.is_set():
            raise Cancelled("step 1 cancelled")
        states = [solve_static(system, gy[0], initial=still, label=labels[0], drag=drag)]
        if progress is not None:
            progress(1, 1)
    return MeanStates(
        time=np.asarray(time, dtype=float),
        displacement=np.stack([s.displacement for s in states]),
        reactions=np.stack([s.reactions for s in states]),
        tension=np.stack([s.tension for s in states]),
        insulator_force=np.stack([s.insulator_force for s in states]),
        nodes=np.stack([s.nodes for s in states]),
        element_tension=np.stack([s.element_tension for s in states]),
        gy=np.asarray(gy, dtype=float),
        still_air=still,
        held=np.stack([np.zeros(system.n_towers, dtype=bool) if s.held is None else s.held for s in states]),
    )


# ---- the compiled kernel's piece ``span`` (linecheck.core.kernel): its load check and numpy form

def _span_check(fns) -> float:
    """The compiled span-tension integrands (``fns.span_terms``) against :func:`span_terms` (one
    and several states, with and without the chords l); the largest relative difference."""
    rng = np.random.default_rng(25)
    pairs = []
    for lead in ((), (3,)):
        by = rng.standard_normal(lead + (4, 9)) * 1e4  # per state (step 1's loads), as the Newton passes it
        bz = rng.standard_normal((4, 9)) * 1e4
        ay, az = (rng.standard_normal(lead + (4, 1)) * 0.05 for _ in range(2))
        H = rng.uniform(1e4, 5e4, lead + (4,))
        l = rng.uniform(300.0, 500.0, lead + (4,))
        for ll in (None, l):
            ref = span_terms(ay, az, by, bz, H, 3.2e7, ll)
            got = kernel.span_compiled(fns.span_terms, ay, az, by, bz, H, 3.2e7, ll)
            if len(ref) != len(got):  # pragma: no cover - a compiled form that lost an output
                return np.inf
            pairs += list(zip(ref, got))
    return kernel.worst_difference(pairs)


kernel.register_check("span", _span_check, numpy=span_terms)
