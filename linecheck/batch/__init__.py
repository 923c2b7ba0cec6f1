"""Batch runs, parallel/distributed execution and the critical-downburst scan.

This package runs inside process-pool and Dask workers: it imports only the
numerical core, the service layer and :mod:`linecheck.io` -- never a UI library
(``textual``, ``rich``, ``typer``) -- and Dask only when a scheduler is used.

- :func:`run_batch` -- many cases, split by case x realization chunk, results saved
  per case as they complete, ``resume``, progress events, cancellation (:mod:`.runner`;
  its parts: :mod:`.plan`, :mod:`.scheduler`, :mod:`.recovery`, :mod:`.saving`, :mod:`.report`).
- :func:`merge_runs` -- join runs of disjoint realization subsets of one case.
- :func:`make_executor`, :class:`SequentialExecutor`, :class:`ProcessPool`,
  :class:`DaskExecutor` -- where the tasks run.
- :func:`run_scan`, :class:`ScanGrid`, :func:`run_critical` -- the critical-downburst scan.
"""

from __future__ import annotations

from .executors import DaskExecutor, Executor, ProcessPool, SequentialExecutor, default_jobs, make_executor
from .merge import merge_runs
from .runner import (
    DEFAULT_CHUNK,
    BatchEvent,
    BatchReport,
    CaseOutcome,
    RunJob,
    auto_chunk_size,
    chunk_ranges,
    result_document,
    run_batch,
    saved_result,
)
from .scan import Critical, ScanGrid, ScanResult, parse_values, run_critical, run_scan, scan_csv_text, write_scan_csv
from .tasks import Failure, apply_changes, run_chunk, scan_chunk

__all__ = [
    "DEFAULT_CHUNK",
    "BatchEvent",
    "BatchReport",
    "CaseOutcome",
    "Critical",
    "DaskExecutor",
    "Executor",
    "Failure",
    "ProcessPool",
    "RunJob",
    "ScanGrid",
    "ScanResult",
    "SequentialExecutor",
    "apply_changes",
    "auto_chunk_size",
    "chunk_ranges",
    "default_jobs",
    "make_executor",
    "merge_runs",
    "parse_values",
    "result_document",
    "run_batch",
    "run_chunk",
    "run_critical",
    "run_scan",
    "saved_result",
    "scan_chunk",
    "scan_csv_text",
    "write_scan_csv",
]
