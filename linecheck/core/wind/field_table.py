"""User running-mean downburst fields: reading, validating and interpolating a table.

A user table (``[wind.downburst] field = "file.csv"`` or ``.npz``; format in ``docs/wind.md``)
gives the radial (and optionally vertical) running-mean velocity on a rectilinear
(r/D_j, z/D_j, t) grid.  :func:`load_field_table` reads and checks it (one-line
:class:`CaseError` naming the file, the line or array and what is allowed; bounded reads, a
size cap); :func:`table_slice` and :func:`table_points` interpolate it linearly (bilinear in
(r/D_j, t) at one height, trilinear with a height per point), refusing points outside the
table.  The field model that scales it is :mod:`linecheck.core.wind.downburst`.  Nothing
here prints.
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

from ..case import cell_text, read_regular_file, reads_as_header
from ..errors import CaseError

if TYPE_CHECKING:
    from scipy.interpolate import RegularGridInterpolator
# scipy.interpolate is imported where it is used: importing it costs ≈ 0.4 s, which
# `linecheck check` of a downburst case would otherwise pay

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


def field_error(path: Path, message: str, line: int | None = None) -> CaseError:
    """The one-line :class:`CaseError` of a field file: its path, the line when known, the message."""
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
        raise field_error(
            path, f"row repeats the grid point (r_over_dj, z_over_dj, t) = ({cols['r_over_dj'][again]:g}, "
            f"{cols['z_over_dj'][again]:g}, {cols['t'][again]:g}) of line {int(lines[first])}: "
            "each grid point must appear exactly once", line=int(lines[again]))
    seen[flat] = np.arange(flat.size)
    missing = np.nonzero(seen < 0)[0]
    if missing.size:
        m = int(missing[0])
        ir, rest = divmod(m, n_z * n_t)
        iz, it = divmod(rest, n_t)
        raise field_error(
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
        raise field_error(path, f"column r_over_dj has {r.size} distinct value(s): expected at least 2")
    if t.size < 2:
        raise field_error(path, f"column t has {t.size} distinct value(s): expected at least 2")
    if z.size < 1:
        raise field_error(path, "column z_over_dj has no values: expected at least 1")
    if r[0] < 0:
        raise field_error(path, f"column r_over_dj has value {r[0]:g}: expected r_over_dj >= 0")
    if z[0] < 0:
        raise field_error(path, f"column z_over_dj has value {z[0]:g}: expected z_over_dj >= 0")


MAX_FIELD_BYTES = 200 * 2**20  # [bytes] size cap of a field file (docs/wind.md, docs/case-files.md)


def _read_csv(path: Path) -> FieldTable:
    raw = read_regular_file(path, "a CSV running-mean field file", MAX_FIELD_BYTES)  # bounded read
    try:
        text = raw.decode("utf-8-sig")  # a leading byte-order mark (spreadsheets write one) is dropped
    except UnicodeDecodeError:
        raise field_error(path, "not a UTF-8 text file: expected a CSV running-mean field (see docs/wind.md)") from None
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
                raise field_error(path, f"not a field table: expected a comma-separated (CSV) file whose first "
                                   f"row names its columns, {_ALLOWED_TEXT} (see docs/wind.md)", line=lineno)
            for k, name in enumerate(fields, start=1):
                if name not in FIELD_COLUMNS:
                    raise field_error(path, f'header column {k} "{name}" is not allowed: expected {_ALLOWED_TEXT}',
                                       line=lineno)
                if fields.count(name) > 1:
                    raise field_error(path, f'header column "{name}" appears twice: expected each of {_ALLOWED_TEXT} once',
                                       line=lineno)
            for name in _REQUIRED_COLUMNS:
                if name not in fields:
                    raise field_error(path, f'header has no column "{name}": expected {_ALLOWED_TEXT}', line=lineno)
            continue
        if len(fields) != len(header):
            raise field_error(path, f"row has {len(fields)} values: expected {len(header)} ({', '.join(header)})",
                               line=lineno)
        row = []
        for name, value in zip(header, fields):
            try:
                v = float(value)
            except ValueError:
                raise field_error(path, f'column "{name}": value {cell_text(value)} is not a number: expected a '
                                   "finite number", line=lineno) from None
            if not math.isfinite(v):
                raise field_error(path, f'column "{name}": value "{value}" is not allowed: expected a finite number',
                                   line=lineno)
            if name in ("r_over_dj", "z_over_dj") and v < 0:
                raise field_error(path, f'column "{name}": value {value} is out of range: expected {name} >= 0',
                                   line=lineno)
            row.append(v)
        rows.append(row)
        lines.append(lineno)
    if header is None:
        raise field_error(path, f"no header line: expected a header with {_ALLOWED_TEXT}")
    if not rows:
        raise field_error(path, "header but no data rows: expected one row per (r_over_dj, z_over_dj, t) grid point",
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
    raise field_error(path, f'array "{name}" has dtype {a.dtype} ({what}): expected real numbers '
                       "(a floating-point array, or integers)")


def _read_npz(path: Path) -> FieldTable:
    try:
        with np.load(path, allow_pickle=False) as npz:
            # uncompressed size of the members checked before any is read (a zip bomb)
            inflated = sum(info.file_size for info in npz.zip.infolist())
            if inflated > MAX_FIELD_BYTES:
                raise field_error(path, f"arrays of {inflated / 2**20:.0f} MB uncompressed are too large: expected "
                                   f"at most {MAX_FIELD_BYTES / 2**20:.0f} MB")
            arrays = {k: np.asarray(npz[k]) for k in npz.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError) as exc:
        # BadZipFile: a file that starts like a zip archive ("PK\x03\x04...") but is not one;
        # NotImplementedError: a member compressed with a method zipfile cannot read
        reason = " ".join(str(exc).split()) or type(exc).__name__
        raise field_error(path, f"not a readable NPZ file ({reason}): expected a zip archive of arrays "
                           f"{_ALLOWED_TEXT} (numpy.savez)") from None
    for name in arrays:
        if name not in FIELD_COLUMNS:
            raise field_error(path, f'array "{name}" is not allowed: expected {_ALLOWED_TEXT}')
    for name in _REQUIRED_COLUMNS:
        if name not in arrays:
            raise field_error(path, f'array "{name}" is missing: expected {_ALLOWED_TEXT}')
    axes = []
    for name in ("r_over_dj", "z_over_dj", "t"):
        a = arrays[name]
        _check_real(path, name, a)
        if a.ndim != 1:
            raise field_error(path, f'array "{name}" has shape {a.shape}: expected a 1-D array of numbers')
        a = a.astype(float)
        if not np.all(np.isfinite(a)):
            raise field_error(path, f'array "{name}" has a non-finite value: expected finite numbers')
        if a.size > 1 and not np.all(np.diff(a) > 0):
            k = int(np.nonzero(np.diff(a) <= 0)[0][0]) + 1
            raise field_error(path, f'array "{name}" entry {k} ({a[k]:g}) is not above the previous one: '
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
            raise field_error(path, f'array "{name}" has shape {a.shape}: expected numbers of shape '
                               f"(len(r_over_dj), len(z_over_dj), len(t)) = {shape}")
        a = a.astype(float)
        if not np.all(np.isfinite(a)):
            i = tuple(int(v) for v in np.argwhere(~np.isfinite(a))[0])
            raise field_error(path, f'array "{name}" entry {i} is not finite: expected finite numbers')
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
    raise field_error(p, f'file type "{p.suffix}" is not allowed: expected a .csv or .npz running-mean field '
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
        raise field_error(p, "field file not found (expected a CSV or NPZ running-mean field, see docs/wind.md)") from None
    except OSError as exc:
        raise field_error(p, f"cannot read field file: {exc.strerror}") from None
    if not p.is_file():
        raise field_error(p, "is not a regular file: expected a CSV or NPZ running-mean field")
    if st.st_size > MAX_FIELD_BYTES:
        raise field_error(p, f"file size {st.st_size / 2**20:.0f} MB is too large: expected at most "
                           f"{MAX_FIELD_BYTES / 2**20:.0f} MB (a CSV or NPZ running-mean field)")
    return _load_cached(str(p.resolve()), st.st_mtime_ns, st.st_size)


class SliceInterpolator:
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
                raise field_error(path, f"the line reaches r/D_j from {lo:.4g} to {hi:.4g} but the table covers "
                                   f"r_over_dj {self.r[0]:g} to {self.r[-1]:g}: extend the table")
            lo, hi = float(tt.min()), float(tt.max())
            if lo < self.t[0] - tol_t or hi > self.t[-1] + tol_t:
                raise field_error(path, f"times {lo:.6g} to {hi:.6g} s are needed but the table covers t "
                                   f"{self.t[0]:g} to {self.t[-1]:g} s: extend the table or shorten analysis.duration")


@lru_cache(maxsize=32)
def _table_slice_cached(table: FieldTable, z: float, vertical: bool) -> SliceInterpolator:
    """The table linearly interpolated to one height z/D_j [-] (a single-height table as is)."""
    values = table.vertical if vertical else table.radial
    if table.z.size == 1:
        sl = values[:, 0, :]
    else:
        if z < table.z[0] - 1e-12 or z > table.z[-1] + 1e-12:
            raise field_error(table.path, f"the conductor height is z/D_j = {z:.4g} but the table covers z_over_dj "
                               f"{table.z[0]:g} to {table.z[-1]:g}: extend the table")
        from scipy.interpolate import RegularGridInterpolator

        rgi = RegularGridInterpolator((table.r, table.z, table.t), values, method="linear")
        rr, tt = np.meshgrid(table.r, table.t, indexing="ij")
        zz = np.full_like(rr, min(max(z, table.z[0]), table.z[-1]))
        sl = rgi(np.stack([rr, zz, tt], axis=-1))
    return SliceInterpolator(table.r, table.t, sl)


def table_slice(table: FieldTable, z: float, vertical: bool = False) -> SliceInterpolator:
    """Interpolator of the table's radial (or vertical) velocity in (r/D_j, t) at height z/D_j = ``z`` [-]
    (cached per table, height and component)."""
    return _table_slice_cached(table, float(z), vertical)


@lru_cache(maxsize=16)
def _table_volume(table: FieldTable) -> RegularGridInterpolator:
    """Trilinear interpolator of the radial velocity on the (r/D_j, z/D_j, t) grid (cached per table)."""
    from scipy.interpolate import RegularGridInterpolator

    return RegularGridInterpolator((table.r, table.z, table.t), table.radial, method="linear")


def table_points(table: FieldTable, rr: np.ndarray, zz: np.ndarray, tt: np.ndarray) -> np.ndarray:
    """Radial table speed at (r/D_j, z/D_j, t) per point (broadcast shapes): trilinear
    interpolation (the same as the per-height slices of :func:`table_slice`), with the same
    range checks; a table with one height has no z dependence."""
    rr, zz, tt = np.broadcast_arrays(rr, zz, tt)
    if table.z.size == 1:
        return table_slice(table, float(table.z[0]))(rr, tt, table.path)
    if zz.size:
        lo, hi = float(zz.min()), float(zz.max())
        if lo < table.z[0] - 1e-12 or hi > table.z[-1] + 1e-12:
            raise field_error(table.path, f"the conductor heights reach z/D_j from {lo:.4g} to {hi:.4g} but the "
                               f"table covers z_over_dj {table.z[0]:g} to {table.z[-1]:g}: extend the table")
    # r and t checks of the slice interpolator (same messages)
    table_slice(table, float(table.z[0])).check(rr, tt, table.path)
    pts = np.stack([np.clip(rr, table.r[0], table.r[-1]).ravel(), np.clip(zz, table.z[0], table.z[-1]).ravel(),
                    np.clip(tt, table.t[0], table.t[-1]).ravel()], axis=-1)
    return _table_volume(table)(pts).reshape(rr.shape)
