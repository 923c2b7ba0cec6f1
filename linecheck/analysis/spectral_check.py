"""The frequency-domain check of a synoptic case: estimate 1 (linear random vibration of the
step-1 model, the time domain's model and damping; a long line's on widening windows around the
tower of interest) and estimate 2 (the Davenport/Castanheta closed form), and the sanity check
of the time-domain r.m.s. against estimate 1.  Nothing here prints.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.case import Case
from ..core.system import LineSystem
from .guard import Warn, check_budget
from .linear import SynopticModel, synoptic_model
from .record import record_time
from .step1 import StaticResult, static_result
from .uplift import require_tension
from .windows import window_models, windowed

if TYPE_CHECKING:  # names of annotations only
    from ..core.spectral import DavenportEstimate, SpectralEstimate
    from .run import RunResult

CHECK_WINDOW_HALVES = (6, 8, 10, 12, 16, 20, 24, 32, 48, 64, 96, 128)  # spans each side, tried in turn
CHECK_WINDOW_RTOL = 0.005  # accept a window when the estimate moved by less than this from the previous one
DAVENPORT_TOLERANCE = 0.15  # estimate 2 shown only where within 15 % of estimate 1
SANITY_QUANTITIES = ("rms_background", "rms_fluctuating")
NUMERICAL_TOLERANCE = 0.03  # frequency-grid and estimator bias allowance, relative


@dataclass(frozen=True)
class CheckWindow:
    """The part of a long line on which the frequency-domain check ran.

    Attributes:
        spans: spans of the window; first_tower: 0-based index (in the whole line) of its
            first tower; estimated_error: [-] per reaction (R_x, R_y, R_z), the relative change
            of the estimate (largest of the dynamic peak and the fluctuating r.m.s.) from the
            previous, smaller window -- the run-time error estimate of the reduction, shape (3,);
        windows: spans of every window tried, in order.
    """

    spans: int
    first_tower: int
    estimated_error: np.ndarray
    windows: tuple[int, ...]


@dataclass(frozen=True)
class SpectralResult:
    """Frequency-domain check of a synoptic case.

    ``exact``: estimate 1 (linear random vibration of the step-1 model), reactions
    (R_x, R_y, R_z) at the tower of interest; ``davenport``: estimate 2 for the
    transverse reaction (closed form) and whether it is within 15 % of estimate 1;
    ``window``: for a long line, the window estimate 1 ran on and its estimated error
    (None: the whole line).
    """

    case: Case
    exact: SpectralEstimate
    davenport: DavenportEstimate
    davenport_applicable: bool
    davenport_note: str
    window: CheckWindow | None = None


Estimator = Callable[[SynopticModel, int], "SpectralEstimate"]


def spectral_analysis(case: Case, *, static: StaticResult | None = None,
                      synoptic: SynopticModel | None = None, warn: Warn | None = None,
                      windows: dict | None = None) -> SpectralResult:
    """Frequency-domain estimates for a synoptic case (same model and damping as the time domain).

    A long line (:func:`~linecheck.analysis.windows.windowed`) gets estimate 1 on windows of
    :data:`CHECK_WINDOW_HALVES` spans each side of the tower of interest, widened until the
    estimate moves by less than :data:`CHECK_WINDOW_RTOL` (the last change is reported as the
    estimated error) or the window is the whole line; the mean reaction is always the whole
    line's step 1.  ``windows``: memo of the window models shared with the burn-in
    (:func:`~linecheck.analysis.windows.window_models`)."""
    from ..core.errors import CaseError

    if case.wind.type != "synoptic":
        raise CaseError("the frequency-domain check is for synoptic cases only (a downburst is non-stationary)",
                        file=str(case.source) if case.source else None, key="wind.type")
    if static is None:
        check_budget(case, "spectral", warn=warn)
    st = static if static is not None else static_result(case)
    require_tension(st)  # the linear model of the mean state: every insulator hanging
    estimate = _estimator(case, st)
    j = case.line.tower_of_interest - 1

    def whole():  # the time domain's model
        return estimate(synoptic if synoptic is not None else synoptic_model(case, st), j)

    if windowed(case):
        exact, window = _window_estimate(case, st, estimate, whole, {} if windows is None else windows)
    else:
        exact, window = whole(), None
    reason = closed_form_not_applicable(case, st.system)
    if reason:
        from ..core.spectral import DavenportEstimate

        nan = float("nan")
        return SpectralResult(case, exact, DavenportEstimate(*([nan] * 9)), False, f"not applicable: {reason}", window)
    return SpectralResult(case, exact, *_davenport(case, st, exact), window)


def _estimator(case: Case, st: StaticResult) -> Estimator:
    """estimate(m, tower): estimate 1 of synoptic model ``m`` at ``tower`` (0-based in ``m``'s
    line) with the whole line's step-1 mean reaction at the tower of interest (each tower's own
    frame) over the record of ``case``."""
    from ..core.results import ZERO_MEAN_RTOL
    from ..core.spectral import random_vibration
    from ..core.wind.turbulence import length_scale

    wind = case.wind
    t = record_time(case)
    rw = st.system.to_tower_frames(st.mean.reactions_wind)  # each tower's own frame
    mean_r = rw[0, case.line.tower_of_interest - 1]
    tol = ZERO_MEAN_RTOL * float(np.abs(rw[0]).max())
    L_u = length_scale(case)

    def estimate(m: SynopticModel, tower: int):
        return random_vibration(
            m.model, m.damping, m.load_per_v, mean_r, tower, modes=m.modes, sigma=wind.turbulence_intensity * wind.v_ref,
            length_scale=L_u, v_mean=wind.v_ref, coherence_decay=wind.coherence_decay, duration=float(t[-1] - t[0]),
            band=(1e-5, 0.5 / case.analysis.time_step), zero_mean_tol=tol,
        )

    return estimate


def _window_estimate(case: Case, st: StaticResult, estimate: Estimator, whole: Callable[[], SpectralEstimate],
                     windows: dict) -> tuple[SpectralEstimate, CheckWindow | None]:
    """Estimate 1 of a long line on widening windows (:data:`CHECK_WINDOW_HALVES`) and the
    window it ran on: the first that is the tower of interest's whole strain section (exact),
    or whose estimate moved by at most :data:`CHECK_WINDOW_RTOL` from the previous window's;
    ``whole()`` (window None) when the window reaches the whole line."""
    j = case.line.tower_of_interest - 1
    prev, tried, window = None, [], None
    for half in CHECK_WINDOW_HALVES:
        w = window_models(case, st, half, windows)
        if w is None:  # the window reached the whole line: the exact estimate
            return whole(), None
        wc, _, wsm, a, whole_section = w
        exact = estimate(wsm, j - a)
        tried.append(wc.line.spans)
        if whole_section:  # the strain section of the tower of interest: exact
            return exact, CheckWindow(wc.line.spans, a, np.zeros(3), tuple(tried))
        if prev is not None:
            err = np.maximum(relative_change(exact.peak_dynamic, prev.peak_dynamic),
                             relative_change(exact.rms_fluctuating, prev.rms_fluctuating))
            window = CheckWindow(wc.line.spans, a, err, tuple(tried))
            if float(err.max()) <= CHECK_WINDOW_RTOL:
                break
        prev = exact
    return exact, window


def _davenport(case: Case, st: StaticResult, exact: SpectralEstimate) -> tuple[DavenportEstimate, bool, str]:
    """Estimate 2 (Davenport/Castanheta closed form) of the transverse reaction, whether it is
    within :data:`DAVENPORT_TOLERANCE` of estimate 1 ``exact``, and the note saying so."""
    from ..core.spectral import davenport_gust_factor
    from ..core.wind.turbulence import length_scale

    line, wind = case.line, case.wind
    t = record_time(case)
    H = float(st.mean.tension[0].mean())
    mu = line.mass_per_length
    span = st.system.common_span_length  # the closed form is for equal spans
    f1 = np.sqrt(H / mu) / (2 * span)  # taut-string fundamental (Irvine 1981 Eq. 3.21)
    dav = davenport_gust_factor(
        span=span, v_mean=wind.v_ref, intensity=wind.turbulence_intensity, length_scale=length_scale(case),
        coherence_decay=wind.coherence_decay, f1=f1, mass_per_length=mu, air_density=wind.air_density,
        drag_coefficient=line.drag_coefficient, diameter=line.diameter, duration=float(t[-1] - t[0]),
        height=line.height,
    )
    ref = exact.GF_Dy[1]
    if not np.isfinite(ref):
        return dav, False, "transverse mean is zero: no gust factor to compare"
    diff = abs(dav.GF_Dy - ref) / ref
    ok = diff <= DAVENPORT_TOLERANCE
    note = (f"within {100 * diff:.0f} % of the exact estimate" if ok else
            f"differs by {100 * diff:.0f} % from the exact estimate (> 15 %): the closed form's uniform "
            "influence line and single mode do not represent this system; use estimate 1")
    return dav, ok, note


def relative_change(new: np.ndarray, old: np.ndarray) -> np.ndarray:
    """|new - old| / |new| per component, a component below 1e-6 of the largest scaled by the largest [-]."""
    scale = np.maximum(np.abs(new), 1e-6 * float(np.abs(new).max()) + 1e-300)
    return np.abs(new - old) / scale


def closed_form_not_applicable(case: Case, system: LineSystem) -> str:
    """Why the Davenport/Castanheta closed form (estimate 2) does not apply to this case, or ""
    when it does: it assumes one straight row of equal, level spans, a uniform wind normal to
    the line and one mean speed."""
    if not system.is_section:
        if case.wind.direction != 0.0 or case.wind.profile_exponent != 0.0:
            return "the closed form assumes a uniform wind normal to the line (direction 0, no profile)"
        return ""
    if not system.equal_spans:
        return "the spans of this section are unequal (the closed form is for one span length)"
    if np.any(system.tower_angles):
        return "the section has angle towers (the closed form is for a straight line)"
    if np.ptp(system.clamp_points[:, 2]) > 0.0:
        return "the section has inclined spans (the closed form is for level spans)"
    if case.wind.direction != 0.0 or case.wind.profile_exponent != 0.0:
        return "the closed form assumes a uniform wind normal to the line (direction 0, no profile)"
    return ""


@dataclass(frozen=True)
class SanityItem:
    """One time- vs frequency-domain comparison of the sanity check (:func:`sanity_check`):
    r.m.s. [N] of the time domain (mean and std over realizations) and of estimate 1, the
    allowed difference [N] and whether the difference is within it."""

    reaction: str
    quantity: str
    time_domain: float
    time_domain_std: float
    frequency_domain: float
    allowed: float
    ok: bool


def sanity_check(res: RunResult) -> list[SanityItem]:
    """Compare the time-domain r.m.s. with estimate 1 at the tower of interest.

    A difference is flagged when it exceeds what sampling explains: three standard
    errors of the realization mean (std / sqrt(N)) plus a 3 % numerical allowance.
    Components whose r.m.s. is below 1 % of the largest are skipped.
    """
    if res.spectral is None:
        return []
    from ..core.results import REACTIONS

    j = res.tower_index
    n = res.stats.n_samples
    ex = res.spectral.exact
    items = []
    scale = float(np.max(ex.rms_fluctuating))
    for q in SANITY_QUANTITIES:
        td = res.stats.mean(q)[j]
        sd = res.stats.std(q)[j]
        fd = getattr(ex, q)
        for c, r in enumerate(REACTIONS):
            if fd[c] < 0.01 * scale:
                continue
            allowed = 3.0 * sd[c] / np.sqrt(max(n, 1)) + NUMERICAL_TOLERANCE * fd[c]
            items.append(SanityItem(r, q, float(td[c]), float(sd[c]), float(fd[c]), float(allowed),
                                    bool(abs(td[c] - fd[c]) <= allowed)))
    return items
