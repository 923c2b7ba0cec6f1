"""Design-code verdicts (``linecheck codes``): the conductor wind load of each of four design codes
(ASCE 74, IEC 60826, EN 50341, AS/NZS 7000; docs/codes.md) at every tower of the line, beside
linecheck's design peak of the transverse reaction.  Nothing here prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.case import Case
from ..core.codes import CODES_PEAK  # what ``linecheck_peak`` is: one text for every front end
from ..core.system import LineSystem

if TYPE_CHECKING:  # names of annotations only
    from .run import RunResult


@dataclass(frozen=True)
class ReactionCheck:
    """One reaction against one code: loads [N], ratio = linecheck_peak / code_load [-]."""

    code_load: float | None
    linecheck_peak: float | None
    ratio: float | None
    verdict: str


@dataclass(frozen=True)
class TowerCheck:
    """A tower's checks; ``reactions`` maps a reaction name ("Ry") to its check."""

    index: int  # 1-based
    reactions: dict


@dataclass(frozen=True)
class CodeCheck:
    """One code's conductor wind load at every tower of the section, beside linecheck's peaks.

    ``load_per_length`` [N/m] on the wind span at ``v_ref`` (None: no provision or outside the
    code's validity, see ``note``); ``towers`` per tower (1-based ``index``).
    """

    code: str
    edition: str
    verified: bool
    provision: str
    load_per_length: float | None
    inputs: dict
    note: str
    towers: tuple


@dataclass(frozen=True)
class CodesResult:
    """The four codes side by side (docs/codes.md); ``peak`` says what ``linecheck_peak`` is."""

    case: Case
    checks: tuple
    peak: str


def design_peaks(run: RunResult, component: int) -> np.ndarray:
    """[N] linecheck's design peak of one reaction component at every tower, shape (n_towers,):
    the Gumbel design value of ``peak_dynamic`` at ``analysis.design_fractile``, or
    the mean over realizations where the fit is undefined (one realization)."""
    pk = run.summary().statistics["peak_dynamic"]
    mean = pk.summary.mean[:, component]
    if pk.gumbel is None:
        return mean
    design = pk.gumbel.design[:, component]
    return np.where(np.isfinite(design), design, mean)


def code_loads(case: Case, *, strict: bool = True) -> list:
    """Each code's :class:`~linecheck.core.codes.CodeLoad` for ``case``: at the case's mean speed at
    the conductor height ``line.height``, v_ref (z/z_ref)^alpha (the case's own profile).

    ``strict``: a value outside a code's validity raises :class:`CaseError`; otherwise the
    code is reported with no load and the message in its note.
    """
    from ..core import codes as C
    from ..core.errors import CaseError

    line, wind, cc = case.line, case.wind, case.codes
    src = str(case.source) if case.source else None
    if wind.type == "downburst":
        return [C.downburst_load(code) for code in C.CODES]
    # the codes' wind span: the section's common span (equal spans); a section of unequal spans:
    # Eq. 17's L_x at the tower of interest (docs/codes.md "Sections")
    system = LineSystem(line)
    span = system.common_span_length if system.equal_spans else system.span_lengths_at_tower(line.tower_of_interest - 1)
    # the case's 10-minute mean at the codes' height h: v_ref carried from its reference height by
    # the case's own power law (wind.profile_exponent), as steps 1-3 load the wire
    from ..core.wind.mean import profile_factor

    v_h = float(wind.v_ref * profile_factor(case, np.array(line.height)))
    args = (v_h, line.height, span, line.diameter, line.drag_coefficient)
    calls = {
        "ASCE74": lambda: C.asce74_wire_load(*args, cc.asce74_exposure or C.TERRAIN_MAP["ASCE74"][cc.terrain],
                                             source=src),
        "IEC60826": lambda: C.iec60826_conductor_load(
            *args, cc.iec60826_terrain or C.TERRAIN_MAP["IEC60826"][cc.terrain], source=src),
        "EN50341": lambda: C.en50341_conductor_load(*args, cc.en50341_terrain or C.TERRAIN_MAP["EN50341"][cc.terrain],
                                                    source=src),
        "ASNZS7000": lambda: C.asnzs7000_conductor_load(*args, turbulence_intensity=wind.turbulence_intensity,
                                                        source=src),
    }
    out = []
    for code in C.CODES:
        try:
            out.append(calls[code]())
        except CaseError as err:
            if strict:
                raise
            out.append(C.CodeLoad(code, C.EDITIONS[code], False, "synoptic", None, {}, f"not applied: {err}"))
    return out


