"""Planning a batch before anything runs: the distinct cases, their files loaded, results
reused by ``--resume``, the resource guard, and the realization chunks (one task each).

:func:`plan_cases` returns one :class:`CaseState` per distinct case, in the order given;
a case that cannot run (a bad file, above the memory limit) is already ``"failed"`` there and
a reused one ``"skipped"``, so the scheduler only submits the ``"pending"`` ones.
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from ..analysis.guard import check_budget
from ..core.case import Case, case_hash, load_case
from ..core.errors import CaseError, LinecheckError
from .report import CaseOutcome, RunJob
from .saving import json_name_for, saved_result
from .tasks import apply_changes

DEFAULT_CHUNK = 10  # realizations per task (each task repeats step 1 and the model set-up)


def auto_chunk_size(total_realizations: int, workers: int) -> int:
    """Realizations per task: :data:`DEFAULT_CHUNK`, or fewer so that every worker gets work
    when the whole batch has fewer than ``DEFAULT_CHUNK`` realizations per worker."""
    return max(1, min(DEFAULT_CHUNK, total_realizations // max(1, workers)))


def chunk_ranges(n: int, size: int = DEFAULT_CHUNK) -> list[list[int]]:
    """Split ``range(n)`` into ceil(n/size) chunks of consecutive realizations, sizes within one.

    Results do not depend on the chunks (see :mod:`linecheck.batch.runner`).
    """
    size = max(1, int(size))
    if n <= 0:
        return []
    k = -(-n // size)
    edges = [round(i * n / k) for i in range(k + 1)]
    return [list(range(a, b)) for a, b in zip(edges[:-1], edges[1:])]


@dataclass
class CaseState:
    """One case of a batch while it runs.

    ``chunks``: its realization chunks (one task each, ``tasks`` in the same order);
    ``parts``: each chunk's result once in (``None`` while it runs); ``done``: realizations
    done so far (fractional while chunks report progress); ``in_overall``: counted in the
    batch's overall realizations (not when the resource guard refused it); ``t0`` [s]: its
    start (``time.perf_counter``).
    """

    index: int
    job: RunJob
    outcome: CaseOutcome
    case: Case | None = None
    chunks: list[list[int]] = field(default_factory=list)
    parts: list[Any] = field(default_factory=list)
    tasks: list[Any] = field(default_factory=list)  # its chunks' tasks (scheduler.Task)
    done: float = 0.0
    started: bool = False
    t0: float = 0.0
    in_overall: bool = True

    @property
    def pending(self) -> bool:
        return self.outcome.status == "pending"


def plan_cases(cases: Sequence[str | Path | RunJob], out_dir: Path | None, *, resume: bool = False,
               until: tuple[float, int] | None = None) -> list[CaseState]:
    """One state per distinct case (the same file with the same changes runs once), loaded,
    with saved results reused (``resume``) and the resource guard applied.

    Raises CaseError when two cases would save to the same result file.
    """
    jobs = distinct_jobs(cases, out_dir)
    states = [load_state(i, job, out_dir) for i, job in enumerate(jobs)]
    if resume:
        for st in states:
            reuse_saved(st)
    for st in states:
        guard(st, until)
    return states


def distinct_jobs(cases: Sequence[str | Path | RunJob], out_dir: Path | None) -> list[RunJob]:
    """The jobs of ``cases`` without repeats; CaseError if two would write the same result."""
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
    return jobs


def load_state(index: int, job: RunJob, out_dir: Path | None) -> CaseState:
    """The case of ``job`` loaded (with its changes) and hashed; ``"failed"`` if it cannot be."""
    st = CaseState(index, job, CaseOutcome(job.path, job.label or job.path.stem))
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
    return st


def reuse_saved(st: CaseState) -> None:
    """``--resume``: the case is ``"skipped"`` if its saved result carries its current hash."""
    o = st.outcome
    if st.case is None or o.json_path is None:
        return
    doc = saved_result(o.json_path, o.hash or "", st.job.changes)
    if doc is not None:
        o.status, o.doc = "skipped", doc
        st.done = o.realizations


def guard(st: CaseState, until: tuple[float, int] | None) -> None:
    """The resource guard of a case to run, before any starts.

    Each task checks its own chunk, but the merged result keeps every realization's histories,
    so a case above the memory limit fails here alone (its one-line estimate, a CaseError) and
    the others run, as does a case with ``[[wires]]`` (a run analyses one wire:
    :func:`~linecheck.analysis.guard.require_one_wire`); above half the limit or about 10 minutes it runs with a warning
    (``outcome.warning``, the ``case_warning`` event).
    """
    o = st.outcome
    if st.case is None or o.status != "pending":
        return
    n = max(2, min(o.realizations, int(until[1]))) if until is not None else o.realizations  # run_until's start
    try:
        check_budget(st.case, "run", realizations=n, warn=lambda m, o=o: setattr(o, "warning", m))
    except CaseError as err:
        o.status, o.error, o.error_kind = "failed", str(err), type(err).__name__
        st.done = o.realizations  # its own progress complete; none of it in the overall count
        st.in_overall = False
