"""Critical-downburst scan: step 1 over a grid of downburst positions and sizes.

The paper's Db_x / Db_y configurations come from such a scan (El Damatty et al. 2013):
for each reaction at the tower of interest, the downburst configuration -- distance
R [m] from the tower to the centre, angle Theta [deg] from the perpendicular to the
line (paper Fig. 2), jet diameter D_j [m] -- giving the largest magnitude of the
wind-induced mean reaction over the event,
``max_t |service.static_analysis(case).mean.reactions_wind[t, tower, comp]|``.

Each grid point is the case with its ``[wind.downburst]`` preset dropped and
``distance``, ``angle``, ``jet_diameter`` set (:func:`~.tasks.scan_changes`; every
other key, e.g. an explicit ``r_max``, is kept; keys left to their default follow
D_j).

Storm strength (``hold``): a case's V_ref is the running-mean speed at point p, so
keeping V_ref while moving the storm would make the storm stronger wherever p falls in
weak outflow (near the centre) -- the scan would then favour degenerate positions.
By default (``hold="jet"``) every configuration is the *same storm*: V_max of the
field is held at its value for the case's own configuration (e.g. its preset), as in a
scan of one CFD downburst (El Damatty et al. 2013); the V_ref at p that this implies
is reported per point.  ``hold="vref"`` keeps the case's V_ref at p instead.  Points run on the batch executors (:func:`~.tasks.scan_chunk`); a point whose
analysis fails (e.g. no outflow reaches the line) is reported and left out.
``run_critical`` then runs the full three-step analysis at the critical
configurations through :func:`~.runner.run_batch`.  No UI imports.
"""

from __future__ import annotations

import csv
import io
import math
import re
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..core.case import Case, case_hash, load_case
from ..core.errors import Cancelled, CaseError, LinecheckError
from ..core.results import REACTIONS
from .executors import Executor, SequentialExecutor
from .report import BatchProgress, BatchReport, RunJob
from .runner import run_batch
from .scheduler import POLL_S
from .tasks import Failure, ScanChunk, scan_changes, scan_chunk

MAX_POINTS = 1_000_000
DEFAULT_DISTANCE = "0.5:2.5:0.1Dj"
DEFAULT_ANGLE = "-80:80:10"
HOLDS = ("jet", "vref")
#: A number with an optional unit: "720", "720m", "1.2Dj", "1.2 D_j", "1.2*Dj".
_NUMBER = re.compile(r"^\s*(?P<num>[^:,]*?)\s*(?:(?P<dj>\*?\s*d_?j)|(?P<m>m))?\s*$", re.IGNORECASE)
#: The units of the scan's options: a length in metres ("m") or in multiples of the jet diameter ("Dj").
UNIT_WORDS = {"m": "m (metres)", "Dj": "Dj (multiples of the jet diameter)"}


#: the forms a scan option's value may take
VALUE_FORMS = "START:STOP:STEP (STOP included), a comma-separated list or a number"
#: examples of the lengths in messages, per option
_EXAMPLES = {"--distance": "720m; 1.2Dj; 1.2Dj,1.6Dj; 0.5:2.5:0.1Dj",
             "--jet-diameter": "600m; 600m,900m; 600:900:100m"}


def parse_values(text: str, option: str, units: tuple[str, ...] = ()) -> tuple[tuple[float, ...], bool]:
    """Values of a scan option: ``A:B:STEP`` (B included), a comma list or one number.

    ``units``: the units the option allows, of ``"m"`` and ``"Dj"`` (lengths); every value
    then needs one -- after every number (``1.2Dj,1.6Dj``, ``600m:900m:100m``) or once after
    the last, for all of them (``0.5:2.5:0.1Dj``, ``600,900m``); a bare number, two units or
    a unit the option does not take is refused.  Empty ``units``: plain numbers (degrees).
    Returns (values, relative: in multiples of D_j).  Raises CaseError (exit 2) on bad text,
    one line naming the option, the value and what is allowed.
    """
    spec = _OptionText(option, text, units)
    raw = text.strip()
    sep = ":" if ":" in raw else ","
    tokens = ([p for p in raw.split(sep) if p.strip()] if sep == "," else raw.split(sep)) if raw else []
    if not tokens:
        raise CaseError(f"{option}: empty value: expected {spec.expected}")
    nums, found = _numbers(tokens, spec)
    unit = _common_unit(found, spec)
    values = _range(nums, spec) if sep == ":" else tuple(nums)
    return values, unit == "Dj"


