"""Travelling-outflow downburst model "ring-jet" (issue 15): ring vortex + ground image + wall jet.

A non-separable, stationary-storm running-mean field built from published parts, in units of
the jet diameter D_j [m] and the downdraft speed V_j [m/s]: lengths rho = r/D_j, zeta = z/D_j,
velocities u/V_j, time tau = t V_j/D_j.  Because every closure constant below is dimensionless,
the field obeys u(r, z, t; D_j, V_j) = V_j s(r/D_j, z/D_j, t V_j/D_j) exactly: doubling D_j with
V_j fixed doubles every event time, doubling V_j halves them (tested).

Parts (each cited where used):

1. Primary ring vortex of circulation -Gamma (sense: descending, outflow beneath it), radius
   a(tau), height h(tau), and its ground image (+Gamma at -h) so that the vertical velocity is
   zero on the ground z = 0 (method of images, Lamb 1932 sec. 161; Saffman 1992 ch. 10).
   Velocity of a circular vortex filament from the Stokes stream function with complete
   elliptic integrals K, E (Lamb 1932 sec. 161; explicit components e.g. Yoon & Heister 2004,
   Int. J. Numer. Meth. Fluids 44, Eq. 6-7).
2. Core: Lamb-Oseen desingularisation of the filament, u -> u (1 - exp(-s^2/delta^2)), s the
   distance to the core centre line (Lamb-Oseen vortex, Saffman 1992 Eq. 1.7.5 -- the local 2-D
   limit of the ring), core radius delta.  Self-induced speed of a ring with a Gaussian core
   (Saffman 1970, Stud. Appl. Math. 49): U = Gamma/(4 pi a) [ln(8 a/delta) - 0.558].  Core
   volume conserved under stretching: delta^2 a = const (Saffman 1992 sec. 10.2).
3. Path: the ring moves with its self-induced velocity plus the velocity its image induces
   at its core (vortex dynamics; Saffman 1992 sec. 10.2; Walker et al. 1987, JFM 181):
   da/dtau = u_r,img(a, h),  dh/dtau = -U(a) + u_z,img(a, h).
4. Circulation from the slug model at the formation number (Gharib, Rambod & Shariff 1998, JFM
   360: a starting jet puts Gamma = V_j L / 2 into its ring until L/D ~ 4, the rest stays in a
   trailing jet): Gamma = 2 V_j D_j.
5. Behind the ring (r < a(tau)) the trailing jet's wall jet, in its quasi-steady state, is the
   Holmes & Oliver (2000) radial profile times the Wood et al. (2001) vertical profile (the same
   f_r, f_z as the "holmes-oliver" model), switched on by the passage of the front and held while
   the jet blows (duration TAU_JET), then decaying exponentially (TAU_DECAY).

Closure constants (modelling choices, sensitivity in docs/wind.md; none fitted to the paper):
ring formation radius A0 = 0.5 (jet radius), height H0 = 1.0, core DELTA0 = 0.1 (core/ring
radius 0.2, Gharib et al. 1998 range 0.2-0.4), circulation decay TAU_GAMMA = 4 (one formation time),
wall-jet amplitude C_W = 1.0 (peak wall-jet speed ~ V_j in impinging-jet experiments), jet
duration TAU_JET = 5, decay TAU_DECAY = 2.5; the ring's core rolls along the ground (h >= delta).
Nothing here prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.special import ellipe, ellipk, erf

# ---------------------------------------------------------------- closure constants (dimensionless)
A0 = 0.5  # ring formation radius / D_j: the jet edge
H0 = 1.0  # ring formation height / D_j above ground
DELTA0 = 0.1  # Lamb-Oseen core radius / D_j at formation (core/ring radius 0.2, Gharib et al. 1998)
GAMMA = 2.0  # circulation / (V_j D_j): slug model at formation number 4 (Gharib et al. 1998)
SAFFMAN_CORE = 0.558  # Saffman (1970): Gaussian-core constant in the self-induced speed
C_W = 1.0  # wall-jet peak speed / V_j
R_MAX = 1.2  # wall-jet radius of peak outflow / D_j (same default as "holmes-oliver")
R_DECAY = 0.5  # wall-jet radial decay length / D_j (same default as "holmes-oliver")
Z_MAX = 0.025  # wall-jet height of peak outflow / D_j (same default as "holmes-oliver")
TAU_GAMMA = 4.0  # circulation decay time / (D_j/V_j): one formation time L/D = 4 (Gharib et al. 1998)
TAU_JET = 5.0  # duration of the trailing jet / (D_j/V_j) (~5 min for D_j = 1 km, V_j = 15 m/s)
TAU_DECAY = 2.5  # decay time of the wall jet after the jet stops / (D_j/V_j)
# default analysed event length / (D_j/V_j): until the jet envelope falls to 0.1 (as Chay's T_f)
TAU_END = TAU_JET + TAU_DECAY * math.log(10.0)
TAU_PATH = 4.0 * TAU_END  # the path is integrated this far (longer analysis.duration: held)
_TAU_GRID = 16001  # trajectory samples over [0, TAU_PATH] (interpolated linearly; smooth path)


# ---------------------------------------------------------------- Biot-Savart kernel
def filament_velocity(r, z, a, h, gamma, delta=0.0):
    """Velocity (u_r, u_z) [V_j] induced at (r, z) by a circular vortex ring.

    Ring radius a, height h, circulation gamma (positive: self-induced motion toward +z),
    Lamb-Oseen core radius delta (0: the bare filament).  All in units of D_j and V_j; array
    arguments broadcast.  Lamb (1932) sec. 161 stream function; components as in Yoon & Heister
    (2004) Eq. 6-7:  m = k^2 = 4 a r / ((r + a)^2 + Z^2),  Z = z - h,
      u_z = gamma/(2 pi) / sqrt((r+a)^2+Z^2) [K(m) + (a^2 - r^2 - Z^2)/((r-a)^2+Z^2) E(m)]
      u_r = gamma/(2 pi) Z / (r sqrt((r+a)^2+Z^2)) [-K(m) + (a^2 + r^2 + Z^2)/((r-a)^2+Z^2) E(m)]
    times the Lamb-Oseen factor 1 - exp(-s^2/delta^2), s^2 = (r-a)^2 + Z^2 (Saffman 1992 Eq. 1.7.5).
    """
    r, z, a, h = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (r, z, a, h)))
    gamma = np.asarray(gamma, dtype=float)
    delta = np.asarray(delta, dtype=float)
    # u_r is odd in r and O(r) on the axis: evaluate at r >= r_eps and scale linearly below it
    r_eps = 1e-4 * a
    rr = np.maximum(r, r_eps)
    Z = z - h
    s2 = (rr - a) ** 2 + Z**2
    p2 = (rr + a) ** 2 + Z**2
    on_core = s2 <= 0.0  # on the filament itself: the cored velocity is 0 there (set below)
    m = np.where(on_core, 0.0, 4.0 * a * rr / np.where(p2 > 0.0, p2, 1.0))
    K, E = ellipk(m), ellipe(m)
    s2_safe = np.where(s2 > 0.0, s2, 1.0)
    c = gamma / (2.0 * math.pi) / np.sqrt(p2)
    uz = c * (K + (a**2 - rr**2 - Z**2) / s2_safe * E)
    ur = c * Z / rr * (-K + (a**2 + rr**2 + Z**2) / s2_safe * E)
    ur = np.where(r < r_eps, ur * r / r_eps, ur)
    with np.errstate(divide="ignore", invalid="ignore"):
        core = np.where(delta > 0.0, -np.expm1(-s2 / np.where(delta > 0.0, delta, 1.0) ** 2), 1.0)
    core = np.where(s2 > 0.0, core, 0.0)
    return ur * core, uz * core


def ring_and_image(r, z, a, h, gamma, delta):
    """(u_r, u_z) [V_j] of the descending ring (circulation -gamma at height h) and its ground
    image (+gamma at -h): method of images, zero normal velocity on z = 0 (Lamb 1932 sec. 161)."""
    ur1, uz1 = filament_velocity(r, z, a, h, -gamma, delta)
    ur2, uz2 = filament_velocity(r, z, a, -np.asarray(h), gamma, delta)
    return ur1 + ur2, uz1 + uz2


def self_induced_speed(a, gamma, delta):
    """Self-induced speed [V_j] of a ring with a Gaussian (Lamb-Oseen) core (Saffman 1970):
    U = gamma/(4 pi a) [ln(8 a / delta) - 0.558]."""
    return gamma / (4.0 * math.pi * a) * (np.log(8.0 * a / delta) - SAFFMAN_CORE)


def core_radius(a):
    """Core radius [D_j]: held at DELTA0 (closure: turbulent core growth taken to balance the
    thinning by stretching, which alone would keep delta^2 a constant, Saffman 1992 sec. 10.2)."""
    return np.full_like(np.asarray(a, dtype=float), DELTA0)


def circulation(tau):
    """Ring circulation [V_j D_j]: GAMMA exp(-tau/TAU_GAMMA) (closure: turbulent and wall-friction
    decay over one formation time; an inviscid ring near a wall expands without bound, Walker et
    al. 1987, which no real outflow does)."""
    return GAMMA * np.exp(-np.asarray(tau, dtype=float) / TAU_GAMMA)


def _rhs(tau, y):
    a, h = y
    d = DELTA0
    g = float(circulation(tau))
    # Saffman 1992 sec. 10.2: the ring moves with its self-induced velocity plus the velocity
    # its image (+Gamma at -h) induces at the core (r = a, z = h)
    ur_i, uz_i = filament_velocity(a, h, a, -h, g, d)
    dh = float(-self_induced_speed(a, g, d) + uz_i)
    if h <= d and dh < 0.0:
        dh = 0.0  # closure: the core rolls along the ground, its centre one core radius above it
    return [float(ur_i), dh]


@lru_cache(maxsize=1)
def trajectory() -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ring path (tau, a, h), each shape (_TAU_GRID,), on tau in [0, TAU_PATH] (dimensionless).

    Integrated once (DOP853, Hairer et al. 1993, at rtol 1e-13) and cached: it does not depend
    on the case, which is what makes the D_j/V_j time scaling exact.  The tolerance is far below
    any physical need on purpose: an adaptive integrator's step choices follow the last bits of its
    arithmetic (its BLAS combinations round differently on another CPU), so its result moves by
    about its own tolerance from one machine to another; at 1e-13 two CPUs' paths agree to ~1e-12
    (measured 8.7e-13; at RK45's 1e-10 they differed by 1.5e-9), well inside the golden results'
    1e-9 (tests/golden).  0.1 s, once per process.
    """
    from scipy.integrate import solve_ivp  # here: scipy.integrate costs start-up time elsewhere

    tau = np.linspace(0.0, TAU_PATH, _TAU_GRID)
    sol = solve_ivp(_rhs, (0.0, TAU_PATH), [A0, H0], t_eval=tau, rtol=1e-13, atol=1e-15, method="DOP853")
    if not sol.success:  # pragma: no cover - a fixed ODE; kept as a guard
        raise RuntimeError(f"ring trajectory failed: {sol.message}")
    return tau, sol.y[0].copy(), sol.y[1].copy()


