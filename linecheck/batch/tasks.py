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

import os
import signal
import threading
import time
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
    report_key: Any = None,
    until: tuple[float, int] | None = None,
) -> Any:
    """Steps 1-3 of one case for a subset of its realizations.

    ``until=(target, max_realizations)`` (``batch --until``): the whole case with an
    adaptive count instead (:func:`linecheck.service.run_until`; ``realizations`` is then the
    initial count's range, used for progress only).

    Returns the :class:`~linecheck.service.RunResult` of those realizations, or a
    :class:`Failure`.  ``progress``/``cancel`` are only passed when the task runs
    in the coordinating process; :class:`Cancelled` is raised, not returned.
    ``report_key``: in a process-pool worker, report start and progress under this key
    (:func:`init_pool_worker`).
    """
    from ..service import run_case

    if cancel is None:
        cancel = _STOP  # in a pool worker: the pool's stop event
    if report_key is not None and _REPORTS is not None:
        _report("start", report_key, os.getpid())
        if os.environ.get(KILL_HOOK_ENV) == Path(case_path).stem:  # test hook (see KILL_HOOK_ENV)
            os.kill(os.getpid(), getattr(signal, "SIGKILL", signal.SIGTERM))
        progress = _worker_progress(report_key, len(realizations))
    try:
        case = load_checked(case_path, expected_hash, changes)
        if until is not None:
            from ..service import run_until

            return run_until(case, float(until[0]), max_realizations=int(until[1]), progress=progress, cancel=cancel)
        return run_case(case, realizations=list(realizations), progress=progress, cancel=cancel)
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
    dynamic: np.ndarray | None = None  # [N] mean over realizations of the dynamic peak |M + B + R|, (n_points, 3)


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
               v_max: float | None = None, dynamic_realizations: int = 0):
    """Step 1 (and with ``dynamic_realizations`` > 0 steps 1-3) at one downburst configuration.

    Returns (signed peak wind-induced mean reaction at the tower of interest [N] (3,),
    its instant [s] (3,), the V_ref at point p used [m/s]) and, with ``dynamic_realizations``
    = k > 0, a fourth item: the expected dynamic peak |M + B + R| of each reaction [N] (3,), the
    mean over realizations 0..k-1 (the scan ranks by the peak the design carries).

    ``v_max``: hold the storm's V_max [m/s] fixed (:func:`fixed_jet_case`); ``None``
    keeps the case's V_ref at point p of every configuration.
    """
    from ..service import run_tower, static_analysis

    c = apply_changes(case, scan_changes(distance, angle, jet_diameter))
    if v_max is not None:
        c = fixed_jet_case(c, v_max)
    j = c.line.tower_of_interest - 1
    if dynamic_realizations > 0:
        res = run_tower(c, realizations=list(range(dynamic_realizations)))  # the tower of interest's reactions only
        st = res.static
        dyn = res.stats.peak_dynamic[:, 0, :].mean(axis=0)
    else:
        st = static_analysis(c)
    rw = st.system.to_tower_frames(st.mean.reactions_wind)[:, j, :]  # (n_t, 3), the tower's own frame
    k = np.argmax(np.abs(rw), axis=0)
    comp = np.arange(rw.shape[1])
    out = (rw[k, comp].copy(), st.mean.time[k].copy(), float(c.wind.v_ref))
    return out + (dyn,) if dynamic_realizations > 0 else out


def scan_chunk(
    case_path: str,
    points: Sequence[tuple[float, float, float]],
    start: int = 0,
    expected_hash: str | None = None,
    v_max: float | None = None,
    *,
    cancel: threading.Event | None = None,
    model: str | None = None,
    dynamic_realizations: int = 0,
    progress: Callable[[int], None] | None = None,
) -> Any:
    """Step 1 at each (distance R [m], angle Theta [deg], jet diameter D_j [m]) of ``points``.

    ``progress(points_done)``: called after each point (only when run in the coordinating process).

    ``model``: the downburst running-mean model to scan under (``None``: the case's own).
    ``dynamic_realizations``: k > 0 also runs steps 1-3 with realizations 0..k-1 at every point
    and returns the expected dynamic peaks.

    ``v_max`` [m/s]: the storm's fixed V_max (see :func:`scan_point`), or ``None``.

    Returns a :class:`ScanChunk` (a point that fails -- e.g. no outflow reaches the
    line -- gets NaN and its message) or a :class:`Failure` if the case itself fails.
    """
    try:
        case = load_checked(case_path, expected_hash)
        if case.wind.type != "downburst" or case.wind.downburst is None:
            raise CaseError('wind.type: a scan needs a downburst case (type = "downburst")', file=str(case_path))
        if model is not None:
            from ..service import model_changes

            case = apply_changes(case, model_changes(case, model))
    except LinecheckError as err:
        return Failure.of(err)
    if cancel is None:
        cancel = _STOP  # in a pool worker: the pool's stop event
    n = len(points)
    peak = np.full((n, 3), np.nan)
    time = np.full((n, 3), np.nan)
    vref = np.full(n, np.nan)
    dyn = np.full((n, 3), np.nan) if dynamic_realizations > 0 else None
    errors: list[str | None] = [None] * n
    for i, (r, th, dj) in enumerate(points):
        if cancel is not None and cancel.is_set():
            raise Cancelled("scan cancelled")
        try:
            got = scan_point(case, r, th, dj, v_max, dynamic_realizations)
            peak[i], time[i], vref[i] = got[:3]
            if dyn is not None:
                dyn[i] = got[3]
        except Cancelled:
            raise
        except LinecheckError as err:
            errors[i] = str(err)
        if progress is not None:
            progress(i + 1)
    return ScanChunk(start, peak, time, vref, tuple(errors), dyn)


