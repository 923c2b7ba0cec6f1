"""Design-code verdicts (``linecheck codes``): the conductor wind load of each of four design codes
(ASCE 74, IEC 60826, EN 50341, AS/NZS 7000; docs/codes.md) at every tower of the line, plus the
code's wind-induced angle load at an angle tower, beside linecheck's design peak of the transverse
reaction.  Nothing here prints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.case import Case
from ..core.codes import CODES_COMPARED, CODES_PEAK  # what is compared: one text for every front end
from ..core.static import solve_static_batch
from ..core.system import LineSystem
from .guard import require_one_wire

if TYPE_CHECKING:  # names of annotations only
    from .run import RunResult


@dataclass(frozen=True)
class ReactionCheck:
    """One reaction against one code: loads [N], ratio = linecheck_peak / code_load [-].

    ``code_load`` = |``wind_load`` + ``angle_load``| (:data:`~linecheck.core.codes.CODES_COMPARED`):
    ``wind_load`` [N] >= 0 the code's conductor wind load on the tower's transverse axis,
    ``angle_load`` [N] the code's wind-induced angle load, positive where it adds to the wind
    load (0 on a straight tower); both None where the code has no load.
    """

    code_load: float | None
    linecheck_peak: float | None
    ratio: float | None
    verdict: str
    wind_load: float | None = None
    angle_load: float | None = None


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
    """The four codes side by side (docs/codes.md); ``peak`` says what ``linecheck_peak`` is and
    ``compared`` what ``code_load`` is."""

    case: Case
    checks: tuple
    peak: str
    compared: str = CODES_COMPARED


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

    require_one_wire(case, "codes")  # the codes' loads are of the case's line: one wire
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
    """Design-code loads beside linecheck's peaks, per tower (docs/codes.md, "What is compared").

    Ry at tower j: wind load = cos(alpha_j/2) |sum over the adjacent spans of w(v_n) L_n / 2|, w
    the code's load per length scaled by (v_n / v_ref)^2 for per-span synoptic speeds and by the
    signed cos(d + h_n)|cos(d + h_n)| of the wind's normal component; angle load = the code's
    wind-induced angle load (:func:`angle_loads`) with its sense relative to the wind load; code
    load = |wind load + angle load|.  ``run``: the run whose peaks are compared (None: the code
    loads only).  Verdict "code covers" when linecheck's peak is at most the code load, else
    "code exceeded by x %"; unverified codes get no verdict.
    """
    system = run.system if run is not None else LineSystem(case.line)
    # [m] wind spans on each tower's y: a span's normal n_i and the tower frame's y_j (bisector's
    # normal) differ by alpha_j/2, so n_i . y_j = cos(alpha_j/2) (docs/codes.md "Sections")
    eq = equivalent_spans(case, signed=True) * np.cos(0.5 * deviation_angles(system))
    sense = np.where(eq < 0.0, -1.0, 1.0)  # the code wind load's sense on each tower's y
    peaks = design_peaks(run, 1) if run is not None else None  # (n_towers,) Ry, the design value
    loads = code_loads(case, strict=strict)
    angle = angle_loads(case, loads, system)
    checks = []
    for load in loads:
        a = sense * angle[load.code] if load.code in angle else np.zeros(system.n_towers)
        towers = [TowerCheck(j + 1, {"Ry": reaction_check(load, float(peaks[j]) if peaks is not None else None,
                                                          float(abs(eq[j])), float(a[j]))})
                  for j in range(system.n_towers)]
        checks.append(CodeCheck(load.code, load.edition, load.verified, load.provision, load.load_per_length,
                                dict(load.inputs), load.note, tuple(towers)))
    return CodesResult(case, tuple(checks), CODES_PEAK, CODES_COMPARED)


def span_wind_factors(case: Case, system: LineSystem, *, signed: bool = False) -> np.ndarray:
    """[-] each span's code wind load relative to the load per length at v_ref, shape (n_spans,):
    (v_n / v_ref)^2 (per-span synoptic speeds) times cos^2(d + h_n), the wind's normal component on
    a span of a section or under an oblique wind (the codes' sin^2(Omega) / cos^2(Phi) factors,
    docs/codes.md "Sections"); ``signed``: cos(d + h_n)|cos(d + h_n)|, negative where the wind
    pushes the span toward its -normal."""
    line, wind = case.line, case.wind
    n_spans = line.spans
    speeds = np.asarray(wind.span_speeds if wind.span_speeds is not None else [wind.v_ref] * n_spans, dtype=float)
    scale = (speeds / wind.v_ref) ** 2 if wind.v_ref > 0 else np.ones(n_spans)
    if system.is_section or wind.direction != 0.0:
        # the wind's normal component on every span, cos(d + h_i)
        c = np.cos(np.radians(wind.direction) + system.span_headings)
        scale = scale * (c * np.abs(c) if signed else c**2)
    return scale


def equivalent_spans(case: Case, *, signed: bool = False) -> np.ndarray:
    """[m] the wind span of every tower at v_ref, shape (n_towers,): the sum over its adjacent spans
    of L_n / 2 scaled by :func:`span_wind_factors` (docs/codes.md "Sections"); ``signed``: each
    half span with the sense of its wind load along its span's normal."""
    system = LineSystem(case.line)
    half = 0.5 * system.span_lengths * span_wind_factors(case, system, signed=signed)  # [m] half spans at v_ref
    eq_span = np.zeros(system.n_spans + 1)
    eq_span[:-1] += half
    eq_span[1:] += half
    return eq_span


