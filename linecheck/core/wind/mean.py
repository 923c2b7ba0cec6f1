"""Running-mean wind along the line (paper section 2.1).

Contract used by the solver steps:

``mean_wind(case, system, times)`` returns a :class:`MeanWind` with the
running-mean velocity components at the still-air FE node positions of every span
(normal to the line, +y, and along it, +x) at the requested instants.
``event_window(case)`` gives the analysed time window [s].

Synoptic wind: V_ref (or ``span_speeds``) uniform along each span, constant in time.

Downburst wind (issue 3; the paper used the CFD field of Hangan & Kim 2007, which is
not public, so linecheck ships an analytic stationary impinging-jet model and lets
users load their own table).  The horizontal outflow is radial from the centre:

    V(r, z, t) = V_max * f_r(r) * f_z(z) * Pi(t)                      (issue 3)

    f_r(r) = r / r_max                          r <= r_max     (Holmes & Oliver 2000)
           = exp(-((r - r_max) / R_r)^2)        r >  r_max
    f_z(z) = 1.55 (z/delta)^(1/6) [1 - erf(0.70 z/delta)]         (Wood et al. 2001)
    Pi(t)  = t / T1                              t <= T1   (Chay, Albermani & Wilson 2006)
           = exp(-(t - T1) / c),  c = (T_f - T1) / ln 10   t > T1

with an optional storm translation added as a vector (Holmes & Oliver 2000).
Geometry (paper Fig. 2): x along the line, the tower of interest at x_T, y = 0
along the line, the centre at (x_T + R sin(Theta), -R cos(Theta)) at the reference
instant, so the outflow at Theta = 0 blows toward +y.  Point p is the point of
the (unbounded) line nearest that centre; V_max is scaled so that the maximum over
the analysed window of the running-mean speed at p, at the conductor height,
equals V_ref (paper section 2.1).  See ``docs/wind.md`` for the defaults and why.

A user table (``[wind.downburst] field = "file.csv"`` or ``.npz``) replaces
f_r(r) f_z(z) Pi(t) by a radial velocity on an (r/D_j, z/D_j, t) grid,
interpolated linearly and scaled the same way.  Nothing here prints.
"""

from __future__ import annotations

import csv
import math
import zipfile
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..case import Case, Downburst, cell_text, read_regular_file, reads_as_header
from ..errors import CaseError
from ..system import LineSystem
from . import ring as ring_model

# Wood et al. (2001) f_z and z/delta of its maximum: one source, shared with the ring-jet models
from .profiles import ETA_PEAK
from .profiles import wood as _wood

if TYPE_CHECKING:
    from scipy.interpolate import RegularGridInterpolator
# scipy.interpolate and scipy.optimize are imported where they are used: importing them costs
# ≈ 0.4 s, which `linecheck check` of a downburst case would otherwise pay

# ------------------------------------------------------------------------- constants
R_MAX_OVER_DJ = 1.2  # r_max = 1.2 D_j: radius of peak outflow of Kim & Hangan (2007), = paper's Db_y R
RADIAL_DECAY_OVER_DJ = 0.5  # R_r = D_j / 2 (issue 3 default; Holmes & Oliver 2000 decay length)
Z_MAX_OVER_DJ = 0.025  # z_max = 0.025 D_j (Wood et al. 2001 / Hangan & Kim 2007 jet scale)
# Lubbock-Reese rear-flank downdraft of 4 June 2002 (Holmes et al. 2008): running mean rose to its
# peak in about two minutes and the event was analysed as a ten-minute record.  See docs/wind.md.
T1_DEFAULT = 120.0  # [s]
T_F_DEFAULT = 600.0  # [s]
SYNOPTIC_DURATION_DEFAULT = 600.0  # [s] ten-minute record (standard averaging period)


# ------------------------------------------------------------------------- MeanWind
@dataclass(frozen=True)
class MeanWind:
    """Running-mean wind at the FE nodes.

    Attributes:
        time: [s] instants, shape (n_t,).
        normal: [m/s] component normal to the line (toward +y) at each span's FE nodes,
            shape (n_t, n_spans, ne+1) (span-local nodes, so a speed may jump at a tower).
        longitudinal: [m/s] component along the line (toward +x), same shape.
        point_p: [m] x-coordinate of point p (line point nearest the downburst centre;
            synoptic: the tower of interest).  Section form: p's coordinate along the tower of
            interest's frame x axis, counted from the first tower like a station.
        point_xy: [m] plan position (x, y) of p in the global frame (section form; equal-span
            form: (point_p, 0)).

    Section form (issue 17): ``normal`` is the component along each span's horizontal normal
    n_i = (-sin h_i, cos h_i, 0) and ``longitudinal`` along its horizontal direction
    (cos h_i, sin h_i, 0), at the nodes' still-air plan positions and heights above ground.
    """

    time: np.ndarray
    normal: np.ndarray
    longitudinal: np.ndarray
    point_p: float
    point_xy: tuple[float, float] | None = None


def synoptic_span_speeds(case: Case) -> np.ndarray:
    """Mean speed of every span [m/s], shape (n_spans,): ``span_speeds`` or V_ref."""
    if case.wind.span_speeds is None:
        return np.full(case.line.spans, case.wind.v_ref)
    return np.asarray(case.wind.span_speeds, dtype=float)


# ------------------------------------------------------------------------- synoptic direction and profile
def reference_height(case: Case) -> float:
    """z_ref [m]: ``wind.reference_height``, else the mean clamp height above ground (``line.height``;
    the equal-span form's conductor height).  Synoptic: the height of V_ref in the power law;
    downburst: the height at which the running mean at p peaks at V_ref."""
    z = case.wind.reference_height
    return float(case.line.height if z is None else z)


