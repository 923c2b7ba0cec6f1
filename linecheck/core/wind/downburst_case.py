"""A case's downburst field: the analysed window, the placement of paper Fig. 2 and V_max.

:func:`downburst_field` builds the :class:`~linecheck.core.wind.downburst.DownburstField` of a
case: the centre at distance R and angle Theta from the tower of interest (paper Fig. 2; on a
section in the tower's own frame), point p the line point nearest the centre, the storm
translation, the model's unscaled field (analytic, ring-jet or user table), then V_max such
that the maximum over the analysed window of the running-mean speed at p, at the reference
height, equals V_ref (paper section 2.1).  :func:`event_window` is the analysed window of any
case and :func:`reference_height` the height of V_ref.  See ``docs/wind.md`` for the defaults
and why.  Nothing here prints.
"""

from __future__ import annotations

import math
from functools import lru_cache
from pathlib import Path

import numpy as np

from ..case import Case, Downburst
from ..errors import CaseError
from ..system import LineSystem
from . import ring as ring_model
from .downburst import (
    R_MAX_OVER_DJ,
    RADIAL_DECAY_OVER_DJ,
    T1_DEFAULT,
    T_F_DEFAULT,
    Z_MAX_OVER_DJ,
    DownburstField,
    wood_delta,
)
from .field_table import FieldTable, field_error, load_field_table, table_slice

SYNOPTIC_DURATION_DEFAULT = 600.0  # [s] ten-minute record (standard averaging period)


def reference_height(case: Case) -> float:
    """z_ref [m]: ``wind.reference_height``, else the mean clamp height above ground (``line.height``;
    the equal-span form's conductor height).  Synoptic: the height of V_ref in the power law;
    downburst: the height at which the running mean at p peaks at V_ref."""
    z = case.wind.reference_height
    return float(case.line.height if z is None else z)


def _downburst(case: Case) -> Downburst:
    """The case's [wind.downburst] table; a :class:`CaseError` for a synoptic case."""
    if case.wind.type != "downburst" or case.wind.downburst is None:
        raise CaseError("is not a downburst case (no [wind.downburst] table)", key="wind.type")
    return case.wind.downburst


def _table_of(case: Case) -> FieldTable | None:
    """The case's user field table (model "table"), else None; t1/t_f with a table are refused."""
    db = _downburst(case)
    if db.model_name != "table" or db.field is None:
        return None
    path = db.field_path if db.field_path is not None else Path(db.field)
    if db.t1 is not None or db.t_f is not None:
        raise CaseError("t1/t_f shape the analytic model only: with a field file the table's t axis is the event "
                        "time history; remove t1 and t_f", file=str(case.source) if case.source else None,
                        key="wind.downburst.field")
    return load_field_table(path)


def event_window(case: Case) -> tuple[float, float]:
    """Analysed time window (t_start, t_end) [s].

    Downburst, analytic model: (0, T_f) by default, (0, analysis.duration) when set.
    Downburst with a field table: the table's t range by default, (t_0, t_0 + duration) when set.
    Synoptic: (0, analysis.duration), default 600 s.
    """
    dur = case.analysis.duration
    if case.wind.type == "synoptic":
        return 0.0, float(dur if dur is not None else SYNOPTIC_DURATION_DEFAULT)
    if _downburst(case).model_name in ring_model.MODELS:
        tau_end = ring_model.closure(_downburst(case).model_name).tau_end
        return 0.0, float(dur if dur is not None else tau_end * ring_scale(case).time_scale)
    table = _table_of(case)
    if table is None:
        t_f = _downburst(case).t_f if _downburst(case).t_f is not None else T_F_DEFAULT
        return 0.0, float(dur if dur is not None else t_f)
    t0, t_last = float(table.t[0]), float(table.t[-1])
    if dur is None:
        return t0, t_last
    if t0 + dur > t_last * (1 + 1e-12) + 1e-12:
        raise CaseError(f"value {dur!r} is too long for field file {table.path}: its t axis covers {t0:g} to "
                        f"{t_last:g} s (expected duration <= {t_last - t0:g})",
                        file=str(case.source) if case.source else None, key="analysis.duration")
    return t0, t0 + float(dur)


