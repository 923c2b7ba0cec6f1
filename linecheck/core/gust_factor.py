"""Closed-form gust response of a span (estimate 2 of the frequency-domain check) and the pieces
both estimates share: the von Karman spectrum S_v and Davenport's peak factor.

Davenport / Castanheta gust response factor for the transverse reaction (Davenport 1979;
Castanheta 1971 via Matheson & Holmes 1981):

    GF = 1 + 2 g I sqrt(B + R),
    B = int S_v(n)/sigma^2 |J(n)|^2 dn,  |J|^2 = 2/eta - 2 (1 - e^-eta)/eta^2,  eta = C n L / V,
    R = pi f1 S_v(f1) / (4 zeta_a sigma^2) |J(f1)|^2,  zeta_a = rho C_d D V / (4 pi f1 m),

g the expected peak factor of Davenport (1964), and the ASCE Manual 74 (2010) wire gust
response factor for comparison.  Estimate 1 (exact random vibration of the FE model) is
:mod:`linecheck.core.spectral`.  Formulas and sources are collected in docs/method.md.
Nothing here prints.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .wind.turbulence import von_karman_psd

EULER_GAMMA = 0.5772156649


# --------------------------------------------------------------------------- spectrum and peak factor
def von_karman(n: np.ndarray, sigma: float, length_scale: float, v_mean: float) -> np.ndarray:
    """One-sided von Karman spectrum S_v(n) [m^2/s^2/Hz] (von Karman 1948; the same
    function the time-domain synthesis uses, :func:`~linecheck.core.wind.turbulence.von_karman_psd`)."""
    return sigma**2 * von_karman_psd(n, length_scale, v_mean)


def peak_factor(nu: np.ndarray | float, duration: float) -> np.ndarray:
    """Davenport (1964) expected peak factor g = sqrt(2 ln nu T) + 0.5772/sqrt(2 ln nu T)."""
    a = np.sqrt(2.0 * np.log(np.maximum(np.asarray(nu, dtype=float) * duration, 1.0 + 1e-12)))
    return a + EULER_GAMMA / a


# --------------------------------------------------------------------------- estimate 2
def joint_acceptance_uniform(eta: np.ndarray) -> np.ndarray:
    """|J|^2 = 2/eta - 2 (1 - e^-eta)/eta^2 for exponential coherence over a uniform span
    (Davenport 1962; eta = C n L / V); limit 1 as eta -> 0."""
    eta = np.asarray(eta, dtype=float)
    small = eta < 1e-6
    e = np.where(small, 1.0, eta)
    out = 2.0 / e - 2.0 * (1.0 - np.exp(-e)) / e**2
    return np.where(small, 1.0 - eta / 3.0, out)


@dataclass(frozen=True)
class DavenportEstimate:
    """Estimate 2 for the transverse reaction: closed-form gust response factors.

    Attributes:
        background: B [-]; resonant: R [-]; peak_factor: g [-]; f1 [Hz]; zeta_a [-];
        GF_Dy = 1 + 2 g I sqrt(B + R); GF_QS = 1 + 2 g I sqrt(B); Cont_R [-];
        GF_ASCE: ASCE Manual 74 (2010) wire gust factor on the mean pressure, 1 + 2.7 E_w sqrt(B_w)
        (:func:`linecheck.core.codes.asce74_wire_gust`, exposure C).
    """

    background: float
    resonant: float
    peak_factor: float
    f1: float
    zeta_a: float
    GF_Dy: float
    GF_QS: float
    Cont_R: float
    GF_ASCE: float


def davenport_gust_factor(
    *,
    span: float,
    v_mean: float,
    intensity: float,
    length_scale: float,
    coherence_decay: float,
    f1: float,
    mass_per_length: float,
    air_density: float,
    drag_coefficient: float,
    diameter: float,
    duration: float,
    height: float,
) -> DavenportEstimate:
    """Estimate 2 (see module docstring); all inputs SI ([m], [m/s], [Hz], [kg/m], [s])."""
    n = np.geomspace(1e-5, 10.0, 4000)
    Sn = von_karman(n, 1.0, length_scale, v_mean)  # S/sigma^2
    J2 = joint_acceptance_uniform(coherence_decay * n * span / v_mean)
    B = float(np.trapezoid(Sn * J2, n))
    zeta = air_density * drag_coefficient * diameter * v_mean / (4 * np.pi * f1 * mass_per_length)  # Davenport 1962
    R = float(np.pi * f1 * von_karman(f1, 1.0, length_scale, v_mean) / (4 * zeta)
              * joint_acceptance_uniform(coherence_decay * f1 * span / v_mean))
    # cycling rate of the response (Davenport 1964): nu^2 = (f1^2 R + nu_B^2 B) / (B + R)
    nuB2 = float(np.trapezoid(n**2 * Sn * J2, n) / max(B, 1e-300))
    nu = np.sqrt((f1**2 * R + nuB2 * B) / (B + R))
    g = float(peak_factor(nu, duration))
    gB = float(peak_factor(np.sqrt(nuB2), duration))
    gf_dy = 1 + 2 * g * intensity * np.sqrt(B + R)
    gf_qs = 1 + 2 * gB * intensity * np.sqrt(B)
    # ASCE 74 (2010) section 2.1.5, exposure C: the wire gust factor on the 10-min mean pressure,
    # 1 + 2.7 E_w sqrt(B_w) (implemented once, in linecheck.core.codes)
    from .codes import asce74_wire_gust

    gf_asce = asce74_wire_gust(height, span, "C").mean_gust_factor
    return DavenportEstimate(B, R, g, f1, float(zeta), float(gf_dy), float(gf_qs),
                             float((gf_dy - gf_qs) / gf_dy), float(gf_asce))
