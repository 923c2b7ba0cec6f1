"""The batch scheduler: submits every chunk task of the planned cases, collects their results,
finishes (merges and saves) or fails each case, recovers from dead workers and stops on
cancellation or a result that cannot be written.

Explicit state: the cases (:class:`~.plan.CaseState`), the task table (:class:`Task`: its case,
chunk, executor handle, progress and worker), the tasks still pending, the overall progress
counters and the :class:`~.report.BatchReport`.  Every event goes to ``progress`` in the calling
thread.  The worker-recovery policy is :class:`~.recovery.WorkerRecovery`.
"""

from __future__ import annotations

import functools
import threading
import time
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from ..core.errors import Cancelled, CaseError, LinecheckError
from .executors import Executor
from .merge import merge_runs
from .plan import CaseState, auto_chunk_size, chunk_ranges
from .recovery import HeldTask, WorkerRecovery
from .report import BatchEvent, BatchProgress, BatchReport
from .saving import result_document, save_result, write_failure
from .tasks import Failure, run_chunk

POLL_S = 0.2  # [s] how often the coordinator checks the cancel event while tasks run


class OutputError(Exception):
    """A result could not be written (disk full, ...): the batch stops, saved results stay."""


@dataclass
class Task:
    """One submitted chunk task: its case and chunk number, the executor's handle, the
    realizations it has done so far while running (fractional) and the process-pool worker
    that reported starting it."""

    index: int
    case: CaseState
    chunk: int
    handle: Any = None
    partial: float = 0.0
    pid: int | None = None

    @property
    def realizations(self) -> list[int]:
        return self.case.chunks[self.chunk]


