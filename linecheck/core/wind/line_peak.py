"""The largest running-mean speed the line sees over a downburst, and where and when.

V_ref fixes the running mean at one point, p (paper section 2.1).  Every other conductor point
sees its own history, and under a travelling or off-centre storm some towers can see more than
V_ref, or (p beyond the modelled section) none sees V_ref at all.  :func:`line_peak` reports the
field's largest running-mean speed anywhere on the line over the analysed window, so that a
designer sees what the other towers get beside V_ref at p.

"On the line" is what the loads see: the global FE nodes at their still-air positions and heights
(:func:`linecheck.core.wind.mean.mean_speed_at_nodes`, the same evaluator as steps 2-3); "over
the event" is the analysed window (:func:`~linecheck.core.wind.mean.event_window`) on the record's
time step, refined to 1e-9 of the window between the grid instants around the largest value.
Nothing here prints.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np

from ..case import Case
from ..errors import CaseError
from ..system import LineSystem
from .mean import event_window, mean_speed_at_nodes


@dataclass(frozen=True)
class LinePeak:
    """The line's largest running-mean speed over the event.

    Attributes:
        speed: [m/s] the largest running-mean speed |V| at a conductor node over the window.
        v_ref: [m/s] V_ref, the peak running mean at p (by construction).
        over_v_ref: [-] speed / v_ref.
        time: [s] when.
        node: global FE node index (0-based, line order) where.
        station: [m] that node's distance along the line from the first tower.
        xy: [m] its still-air plan position (global frame; equal-span form: (x, 0)).
        height: [m] its height above ground the field is evaluated at (equal-span form: ``height``).
    """

    speed: float
    v_ref: float
    over_v_ref: float
    time: float
    node: int
    station: float
    xy: tuple[float, float]
    height: float

    def to_dict(self) -> dict:
        """JSON-ready dict (SI units; ``xy`` as a list)."""
        d = asdict(self)
        d["xy"] = [float(v) for v in self.xy]
        return d


def line_peak(case: Case, system: LineSystem | None = None) -> LinePeak:
    """:class:`LinePeak` of a downburst case (any running-mean model).

    The running mean at every global node on the record's grid (``analysis.time_step`` over
    :func:`event_window`), then a bounded refinement in time at the node of the largest value.
    Raises :class:`CaseError` for a synoptic case (its mean is V_ref, or the span speeds, always).
    """
    if case.wind.type != "downburst":
        raise CaseError("is not a downburst case: the line's largest running mean is reported for downbursts",
                        key="wind.type")
    system = system if system is not None else LineSystem(case.line)
    t0, t1 = event_window(case)
    n = max(int(round((t1 - t0) / case.analysis.time_step)) + 1, 3)
    t = np.linspace(t0, t1, n)
    speed = mean_speed_at_nodes(case, system, t)
    k, j = np.unravel_index(int(np.argmax(speed)), speed.shape)
    best_t, best = float(t[k]), float(speed[k, j])
    lo, hi = t[max(k - 1, 0)], t[min(k + 1, n - 1)]
    if hi > lo:
        from scipy.optimize import minimize_scalar

        def minus(tt: float) -> float:
            return -float(mean_speed_at_nodes(case, system, np.array([tt]))[0, j])

        res = minimize_scalar(minus, bounds=(lo, hi), method="bounded", options={"xatol": 1e-9 * max(1.0, t1 - t0)})
        if -res.fun > best:
            best_t, best = float(res.x), float(-res.fun)
    xyz = system.node_xyz0[j]
    v_ref = float(case.wind.v_ref)
    return LinePeak(best, v_ref, best / v_ref, best_t, int(j), float(system.node_station[j]),
                    (float(xyz[0]), float(xyz[1])), float(system.node_height[j]))
