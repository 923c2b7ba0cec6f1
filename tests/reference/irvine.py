"""Exact elastic catenary (Irvine 1981, "Cable Structures", ch. 2, Eqs 2.3-2.6).

Independent of linecheck's solver: a cable of unstretched length L_u, axial
stiffness EA and uniform load w per unit unstretched length, between two
supports at the same level a horizontal distance l apart.  Under a uniform
transverse wind load g and weight W the resultant w = sqrt(W^2 + g^2) lies in a
plane tilted about the chord, so the same closed form applies in that plane.
"""

from __future__ import annotations

import math

from scipy.optimize import brentq


def horizontal_tension(l: float, Lu: float, w: float, EA: float) -> float:
    """H [N] of a level elastic catenary: l = H L_u/EA + (2H/w) asinh(w L_u / (2H))."""
    V = 0.5 * w * Lu  # vertical (in-plane) end reaction by symmetry

    def f(H: float) -> float:
        return H * Lu / EA + 2.0 * H / w * math.asinh(V / H) - l

    return brentq(f, 1e-3, 1e10, xtol=1e-12, rtol=1e-15)


def reactions(l: float, Lu: float, W: float, g: float, EA: float) -> tuple[float, float, float]:
    """(R_x, R_y, R_z) [N] on the left support: H, g L_u / 2, W L_u / 2."""
    w = math.hypot(W, g)
    H = horizontal_tension(l, Lu, w, EA)
    return H, 0.5 * g * Lu, 0.5 * W * Lu


def midspan_sag(l: float, Lu: float, w: float, EA: float) -> float:
    """In-plane mid-span sag [m] (Irvine 1981 Eq. 2.6 at s = L_u/2, z positive downward)."""
    H = horizontal_tension(l, Lu, w, EA)
    V = 0.5 * w * Lu
    s = 0.5 * Lu
    return (w * s / EA) * (V / w - s / 2) + (H / w) * (
        math.sqrt(1 + (V / H) ** 2) - math.sqrt(1 + ((V - w * s) / H) ** 2)
    )