def profile_factor(case: Case, z_agl: np.ndarray) -> np.ndarray:
    """V(z)/v_ref [-] = (z_agl / z_ref)^alpha at heights above ground z_agl [m] (any shape).

    Power law (Hellmann 1916; Davenport 1960);
    alpha = ``profile_exponent`` (0: exactly 1 everywhere).  A point at or below the ground
    (possible only for a sagging conductor) gets 0."""
    z_agl = np.asarray(z_agl, dtype=float)
    alpha = float(case.wind.profile_exponent)
    if alpha == 0.0:
        return np.ones_like(z_agl)
    # power law (Hellmann 1916; Davenport 1960): V(z) = V_ref (z / z_ref)^alpha
    return (np.maximum(z_agl, 0.0) / reference_height(case)) ** alpha


def wind_direction_vector(case: Case) -> np.ndarray:
    """Unit mean-wind direction m = (sin d, cos d, 0) [-], shape (3,) (d = ``wind.direction``;
    d = 0 blows toward +y, normal to the first span; issue 17)."""
    d = math.radians(case.wind.direction)
    return np.array([math.sin(d), math.cos(d), 0.0])


def _span_node_index(system: LineSystem) -> np.ndarray:
    """Global node index of every span-local node, shape (n_spans, ne+1)."""
    return np.arange(system.n_spans)[:, None] * system.ne + np.arange(system.ne + 1)[None, :]


def _span_along(system: LineSystem) -> np.ndarray:
    """Horizontal unit direction (cos h_i, sin h_i, 0) of every span, shape (n_spans, 3)."""
    h = system.span_headings
    return np.stack([np.cos(h), np.sin(h), np.zeros_like(h)], axis=1)


def _node_along(system: LineSystem) -> np.ndarray:
    """Horizontal unit along-line direction of every global node, shape (n_nodes, 3): the node
    normal turned -90 deg in plan (span nodes: the span's direction; tower nodes: the tower frame x)."""
    n = system.node_normals
    return np.stack([n[:, 1], -n[:, 0], np.zeros(n.shape[0])], axis=1)


def _synoptic_plain(case: Case, system: LineSystem) -> bool:
    """True for the paper's synoptic wind: equal-span form, d = 0, no profile (the original,
    bit-identical code path)."""
    return (not system.is_section and case.wind.direction == 0.0 and case.wind.profile_exponent == 0.0
            and case.wind.reference_height is None)


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


# ------------------------------------------------------------------------- user field tables
FIELD_COLUMNS = ("r_over_dj", "z_over_dj", "t", "v_radial", "v_vertical")
_REQUIRED_COLUMNS = FIELD_COLUMNS[:4]
_ALLOWED_TEXT = "r_over_dj, z_over_dj, t, v_radial and optionally v_vertical"


@dataclass(frozen=True, eq=False)
class FieldTable:
    """A user running-mean field on a rectilinear (r/D_j, z/D_j, t) grid (see docs/wind.md).

    Attributes:
        path: the file read.
        r: [-] r/D_j axis, strictly increasing, shape (n_r,), n_r >= 2.
        z: [-] z/D_j axis, strictly increasing, shape (n_z,), n_z >= 1 (1: no height variation).
        t: [s] time axis, strictly increasing, shape (n_t,), n_t >= 2.
        radial: [any unit, rescaled] radial (outward) velocity, shape (n_r, n_z, n_t).
        vertical: [same unit] vertical velocity (upward) or None, shape (n_r, n_z, n_t).
    """

    path: Path
    r: np.ndarray
    z: np.ndarray
    t: np.ndarray
    radial: np.ndarray
    vertical: np.ndarray | None


def _field_error(path: Path, message: str, line: int | None = None) -> CaseError:
    return CaseError(message, file=str(path), line=line)


def _grid_from_rows(path: Path, cols: dict[str, np.ndarray], lines: np.ndarray) -> FieldTable:
    """Assemble the grid from CSV rows; every (r, z, t) combination exactly once."""
    axes = {}
    idx = {}
    for name in ("r_over_dj", "z_over_dj", "t"):
        values, inverse = np.unique(cols[name], return_inverse=True)
        axes[name], idx[name] = values, inverse
    n_r, n_z, n_t = (axes[k].size for k in ("r_over_dj", "z_over_dj", "t"))
    _check_axes(path, axes["r_over_dj"], axes["z_over_dj"], axes["t"])
    flat = (idx["r_over_dj"] * n_z + idx["z_over_dj"]) * n_t + idx["t"]
    seen = np.full(n_r * n_z * n_t, -1, dtype=np.int64)
    order = np.argsort(flat, kind="stable")
    sorted_flat = flat[order]
    dup = np.nonzero(sorted_flat[1:] == sorted_flat[:-1])[0]
    if dup.size:
        first, again = order[dup[0]], order[dup[0] + 1]
        raise _field_error(
            path, f"row repeats the grid point (r_over_dj, z_over_dj, t) = ({cols['r_over_dj'][again]:g}, "
            f"{cols['z_over_dj'][again]:g}, {cols['t'][again]:g}) of line {int(lines[first])}: "
            "each grid point must appear exactly once", line=int(lines[again]))
    seen[flat] = np.arange(flat.size)
    missing = np.nonzero(seen < 0)[0]
    if missing.size:
        m = int(missing[0])
        ir, rest = divmod(m, n_z * n_t)
        iz, it = divmod(rest, n_t)
        raise _field_error(
            path, f"grid point (r_over_dj, z_over_dj, t) = ({axes['r_over_dj'][ir]:g}, {axes['z_over_dj'][iz]:g}, "
            f"{axes['t'][it]:g}) is missing: the rows must fill the full rectilinear grid "
            f"({n_r} r x {n_z} z x {n_t} t = {n_r * n_z * n_t} rows, found {flat.size})")
    shape = (n_r, n_z, n_t)
    radial = np.empty(n_r * n_z * n_t)
    radial[flat] = cols["v_radial"]
    vertical = None
    if "v_vertical" in cols:
        vertical = np.empty(n_r * n_z * n_t)
        vertical[flat] = cols["v_vertical"]
        vertical = vertical.reshape(shape)
    return FieldTable(path, axes["r_over_dj"], axes["z_over_dj"], axes["t"], radial.reshape(shape), vertical)


