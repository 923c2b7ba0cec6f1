"""Travelling-outflow downburst models: "ring-jet" (ring kinematics, wall-layer outflow) and
"ring-jet-inviscid" (the ring vortex + image field itself, the former "ring-jet").

Both are non-separable, stationary-storm running-mean fields built from published parts, in units
of the jet diameter D_j [m] and the downdraft speed V_j [m/s]: lengths rho = r/D_j, zeta = z/D_j,
velocities u/V_j, time tau = t V_j/D_j.  Because every closure constant below is dimensionless,
a field obeys u(r, z, t; D_j, V_j) = V_j s(r/D_j, z/D_j, t V_j/D_j) exactly: doubling D_j with V_j
fixed doubles every event time, doubling V_j halves them (tested).

Common parts (each cited where used):

1. Primary ring vortex of circulation -Gamma (sense: descending, outflow beneath it), radius
   a(tau), height h(tau), and its ground image (+Gamma at -h) so that the vertical velocity is
   zero on the ground z = 0 (method of images, Lamb 1932 sec. 161; Saffman 1992 ch. 10).
   Velocity of a circular vortex filament from the Stokes stream function with complete
   elliptic integrals K, E (Lamb 1932 sec. 161; explicit components e.g. Yoon & Heister 2004,
   Int. J. Numer. Meth. Fluids 44, Eq. 6-7).
2. Core: Lamb-Oseen desingularisation of the filament, u -> u (1 - exp(-s^2/delta^2)), s the
   distance to the core centre line (Lamb-Oseen vortex, Saffman 1992 Eq. 1.7.5 -- the local 2-D
   limit of the ring), core radius delta.  Self-induced speed of a ring with a Gaussian core
   (Saffman 1970, Stud. Appl. Math. 49): U = Gamma/(4 pi a) [ln(8 a/delta) - 0.558].  The core
   radius is held at delta0 (:func:`core_radius`).
3. Path: the ring moves with its self-induced velocity plus the velocity its image induces
   at its core (vortex dynamics; Saffman 1992 sec. 10.2; Walker et al. 1987, JFM 181):
   da/dtau = u_r,img(a, h),  dh/dtau = -U(a) + u_z,img(a, h);  the core rolls along the ground
   (h >= delta0).
4. Circulation from the slug model at the formation number (Gharib, Rambod & Shariff 1998, JFM
   360: a starting jet puts Gamma = V_j L / 2 into its ring until L/D ~ 4, the rest stays in a
   trailing jet): Gamma = 2 V_j D_j at formation, decaying as exp(-tau/TAU_GAMMA).
5. Behind the ring (r < a(tau)) the trailing jet's wall jet, in its quasi-steady state, is the
   Holmes & Oliver (2000) radial profile (the same f_r as the "holmes-oliver" model), switched on
   by the passage of the front and held while the jet blows (duration TAU_JET), then decaying
   exponentially (TAU_DECAY).

"ring-jet" (:data:`RING_JET`): the ring's kinematics give the timing and the radius; the outflow
is a wall jet whose local maximum U_m(rho, tau) is the ring + image's velocity along the ground
(the inviscid slip velocity, the edge velocity of the wall layer), scaled by K, plus the trailing
wall jet, and whose vertical shape is the Wood et al. (2001) profile with its maximum at
z_max = 0.025 D_j (wall-jet similarity: one shape scaled by the local maximum, Glauert 1956):

    u(rho, zeta, tau) = U_m(rho, tau) f_z(zeta),
    U_m = K u_r,ring+image(rho, 0, tau) + C_W J(tau) G(rho, tau) f_r(rho).

K normalises the ring so that the downdraft it induces through its centre at formation is V_j
(:func:`downdraft_scale`): V_j is the downdraft speed, as the docs say.  Core delta0 = 0.2 D_j
(core/ring radius 0.4, Gharib et al. 1998 range 0.2-0.4).

"ring-jet-inviscid" (:data:`RING_JET_INVISCID`, the model "ring-jet" was until the wall layer was
added): the ring + image velocity at the point itself, unscaled, plus the wall jet C_W J G f_r
f_z(zeta); delta0 = 0.1 D_j.  It has no near-ground decay (its outflow grows down to ~0.01 D_j
and is flat below) and peaks at 2.5-3.1 V_j; kept so that results made with it can be reproduced.

Closure constants (modelling choices, sensitivity and the published ranges each descriptor of the
field falls in: docs/wind.md; none fitted to the seed paper): ring formation radius A0 = 0.5 (jet
radius), height H0 = 1.0, circulation decay TAU_GAMMA = 4 (one formation time), wall-jet amplitude
C_W = 1.0 (peak steady wall-jet speed ~ V_j in impinging-jet experiments), jet duration
TAU_JET = 5, decay TAU_DECAY = 2.5.  Nothing here prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.special import ellipe, ellipk

from .profiles import ETA_PEAK, wood


# ---------------------------------------------------------------- closure constants (dimensionless)
@dataclass(frozen=True)
class Closure:
    """Dimensionless closure constants of one ring-jet model (lengths / D_j, speeds / V_j,
    times / (D_j/V_j)).

    Attributes:
        name: model name as in ``[wind.downburst] model``.
        delta0: Lamb-Oseen core radius of the ring (held; the ring rolls at h >= delta0).
        wall_layer: True: the outflow is U_m(rho, tau) f_z(zeta) (the wall-layer form of "ring-jet");
            False: the ring + image velocity at the point itself ("ring-jet-inviscid").
        a0, h0: ring radius and height at formation.
        gamma0, tau_gamma: circulation at formation and its decay time.
        c_w, r_max, r_decay, z_max: trailing wall jet: peak speed, radius of peak, radial decay
            length (Holmes & Oliver 2000) and height of peak (Wood et al. 2001).
        tau_jet, tau_decay: duration of the trailing jet and its decay time after it stops.
    """

    name: str
    delta0: float
    wall_layer: bool
    a0: float = 0.5  # the jet edge
    h0: float = 1.0  # the ring forms about one diameter above ground
    gamma0: float = 2.0  # slug model at formation number 4 (Gharib et al. 1998)
    tau_gamma: float = 4.0  # one formation time L/D = 4 (Gharib et al. 1998)
    c_w: float = 1.0  # steady wall-jet peak ~ V_j (impinging-jet experiments)
    r_max: float = 1.2  # same default as "holmes-oliver" (Kim & Hangan 2007)
    r_decay: float = 0.5  # same default as "holmes-oliver"
    z_max: float = 0.025  # same default as "holmes-oliver" (Wood et al. 2001)
    tau_jet: float = 5.0  # ~5 min for D_j = 1 km, V_j = 15 m/s
    tau_decay: float = 2.5

    @property
    def tau_end(self) -> float:
        """Default analysed event length / (D_j/V_j): until the jet envelope falls to 0.1 (as Chay's T_f)."""
        return self.tau_jet + self.tau_decay * math.log(10.0)

    @property
    def tau_path(self) -> float:
        """The path is integrated this far (a longer ``analysis.duration`` holds the last state)."""
        return 4.0 * self.tau_end


RING_JET = Closure("ring-jet", delta0=0.2, wall_layer=True)
RING_JET_INVISCID = Closure("ring-jet-inviscid", delta0=0.1, wall_layer=False)
#: the travelling models by name (linecheck.core.case.RING_MODELS lists the same names)
CLOSURES = {c.name: c for c in (RING_JET, RING_JET_INVISCID)}
MODELS = tuple(CLOSURES)

# module-level names of the shared constants (as before the two models existed)
A0 = RING_JET.a0
H0 = RING_JET.h0
GAMMA = RING_JET.gamma0
SAFFMAN_CORE = 0.558  # Saffman (1970): Gaussian-core constant in the self-induced speed
C_W = RING_JET.c_w
R_MAX = RING_JET.r_max
R_DECAY = RING_JET.r_decay
Z_MAX = RING_JET.z_max
TAU_GAMMA = RING_JET.tau_gamma
TAU_JET = RING_JET.tau_jet
TAU_DECAY = RING_JET.tau_decay
TAU_END = RING_JET.tau_end
TAU_PATH = RING_JET.tau_path
DELTA0 = RING_JET.delta0  # "ring-jet" core radius / D_j (core/ring radius 0.4, Gharib et al. 1998 0.2-0.4)
DELTA0_INVISCID = RING_JET_INVISCID.delta0  # "ring-jet-inviscid" (core/ring radius 0.2)
_TAU_GRID = 16001  # trajectory samples over [0, TAU_PATH] (interpolated linearly; smooth path)


def closure(model: str | Closure = "ring-jet") -> Closure:
    """The closure of a model name (a :class:`Closure` passes through)."""
    if isinstance(model, Closure):
        return model
    try:
        return CLOSURES[model]
    except KeyError:
        raise ValueError(f'unknown ring model "{model}": expected one of {", ".join(MODELS)}') from None


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


# ---------------------------------------------------------------- ring kinematics
def core_radius(a, model: str | Closure = "ring-jet"):
    """Core radius [D_j]: held at the model's delta0, whatever the ring radius a.

    Closure: stretching alone would thin the core as the ring grows (an inviscid ring conserves
    its core volume, delta^2 a = const, Saffman 1992 sec. 10.2); the turbulent growth of the core
    is taken to balance it, so delta stays at its formation value."""
    return np.full_like(np.asarray(a, dtype=float), closure(model).delta0)


def circulation(tau, model: str | Closure = "ring-jet"):
    """Ring circulation [V_j D_j]: gamma0 exp(-tau/tau_gamma) (closure: turbulent and wall-friction
    decay over one formation time; an inviscid ring near a wall expands without bound, Walker et
    al. 1987, which no real outflow does)."""
    c = closure(model)
    return c.gamma0 * np.exp(-np.asarray(tau, dtype=float) / c.tau_gamma)


def _rhs(tau, y, c: Closure):
    a, h = y
    d = c.delta0
    g = float(circulation(tau, c))
    # Saffman 1992 sec. 10.2: the ring moves with its self-induced velocity plus the velocity
    # its image (+Gamma at -h) induces at the core (r = a, z = h)
    ur_i, uz_i = filament_velocity(a, h, a, -h, g, d)
    dh = float(-self_induced_speed(a, g, d) + uz_i)
    if h <= d and dh < 0.0:
        dh = 0.0  # closure: the core rolls along the ground, its centre one core radius above it
    return [float(ur_i), dh]


def trajectory(model: str | Closure = "ring-jet") -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Ring path (tau, a, h), each shape (_TAU_GRID,), on tau in [0, tau_path] (dimensionless).

    Integrated once per model (DOP853, Hairer et al. 1993, at rtol 1e-13) and cached: it does not
    depend on the case, which is what makes the D_j/V_j time scaling exact.  The tolerance is far
    below any physical need on purpose: an adaptive integrator's step choices follow the last bits
    of its arithmetic (its BLAS combinations round differently on another CPU), so its result moves
    by about its own tolerance from one machine to another; at 1e-13 two CPUs' paths agree to
    ~1e-12 (measured 8.7e-13; at RK45's 1e-10 they differed by 1.5e-9), well inside the golden
    results' 1e-9 (tests/golden).  0.1 s, once per process and model.
    """
    return _trajectory(closure(model))


@lru_cache(maxsize=8)
def _trajectory(c: Closure) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    from scipy.integrate import solve_ivp  # here: scipy.integrate costs start-up time elsewhere

    tau = np.linspace(0.0, c.tau_path, _TAU_GRID)
    sol = solve_ivp(_rhs, (0.0, c.tau_path), [c.a0, c.h0], t_eval=tau, rtol=1e-13, atol=1e-15, method="DOP853",
                    args=(c,))
    if not sol.success:  # pragma: no cover - a fixed ODE; kept as a guard
        raise RuntimeError(f"ring trajectory failed: {sol.message}")
    return tau, sol.y[0].copy(), sol.y[1].copy()


def ring_state(tau, model: str | Closure = "ring-jet") -> tuple[np.ndarray, np.ndarray]:
    """Ring radius a and height h [D_j] at dimensionless times tau (any shape; held beyond the grid)."""
    tg, ag, hg = _trajectory(closure(model))
    tau = np.asarray(tau, dtype=float)
    return np.interp(tau, tg, ag), np.interp(tau, tg, hg)


def touchdown(model: str | Closure = "ring-jet") -> float:
    """tau at which the ring's core first reaches the ground (h = delta0, where it starts rolling)."""
    c = closure(model)
    tg, _, hg = _trajectory(c)
    return float(tg[int(np.argmax(hg <= c.delta0 * (1.0 + 1e-9)))])


@lru_cache(maxsize=4)
def downdraft_scale(model: str | Closure = "ring-jet") -> float:
    """K [-]: 1 / the downdraft speed the ring + image induce through the ring's centre at formation.

    The "ring-jet" outflow is K times the ring's velocity along the ground: the ring's own
    downdraft at formation is then exactly V_j, the downdraft speed V_j stands for.  Unscaled,
    the slug-model ring (Gamma = 2 V_j D_j, a = D_j/2) induces Gamma/(2a) = 2 V_j at its centre
    (the image, 2 h0 below, takes 1.4 % off): K = 0.508."""
    c = closure(model)

    def on_axis(Z: float) -> float:
        # a Lamb-Oseen-cored loop on its axis, a distance Z from its plane (Biot-Savart; Saffman 1992
        # ch. 10 for the filament): Gamma a^2 / (2 (a^2 + Z^2)^(3/2)) (1 - exp(-(a^2 + Z^2)/delta^2))
        s2 = c.a0**2 + Z**2
        return c.gamma0 * c.a0**2 / (2.0 * s2**1.5) * -math.expm1(-s2 / c.delta0**2)

    return 1.0 / (on_axis(0.0) - on_axis(2.0 * c.h0))  # the ring's downdraft minus its image's upflow


# ---------------------------------------------------------------- outflow
def radial_profile(rho, model: str | Closure = "ring-jet"):
    """f_r(rho) [-] of Holmes & Oliver (2000) Eq. 1-2 with the model's r_max and decay length."""
    c = closure(model)
    rho = np.abs(np.asarray(rho, dtype=float))
    return np.where(rho <= c.r_max, rho / c.r_max, np.exp(-(((rho - c.r_max) / c.r_decay) ** 2)))


def vertical_profile(zeta, model: str | Closure = "ring-jet"):
    """f_z(zeta) [-] of Wood et al. (2001), its maximum (1.00001) at zeta = z_max."""
    c = closure(model)
    return wood(np.asarray(zeta, dtype=float) * ETA_PEAK / c.z_max)  # Wood et al. (2001) f_z


def wall_jet(rho, zeta, model: str | Closure = "ring-jet"):
    """Quasi-steady wall-jet radial speed [V_j] at rho = r/D_j, zeta = z/D_j:
    C_W f_r(rho) f_z(zeta), Holmes & Oliver (2000) Eq. 1-2 times Wood et al. (2001)."""
    return closure(model).c_w * radial_profile(rho, model) * vertical_profile(zeta, model)


def jet_envelope(tau, model: str | Closure = "ring-jet"):
    """Strength of the trailing jet [-]: 1 while it blows (tau <= tau_jet), then exp decay."""
    c = closure(model)
    tau = np.asarray(tau, dtype=float)
    return np.where(tau <= c.tau_jet, 1.0, np.exp(-np.maximum(tau - c.tau_jet, 0.0) / c.tau_decay))


def front_gate(rho, tau, model: str | Closure = "ring-jet"):
    """0 ahead of the ring, 1 behind it: 1/2 [1 + tanh((a(tau) - rho)/delta0)] (a smooth front one
    core radius wide; the wall jet fills in behind the primary vortex)."""
    a, _ = ring_state(tau, model)
    return 0.5 * (1.0 + np.tanh((a - np.asarray(rho, dtype=float)) / core_radius(a, model)))


def surface_speed(rho, tau, model: str | Closure = "ring-jet"):
    """U_m [V_j]: the local maximum of the "ring-jet" wall-layer outflow at rho, tau (broadcast):
    K u_r,ring+image(rho, 0, tau) + C_W J(tau) G(rho, tau) f_r(rho).

    The ring + image velocity on the ground is the inviscid slip velocity, the velocity at the edge
    of the wall layer; scaled by K (:func:`downdraft_scale`)."""
    c = closure(model)
    rho, tau = np.broadcast_arrays(np.asarray(rho, dtype=float), np.asarray(tau, dtype=float))
    a, h = ring_state(tau, c)
    ur, _ = ring_and_image(rho, 0.0, a, h, circulation(tau, c), core_radius(a, c))
    return downdraft_scale(c) * ur + c.c_w * jet_envelope(tau, c) * front_gate(rho, tau, c) * radial_profile(rho, c)


def radial_speed(rho, zeta, tau, model: str | Closure = "ring-jet"):
    """Running-mean radial (outward) speed [V_j] at rho = r/D_j, height zeta = z/D_j, time
    tau = t V_j/D_j (broadcast shapes).

    "ring-jet": U_m(rho, tau) f_z(zeta) (:func:`surface_speed`, Wood et al. 2001 profile).
    "ring-jet-inviscid": ring + image at (rho, zeta) plus the wall jet behind the front."""
    c = closure(model)
    if c.wall_layer:
        return surface_speed(rho, tau, c) * vertical_profile(zeta, c)
    rho, tau = np.broadcast_arrays(np.asarray(rho, dtype=float), np.asarray(tau, dtype=float))
    a, h = ring_state(tau, c)
    env = jet_envelope(tau, c)
    ur, _ = ring_and_image(rho, zeta, a, h, circulation(tau, c), core_radius(a, c))
    return ur + env * front_gate(rho, tau, c) * wall_jet(rho, zeta, c)


def peak_over_event(rho: float, zeta: float, model: str | Closure = "ring-jet") -> tuple[float, float]:
    """(max over the event of |radial_speed(rho, zeta, tau)| [V_j], the tau of it): a grid of 6001
    instants over [0, tau_end], then a bounded refinement (xatol 1e-10) around the best one."""
    from scipy.optimize import minimize_scalar

    c = closure(model)
    tau = np.linspace(0.0, c.tau_end, 6001)
    s = np.abs(radial_speed(rho, zeta, tau, c))
    k = int(np.argmax(s))
    peak, at = float(s[k]), float(tau[k])
    lo, hi = tau[max(k - 1, 0)], tau[min(k + 1, tau.size - 1)]
    res = minimize_scalar(lambda tt: -abs(float(radial_speed(rho, zeta, tt, c))),
                          bounds=(lo, hi), method="bounded", options={"xatol": 1e-10})
    if float(-res.fun) > peak:
        peak, at = float(-res.fun), float(res.x)
    return peak, at


# ---------------------------------------------------------------- what the field looks like
@dataclass(frozen=True)
class EventDescriptors:
    """The published descriptors of a downburst outflow, read off one model's field (D_j, V_j units).

    Attributes:
        model: the model name.
        rho_p: [-] the fixed point the time descriptors are read at (r/D_j).
        z_peak: [-] height z/D_j of the maximum of the peak-over-time profile at rho_p.
        decay_5m: [-] peak speed at z = 0.005 D_j (5 m for D_j = 1 km) over that at z_peak.
        peak_outflow: [V_j] the largest outflow anywhere over the event at the height z_peak.
        rho_peak: [-] r/D_j of that largest outflow.
        tau_peak_anywhere: [-] its time.
        tau_touchdown: [-] time the ring's core reaches the ground (:func:`touchdown`).
        tau_peak_p: [-] time of the peak at rho_p (height z_peak).
        w90_p, w95_p: [-] time the speed at rho_p stays above 90 % / 95 % of its peak (first to last
            crossing).
    """

    model: str
    rho_p: float
    z_peak: float
    decay_5m: float
    peak_outflow: float
    rho_peak: float
    tau_peak_anywhere: float
    tau_touchdown: float
    tau_peak_p: float
    w90_p: float
    w95_p: float


@lru_cache(maxsize=8)
def event_descriptors(model: str | Closure = "ring-jet", rho_p: float = 1.2) -> EventDescriptors:
    """:class:`EventDescriptors` of a model (grids: heights 0.001-0.3 D_j, radii 0.05-3 D_j,
    4001 instants over the default window; ~1 s).  docs/wind.md quotes these numbers."""
    c = closure(model)
    tau = np.linspace(0.0, c.tau_end, 4001)
    zeta = np.geomspace(1e-3, 0.3, 241)
    prof = np.abs(radial_speed(rho_p, zeta[:, None], tau[None, :], c)).max(axis=1)
    z_peak = float(zeta[int(np.argmax(prof))])
    if c.wall_layer:
        z_peak = c.z_max  # separable in height: the grid only confirms it
    low = float(np.abs(radial_speed(rho_p, 0.005, tau, c)).max())
    at_p = np.abs(radial_speed(rho_p, z_peak, tau, c))
    rho = np.linspace(0.05, 3.0, 296)
    field = np.abs(radial_speed(rho[:, None], z_peak, tau[None, :], c))
    i, j = np.unravel_index(int(np.argmax(field)), field.shape)
    k = int(np.argmax(at_p))

    def window(frac: float) -> float:
        above = tau[at_p >= frac * at_p[k]]
        return float(above[-1] - above[0])

    return EventDescriptors(c.name, rho_p, z_peak, low / float(at_p[k]), float(field[i, j]), float(rho[i]),
                            float(tau[j]), touchdown(c), float(tau[k]), window(0.9), window(0.95))


@dataclass(frozen=True)
class RingJet:
    """Scale of a travelling ("ring-jet" family) field of one case.

    Attributes:
        jet_diameter: [m] D_j.
        jet_velocity: [m/s] V_j, sets the time scale D_j/V_j (the amplitude is set by V_ref at p).
        model: "ring-jet" or "ring-jet-inviscid".
    """

    jet_diameter: float
    jet_velocity: float
    model: str = "ring-jet"

    @property
    def time_scale(self) -> float:
        """D_j / V_j [s]."""
        return self.jet_diameter / self.jet_velocity

    def shape(self, r, z, t):
        """Radial speed per unit V_j [-] at r [m], height z [m], time t [s] (broadcast shapes)."""
        return radial_speed(np.asarray(r, dtype=float) / self.jet_diameter, z / self.jet_diameter,
                            np.asarray(t, dtype=float) / self.time_scale, self.model)