@lru_cache(maxsize=64)
def ring_scale(case: Case) -> ring_model.RingJet:
    """D_j and V_j of a "ring-jet" / "ring-jet-inviscid" case: ``jet_velocity``, else V_ref / (peak
    over the event of the stationary dimensionless outflow at p, at the reference height), i.e.
    V_j = V_max."""
    db = _downburst(case)
    dj = db.jet_diameter
    model = db.model_name
    if db.jet_velocity is not None:
        return ring_model.RingJet(dj, float(db.jet_velocity), model)
    rho_p = abs(db.distance * math.cos(math.radians(db.angle))) / dj
    if abs(math.cos(math.radians(db.angle))) < 1e-12:
        rho_p = 0.0
    z_ref = reference_height(case)  # the height of V_ref at p (equal-span form: the conductor height)
    peak = ring_model.peak_over_event(rho_p, z_ref / dj, model)[0]
    if not peak > 0.0:
        raise CaseError("the outflow at point p is zero (the centre lies on the line): change distance/angle",
                        file=str(case.source) if case.source else None, key="wind.downburst")
    return ring_model.RingJet(dj, case.wind.v_ref / peak, model)


def _max_speed_at_p(field: DownburstField, v_max: float, times: np.ndarray) -> tuple[float, float]:
    """max over t of |V(p, t)| for a trial V_max: grid search then bounded refinement."""
    f = DownburstField(**{**field.__dict__, "v_max": v_max})
    xp = np.array([field.point_p])
    px, py = field.p_xy()

    def speed(t: np.ndarray) -> np.ndarray:
        if field.point_xy is None:
            vx, vy = f.velocity(xp, np.atleast_1d(t))
        else:  # section form: p off the line, in the global plan frame, at the reference height
            vx, vy = f.velocity_at(np.array([px]), np.array([py]), np.atleast_1d(t))
        return np.hypot(vx, vy)[:, 0]

    s = speed(times)
    k = int(np.argmax(s))
    best_t, best = float(times[k]), float(s[k])
    lo, hi = times[max(k - 1, 0)], times[min(k + 1, times.size - 1)]
    if hi > lo:
        from scipy.optimize import minimize_scalar

        res = minimize_scalar(lambda tt: -float(speed(np.array([tt]))[0]), bounds=(lo, hi), method="bounded",
                              options={"xatol": 1e-9 * max(1.0, abs(hi))})
        if -res.fun > best:
            best_t, best = float(res.x), float(-res.fun)
    return best, best_t


def downburst_field(case: Case) -> DownburstField:
    """Build the scaled downburst running-mean field of a case (analytic or user table).

    Cached per case (and per field-file modification time).  Raises :class:`CaseError`
    when V_ref cannot be matched at p (centre on the line, translation faster than
    V_ref, or a table with no outflow at p).
    """
    db = _downburst(case)
    stamp = None
    if db.field is not None:
        path = db.field_path if db.field_path is not None else Path(db.field)
        try:
            st = path.stat()
            stamp = (st.st_mtime_ns, st.st_size)
        except OSError:
            stamp = None  # load_field_table reports it
    return _downburst_field_cached(case, stamp)


def _distance_to_p(centre: tuple[float, float], point_p: float, point_xy: tuple[float, float] | None) -> float:
    """Plan distance [m] from the downburst centre to p (equal-span form: |y_c|, as always)."""
    if point_xy is None:
        return abs(centre[1])
    return math.hypot(centre[0] - point_xy[0], centre[1] - point_xy[1])


def _placement(case: Case, db: Downburst, system: LineSystem) -> dict:
    """The paper's Fig. 2 geometry: the centre at the reference instant, point p and the translation.

    Equal-span form: the centre at (x_T + R sin(Theta), -R cos(Theta)), p the foot of the
    perpendicular from it on the line y = 0.  Section form: the same geometry in the tower of
    interest's own frame (docs/wind.md).  Returns :class:`DownburstField` keyword arguments:
    centre [m] (x, y), point_p [m], point_xy [m] (x, y) or None, translation [m/s] (v_x, v_y).
    """
    toi = case.line.tower_of_interest - 1
    x_toi = float(system.tower_x[toi])
    theta = math.radians(db.angle)
    # paper Fig. 2: centre at distance R, angle Theta from the perpendicular through the tower, upwind (-y)
    sin_t, cos_t = math.sin(theta), math.cos(theta)
    # snap round-off of sin/cos at multiples of 90 degrees (e.g. cos(pi/2) = 6e-17)
    sin_t, cos_t = (0.0 if abs(sin_t) < 1e-12 else sin_t), (0.0 if abs(cos_t) < 1e-12 else cos_t)
    beta = math.radians(db.translation_direction)
    point_xy = None
    if system.is_section:
        # section form: the paper's Fig. 2 geometry in the tower of interest's own frame (x' along its mean
        # heading psi, y' = x' turned +90 deg): centre = P_T + R sin(Theta) x' - R cos(Theta) y'; p = the
        # foot of the perpendicular from the centre on the x' axis, P_T + R sin(Theta) x' (docs/wind.md)
        psi = float(system.tower_headings[toi])
        cp, sp = math.cos(psi), math.sin(psi)
        px0, py0 = (float(v) for v in system.clamp_points[toi, :2])
        a, b = db.distance * sin_t, -db.distance * cos_t  # centre in the tower frame (x', y')
        centre = (round(px0 + a * cp - b * sp, 9) + 0.0, round(py0 + a * sp + b * cp, 9) + 0.0)
        point_xy = (px0 + a * cp, py0 + a * sp)
        point_p = round(x_toi + a, 9)  # p's coordinate along the x' axis, counted like a station
        beta += psi  # translation_direction is measured from the tower frame's x' axis
    else:
        # (rounded to 1 nm so that, e.g., R sin 30 deg lands on its FE node: 480.0, not 479.99999999999994)
        centre = (round(x_toi + db.distance * sin_t, 9), round(-db.distance * cos_t, 9) + 0.0)
        point_p = centre[0]  # foot of the perpendicular from the centre to the line y = 0
    translation = (db.translation_speed * math.cos(beta), db.translation_speed * math.sin(beta))
    if abs(translation[0]) < 1e-15:
        translation = (0.0, translation[1])
    if abs(translation[1]) < 1e-15:
        translation = (translation[0], 0.0)
    return {"centre": centre, "translation": translation, "point_p": point_p, "point_xy": point_xy}