def _check_axes(path: Path, r: np.ndarray, z: np.ndarray, t: np.ndarray) -> None:
    if r.size < 2:
        raise _field_error(path, f"column r_over_dj has {r.size} distinct value(s): expected at least 2")
    if t.size < 2:
        raise _field_error(path, f"column t has {t.size} distinct value(s): expected at least 2")
    if z.size < 1:
        raise _field_error(path, "column z_over_dj has no values: expected at least 1")
    if r[0] < 0:
        raise _field_error(path, f"column r_over_dj has value {r[0]:g}: expected r_over_dj >= 0")
    if z[0] < 0:
        raise _field_error(path, f"column z_over_dj has value {z[0]:g}: expected z_over_dj >= 0")


MAX_FIELD_BYTES = 200 * 2**20  # [bytes] size cap of a field file (docs/wind.md, docs/case-files.md)


def _read_csv(path: Path) -> FieldTable:
    raw = read_regular_file(path, "a CSV running-mean field file", MAX_FIELD_BYTES)  # bounded read (issue 14)
    try:
        text = raw.decode("utf-8-sig")  # a leading byte-order mark (spreadsheets write one) is dropped
    except UnicodeDecodeError:
        raise _field_error(path, "not a UTF-8 text file: expected a CSV running-mean field (see docs/wind.md)") from None
    header: list[str] | None = None
    header_line = 0
    rows: list[list[float]] = []
    lines: list[int] = []
    for lineno, raw in enumerate(text.splitlines(), start=1):
        s = raw.strip()
        if not s or s.startswith("#"):
            continue
        fields = [f.strip() for f in next(csv.reader([s]))]
        if header is None:
            header, header_line = fields, lineno
            if not reads_as_header(fields, FIELD_COLUMNS):  # not quoted: any file may be named here
                raise _field_error(path, f"not a field table: expected a comma-separated (CSV) file whose first "
                                   f"row names its columns, {_ALLOWED_TEXT} (see docs/wind.md)", line=lineno)
            for k, name in enumerate(fields, start=1):
                if name not in FIELD_COLUMNS:
                    raise _field_error(path, f'header column {k} "{name}" is not allowed: expected {_ALLOWED_TEXT}',
                                       line=lineno)
                if fields.count(name) > 1:
                    raise _field_error(path, f'header column "{name}" appears twice: expected each of {_ALLOWED_TEXT} once',
                                       line=lineno)
            for name in _REQUIRED_COLUMNS:
                if name not in fields:
                    raise _field_error(path, f'header has no column "{name}": expected {_ALLOWED_TEXT}', line=lineno)
            continue
        if len(fields) != len(header):
            raise _field_error(path, f"row has {len(fields)} values: expected {len(header)} ({', '.join(header)})",
                               line=lineno)
        row = []
        for name, value in zip(header, fields):
            try:
                v = float(value)
            except ValueError:
                raise _field_error(path, f'column "{name}": value {cell_text(value)} is not a number: expected a '
                                   "finite number", line=lineno) from None
            if not math.isfinite(v):
                raise _field_error(path, f'column "{name}": value "{value}" is not allowed: expected a finite number',
                                   line=lineno)
            if name in ("r_over_dj", "z_over_dj") and v < 0:
                raise _field_error(path, f'column "{name}": value {value} is out of range: expected {name} >= 0',
                                   line=lineno)
            row.append(v)
        rows.append(row)
        lines.append(lineno)
    if header is None:
        raise _field_error(path, f"no header line: expected a header with {_ALLOWED_TEXT}")
    if not rows:
        raise _field_error(path, "header but no data rows: expected one row per (r_over_dj, z_over_dj, t) grid point",
                           line=header_line)
    data = np.asarray(rows, dtype=float)
    cols = {name: data[:, k] for k, name in enumerate(header)}
    return _grid_from_rows(path, cols, np.asarray(lines))


def _check_real(path: Path, name: str, a: np.ndarray) -> None:
    """CaseError unless ``a`` holds real numbers (floating point or integer): a complex array would
    lose its imaginary part, text, booleans, dates or objects are not velocities or coordinates."""
    if a.dtype.kind in "fiu":
        return
    what = {"c": "complex numbers", "b": "booleans", "U": "text", "S": "bytes", "O": "Python objects",
            "M": "dates", "m": "time spans", "V": "records"}.get(a.dtype.kind, "not numbers")
    raise _field_error(path, f'array "{name}" has dtype {a.dtype} ({what}): expected real numbers '
                       "(a floating-point array, or integers)")


