"""The resource guard, the one-wire guard and the checks of ``linecheck check`` beyond the case
schema.

Every job calls :func:`check_budget` before it allocates anything; it refuses first a case with
``[[wires]]`` for a job that analyses one wire (:func:`require_one_wire`).  :func:`check_case`
adds what ``check`` verifies without running (field file, V_ref at point p, record length).
Imports only the case model, the budget and (for downbursts) the mean-wind module: ``linecheck
check`` answers without loading the solvers.  Nothing here prints.
"""

from __future__ import annotations

from collections.abc import Callable

from ..core import budget
from ..core.case import Case, case_warnings
from ..core.errors import CaseError

Warn = Callable[[str], None]

#: The jobs a case with ``[[wires]]`` runs through :func:`check_budget`: every other job analyses
#: one wire (the case's ``line`` is only its first wire's) and :func:`require_one_wire` refuses
#: it.  Its dynamic run is :func:`~linecheck.analysis.wires_run.run_wires` (``linecheck run``),
#: which guards each wire's single-wire case instead (``linecheck run`` and the TUI's run call
#: it); the one-wire run (``run_case``: a batch's run) stays refused.
WIRES_JOBS = frozenset({"static"})


def require_one_wire(case: Case, job: str) -> None:
    """Refuse ``job`` on a case with ``[[wires]]`` unless it is one of :data:`WIRES_JOBS`: one
    :class:`~linecheck.core.errors.CaseError` line (exit 2) naming the file, what such a case
    runs and what to do.  :func:`check_budget` calls it, so every job meets it before any work;
    the few entry points without a resource guard (code loads, scan, batch) call it themselves.
    ``job`` "run" is the one-wire run (``run_case``), which a batch calls."""
    if not case.has_wires or job in WIRES_JOBS:
        return
    what = ("a batch's run of several wires is not available yet: run the case with `linecheck run` (or in the "
            "TUI)"
            if job == "run" else
            f"`{job}` of several wires is not available yet: run each wire as a single-wire case")
    raise CaseError(f"a case with several wires runs `check`, `static` and `linecheck run` (every attachment, the "
                    f"tower totals and load trees); {what}",
                    file=str(case.source) if case.source else None, key="wires")


def warn_once(warn: Warn | None) -> Warn | None:
    """``warn`` passing each distinct message once (a job over several wires meets the same
    resource warning for each wire); None without ``warn``."""
    if warn is None:
        return None
    told: set[str] = set()

    def once(message: str) -> None:
        if message not in told:
            told.add(message)
            warn(message)

    return once


def check_budget(case: Case, job: str = "run", *, warn: Warn | None = None, **kwargs) -> budget.Estimate:
    """Estimated peak memory and time of ``job`` (:mod:`linecheck.core.budget`); raises
    :class:`~linecheck.core.errors.CaseError` (exit 2) for a job a case with ``[[wires]]`` does
    not run (:func:`require_one_wire`) and above the memory limit, and calls ``warn(message)``
    above the warning thresholds.  Every job calls it first."""
    require_one_wire(case, job)
    return budget.guard(case, job, warn, **kwargs)


def warn_case(case: Case, warn: Warn | None) -> None:
    """Hand each of :func:`~linecheck.core.case.case_warnings` (values the schema allows but
    that are probably mistyped, e.g. a weight in kg/m) to ``warn(message)``.  A job calls it once,
    before its work."""
    if warn is not None:
        for message in case_warnings(case):
            warn(message)


def check_case(case: Case, *, warn: Warn | None = None) -> budget.Estimate:
    """Checks of ``linecheck check`` beyond the schema: the field file is read and validated,
    the downburst is scaled to V_ref at p, the record has enough steps, and the run fits the
    resource limits; :func:`warn_case`'s warnings go to ``warn``.  Raises
    :class:`~linecheck.core.errors.CaseError`."""
    warn_case(case, warn)
    if case.wind.type == "downburst":
        from ..core.wind.mean import downburst_field, load_field_table

        db = case.wind.downburst
        if db is not None and db.field_path is not None:
            load_field_table(db.field_path)
        downburst_field(case)
    if not case.wind.v_ref > 0:
        raise CaseError("value 0.0 is not allowed: expected v_ref > 0 for a run (turbulence is scaled by it)",
                        file=str(case.source) if case.source else None, key="wind.v_ref")
    est = budget.estimate(case, "run")
    if est.n_steps < 4:
        raise CaseError(f"value {case.analysis.time_step!r} gives {est.n_steps} steps: expected at least 4",
                        file=str(case.source) if case.source else None, key="analysis.time_step")
    return budget.check(est, case, warn)
