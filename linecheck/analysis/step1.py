"""Step 1 of the method: the non-linear static analysis of the line under the running-mean wind
(the mean loads of paper Eq. 1), from the still-air state to the mean states at the instants of
:func:`mean_state_times`.  Nothing here prints.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from ..core.case import Case
from ..core.crossflow import NodeWind, applies, node_wind
from ..core.damping import node_tangents
from ..core.loads import mean_drag, mean_loads
from ..core.static import MeanStates, solve_mean_states
from ..core.system import LineSystem
from ..core.wind.mean import MeanWind, mean_vector_at_nodes, mean_wind
from .guard import Warn, check_budget, warn_case

Progress = Callable[[str, int, int], None]


@dataclass(frozen=True)
class StaticResult:
    """Step-1 result of a case: the mean wind used and the mean states."""

    case: Case
    system: LineSystem
    wind: MeanWind
    mean: MeanStates

    @cached_property
    def cross_wind(self) -> NodeWind | None:
        """The cross-flow form's wind at the global nodes at the mean states, on each state's
        deformed conductor axes (:class:`~linecheck.core.crossflow.NodeWind`, (n_k, n_nodes) each),
        its load directions d_j at each node's largest |V_perp| among the states; None for the
        horizontal-normal form (:func:`~linecheck.core.crossflow.applies`).  Computed once: the
        damping, the record's loads and the frequency-domain check share it."""
        if not applies(self.case, self.system):
            return None
        v = mean_vector_at_nodes(self.case, self.system, self.mean.time)
        return node_wind(self.system, v, node_tangents(self.mean.nodes))


def mean_state_times(case: Case) -> np.ndarray:
    """Instants of the step-1 mean states [s] (synoptic: one state at t = 0)."""
    if case.wind.type == "synoptic":
        return np.zeros(1)
    from ..core.wind.mean import event_window  # downburst only

    t0, t1 = event_window(case)
    return np.linspace(t0, t1, case.analysis.mean_states)


def static_analysis(
    case: Case,
    *,
    progress: Progress | None = None,
    cancel: threading.Event | None = None,
    warn: Warn | None = None,
) -> StaticResult:
    """Step 1 of the method: non-linear static analysis under the running-mean wind.

    ``warn(message)`` receives the case's warnings (:func:`~linecheck.analysis.guard.warn_case`)
    and resource warnings (:func:`~linecheck.analysis.guard.check_budget`)."""
    warn_case(case, warn)
    check_budget(case, "static", warn=warn)
    return static_result(case, progress=progress, cancel=cancel)


def static_result(case: Case, *, progress: Progress | None = None,
                  cancel: threading.Event | None = None) -> StaticResult:
    """:func:`static_analysis` without the case's warnings and the resource guard: for jobs that
    ran the guard themselves.  ``progress(stage, done, total)`` over the mean states; a set
    ``cancel`` stops with :class:`~linecheck.core.errors.Cancelled`.  ValueError for a case with
    ``[[wires]]``: its ``line`` is only the first wire's (every wire:
    :func:`~linecheck.analysis.wires_static.wires_static_analysis`)."""
    if case.has_wires:
        raise ValueError(f"{case.name}: step 1 analyses one wire: a case with [[wires]] goes through "
                         "wires_static_analysis (each wire's wire_case)")
    system = LineSystem(case.line)
    wind = mean_wind(case, system, mean_state_times(case))
    gy = mean_loads(case, wind)  # paper Eq. 1
    cb = None if progress is None else (lambda d, n: progress("step 1: mean states", d, n))
    drag = mean_drag(case, system, wind)  # a section, cross-flow: the drag on the deformed conductor
    mean = solve_mean_states(system, wind.time, gy, progress=cb, cancel=cancel, drag=drag)
    return StaticResult(case, system, wind, mean)
