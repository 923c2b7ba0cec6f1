"""Worker functions: top-level, importable, plain data in, picklable results out.

They run in the coordinating process (sequential executor), in a local process
pool or on Dask workers, so they take a case *file path* (a string: workers load
the file themselves -- on a cluster it must be on a shared file system), the
realization indices or scan points, and an optional ``changes`` mapping of dotted
case keys to values applied on top of the file (``{"wind.downburst.distance": 720.0}``).

Errors the user can act on (:class:`~linecheck.core.errors.LinecheckError`: bad
file, non-convergence, numerical failure) are returned as a :class:`Failure`
value instead of raised, so one bad case never poisons a pool and the message
crosses process boundaries intact.  Nothing here prints or imports a UI library.
"""

from __future__ import annotations

import signal
import threading
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..core.case import Case, case_hash, load_case, with_values
from ..core.errors import Cancelled, CaseError, LinecheckError

@dataclass(frozen=True)
class Failure:
    """A task that ended with a user-facing error.

    Attributes:
        kind: the error class name (``CaseError``, ``ConvergenceError``, ...).
        message: its one-line message.
        exit_code: the error's exit code when run alone (2 bad input, 1 otherwise).
    """

    kind: str
    message: str
    exit_code: int = 1

    @classmethod
    def of(cls, err: BaseException) -> Failure:
        if isinstance(err, LinecheckError):
            return cls(type(err).__name__, str(err), err.exit_code)
        return cls(type(err).__name__, f"internal error: {type(err).__name__}: {err}", 1)


def apply_changes(case: Case, changes: Mapping[str, Any] | None) -> Case:
    """A validated copy of ``case`` with several dotted keys set at once (``None`` removes a key).

    :func:`linecheck.core.case.with_values`: same validation and messages as the file
    loader.  Setting them together matters for downburst geometry: a ``preset`` must be
    removed in the same edit that sets ``distance``/``angle``/``jet_diameter``.
    """
    return with_values(case, dict(changes)) if changes else case


def scan_changes(distance: float, angle: float, jet_diameter: float) -> dict[str, Any]:
    """The ``changes`` of one downburst scan point (drops any preset)."""
    return {
        "wind.downburst.preset": None,
        "wind.downburst.distance": float(distance),
        "wind.downburst.angle": float(angle),
        "wind.downburst.jet_diameter": float(jet_diameter),
    }


def load_checked(case_path: str | Path, expected_hash: str | None = None,
                 changes: Mapping[str, Any] | None = None) -> Case:
    """Load a case file on a worker; with ``expected_hash`` refuse a file changed since submission."""
    if expected_hash is not None:
        try:
            actual = case_hash(case_path)
        except OSError as exc:
            raise CaseError(f"cannot read on the worker: {exc.strerror} (is the file on a shared file system?)",
                            file=str(case_path)) from None
        if actual != expected_hash:
            raise CaseError("file changed while the batch was running; run it again", file=str(case_path))
    return apply_changes(load_case(case_path), changes)


def run_chunk(
    case_path: str,
    realizations: Sequence[int],
    expected_hash: str | None = None,
    changes: Mapping[str, Any] | None = None,
    *,
    progress: Callable[[str, int, int], None] | None = None,
    cancel: threading.Event | None = None,
) -> Any:
    """Steps 1-3 of one case for a subset of its realizations.

    Returns the :class:`~linecheck.service.RunResult` of those realizations, or a
    :class:`Failure`.  ``progress``/``cancel`` are only passed when the task runs
    in the coordinating process; :class:`Cancelled` is raised, not returned.
    """
    from ..service import run_case

    try:
        case = load_checked(case_path, expected_hash, changes)
        return run_case(case, realizations=list(realizations), progress=progress, cancel=cancel)
    except Cancelled:
        raise
    except LinecheckError as err:
        return Failure.of(err)


def run_until_case(
    case_path: str,
    target: float,
    max_realizations: int,
    expected_hash: str | None = None,
    changes: Mapping[str, Any] | None = None,
    *,
    progress: Callable[[str, int, int], None] | None = None,
    cancel: threading.Event | None = None,
) -> Any:
    """``batch --until``: one case with an adaptive realization count (:func:`service.run_until`),
    as one task (its chunks run in sequence: each decides the next).  Returns the RunResult or a
    :class:`Failure`."""
    from ..service import run_until

    try:
        case = load_checked(case_path, expected_hash, changes)
        return run_until(case, target, max_realizations=max_realizations, progress=progress, cancel=cancel)
    except Cancelled:
        raise
    except LinecheckError as err:
        return Failure.of(err)