def _read_npz(path: Path) -> FieldTable:
    try:
        with np.load(path, allow_pickle=False) as npz:
            # uncompressed size of the members checked before any is read (a zip bomb; issue 14)
            inflated = sum(info.file_size for info in npz.zip.infolist())
            if inflated > MAX_FIELD_BYTES:
                raise _field_error(path, f"arrays of {inflated / 2**20:.0f} MB uncompressed are too large: expected "
                                   f"at most {MAX_FIELD_BYTES / 2**20:.0f} MB")
            arrays = {k: np.asarray(npz[k]) for k in npz.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError) as exc:
        # BadZipFile: a file that starts like a zip archive ("PK\x03\x04...") but is not one;
        # NotImplementedError: a member compressed with a method zipfile cannot read
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise _field_error(path, f"not a readable NPZ file ({reason}): expected a zip archive of arrays "
                           f"{_ALLOWED_TEXT} (numpy.savez)") from None
    for name in arrays:
        if name not in FIELD_COLUMNS:
            raise _field_error(path, f'array "{name}" is not allowed: expected {_ALLOWED_TEXT}')
    for name in _REQUIRED_COLUMNS:
        if name not in arrays:
            raise _field_error(path, f'array "{name}" is missing: expected {_ALLOWED_TEXT}')
    axes = []
    for name in ("r_over_dj", "z_over_dj", "t"):
        a = arrays[name]
        _check_real(path, name, a)
        if a.ndim != 1:
            raise _field_error(path, f'array "{name}" has shape {a.shape}: expected a 1-D array of numbers')
        a = a.astype(float)
        if not np.all(np.isfinite(a)):
            raise _field_error(path, f'array "{name}" has a non-finite value: expected finite numbers')
        if a.size > 1 and not np.all(np.diff(a) > 0):
            k = int(np.nonzero(np.diff(a) <= 0)[0][0]) + 1
            raise _field_error(path, f'array "{name}" entry {k} ({a[k]:g}) is not above the previous one: '
                               "expected strictly increasing values")
        axes.append(a)
    r, z, t = axes
    _check_axes(path, r, z, t)
    shape = (r.size, z.size, t.size)
    out = {}
    for name in ("v_radial", "v_vertical"):
        if name not in arrays:
            continue
        a = arrays[name]
        _check_real(path, name, a)
        if a.shape != shape:
            raise _field_error(path, f'array "{name}" has shape {a.shape}: expected numbers of shape '
                               f"(len(r_over_dj), len(z_over_dj), len(t)) = {shape}")
        a = a.astype(float)
        if not np.all(np.isfinite(a)):
            i = tuple(int(v) for v in np.argwhere(~np.isfinite(a))[0])
            raise _field_error(path, f'array "{name}" entry {i} is not finite: expected finite numbers')
        out[name] = a
    return FieldTable(path, r, z, t, out["v_radial"], out.get("v_vertical"))


@lru_cache(maxsize=16)
def _load_cached(path: str, mtime_ns: int, size: int) -> FieldTable:
    p = Path(path)
    suffix = p.suffix.lower()
    if suffix == ".csv":
        return _read_csv(p)
    if suffix == ".npz":
        return _read_npz(p)
    raise _field_error(p, f'file type "{p.suffix}" is not allowed: expected a .csv or .npz running-mean field '
                       "(see docs/wind.md)")


def load_field_table(path: str | Path) -> FieldTable:
    """Read and validate a user running-mean field (CSV or NPZ; format in ``docs/wind.md``).

    Raises :class:`CaseError` with one line naming the file, the line/column or array and
    what is allowed.  Results are cached per (path, modification time, size).
    """
    p = Path(path)
    try:
        st = p.stat()
    except FileNotFoundError:
        raise _field_error(p, "field file not found (expected a CSV or NPZ running-mean field, see docs/wind.md)") from None
    except OSError as exc:
        raise _field_error(p, f"cannot read field file: {exc.strerror}") from None
    if not p.is_file():
        raise _field_error(p, "is not a regular file: expected a CSV or NPZ running-mean field")
    if st.st_size > MAX_FIELD_BYTES:
        raise _field_error(p, f"file size {st.st_size / 2**20:.0f} MB is too large: expected at most "
                           f"{MAX_FIELD_BYTES / 2**20:.0f} MB (a CSV or NPZ running-mean field)")
    return _load_cached(str(p.resolve()), st.st_mtime_ns, st.st_size)


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

    Section form (issue 17): ``centre``, ``translation`` and ``point_xy`` are in the global
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
            # issue 15: non-separable ring vortex + image + wall jet, per unit V_j
            return self.ring.shape(r, self.height, t)
        if self.table is None:
            # issue 3: V = V_max f_r(r) f_z(z) Pi(t); Pi on the given instants (e.g. (n_t, 1)), not on
            # the broadcast grid: the same values, n_x times fewer exponentials
            return (radial_profile(r, self.r_max, self.radial_decay)
                    * float(vertical_profile(self.height, self.delta)) * intensity(t0, self.t1, self.t_f))
        return _table_slice(self.table, self.height / self.jet_diameter)(r / self.jet_diameter, t, self.table.path)

    def _shape_z(self, r: np.ndarray, t: np.ndarray, z: np.ndarray) -> np.ndarray:
        """:meth:`shape` with a height per point (section form: each node's own height)."""
        r, t, z = np.broadcast_arrays(np.asarray(r, dtype=float), np.asarray(t, dtype=float),
                                      np.asarray(z, dtype=float))
        if self.ring is not None:
            # issue 15: the ring-jet field is a function of (r, z, t) (not separable)
            return self.ring.shape(r, z, t)
        if self.table is None:
            # issue 3: V = V_max f_r(r) f_z(z) Pi(t), f_z of Wood et al. (2001) at each point's height
            return (radial_profile(r, self.r_max, self.radial_decay) * vertical_profile(z, self.delta)
                    * intensity(t, self.t1, self.t_f))
        return _table_points(self.table, r / self.jet_diameter, z / self.jet_diameter, t)

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
        interp = _table_slice(self.table, self.height / self.jet_diameter, vertical=True)
        return self.v_max * interp(r / self.jet_diameter, np.broadcast_to(t, r.shape), self.table.path)


