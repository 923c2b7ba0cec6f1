"""Closed-form references used by ``linecheck validate`` (and the tests).

Independent of the solvers they check: the exact elastic catenary (Irvine 1981), the
lumped (discrete) taut string, and the damped single-DOF response to a harmonic load.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq


def catenary_tension(l: float, Lu: float, w: float, EA: float) -> float:
    """Horizontal tension [N] of a level elastic catenary (Irvine 1981, Eqs 2.3-2.6):
    l = H L_u/EA + (2H/w) asinh(w L_u / (2H)); w per unit unstretched length [N/m]."""
    V = 0.5 * w * Lu

    def f(H: float) -> float:
        return H * Lu / EA + 2.0 * H / w * math.asinh(V / H) - l

    return brentq(f, 1e-3, 1e10, xtol=1e-12, rtol=1e-15)


def catenary_midspan_sag(l: float, Lu: float, w: float, EA: float) -> float:
    """In-plane mid-span sag [m] of the level elastic catenary (Irvine 1981 Eq. 2.6)."""
    H = catenary_tension(l, Lu, w, EA)
    V = 0.5 * w * Lu
    s = 0.5 * Lu
    return (w * s / EA) * (V / w - s / 2) + (H / w) * (
        math.sqrt(1 + (V / H) ** 2) - math.sqrt(1 + ((V - w * s) / H) ** 2)
    )


def discrete_string_frequencies(H: float, span: float, n_el: int, node_mass: float, n: int) -> np.ndarray:
    """[Hz] of a lumped taut string: f_k = (1/pi) sqrt(k_e/m) sin(k pi / (2 n_el)), k_e = H n_el / span."""
    k_e = H * n_el / span
    k = np.arange(1, n + 1)
    return 2 * np.sqrt(k_e / node_mass) * np.sin(k * np.pi / (2 * n_el)) / (2 * np.pi)


def sdof_harmonic(t: np.ndarray, k: float, m: float, zeta: float, F0: float, W: float) -> np.ndarray:
    """Displacement [m] of a damped SDOF from rest under F0 sin(W t) (Chopra 2012 section 3.2)."""
    wn = math.sqrt(k / m)
    r = W / wn
    ust = F0 / k
    den = (1 - r**2) ** 2 + (2 * zeta * r) ** 2
    C = ust * (1 - r**2) / den
    D = -ust * 2 * zeta * r / den
    wd = wn * math.sqrt(1 - zeta**2)
    A = -D
    B = (-C * W + zeta * wn * A) / wd
    return np.exp(-zeta * wn * t) * (A * np.cos(wd * t) + B * np.sin(wd * t)) + C * np.sin(W * t) + D * np.cos(W * t)
