"""The linearised line at its step-1 mean states: the damping matrices of the record's models
and the synoptic mean state's model, damping, load per unit turbulence and complex modes, which
the burn-in, the frequency-domain check and the time domain share.  Nothing here prints.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ..core.case import Case
from ..core.line_damping import damping_stack
from ..core.loads import synoptic_load_per_v, to_global_nodes
from ..core.model import LinearModel, build_model
from .record import record_mean_wind
from .step1 import StaticResult
from .uplift import require_tension


def damping_matrices(case: Case, st: StaticResult, models: list[LinearModel], states: list[int] | None = None,
                     omega1: float | None = None) -> np.ndarray:
    """Damping of mean states [N s/m], upper band storage, shape (len(models), 6, n_dof).

    ``models[i]`` is the model of mean state ``states[i]`` (default: all states in order).
    Aerodynamic (``analysis.damping``) plus stiffness-proportional structural damping
    calibrated at the lowest mode of the reference mean state (docs/method.md, damping), or
    at ``omega1`` [rad/s] when given (a window of a long line keeps the whole line's);
    :func:`~linecheck.core.line_damping.damping_stack`.
    """
    states = list(range(len(models))) if states is None else list(states)
    vn = to_global_nodes(st.system, st.wind.normal)  # (n_k, n_nodes)
    cross = st.cross_wind
    u = None if cross is None else (cross.perp_vectors, cross.directions)
    return damping_stack(case, st.system, st.mean, vn, models, states, omega1, u)


@dataclass(frozen=True)
class SynopticModel:
    """The linearised synoptic mean state shared by the time and frequency domains.

    Attributes:
        model: the linear model of the mean state; damping: [N s/m] its damping, upper band
        storage (6, n_dof); load_per_v: [N s/m] load per unit along-wind turbulence at the global
        nodes (paper Eq. 5), (n_nodes,); modes: its complex modes
        (:class:`~linecheck.core.spectral.ComplexModes`).
    """

    model: object
    damping: np.ndarray
    load_per_v: np.ndarray
    modes: object


def synoptic_model(case: Case, st: StaticResult, *, vectors: bool = True, omega1: float | None = None) -> SynopticModel:
    """Model, damping, load per unit turbulence (Eq. 5) and complex modes of the synoptic state
    (with eigenvectors when ``vectors``: the burn-in and the modal superposition of the
    frequency-domain check need them); ``omega1`` [rad/s]: see :func:`damping_matrices`."""
    from ..core.spectral import complex_modes

    require_tension(st)
    system = st.system
    model = build_model(system, st.mean.state(0))
    damping = damping_matrices(case, st, [model], omega1=omega1)[0]
    vn = to_global_nodes(system, st.wind.normal)[0]
    vl = perp = None
    cross = st.cross_wind
    if cross is not None:  # cross-flow form: along each node's direction d_j, |V_perp| for |V_n|
        model = replace(model, load_directions=cross.directions)
        vn, vl, perp = cross.along[0], cross.rest[0], cross.perp[0]
    elif system.is_section or case.wind.direction != 0.0:
        # the normal component of the along-wind fluctuation, v cos(phi), as the time domain
        vl = record_mean_wind(case, st, np.zeros(1))[1][0]
    a = synoptic_load_per_v(case, model, vn, vl, perp)
    f_top = 0.75 / case.analysis.time_step
    modes = complex_modes(model, damping, max_hz=f_top, vectors=vectors)
    return SynopticModel(model, damping, a, modes)