@dataclass(frozen=True)
class _OptionText:
    """The text of one scan option being parsed, and the wording of its error messages."""

    option: str
    text: str
    units: tuple[str, ...]

    @property
    def allowed(self) -> str:
        return " or ".join(UNIT_WORDS[u] for u in self.units)

    @property
    def example(self) -> str:
        return _EXAMPLES.get(self.option, "; ".join(f"1.2{u}" for u in self.units))

    @property
    def expected(self) -> str:
        if not self.units:
            return VALUE_FORMS
        return (f"{VALUE_FORMS}, in {self.allowed}: a unit after every number, or once after the last for all "
                f"of them (e.g. {self.example})")

    def refuse(self, why: str) -> CaseError:
        return CaseError(f"{self.option}: value {self.text!r} is not allowed: {why}")


def _numbers(tokens: list[str], spec: _OptionText) -> tuple[list[float], list[str]]:
    """The finite numbers of ``tokens`` and the unit written after each (``""``: none)."""
    nums, found = [], []
    for tok in tokens:
        mt = _NUMBER.match(tok)
        if mt is None:
            raise spec.refuse(f"expected {spec.expected}")
        found.append("Dj" if mt["dj"] else "m" if mt["m"] else "")
        try:
            v = float(mt["num"])
        except ValueError:
            raise spec.refuse(f"expected {spec.expected}") from None
        if not math.isfinite(v):
            raise spec.refuse("expected finite numbers")
        nums.append(v)
    return nums, found


def _common_unit(found: list[str], spec: _OptionText) -> str:
    """The one unit of all the values (``""`` for plain numbers); CaseError when the units
    written do not fit the option (see :func:`parse_values`)."""
    given = {u for u in found if u}
    eg, allowed = spec.example, spec.allowed
    if not spec.units:
        if given:
            raise spec.refuse(f"expected plain numbers, {VALUE_FORMS} (no unit)")
        return ""
    if not given:
        raise spec.refuse(f"a length needs its unit, {allowed} (e.g. {eg}; one unit after the last number "
                          "applies to all)")
    if len(given) > 1:
        raise spec.refuse(f"one unit for every number ({' and '.join(sorted(given))} given; e.g. {eg})")
    (unit,) = given
    if unit not in spec.units:
        raise spec.refuse(f"{spec.option} takes {allowed}, not {unit} (e.g. {eg})")
    if not (all(found) or (found[-1] and not any(found[:-1]))):
        raise spec.refuse(f"a unit after every number, or once after the last for all of them (e.g. {eg})")
    return unit


def _range(nums: list[float], spec: _OptionText) -> tuple[float, ...]:
    """The values of ``START:STOP:STEP`` (STOP included, at most :data:`MAX_POINTS`)."""
    if len(nums) != 3:
        raise spec.refuse(f"expected {spec.expected}")
    a, b, step = nums
    if step == 0 or (b - a) * step < 0:
        raise spec.refuse("STEP must be non-zero and go from A toward B")
    n = int(math.floor((b - a) / step + 1e-9)) + 1
    if n > MAX_POINTS:
        raise CaseError(f"{spec.option}: value {spec.text!r} gives {n} values: expected at most {MAX_POINTS}")
    return tuple(float(round(a + i * step, 10)) for i in range(n))


