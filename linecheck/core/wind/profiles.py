"""The Wood et al. (2001) wall-jet vertical profile, shared by every downburst model.

One source for the profile and the position of its maximum: ``mean`` (the separable
"holmes-oliver" model) and ``ring`` (the travelling "ring-jet" models) both import it from here, so
neither keeps a copy (nothing here imports another linecheck module).

    f_z(eta) = 1.55 eta^(1/6) [1 - erf(0.70 eta)],   eta = z / delta        (Wood et al. 2001)

delta is the height where the speed has fallen to half its maximum; f_z peaks (1.00001) at
eta = ETA_PEAK.  Nothing here prints.
"""

from __future__ import annotations

import numpy as np
from scipy.special import erf

# Wood, Kwok, Motteram & Fletcher (2001), J. Wind Eng. Ind. Aerodyn. 89, 535-552: the constants of f_z
WOOD_A, WOOD_B = 1.55, 0.70


def wood(eta: np.ndarray | float) -> np.ndarray:
    """f_z [-] at eta = z/delta [-] (any shape; eta < 0 is taken as 0)."""
    eta = np.maximum(np.asarray(eta, dtype=float), 0.0)
    # Wood, Kwok, Motteram & Fletcher (2001), J. Wind Eng. Ind. Aerodyn. 89: V/V_max
    return WOOD_A * eta ** (1.0 / 6.0) * (1.0 - erf(WOOD_B * eta))


def wood_peak() -> float:
    """The maximum of f_z, found numerically (tests/core/test_ring.py checks :data:`ETA_PEAK` against it)."""
    from scipy.optimize import minimize_scalar

    res = minimize_scalar(lambda e: -float(wood(e)), bounds=(1e-6, 2.0), method="bounded",
                          options={"xatol": 1e-13})
    return float(res.x)


#: z/delta of the maximum of Wood et al.'s f_z, as :func:`wood_peak` finds it (xatol 1e-13); a
#: constant, so that every machine uses the same value and importing costs no optimisation
ETA_PEAK = 0.18358363375664333  # z_max = ETA_PEAK * delta
