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
  running NAME"), every other unfinished task runs again -- same results, bit for bit
  (the policy: :mod:`.recovery`).
- The results folder is checked writable before anything runs (CaseError, exit 2).  A
  result that cannot be written later (disk full) fails its case and stops the batch
  (``report.output_error``, exit code 2); the results saved so far stay.
- Progress goes to ``progress(event)`` (:class:`BatchEvent`, overall and per case);
  setting ``cancel`` (a :class:`threading.Event`) or Ctrl-C stops the batch after
  saving what is finished.

The parts: :mod:`.plan` (the distinct cases, resume, the resource guard, chunks),
:mod:`.scheduler` (submitting and collecting tasks, finishing or failing cases, stopping),
:mod:`.recovery` (the worker-recovery policy), :mod:`.saving` (the result files) and
:mod:`.report` (events, outcomes, the report).  This module is the entry point,
:func:`run_batch`, and re-exports their public names.

No UI imports: this runs under the CLI, the TUI or a notebook alike.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from pathlib import Path

from .executors import Executor, SequentialExecutor
from .plan import DEFAULT_CHUNK, auto_chunk_size, chunk_ranges, plan_cases
from .recovery import MAX_IDLE_RESTARTS
from .report import BatchEvent, BatchProgress, BatchReport, CaseOutcome, RunJob
from .saving import check_writable, json_name_for, result_document, results_folder, saved_result
from .scheduler import POLL_S, BatchScheduler

__all__ = [
    "DEFAULT_CHUNK",
    "MAX_IDLE_RESTARTS",
    "POLL_S",
    "BatchEvent",
    "BatchProgress",
    "BatchReport",
    "CaseOutcome",
    "RunJob",
    "auto_chunk_size",
    "check_writable",
    "chunk_ranges",
    "json_name_for",
    "result_document",
    "run_batch",
    "saved_result",
]


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
    out_dir = results_folder(json_dir, resume)
    states = plan_cases(cases, out_dir, resume=resume, until=until)
    scheduler = BatchScheduler(states, executor, cancel=cancel, progress=progress, keep_results=keep_results,
                               until=until)
    scheduler.announce()
    scheduler.submit_all(chunk_size)
    return scheduler.run(t_start)