def ignore_sigint() -> None:
    """Process-pool initializer: Ctrl-C is handled by the coordinator, not by each worker."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


# --------------------------------------------------------------------------- pool workers
#: the coordinator's report queue in a pool worker (set by :func:`init_pool_worker`)
_REPORTS: Any = None
_STOP: Any = None  # the pool's stop event, in a worker (init_pool_worker)
#: seconds between two progress reports of one task (at least one per realization is sent)
REPORT_INTERVAL_S = 0.25
#: seconds between two checks of the parent process by the worker's watchdog thread
WATCHDOG_S = 1.0
#: test hook: a pool worker that starts a chunk of the case file with this stem kills itself
#: with SIGKILL, as the kernel's out-of-memory killer would (tests of the dead-worker recovery)
KILL_HOOK_ENV = "LINECHECK_TEST_KILL_WORKER_ON"
PR_SET_PDEATHSIG = 1  # <linux/prctl.h>


def _exit_with_parent(parent_pid: int, pdeathsig: bool) -> None:
    """Make this worker exit when the coordinator dies (SIGKILL, SIGTERM, crash).

    Linux: ``prctl(PR_SET_PDEATHSIG, SIGKILL)`` -- the kernel kills the worker when its
    parent goes (only set when the pool was created in the coordinator's main thread: the
    signal follows the thread that started the worker).  Everywhere: a daemon thread
    polls ``os.getppid()`` every :data:`WATCHDOG_S` and exits once the worker has been
    re-parented.  Without this, idle workers wait forever on the task queue (they hold
    its write end themselves), and with them the resource tracker.
    """
    if pdeathsig and os.name == "posix" and os.uname().sysname == "Linux":
        try:
            import ctypes

            libc = ctypes.CDLL(None, use_errno=True)
            libc.prctl(PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0)
        except (OSError, AttributeError):  # pragma: no cover - no prctl: the watchdog remains
            pass
    if os.getppid() != parent_pid:  # the parent died before we got here
        os._exit(1)

    def watch() -> None:
        while True:
            time.sleep(WATCHDOG_S)
            if os.getppid() != parent_pid:
                os._exit(1)

    threading.Thread(target=watch, name="linecheck-parent-watchdog", daemon=True).start()


def init_pool_worker(reports: Any = None, parent_pid: int | None = None, pdeathsig: bool = False,
                     stop: Any = None) -> None:
    """Process-pool initializer: ignore Ctrl-C, exit with the parent, keep the report queue
    and the pool's stop event.

    ``reports``: a ``multiprocessing.SimpleQueue`` read by the coordinator; tasks
    submitted with a ``report_key`` put ``("start", key, pid)`` on it before they run
    (synchronously: the coordinator knows which worker holds which task even when the
    worker is killed right after) and ``("progress", key, done, total)`` while they run.
    ``stop``: a ``multiprocessing.Event`` the coordinator sets to stop the batch; the
    worker's tasks take it as their cancel event and end with :class:`Cancelled` at their
    next cancellation check, so the pool stops without killing a worker mid-write.
    """
    global _REPORTS, _STOP
    ignore_sigint()
    _REPORTS = reports
    _STOP = stop
    if parent_pid is not None:
        _exit_with_parent(parent_pid, pdeathsig)


def _report(*msg: Any) -> None:
    if _REPORTS is not None:
        _REPORTS.put(msg)


def _worker_progress(key: Any, n: int) -> Callable[[str, int, int], None]:
    """A ``progress(stage, done, total)`` callback sending the task's realizations done
    (fraction of ``n``) at most every :data:`REPORT_INTERVAL_S`, and whenever one more
    whole realization is done."""
    last = [time.monotonic(), 0]

    def cb(stage: str, d: int, total: int) -> None:
        if not stage.startswith("steps 2-3") or total <= 0:
            return
        done = n * d / total
        now = time.monotonic()
        if int(done) > last[1] or now - last[0] >= REPORT_INTERVAL_S:
            last[0], last[1] = now, int(done)
            _report("progress", key, done)

    return cb


def noop() -> None:
    """Does nothing: submitted to start a pool's worker processes early."""
