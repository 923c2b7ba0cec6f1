"""Join runs of disjoint realization subsets of one case into one :class:`RunResult`.

A batch splits a case into realization chunks (``service.run_case(case,
realizations=[...])``).  Realization r always gets the same turbulence whatever
else is run with it (seeds spawned per realization from ``analysis.seed``), and the
step-1 mean M(t) does not depend on the turbulence, so concatenating the parts in
realization order reproduces a single run: background/resonant along axis 0,
statistics with :meth:`Statistics.concatenate`, realization indices likewise.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..core.results import Statistics
from ..service import RunResult


def merge_runs(parts: list[RunResult]) -> RunResult:
    """One :class:`RunResult` from runs of disjoint realization subsets of the same case.

    Parts may arrive in any order; the result lists realizations in increasing order
    (sorted by each part's first realization, then checked to be strictly increasing).

    Raises:
        ValueError: no parts, parts of different cases (name, time grid or mean
            reaction differ), or overlapping realization sets.
    """
    if not parts:
        raise ValueError("merge_runs needs at least one part")
    if len(parts) == 1:
        return parts[0]
    ordered = sorted(parts, key=lambda p: int(p.realizations[0]) if p.realizations.size else -1)
    first = ordered[0]
    for p in ordered[1:]:
        if p.case.name != first.case.name or not np.array_equal(p.time, first.time):
            raise ValueError(f"cannot merge runs of different cases ({first.case.name!r}, {p.case.name!r})")
        if not np.array_equal(p.mean, first.mean):
            raise ValueError(f"cannot merge runs of {first.case.name!r}: their mean reactions differ")
    real = np.concatenate([np.asarray(p.realizations, dtype=int) for p in ordered])
    if real.size > 1 and np.any(np.diff(real) <= 0):
        raise ValueError(f"cannot merge runs of {first.case.name!r}: realization sets overlap or interleave")
    return dataclasses.replace(
        first,
        realizations=real,
        background=np.concatenate([p.background for p in ordered], axis=0),
        resonant=np.concatenate([p.resonant for p in ordered], axis=0),
        stats=Statistics.concatenate([p.stats for p in ordered]),
    )
