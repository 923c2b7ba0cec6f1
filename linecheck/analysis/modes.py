"""Natural modes of a case (``linecheck modes``): the undamped modes of the still-air and of the
mean state, and the damped (complex) modes of the mean state paired with them by shape.
Nothing here prints.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from ..core.case import Case
from ..core.line_damping import reference_state_index
from ..core.model import build_model
from .guard import Warn, check_budget, warn_case
from .linear import damping_matrices
from .step1 import static_result
from .uplift import require_tension

if TYPE_CHECKING:  # names of annotations only
    from ..core.modes import Modes


@dataclass(frozen=True)
class ModesResult:
    """Natural modes of the still-air state and of the mean state.

    ``mean_time`` [s] is the instant of the mean state used: synoptic 0; downburst the
    step-1 instant of the largest wind-induced mean reaction at the tower of interest.
    """

    case: Case
    still_air: Modes
    mean: Modes
    mean_time: float
    damped: object = None  # ComplexModes of the mean state with the case's damping
    #: per undamped mean-state mode, its damped counterpart (:func:`~linecheck.core.modes.pair_by_shape`):
    #: frequency [Hz], damping ratio [-] and MAC [-] of the paired complex mode (NaN where none)
    paired_hz: np.ndarray | None = None
    paired_ratio: np.ndarray | None = None
    paired_mac: np.ndarray | None = None


def modes_analysis(case: Case, *, n_modes: int = 20, warn: Warn | None = None) -> ModesResult:
    """Natural frequencies and mode shapes of the still-air and the mean state (the first
    ``n_modes``), and the mean state's complex modes with the case's damping."""
    from ..core.modes import natural_modes, pair_by_shape
    from ..core.spectral import complex_modes

    warn_case(case, warn)
    check_budget(case, "modes", warn=warn)
    st = static_result(case)
    require_tension(st)  # modes of the still-air and mean states: every insulator hanging
    system, mean = st.system, st.mean
    k = reference_state_index(case, mean)
    still = natural_modes(build_model(system, mean.still_air), n_modes)
    model = build_model(system, mean.state(k))
    at_mean = natural_modes(model, n_modes)
    cm = complex_modes(model, damping_matrices(case, st, [model], states=[k])[0], vectors=True)
    index, mac = pair_by_shape(at_mean, model, cm.right, cm.S)  # the damped counterpart of each mode
    ok = index >= 0
    paired_hz, paired_ratio = np.full(index.size, np.nan), np.full(index.size, np.nan)
    paired_hz[ok], paired_ratio[ok] = cm.frequencies_hz[index[ok]], cm.damping_ratio[index[ok]]
    n = min(n_modes, cm.poles.size)
    damped = dataclasses.replace(cm, frequencies_hz=cm.frequencies_hz[:n], damping_ratio=cm.damping_ratio[:n],
                                 poles=cm.poles[:n], right=None, left=None, S=None, mass=None, expansion=None,
                                 norm=None)
    return ModesResult(case, still, at_mean, float(mean.time[k]), damped, paired_hz, paired_ratio, mac)