class _SliceInterpolator:
    """Bilinear (r/D_j, t) interpolation of a table at one height (trilinear overall)."""

    def __init__(self, r: np.ndarray, t: np.ndarray, values: np.ndarray) -> None:
        self.r, self.t = r, t
        from scipy.interpolate import RegularGridInterpolator

        self.rgi = RegularGridInterpolator((r, t), values, method="linear", bounds_error=False, fill_value=None)

    def __call__(self, rr: np.ndarray, tt: np.ndarray, path: Path) -> np.ndarray:
        rr, tt = np.broadcast_arrays(rr, tt)
        self.check(rr, tt, path)
        pts = np.stack([np.clip(rr, self.r[0], self.r[-1]).ravel(), np.clip(tt, self.t[0], self.t[-1]).ravel()], axis=-1)
        return self.rgi(pts).reshape(rr.shape)

    def check(self, rr: np.ndarray, tt: np.ndarray, path: Path) -> None:
        """One-line error when points leave the table's r or t range (round-off tolerated)."""
        tol_r = 1e-9 * max(1.0, abs(self.r[-1]))
        tol_t = 1e-9 * max(1.0, abs(self.t[-1]))
        if rr.size:
            lo, hi = float(rr.min()), float(rr.max())
            if lo < self.r[0] - tol_r or hi > self.r[-1] + tol_r:
                raise _field_error(path, f"the line reaches r/D_j from {lo:.4g} to {hi:.4g} but the table covers "
                                   f"r_over_dj {self.r[0]:g} to {self.r[-1]:g}: extend the table")
            lo, hi = float(tt.min()), float(tt.max())
            if lo < self.t[0] - tol_t or hi > self.t[-1] + tol_t:
                raise _field_error(path, f"times {lo:.6g} to {hi:.6g} s are needed but the table covers t "
                                   f"{self.t[0]:g} to {self.t[-1]:g} s: extend the table or shorten analysis.duration")


@lru_cache(maxsize=32)
def _table_slice_cached(table: FieldTable, z: float, vertical: bool) -> _SliceInterpolator:
    values = table.vertical if vertical else table.radial
    if table.z.size == 1:
        sl = values[:, 0, :]
    else:
        if z < table.z[0] - 1e-12 or z > table.z[-1] + 1e-12:
            raise _field_error(table.path, f"the conductor height is z/D_j = {z:.4g} but the table covers z_over_dj "
                               f"{table.z[0]:g} to {table.z[-1]:g}: extend the table")
        from scipy.interpolate import RegularGridInterpolator

        rgi = RegularGridInterpolator((table.r, table.z, table.t), values, method="linear")
        rr, tt = np.meshgrid(table.r, table.t, indexing="ij")
        zz = np.full_like(rr, min(max(z, table.z[0]), table.z[-1]))
        sl = rgi(np.stack([rr, zz, tt], axis=-1))
    return _SliceInterpolator(table.r, table.t, sl)


def _table_slice(table: FieldTable, z: float, vertical: bool = False) -> _SliceInterpolator:
    return _table_slice_cached(table, float(z), vertical)


@lru_cache(maxsize=16)
def _table_volume(table: FieldTable) -> RegularGridInterpolator:
    from scipy.interpolate import RegularGridInterpolator

    return RegularGridInterpolator((table.r, table.z, table.t), table.radial, method="linear")


def _table_points(table: FieldTable, rr: np.ndarray, zz: np.ndarray, tt: np.ndarray) -> np.ndarray:
    """Radial table speed at (r/D_j, z/D_j, t) per point (broadcast shapes): trilinear
    interpolation (the same as the per-height slices of :func:`_table_slice`), with the same
    range checks; a table with one height has no z dependence."""
    rr, zz, tt = np.broadcast_arrays(rr, zz, tt)
    if table.z.size == 1:
        return _table_slice(table, float(table.z[0]))(rr, tt, table.path)
    if zz.size:
        lo, hi = float(zz.min()), float(zz.max())
        if lo < table.z[0] - 1e-12 or hi > table.z[-1] + 1e-12:
            raise _field_error(table.path, f"the conductor heights reach z/D_j from {lo:.4g} to {hi:.4g} but the "
                               f"table covers z_over_dj {table.z[0]:g} to {table.z[-1]:g}: extend the table")
    # r and t checks of the slice interpolator (same messages)
    _table_slice(table, float(table.z[0])).check(rr, tt, table.path)
    pts = np.stack([np.clip(rr, table.r[0], table.r[-1]).ravel(), np.clip(zz, table.z[0], table.z[-1]).ravel(),
                    np.clip(tt, table.t[0], table.t[-1]).ravel()], axis=-1)
    return _table_volume(table)(pts).reshape(rr.shape)


def _downburst(case: Case) -> Downburst:
    if case.wind.type != "downburst" or case.wind.downburst is None:
        raise CaseError("is not a downburst case (no [wind.downburst] table)", key="wind.type")
    return case.wind.downburst


def _table_of(case: Case) -> FieldTable | None:
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
        return 0.0, float(dur if dur is not None else tau_end * _ring_scale(case).time_scale)
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
def _ring_scale(case: Case) -> ring_model.RingJet:
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