@dataclass(frozen=True)
class ScanGrid:
    """Downburst configurations to scan.

    distances: R values [m], or multiples of D_j when ``distance_relative``;
    angles: Theta [deg]; jet_diameters: D_j [m].
    """

    distances: tuple[float, ...]
    angles: tuple[float, ...]
    jet_diameters: tuple[float, ...]
    distance_relative: bool = False

    @classmethod
    def from_options(cls, case: Case, distance: str | None = None, angle: str | None = None,
                     jet_diameter: str | None = None) -> ScanGrid:
        """The grid of the CLI options; defaults: R = 0.5..2.5 D_j by 0.1 D_j,
        Theta = -80..80 deg by 10 deg (at +-90 deg the centre is on the line and V_ref at p
        is undefined), D_j of the case."""
        db = case.wind.downburst
        if case.wind.type != "downburst" or db is None:
            raise CaseError('wind.type: a scan needs a downburst case (type = "downburst")',
                            file=str(case.source) if case.source else None)
        dist, rel = parse_values(distance or DEFAULT_DISTANCE, "--distance", ("m", "Dj"))
        ang, _ = parse_values(angle or DEFAULT_ANGLE, "--angle")  # degrees, plain numbers
        if jet_diameter is None:
            dj: tuple[float, ...] = (float(db.jet_diameter),)
        else:
            dj, _ = parse_values(jet_diameter, "--jet-diameter", ("m",))
        for v in dj:
            if v <= 0:
                raise CaseError(f"--jet-diameter: value {v:g} is out of range: expected D_j > 0 m")
        for v in dist:
            if v < 0:
                raise CaseError(f"--distance: value {v:g} is out of range: expected R >= 0")
        for v in ang:
            if not -180.0 <= v <= 180.0:
                raise CaseError(f"--angle: value {v:g} is out of range: expected -180 to 180 deg")
        grid = cls(dist, ang, dj, rel)
        if grid.size > MAX_POINTS:
            raise CaseError(f"scan grid has {grid.size} points: expected at most {MAX_POINTS}")
        return grid

    @property
    def size(self) -> int:
        return len(self.distances) * len(self.angles) * len(self.jet_diameters)

    def points(self) -> np.ndarray:
        """(n, 3) array of (R [m], Theta [deg], D_j [m]); D_j outermost, Theta innermost."""
        out = []
        for dj in self.jet_diameters:
            for r in self.distances:
                for th in self.angles:
                    out.append((r * dj if self.distance_relative else r, th, dj))
        return np.array(out, dtype=float).reshape(-1, 3)


# --------------------------------------------------------------------------- results
@dataclass(frozen=True)
class Critical:
    """The configuration giving the largest |mean| of one reaction.

    value: [N] the signed wind-induced mean reaction there; time: [s] its instant;
    v_ref: [m/s] running-mean speed at point p in that configuration (scan's storm).
    """

    reaction: str
    index: int
    distance: float
    angle: float
    jet_diameter: float
    value: float
    time: float
    v_ref: float = math.nan

    @property
    def distance_over_dj(self) -> float:
        return self.distance / self.jet_diameter

    def changes(self) -> dict[str, Any]:
        """Case key changes that set this configuration (preset dropped)."""
        return scan_changes(self.distance, self.angle, self.jet_diameter)


@dataclass(frozen=True)
class ScanResult:
    """Step-1 results over a scan grid.

    Attributes:
        case: the scanned case (as in its file); case_path: its file.
        points: (n, 3) of (R [m], Theta [deg], D_j [m]).
        peak: [N] signed wind-induced mean reaction with the largest |.| over the event at
            the tower of interest, (n, 3) for (Rx, Ry, Rz); NaN where the point failed.
        time: [s] instant of that value, (n, 3).
        v_ref: [m/s] running-mean speed at point p of each configuration, (n,).
        errors: per point, None or its error message.
        hold: ``"jet"`` (V_max held at ``v_max`` [m/s]) or ``"vref"`` (V_ref at p held).
        elapsed: [s] wall time; executor: description of where it ran.
    """

    case: Case
    case_path: Path
    points: np.ndarray
    peak: np.ndarray
    time: np.ndarray
    v_ref: np.ndarray
    errors: tuple[str | None, ...]
    hold: str = "jet"
    v_max: float | None = None
    elapsed: float = 0.0
    executor: str = ""
    model: str | None = None  # downburst running-mean model scanned; None: the case's own
    dynamic: np.ndarray | None = None  # [N] expected dynamic peak |M+B+R| per point (n, 3), with dynamic_realizations
    dynamic_realizations: int = 0  # realizations behind ``dynamic``

    @property
    def n_failed(self) -> int:
        return sum(e is not None for e in self.errors)

    def critical(self, reaction: str | int, by: str = "mean") -> Critical | None:
        """The point with the largest |peak| of ``reaction`` (``"Rx"``/0, ``"Ry"``/1, ``"Rz"``/2).

        ``by="mean"``: the largest wind-induced mean (step 1); ``by="peak"``: the largest expected
        dynamic peak (a scan with ``dynamic_realizations``; its ``value`` is that peak, its
        ``time`` the instant of the point's largest mean)."""
        c = REACTIONS.index(reaction) if isinstance(reaction, str) else int(reaction)
        if by == "peak":
            if self.dynamic is None:
                return None
            mag = np.abs(self.dynamic[:, c])
        else:
            mag = np.abs(self.peak[:, c])
        if not np.any(np.isfinite(mag)):
            return None
        i = int(np.nanargmax(mag))  # first point on ties (grid order)
        r, th, dj = self.points[i]
        value = self.dynamic[i, c] if by == "peak" else self.peak[i, c]
        return Critical(REACTIONS[c], i, float(r), float(th), float(dj), float(value), float(self.time[i, c]),
                        float(self.v_ref[i]))

    def centre_offsets(self) -> np.ndarray:
        """[m] each point's downburst centre relative to the tower of interest in the global frame
        (x along the first span, y to its left), (n, 2): R sin(Theta) x' - R cos(Theta) y' with
        (x', y') the tower's own frame ((R sin Theta, -R cos Theta) where that is the global frame)."""
        from ..core.system import LineSystem

        psi = float(LineSystem(self.case.line).tower_headings[self.case.line.tower_of_interest - 1])
        r, th = self.points[:, 0], np.radians(self.points[:, 1])
        a, b = r * np.sin(th), -r * np.cos(th)
        return np.stack([a * np.cos(psi) - b * np.sin(psi), a * np.sin(psi) + b * np.cos(psi)], axis=1)

    def criticals(self, reactions: Sequence[str] = ("Rx", "Ry"), by: str = "mean") -> list[Critical]:
        return [c for c in (self.critical(r, by) for r in reactions) if c is not None]


