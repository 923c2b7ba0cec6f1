"""The run job of the TUI: service calls only, no Textual (runs in a thread worker).

``execute`` runs steps 1-3 (:func:`linecheck.service.run_case`), builds the typed
document exactly as ``linecheck run`` does (:func:`linecheck.io.jsonout.run_document`),
then the natural frequencies and the wind at point p for the extra result tabs.  A case with
``[[wires]]`` runs as ``linecheck run`` runs it: every wire in one correlated wind
(:func:`linecheck.service.run_wires`, its document
:func:`linecheck.io.wires_document.wires_run_document`), without the one-wire extras.
Progress goes through ``progress(stage, done, total)``; ``cancel`` is a plain
:class:`threading.Event` checked by the service and between the jobs.
"""

from __future__ import annotations

import threading
import time
from dataclasses import dataclass

from .. import service
from ..batch.executors import default_jobs
from ..core.case import Case
from ..core.errors import Cancelled, CaseError
from ..io.document import RunDocument
from ..io.jsonout import run_document

STAGE_MODES = "natural frequencies"
STAGE_WIND_P = "wind at point p"


@dataclass(frozen=True)
class RunOutput:
    """Everything the result tabs show for one run.

    ``doc`` is the typed ``linecheck run`` document of ``result`` (a
    :class:`~linecheck.service.WiresRun` for a case with ``[[wires]]``); ``modes`` and
    ``wind`` are ``None`` if they were not computed (always for several wires).
    """

    case: Case
    result: service.RunResult | service.WiresRun
    doc: RunDocument
    modes: service.ModesResult | None
    wind: service.WindAtP | None
    seconds: float

    @property
    def has_wires(self) -> bool:
        """A run of a case with ``[[wires]]`` (its document has every tower's totals and load trees)."""
        return self.doc.has_wires

    @property
    def label(self) -> str:
        return f"{self.case.name} (V_ref {self.case.wind.v_ref:g} m/s)"


def execute(
    case: Case,
    *,
    progress: service.Progress | None = None,
    cancel: threading.Event | None = None,
    extras: bool = True,
    models: str | None = None,
) -> RunOutput:
    """Run ``case`` and collect the result tabs' data (raises ``Cancelled`` when ``cancel`` is set).

    ``models``: e.g. ``"all"``: the downburst model spread (:func:`service.run_models`);
    the result tabs show the case's own model, the document gets the ``"models"`` block.
    A case with ``[[wires]]``: :func:`service.run_wires` (no model spread: CaseError)."""
    t0 = time.perf_counter()
    threads = default_jobs()  # realization chunks in threads: the same bits (service.run_case)
    if case.has_wires:
        return _execute_wires(case, progress=progress, cancel=cancel, threads=threads, models=models, t0=t0)

    def check() -> None:
        if cancel is not None and cancel.is_set():
            raise Cancelled("run cancelled")

    def report(stage: str, done: int, total: int) -> None:
        if progress is not None:
            progress(stage, done, total)

    if models is not None:
        from ..io.jsonout import model_reactions, with_models

        spread = service.run_models(case, service.parse_models(case, models), progress=progress, cancel=cancel,
                                    threads=threads)
        own = case.wind.downburst.model_name
        result = spread[own] if own in spread else next(iter(spread.values()))
        doc = with_models(run_document(result), result.case.wind.downburst.model_name, model_reactions(spread))
    else:
        result = service.run_case(case, progress=progress, cancel=cancel, threads=threads)
        doc = run_document(result)
    modes = wind = None
    if extras:
        check()
        report(STAGE_MODES, 0, 1)
        modes = service.modes_analysis(case)
        report(STAGE_MODES, 1, 1)
        check()
        report(STAGE_WIND_P, 0, 1)
        wind = service.wind_at_p(case, realization=int(result.realizations[0]))
        report(STAGE_WIND_P, 1, 1)
    check()
    return RunOutput(case, result, doc, modes, wind, time.perf_counter() - t0)


def _execute_wires(case: Case, *, progress: service.Progress | None, cancel: threading.Event | None, threads: int,
                   models: str | None, t0: float) -> RunOutput:
    """Every wire of ``case`` in one correlated wind, as ``linecheck run`` runs it (the same
    service call and document: the same numbers for the same seed)."""
    from ..io.wires_document import wires_run_document

    if models is not None:
        raise CaseError("the downburst model spread of several wires is not available yet: r runs the case under its "
                        "own model", file=str(case.source) if case.source else None, key="wires")
    result = service.run_wires(case, progress=progress, cancel=cancel, threads=threads)
    if cancel is not None and cancel.is_set():
        raise Cancelled("run cancelled")
    return RunOutput(case, result, wires_run_document(result), None, None, time.perf_counter() - t0)
