"""Exact elastic-cable span element and the step-1 equilibrium of a line section (section form).

The paper's Appendix A describes every span by the shallow-cable (parabolic) theory with the
loads spread along the horizontal chord and the line straight and level.  A real section has
inclined spans (the weight is then no longer uniform along the horizontal), angle towers (the
spans are not colinear) and per-tower insulators.  For the section form linecheck therefore
describes every span by the exact extensible cable under distributed loads given per unit
UNSTRETCHED length (Irvine 1981, "Cable Structures", ch. 2, Eqs 2.20-2.25 in vector form):

    N(sigma) = N_0 - P(sigma),            P(sigma) = int_0^sigma p(s) ds          (equilibrium)
    dr/dsigma = N/|N| + N/EA                                                       (elastic, Hooke)
    r(L_u) - r(0) = c                                                              (chord)

with sigma the unstretched arc length, N the tension vector (pointing toward increasing sigma),
p the load per unit unstretched length (weight and drag; piecewise linear between the FE
nodes, which are equally spaced in sigma) and c the chord between the two clamps.  The three
unknowns N_0 are found by Newton's method with the exact flexibility

    F = dc/dN_0 = int_0^L_u [(I - t t^T)/|N| + I/EA] dsigma,  t = N/|N|,

integrated by 4-point Gauss-Legendre quadrature on every element (the integrand is smooth:
the error is far below 1e-9 of the chord with 10 elements per span).  Under a uniform load this
is Irvine's elastic catenary exactly (tests/core/test_sections_core.py checks the inclined span against
the closed form).

The towers are solved as in the paper's Fig. 6 (strain clamps fixed, suspension clamps on
their insulators), but with one Newton iteration over all suspension clamps at once: a clamp
moves on the sphere of radius v_j about its insulator's fixed top (a rigid link), its two
tangential force components are the residual, and the tangent is

    A = B^T (K_left + K_right) B + (f . u / v) I     (K = F^-1 of the adjacent spans),

the span stiffness projected on the sphere's tangent plane plus the pendulum stiffness of the
insulator (f the conductor force on the clamp, u the insulator's unit axis), block-tridiagonal
along the line.  Derivation: docs/method.md, "Line sections".

Uplift: a rigid insulator hangs in equilibrium only while the conductor pulls its clamp away
from the fixed top (f . u > 0; hanging, f points downward).  A clamp whose insulator would be in
compression (f . u <= 0: the adjacent spans pull it up, e.g. a valley tower) has no stable
pendulum equilibrium; it is then held at its still-air point (as a strain clamp, i.e. as if held
down) for that load case and reported (:attr:`SectionEquilibrium.held`).  A held clamp whose
conductor force turns downward at convergence is released and the iteration resumes (at most
:data:`MAX_RELEASES` times per load case).  docs/method.md, "Line sections".  Nothing here prints.
"""

from __future__ import annotations

import threading
from collections.abc import Callable

import numpy as np

from .errors import Cancelled, ConvergenceError

_GT, _GW = np.polynomial.legendre.leggauss(4)
_GT = 0.5 * (_GT + 1.0)  # Gauss points on [0, 1]
_GW = 0.5 * _GW

#: Times a load case may release its held clamps (uplift) and iterate again before its uplift is
#: called undecided (an insulator whose vertical force is about zero, alternating in sign).
MAX_RELEASES = 3


