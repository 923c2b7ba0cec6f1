"""Batch runs: many cases, each split into realization chunks, on any executor.

Contract:

- Every case is split into chunks of at most ``chunk_size`` consecutive realizations
  (:func:`chunk_ranges`; default :func:`auto_chunk_size`: up to :data:`DEFAULT_CHUNK`,
  fewer when there are fewer realizations than workers); each chunk is one task
  (:func:`~.tasks.run_chunk`, plain data in: case file path, hash, indices), so a
  large case also spreads over workers.  The chunks of a case are joined with
  :func:`~.merge.merge_runs` in realization order.  Realization r always gets the same
  turbulence, and the core computes each realization's response independently of the
  others in its run (fixed-order products, no BLAS across realizations), so results are
  bit-identical to ``service.run_case(case)`` whatever the chunking, ``--jobs`` or
  scheduler.
- A case whose chunks are all in is saved at once (``<json_dir>/<file stem>.json``,
  the typed :func:`~linecheck.io.jsonout.run_document` plus its ``BatchSource``
  (``"case_file"``, ``"case_hash"``), written atomically), so an interrupted batch loses
  only running cases.  With ``resume`` a case whose saved JSON carries the same file hash
  (and reads as the current schema version) is skipped and its saved document reused.
- One failing case (bad file, non-convergence, any LinecheckError, a crashed worker)
  is reported in its :class:`CaseOutcome`; the other cases complete.  When a process-pool
  worker dies (out-of-memory kill), the pool is restarted (:meth:`Executor.restart`): the
  tasks the dead worker held fail their case ("worker died (killed by signal 9, ...) while
  running NAME"), every other unfinished task runs again -- same results, bit for bit.
- The results folder is checked writable before anything runs (CaseError, exit 2).  A
  result that cannot be written later (disk full) fails its case and stops the batch
  (``report.output_error``, exit code 2); the results saved so far stay.
- Progress goes to ``progress(event)`` (:class:`BatchEvent`, overall and per case);
  setting ``cancel`` (a :class:`threading.Event`) or Ctrl-C stops the batch after
  saving what is finished.

No UI imports: this runs under the CLI, the TUI or a notebook alike.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..core import budget
from ..core.case import Case, case_hash, load_case
from ..core.errors import Cancelled, CaseError, LinecheckError
from ..io.document import BatchSource, FailedRun, RunDocument
from .executors import Executor, SequentialExecutor, describe_exit
from .merge import merge_runs
from .tasks import Failure, apply_changes, run_chunk

POLL_S = 0.2  # how often the coordinator checks the cancel event while tasks run
MAX_IDLE_RESTARTS = 3  # pool restarts without any task finishing before the remaining cases fail


class _OutputError(Exception):
    """A result could not be written (disk full, ...): the batch stops, saved results stay."""


def _write_failure(exc: BaseException) -> str:
    """Why a result could not be written: the operating system's reason (``No space left on
    device``), also when the atomic writer reported it as a one-line CaseError naming the file."""
    cause = exc if isinstance(exc, OSError) else (exc.__cause__ or exc.__context__)
    if isinstance(cause, OSError):
        return cause.strerror or str(cause) or type(cause).__name__
    text = str(exc)
    file = getattr(exc, "file", None)
    return text[len(file) + 2:] if file and text.startswith(f"{file}: ") else text


# --------------------------------------------------------------------------- public data
@dataclass(frozen=True)
class BatchEvent:
    """One progress report of a batch.

    kind: ``"start"`` (batch planned), ``"case_warning"`` (the resource guard's warning for a
    case, in ``message``: above half the memory limit or a long run), ``"case_start"``,
    ``"case_progress"``, ``"case_done"``, ``"case_skipped"`` (resume), ``"case_failed"``, ``"finish"``.
    ``case`` is the case index (-1 for batch-level events); ``done``/``total`` count
    that case's realizations (``done`` is fractional while chunks run: tasks report
    their progress at least once per realization), ``overall_done``/``overall_total``
    all realizations of the batch (skipped and failed cases count as done),
    ``cases_done``/``cases_total`` the cases finished (done, skipped or failed) and all.
    """

    kind: str
    case: int
    name: str
    done: float
    total: int
    overall_done: float
    overall_total: int
    message: str = ""
    cases_done: int = 0
    cases_total: int = 0


BatchProgress = Callable[[BatchEvent], None]


@dataclass
class CaseOutcome:
    """What happened to one case of a batch.

    status: ``"done"`` (run and saved), ``"skipped"`` (resume: saved result reused),
    ``"failed"`` (``error`` says why), ``"cancelled"`` (not finished when the batch stopped).
    ``doc`` is the per-case JSON document (done/skipped), ``result`` the merged
    :class:`~linecheck.service.RunResult` when the batch was asked to keep results.
    """

    path: Path
    name: str
    status: str = "pending"
    hash: str | None = None
    realizations: int = 0
    json_path: Path | None = None
    doc: RunDocument | None = None
    result: Any = None
    error: str | None = None
    error_kind: str | None = None
    elapsed: float = 0.0
    warning: str | None = None  # the resource guard's warning (above half the memory limit, a long run)

    @property
    def ok(self) -> bool:
        return self.status in ("done", "skipped")

    def excel_doc(self) -> RunDocument | FailedRun:
        """The document handed to the Excel writer: the result, or a :class:`FailedRun`."""
        if self.doc is not None:
            return self.doc
        return FailedRun(self.name, self.error or self.status)


@dataclass
class BatchReport:
    """Outcome of a batch, in the order the cases were given."""

    outcomes: list[CaseOutcome]
    executor: str = ""
    elapsed: float = 0.0
    cancelled: bool = False
    interrupted: bool = False  # Ctrl-C (KeyboardInterrupt) rather than the cancel event
    output_error: str | None = None  # a result could not be written (disk full): the batch stopped

    @property
    def failed(self) -> list[CaseOutcome]:
        return [o for o in self.outcomes if o.status == "failed"]

    @property
    def exit_code(self) -> int:
        """0 all cases done, 1 any case failed, 2 a result could not be written, 130 cancelled."""
        if self.output_error:
            return 2
        if self.cancelled:
            return 130
        return 1 if self.failed else 0

    def docs(self) -> list[RunDocument | FailedRun]:
        """Per-case documents for the Excel workbook (errors as :class:`FailedRun`)."""
        return [o.excel_doc() for o in self.outcomes if o.status != "pending"]


@dataclass
class RunJob:
    """One case to run: a file, optional key changes, a label (scan --dynamic uses changes)."""

    path: Path
    label: str | None = None
    changes: Mapping[str, Any] | None = None
    json_name: str | None = None


# --------------------------------------------------------------------------- helpers
DEFAULT_CHUNK = 10  # realizations per task (each task repeats step 1 and the model set-up)


def auto_chunk_size(total_realizations: int, workers: int) -> int:
    """Realizations per task: :data:`DEFAULT_CHUNK`, or fewer so that every worker gets work
    when the whole batch has fewer than ``DEFAULT_CHUNK`` realizations per worker."""
    return max(1, min(DEFAULT_CHUNK, total_realizations // max(1, workers)))


def chunk_ranges(n: int, size: int = DEFAULT_CHUNK) -> list[list[int]]:
    """Split ``range(n)`` into ceil(n/size) chunks of consecutive realizations, sizes within one.

    Results do not depend on the chunks (see the module docstring).
    """
    size = max(1, int(size))
    if n <= 0:
        return []
    k = -(-n // size)
    edges = [round(i * n / k) for i in range(k + 1)]
    return [list(range(a, b)) for a, b in zip(edges[:-1], edges[1:])]


def json_name_for(path: Path) -> str:
    return f"{path.stem}.json"


def saved_result(json_path: Path, digest: str, changes: Mapping[str, Any] | None = None) -> RunDocument | None:
    """The saved document at ``json_path``, typed, if it carries ``digest`` as its case hash
    (and the same key ``changes``, for runs that alter the file's case); None when it is
    missing, damaged, of another schema version or of another case (it is then run again)."""
    from ..io.document import read_result_file

    try:  # a regular file of bounded size (a FIFO there must not hang), parsable JSON (not 100,000
        doc = read_result_file(json_path)  # nested brackets, not a 5,001-digit integer): else run it again
    except CaseError:
        return None
    try:  # saved by an older linecheck, or damaged: run it again
        typed = RunDocument.from_json(doc, source=str(json_path))
    except CaseError:
        return None
    if typed.batch is None or typed.batch.case_hash != digest:
        return None
    if typed.batch.changes != (json.loads(json.dumps(dict(changes))) if changes else None):
        return None
    return typed


def check_writable(folder: Path) -> None:
    """CaseError (exit 2) unless a file can be created in ``folder`` -- checked before any
    computing by writing and removing a probe file (``os.access`` is wrong for root and for
    read-only mounts)."""
    import os
    import tempfile

    try:
        fd, probe = tempfile.mkstemp(prefix=".linecheck-probe.", suffix=".tmp", dir=folder)
    except OSError as exc:
        raise CaseError(f"results folder is not writable: {exc.strerror or exc}", file=str(folder)) from None
    os.close(fd)
    Path(probe).unlink(missing_ok=True)


def result_document(result: Any, path: Path, digest: str | None,
                    changes: Mapping[str, Any] | None = None) -> RunDocument:
    """The per-case typed document: the run's plus its :class:`BatchSource` (``"case_file"``,
    ``"case_hash"`` and ``"changes"`` in the JSON)."""
    from dataclasses import replace

    from ..io.jsonout import run_document

    return replace(run_document(result),
                   batch=BatchSource(str(path), digest, {k: v for k, v in changes.items()} if changes else None))


# --------------------------------------------------------------------------- the runner
@dataclass
class _CaseState:
    index: int
    job: RunJob
    outcome: CaseOutcome
    case: Case | None = None
    chunks: list[list[int]] = field(default_factory=list)
    parts: list[Any] = field(default_factory=list)
    tasks: list[int] = field(default_factory=list)  # indices of its chunks' tasks
    done: float = 0.0
    started: bool = False
    t0: float = 0.0


def run_batch(
    cases: Sequence[str | Path | RunJob],
    *,
    executor: Executor | None = None,
    json_dir: str | Path | None = None,
    resume: bool = False,
    chunk_size: int | None = None,
    keep_results: bool = False,
    progress: BatchProgress | None = None,
    cancel: threading.Event | None = None,
    until: tuple[float, int] | None = None,
) -> BatchReport:
    """Run every case (all realizations) and save each result as it completes.

    Args:
        cases: case files (or :class:`RunJob`); the same file given twice runs once.
        executor: where tasks run (default :class:`SequentialExecutor`); not closed here.
        json_dir: folder of the per-case JSON results (created if missing; ``None``: no files).
        resume: skip cases whose saved JSON carries the case file's current hash.
        chunk_size: realizations per task (default :func:`auto_chunk_size`); the
            results do not depend on it.
        keep_results: keep the merged RunResult of each case in its outcome.
        progress: ``progress(BatchEvent)``; called in the calling thread.
        cancel: a threading.Event; when set the batch stops, finished cases stay saved.
        until: ``(target, max_realizations)``: each case adds realizations until the relative
            standard error is below ``target`` (:func:`linecheck.service.run_until`), as one task
            per case (cases still run in parallel); bit-identical to a fixed run of the same count.

    Returns:
        A :class:`BatchReport`; it never raises for a failing case.
    Raises:
        CaseError: ``json_dir`` cannot be created, two cases would write the same JSON,
            or ``resume`` without ``json_dir``.
    """
    t_start = time.perf_counter()
    executor = executor or SequentialExecutor()
    cancel = cancel or threading.Event()
    out_dir = Path(json_dir) if json_dir is not None else None
    if resume and out_dir is None:
        raise CaseError("--resume needs a results folder (--json-dir)")
    if out_dir is not None:
        if out_dir.exists() and not out_dir.is_dir():
            raise CaseError("results folder is a file, expected a folder", file=str(out_dir))
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise CaseError(f"cannot create results folder: {exc.strerror}", file=str(out_dir)) from None
        check_writable(out_dir)

    # ---- plan: one state per distinct job
    jobs: list[RunJob] = []
    seen: set[tuple[Path, str]] = set()
    for c in cases:
        job = c if isinstance(c, RunJob) else RunJob(Path(c))
        key = (job.path.resolve(), json.dumps(dict(job.changes or {}), sort_keys=True, default=str))
        if key in seen:
            continue
        seen.add(key)
        jobs.append(job)
    names: dict[str, Path] = {}
    for job in jobs:
        jn = job.json_name or json_name_for(job.path)
        if out_dir is not None and jn in names:
            raise CaseError(f"two cases would save to the same result {out_dir / jn} "
                            f"({names[jn]} and {job.path}): rename one file", file=str(job.path))
        names[jn] = job.path

    states: list[_CaseState] = []
    for i, job in enumerate(jobs):
        st = _CaseState(i, job, CaseOutcome(job.path, job.label or job.path.stem))
        o = st.outcome
        if out_dir is not None:
            o.json_path = out_dir / (job.json_name or json_name_for(job.path))
        try:
            case = apply_changes(load_case(job.path), job.changes)
            o.hash = case_hash(job.path)
            st.case = case
        except LinecheckError as err:
            o.status, o.error, o.error_kind = "failed", str(err), type(err).__name__
        except OSError as exc:
            o.status, o.error, o.error_kind = "failed", f"{job.path}: cannot read: {exc.strerror}", "CaseError"
        if st.case is not None:
            o.name = job.label or st.case.name
            o.realizations = st.case.analysis.realizations
        states.append(st)

    overall_total = sum(s.outcome.realizations for s in states)
    overall_done = 0.0

    def emit(kind: str, st: _CaseState | None, message: str = "") -> None:
        if progress is None:
            return
        n_done = sum(s.outcome.status in ("done", "skipped", "failed") for s in states)
        if st is None:
            progress(BatchEvent(kind, -1, "", overall_done, overall_total, overall_done, overall_total, message,
                                n_done, len(states)))
        else:
            progress(BatchEvent(kind, st.index, st.outcome.name, st.done, st.outcome.realizations,
                                overall_done, overall_total, message, n_done, len(states)))

    # ---- resume
    for st in states:
        o = st.outcome
        if st.case is None or not resume or o.json_path is None:
            continue
        doc = saved_result(o.json_path, o.hash or "", st.job.changes)
        if doc is not None:
            o.status, o.doc = "skipped", doc
            st.done = o.realizations
            overall_done += o.realizations

    # ---- the resource guard of every case to run, before any starts: each task checks
    # its own chunk, but the merged result keeps every realization's histories, so a case above
    # the memory limit fails here alone (its one-line estimate, a CaseError) and the others run
    for st in states:
        o = st.outcome
        if st.case is None or o.status != "pending":
            continue
        n = max(2, min(o.realizations, int(until[1]))) if until is not None else o.realizations  # run_until's start
        try:  # above half the limit or about 10 minutes: the case runs with a warning (case_warning)
            budget.guard(st.case, "run", realizations=n, warn=lambda m, o=o: setattr(o, "warning", m))
        except CaseError as err:
            o.status, o.error, o.error_kind = "failed", str(err), type(err).__name__
            st.done = o.realizations  # its own progress complete; none of it in the overall count
            overall_total -= o.realizations

    emit("start", None, executor.describe())
    for st in states:
        if st.outcome.warning and st.outcome.status == "pending":
            emit("case_warning", st, st.outcome.warning)
        if st.outcome.status == "failed":
            emit("case_failed", st, st.outcome.error or "")
        elif st.outcome.status == "skipped":
            emit("case_skipped", st, str(st.outcome.json_path))

    # ---- submit
    todo = [s for s in states if s.case is not None and s.outcome.status == "pending"]
    if chunk_size is None:
        size = auto_chunk_size(sum(s.outcome.realizations for s in todo), executor.workers)
    else:
        size = max(1, int(chunk_size))

    handles: list[Any] = []
    owner: list[tuple[_CaseState, int]] = []  # per task: its case and chunk number
    partial: dict[int, float] = {}  # per running task: realizations done so far (fractional)
    holder: dict[int, int] = {}  # per started task of a process pool: the worker's pid
    suspected: dict[int, int] = {}  # per task: times it was running when a worker died unidentified

    def update_done(st: _CaseState) -> None:
        nonlocal overall_done
        new = (sum(len(c) for c, p in zip(st.chunks, st.parts) if p is not None)
               + sum(partial.get(i, 0.0) for i, p in zip(st.tasks, st.parts) if p is None))
        overall_done += new - st.done
        st.done = new

    def in_process_progress(idx: int, n: int) -> Callable[[str, int, int], None]:
        def cb(stage: str, d: int, total: int) -> None:
            if not stage.startswith("steps 2-3") or total <= 0:
                return
            st = owner[idx][0]
            partial[idx] = n * d / total
            update_done(st)
            emit("case_progress", st)
        return cb

    def submit(idx: int) -> Any:
        st, k = owner[idx]
        chunk = st.chunks[k]
        kwargs: dict[str, Any] = {}
        if executor.in_process:
            kwargs = {"cancel": cancel, "progress": in_process_progress(idx, len(chunk))}
        elif executor.reporting:
            kwargs = {"report_key": idx}
        partial.pop(idx, None)
        holder.pop(idx, None)
        if until is not None:  # adaptive count (issue 18): the task runs the whole case
            kwargs["until"] = (float(until[0]), int(until[1]))
        return executor.submit(run_chunk, str(st.job.path), chunk, st.outcome.hash,
                               dict(st.job.changes) if st.job.changes else None, **kwargs)

    for st in todo:
        # --until (issue 18): one task per case, its chunks run in sequence inside it
        st.chunks = [list(range(st.outcome.realizations))] if until is not None else \
            chunk_ranges(st.outcome.realizations, size)
        st.parts = [None] * len(st.chunks)
        for k in range(len(st.chunks)):
            idx = len(owner)
            owner.append((st, k))
            st.tasks.append(idx)
            handles.append(submit(idx))

    report = BatchReport([s.outcome for s in states], executor=executor.describe())

    def start_case(st: _CaseState) -> None:
        if not st.started:
            st.started, st.t0 = True, time.perf_counter()
            emit("case_start", st)

    def fail_case(st: _CaseState, failure: Failure) -> None:
        nonlocal overall_done
        o = st.outcome
        o.status, o.error, o.error_kind = "failed", failure.message, failure.kind
        o.elapsed = time.perf_counter() - st.t0 if st.t0 else 0.0
        executor.cancel([handles[i] for i, p in zip(st.tasks, st.parts) if p is None])
        overall_done += st.outcome.realizations - st.done
        st.done = st.outcome.realizations
        st.parts = []
        emit("case_failed", st, failure.message)

    def finish_case(st: _CaseState) -> None:
        o = st.outcome
        try:
            merged = merge_runs([p for p in st.parts])
            doc = result_document(merged, st.job.path, o.hash, st.job.changes)
        except LinecheckError as err:
            fail_case(st, Failure.of(err))
            return
        if o.json_path is not None:
            from ..io.jsonout import write_json

            try:
                write_json(o.json_path, doc)
            except (OSError, CaseError) as exc:  # disk full, folder gone read-only...: stop, keep what is saved
                msg = f"cannot save the result {o.json_path}: {_write_failure(exc)}"
                fail_case(st, Failure("OutputError", msg, 2))
                raise _OutputError(msg) from None
        o.status, o.doc = "done", doc
        o.result = merged if keep_results else None
        o.elapsed = time.perf_counter() - st.t0
        st.parts = []
        emit("case_done", st, str(o.json_path) if o.json_path else "")

    def take_reports() -> None:
        for msg in executor.reports():
            kind, idx = msg[0], msg[1]
            if not isinstance(idx, int) or not 0 <= idx < len(owner):
                continue
            st = owner[idx][0]
            if st.outcome.status != "pending":
                continue
            if kind == "start":
                holder[idx] = int(msg[2])
                start_case(st)
            elif kind == "progress":
                partial[idx] = float(msg[2])
                update_done(st)
                emit("case_progress", st)

    restarts_idle = 0  # pool restarts since a task last finished

    def recover(pending: list[int]) -> None:
        """A worker died: fail the tasks it held, re-run the others on a new pool."""
        nonlocal restarts_idle
        take_reports()  # every "start" message sent before the death
        running = {i: holder[i] for i in pending if i in holder}
        dead = executor.restart()
        restarts_idle += 1
        for idx in pending:
            st = owner[idx][0]
            if st.outcome.status != "pending":
                continue
            h = handles[idx]
            if h.done() and not isinstance(executor.outcome(h), Failure):
                continue  # finished before the pool broke: collected below
            pid = running.get(idx)
            why = None
            if pid is not None and pid in dead:
                why = describe_exit(dead[pid])
            elif pid is not None and not dead:  # the dead worker is unknown: every running task is suspect
                suspected[idx] = suspected.get(idx, 0) + 1
                if suspected[idx] > 1:
                    why = "ended abruptly, twice"
            elif restarts_idle > MAX_IDLE_RESTARTS:
                why = f"ended abruptly {restarts_idle} times in a row"
            if why is not None:
                fail_case(st, Failure("WorkerDied", f"worker died ({why}) while running {st.outcome.name}", 1))
        for idx in pending:
            st = owner[idx][0]
            h = handles[idx]
            if st.outcome.status == "pending" and not (h.done() and not isinstance(executor.outcome(h), Failure)):
                partial[idx] = 0.0
                handles[idx] = submit(idx)
                update_done(st)

    # ---- collect
    pending = list(range(len(handles)))
    try:
        while pending:
            if cancel.is_set():
                raise Cancelled("batch cancelled")
            take_reports()
            if not executor.reporting:
                for idx in pending:  # best-effort start notices
                    if executor.running(handles[idx]):
                        start_case(owner[idx][0])
            if executor.in_process:  # the next task runs now: announce its case first
                start_case(owner[pending[0]][0])
            done_local = executor.wait([handles[i] for i in pending], timeout=POLL_S)
            if executor.broken():
                recover(pending)
                pending = [i for i in pending if owner[i][0].outcome.status == "pending"]
                continue
            take_reports()
            finished = [pending[i] for i in done_local]
            for idx in finished:
                st, k = owner[idx]
                value = executor.outcome(handles[idx])
                if st.outcome.status != "pending":
                    continue  # its case already failed
                start_case(st)
                if isinstance(value, Failure):
                    fail_case(st, value)
                    continue
                restarts_idle = 0
                st.parts[k] = value
                partial.pop(idx, None)
                update_done(st)
                emit("case_progress", st)
                if all(p is not None for p in st.parts):
                    finish_case(st)
            fs = set(finished)
            # drop finished tasks and every task of a case that has failed meanwhile
            pending = [i for i in pending if i not in fs and owner[i][0].outcome.status == "pending"]
    except (Cancelled, KeyboardInterrupt, _OutputError) as exc:
        if isinstance(exc, _OutputError):
            report.output_error = str(exc)
        else:
            report.cancelled = True
            report.interrupted = isinstance(exc, KeyboardInterrupt)
        cancel.set()
        executor.abort([handles[i] for i in pending])
        for st in states:
            if st.outcome.status == "pending":
                st.outcome.status = "cancelled"
                st.parts = []
    report.elapsed = time.perf_counter() - t_start
    emit("finish", None, "cancelled" if report.cancelled else "")
    return report