def ring_state(tau) -> tuple[np.ndarray, np.ndarray]:
    """Ring radius a and height h [D_j] at dimensionless times tau (any shape; held beyond the grid)."""
    tg, ag, hg = trajectory()
    tau = np.asarray(tau, dtype=float)
    return np.interp(tau, tg, ag), np.interp(tau, tg, hg)


def _wood(eta):
    # Wood, Kwok, Motteram & Fletcher (2001): f_z = 1.55 eta^(1/6) [1 - erf(0.70 eta)], eta = z/delta
    eta = np.maximum(np.asarray(eta, dtype=float), 0.0)
    return 1.55 * eta ** (1.0 / 6.0) * (1.0 - erf(0.70 * eta))


_ETA_PEAK = 0.18360  # z_max / delta of the Wood profile (linecheck.core.wind.mean.ETA_PEAK, to 4 digits)


def wall_jet(rho, zeta):
    """Quasi-steady wall-jet radial speed [V_j] at rho = r/D_j, zeta = z/D_j:
    C_W f_r(rho) f_z(zeta), Holmes & Oliver (2000) Eq. 1-2 times Wood et al. (2001)."""
    rho = np.abs(np.asarray(rho, dtype=float))
    f_r = np.where(rho <= R_MAX, rho / R_MAX, np.exp(-(((rho - R_MAX) / R_DECAY) ** 2)))
    return C_W * f_r * _wood(np.asarray(zeta, dtype=float) * _ETA_PEAK / Z_MAX)