def scan_csv_text(result: ScanResult) -> str:
    """CSV of every scan point (SI units; empty cells where a point failed)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    dyn = result.dynamic
    extra = ["Rx_peak_N", "Ry_peak_N", "Rz_peak_N"] if dyn is not None else []
    offsets = result.centre_offsets()
    w.writerow(["jet_diameter_m", "distance_m", "distance_over_dj", "angle_deg", "v_ref_at_p_m_s",
                "Rx_N", "Ry_N", "Rz_N", "t_Rx_s", "t_Ry_s", "t_Rz_s", *extra, "centre_dx_m", "centre_dy_m", "error"])

    def f(x: float) -> str:
        return "" if not math.isfinite(x) else repr(float(x))

    for i, (r, th, dj) in enumerate(result.points):
        more = [f(v) for v in dyn[i]] if dyn is not None else []
        w.writerow([repr(float(dj)), repr(float(r)), f(r / dj), repr(float(th)), f(result.v_ref[i]),
                    *(f(v) for v in result.peak[i]), *(f(v) for v in result.time[i]), *more,
                    f(offsets[i, 0]), f(offsets[i, 1]), result.errors[i] or ""])
    return buf.getvalue()


def write_scan_csv(result: ScanResult, path: str | Path, *, force: bool = True) -> Path:
    """Write :func:`scan_csv_text` atomically."""
    from ..io.atomic import write_text_atomic

    return write_text_atomic(path, scan_csv_text(result), force=force, what="CSV")


# --------------------------------------------------------------------------- running
def default_scan_chunk(n_points: int, workers: int) -> int:
    """Points per task: about four tasks per worker, at most 25 points (results do not depend on it)."""
    return max(1, min(25, math.ceil(n_points / (4 * max(1, workers)))))


def _raise_failure(f: Failure) -> None:
    if f.exit_code == 130:
        raise Cancelled(f.message)
    if f.exit_code == 2:
        raise CaseError(f.message)
    err = LinecheckError(f.message)
    raise err


def run_scan(
    case_path: str | Path,
    grid: ScanGrid,
    *,
    executor: Executor | None = None,
    hold: str = "jet",
    chunk_size: int | None = None,
    progress: Callable[[str, int, int], None] | None = None,
    cancel: threading.Event | None = None,
    model: str | None = None,
    dynamic_realizations: int = 0,
    warn: Callable[[str], None] | None = None,
) -> ScanResult:
    """Step 1 at every grid point of ``grid`` for the case in ``case_path``.

    ``model``: scan under this downburst running-mean model (``None``: the case's own).
    ``dynamic_realizations``: k > 0 runs steps 1-3 with realizations 0..k-1 at every point too,
    so that positions are ranked by the expected dynamic peak (``critical(r, "peak")``).

    Args:
        hold: ``"jet"`` (default): one storm, V_max held at its value for the case's own
            configuration; ``"vref"``: every configuration keeps the case's V_ref at p.
        executor: where points run (default sequential, in this process); not closed here.
        chunk_size: points per task (default :func:`default_scan_chunk`).
        progress: ``progress("scan", points_done, points_total)``: once before any task is
            submitted, then as points finish (per point in this process, per chunk elsewhere).
        cancel: a threading.Event; when set the scan stops with :class:`Cancelled`.
        warn: ``warn(message)`` gets the resource guard's warning (:func:`scan_estimate`: above
            half the memory limit, or longer than about 10 minutes).

    Raises:
        CaseError: the case is not a valid downburst case, or one position is estimated above
            the memory limit (before anything runs).  Cancelled.  LinecheckError when a worker
            crashed.
    """
    t0 = time.perf_counter()
    executor = executor or SequentialExecutor()
    path = Path(case_path)
    case, v_max = _scan_case(path, hold, model)
    digest = case_hash(path)
    scan_estimate(case, grid.size, dynamic_realizations=dynamic_realizations, workers=executor.workers, warn=warn)
    pts = grid.points()
    n = pts.shape[0]
    size = chunk_size or default_scan_chunk(n, executor.workers)
    if progress is not None:
        progress("scan", 0, n)
    submit = _PointSubmitter(executor, str(path), digest, v_max, n, cancel, progress, model, dynamic_realizations)
    handles = [submit(pts, a, size) for a in range(0, n, size)]
    table = _ScanTable.empty(n, dynamic_realizations > 0)
    _collect_points(executor, handles, table, progress, cancel)
    return ScanResult(case, path, pts, table.peak, table.time, table.v_ref, tuple(table.errors), hold, v_max,
                      time.perf_counter() - t0, executor.describe(), model, table.dynamic, int(dynamic_realizations))


def _scan_case(path: Path, hold: str, model: str | None) -> tuple[Case, float | None]:
    """The case to scan (under ``model`` if given) and, for ``hold="jet"``, the V_max [m/s] of
    its own configuration's field; CaseError for a case that is not a downburst or a bad ``hold``."""
    case = load_case(path)
    if case.wind.type != "downburst" or case.wind.downburst is None:
        raise CaseError('wind.type: a scan needs a downburst case (type = "downburst")', file=str(path))
    if hold not in HOLDS:
        raise CaseError(f"--hold: value {hold!r} is not allowed: expected one of {', '.join(HOLDS)}")
    if model is not None:
        from ..service import case_with_model

        case = case_with_model(case, model)
    v_max = None
    if hold == "jet":
        from ..core.wind.mean import downburst_field

        v_max = float(downburst_field(case).v_max)  # CaseError if the case's own configuration is invalid
    return case, v_max


