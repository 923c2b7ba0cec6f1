"""Service layer: the one function per job that every front end calls.

CLI, TUI, Excel export and batch runners call these functions and nothing
deeper.  They take a validated :class:`~linecheck.core.case.Case`, report
progress through a callback ``progress(stage, done, total)`` and stop when the
``cancel`` event is set (raising :class:`~linecheck.core.errors.Cancelled`).
This module imports only the numerical core (numpy/scipy) and never prints.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .core.case import Case
from .core.static import MeanStates, drag_intensity, solve_mean_states
from .core.system import LineSystem
from .core.wind.mean import MeanWind, mean_wind

Progress = Callable[[str, int, int], None]


@dataclass(frozen=True)
class StaticResult:
    """Step-1 result of a case: the mean wind used and the mean states."""

    case: Case
    system: LineSystem
    wind: MeanWind
    mean: MeanStates


def mean_state_times(case: Case) -> np.ndarray:
    """Instants of the step-1 mean states [s] (synoptic: one state at t = 0)."""
    if case.wind.type == "synoptic":
        return np.zeros(1)
    from .core.wind.mean import event_window  # downburst only

    t0, t1 = event_window(case)
    return np.linspace(t0, t1, case.analysis.mean_states)


def mean_loads(case: Case, wind: MeanWind) -> np.ndarray:
    """Transverse mean load per unit length [N/m], shape (n_t, n_spans, ne+1) (paper Eq. 1)."""
    line = case.line
    return drag_intensity(wind.normal, case.wind.air_density, line.drag_coefficient, line.diameter)


def static_analysis(
    case: Case,
    *,
    progress: Progress | None = None,
    cancel: threading.Event | None = None,
) -> StaticResult:
    """Step 1 of the method: non-linear static analysis under the running-mean wind."""
    system = LineSystem(case.line)
    wind = mean_wind(case, system, mean_state_times(case))
    gy = mean_loads(case, wind)
    cb = None if progress is None else (lambda d, n: progress("step 1: mean states", d, n))
    mean = solve_mean_states(system, wind.time, gy, progress=cb, cancel=cancel)
    return StaticResult(case, system, wind, mean)