class BatchScheduler:
    """Runs the planned cases of one batch on ``executor`` (see the module docstring).

    ``keep_results``: keep each case's merged RunResult in its outcome; ``until``:
    ``(target, max_realizations)``, one task per case that adds realizations until the
    relative standard error is below ``target``.
    """

    def __init__(self, states: Sequence[CaseState], executor: Executor, *, cancel: threading.Event,
                 progress: BatchProgress | None = None, keep_results: bool = False,
                 until: tuple[float, int] | None = None) -> None:
        self.states = list(states)
        self.executor = executor
        self.cancel = cancel
        self.progress = progress
        self.keep_results = keep_results
        self.until = until
        self.overall_total = sum(s.outcome.realizations for s in self.states if s.in_overall)
        self.overall_done = sum((s.done for s in self.states if s.outcome.status == "skipped"), 0.0)
        self.tasks: list[Task] = []
        self.pending: list[Task] = []
        self.recovery = WorkerRecovery()
        self.report = BatchReport([s.outcome for s in self.states])

    # ------------------------------------------------------------------ events
    def emit(self, kind: str, st: CaseState | None, message: str = "") -> None:
        """Send one :class:`BatchEvent` (batch-level when ``st`` is None)."""
        if self.progress is None:
            return
        n_done = sum(s.outcome.status in ("done", "skipped", "failed") for s in self.states)
        n = len(self.states)
        if st is None:
            self.progress(BatchEvent(kind, -1, "", self.overall_done, self.overall_total, self.overall_done,
                                     self.overall_total, message, n_done, n))
        else:
            self.progress(BatchEvent(kind, st.index, st.outcome.name, st.done, st.outcome.realizations,
                                     self.overall_done, self.overall_total, message, n_done, n))

    def announce(self) -> None:
        """The ``start`` event, then each planned case's warning, failure or reuse."""
        self.emit("start", None, self.executor.describe())
        for st in self.states:
            o = st.outcome
            if o.warning and o.status == "pending":
                self.emit("case_warning", st, o.warning)
            if o.status == "failed":
                self.emit("case_failed", st, o.error or "")
            elif o.status == "skipped":
                self.emit("case_skipped", st, str(o.json_path))

    def update_done(self, st: CaseState) -> None:
        """Recount a case's realizations done (chunks in, plus running chunks' progress)."""
        new = (sum(len(c) for c, p in zip(st.chunks, st.parts) if p is not None)
               + sum(t.partial for t, p in zip(st.tasks, st.parts) if p is None))
        self.overall_done += new - st.done
        st.done = new

    def start_case(self, st: CaseState) -> None:
        if not st.started:
            st.started, st.t0 = True, time.perf_counter()
            self.emit("case_start", st)

    # ------------------------------------------------------------------ submitting
    def submit_all(self, chunk_size: int | None = None) -> None:
        """Split every pending case into chunk tasks (``chunk_size`` realizations each, default
        :func:`~.plan.auto_chunk_size`; one task per case with ``until``) and submit them."""
        todo = [s for s in self.states if s.case is not None and s.pending]
        if chunk_size is None:
            size = auto_chunk_size(sum(s.outcome.realizations for s in todo), self.executor.workers)
        else:
            size = max(1, int(chunk_size))
        for st in todo:  # with until, the task runs the chunks of its case in sequence
            n = st.outcome.realizations
            st.chunks = [list(range(n))] if self.until is not None else chunk_ranges(n, size)
            st.parts = [None] * len(st.chunks)
            for k in range(len(st.chunks)):
                task = Task(len(self.tasks), st, k)
                self.tasks.append(task)
                st.tasks.append(task)
                self.submit(task)
        self.pending = list(self.tasks)
        self.report.executor = self.executor.describe()

    def submit(self, task: Task) -> None:
        """Submit (or submit again) one chunk task; its progress and worker start from nothing."""
        st = task.case
        kwargs: dict[str, Any] = {}
        if self.executor.in_process:
            kwargs = {"cancel": self.cancel,
                      "progress": functools.partial(self._in_process_progress, task, len(task.realizations))}
        elif self.executor.reporting:
            kwargs = {"report_key": task.index}
        task.partial, task.pid = 0.0, None
        if self.until is not None:  # adaptive count: the task runs the whole case
            kwargs["until"] = (float(self.until[0]), int(self.until[1]))
        task.handle = self.executor.submit(run_chunk, str(st.job.path), task.realizations, st.outcome.hash,
                                           dict(st.job.changes) if st.job.changes else None, **kwargs)

    def _in_process_progress(self, task: Task, n: int, stage: str, done: int, total: int) -> None:
        """Progress of a task running in this process: ``n`` realizations, ``done`` of ``total`` steps."""
        if not stage.startswith("steps 2-3") or total <= 0:
            return
        task.partial = n * done / total
        self.update_done(task.case)
        self.emit("case_progress", task.case)

    def take_reports(self) -> None:
        """Start/progress messages from the process pool's tasks."""
        for msg in self.executor.reports():
            kind, idx = msg[0], msg[1]
            if not isinstance(idx, int) or not 0 <= idx < len(self.tasks):
                continue
            task = self.tasks[idx]
            if not task.case.pending:
                continue
            if kind == "start":
                task.pid = int(msg[2])
                self.start_case(task.case)
            elif kind == "progress":
                task.partial = float(msg[2])
                self.update_done(task.case)
                self.emit("case_progress", task.case)

    # ------------------------------------------------------------------ running
    def run(self, t_start: float) -> BatchReport:
        """Collect every task, then the ``finish`` event; ``t_start`` [s]: the batch's start
        (``time.perf_counter``).  Cancellation, Ctrl-C or an unwritable result stop the batch."""
        try:
            while self.pending:
                self.step()
        except (Cancelled, KeyboardInterrupt, OutputError) as exc:
            self.stop(exc)
        self.report.elapsed = time.perf_counter() - t_start
        self.emit("finish", None, "cancelled" if self.report.cancelled else "")
        return self.report

    def step(self) -> None:
        """Wait up to :data:`POLL_S` for tasks and take in those that finished."""
        if self.cancel.is_set():
            raise Cancelled("batch cancelled")
        ex = self.executor
        self.take_reports()
        if not ex.reporting:
            for task in self.pending:  # best-effort start notices
                if ex.running(task.handle):
                    self.start_case(task.case)
        if ex.in_process:  # the next task runs now: announce its case first
            self.start_case(self.pending[0].case)
        done_local = ex.wait([t.handle for t in self.pending], timeout=POLL_S)
        if ex.broken():
            self.recover()
            self.pending = [t for t in self.pending if t.case.pending]
            return
        self.take_reports()
        finished = [self.pending[i] for i in done_local]
        for task in finished:
            self.collect(task)
        gone = {t.index for t in finished}
        # drop finished tasks and every task of a case that has failed meanwhile
        self.pending = [t for t in self.pending if t.index not in gone and t.case.pending]

    def collect(self, task: Task) -> None:
        """Take in a finished task's result: its chunk, or the failure of its case."""
        st = task.case
        value = self.executor.outcome(task.handle)
        if not st.pending:
            return  # its case already failed
        self.start_case(st)
        if isinstance(value, Failure):
            self.fail_case(st, value)
            return
        self.recovery.progressed()
        st.parts[task.chunk] = value
        task.partial = 0.0
        self.update_done(st)
        self.emit("case_progress", st)
        if all(p is not None for p in st.parts):
            self.finish_case(st)

    def _finished_ok(self, task: Task) -> bool:
        return task.handle.done() and not isinstance(self.executor.outcome(task.handle), Failure)

    def recover(self) -> None:
        """A worker died: restart the pool, fail the tasks the policy blames, re-run the others."""
        self.take_reports()  # every "start" message sent before the death
        held = [HeldTask(t.index, t.case.index, t.pid) for t in self.pending if t.case.pending]
        dead = self.executor.restart()
        held = [HeldTask(h.index, h.case, h.pid, self._finished_ok(self.tasks[h.index])) for h in held]
        plan = self.recovery.after_restart(held, dead)
        for h, why in plan.failed:
            st = self.tasks[h.index].case
            self.fail_case(st, self.recovery.failure(why, st.outcome.name))
        for h in plan.rerun:
            task = self.tasks[h.index]
            self.submit(task)
            self.update_done(task.case)

    # ------------------------------------------------------------------ ending cases
    def fail_case(self, st: CaseState, failure: Failure) -> None:
        """The case failed: cancel its other tasks, count it as done, ``case_failed``."""
        o = st.outcome
        o.status, o.error, o.error_kind = "failed", failure.message, failure.kind
        o.elapsed = time.perf_counter() - st.t0 if st.t0 else 0.0
        self.executor.cancel([t.handle for t, p in zip(st.tasks, st.parts) if p is None])
        self.overall_done += st.outcome.realizations - st.done
        st.done = st.outcome.realizations
        st.parts = []
        self.emit("case_failed", st, failure.message)

    def finish_case(self, st: CaseState) -> None:
        """All chunks are in: merge, save (OutputError if that fails), ``case_done``."""
        o = st.outcome
        try:
            merged = merge_runs(list(st.parts))
            doc = result_document(merged, st.job.path, o.hash, st.job.changes)
        except LinecheckError as err:
            self.fail_case(st, Failure.of(err))
            return
        if o.json_path is not None:
            try:
                save_result(o.json_path, doc)
            except (OSError, CaseError) as exc:  # disk full, folder gone read-only...: stop, keep what is saved
                msg = f"cannot save the result {o.json_path}: {write_failure(exc)}"
                self.fail_case(st, Failure("OutputError", msg, 2))
                raise OutputError(msg) from None
        o.status, o.doc = "done", doc
        o.result = merged if self.keep_results else None
        o.elapsed = time.perf_counter() - st.t0
        st.parts = []
        self.emit("case_done", st, str(o.json_path) if o.json_path else "")

    def stop(self, exc: BaseException) -> None:
        """Stop the batch (cancelled, Ctrl-C or an unwritable result): abort the running tasks,
        mark the unfinished cases ``"cancelled"``; finished results stay."""
        if isinstance(exc, OutputError):
            self.report.output_error = str(exc)
        else:
            self.report.cancelled = True
            self.report.interrupted = isinstance(exc, KeyboardInterrupt)
        self.cancel.set()
        self.executor.abort([t.handle for t in self.pending])
        for st in self.states:
            if st.pending:
                st.outcome.status = "cancelled"
                st.parts = []

