"""The burn-in of a synoptic record: the start discarded so that the transient of the initial
conditions has decayed, derived from the least-damped significant complex mode of the mean
state (a long line's: from the modes of a window around the tower of interest).  Nothing here
prints.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from ..core.case import Case
from .linear import SynopticModel, synoptic_model
from .step1 import StaticResult
from .windows import window_models, windowed

BURN_IN_DECAY = np.log(100.0)  # transient amplitude down to 1 %: t = ln(100) / (zeta omega)
BURN_IN_MAX_FACTOR = 10.0  # derived burn-in capped at this multiple of the analysed duration
SIGNIFICANT_FRACTION = 0.01  # a mode matters if it adds > 1 % of the largest background r.m.s.
BURN_IN_WINDOW_HALF = 8  # the burn-in of a long line: the modes of the 16-span window


@dataclass(frozen=True)
class BurnIn:
    """Discarded start of a synoptic record, long enough for the start-up transient to decay.

    Attributes:
        seconds: [s] burn-in used; required: [s] time for the transient of the least-damped
        significant mode to decay to 1 % (inf if undamped); mode_hz [Hz], zeta [-]: that mode;
        sufficient: whether the analysed record is stationary for every significant mode;
        source: where ``seconds`` comes from.
    """

    seconds: float
    required: float
    mode_hz: float
    zeta: float
    sufficient: bool
    source: str


#: the burn-in of a downburst record
NO_BURN_IN = BurnIn(0.0, 0.0, float("nan"), float("nan"), True, "none: a downburst starts from a weak running mean")


def _significant_modes(case: Case, sm: SynopticModel, f_top: float):
    """Frequencies [Hz], damping ratios [-], decay rates [1/s] of the complex modes and the
    indices of the significant ones: those adding more than :data:`SIGNIFICANT_FRACTION` of the
    largest background r.m.s. at the tower of interest, or every mode up to ``f_top`` [Hz] with
    the paper's damping (or without eigenvectors)."""
    from ..core.spectral import modal_contributions
    from ..core.wind.turbulence import length_scale

    # the paper's damping gets no burn-in, and its verdict counts every mode in the band
    if sm.modes.right is not None and case.analysis.damping != "paper":
        mc = modal_contributions(
            sm.model, sm.modes, sm.load_per_v, case.line.tower_of_interest - 1,
            sigma=case.wind.turbulence_intensity * case.wind.v_ref, length_scale=length_scale(case),
            v_mean=case.wind.v_ref, coherence_decay=case.wind.coherence_decay, max_hz=f_top,
        )
        return mc.frequencies_hz, mc.damping_ratio, mc.decay_rate, np.flatnonzero(mc.significant(SIGNIFICANT_FRACTION))
    cm = sm.modes  # paper damping (or no eigenvectors): every mode in the band counts (conservative)
    return cm.frequencies_hz, cm.damping_ratio, -cm.poles.real, np.flatnonzero(cm.frequencies_hz <= f_top)


def burn_in(case: Case, sm: SynopticModel) -> BurnIn:
    """Burn-in of a synoptic run from the least-damped significant complex mode: the time
    ln(100) / (zeta omega) for its transient to decay to 1 %, capped at
    :data:`BURN_IN_MAX_FACTOR` times the analysed duration, unless ``analysis.burn_in`` is given
    (none with the paper's damping)."""
    duration = case.analysis.duration if case.analysis.duration is not None else 600.0
    freq, zeta, rate_all, sig = _significant_modes(case, sm, 0.5 / case.analysis.time_step)
    if sig.size == 0:
        required, f1, z1 = 0.0, float("nan"), float("nan")
    else:
        i = sig[np.argmin(rate_all[sig])]
        rate = rate_all[i]
        required = float(BURN_IN_DECAY / rate) if rate > 0 else float("inf")
        f1, z1 = float(freq[i]), float(zeta[i])
    if case.analysis.burn_in is not None:
        used, src = float(case.analysis.burn_in), "analysis.burn_in"
    elif case.analysis.damping == "paper":
        used, src = 0.0, "none with damping = \"paper\" (the paper's method)"
    else:
        used, src = min(required, BURN_IN_MAX_FACTOR * duration), "derived from the least-damped significant mode"
    return BurnIn(float(used), required, f1, z1, bool(used >= required), src)


def synoptic_burn_in(case: Case, st: StaticResult, sm: SynopticModel | None = None,
                     cache: dict | None = None) -> BurnIn:
    """:func:`burn_in` of a synoptic case; a long line's (:func:`~linecheck.analysis.windows.windowed`)
    from the modes of the window of :data:`BURN_IN_WINDOW_HALF` spans each side of the tower of
    interest (the modes that matter there), never from a dense eigenproblem of the whole line;
    ``cache``: the window models' memo (:func:`~linecheck.analysis.windows.window_models`)."""
    if windowed(case):
        w = window_models(case, st, BURN_IN_WINDOW_HALF, cache)
        if w is not None:
            wc, _, wsm, _, _ = w
            b = burn_in(wc, wsm)
            if case.analysis.burn_in is None and case.analysis.damping != "paper":
                b = dataclasses.replace(b, source=f"{b.source}, in the {wc.line.spans}-span window around the tower of interest")
            return b
    return burn_in(case, sm if sm is not None else synoptic_model(case, st))