@dataclass(frozen=True)
class _PointSubmitter:
    """Submits the scan's chunks of points (:func:`~.tasks.scan_chunk`) to the executor;
    ``n``: the number of points, for per-point progress in this process."""

    executor: Executor
    path: str
    digest: str
    v_max: float | None
    n: int
    cancel: threading.Event | None
    progress: Callable[[str, int, int], None] | None
    model: str | None
    dynamic_realizations: int

    def __call__(self, pts: np.ndarray, a: int, size: int) -> Any:
        """Submit points ``a`` to ``a + size`` of ``pts``; returns the handle."""
        ex, progress, n = self.executor, self.progress, self.n
        chunk = [tuple(map(float, p)) for p in pts[a:a + size]]
        kwargs: dict[str, Any] = {"cancel": self.cancel} if ex.in_process and self.cancel is not None else {}
        if ex.in_process and progress is not None:  # per point: a chunk of --dynamic positions is long
            kwargs["progress"] = lambda i: progress("scan", a + i, n)
        if self.model is not None:
            kwargs["model"] = self.model
        if self.dynamic_realizations > 0:
            kwargs["dynamic_realizations"] = int(self.dynamic_realizations)
        return ex.submit(scan_chunk, self.path, chunk, a, self.digest, self.v_max, **kwargs)


@dataclass
class _ScanTable:
    """The scan's results as its chunks come in (NaN where a point is not in or failed); units
    as in :class:`ScanResult`."""

    peak: np.ndarray
    time: np.ndarray
    v_ref: np.ndarray
    dynamic: np.ndarray | None
    errors: list[str | None]
    done: int = 0  # points in

    @classmethod
    def empty(cls, n: int, dynamic: bool) -> _ScanTable:
        return cls(np.full((n, 3), np.nan), np.full((n, 3), np.nan), np.full(n, np.nan),
                   np.full((n, 3), np.nan) if dynamic else None, [None] * n)

    def add(self, value: ScanChunk) -> None:
        a, m = value.start, value.peak.shape[0]
        self.peak[a:a + m] = value.peak
        self.time[a:a + m] = value.time
        self.v_ref[a:a + m] = value.v_ref
        if self.dynamic is not None and value.dynamic is not None:
            self.dynamic[a:a + m] = value.dynamic
        self.errors[a:a + m] = list(value.errors)
        self.done += m