@lru_cache(maxsize=64)
def _downburst_field_cached(case: Case, stamp: tuple[int, int] | None) -> DownburstField:
    db = _downburst(case)
    line = case.line
    src = str(case.source) if case.source else None
    dj = db.jet_diameter
    h = reference_height(case)  # V_ref at p at this height (equal-span form: the conductor height)
    system = LineSystem(line)
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
        # issue 17: the paper's Fig. 2 geometry in the tower of interest's own frame (x' along its mean
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
    window = event_window(case)
    table = _table_of(case)
    if db.model_name in ring_model.MODELS:
        rj = _ring_scale(case)
        if db.t1 is not None or db.t_f is not None:  # guarded by the loader too
            raise CaseError("t1/t_f shape the holmes-oliver model only", file=src, key="wind.downburst.t1")
        field = DownburstField(dj, h, centre, 0.0, translation, 1.0, point_p, window, ring=rj, point_xy=point_xy)
        # reference instant of the centre position: when the stationary outflow at p peaks
        times = np.linspace(window[0], window[1], 6001)
        r_p0 = _distance_to_p(centre, point_p, point_xy)
        t_ref = float(times[int(np.argmax(np.abs(field.shape(np.full(times.size, r_p0), times))))])
        field = DownburstField(**{**field.__dict__, "t_ref": t_ref})
        special = times
    elif table is None:
        r_max = db.r_max if db.r_max is not None else R_MAX_OVER_DJ * dj
        r_dec = db.radial_decay if db.radial_decay is not None else RADIAL_DECAY_OVER_DJ * dj
        z_max = db.z_max if db.z_max is not None else Z_MAX_OVER_DJ * dj
        t1 = db.t1 if db.t1 is not None else T1_DEFAULT
        t_f = db.t_f if db.t_f is not None else T_F_DEFAULT
        if t_f <= t1:
            raise CaseError(f"value {t_f!r} is not allowed: expected t_f > t1 = {t1!r} (t1 default {T1_DEFAULT:g} s)",
                            file=src, key="wind.downburst.t_f")
        field = DownburstField(dj, h, centre, t1, translation, 1.0, point_p, window, r_max, r_dec, z_max,
                               wood_delta(z_max), t1, t_f, None, point_xy=point_xy)
        # candidate instants where the stationary speed at p peaks: T1 and the window ends
        special = np.array([t1, *window])
    else:
        z = h / dj
        if system.is_section and table.z.size > 1:
            # every conductor node is evaluated at its own height: the table must cover them all
            # (checked here so that `linecheck check` reports it; same message as the evaluation)
            zn = system.node_height / dj
            lo, hi = float(zn.min()), float(zn.max())
            if lo < table.z[0] - 1e-12 or hi > table.z[-1] + 1e-12:
                raise _field_error(table.path, f"the conductor heights reach z/D_j from {lo:.4g} to {hi:.4g} but "
                                   f"the table covers z_over_dj {table.z[0]:g} to {table.z[-1]:g}: extend the table")
        sl = _table_slice(table, z)
        # reference instant: the table's peak radial speed at the conductor height
        t_ref = float(table.t[int(np.argmax(np.max(np.abs(sl.rgi.values), axis=0)))])
        field = DownburstField(dj, h, centre, t_ref, translation, 1.0, point_p, window, table=table,
                               point_xy=point_xy)
        special = np.concatenate([table.t, np.array(window)])
    special = special[(special >= window[0]) & (special <= window[1])]
    r_p = _distance_to_p(centre, point_p, point_xy)
    v_ref = case.wind.v_ref
    if translation == (0.0, 0.0) and db.model_name in ring_model.MODELS:
        # stationary ring-jet: |V(p,t)| = V_max |s(r_p, t)|, maximum found by grid + refinement
        peak = _max_speed_at_p(field, 1.0, special)[0]
        if not peak > 0.0:
            raise CaseError(f"the outflow at point p (x = {point_p:g} m) is zero over the window, so V_ref cannot "
                            "be matched; change distance/angle", file=src, key="wind.downburst")
        v_max = v_ref / peak  # paper section 2.1: peak running mean at p (conductor height) = V_ref
    elif translation == (0.0, 0.0):
        # stationary centre: |V(p,t)| = V_max |shape(r_p, t)|; its maximum is at T1 or a table instant
        # (linear interpolation in t) or a window end, so the scaling is exact (issue 3).
        peak = float(np.max(np.abs(field.shape(np.full(special.size, r_p), special))))
        if not peak > 0.0:
            raise CaseError(
                f"the outflow at point p (x = {point_p:g} m, r = {r_p:g} m from the centre) is zero over the window, "
                "so V_ref cannot be matched: the centre lies on the line (R cos(Theta) = 0) or the field has no "
                "outflow there; change distance/angle", file=src, key="wind.downburst")
        v_max = v_ref / peak  # paper section 2.1: peak running mean at p (conductor height) = V_ref
    else:
        if math.hypot(*translation) >= v_ref:
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
                raise CaseError(f"the outflow at point p (x = {point_p:g} m) is too weak to reach V_ref; change "
                                "distance/angle", file=src, key="wind.downburst")
        # the max over t of |affine in V_max| is convex in V_max with value < V_ref at 0: one root
        from scipy.optimize import brentq

        v_max = brentq(excess, 0.0, hi, xtol=1e-13 * v_ref, rtol=1e-15, maxiter=200)
    return DownburstField(**{**field.__dict__, "v_max": float(v_max)})


# ------------------------------------------------------------------------- public evaluators
def span_node_x(system: LineSystem) -> np.ndarray:
    """Still-air x [m] of each span's FE nodes, shape (n_spans, ne+1)."""
    return system.span_node_x0


