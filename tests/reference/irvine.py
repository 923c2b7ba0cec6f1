"""Exact elastic catenary (Irvine 1981) for the tests: re-exported from :mod:`linecheck.reference`,
which holds the closed forms once (they are independent of the solvers they check)."""

from __future__ import annotations

import math

from linecheck.reference import catenary_midspan_sag as midspan_sag  # noqa: F401
from linecheck.reference import catenary_tension as horizontal_tension


def reactions(l: float, Lu: float, W: float, g: float, EA: float) -> tuple[float, float, float]:
    """(R_x, R_y, R_z) [N] on the left support: H, g L_u / 2, W L_u / 2 (the resultant
    w = sqrt(W^2 + g^2) lies in a plane tilted about the chord)."""
    w = math.hypot(W, g)
    return horizontal_tension(l, Lu, w, EA), 0.5 * g * Lu, 0.5 * W * Lu
