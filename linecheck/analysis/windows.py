"""Long lines: the synoptic burn-in and the frequency-domain check run on windows of the line
around the tower of interest instead of the whole line (docs/method.md "Long lines"); this module
cuts the windows and builds their models.  Nothing here prints.
"""

from __future__ import annotations

import dataclasses

import numpy as np

from ..core import budget
from ..core.case import Case
from ..core.line_damping import structural_omega1
from ..core.model import build_model
from ..core.system import LineSystem
from .linear import SynopticModel, synoptic_model
from .step1 import StaticResult, static_result

#: lines with more spans (20): burn-in and check on windows around the tower of interest
CHECK_WINDOW_MIN_SPANS = budget.WINDOW_SPANS


def windowed(case: Case) -> bool:
    """True when the synoptic burn-in and check of ``case`` run on windows (a line of more than
    :data:`CHECK_WINDOW_MIN_SPANS` spans; docs/method.md "Long lines")."""
    return case.wind.type == "synoptic" and case.line.spans > CHECK_WINDOW_MIN_SPANS


def window_case(case: Case, system: LineSystem, half: int) -> tuple[Case, int, bool] | None:
    """The sub-line of ``half`` spans each side of the tower of interest (clipped at the strain
    towers that bound its strain section), cut at strain towers, with everything else as in
    ``case``; the index of its first tower in the whole line; and whether it is exact (the whole
    strain section: strain towers are pinned, so the rest of the line does not move it).  None
    when the window is the whole line.

    The cut ends hold the conductor at its clipped-in clamp points (a strain tower); a section
    window is re-framed on its own first span (stations from 0, the wind direction turned by
    that span's heading, the reference height pinned to the whole line's), so every node keeps
    its height, its plan position relative to the tower of interest and its wind."""
    line, wind = case.line, case.wind
    j = line.tower_of_interest - 1
    strain = [i for i, sp in enumerate(line.supports) if sp == "strain"]  # the two ends at least
    lo, hi = max(i for i in strain if i < max(j, 1)), min(i for i in strain if i > min(j, line.n_towers - 2))
    if j in (0, line.n_towers - 1):  # an end tower: its one strain section
        lo, hi = (0, hi) if j == 0 else (lo, j)
    a, b = max(lo, j - half), min(hi, j + half)
    if a == 0 and b == line.n_towers - 1:
        return None
    sup = ("strain",) + tuple(line.supports[a + 1:b]) + ("strain",)
    if wind.span_speeds is not None:
        wind = dataclasses.replace(wind, span_speeds=tuple(wind.span_speeds[a:b]))
    if line.is_section:
        new, wind = _section_window(case, system, wind, a, b, sup)
    else:
        new = dataclasses.replace(line, spans=b - a, supports=sup, tower_of_interest=j - a + 1)
    return dataclasses.replace(case, line=new, wind=wind), a, (a, b) == (lo, hi)


def _section_window(case: Case, system: LineSystem, wind, a: int, b: int, sup: tuple):
    """The line and wind of a section's window of towers ``a``..``b`` (0-based), re-framed on its
    first span: stations from 0, end towers strain, the wind direction [deg] turned by that span's
    heading and the reference height pinned to the whole line's."""
    from ..core.wind.mean import reference_height

    line = case.line
    s0 = line.towers[a].station
    tw = [dataclasses.replace(t, station=t.station - s0) for t in line.towers[a:b + 1]]
    for k in (0, -1):
        tw[k] = dataclasses.replace(tw[k], support="strain", angle=0.0, insulator_length=None)
    new = dataclasses.replace(line, spans=b - a, supports=sup, tower_of_interest=line.tower_of_interest - a,
                              towers=tuple(tw))
    d = wind.direction + float(np.degrees(system.span_headings[a]))  # global frame: x along the first span
    wind = dataclasses.replace(wind, direction=(d + 180.0) % 360.0 - 180.0, reference_height=reference_height(case))
    return new, wind


def window_models(case: Case, st: StaticResult, half: int,
                  cache: dict | None) -> tuple[Case, StaticResult, SynopticModel, int, bool] | None:
    """(window case, its static result, its synoptic model, first tower, exact) of ``half``, or
    None for the whole line (:func:`window_case`); memoised in ``cache`` (key ``half``; key
    "omega1": the structural-damping calibration [rad/s], the whole line's, as the time domain)."""
    cache = {} if cache is None else cache
    if half in cache:
        return cache[half]
    w = window_case(case, st.system, half)
    out = None
    if w is not None:
        wc, a, exact = w
        wst = static_result(wc)
        if "omega1" not in cache:  # structural damping: calibrated on the whole line, as the time domain
            cache["omega1"] = (structural_omega1(build_model(st.system, st.mean.state(0)))
                               if case.analysis.structural_ratio > 0 else None)
        out = (wc, wst, synoptic_model(wc, wst, omega1=cache["omega1"]), a, exact)
    cache[half] = out
    return out
