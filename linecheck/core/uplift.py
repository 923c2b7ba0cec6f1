"""Uplift at suspension towers: the vertical margin and the weight span of every step-1 state.

At a suspension tower the conductor hangs from a rigid insulator, which can carry tension only.
The quantity a designer checks is the vertical force of the conductor on the clamp:

    margin = R_z = -f_z                                                            [N]

the downward vertical component of the force the conductor exerts on its clamp (``R_z`` of the
reactions, z down; f_z the same force z up, :func:`linecheck.core.catenary.conductor_forces`).
Positive: the insulator hangs in tension.  Zero or negative: the adjacent spans pull the clamp up
(uplift, e.g. a valley tower or a tower much lower than its neighbours) and a suspension
insulator would be in compression; step 1 then holds that clamp at its still-air point for the
state (as if held down; :func:`linecheck.core.catenary.equilibrium`) and :attr:`Uplift.held` says
so.  At equilibrium the insulator lies along f, so it hangs below its fixed top exactly when
f_z < 0: the sign of the margin is the admissibility of the pendulum.  For a shallow span the
vertical force at a clamp is the sum over its two spans of H tan(slope of the conductor at the
clamp) (Irvine 1981, ch. 2: V = H dz/dx at a support of a cable under vertical load).

    weight span = R_z / W                                                          [m]

the length of conductor whose weight the tower carries (W per unit unstretched length); for a
shallow span in still air, the horizontal distance between the low points of the two adjacent
spans (the low point may lie outside a span: the weight span is then shorter than the spans,
and negative under uplift).  Under wind it includes any vertical wind load on the spans.

Strain towers have no insulator to lift: their entries are NaN (``uplift: null`` in the JSON).
Nothing here prints.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # annotations only
    from .static import MeanStates
    from .system import LineSystem


@dataclass(frozen=True)
class Uplift:
    """Vertical margin and weight span of every tower in still air and in every mean state.

    Attributes:
        suspension: bool (n_towers,): the towers the values apply to (NaN elsewhere).
        margin_still_air: [N] R_z in still air, (n_towers,).
        weight_span_still_air: [m] margin_still_air / W, (n_towers,).
        held_still_air: bool (n_towers,): clamps held at their still-air point (uplift) in still air.
        time: [s] instants of the mean states, (n_t,).
        margin: [N] R_z in every mean state, (n_t, n_towers).
        weight_span: [m] margin / W, (n_t, n_towers).
        held: bool (n_t, n_towers): clamps held in each mean state.
    """

    suspension: np.ndarray
    margin_still_air: np.ndarray
    weight_span_still_air: np.ndarray
    held_still_air: np.ndarray
    time: np.ndarray
    margin: np.ndarray
    weight_span: np.ndarray
    held: np.ndarray

    @property
    def worst_state(self) -> np.ndarray:
        """Index of the mean state of the smallest margin at every tower, (n_towers,) (0 at strain towers)."""
        return np.argmin(np.where(np.isnan(self.margin), np.inf, self.margin), axis=0)

    @property
    def any_held(self) -> bool:
        """True when a clamp is held (uplift) in still air or in some mean state."""
        return bool(self.held_still_air.any() or self.held.any())

    def first_uplift(self) -> tuple[int, int | None, float] | None:
        """The uplift to report first, or None: ``(tower, state, margin [N])``, tower 0-based,
        state None for still air.  A tower held in still air comes first (the smallest still-air
        margin), else the smallest margin of a held clamp over the mean states."""
        if self.held_still_air.any():
            j = int(np.argmin(np.where(self.held_still_air, self.margin_still_air, np.inf)))
            return j, None, float(self.margin_still_air[j])
        if self.held.any():
            k, j = np.unravel_index(int(np.argmin(np.where(self.held, self.margin, np.inf))), self.margin.shape)
            return int(j), int(k), float(self.margin[k, j])
        return None


def uplift(system: LineSystem, mean: MeanStates) -> Uplift:
    """The :class:`Uplift` of step-1 results: margin R_z [N] and weight span R_z / W [m] of every
    suspension tower (module docstring), in still air and at every mean state."""
    sus = np.asarray(system.suspension, dtype=bool)
    W = float(system.line.weight)
    still = mean.still_air

    def at_suspension(a: np.ndarray) -> np.ndarray:
        return np.where(sus, a, np.nan)

    m0 = at_suspension(still.reactions[:, 2])  # R_z: downward force on the tower [N]
    m = at_suspension(mean.reactions[..., 2])
    held0 = np.zeros(sus.size, dtype=bool) if still.held is None else np.asarray(still.held, dtype=bool)
    return Uplift(sus, m0, m0 / W, held0, np.asarray(mean.time, dtype=float), m, m / W,
                  np.asarray(mean.held, dtype=bool))