# --------------------------------------------------------------------------- clipping-in
def clip_in(H: np.ndarray, L: np.ndarray, h: np.ndarray, W: float, EA: float) -> tuple[np.ndarray, np.ndarray]:
    """Unstretched length of inclined elastic catenaries with horizontal tension H.

    Irvine (1981) ch. 2, elastic catenary with supports at different levels, in the span's
    vertical plane (x along the span, z up), weight W per unit unstretched length:

        L = H L_u/EA + (H/W) [asinh((V_0 + W L_u)/H) - asinh(V_0/H)]
        h = V_0 L_u/EA + W L_u^2/(2 EA) + [sqrt(H^2 + (V_0 + W L_u)^2) - sqrt(H^2 + V_0^2)]/W

    solved for (V_0, L_u) by Newton's method (V_0 the vertical component of the tension at
    the first support, along the cable: negative when the cable leaves it downward).

    Args: H [N], L [m] horizontal chord, h [m] rise of the second support, all shape (n,);
        W [N/m]; EA [N].
    Returns: L_u [m], V_0 [N], shape (n,).
    """
    H, L, h = (np.asarray(a, dtype=float) for a in (H, L, h))
    Lu = np.hypot(L, h) * (1.0 + (W * L) ** 2 / (24.0 * H**2))  # parabola length (Irvine Eq. 2.14)
    V0 = H * h / L - 0.5 * W * Lu
    for _ in range(100):
        a, b = V0 / H, (V0 + W * Lu) / H
        ra, rb = np.sqrt(1.0 + a * a), np.sqrt(1.0 + b * b)
        X = H * Lu / EA + (H / W) * (np.arcsinh(b) - np.arcsinh(a)) - L
        Z = V0 * Lu / EA + W * Lu**2 / (2.0 * EA) + (H / W) * (rb - ra) - h
        # Jacobian d(X, Z)/d(V_0, L_u)
        x_v = (1.0 / rb - 1.0 / ra) / W
        x_l = H / EA + 1.0 / rb
        z_v = Lu / EA + (b / rb - a / ra) / W
        z_l = (V0 + W * Lu) / EA + b / rb
        det = x_v * z_l - x_l * z_v
        dV = -(z_l * X - x_l * Z) / det
        dL = -(-z_v * X + x_v * Z) / det
        V0, Lu = V0 + dV, Lu + dL
        if np.all(np.abs(dL) <= 1e-14 * Lu) and np.all(np.abs(dV) <= 1e-12 * H):
            break
    else:  # pragma: no cover - guarded by the loader's tension > W L/2
        raise ConvergenceError("clipping-in: the elastic catenary of a span did not converge")
    return Lu, V0


# --------------------------------------------------------------------------- span element
class SpanSolution:
    """Exact extensible cable of every span for one set of chords (vectorised).

    Attributes (leading axes ``(..., n_spans)``):
        N0: [N] tension vector at the first clamp, (..., 3).
        N_end: [N] tension vector at the second clamp, (..., 3).
        K: [N/m] chord stiffness F^-1, (..., 3, 3).
        r: [m] node positions relative to the first clamp, (..., ne+1, 3).
        element_tension: [N] |N| at element mid-points, (..., ne).
    """

    def __init__(self, N0, N_end, K, r, element_tension) -> None:
        self.N0, self.N_end, self.K, self.r, self.element_tension = N0, N_end, K, r, element_tension


def _integrals(p: np.ndarray, h: np.ndarray):
    """Load integrals of piecewise-linear p on elements of length h (exact).

    p: (..., n_spans, ne+1, 3) [N/m]; h: (n_spans,) [m].
    Returns P at the Gauss points (..., ne, g, 3), the element integrals of P (..., ne, 3)
    and the total P(L_u) (..., 3).
    """
    hh = h[:, None, None]
    P_nodes = np.concatenate([np.zeros_like(p[..., :1, :]),
                              np.cumsum(0.5 * hh * (p[..., :-1, :] + p[..., 1:, :]), axis=-2)], axis=-2)
    pa, pb = p[..., :-1, None, :], p[..., 1:, None, :]
    t = _GT[:, None]
    h4 = h[:, None, None, None]
    P_g = P_nodes[..., :-1, None, :] + h4 * (pa * (t - 0.5 * t * t) + pb * (0.5 * t * t))
    intP = hh * (P_nodes[..., :-1, :] + hh * (p[..., :-1, :] / 3.0 + p[..., 1:, :] / 6.0))
    return P_g, intP, P_nodes[..., -1, :]


