"""Model spread in a batch (``batch --models``: the same cases under several downburst
running-mean models): one run per (case, downburst model), then one document per
case with the typed ``models`` block and the envelope (:func:`linecheck.io.jsonout.with_models`)."""

from __future__ import annotations

from pathlib import Path

from ..core.case import load_case
from ..io.document import FailedRun, RunDocument
from ..service import model_changes, parse_models
from .report import BatchReport, RunJob


def model_jobs(paths: list[Path], models: str) -> tuple[list[RunJob], dict[Path, list[tuple[str, int]]]]:
    """The jobs of ``batch --models``: every case under every model of :func:`parse_models`
    (results ``<stem>.<model>.json``), and per case file its (model, job index) list."""
    jobs: list[RunJob] = []
    plan: dict[Path, list[tuple[str, int]]] = {}
    for p in paths:
        case = load_case(p)
        plan[p] = []
        if case.wind.type != "downburst":  # a synoptic case in the batch runs once, as without --models
            plan[p].append(("", len(jobs)))
            jobs.append(RunJob(p))
            continue
        for m in parse_models(case, models):
            plan[p].append((m, len(jobs)))
            jobs.append(RunJob(p, label=f"{case.name} [{m}]", changes=model_changes(case, m) or None,
                               json_name=f"{p.stem}.{m}.json"))
    return jobs, plan


def combined_documents(report: BatchReport, plan: dict[Path, list[tuple[str, int]]]) -> list[RunDocument | FailedRun]:
    """One typed document per case file: the run under the case's own model (else the first model
    that ran) with ``model``, ``models`` and ``models_envelope`` (and ``models_failed``); a
    :class:`FailedRun` if none ran."""
    from dataclasses import replace

    from ..io.jsonout import with_models

    out: list[RunDocument | FailedRun] = []
    for path, entries in plan.items():
        if entries[0][0] == "":  # synoptic: its own document
            out.append(report.outcomes[entries[0][1]].excel_doc())
            continue
        runs = {m: report.outcomes[i] for m, i in entries}
        done = {m: o.doc for m, o in runs.items() if o.ok and o.doc is not None}
        if not done:
            first = runs[entries[0][0]]
            out.append(FailedRun(first.name, first.error or first.status))
            continue
        case = load_case(path)
        main = case.wind.downburst.model_name if case.wind.downburst.model_name in done else next(iter(done))
        failed = {m: o.error for m, o in runs.items() if m not in done}
        out.append(with_models(replace(done[main], case=case.name), main,
                               {m: d.reactions for m, d in done.items()}, failed))
    return out