def jet_envelope(tau):
    """Strength of the trailing jet [-]: 1 while it blows (tau <= TAU_JET), then exp decay."""
    tau = np.asarray(tau, dtype=float)
    return np.where(tau <= TAU_JET, 1.0, np.exp(-np.maximum(tau - TAU_JET, 0.0) / TAU_DECAY))


def front_gate(rho, tau):
    """0 ahead of the ring, 1 behind it: 1/2 [1 + tanh((a(tau) - rho)/delta(tau))] (a smooth
    front one core radius wide; the wall jet fills in behind the primary vortex)."""
    a, _ = ring_state(tau)
    return 0.5 * (1.0 + np.tanh((a - np.asarray(rho, dtype=float)) / core_radius(a)))


def radial_speed(rho, zeta, tau):
    """Running-mean radial (outward) speed [V_j] at rho = r/D_j, height zeta = z/D_j, time
    tau = t V_j/D_j (broadcast shapes): ring + image (decaying circulation)
    plus the wall jet behind the front."""
    rho, tau = np.broadcast_arrays(np.asarray(rho, dtype=float), np.asarray(tau, dtype=float))
    a, h = ring_state(tau)
    env = jet_envelope(tau)
    ur, _ = ring_and_image(rho, zeta, a, h, circulation(tau), core_radius(a))
    return ur + env * front_gate(rho, tau) * wall_jet(rho, zeta)


@dataclass(frozen=True)
class RingJet:
    """Scale of the "ring-jet" field of one case.

    Attributes:
        jet_diameter: [m] D_j.
        jet_velocity: [m/s] V_j, sets the time scale D_j/V_j (the amplitude is set by V_ref at p).
    """

    jet_diameter: float
    jet_velocity: float

    @property
    def time_scale(self) -> float:
        """D_j / V_j [s]."""
        return self.jet_diameter / self.jet_velocity

    def shape(self, r, z, t):
        """Radial speed per unit V_j [-] at r [m], height z [m], time t [s] (broadcast shapes)."""
        return radial_speed(np.asarray(r, dtype=float) / self.jet_diameter, z / self.jet_diameter,
                            np.asarray(t, dtype=float) / self.time_scale)