def _ring_field(case: Case, db: Downburst, common: dict, src: str | None) -> tuple[DownburstField, np.ndarray]:
    """Unscaled (V_max = 1) ring-jet field with its reference instant, the instant the stationary
    outflow at p peaks, and the candidate instants [s] of the peak at p (a fine grid of the window)."""
    rj = ring_scale(case)
    if db.t1 is not None or db.t_f is not None:  # guarded by the loader too
        raise CaseError("t1/t_f shape the holmes-oliver model only", file=src, key="wind.downburst.t1")
    field = DownburstField(t_ref=0.0, ring=rj, **common)
    # reference instant of the centre position: when the stationary outflow at p peaks
    window = common["window"]
    times = np.linspace(window[0], window[1], 6001)
    r_p0 = _distance_to_p(common["centre"], common["point_p"], common["point_xy"])
    t_ref = float(times[int(np.argmax(np.abs(field.shape(np.full(times.size, r_p0), times))))])
    return DownburstField(**{**field.__dict__, "t_ref": t_ref}), times


def _analytic_field(db: Downburst, common: dict, src: str | None) -> tuple[DownburstField, np.ndarray]:
    """Unscaled (V_max = 1) Holmes & Oliver (2000) field, V = f_r(r) f_z(z) Pi(t), with the
    defaults of unset parameters, and the candidate instants [s] of the peak at p (T1, window ends)."""
    dj = common["jet_diameter"]
    r_max = db.r_max if db.r_max is not None else R_MAX_OVER_DJ * dj
    r_dec = db.radial_decay if db.radial_decay is not None else RADIAL_DECAY_OVER_DJ * dj
    z_max = db.z_max if db.z_max is not None else Z_MAX_OVER_DJ * dj
    t1 = db.t1 if db.t1 is not None else T1_DEFAULT
    t_f = db.t_f if db.t_f is not None else T_F_DEFAULT
    if t_f <= t1:
        raise CaseError(f"value {t_f!r} is not allowed: expected t_f > t1 = {t1!r} (t1 default {T1_DEFAULT:g} s)",
                        file=src, key="wind.downburst.t_f")
    field = DownburstField(t_ref=t1, r_max=r_max, radial_decay=r_dec, z_max=z_max, delta=wood_delta(z_max), t1=t1,
                           t_f=t_f, table=None, **common)
    # candidate instants where the stationary speed at p peaks: T1 and the window ends
    return field, np.array([t1, *common["window"]])


def _table_field(system: LineSystem, table: FieldTable, common: dict) -> tuple[DownburstField, np.ndarray]:
    """Unscaled (V_max = 1) user-table field, its reference instant the table's peak radial speed at
    the reference height, and the candidate instants [s] of the peak at p (the table's t, window ends)."""
    dj, h = common["jet_diameter"], common["height"]
    if system.is_section and table.z.size > 1:
        # every conductor node is evaluated at its own height: the table must cover them all
        # (checked here so that `linecheck check` reports it; same message as the evaluation)
        zn = system.node_height / dj
        lo, hi = float(zn.min()), float(zn.max())
        if lo < table.z[0] - 1e-12 or hi > table.z[-1] + 1e-12:
            raise field_error(table.path, f"the conductor heights reach z/D_j from {lo:.4g} to {hi:.4g} but "
                              f"the table covers z_over_dj {table.z[0]:g} to {table.z[-1]:g}: extend the table")
    sl = table_slice(table, h / dj)
    # reference instant: the table's peak radial speed at the conductor height
    t_ref = float(table.t[int(np.argmax(np.max(np.abs(sl.rgi.values), axis=0)))])
    field = DownburstField(t_ref=t_ref, table=table, **common)
    return field, np.concatenate([table.t, np.array(common["window"])])