def mean_velocity_at(case: Case, x: np.ndarray, time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Running-mean (longitudinal v_x, normal v_y) [m/s] at line points x [m], times [s].

    x shape (n_x,), time shape (n_t,) -> two arrays (n_t, n_x).  Synoptic: (0, V_ref)
    everywhere (``span_speeds`` apply only through :func:`mean_wind` and the node helpers).
    Equal-span form (points on the straight line y = 0 at the conductor height); sections use
    :func:`mean_vector_at_nodes`.
    """
    x = np.atleast_1d(np.asarray(x, dtype=float))
    time = np.atleast_1d(np.asarray(time, dtype=float))
    if case.wind.type == "synoptic":
        shape = (time.size, x.size)
        return np.zeros(shape), np.full(shape, case.wind.v_ref)
    return _equal_span_downburst(case, downburst_field(case), x, time)


def point_p(case: Case) -> float:
    """x [m] of point p: the line point nearest the downburst centre (synoptic: tower of interest).

    Section form: p's coordinate along the tower of interest's frame x axis, counted like a
    station (the tower's station + R sin(Theta)); its plan position is :func:`point_p_xy`."""
    if case.wind.type == "synoptic":
        return float(LineSystem(case.line).tower_x[case.line.tower_of_interest - 1])
    return downburst_field(case).point_p


def point_p_xy(case: Case) -> tuple[float, float]:
    """Plan position (x, y) [m] of point p in the global frame (synoptic: the tower of interest's
    still-air clamp; downburst on a section: the foot of the perpendicular from the centre on the
    tower of interest's frame x axis; equal-span form: (point_p, 0))."""
    if case.wind.type == "synoptic":
        c = LineSystem(case.line).clamp_points[case.line.tower_of_interest - 1]
        return float(c[0]), float(c[1])
    return downburst_field(case).p_xy()


def nearest_node_to_p(case: Case, system: LineSystem) -> int:
    """Global FE node nearest point p (0-based): in plan (still-air ``node_xyz0``) on a section,
    along x (``node_x0``) on the equal-span form."""
    if not system.is_section:
        return int(np.argmin(np.abs(system.node_x0 - point_p(case))))
    px, py = point_p_xy(case)
    xy = system.node_xyz0[:, :2]
    return int(np.argmin(np.hypot(xy[:, 0] - px, xy[:, 1] - py)))


def _downburst_nodes(case: Case, system: LineSystem, field: DownburstField,
                     time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Downburst (v_x, v_y) [m/s] in the global plan frame at every global node's still-air plan
    position and height above ground (section form), shape (n_t, n_nodes) each."""
    xyz = system.node_xyz0
    return field.velocity_at(xyz[:, 0], xyz[:, 1], time, system.node_height)


def _synoptic_speed_nodes(case: Case, system: LineSystem) -> np.ndarray:
    """Synoptic mean speed |V| [m/s] at the global nodes: the span speed (tower nodes: the mean
    of their two spans) times the power-law profile at the node's height, shape (n_nodes,)."""
    return _synoptic_node_speeds(case, system) * profile_factor(case, system.node_height)


def mean_vector_at_nodes(case: Case, system: LineSystem, time: np.ndarray) -> np.ndarray:
    """Running-mean wind velocity vector [m/s] at the global FE nodes in the global frame
    (x along the first span, y to its left, z up; z component 0), shape (n_t, n_nodes, 3).

    Synoptic: V(z_node) (sin d, cos d, 0) (issue 17), V(z) = v (z/z_ref)^alpha with v the node's
    span speed (``span_speeds``, else V_ref; tower nodes the mean of their two spans).
    Downburst: the horizontal outflow at the node's still-air plan position and height
    (equal-span form: on y = 0 at the conductor height, as :func:`mean_velocity_at`).
    """
    time = np.atleast_1d(np.asarray(time, dtype=float))
    out = np.zeros((time.size, system.n_nodes, 3))
    if case.wind.type == "synoptic":
        v = _synoptic_speed_nodes(case, system)
        m = wind_direction_vector(case)
        out[:, :, 0] = (v * m[0])[None, :]
        out[:, :, 1] = (v * m[1])[None, :]
        return out
    field = downburst_field(case)
    if system.is_section:
        vx, vy = _downburst_nodes(case, system, field, time)
    else:
        vx, vy = _equal_span_downburst(case, field, system.node_x0, time)
    out[:, :, 0], out[:, :, 1] = vx, vy
    return out


def _equal_span_downburst(case: Case, field: DownburstField, x: np.ndarray,
                          time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Equal-span form: the field on y = 0 at the conductor height (the original path; with an
    explicit ``reference_height`` the scaling height differs from the conductor height)."""
    if reference_height(case) == float(case.line.height):
        return field.velocity(x, time)
    return field.velocity_at(x, np.zeros_like(x), time, np.full(x.size, float(case.line.height)))


def equal_span_downburst_both(case: Case, system: LineSystem,
                              time: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """An equal-span downburst's running-mean (v_x, v_y) [m/s] at the span nodes, each
    (n_t, n_spans, ne+1) (as :func:`mean_wind`), and at the global nodes, each (n_t, n_nodes) (as
    :func:`mean_speed_at_nodes`), from one evaluation of the field at the distinct stations of
    both sets (they differ in the last bit at some nodes of a single span).  The field is
    evaluated point by point, so the values are the same bits as evaluating each set (issue 20)."""
    time = np.atleast_1d(np.asarray(time, dtype=float))
    xs = span_node_x(system).ravel()
    xu, inv = np.unique(np.concatenate([xs, system.node_x0]), return_inverse=True)
    vx, vy = _equal_span_downburst(case, downburst_field(case), xu, time)
    span, node = inv[:xs.size], inv[xs.size:]
    shape = (time.size, system.n_spans, system.ne + 1)
    # np.take along the columns copies the same values as vx[:, span], 3-5x faster (≈ 35 ms of a
    # six-span downburst realization's four (12,001 x 64) gathers, issue 20)
    return (np.take(vx, span, axis=1).reshape(shape), np.take(vy, span, axis=1).reshape(shape),
            np.take(vx, node, axis=1), np.take(vy, node, axis=1))


def mean_wind(case: Case, system: LineSystem, times: np.ndarray | None = None) -> MeanWind:
    """Running-mean wind at the FE nodes at ``times`` [s].

    Synoptic: constant (``times`` default one instant t = 0).  Downburst: ``times``
    default ``analysis.mean_states`` instants over :func:`event_window`.
    Components per span node: ``normal`` along the span's horizontal normal n_i, ``longitudinal``
    along its horizontal direction (equal-span form: +y and +x).
    """
    if case.wind.type == "synoptic":
        t = np.zeros(1) if times is None else np.asarray(times, dtype=float)
        p = float(system.tower_x[case.line.tower_of_interest - 1])
        if _synoptic_plain(case, system):
            v = synoptic_span_speeds(case)
            normal = np.broadcast_to(v[:, None], (t.size, system.n_spans, system.ne + 1)).copy()
            return MeanWind(t, normal, np.zeros_like(normal), p)
        # issue 17: V(z) = v_span (z_agl/z_ref)^alpha at each span node's still-air height, direction
        # m = (sin d, cos d, 0); normal V m.n_i = V cos(d + h_i), longitudinal V m.e_i = V sin(d + h_i)
        idx = _span_node_index(system)
        speed = synoptic_span_speeds(case)[:, None] * profile_factor(case, system.node_height[idx])
        m = wind_direction_vector(case)
        cn = system.span_normals @ m  # (n_spans,)
        cl = _span_along(system) @ m
        shape = (t.size, system.n_spans, system.ne + 1)
        normal = np.broadcast_to(speed * cn[:, None], shape).copy()
        longitudinal = np.broadcast_to(speed * cl[:, None], shape).copy()
        c = system.clamp_points[case.line.tower_of_interest - 1]
        return MeanWind(t, normal, longitudinal, p, (float(c[0]), float(c[1])) if system.is_section else None)
    if times is None:
        t0, t1 = event_window(case)
        t = np.linspace(t0, t1, case.analysis.mean_states)
    else:
        t = np.atleast_1d(np.asarray(times, dtype=float))
    field = downburst_field(case)
    shape = (t.size, system.n_spans, system.ne + 1)
    if not system.is_section:
        xs = span_node_x(system)
        vx, vy = _equal_span_downburst(case, field, xs.ravel(), t)
        return MeanWind(t, vy.reshape(shape), vx.reshape(shape), field.point_p)
    # section form: the field at each span node's plan position and height, resolved on the span's
    # horizontal normal n_i and direction e_i (a tower node gets each adjacent span's components)
    idx = _span_node_index(system).ravel()
    vx, vy = _downburst_nodes(case, system, field, t)
    vx, vy = vx[:, idx], vy[:, idx]
    span = np.repeat(np.arange(system.n_spans), system.ne + 1)
    n, e = system.span_normals[span], _span_along(system)[span]
    normal = vx * n[None, :, 0] + vy * n[None, :, 1]
    longitudinal = vx * e[None, :, 0] + vy * e[None, :, 1]
    return MeanWind(t, normal.reshape(shape), longitudinal.reshape(shape), field.point_p, field.p_xy())


def _synoptic_node_speeds(case: Case, system: LineSystem) -> np.ndarray:
    """Synoptic speed at the global nodes [m/s], shape (n_nodes,); a shared tower node
    takes the average of its two spans."""
    v = synoptic_span_speeds(case)
    ne = system.ne
    node = np.repeat(v, ne)
    node = np.append(node, v[-1])
    inner = system.tower_nodes[1:-1]
    node[inner] = 0.5 * (v[:-1] + v[1:])
    return node


def mean_components_at_nodes(case: Case, system: LineSystem, time: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Running-mean (normal, longitudinal) components [m/s] at the global FE nodes, shape
    (n_steps, n_nodes) each: along ``system.node_normals`` (span nodes: the span's normal n_i;
    tower nodes: the tower frame's y) and along the node's horizontal along-line direction
    (the normal turned -90 deg in plan; tower nodes: the tower frame's x).

    This is the synoptic longitudinal component the fluctuating loads need (cos phi = |V_n|/|V|).
    """
    time = np.atleast_1d(np.asarray(time, dtype=float))
    if not system.is_section and case.wind.type == "downburst":
        vx, vy = _equal_span_downburst(case, downburst_field(case), system.node_x0, time)
        return vy, vx
    if case.wind.type == "synoptic" and _synoptic_plain(case, system):
        return mean_normal_at_nodes(case, system, time), np.zeros((time.size, system.n_nodes))
    u = mean_vector_at_nodes(case, system, time)
    n, e = system.node_normals, _node_along(system)
    return (u[..., 0] * n[None, :, 0] + u[..., 1] * n[None, :, 1],
            u[..., 0] * e[None, :, 0] + u[..., 1] * e[None, :, 1])


def mean_normal_at_nodes(case: Case, system: LineSystem, time: np.ndarray) -> np.ndarray:
    """Running-mean normal speed [m/s] at the global FE nodes, shape (n_steps, n_nodes): toward +y
    on the equal-span form, along ``system.node_normals`` on a section.

    Nodes at their still-air position.  Synoptic with ``span_speeds``: a
    tower node shared by two spans takes their average.
    """
    time = np.atleast_1d(np.asarray(time, dtype=float))
    if case.wind.type == "synoptic" and _synoptic_plain(case, system):
        return np.broadcast_to(_synoptic_node_speeds(case, system), (time.size, system.n_nodes)).copy()
    if case.wind.type == "downburst" and not system.is_section:
        return _equal_span_downburst(case, downburst_field(case), system.node_x0, time)[1]
    return mean_components_at_nodes(case, system, time)[0]


def mean_speed_at_nodes(case: Case, system: LineSystem, time: np.ndarray) -> np.ndarray:
    """Running-mean horizontal speed magnitude [m/s] at the global FE nodes, shape (n_steps, n_nodes)."""
    time = np.atleast_1d(np.asarray(time, dtype=float))
    if case.wind.type == "synoptic":
        if _synoptic_plain(case, system):
            return np.abs(mean_normal_at_nodes(case, system, time))
        return np.broadcast_to(np.abs(_synoptic_speed_nodes(case, system)), (time.size, system.n_nodes)).copy()
    if not system.is_section:
        vx, vy = _equal_span_downburst(case, downburst_field(case), system.node_x0, time)
    else:
        vx, vy = _downburst_nodes(case, system, downburst_field(case), time)
    return np.hypot(vx, vy)


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
