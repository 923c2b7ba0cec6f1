"""The public data of a batch: its cases (:class:`RunJob`), progress events
(:class:`BatchEvent`), per-case outcomes (:class:`CaseOutcome`) and the report
(:class:`BatchReport`).

Plain data shared by the planner, the scheduler and their callers (the CLI's display, the
TUI, notebooks); nothing here runs a task.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ..io.document import FailedRun, RunDocument


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
    elapsed: float = 0.0  # [s] from the case's start to its end
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
    elapsed: float = 0.0  # [s] wall time of the whole batch
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