def solve_spans(chord: np.ndarray, p: np.ndarray, Lu: np.ndarray, EA: float, N0: np.ndarray,
                *, what: str = "span") -> SpanSolution:
    """Tension of every span for given chords (Newton on N_0 with the exact flexibility F).

    Args:
        chord: [m] second clamp minus first clamp, shape (..., n_spans, 3).
        p: [N/m] load per unit unstretched length at the FE nodes, (..., n_spans, ne+1, 3).
        Lu: [m] unstretched lengths, (n_spans,).
        EA: [N] axial stiffness.
        N0: [N] start value of the tension vector at the first clamp, (..., n_spans, 3).
    """
    ne = p.shape[-2] - 1
    h = Lu / ne
    P_g, intP, P_tot = _integrals(p, h)
    w = (h[:, None] * _GW[None, :])[:, None, :, None]  # (n_spans, 1, g, 1)
    eye = np.eye(3)
    N0 = np.array(N0, dtype=float)
    scale = np.linalg.norm(chord, axis=-1)

    def evaluate(N0: np.ndarray):
        """Element chords seg (..., n_spans, ne, 3), |N| at the Gauss points and the flexibility F."""
        N = N0[..., None, None, :] - P_g  # (..., n_spans, ne, g, 3)
        nn = np.linalg.norm(N, axis=-1, keepdims=True)
        t = N / nn
        seg = (w * t).sum(axis=-2) + (h[:, None, None] * N0[..., None, :] - intP) / EA
        F = (w[..., None] * (eye - t[..., :, None] * t[..., None, :]) / nn[..., None]).sum(axis=(-3, -4))
        return seg, nn, F + (Lu / EA)[:, None, None] * eye

    for _ in range(60):
        seg, _nn, F = evaluate(N0)
        res = chord - seg.sum(axis=-2)
        step = np.linalg.solve(F, res[..., None])[..., 0]
        big = np.linalg.norm(step, axis=-1, keepdims=True) / np.maximum(np.linalg.norm(N0, axis=-1, keepdims=True), 1e-300)
        step = np.where(big > 0.5, step * (0.5 / np.maximum(big, 1e-300)), step)  # cap |dN_0| at |N_0|/2
        N0 = N0 + step
        if np.all(np.linalg.norm(res, axis=-1) <= 1e-12 * scale):
            break
    else:
        raise ConvergenceError(f"{what}: the elastic-cable span iteration did not converge (loads too large?)")
    seg, nn, F = evaluate(N0)  # at the converged N_0
    r = np.concatenate([np.zeros_like(seg[..., :1, :]), np.cumsum(seg, axis=-2)], axis=-2)
    # element tension at the mid-point: Gauss points are symmetric, take the mean of the two inner ones
    mid = 0.5 * (nn[..., 1, 0] + nn[..., 2, 0])
    return SpanSolution(N0, N0 - P_tot, np.linalg.inv(F), r, mid)


def span_node_tangents(spans: SpanSolution, Lu: np.ndarray, p: np.ndarray) -> np.ndarray:
    """[-] unit tangent of every span's cable at its FE nodes, t = N/|N| with N(sigma_k) = N_0 - P(sigma_k)
    (module docstring; P of the piecewise-linear load, exact by the trapezoid rule), shape
    (..., n_spans, ne+1, 3); ``spans`` a solution for the loads p [N/m] (..., n_spans, ne+1, 3)."""
    ne = p.shape[-2] - 1
    inc = 0.5 * (Lu / ne)[:, None, None] * (p[..., :-1, :] + p[..., 1:, :])  # (..., n_spans, ne, 3)
    P = np.concatenate([np.zeros_like(inc[..., :1, :]), np.cumsum(inc, axis=-2)], axis=-2)
    N = spans.N0[..., None, :] - P
    return N / np.linalg.norm(N, axis=-1, keepdims=True)


def start_tension(chord: np.ndarray, p: np.ndarray, Lu: np.ndarray, H: np.ndarray) -> np.ndarray:
    """A start N_0 for :func:`solve_spans`: H along the chord's part normal to the resultant
    load, plus half the resultant (the mid-span tension of a symmetric cable is then H).

    chord (..., n_spans, 3); p (..., n_spans, ne+1, 3); Lu (n_spans,); H [N] (..., n_spans)."""
    ne = p.shape[-2] - 1
    P_tot = (0.5 * (Lu / ne)[:, None, None] * (p[..., :-1, :] + p[..., 1:, :])).sum(axis=-2)
    wdir = P_tot / np.maximum(np.linalg.norm(P_tot, axis=-1, keepdims=True), 1e-300)
    c_perp = chord - (chord * wdir).sum(axis=-1, keepdims=True) * wdir
    c_perp /= np.linalg.norm(c_perp, axis=-1, keepdims=True)
    return H[..., None] * c_perp + 0.5 * P_tot


