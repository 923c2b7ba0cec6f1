"""Running-mean wind along the line (paper section 2.1).

Contract used by the solver steps:

``mean_wind(case, system, times)`` returns a :class:`MeanWind` with the
running-mean velocity components at the still-air FE node positions of every span
(normal to the line, +y, and along it, +x) at the requested instants.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..case import Case
from ..errors import CaseError
from ..system import LineSystem


@dataclass(frozen=True)
class MeanWind:
    """Running-mean wind at the FE nodes.

    Attributes:
        time: [s] instants, shape (n_t,).
        normal: [m/s] component normal to the line (toward +y) at each span's FE nodes,
            shape (n_t, n_spans, ne+1) (span-local nodes, so a speed may jump at a tower).
        longitudinal: [m/s] component along the line (toward +x), same shape.
        point_p: [m] x-coordinate of point p (line point nearest the downburst centre;
            synoptic: the tower of interest).
    """

    time: np.ndarray
    normal: np.ndarray
    longitudinal: np.ndarray
    point_p: float


def synoptic_span_speeds(case: Case) -> np.ndarray:
    """Mean speed of every span [m/s], shape (n_spans,): ``span_speeds`` or V_ref."""
    if case.wind.span_speeds is None:
        return np.full(case.line.spans, case.wind.v_ref)
    return np.asarray(case.wind.span_speeds, dtype=float)


def mean_wind(case: Case, system: LineSystem, times: np.ndarray | None = None) -> MeanWind:
    """Running-mean wind at the FE nodes at ``times`` [s] (synoptic: constant)."""
    if case.wind.type == "synoptic":
        t = np.zeros(1) if times is None else np.asarray(times, dtype=float)
        v = synoptic_span_speeds(case)
        normal = np.broadcast_to(v[:, None], (t.size, system.n_spans, system.ne + 1)).copy()
        p = float(system.tower_x[case.line.tower_of_interest - 1])
        return MeanWind(t, normal, np.zeros_like(normal), p)
    raise CaseError("downburst running-mean field is not available yet", key="wind.type")
