"""Uplift at suspension towers as a result of step 1, and the jobs it stops.

Step 1 reports the vertical margin and the weight span of every suspension tower in still air and
in every mean state (:mod:`linecheck.core.uplift`); where an insulator would be in compression it
computes the state with that clamp held at its still-air point.  The dynamic model (steps 2-3,
the natural modes, the frequency-domain check, the burn-in) linearises about the mean states with
every suspension insulator hanging in tension, so each job that builds a linear model calls
:func:`require_tension` after step 1 and refuses the case in one line naming the tower and its
margin (:class:`~linecheck.core.errors.UpliftError`, exit 1).  Messages give forces in N (the
front ends show kN).  Nothing here prints.
"""

from __future__ import annotations

import numpy as np

from ..core.errors import UpliftError
from ..core.system import LineSystem
from ..core.uplift import Uplift, uplift
from .step1 import StaticResult


def step1_uplift(st: StaticResult) -> Uplift:
    """Vertical margin [N] and weight span [m] of every suspension tower of a step-1 result, in
    still air and in every mean state (:func:`linecheck.core.uplift.uplift`)."""
    return uplift(st.system, st.mean)


def tower_label(system: LineSystem, j: int) -> str:
    """``"tower T3"`` (a section: the tower's name) or ``"tower 3"`` (the equal-span form); j 0-based."""
    return f"tower {system.line.towers[j].name}" if system.is_section else f"tower {j + 1}"


def state_label(st: StaticResult, k: int | None) -> str:
    """Where a step-1 value holds: ``"in still air"`` (k None), ``"under the mean wind"``
    (synoptic) or ``"under the mean wind at t = 120.0 s"`` (downburst state k)."""
    if k is None:
        return "in still air"
    if st.mean.time.size == 1:
        return "under the mean wind"
    return f"under the mean wind at t = {st.mean.time[k]:.1f} s"


def uplift_towers(st: StaticResult) -> list[tuple[int, list[tuple[int | None, float]]]]:
    """Every tower with uplift (its clamp held in still air or in some mean state), in tower order:
    ``(tower 0-based, [(state, margin [N]), ...])`` with still air first (state None) when held
    there, then the held mean state of the smallest margin."""
    u = step1_uplift(st)
    out = []
    for j in np.flatnonzero(u.held_still_air | u.held.any(axis=0)):
        where: list[tuple[int | None, float]] = [(None, float(u.margin_still_air[j]))] if u.held_still_air[j] else []
        if u.held[:, j].any():
            k = int(np.argmin(np.where(u.held[:, j], u.margin[:, j], np.inf)))
            where.append((k, float(u.margin[k, j])))
        out.append((int(j), where))
    return out


def uplift_warning(st: StaticResult) -> str | None:
    """One line naming every uplifting tower and its margins [N], or None (no uplift)."""
    towers = uplift_towers(st)
    if not towers:
        return None
    text = ", ".join(f"{tower_label(st.system, j)} (margin " + ", ".join(f"{m:.0f} N {state_label(st, k)}"
                                                                       for k, m in where) + ")"
                     for j, where in towers)
    return (f"{st.case.name}: uplift at {text}: a suspension insulator would be in compression; step 1 holds "
            "the clamp at its still-air point and the dynamic analyses (run, modes, spectral) refuse the case")


def require_tension(st: StaticResult) -> None:
    """Raise :class:`~linecheck.core.errors.UpliftError` (one line: the case, the tower, its margin
    [N] and the state) when a suspension clamp is held (uplift) in still air or in a mean state:
    the dynamic model linearises about those states with every suspension insulator hanging in
    tension.  Every job that builds a linear model calls it after step 1."""
    first = step1_uplift(st).first_uplift()
    if first is None:
        return
    j, k, m = first
    raise UpliftError(f"{st.case.name}: uplift at {tower_label(st.system, j)} (margin {m:.0f} N {state_label(st, k)}): "
                      "the dynamic model needs every suspension insulator in tension; see `linecheck static`")
