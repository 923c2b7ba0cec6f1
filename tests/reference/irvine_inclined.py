"""Closed-form elastic catenary of an inclined span (Irvine 1981, "Cable Structures", ch. 2,
"the elastic catenary" with supports at different levels) -- an independent reference for the
section tests.  Written from the equilibrium of a cable element, shares no code with
linecheck.

Frame: the span's vertical plane, x horizontal from support A toward support B, z UP;
A = (0, 0), B = (L, h).  Lagrangian (unstretched arc-length) coordinate s in [0, L_u]; weight
W per unit unstretched length; axial stiffness EA; linear elastic (strain T/EA).

Equilibrium of the piece [0, s] (Irvine 1981 Eqs 2.1-2.2): the tension vector (force of the part
beyond s on the part before it) is (H, Q(s)) with H constant and Q(s) = Q0 + W s, Q0 = -V_A,
V_A the upward support force at A.  With T = sqrt(H^2 + Q^2) and the stretch dp/ds = 1 + T/EA,
(dx/ds, dz/ds) = (1 + T/EA) (H, Q) / T, which integrate to (Irvine 1981 Eqs 2.26-2.27 in our
sign convention)

    x(s) = H s / EA + (H/W) [asinh(Q(s)/H) - asinh(Q0/H)]
    z(s) = (Q0 s + W s^2/2) / EA + (H/W) [sqrt(1 + (Q(s)/H)^2) - sqrt(1 + (Q0/H)^2)].

The end conditions x(L_u) = L, z(L_u) = h fix (L_u, Q0) for a given H (or (H, Q0) for a given
L_u).  With a = asinh(Q0/H), b = asinh(Q1/H), Q1 = Q0 + W L_u, m = (a+b)/2, beta = (b-a)/2 they
read (cosh b - cosh a = 2 sinh m sinh beta, Q0 + Q1 = 2 H sinh m cosh beta,
sinh b - sinh a = 2 cosh m sinh beta):

    2 beta = (W/H) (L - H L_u/EA)                                   (x end condition)
    sinh m = h / (L_u H cosh(beta)/EA + (2H/W) sinh(beta))          (z end condition)
    L_u    = (2H/W) cosh(m) sinh(beta)                               (definition of Q1)

so L_u is the root of one scalar equation (monotone in practice, solved by bracketing).

Forces on the supports (the force of the cable on the support, global (x, z-down)):
A: (+H, V_A) with V_A = -Q0;  B: (-H, V_B) with V_B = Q1 = W L_u - V_A.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq


@dataclass(frozen=True)
class InclinedCatenary:
    """Elastic catenary between A = (0, 0) and B = (L, h) (z up).

    Attributes:
        L: [m] horizontal chord length.
        h: [m] rise of B above A.
        W: [N/m] weight per unit unstretched length.
        EA: [N] axial stiffness.
        H: [N] horizontal tension component (constant along the span).
        Lu: [m] unstretched length.
        VA: [N] upward support force at A (= downward force of the cable on A).
        VB: [N] upward support force at B; VA + VB = W Lu.
    """

    L: float
    h: float
    W: float
    EA: float
    H: float
    Lu: float
    VA: float
    VB: float

    @property
    def Q0(self) -> float:
        """[N] vertical tension component at A toward +s (= -VA)."""
        return -self.VA

    def shape(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(x, z) [m] at unstretched arc positions ``s`` [m] (any shape), Irvine 1981 Eqs 2.26-2.27."""
        s = np.asarray(s, dtype=float)
        H, W, EA, Q0 = self.H, self.W, self.EA, self.Q0
        Q = Q0 + W * s
        x = H * s / EA + (H / W) * (np.arcsinh(Q / H) - math.asinh(Q0 / H))
        z = (Q0 * s + 0.5 * W * s * s) / EA + (H / W) * (np.sqrt(1.0 + (Q / H) ** 2) - math.sqrt(1.0 + (Q0 / H) ** 2))
        return x, z

    def tension(self, s: np.ndarray) -> np.ndarray:
        """[N] tension magnitude T(s) = sqrt(H^2 + (Q0 + W s)^2) at unstretched positions ``s`` [m]."""
        s = np.asarray(s, dtype=float)
        return np.hypot(self.H, self.Q0 + self.W * s)

    def support_forces(self) -> tuple[tuple[float, float], tuple[float, float]]:
        """Force of the cable ON the supports [N] as (horizontal toward +x, vertical DOWN):
        A: (H, VA), B: (-H, VB)."""
        return (self.H, self.VA), (-self.H, self.VB)


