"""The adaptive realization count (``--until``): realizations added in chunks until the
relative standard error of the gust factor and of the dynamic peak at the tower of interest
reaches a target.  Realization r always gets the same turbulence, so the result is
bit-identical to one run of the same count.  Nothing here prints.
"""

from __future__ import annotations

import dataclasses
import threading
from dataclasses import dataclass

import numpy as np

from ..core.case import Case
from ..core.results import Statistics
from .guard import Warn
from .run import RunResult, run_case
from .step1 import Progress

UNTIL_OVERSHOOT = 1.1  # next count: 10 % above the n (se ~ 1/sqrt(n)) predicts, to stop in few chunks
UNTIL_MAX_CHUNK = 50  # realizations added per chunk at most: bounds a chunk's memory (resource guard)


@dataclass(frozen=True)
class UntilInfo:
    """Adaptive realization count (``--until``).

    target, achieved: [-] relative standard errors (0.01 = 1 %); achieved is the largest
    se/|mean| of GF_Dy and of peak_dynamic over the reactions at the tower of interest whose
    GF_Dy is defined; reached: achieved <= target; max_realizations: the cap.
    """

    target: float
    achieved: float
    reached: bool
    max_realizations: int


def relative_standard_error(res: RunResult) -> float:
    """Largest se/|mean| of GF_Dy and peak_dynamic at the tower of interest over the reactions whose
    GF_Dy is defined (a reaction with a vanishing mean has no gust factor to converge) [-]."""
    from ..core.extremes import summarise

    j = res.tower_index
    gf = summarise(res.stats.GF_Dy[:, j])
    pk = summarise(res.stats.peak_dynamic[:, j])
    if gf.n < 2:
        return float("inf")
    ok = np.isfinite(gf.mean)
    if not ok.any():
        ok = pk.mean > 0
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.concatenate([(gf.se / np.abs(gf.mean))[ok & np.isfinite(gf.mean)], (pk.se / np.abs(pk.mean))[ok]])
    return float(rel.max()) if rel.size else 0.0


def join_runs(parts: list[RunResult]) -> RunResult:
    """One result from runs of consecutive disjoint realization sets of one case, in order
    (realization r always has the same turbulence, so this is bit-identical to one run)."""
    if len(parts) == 1:
        return parts[0]
    first = parts[0]
    return dataclasses.replace(
        first,
        realizations=np.concatenate([p.realizations for p in parts]),
        background=np.concatenate([p.background for p in parts], axis=0),
        resonant=np.concatenate([p.resonant for p in parts], axis=0),
        stats=Statistics.concatenate([p.stats for p in parts]),
    )


def run_until(
    case: Case,
    target: float,
    *,
    max_realizations: int = 1000,
    interpolate_states: bool = False,
    spectral_check: bool = True,
    progress: Progress | None = None,
    cancel: threading.Event | None = None,
    warn: Warn | None = None,
    threads: int = 1,
) -> RunResult:
    """Add realizations in chunks until :func:`relative_standard_error` <= ``target`` [-] or
    ``max_realizations`` have run.

    Starts with ``analysis.realizations`` (at most the cap); each next count is the one the
    1/sqrt(n) law predicts, times :data:`UNTIL_OVERSHOOT`, adding at most
    :data:`UNTIL_MAX_CHUNK` realizations per chunk.  Realization r always gets the same
    turbulence, so the result is bit-identical to ``run_case`` with the same count.
    """
    if not target > 0:
        raise ValueError(f"target {target!r} must be > 0")
    n = max(2, min(case.analysis.realizations, max_realizations))
    parts = [run_case(case, realizations=range(n), interpolate_states=interpolate_states,
                      spectral_check=spectral_check, progress=progress, cancel=cancel, warn=warn, threads=threads)]
    while True:
        res = join_runs(parts)
        achieved = relative_standard_error(res)
        done = res.realizations.size
        if achieved <= target or done >= max_realizations:
            return dataclasses.replace(res, until=UntilInfo(float(target), achieved, bool(achieved <= target),
                                                            int(max_realizations)))
        want = done * (achieved / target) ** 2 * UNTIL_OVERSHOOT if np.isfinite(achieved) else 2 * done
        nxt = int(min(max_realizations, done + UNTIL_MAX_CHUNK, max(done + 1, int(np.ceil(want)))))
        parts.append(run_case(case, realizations=np.arange(done, nxt), interpolate_states=interpolate_states,
                              spectral_check=False, progress=progress, cancel=cancel, warn=warn, threads=threads))