def _collect_points(executor: Executor, handles: list[Any], table: _ScanTable,
                    progress: Callable[[str, int, int], None] | None, cancel: threading.Event | None) -> None:
    """Wait for every chunk and put it in ``table``; on a failed chunk (raised as its error),
    cancellation or Ctrl-C the chunks still pending are aborted."""
    n = len(table.errors)
    pending = list(range(len(handles)))
    try:
        while pending:
            if cancel is not None and cancel.is_set():
                raise Cancelled("scan cancelled")
            idx = executor.wait([handles[i] for i in pending], timeout=POLL_S)
            finished = [pending[i] for i in idx]
            for h in finished:
                value = executor.outcome(handles[h])
                if isinstance(value, Failure):
                    _raise_failure(value)
                if not isinstance(value, ScanChunk):  # pragma: no cover - an executor bug
                    raise TypeError(f"scan task returned {type(value).__name__}, expected ScanChunk")
                table.add(value)
                if progress is not None:
                    progress("scan", table.done, n)
            fs = set(finished)
            pending = [i for i in pending if i not in fs]
    except BaseException:
        executor.abort([handles[i] for i in pending])
        raise


def scan_estimate(case: Case, points: int, *, dynamic_realizations: int = 0, workers: int = 1,
                  warn: Callable[[str], None] | None = None) -> Any:
    """The resource guard of a scan (:func:`linecheck.core.budget.estimate_scan`): CaseError
    (exit 2) when one position is above the memory limit; ``warn(message)`` above half of it or
    when the scan is estimated to take longer than about 10 minutes on ``workers``; CaseError for a
    case with ``[[wires]]`` (:func:`~linecheck.analysis.guard.require_one_wire`)."""
    from ..analysis.guard import require_one_wire
    from ..core import budget

    require_one_wire(case, "scan")
    return budget.check(budget.estimate_scan(case, points, dynamic_realizations=dynamic_realizations,
                                             workers=workers), case, warn)


def critical_groups(result: ScanResult, reactions: Sequence[str] = ("Rx", "Ry"),
                    by: str | None = None) -> list[tuple[tuple[float, float, float], list[Critical]]]:
    """The distinct critical configurations (R, Theta, D_j) of a scan, each with the criticals
    that share it, in the order of :func:`critical_jobs`'s runs; ``by`` as there."""
    by = by or ("peak" if result.dynamic is not None else "mean")
    groups: dict[tuple[float, float, float], list[Critical]] = {}
    for c in result.criticals(reactions, by):
        groups.setdefault((c.distance, c.angle, c.jet_diameter), []).append(c)
    return list(groups.items())


def critical_jobs(result: ScanResult, reactions: Sequence[str] = ("Rx", "Ry"), by: str | None = None) -> list[RunJob]:
    """One run per distinct critical configuration (reactions sharing one are grouped);
    ``by``: "mean" or "peak" (default: "peak" when the scan has dynamic peaks, else "mean")."""
    stem = result.case_path.stem
    jobs = []
    for (r, th, dj), crits in critical_groups(result, reactions, by):
        names = [c.reaction for c in crits]
        tag = "-".join(names)
        changes = {"name": f"{result.case.name} critical {', '.join(names)}", **scan_changes(r, th, dj)}
        suffix = ""
        if result.model is not None:
            from ..service import model_changes

            changes.update(model_changes(result.case, result.model))
            changes["name"] += f" [{result.model}]"
            suffix = f".{result.model}"
        jobs.append(RunJob(result.case_path, label=changes["name"], changes=changes,
                           json_name=f"{stem}-critical-{tag}{suffix}.json"))
    return jobs


def run_critical(
    result: ScanResult,
    *,
    reactions: Sequence[str] = ("Rx", "Ry"),
    executor: Executor | None = None,
    json_dir: str | Path | None = None,
    keep_results: bool = False,
    progress: BatchProgress | None = None,
    cancel: threading.Event | None = None,
) -> BatchReport:
    """Full three-step analysis (all realizations) at the critical configurations of a scan.

    Each run keeps the case's own V_ref at point p (the design speed, as the paper's
    Db_x/Db_y cases do); only the geometry comes from the scan.
    """
    return run_batch(critical_jobs(result, reactions), executor=executor, json_dir=json_dir,
                     keep_results=keep_results, progress=progress, cancel=cancel)
