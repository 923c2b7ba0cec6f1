"""Step 1 of every wire of a case with ``[[wires]]``: each wire's static analysis and, at every
tower, each attachment's reactions and the tower's totals (forces and moments about its base).

The wires meet only at the towers, which step 1 takes as rigid, so in statics they are
independent: wire w's step 1 is the static analysis of its single-wire case
(:func:`~linecheck.core.case_wires.wire_case`: the bundle-equivalent wire on its attachments,
under the case's one wind).  At tower j the attachment of wire w is the point
r = (0, y, z) of the tower frame (x along the line, y to its left, z up from the tower's
ground; docs/wires.md), where the wire's reaction R = (R_x, R_y, R_z) acts (z down, as every
reaction: docs/method.md).  The tower's totals are the resultant of its attachments' reactions
and its moment about the base point (0, 0, 0)
(:func:`~linecheck.core.tower_totals.tower_totals`).  Nothing here prints.
"""

from __future__ import annotations

import dataclasses
import threading
from dataclasses import dataclass

import numpy as np

from ..core.case import Case, wire_case
from ..core.tower_totals import tower_totals
from ..core.uplift import Uplift
from .guard import Warn, check_budget, warn_case, warn_once
from .step1 import Progress, StaticResult, static_result
from .uplift import step1_uplift, uplift_warning


@dataclass(frozen=True)
class WiresStatic:
    """Step 1 of every wire of a case with ``[[wires]]``.

    Attributes:
        case: the case with ``[[wires]]``.
        wires: each wire's step-1 result (of its single-wire case), in ``case.wires`` order.
        y, z: [m] attachment point of wire w on tower j, (n_towers, n_wires): y to the left of the
            line's centre, z above the tower's ground (the insulator's top or the strain clamp).
        reactions: [N] every attachment's reaction in every mean state, (n_t, n_towers, n_wires, 3),
            in the tower frames (x along the tower's heading, y to its left, z down).
        still_air: [N] the same in still air, (n_towers, n_wires, 3).
    """

    case: Case
    wires: tuple[StaticResult, ...]
    y: np.ndarray
    z: np.ndarray
    reactions: np.ndarray
    still_air: np.ndarray

    @property
    def time(self) -> np.ndarray:
        """[s] instants of the mean states, (n_t,) (every wire's: the case's one wind)."""
        return self.wires[0].mean.time

    @property
    def totals(self) -> np.ndarray:
        """[N, N m] every tower's totals in every mean state, (n_t, n_towers, 6) (:func:`~linecheck.core.tower_totals.tower_totals`)."""
        return tower_totals(self.reactions, self.y, self.z)

    @property
    def totals_still_air(self) -> np.ndarray:
        """[N, N m] every tower's totals in still air, (n_towers, 6)."""
        return tower_totals(self.still_air, self.y, self.z)

    def uplift(self, w: int) -> Uplift:
        """Wire w's (0-based) margin [N] and weight span [m] at every suspension attachment."""
        return step1_uplift(self.wires[w])


def attachment_points(case: Case) -> tuple[np.ndarray, np.ndarray]:
    """[m] y and z of every wire's attachment on every tower of a case with ``[[wires]]``, each
    (n_towers, n_wires) in ``case.wires`` order (the tower's type's attachment)."""
    atts = [[case.tower_type(t.type).attachment(w.name) for w in case.wires] for t in case.line.towers]
    return (np.array([[a.y for a in row] for row in atts], dtype=float),
            np.array([[a.z for a in row] for row in atts], dtype=float))


def wires_result(case: Case, results: list[StaticResult] | tuple[StaticResult, ...]) -> WiresStatic:
    """The :class:`WiresStatic` of ``case`` from every wire's step-1 result (``case.wires``
    order): the reactions turned into the tower frames and stacked by wire."""
    times = [st.mean.time for st in results]
    if any(t.shape != times[0].shape or not np.array_equal(t, times[0]) for t in times):
        raise ValueError("the wires' mean states are at different instants: one wind has one set")
    R = np.stack([st.system.to_tower_frames(st.mean.reactions) for st in results], axis=2)
    R0 = np.stack([st.system.to_tower_frames(st.mean.still_air.reactions) for st in results], axis=1)
    y, z = attachment_points(case)
    return WiresStatic(case, tuple(results), y, z, R, R0)


def wire_progress(progress: Progress | None, name: str) -> Progress | None:
    """``progress`` with each stage named for wire ``name`` ("step 1, wire P"), or None."""
    return None if progress is None else (lambda stage, done, total: progress(f"{stage}, wire {name}", done, total))


def wires_static_analysis(case: Case, *, progress: Progress | None = None, cancel: threading.Event | None = None,
                          warn: Warn | None = None) -> WiresStatic:
    """Step 1 of every wire of ``case`` (a case with ``[[wires]]``): the case's warnings once
    (:func:`~linecheck.analysis.guard.warn_case`: they name the wire), then for each wire the
    resource guard and step 1 of its single-wire case.  ``progress(stage, done, total)`` per
    wire (the stage names it); a set ``cancel`` stops with
    :class:`~linecheck.core.errors.Cancelled`.  ValueError for a case without wires."""
    if not case.has_wires:
        raise ValueError(f"{case.name}: no [[wires]]: step 1 of its one wire is static_analysis")
    warn_case(case, warn)
    once = warn_once(warn)  # the same resource warning of every wire: once
    results = []
    for w in case.wires:
        single = wire_case(case, w.name)
        check_budget(single, "static", warn=once)
        results.append(static_result(single, progress=wire_progress(progress, w.name), cancel=cancel))
    return wires_result(case, results)


def wires_uplift_warnings(case: Case) -> list[str]:
    """``linecheck check``'s uplift warnings of a case with ``[[wires]]``: step 1 of every wire
    (still air and the mean wind; no resource guard: ``check`` ran it) and one line per wire
    with uplift, naming it (:func:`~linecheck.analysis.uplift.uplift_warning`)."""
    out = []
    for w in case.wires:
        st = static_result(wire_case(case, w.name))
        message = uplift_warning(dataclasses.replace(st, case=dataclasses.replace(st.case, name=f"{case.name}, wire "
                                                                                                f"{w.name}")))
        if message:
            out.append(message)
    return out
