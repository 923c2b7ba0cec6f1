"""A tower's totals from the reactions of the wires attached to it: the resultant force and the
moment about the tower's base (docs/wires.md "Tower totals").

Frames and signs.  A reaction R = (R_x, R_y, R_z) [N] is the force of a wire on the tower in the
tower's frame (docs/method.md "Line sections"): x along the tower's heading, y turned +90 deg in
plan (to the left of the line), z DOWN.  It acts at the attachment point r = (0, y, z) [m]: y to
the left of the line's centre, z UP above the tower's ground (the insulator's top or the strain
clamp).  The totals are

* forces: F = sum_a R_a (z down, as the reactions);
* moments about the base point (0, 0, 0): M = sum_a r_a x F_a, the moment of a force about a
  point (Meriam & Kraige, *Engineering Mechanics: Statics*, Art. 2/8), with F_a = (R_x, R_y, -R_z)
  the reaction in the right-handed frame (x, y, z up):

      M_x = -sum_a (z_a R_y,a + y_a R_z,a)   transverse overturning (about the line's direction)
      M_y =  sum_a z_a R_x,a                 longitudinal overturning (across the line)
      M_z = -sum_a y_a R_x,a                 torsion (about the vertical)

  A positive moment turns the tower about the positive axis (right-hand rule): a wind toward +y
  tips the tower about -x (M_x < 0).

Nothing here prints; numpy only.
"""

from __future__ import annotations

import numpy as np

#: The totals' components in the order of :func:`tower_totals`'s last axis: forces [N] (tower
#: frame, z down) and moments [N m] about the tower's base (right-hand rule, z up).
TOTALS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
FORCES = TOTALS[:3]
MOMENTS = TOTALS[3:]

#: The load cases of a tower's load trees (docs/wires.md "Load trees"), in their order: name ->
#: (the governing total of :data:`TOTALS`, "abs": the instant of its largest magnitude, "min": of
#: its least value).  ``min_vertical`` is the least downward force, the case of uplift.
LOAD_CASES: dict[str, tuple[str, str]] = {
    "max_transverse": ("Fy", "abs"),
    "max_longitudinal": ("Fx", "abs"),
    "max_overturning": ("Mx", "abs"),
    "max_torsion": ("Mz", "abs"),
    "min_vertical": ("Fz", "min"),
}


def reaction_moments(R: np.ndarray, y: np.ndarray | float, z: np.ndarray | float) -> np.ndarray:
    """The moment about the tower's base of each reaction at its own attachment point.

    Args:
        R: [N] reactions (..., 3) in the tower frame (z down).
        y, z: [m] the attachment point (0, y, z) (z up), numbers or arrays broadcasting against
            ``R[..., 0]`` (e.g. (n_towers,) for R (..., n_towers, 3)).

    Returns:
        [N m] (..., 3) = (M_x, M_y, M_z) = (-(z R_y + y R_z), z R_x, -y R_x): r x F with
        r = (0, y, z) and F = (R_x, R_y, -R_z) (module docstring; Meriam & Kraige, Art. 2/8).
    """
    R = np.asarray(R, dtype=float)
    out = np.empty(R.shape)
    # r x F = (r_y F_z - r_z F_y, r_z F_x - r_x F_z, r_x F_y - r_y F_x), r_x = 0, F_z = -R_z
    out[..., 0] = -(z * R[..., 1] + y * R[..., 2])
    out[..., 1] = z * R[..., 0]
    out[..., 2] = -(y * R[..., 0])
    return out


def tower_totals(R: np.ndarray, y: np.ndarray, z: np.ndarray) -> np.ndarray:
    """Every tower's totals from its attachments' reactions.

    Args:
        R: [N] reactions (..., n_towers, n_wires, 3) in the tower frames (z down).
        y, z: [m] attachment points (n_towers, n_wires): y to the left of the line's centre, z
            above the tower's ground.

    Returns:
        (..., n_towers, 6) in :data:`TOTALS` order: F = sum of the reactions [N] (z down) and
        M = sum of :func:`reaction_moments` [N m] about the tower's base.
    """
    R = np.asarray(R, dtype=float)
    y, z = np.asarray(y, dtype=float), np.asarray(z, dtype=float)
    return np.concatenate([R.sum(axis=-2), reaction_moments(R, y, z).sum(axis=-2)], axis=-1)
