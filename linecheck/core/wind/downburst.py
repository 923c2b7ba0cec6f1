"""The downburst running-mean field model (paper section 2.1): profiles and :class:`DownburstField`.

The paper used the CFD field of Hangan & Kim 2007, which is not public, so linecheck ships an
analytic stationary impinging-jet model and lets users load their own table.  The horizontal
outflow is radial from the centre:

    V(r, z, t) = V_max * f_r(r) * f_z(z) * Pi(t)

    f_r(r) = r / r_max                          r <= r_max     (Holmes & Oliver 2000)
           = exp(-((r - r_max) / R_r)^2)        r >  r_max
    f_z(z) = 1.55 (z/delta)^(1/6) [1 - erf(0.70 z/delta)]         (Wood et al. 2001)
    Pi(t)  = t / T1                              t <= T1   (Chay, Albermani & Wilson 2006)
           = exp(-(t - T1) / c),  c = (T_f - T1) / ln 10   t > T1

with an optional storm translation added as a vector (Holmes & Oliver 2000).  The
"ring-jet" models (:mod:`linecheck.core.wind.ring`) replace the separable shape by a
travelling ring vortex; a user table (:mod:`linecheck.core.wind.field_table`) replaces
f_r(r) f_z(z) Pi(t) by a radial velocity on an (r/D_j, z/D_j, t) grid, interpolated linearly.

How a case places the field and scales V_max (V_ref at point p) is
:mod:`linecheck.core.wind.downburst_case`.  The analytic field's velocity has a compiled form
(kernel piece ``field``), checked against :meth:`DownburstField.velocity_numpy` at its first
use.  Nothing here prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from . import ring as ring_model
from .field_table import FieldTable, table_points, table_slice

# Wood et al. (2001) f_z and z/delta of its maximum: one source, shared with the ring-jet models
from .profiles import ETA_PEAK
from .profiles import wood as _wood

# ------------------------------------------------------------------------- defaults
R_MAX_OVER_DJ = 1.2  # r_max = 1.2 D_j: radius of peak outflow of Kim & Hangan (2007), = paper's Db_y R
RADIAL_DECAY_OVER_DJ = 0.5  # R_r = D_j / 2 (default; Holmes & Oliver 2000 decay length)
Z_MAX_OVER_DJ = 0.025  # z_max = 0.025 D_j (Wood et al. 2001 / Hangan & Kim 2007 jet scale)
# Lubbock-Reese rear-flank downdraft of 4 June 2002 (Holmes et al. 2008): running mean rose to its
# peak in about two minutes and the event was analysed as a ten-minute record.  See docs/wind.md.
T1_DEFAULT = 120.0  # [s]
T_F_DEFAULT = 600.0  # [s]


# ------------------------------------------------------------------------- profiles
def radial_profile(r: np.ndarray | float, r_max: float, radial_decay: float) -> np.ndarray:
    """f_r(r) [-] of Holmes & Oliver (2000): r/r_max inside r_max, Gaussian decay beyond.

    r [m] any shape; r_max, radial_decay [m].  Peak 1 at r = r_max.
    """
    r = np.abs(np.asarray(r, dtype=float))
    # Holmes & Oliver (2000) Eq. 1-2: linear growth, then exp(-((r - r_max)/R_r)^2)
    return np.where(r <= r_max, r / r_max, np.exp(-(((r - r_max) / radial_decay) ** 2)))


def wood_delta(z_max: float) -> float:
    """delta [m] of the Wood et al. (2001) profile from the height z_max [m] of peak outflow.

    Wood et al. write f_z in terms of delta, the height (above the peak) where the speed is
    half its maximum; f_z peaks at z/delta = ETA_PEAK ~ 0.1836, so delta = z_max / ETA_PEAK.
    """
    return z_max / ETA_PEAK


def vertical_profile(z: np.ndarray | float, delta: float) -> np.ndarray:
    """f_z(z) [-] = 1.55 (z/delta)^(1/6) [1 - erf(0.70 z/delta)] (Wood et al. 2001); z, delta [m].

    Its maximum is 1.00001 at z = ETA_PEAK delta; f_z(delta) = 0.4994 (half the peak).
    """
    return _wood(np.asarray(z, dtype=float) / delta)


def intensity(t: np.ndarray | float, t1: float, t_f: float) -> np.ndarray:
    """Pi(t) [-] of Chay, Albermani & Wilson (2006): linear rise to 1 at T1, exponential decay.

    t, t1, t_f [s]; Pi(T_f) = 0.1; Pi = 0 for t < 0.
    """
    t = np.asarray(t, dtype=float)
    c = (t_f - t1) / math.log(10.0)  # Chay et al. (2006): decay constant, Pi(T_f) = 0.1
    rise = np.clip(t / t1, 0.0, None)
    # Chay et al. (2006): t/T1 for t <= T1, exp(-(t - T1)/c) after
    return np.where(t <= t1, rise, np.exp(-np.maximum(t - t1, 0.0) / c))


# ------------------------------------------------------------------------- downburst field
@dataclass(frozen=True, eq=False)
class DownburstField:
    """A scaled downburst running-mean field along the line (paper Fig. 2 geometry).

    All positions in the line frame of :class:`LineSystem` (x along the line from tower 1,
    y transverse, wind toward +y at Theta = 0).

    Attributes:
        jet_diameter: [m] D_j.
        height: [m] conductor height z where the field is evaluated.
        centre: [m] (x, y) of the downburst centre at ``t_ref``.
        t_ref: [s] instant at which the centre is at (R, Theta) (analytic: T1; table: its peak).
        translation: [m/s] (v_x, v_y) storm translation velocity (Holmes & Oliver 2000).
        v_max: [m/s per unit of shape] scale factor V_max found from V_ref at p.
        point_p: [m] x of point p, the line point nearest ``centre``.
        window: [s] (t_start, t_end) analysed window.
        r_max, radial_decay, z_max, delta: [m] analytic profile parameters (NaN for a table).
        t1, t_f: [s] intensity-function times (NaN for a table).
        table: the user :class:`FieldTable`, or None for the analytic model.
        point_xy: [m] plan position (x, y) of p in the global frame (section form: the foot of
            the perpendicular from the centre on the tower of interest's frame x axis); None for
            the equal-span form, where p is (point_p, 0).

    Section form: ``centre``, ``translation`` and ``point_xy`` are in the global
    plan frame; :meth:`velocity_at` evaluates the field at any plan point and height.
    ``height`` is then the reference height at which the running mean at p peaks at V_ref.
    """

    jet_diameter: float
    height: float
    centre: tuple[float, float]
    t_ref: float
    translation: tuple[float, float]
    v_max: float
    point_p: float
    window: tuple[float, float]
    r_max: float = math.nan
    radial_decay: float = math.nan
    z_max: float = math.nan
    delta: float = math.nan
    t1: float = math.nan
    t_f: float = math.nan
    table: FieldTable | None = None
    ring: ring_model.RingJet | None = None  # models "ring-jet", "ring-jet-inviscid"
    point_xy: tuple[float, float] | None = None  # [m] plan position of p (section form; None: (point_p, 0))

    # -- model pieces
    def centre_at(self, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Centre position [m] at times t [s] (any shape): c(t_ref) + v_T (t - t_ref)."""
        t = np.asarray(t, dtype=float)
        dt = t - self.t_ref
        return self.centre[0] + self.translation[0] * dt, self.centre[1] + self.translation[1] * dt

    def shape(self, r: np.ndarray, t: np.ndarray, z: np.ndarray | None = None) -> np.ndarray:
        """Radial speed per unit V_max [-] at radius r [m], time t [s] and height above ground
        z [m] (broadcast shapes; None: ``height`` everywhere)."""
        if z is not None:
            return self._shape_z(r, t, z)
        t0 = np.asarray(t, dtype=float)
        r, t = np.broadcast_arrays(np.asarray(r, dtype=float), t0)
        if self.ring is not None:
            # ring-jet models: non-separable ring vortex + image + wall jet, per unit V_j
            return self.ring.shape(r, self.height, t)
        if self.table is None:
            # Holmes & Oliver (2000): V = V_max f_r(r) f_z(z) Pi(t); Pi on the given instants (e.g. (n_t, 1)), not on
            # the broadcast grid: the same values, n_x times fewer exponentials
            return (radial_profile(r, self.r_max, self.radial_decay)
                    * float(vertical_profile(self.height, self.delta)) * intensity(t0, self.t1, self.t_f))
        return table_slice(self.table, self.height / self.jet_diameter)(r / self.jet_diameter, t, self.table.path)

    def _shape_z(self, r: np.ndarray, t: np.ndarray, z: np.ndarray) -> np.ndarray:
        """:meth:`shape` with a height per point (section form: each node's own height)."""
        r, t, z = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(t, dtype=float),
                                      np.asarray(z, dtype=float))
        if self.ring is not None:
            # the ring-jet field is a function of (r, z, t) (not separable)
            return self.ring.shape(r, z, t)
        if self.table is None:
            # Holmes & Oliver (2000): V = V_max f_r(r) f_z(z) Pi(t), f_z of Wood et al. (2001) at each point's height
            return (radial_profile(r, self.r_max, self.radial_decay) * vertical_profile(z, self.delta)
                    * intensity(t, self.t1, self.t_f))
        return table_points(self.table, r / self.jet_diameter, z / self.jet_diameter, t)

    def p_xy(self) -> tuple[float, float]:
        """Plan position of p [m] in the frame of ``centre``."""
        return self.point_xy if self.point_xy is not None else (self.point_p, 0.0)

    def velocity_at(self, x: np.ndarray, y: np.ndarray, t: np.ndarray,
                    z: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Running-mean horizontal velocity (v_x, v_y) [m/s] at plan points (x, y) [m] and heights
        above ground z [m] (None: ``height``), in the frame of ``centre`` (global for sections).

        x, y, z shape (n_x,), t shape (n_t,) -> two arrays (n_t, n_x).  Radial outflow from the
        moving centre plus the translation velocity (vector sum, Holmes & Oliver 2000).
        """
        x = np.asarray(x, dtype=float)[None, :]
        y = np.asarray(y, dtype=float)[None, :]
        t = np.asarray(t, dtype=float)[:, None]
        cx, cy = self.centre_at(t)
        dx, dy = x - cx, y - cy
        r = np.hypot(dx, dy)
        zz = None if z is None else np.asarray(z, dtype=float)[None, :]
        speed = self.v_max * self.shape(r, t, zz)
        safe = np.where(r > 0.0, r, 1.0)
        # Holmes & Oliver (2000): vector sum of the radial outflow and the translation velocity
        vx = np.where(r > 0.0, speed * dx / safe, 0.0) + self.translation[0]
        vy = np.where(r > 0.0, speed * dy / safe, 0.0) + self.translation[1]
        return vx, vy

    def velocity(self, x: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Running-mean velocity (v_x, v_y) [m/s] at line points x [m] (y = 0, z = height).

        x shape (n_x,), t shape (n_t,) -> two arrays of shape (n_t, n_x).  Radial outflow
        plus the translation velocity (vector sum, Holmes & Oliver 2000).
        """
        if self.ring is None and self.table is None:  # the analytic field compiled (kernel piece ``field``)
            from .. import kernel

            tt = np.asarray(t, dtype=float).ravel()
            fast = kernel.field_velocity(self, np.asarray(x, dtype=float).ravel(), tt, *_field_factors(self, tt))
            if fast is not None:
                return fast
        return self.velocity_numpy(x, t)

    def velocity_numpy(self, x: np.ndarray, t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`velocity` in numpy (the compiled form agrees within the kernel's tolerance)."""
        x = np.asarray(x, dtype=float)[None, :]
        t = np.asarray(t, dtype=float)[:, None]
        cx, cy = self.centre_at(t)
        dx, dy = x - cx, 0.0 - cy
        r = np.hypot(dx, dy)
        speed = self.v_max * self.shape(r, t)
        safe = np.where(r > 0.0, r, 1.0)
        # Holmes & Oliver (2000): vector sum of the radial outflow and the translation velocity
        vx = np.where(r > 0.0, speed * dx / safe, 0.0) + self.translation[0]
        vy = np.where(r > 0.0, speed * dy / safe, 0.0) + self.translation[1]
        return vx, vy

    def vertical_velocity(self, x: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Table vertical velocity [m/s] (same scaling as the radial one), shape (n_t, n_x);
        zeros for the analytic model or a table without ``v_vertical``.  Not used by the
        loads (paper section 3, Step 1: the vertical component is neglected)."""
        x = np.asarray(x, dtype=float)[None, :]
        t = np.asarray(t, dtype=float)[:, None]
        if self.table is None or self.table.vertical is None:
            return np.zeros(np.broadcast_shapes(x.shape, t.shape))
        cx, cy = self.centre_at(t)
        r = np.hypot(x - cx, cy)
        interp = table_slice(self.table, self.height / self.jet_diameter, vertical=True)
        return self.v_max * interp(r / self.jet_diameter, np.broadcast_to(t, r.shape), self.table.path)


# ---- the compiled kernel's piece ``field`` (linecheck.core.kernel): its load check

def _field_check(fns) -> float:
    """The compiled analytic downburst field against :meth:`DownburstField.velocity_numpy`
    (points inside and outside r_max, at the centre, before and after the peak of Pi(t)); the
    largest relative difference."""
    from .. import kernel

    field = DownburstField(jet_diameter=600.0, height=15.0, centre=(450.0, -700.0), t_ref=300.0,
                           translation=(3.0, 8.0), v_max=41.3, point_p=450.0, window=(0.0, 600.0),
                           r_max=780.0, radial_decay=430.0, z_max=50.0, delta=272.0, t1=300.0, t_f=1200.0)
    x = np.concatenate([np.linspace(0.0, 1800.0, 37), [712.5]])
    t = np.concatenate([np.linspace(0.0, 900.0, 41), [387.5]])  # the centre crosses the line at x = 712.5
    got = kernel.field_compiled(fns, field, x, t, *_field_factors(field, t))
    return kernel.worst_difference(zip(field.velocity_numpy(x, t), got))


def _field_factors(field: DownburstField, t: np.ndarray) -> tuple[float, np.ndarray]:
    """The compiled field's height factor f_z [-] (Wood et al. 2001) and Pi(t) [-] (Chay et al.
    2006) at the instants t [s] (n_t,)."""
    return float(vertical_profile(field.height, field.delta)), intensity(t, field.t1, field.t_f)


def _register_kernel_check() -> None:
    from .. import kernel

    kernel.register_check("field", _field_check)


_register_kernel_check()