def codes_analysis(case: Case, run: RunResult | None = None, *, strict: bool = True) -> CodesResult:
    """Design-code conductor wind loads beside linecheck's peaks, per tower.

    Ry at tower j: code load = sum over the adjacent spans of w(v_n) L_n / 2, w the code's
    load per length scaled by (v_n / v_ref)^2 for per-span synoptic speeds.  ``run``: the run
    whose peaks are compared (None: the code loads only).  Verdict "code covers" when
    linecheck's peak is at most the code load, else "code exceeded by x %"; unverified codes
    get no verdict.
    """
    eq_span = equivalent_spans(case)
    peaks = design_peaks(run, 1) if run is not None else None  # (n_towers,) Ry, the design value
    checks = []
    for load in code_loads(case, strict=strict):
        towers = [TowerCheck(j + 1, {"Ry": reaction_check(load, float(peaks[j]) if peaks is not None else None,
                                                          float(eq_span[j]))})
                  for j in range(case.line.spans + 1)]
        checks.append(CodeCheck(load.code, load.edition, load.verified, load.provision, load.load_per_length,
                                dict(load.inputs), load.note, tuple(towers)))
    return CodesResult(case, tuple(checks), CODES_PEAK)


def equivalent_spans(case: Case) -> np.ndarray:
    """[m] the wind span of every tower at v_ref, shape (n_towers,): the sum over its adjacent spans
    of L_n / 2 scaled by (v_n / v_ref)^2 (per-span synoptic speeds) and by cos^2(d + h_n), the
    wind's normal component on each span of a section or under an oblique wind (docs/codes.md
    "Sections")."""
    line, wind = case.line, case.wind
    n_spans = line.spans
    speeds = np.asarray(wind.span_speeds if wind.span_speeds is not None else [wind.v_ref] * n_spans, dtype=float)
    scale = (speeds / wind.v_ref) ** 2 if wind.v_ref > 0 else np.ones(n_spans)
    system = LineSystem(line)
    if system.is_section or wind.direction != 0.0:
        # the wind's normal component on every span, cos(d + h_i)
        scale = scale * np.cos(np.radians(wind.direction) + system.span_headings) ** 2
    half = 0.5 * system.span_lengths * scale  # [m] equivalent half spans at v_ref
    eq_span = np.zeros(n_spans + 1)
    eq_span[:-1] += half
    eq_span[1:] += half
    return eq_span


def reaction_check(load, peak: float | None, eq_span: float) -> ReactionCheck:
    """One code ``load`` (:class:`~linecheck.core.codes.CodeLoad`) on a tower's wind span
    ``eq_span`` [m] against linecheck's design ``peak`` [N] (None: no run), with its verdict."""
    if load.load_per_length is None:
        verdict = {"none": "no provision", "not established": "provision not established"}.get(
            load.provision, "outside the code's validity")
        return ReactionCheck(None, peak, None, verdict)
    F = float(load.load_per_length * eq_span)
    ratio = peak / F if (peak is not None and F > 0) else None
    if ratio is None:
        verdict = "no linecheck run"
    elif not load.verified:
        verdict = "unverified: not judged"
    elif ratio <= 1.0:
        verdict = "code covers"
    else:
        verdict = f"code exceeded by {100 * (ratio - 1):.0f} %"
    if ratio is not None and not math.isfinite(ratio):
        ratio = None
    return ReactionCheck(F, peak, ratio, verdict)