@dataclass(frozen=True)
class ScanChunk:
    """Step-1 results at a list of downburst scan points.

    Attributes:
        start: index of the first point of the chunk in the whole grid.
        peak: [N] wind-induced mean reaction at the tower of interest with the largest
            magnitude over the event (signed), shape (n_points, 3) for (Rx, Ry, Rz).
        time: [s] instant of that value, shape (n_points, 3).
        v_ref: [m/s] running-mean speed at point p of each configuration, shape (n_points,).
        errors: per point, ``None`` or the message of the error that stopped it.
    """

    start: int
    peak: np.ndarray
    time: np.ndarray
    v_ref: np.ndarray
    errors: tuple[str | None, ...]


def fixed_jet_case(case: Case, v_max: float, *, iterations: int = 4) -> Case:
    """``case`` with ``wind.v_ref`` chosen so that its field's V_max equals ``v_max``.

    The case file's V_ref is the running-mean speed at point p, so moving the storm
    with V_ref kept would change the storm's strength with its position; a scan compares
    one storm (fixed V_max: same jet, same intensity) at different positions.  V_max is
    proportional to V_ref without storm translation (one step is exact); with
    translation a few fixed-point steps are taken.
    """
    import dataclasses

    from ..core.wind.mean import downburst_field

    c = case
    for _ in range(iterations):
        vm = downburst_field(c).v_max
        if abs(vm - v_max) <= 1e-12 * v_max:
            break
        c = dataclasses.replace(c, wind=dataclasses.replace(c.wind, v_ref=c.wind.v_ref * v_max / vm))
    return c


def scan_point(case: Case, distance: float, angle: float, jet_diameter: float,
               v_max: float | None = None) -> tuple[np.ndarray, np.ndarray, float]:
    """Step 1 at one downburst configuration.

    Returns (signed peak wind-induced mean reaction at the tower of interest [N] (3,),
    its instant [s] (3,), the V_ref at point p used [m/s]).

    ``v_max``: hold the storm's V_max [m/s] fixed (:func:`fixed_jet_case`); ``None``
    keeps the case's V_ref at point p of every configuration.
    """
    from ..service import static_analysis

    c = apply_changes(case, scan_changes(distance, angle, jet_diameter))
    if v_max is not None:
        c = fixed_jet_case(c, v_max)
    st = static_analysis(c)
    rw = st.mean.reactions_wind[:, c.line.tower_of_interest - 1, :]  # (n_t, 3)
    k = np.argmax(np.abs(rw), axis=0)
    comp = np.arange(rw.shape[1])
    return rw[k, comp].copy(), st.mean.time[k].copy(), float(c.wind.v_ref)


def scan_chunk(
    case_path: str,
    points: Sequence[tuple[float, float, float]],
    start: int = 0,
    expected_hash: str | None = None,
    v_max: float | None = None,
    *,
    cancel: threading.Event | None = None,
) -> Any:
    """Step 1 at each (distance R [m], angle Theta [deg], jet diameter D_j [m]) of ``points``.

    ``v_max`` [m/s]: the storm's fixed V_max (see :func:`scan_point`), or ``None``.

    Returns a :class:`ScanChunk` (a point that fails -- e.g. no outflow reaches the
    line -- gets NaN and its message) or a :class:`Failure` if the case itself fails.
    """
    try:
        case = load_checked(case_path, expected_hash)
        if case.wind.type != "downburst" or case.wind.downburst is None:
            raise CaseError('wind.type: a scan needs a downburst case (type = "downburst")', file=str(case_path))
    except LinecheckError as err:
        return Failure.of(err)
    n = len(points)
    peak = np.full((n, 3), np.nan)
    time = np.full((n, 3), np.nan)
    vref = np.full(n, np.nan)
    errors: list[str | None] = [None] * n
    for i, (r, th, dj) in enumerate(points):
        if cancel is not None and cancel.is_set():
            raise Cancelled("scan cancelled")
        try:
            peak[i], time[i], vref[i] = scan_point(case, r, th, dj, v_max)
        except Cancelled:
            raise
        except LinecheckError as err:
            errors[i] = str(err)
    return ScanChunk(start, peak, time, vref, tuple(errors))


def ignore_sigint() -> None:
    """Process-pool initializer: Ctrl-C is handled by the coordinator, not by each worker."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def noop() -> None:
    """Does nothing: submitted to start a pool's worker processes early."""