def _stationary_v_max(case: Case, field: DownburstField, special: np.ndarray, src: str | None) -> float:
    """V_max [m/s] of a stationary centre: V_ref over the peak of |shape| at p over the candidate
    instants ``special`` [s] (paper section 2.1: the peak running mean at p equals V_ref)."""
    v_ref = case.wind.v_ref
    point_p = field.point_p
    if field.ring is not None:
        # stationary ring-jet: |V(p,t)| = V_max |s(r_p, t)|, maximum found by grid + refinement
        peak = _max_speed_at_p(field, 1.0, special)[0]
        if not peak > 0.0:
            raise CaseError(f"the outflow at point p (x = {point_p:g} m) is zero over the window, so V_ref cannot "
                            "be matched; change distance/angle", file=src, key="wind.downburst")
        return v_ref / peak  # paper section 2.1: peak running mean at p (conductor height) = V_ref
    # stationary centre: |V(p,t)| = V_max |shape(r_p, t)|; its maximum is at T1 or a table instant
    # (linear interpolation in t) or a window end, so the scaling is exact.
    r_p = _distance_to_p(field.centre, point_p, field.point_xy)
    peak = float(np.max(np.abs(field.shape(np.full(special.size, r_p), special))))
    if not peak > 0.0:
        raise CaseError(
            f"the outflow at point p (x = {point_p:g} m, r = {r_p:g} m from the centre) is zero over the window, "
            "so V_ref cannot be matched: the centre lies on the line (R cos(Theta) = 0) or the field has no "
            "outflow there; change distance/angle", file=src, key="wind.downburst")
    return v_ref / peak  # paper section 2.1: peak running mean at p (conductor height) = V_ref


def _translating_v_max(case: Case, db: Downburst, field: DownburstField, special: np.ndarray,
                       src: str | None) -> float:
    """V_max [m/s] of a travelling storm: the root of max_t |V(p, t)| = V_ref (paper section 2.1),
    the radial outflow and the translation added as vectors (Holmes & Oliver 2000)."""
    v_ref = case.wind.v_ref
    window = field.window
    if math.hypot(*field.translation) >= v_ref:
        raise CaseError(f"value {db.translation_speed!r} is not allowed: the translation speed alone reaches "
                        f"V_ref = {v_ref:g} m/s at p (expected translation_speed < v_ref)",
                        file=src, key="wind.downburst.translation_speed")
    times = np.union1d(np.linspace(window[0], window[1], 4001), special)

    def excess(v: float) -> float:
        return _max_speed_at_p(field, v, times)[0] - v_ref

    hi = v_ref
    while excess(hi) < 0.0:
        hi *= 2.0
        if hi > 1e6 * v_ref:
            raise CaseError(f"the outflow at point p (x = {field.point_p:g} m) is too weak to reach V_ref; change "
                            "distance/angle", file=src, key="wind.downburst")
    # the max over t of |affine in V_max| is convex in V_max with value < V_ref at 0: one root
    from scipy.optimize import brentq

    return brentq(excess, 0.0, hi, xtol=1e-13 * v_ref, rtol=1e-15, maxiter=200)


@lru_cache(maxsize=64)
def _downburst_field_cached(case: Case, stamp: tuple[int, int] | None) -> DownburstField:
    """:func:`downburst_field` for one field-file stamp (modification time, size): the placement
    (paper Fig. 2), the unscaled field of the case's model, then V_max from V_ref at p."""
    db = _downburst(case)
    src = str(case.source) if case.source else None
    h = reference_height(case)  # V_ref at p at this height (equal-span form: the conductor height)
    system = LineSystem(case.line)
    common = {"jet_diameter": db.jet_diameter, "height": h, "v_max": 1.0, **_placement(case, db, system)}
    window = common["window"] = event_window(case)
    table = _table_of(case)
    if db.model_name in ring_model.MODELS:
        field, special = _ring_field(case, db, common, src)
    elif table is None:
        field, special = _analytic_field(db, common, src)
    else:
        field, special = _table_field(system, table, common)
    special = special[(special >= window[0]) & (special <= window[1])]
    if field.translation == (0.0, 0.0):
        v_max = _stationary_v_max(case, field, special, src)
    else:
        v_max = _translating_v_max(case, db, field, special, src)
    return DownburstField(**{**field.__dict__, "v_max": float(v_max)})