# --------------------------------------------------------------------------- section equilibrium
def _tangent_bases(u: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Orthonormal tangent bases (3, 2) of the unit sphere at u, first vector closest to ``ref``.

    u: (..., k, 3) unit insulator axes; ref: (k, 3) horizontal along-line directions."""
    t1 = ref - (ref * u).sum(axis=-1, keepdims=True) * u
    t1 /= np.linalg.norm(t1, axis=-1, keepdims=True)
    t2 = np.cross(u, t1)
    return np.stack([t1, t2], axis=-1)


def _block_tridiag_solve(D: np.ndarray, E: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Solve a symmetric block-tridiagonal system (block Thomas, vectorised over states).

    D: (n_s, k, m, m) diagonal blocks, E: (n_s, k-1, m, m) blocks A[i, i+1], b: (n_s, k, m).
    A is symmetric positive definite here (span stiffness + pendulum), so no pivoting is needed
    (Golub & Van Loan 2013, section 4.5.1)."""
    k = D.shape[1]
    Dp = np.empty_like(D)
    y = np.empty_like(b)
    Dp[:, 0] = D[:, 0]
    y[:, 0] = b[:, 0]
    for i in range(1, k):
        # eliminate block row i: L_i = E_{i-1}^T Dp_{i-1}^-1
        Et = np.swapaxes(E[:, i - 1], -1, -2)
        X = np.linalg.solve(Dp[:, i - 1], E[:, i - 1])  # Dp^-1 E
        Dp[:, i] = D[:, i] - Et @ X
        y[:, i] = b[:, i] - (Et @ np.linalg.solve(Dp[:, i - 1], y[:, i - 1][..., None]))[..., 0]
    x = np.empty_like(b)
    x[:, -1] = np.linalg.solve(Dp[:, -1], y[:, -1][..., None])[..., 0]
    for i in range(k - 2, -1, -1):
        x[:, i] = np.linalg.solve(Dp[:, i], (y[:, i] - (E[:, i] @ x[:, i + 1][..., None])[..., 0])[..., None])[..., 0]
    return x


class SectionEquilibrium:
    """Converged clamps and span solutions of ``n_s`` load cases (see :func:`equilibrium`).

    Attributes: p [m] clamp positions (n_s, n_towers, 3); spans: :class:`SpanSolution`
    (leading axes (n_s, n_spans)); force [N] conductor force on every clamp f_j (z up),
    (n_s, n_towers, 3); iterations (n_s,); residual [N] (n_s,); held: bool (n_s, n_towers),
    the suspension clamps held at their still-air point because their insulator would be in
    compression (uplift; module docstring).
    """

    def __init__(self, p, spans, force, iterations, residual, held) -> None:
        self.p, self.spans, self.force, self.iterations, self.residual = p, spans, force, iterations, residual
        self.held = held


def conductor_forces(sol: SpanSolution, n_towers: int) -> np.ndarray:
    """Force of the conductor on every clamp, f_j = N_0 of span j - N_end of span j-1, (..., n_towers, 3)."""
    shape = sol.N0.shape[:-2] + (n_towers, 3)
    f = np.zeros(shape)
    f[..., :-1, :] += sol.N0
    f[..., 1:, :] -= sol.N_end
    return f


def _check_finite(f: np.ndarray, labels: list[str], it: int) -> None:
    """Raise :class:`ConvergenceError` naming the first state whose clamp forces f (n_s, n_towers, 3)
    are not all finite after ``it`` iterations."""
    if not np.all(np.isfinite(f)):
        j = int(np.flatnonzero(~np.all(np.isfinite(f.reshape(f.shape[0], -1)), axis=1))[0])
        raise ConvergenceError(f"{labels[j]}: non-finite values after {it} iterations")


def _tangent_system(sol: SpanSolution, f: np.ndarray, pos: np.ndarray, tops: np.ndarray, along: np.ndarray,
                    idx: np.ndarray, vs: np.ndarray, adjacent: np.ndarray, held: np.ndarray):
    """Newton system of the suspension clamps on their insulator spheres (module docstring).

    Args: sol: spans at the current clamps; f [N] conductor forces (n_s, n_towers, 3); pos [m]
        clamps (n_s, n_towers, 3); tops [m] (n_towers, 3); along (n_towers, 3); idx: suspension
        towers (k,); vs [m] their insulator lengths (k,); adjacent: bool (k-1,) consecutive towers;
        held: bool (n_s, k), clamps held at their still-air point (uplift): their rows are the
        identity with a zero residual, decoupled from their neighbours (a fixed clamp).
    Returns: B tangent bases (n_s, k, 3, 2); r [N] tangential forces (n_s, k, 2); D [N/m]
        diagonal blocks (n_s, k, 2, 2) and E [N/m] off-diagonal blocks (n_s, k-1, 2, 2) of
        A = B^T (K_left + K_right) B + (f . u / v) I.
    """
    n_s, nt, k = pos.shape[0], pos.shape[1], idx.size
    u = (pos[:, idx] - tops[idx]) / vs[:, None]
    B = _tangent_bases(u, along[idx])  # (n_s, k, 3, 2)
    fk = f[:, idx]
    fu = (fk * u).sum(axis=-1)  # insulator tension (positive at every clamp not held)
    r = np.einsum("skab,ska->skb", B, fk)  # tangential force components [N]
    r[held] = 0.0
    Bt = np.swapaxes(B, -1, -2)
    Kl = np.zeros((n_s, k, 3, 3))
    has_left = idx > 0
    Kl[:, has_left] = sol.K[:, idx[has_left] - 1]
    Kr = np.zeros((n_s, k, 3, 3))
    has_right = idx < nt - 1
    Kr[:, has_right] = sol.K[:, idx[has_right]]
    D = Bt @ (Kl + Kr) @ B + (fu / vs)[..., None, None] * np.eye(2)
    D[held] = np.eye(2)
    E = np.zeros((n_s, max(k - 1, 0), 2, 2))
    if k > 1:
        E[:, adjacent] = -(Bt[:, :-1] @ sol.K[:, idx[:-1]] @ B[:, 1:])[:, adjacent]
        E[held[:, :-1] | held[:, 1:]] = 0.0
    return B, r, D, E


def _hold_compressed(pos: np.ndarray, f: np.ndarray, clamps: np.ndarray, tops: np.ndarray, idx: np.ndarray,
                     vs: np.ndarray, held: np.ndarray, active: np.ndarray) -> bool:
    """Hold the active states' suspension clamps whose insulator is in compression (f . u <= 0,
    uplift) at their still-air points (``pos`` and ``held`` updated in place); True if any."""
    u = (pos[:, idx] - tops[idx]) / vs[:, None]
    new = ((f[:, idx] * u).sum(axis=-1) <= 0.0) & ~held & active[:, None]
    if not new.any():
        return False
    held |= new
    s, i = np.nonzero(new)
    pos[s, idx[i]] = clamps[idx[i]]
    return True


def _release_pulled_down(f: np.ndarray, idx: np.ndarray, held: np.ndarray, done: np.ndarray, releases: np.ndarray,
                         labels: list[str]) -> None:
    """Release the held clamps of converged states whose conductor force points downward
    (f_z < 0: a hanging insulator would be in tension there) and reopen those states (``held``,
    ``done`` and ``releases`` updated in place).  Raises :class:`ConvergenceError` when a state
    needs more than :data:`MAX_RELEASES` releases (its uplift is undecided)."""
    pulled = held & (f[:, idx, 2] < 0.0) & (done > 0)[:, None]
    if not pulled.any():
        return
    states = np.flatnonzero(pulled.any(axis=1))
    releases[states] += 1
    if np.any(releases[states] > MAX_RELEASES):
        j = int(states[np.argmax(releases[states])])
        t = int(idx[np.flatnonzero(held[j])[0]]) + 1
        raise ConvergenceError(f"{labels[j]}: the suspension insulator at tower {t} alternates between tension "
                               "and compression (its vertical force is about zero): uplift undecided")
    held &= ~pulled
    done[states] = 0


def _move_clamps(pos: np.ndarray, tops: np.ndarray, idx: np.ndarray, vs: np.ndarray, B: np.ndarray,
                 dq: np.ndarray, active: np.ndarray) -> np.ndarray:
    """Move the active states' suspension clamps by dq on their spheres (in place).

    The step is capped at 0.3 v per clamp, then the moved point is projected back on the sphere
    of radius v about the insulator top (rigid link).  dq [m] (n_s, k, 2) in the bases B;
    active: bool (n_s,).  Returns the largest clamp step per state [m] (n_s,).
    """
    size = np.linalg.norm(dq, axis=-1)
    cap = 0.3 * vs
    dq = np.where((size > cap)[..., None], dq * (cap / np.maximum(size, 1e-300))[..., None], dq)
    dq[~active] = 0.0
    moved = pos[:, idx] + np.einsum("skab,skb->ska", B, dq) - tops[idx]
    pos[:, idx] = tops[idx] + vs[:, None] * moved / np.linalg.norm(moved, axis=-1, keepdims=True)
    return np.max(np.linalg.norm(dq, axis=-1), axis=1)


def _tangential_residual(f: np.ndarray, pos: np.ndarray, tops: np.ndarray, idx: np.ndarray,
                         vs: np.ndarray, held: np.ndarray) -> np.ndarray:
    """Largest force [N] on a suspension clamp normal to its insulator, per state (n_s,); a held
    clamp (uplift) is fixed and carries any force."""
    if not idx.size:
        return np.zeros(pos.shape[0])
    u = (pos[:, idx] - tops[idx]) / vs[:, None]
    fk = f[:, idx]
    normal = np.linalg.norm(fk - (fk * u).sum(axis=-1, keepdims=True) * u, axis=-1)
    return np.max(np.where(held, 0.0, normal), axis=1)


def equilibrium(clamps: np.ndarray, tops: np.ndarray, v: np.ndarray, suspension: np.ndarray, along: np.ndarray,
                p: np.ndarray, Lu: np.ndarray, EA: float, p_start: np.ndarray, N0_start: np.ndarray, *,
                labels: list[str], tol: float, max_iter: int, progress: Callable[[int, int], None] | None = None,
                cancel: threading.Event | None = None) -> SectionEquilibrium:
    """Step-1 equilibrium of a section under ``n_s`` load cases (Newton over the suspension clamps;
    a clamp whose insulator would be in compression is held at its still-air point, module docstring).

    Args:
        clamps: [m] still-air clamp points (n_towers, 3) (strain clamps and held clamps stay there).
        tops: [m] insulator fixed tops (n_towers, 3) (used at suspension towers).
        v: [m] insulator lengths (n_towers,); suspension: bool (n_towers,).
        along: [-] horizontal along-line unit vector at every tower (n_towers, 3) (basis reference).
        p: [N/m] loads per unit unstretched length (n_s, n_spans, ne+1, 3).
        Lu: [m] unstretched lengths (n_spans,); EA [N].
        p_start: [m] start clamp positions (n_s, n_towers, 3); N0_start: [N] (n_s, n_spans, 3).
        labels: state names for messages; tol: [m] clamp-motion tolerance relative to max(v, 1).
    """
    n_s, nt = p.shape[0], clamps.shape[0]
    idx = np.flatnonzero(suspension)
    k = idx.size
    pos = np.array(p_start, dtype=float)
    pos[:, ~suspension] = clamps[~suspension]
    N0 = np.array(N0_start, dtype=float)
    tol_d = tol * max(float(v[idx].max()) if k else 1.0, 1.0)
    adjacent = np.diff(idx) == 1 if k else np.zeros(0, dtype=bool)
    vs = v[idx]
    what = labels[0] if n_s == 1 else "mean states"
    done_at = np.zeros(n_s, dtype=int)
    last = np.full(n_s, np.inf)
    held = np.zeros((n_s, k), dtype=bool)
    releases = np.zeros(n_s, dtype=int)
    for it in range(1, max_iter + 1):
        if cancel is not None and cancel.is_set():
            raise Cancelled("step 1 cancelled")
        sol = solve_spans(np.diff(pos, axis=1), p, Lu, EA, N0, what=what)
        N0 = sol.N0
        f = conductor_forces(sol, nt)
        _check_finite(f, labels, it)
        if k == 0:
            done_at[:] = it
            last[:] = 0.0
            break
        active = done_at == 0
        if _hold_compressed(pos, f, clamps, tops, idx, vs, held, active):
            continue  # held clamps moved back to their still-air points: solve the spans there first
        B, r, D, E = _tangent_system(sol, f, pos, tops, along, idx, vs, adjacent, held)
        change = _move_clamps(pos, tops, idx, vs, B, _block_tridiag_solve(D, E, r), active)
        last = np.where(active, change, last)
        done_at[active & (change <= tol_d)] = it
        _release_pulled_down(f, idx, held, done_at, releases, labels)
        if progress is not None:
            progress(int((done_at > 0).sum()), n_s)
        if np.all(done_at > 0):
            break
    else:
        j = int(np.flatnonzero(done_at == 0)[0])
        raise ConvergenceError(f"{labels[j]}: step-1 section solver did not converge in {max_iter} iterations "
                               f"(last clamp motion {last[j]:.3g} m)")
    sol = solve_spans(np.diff(pos, axis=1), p, Lu, EA, N0, what=what)
    f = conductor_forces(sol, nt)
    held_towers = np.zeros((n_s, nt), dtype=bool)
    held_towers[:, idx] = held
    return SectionEquilibrium(pos, sol, f, done_at, _tangential_residual(f, pos, tops, idx, vs, held), held_towers)