def deviation_angles(system: LineSystem) -> np.ndarray:
    """[rad] line deviation alpha_j at every tower, + turning left, shape (n_towers,): the angle
    between its two spans (0 at the end towers, whose frames follow their one span)."""
    alpha = np.array(system.tower_angles, dtype=float)
    alpha[[0, -1]] = 0.0
    return alpha


def code_tensions(case: Case, loads: list, system: LineSystem) -> np.ndarray:
    """[N] horizontal conductor tension of every span under each code's wind load case, shape
    (len(loads), n_spans): linecheck's static model of the section (step 1's solver, docs/method.md)
    under the weight and, on span n, the code's load w (:class:`~linecheck.core.codes.CodeLoad`
    ``load_per_length``) times :func:`span_wind_factors` (signed), uniform along the span, per
    metre of horizontal span as the codes define it (w L_n / L_u,n per unit unstretched length)."""
    f = span_wind_factors(case, system, signed=True) * system.span_lengths / system.unstretched_lengths
    w = np.array([x.load_per_length for x in loads], dtype=float)
    gy = np.repeat((w[:, None] * f[None, :])[..., None], system.ne + 1, axis=-1)  # (n_codes, n_spans, ne+1)
    states = solve_static_batch(system, gy, labels=[f"{x.code} wind load case (design codes)" for x in loads])
    return np.stack([s.tension for s in states])


def angle_loads(case: Case, loads: list, system: LineSystem | None = None) -> dict:
    """[N] each code's wind-induced angle load at every tower, on the tower frame's y (+ to the
    left, the inside of a left turn), shape (n_towers,), by code name (codes with a load only):

        A_j = (dT_{j-1} + dT_j) sin(alpha_j / 2)      (= 2 dT sin(alpha_j / 2) for equal tensions)

    the y-component of the resultant of the two spans' tension rises dT_n = T_n(code) - T_n(still
    air) (horizontal tensions, :func:`code_tensions`; statics of the clamp: the unit vectors
    e_j - e_{j-1} of the two spans differ by 2 sin(alpha_j/2) along the bisector's normal), alpha_j
    the line deviation (:func:`deviation_angles`): the wires' resultant at an angle, with the wind's
    effect on the tension (NESC C2-2017 Rule 252B3, IEC 60826:2003; docs/codes.md "Angle towers:
    the decision and why").  Zero, with no static solve, on a line without angle towers."""
    # statics of the clamp, A = sum_n dT_n (e_n . y_j) with e_j . y_j = -e_{j-1} . y_j = sin(alpha_j/2)
    system = system if system is not None else LineSystem(case.line)
    loaded = [x for x in loads if x.load_per_length is not None]
    alpha = deviation_angles(system)
    if not loaded or not np.any(alpha):
        return {x.code: np.zeros(system.n_towers) for x in loaded}
    dT = code_tensions(case, loaded, system) - system.still_air.tension[None, :]  # (n_codes, n_spans)
    A = np.zeros((len(loaded), system.n_towers))
    A[:, 1:-1] = (dT[:, :-1] + dT[:, 1:]) * np.sin(0.5 * alpha[1:-1])
    return {x.code: A[k] for k, x in enumerate(loaded)}


def reaction_check(load, peak: float | None, eq_span: float, angle_load: float = 0.0) -> ReactionCheck:
    """One code ``load`` (:class:`~linecheck.core.codes.CodeLoad`) on a tower's wind span
    ``eq_span`` [m] (on the tower's transverse axis) plus its ``angle_load`` [N] (+ where it adds
    to the wind load) against linecheck's design ``peak`` [N] (None: no run), with its verdict."""
    if load.load_per_length is None:
        verdict = {"none": "no provision", "not established": "provision not established"}.get(
            load.provision, "outside the code's validity")
        return ReactionCheck(None, peak, None, verdict)
    W = float(load.load_per_length * eq_span)
    F = abs(W + angle_load)
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
    return ReactionCheck(F, peak, ratio, verdict, W, float(angle_load))