def _m_beta(L: float, h: float, W: float, EA: float, H: float, Lu: float) -> tuple[float, float]:
    """(m, beta) from the two end conditions for given H and L_u (module docstring)."""
    beta = 0.5 * (W / H) * (L - H * Lu / EA)
    sm = h / (Lu * H * math.cosh(beta) / EA + (2.0 * H / W) * math.sinh(beta))
    return math.asinh(sm), beta


def _residual_lu(L: float, h: float, W: float, EA: float, H: float, Lu: float) -> float:
    m, beta = _m_beta(L, h, W, EA, H, Lu)
    return (2.0 * H / W) * math.cosh(m) * math.sinh(beta) - Lu


def _build(L: float, h: float, W: float, EA: float, H: float, Lu: float) -> InclinedCatenary:
    m, beta = _m_beta(L, h, W, EA, H, Lu)
    a = m - beta
    Q0 = H * math.sinh(a)
    VA = -Q0
    return InclinedCatenary(L=L, h=h, W=W, EA=EA, H=H, Lu=Lu, VA=VA, VB=W * Lu - VA)


def from_tension(L: float, h: float, W: float, EA: float, H: float) -> InclinedCatenary:
    """The elastic catenary of horizontal tension ``H`` [N] on the chord (``L``, ``h``) [m]:
    its unstretched length L_u and support forces (Irvine 1981 ch. 2, inclined span).

    Raises ValueError if no cable of positive stretch-free length fits (H >= EA-ish)."""
    if not (L > 0 and W > 0 and EA > 0 and H > 0):
        raise ValueError("L, W, EA and H must be positive")
    chord = math.hypot(L, h)
    lu_max = L * EA / H  # beta > 0 needs L_u < L EA / H
    lo = chord / (1.0 + 10.0 * (H + W * chord) / EA)  # far too short: residual > 0
    lo = min(lo, 0.5 * lu_max)
    hi = min(1.5 * chord, lu_max * (1.0 - 1e-12))
    f_lo = _residual_lu(L, h, W, EA, H, lo)
    f_hi = _residual_lu(L, h, W, EA, H, hi)
    while f_hi > 0 and hi < lu_max * (1.0 - 1e-9):
        hi = min(2.0 * hi, 0.5 * (hi + lu_max))
        f_hi = _residual_lu(L, h, W, EA, H, hi)
    if not (f_lo > 0 > f_hi):
        raise ValueError(f"no elastic catenary with H = {H} N on chord ({L}, {h}) m")
    Lu = brentq(lambda u: _residual_lu(L, h, W, EA, H, u), lo, hi, xtol=1e-13, rtol=1e-15, maxiter=500)
    return _build(L, h, W, EA, H, Lu)


def from_length(L: float, h: float, W: float, EA: float, Lu: float) -> InclinedCatenary:
    """The inverse: the elastic catenary of unstretched length ``Lu`` [m] on the chord (``L``,
    ``h``): its horizontal tension H and support forces.  L_u(H) decreases monotonically in H."""

    def g(logH: float) -> float:
        return from_tension(L, h, W, EA, math.exp(logH)).Lu - Lu

    chord = math.hypot(L, h)
    if Lu <= chord / (1.0 + 1.0):  # would need T > EA
        raise ValueError("unstretched length too short")
    lo, hi = math.log(1e-3 * W * chord), math.log(1e-3 * EA)
    while g(hi) > 0:
        hi += 1.0
    H = math.exp(brentq(g, lo, hi, xtol=1e-15, rtol=1e-15, maxiter=500))
    return from_tension(L, h, W, EA, H)
